//! Convergence studies: the order formulas on sequences with known slopes,
//! `hasse converge` end to end (tables, CSV, JSON, PNG, SVG, `--expect`
//! exit codes), and uniform refinement of the generators.

use approx::{abs_diff_eq, assert_abs_diff_eq};
use hasse_solver::frontend::converge::{Study, StudyError};
use hasse_solver::frontend::output::study::write_plot;
use hasse_solver::metric::Method;
use hasse_solver::study::{
    least_squares_order, pairwise_orders, Norm, OrderError, PlotFormat, PlotOptions, Refinement,
};
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn hasse(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_hasse"))
        .args(args)
        .current_dir(Path::new(env!("CARGO_MANIFEST_DIR")).join(".."))
        .output()
        .expect("the hasse binary runs")
}

fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("hasse-converge-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn text(bytes: &[u8]) -> String {
    String::from_utf8_lossy(bytes).into_owned()
}

// ---- order formulas ---------------------------------------------------

#[test]
fn exact_power_laws_give_their_slope_pairwise_and_by_least_squares() {
    // Uneven refinement ratios: the formulas must not assume h halves.
    let h = [0.3, 0.2, 0.07, 0.05, 0.011];
    for p in [0.5, 1.0, 2.0, 3.0] {
        let e: Vec<f64> = h.iter().map(|h: &f64| 7.5 * h.powf(p)).collect();
        let pairwise = pairwise_orders(&h, &e).unwrap();
        assert_eq!(pairwise.len(), h.len() - 1);
        for q in pairwise {
            assert!(
                abs_diff_eq!(q, p, epsilon = 1e-12),
                "pairwise {q} for slope {p}"
            );
        }
        let fitted = least_squares_order(&h, &e).unwrap();
        assert!(
            abs_diff_eq!(fitted, p, epsilon = 1e-12),
            "least squares {fitted} for {p}"
        );
    }
}

#[test]
fn least_squares_differs_from_pairwise_as_computed_by_hand() {
    // In units of ln 2: ln h = 0, −1, −2, −3 and ln e = 0, −2, −4, −5.
    // Pairwise slopes 2, 2, 1. Least squares: mean ln h = −1.5,
    // mean ln e = −2.75; Σ dx dy = 1.5·2.75 + 0.5·0.75 + 0.5·1.25 + 1.5·2.25
    // = 8.5 and Σ dx² = 5, so p = 8.5 / 5 = 1.7.
    let h = [1.0, 0.5, 0.25, 0.125];
    let e = [1.0, 0.25, 0.0625, 0.03125];
    let pairwise = pairwise_orders(&h, &e).unwrap();
    for (q, want) in pairwise.iter().zip([2.0, 2.0, 1.0]) {
        assert!(abs_diff_eq!(*q, want, epsilon = 1e-12), "{pairwise:?}");
    }
    let p = least_squares_order(&h, &e).unwrap();
    assert_abs_diff_eq!(p, 1.7, epsilon = 1e-12);
}

#[test]
fn orders_refuse_what_has_no_logarithm_or_no_slope() {
    assert_eq!(
        pairwise_orders(&[1.0, 0.5], &[1.0]),
        Err(OrderError::LengthMismatch { h: 2, e: 1 })
    );
    assert_eq!(
        least_squares_order(&[1.0], &[1.0]),
        Err(OrderError::TooFewLevels(1))
    );
    assert!(matches!(
        pairwise_orders(&[1.0, 0.5], &[1.0, 0.0]),
        Err(OrderError::NotPositive { level: 1, .. })
    ));
    assert!(matches!(
        least_squares_order(&[1.0, f64::NAN], &[1.0, 0.5]),
        Err(OrderError::NotPositive { level: 1, .. })
    ));
    assert_eq!(
        pairwise_orders(&[0.5, 0.5], &[1.0, 0.5]),
        Err(OrderError::SameSize(0, 1))
    );
    assert!(least_squares_order(&[0.5, 0.5, 0.5], &[1.0, 0.5, 0.2]).is_err());
}

