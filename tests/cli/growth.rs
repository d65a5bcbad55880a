//! Growing tissues (`kind = "growth"`) through the `hasse` binary: the
//! shipped filament's cell counts and length against the hand count in
//! its comments, the shipped tissue's area under its affine growth, the
//! mass kept without sources and divided by 1 + λΔt a step under decay
//! alone, χ = 1 at every saved level, the series output, and the
//! refusals of `hasse check`.

use crate::hasse::{hasse, summary};
use crate::scratch::Scratch;

type Result<T = ()> = std::result::Result<T, Box<dyn std::error::Error>>;

const FILAMENT: &str = "cases/growing-filament.toml";
const TISSUE: &str = "cases/growing-tissue.toml";

/// One row of the summary's `levels` table.
#[derive(Debug)]
struct Level {
    step: usize,
    cells: usize,
    euler: i64,
    size: f64,
    mass: f64,
    /// `None` for t₀ (printed as —).
    balance: Option<f64>,
}

/// The rows of the `levels` table of a growth summary.
fn levels(stdout: &str) -> Result<Vec<Level>> {
    let mut lines = stdout.lines().skip_while(|l| !l.starts_with("levels"));
    lines
        .next()
        .ok_or_else(|| format!("no levels table in\n{stdout}"))?;
    let mut rows = Vec::new();
    for line in lines.take_while(|l| l.starts_with("    ")) {
        let w: Vec<&str> = line.split_whitespace().collect();
        if w.len() != 7 {
            return Err(format!("row `{line}` has {} words", w.len()).into());
        }
        rows.push(Level {
            step: w[0].parse()?,
            cells: w[2].parse()?,
            euler: w[3].parse()?,
            size: w[4].parse()?,
            mass: w[5].parse()?,
            balance: if w[6] == "—" {
                None
            } else {
                Some(w[6].parse()?)
            },
        });
    }
    Ok(rows)
}

#[test]
fn the_filament_divides_at_the_hand_counted_steps() -> Result {
    // The case's comment: 1 + gΔt = 1.03 a step; the 4 cells of 0.25
    // divide at step 16 (0.25·1.03¹⁵ = 0.3895 < 0.4 < 0.25·1.03¹⁶ =
    // 0.4012), their halves at step 40 (0.2006·1.03²³ = 0.3960 < 0.4 <
    // 0.2006·1.03²⁴ = 0.4078). Saved every 10 steps: 4, 4, 8, 8, 16, 16.
    let dir = Scratch::new("growth-filament");
    let stem = dir.join("filament");
    let out = hasse(&["run", FILAMENT, "-o", stem.to_str().ok_or("path")?]);
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "{stdout}{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let rows = levels(&stdout)?;
    let steps: Vec<usize> = rows.iter().map(|r| r.step).collect();
    assert_eq!(steps, vec![0, 10, 20, 30, 40, 50]);
    let cells: Vec<usize> = rows.iter().map(|r| r.cells).collect();
    assert_eq!(cells, vec![4, 4, 8, 8, 16, 16]);
    for r in &rows {
        // A filament is one segment at every level.
        assert_eq!(r.euler, 1, "{r:?}");
        // Length 1.03^k (forward Euler on v = 0.3 x moves each vertex by
        // the factor 1.03 a step); printed with 6 decimals.
        assert!((r.size - 1.03f64.powi(r.step as i32)).abs() < 1e-6, "{r:?}");
        // The balance closes to rounding (relative to its largest term).
        assert!(r.balance.is_none_or(|b| b < 1e-12), "{r:?}");
    }
    // The series: one mesh per saved level, with c and amount.
    let xdmf = std::fs::read_to_string(dir.join("filament.xdmf"))?;
    for k in 0..6 {
        assert!(
            xdmf.contains(&format!("filament.h5:/steps/{k}/mesh/vertices")),
            "{xdmf}"
        );
        assert!(
            xdmf.contains(&format!("filament.h5:/steps/{k}/c")),
            "{xdmf}"
        );
        assert!(
            xdmf.contains(&format!("filament.h5:/steps/{k}/amount")),
            "{xdmf}"
        );
    }
    assert!(dir.join("filament.level-5.xdmf").exists());
    Ok(())
}

#[test]
fn the_tissue_grows_by_its_affine_factor_and_stays_a_disc() -> Result {
    // v = 0.5 (x − ½, y − ½) moves every vertex to ½ + 1.025 (x − ½) a
    // step: the tissue (area 1) has area 1.025^{2k} after k steps.
    let stdout = summary(TISSUE, &[]);
    let rows = levels(&stdout)?;
    assert_eq!(rows.len(), 7); // t₀ and every 5 of 30 steps
    for pair in rows.windows(2) {
        assert!(pair[1].cells >= pair[0].cells, "{pair:?}");
    }
    assert_eq!(rows[0].cells, 50);
    assert!(rows[6].cells > 100, "{stdout}");
    for r in &rows {
        assert_eq!(r.euler, 1, "{r:?}");
        assert!(
            (r.size - 1.025f64.powi(2 * r.step as i32)).abs() < 1e-6,
            "{r:?}"
        );
        assert!(r.balance.is_none_or(|b| b < 1e-12), "{r:?}");
    }
    Ok(())
}