// ---- the command line -------------------------------------------------

/// The Poisson case on 8×8, 16×16, 32×32: small and fast.
fn poisson(dir: &Path, methods: &str, extra: &[&str]) -> Output {
    let mut args = vec![
        "converge",
        "cases/poisson-square.toml",
        "--levels",
        "3",
        "--set",
        "mesh.n=[8,8]",
        "--methods",
        methods,
        "-o",
        dir.to_str().unwrap(),
    ];
    args.extend_from_slice(extra);
    hasse(&args)
}

#[test]
fn expect_fails_the_run_when_an_order_is_missed_and_passes_when_met() {
    let dir = scratch("expect");
    let missed = poisson(&dir, "fd,fe", &["--expect", "3"]);
    assert_eq!(missed.status.code(), Some(1), "{}", text(&missed.stderr));
    let stderr = text(&missed.stderr);
    for method in ["fd", "fe"] {
        assert!(
            stderr.contains(&format!(
                "expectation missed: {method} least-squares L² order"
            )),
            "{stderr}"
        );
    }
    // A tolerance wide enough to let second order pass for 3 is honoured.
    let widened = poisson(&dir, "fd", &["--expect", "3:1.1"]);
    assert_eq!(widened.status.code(), Some(0), "{}", text(&widened.stderr));

    let met = poisson(&dir, "fd,fe", &["--expect", "2"]);
    assert_eq!(met.status.code(), Some(0), "{}", text(&met.stderr));
    let stdout = text(&met.stdout);
    assert!(stdout.contains("fd least squares"), "{stdout}");
    assert!(stdout.contains(": met"), "{stdout}");
    // One progress line per level on stderr, numbered from 0 as the table
    // numbers them.
    let progress = text(&met.stderr);
    let numbers: Vec<&str> = progress
        .lines()
        .filter_map(|l| l.strip_prefix("level "))
        .map(|l| l.split_whitespace().next().unwrap_or(""))
        .collect();
    assert_eq!(numbers, ["0", "1", "2"], "{progress}");
    let quiet = poisson(&dir, "fd", &["-q"]);
    assert!(quiet.status.success());
    assert!(quiet.stdout.is_empty() && quiet.stderr.is_empty());
}

#[test]
fn csv_json_png_and_svg_are_written_with_the_stated_shape() {
    let dir = scratch("files");
    let out = poisson(&dir, "fd,fe,fv", &[]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let mut names: Vec<String> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    names.sort();
    // Nothing else: no temporary file left behind.
    assert_eq!(
        names,
        [
            "convergence.csv",
            "convergence.json",
            "convergence.png",
            "convergence.svg"
        ]
    );

    let csv = std::fs::read_to_string(dir.join("convergence.csv")).unwrap();
    let lines: Vec<&str> = csv.lines().collect();
    assert_eq!(
        lines[0],
        "method,level,resolution,h,cells,unknowns,l2,l2_order,max,max_order,gradient_l2,gradient_l2_order,flux,flux_order,mesh_seconds,solve_seconds"
    );
    assert_eq!(lines.len(), 1 + 3 * 3, "3 levels × 3 methods:\n{csv}");
    assert!(lines[1].starts_with("fd,0,8x8,"));
    assert!(lines[9].starts_with("fv,2,32x32,"));
    let columns = lines[0].split(',').count();
    assert!(lines.iter().all(|l| l.split(',').count() == columns));
    // fe (nodal) has no face flux: empty fields, not zeros.
    let fe: Vec<&str> = lines[4].split(',').collect();
    assert!(
        fe[0] == "fe" && fe[12].is_empty() && fe[13].is_empty(),
        "{fe:?}"
    );

    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("convergence.json")).unwrap())
            .unwrap();
    assert_eq!(json["levels"], 3);
    let methods = json["methods"].as_array().unwrap();
    assert_eq!(methods.len(), 3);
    let fd_l2 = methods[0]["orders"]["l2"]["least_squares"]
        .as_f64()
        .unwrap();
    assert_abs_diff_eq!(fd_l2, 2.0, epsilon = 0.15);
    assert_eq!(methods[0]["rows"].as_array().unwrap().len(), 3);
    assert!(methods[1]["orders"].get("flux").is_none(), "fe has no flux");

    let png = std::fs::read(dir.join("convergence.png")).unwrap();
    assert_eq!(png_size(&png), (960, 600));

    let svg = std::fs::read_to_string(dir.join("convergence.svg")).unwrap();
    assert_eq!(svg_size(&svg), (960, 600));
    // One series per method and norm: fd and fv have L², max, gradient L²
    // and flux; fe has no flux. Each series has exactly one legend label.
    let labels = legend_labels(&svg);
    let mut want = Vec::new();
    for (method, norms) in [("fd", 4), ("fe", 3), ("fv", 4)] {
        for norm in &Norm::ALL[..norms] {
            want.push(format!("{method} · {}", norm.label()));
        }
    }
    assert_eq!(labels, want);

    // The methods were chosen on the command line, so the case's title
    // (which describes its own method, fe) gives way to the methods.
    let texts = svg_texts(&svg);
    assert!(
        texts
            .iter()
            .any(|t| t == "fd, fe, fv on poisson-square.toml"),
        "{texts:?}"
    );
    // The reference slopes are named in the legend and at their lines.
    for label in [
        "reference slope 1 (h¹)",
        "reference slope 2 (h²)",
        "h¹",
        "h²",
    ] {
        assert!(texts.iter().any(|t| t == label), "{label}: {texts:?}");
    }
    // h runs from 1.8e-1 (8×8, √2/8) to 4.4e-2: the decade 10⁻¹ lies inside
    // and is written as a power, the 2 and 5 marks between as 2·10⁻¹ …
    assert!(texts.iter().any(|t| t == "10⁻¹"), "{texts:?}");
    assert!(!texts.iter().any(|t| t.contains("e-")), "{texts:?}");
}

/// Every text element of an SVG, trimmed.
fn svg_texts(svg: &str) -> Vec<String> {
    svg.split("<text")
        .skip(1)
        .map(|t| {
            let body = &t[t.find('>').unwrap() + 1..t.find("</text>").unwrap()];
            body.trim().to_string()
        })
        .collect()
}

#[test]
fn a_study_of_the_case_s_own_method_keeps_its_title() {
    let study = Study {
        levels: 2,
        refinement: Refinement::Uniform,
        methods: Vec::new(),
    };
    let result = study
        .run(
            &Path::new(env!("CARGO_MANIFEST_DIR")).join("../cases/poisson-square.toml"),
            &["mesh.n=[4,4]".into()],
            &mut |_, _| {},
        )
        .unwrap();
    let svg = result.svg(PlotOptions::default()).unwrap();
    // cases/poisson-square.toml: title and method = "fe".
    let title = "Poisson on the unit square, manufactured solution (fe)";
    assert!(svg_texts(&svg).iter().any(|t| t == title));
}

/// Width and height from the IHDR chunk, after checking the signature.
fn png_size(png: &[u8]) -> (u32, u32) {
    assert_eq!(&png[..8], b"\x89PNG\r\n\x1a\n", "PNG signature");
    // The first chunk: length (4 bytes, = 13), type "IHDR", then width and
    // height as big-endian u32.
    assert_eq!(u32::from_be_bytes(png[8..12].try_into().unwrap()), 13);
    assert_eq!(&png[12..16], b"IHDR");
    let width = u32::from_be_bytes(png[16..20].try_into().unwrap());
    let height = u32::from_be_bytes(png[20..24].try_into().unwrap());
    // Colour type 2 (RGB) with 8-bit depth, as plotters' encoder writes.
    assert_eq!((png[24], png[25]), (8, 2));
    // The file ends with the IEND chunk: the encoder finished.
    assert_eq!(&png[png.len() - 8..png.len() - 4], b"IEND");
    (width, height)
}