#[test]
fn mass_is_kept_without_sources_and_decays_by_one_plus_lambda_dt() -> Result {
    // No source, no decay, no flux: M stays ∫(1 + x) over the unit square
    // = 1.5 (each cell starts with c(centroid)|σ|, exact for linear c).
    let kept = summary(
        TISSUE,
        &[
            "problem.source=\"0\"",
            "problem.decay=0",
            "problem.initial=\"1 + x\"",
        ],
    );
    for r in levels(&kept)? {
        assert!((r.mass - 1.5).abs() < 1e-6 * 1.5, "{r:?}");
    }
    // Decay alone on c = 1: the uniform state stays uniform (affine growth
    // stretches every cell alike and division shares by area), so backward
    // Euler gives M^{n+1} = Mⁿ/(1 + λΔt) = Mⁿ/1.1 with λ = 2, Δt = 0.05.
    let decayed = summary(
        TISSUE,
        &[
            "problem.source=\"0\"",
            "problem.decay=2",
            "problem.initial=\"1\"",
        ],
    );
    for r in levels(&decayed)? {
        let expected = 1.1f64.powi(-(r.step as i32));
        assert!((r.mass - expected).abs() < 1e-6 * expected, "{r:?}");
    }
    Ok(())
}

fn check_fails(case: &str, sets: &[&str], key: &str, expected: &str) -> Result {
    let mut args = vec!["check", case];
    for s in sets {
        args.extend(["--set", s]);
    }
    let out = hasse(&args);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{args:?}: {stderr}");
    assert!(stderr.contains(&format!("`{key}`")), "{args:?}: {stderr}");
    assert!(stderr.contains(expected), "{args:?}: {stderr}");
    Ok(())
}

#[test]
fn check_refuses_what_cannot_grow() -> Result {
    for case in [FILAMENT, TISSUE] {
        let out = hasse(&["check", case]);
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
    }
    check_fails(
        TISSUE,
        &["mesh.generator=\"box\"", "mesh.n=[2, 2, 2]"],
        "mesh",
        "n = d = 1 or 2",
    )?;
    check_fails(
        TISSUE,
        &["growth.divide_above=0"],
        "growth.divide_above",
        "must be a positive, finite measure",
    )?;
    check_fails(
        TISSUE,
        &["growth.velocity=[\"x\"]"],
        "growth.velocity",
        "the velocity has 1 components but the vertices have 2 coordinates",
    )?;
    check_fails(
        FILAMENT,
        &["growth.rule=\"shortest-wall\""],
        "growth.rule",
        "does not divide 1-cells (use midpoint)",
    )?;
    check_fails(
        TISSUE,
        &["problem.method=\"fe\""],
        "problem.method",
        "has no cell unknowns",
    )?;
    check_fails(
        TISSUE,
        &["problem.decay=-1"],
        "problem.decay",
        "must be finite and ≥ 0",
    )?;
    check_fails(
        TISSUE,
        &["time.scheme=\"crank-nicolson\""],
        "time.scheme",
        "backward Euler",
    )?;
    // Keys of other kinds.
    check_fails(
        TISSUE,
        &["problem.reaction=\"u\""],
        "problem.reaction",
        "not used by kind = \"growth\"",
    )?;
    check_fails(
        TISSUE,
        &["refine.steps=2"],
        "refine",
        "[refine] is for diffusion problems",
    )?;
    check_fails(
        "cases/heat-square.toml",
        &["growth.divide_above=1"],
        "growth",
        "[growth] is for kind = \"growth\"",
    )?;
    Ok(())
}

/// A growth case without `[time]` is told so in its own kind's terms.
#[test]
fn a_growth_case_without_time_is_refused_in_its_terms() {
    let dir = Scratch::new("growth_without_time");
    std::fs::create_dir_all(&*dir).unwrap();
    let path = dir.join("filament.toml");
    std::fs::write(
        &path,
        "[mesh]\ngenerator = \"interval\"\nn = [4]\n\n[problem]\nkind = \"growth\"\nmethod = \"fv\"\ninitial = 1\n\n[growth]\nvelocity = [\"x\"]\ndivide_above = 0.5\n",
    )
    .unwrap();
    let out = hasse(&["check", path.to_str().unwrap()]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success(), "{stderr}");
    assert!(
        stderr.contains("no [time] table: a growth problem steps in time"),
        "{stderr}"
    );
}