fn svg_size(svg: &str) -> (u32, u32) {
    let root = &svg[svg.find("<svg").expect("an <svg> element")..];
    let root = &root[..root.find('>').unwrap()];
    let attribute = |name: &str| -> u32 {
        let key = format!(" {name}=\"");
        let start = root
            .find(&key)
            .unwrap_or_else(|| panic!("no {name} in {root}"))
            + key.len();
        root[start..][..root[start..].find('"').unwrap()]
            .parse()
            .unwrap()
    };
    (attribute("width"), attribute("height"))
}

/// The series labels of the legend, in order: texts of the form
/// `METHOD · NORM`.
fn legend_labels(svg: &str) -> Vec<String> {
    svg_texts(svg)
        .into_iter()
        .filter(|t| t.contains(" · "))
        .collect()
}

#[test]
fn the_library_draws_plots_of_any_size() {
    let study = Study {
        levels: 2,
        refinement: Refinement::Uniform,
        methods: vec![Method::Fv],
    };
    let result = study
        .run(
            &Path::new(env!("CARGO_MANIFEST_DIR")).join("../cases/poisson-square.toml"),
            &["mesh.n=[4,4]".into()],
            &mut |_, _| {},
        )
        .unwrap();
    let dir = scratch("sizes");
    let png = dir.join("small.png");
    write_plot(
        &result,
        &png,
        PlotFormat::Png,
        PlotOptions {
            width: 500,
            height: 321,
        },
    )
    .unwrap();
    assert_eq!(png_size(&std::fs::read(&png).unwrap()), (500, 321));
    let svg = result
        .svg(PlotOptions {
            width: 800,
            height: 450,
        })
        .unwrap();
    assert_eq!(svg_size(&svg), (800, 450));
    assert_eq!(legend_labels(&svg).len(), 4);
}

#[test]
fn bad_studies_exit_2_and_write_nothing() {
    let dir = scratch("bad");
    let out_dir = dir.join("never");
    let o = out_dir.to_str().unwrap();
    for (args, message) in [
        (
            vec!["converge", "cases/l-shape.toml", "--levels", "2", "-o", o],
            "a mesh file has none; use --refine split",
        ),
        (
            vec!["converge", "cases/torus.toml", "--levels", "2", "-o", o],
            "measures diffusion (of functions or k-forms), heat, darcy and coupled cases; this case is kind = \"gradient\"",
        ),
        (
            vec![
                "converge",
                "cases/poisson-square.toml",
                "--levels",
                "2",
                "--methods",
                "fd,fvm",
                "-o",
                o,
            ],
            "unknown method \"fvm\"; the methods are fd, fe, fv, fv-mimetic",
        ),
        (
            vec![
                "converge",
                "cases/poisson-square.toml",
                "--levels",
                "1",
                "--expect",
                "2",
                "-o",
                o,
            ],
            "at least 2 levels",
        ),
        (
            // A steady case has no time step to halve.
            vec![
                "converge",
                "cases/poisson-square.toml",
                "--levels",
                "2",
                "--refine",
                "time",
                "-o",
                o,
            ],
            "--refine time halves the time step of a transient case; this case is kind = \"diffusion\"",
        ),
        (
            // Darcy's methods are flux masses, not the diffusion methods.
            vec![
                "converge",
                "cases/darcy-layered.toml",
                "--levels",
                "2",
                "--methods",
                "fe",
                "-o",
                o,
            ],
            "a darcy case's method is its own",
        ),
        (
            // DEC's circumcentric dual needs simplices; the case has quads.
            vec![
                "converge",
                "cases/poisson-square.toml",
                "--levels",
                "2",
                "--methods",
                "dec",
                "-o",
                o,
            ],
            "level 0, method dec",
        ),
    ] {
        let out = hasse(&args);
        let stderr = text(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{args:?}: {stderr}");
        assert!(stderr.contains(message), "{args:?}: {stderr}");
        assert!(!out_dir.exists(), "{args:?} wrote output");
    }
}

// ---- refinement -------------------------------------------------------

fn exact_case(mesh: &str) -> String {
    format!(
        "{mesh}\n[problem]\nmethod = \"fe\"\nsource = \"2*pi^2*sin(pi*x)*sin(pi*y)\"\n\
         [[boundary]]\ntag = \"boundary\"\ntype = \"dirichlet\"\nvalue = \"sin(pi*x)*sin(pi*y)\"\n\
         [exact]\nsolution = \"sin(pi*x)*sin(pi*y)\"\n"
    )
}

#[test]
fn uniform_refinement_scales_each_generator_resolution() {
    let study = |levels| Study {
        levels,
        refinement: Refinement::Uniform,
        methods: vec![],
    };
    // Voronoi: n counts sites in the plane, 4× per level.
    let voronoi = exact_case("[mesh]\ngenerator = \"voronoi\"\nn = [30]\nseed = 2\n");
    let r = study(3)
        .run_text("voronoi.toml", &voronoi, &[], &mut |_, _| {})
        .unwrap();
    let cells: Vec<usize> = r.rows.iter().map(|r| r.cells).collect();
    assert_eq!(cells, [30, 120, 480]);
    assert_eq!(r.rows[2].resolution, vec![480]);

    // Hollow box: the cavity's cell indices double with n, so the hole
    // stays the same region: (2ᵏn)³ − (2ᵏ·2)³ cells.
    let hollow = exact_case("[mesh]\ngenerator = \"hollow-box\"\nn = [4]\ncavity = [1, 3]\n");
    let r = study(2)
        .run_text("hollow.toml", &hollow, &[], &mut |_, _| {})
        .unwrap();
    let cells: Vec<usize> = r.rows.iter().map(|r| r.cells).collect();
    assert_eq!(cells, [64 - 8, 512 - 64]);

    // Grids: n doubles per axis and h halves; the progress callback sees
    // each level once, in order.
    let mut seen = Vec::new();
    let rect = exact_case("[mesh]\ngenerator = \"rectangle\"\nn = [3, 5]\n");
    let r = study(3)
        .run_text("rect.toml", &rect, &[], &mut |level, rows| {
            seen.push((level, rows.len()))
        })
        .unwrap();
    assert_eq!(seen, [(0, 1), (1, 1), (2, 1)]);
    assert_eq!(r.rows[2].resolution, vec![12, 20]);
    assert_abs_diff_eq!(r.rows[0].h / r.rows[2].h, 4.0, epsilon = 1e-12);
    assert_eq!(r.rows[1].unknowns, 7 * 11);
}

#[test]
fn studies_need_an_exact_solution_and_a_refinable_mesh() {
    let study = Study {
        levels: 2,
        refinement: Refinement::Uniform,
        methods: vec![Method::Fe],
    };
    let no_exact = "[mesh]\ngenerator = \"rectangle\"\nn = [4, 4]\n[problem]\nmethod = \"fe\"\n\
                    [[boundary]]\ntag = \"boundary\"\ntype = \"dirichlet\"\nvalue = 0\n";
    let e = study
        .run_text("plain.toml", no_exact, &[], &mut |_, _| {})
        .unwrap_err();
    assert!(
        matches!(e, StudyError::NoExact { .. }) && e.is_input(),
        "{e}"
    );
    let from_file = exact_case("[mesh]\nfile = \"some.msh\"\n");
    let e = study
        .run_text("file.toml", &from_file, &[], &mut |_, _| {})
        .unwrap_err();
    assert!(matches!(e, StudyError::Refinement { .. }), "{e}");
    assert!(e.to_string().contains("some.msh"), "{e}");
}
