//! Distributed solves (`[solver] type = "petsc"`, cargo feature `mpi`):
//! `mpirun -np 1, 2, 3` give the serial solution, cell by cell through the
//! global numbering of the output, for every diffusion method on a 2D
//! grid, a Kuhn tetrahedral box and the shipped Gmsh L-shape; failures
//! exit non-zero and leave no output. Needs `mpirun` (Open MPI) and PETSc:
//! `scripts/setup --mpi`; `scripts/test` runs these with `--features mpi`.

use crate::scratch::Scratch;
use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};

type TestResult = Result<(), Box<dyn std::error::Error>>;

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

/// `mpirun -np N hasse ARGS…` (oversubscribed: CI machines have 2 cores).
fn mpirun(ranks: usize, args: &[&str]) -> Command {
    let mut command = Command::new("mpirun");
    command
        .args(["--oversubscribe", "-np", &ranks.to_string()])
        .arg(env!("CARGO_BIN_EXE_hasse"))
        .args(args)
        // Open MPI refuses root unless told; CI containers run as root.
        .env("OMPI_ALLOW_RUN_AS_ROOT", "1")
        .env("OMPI_ALLOW_RUN_AS_ROOT_CONFIRM", "1")
        .current_dir(root());
    command
}

fn text(out: &Output) -> String {
    format!(
        "{}\n{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    )
}

/// The mesh sections of the three test meshes, with a Dirichlet tag each.
fn meshes() -> Vec<(&'static str, String, &'static str)> {
    let lshape = root().join("cases/l-shape.msh");
    vec![
        (
            "grid",
            "generator = \"rectangle\"\nn = [12, 10]\n".to_string(),
            "boundary",
        ),
        (
            "kuhn",
            "generator = \"box\"\nn = [4, 4, 4]\ncells = \"simplex\"\n".to_string(),
            "boundary",
        ),
        (
            "lshape",
            format!("file = {:?}\n", lshape.display().to_string()),
            "dirichlet",
        ),
    ]
}

fn case(mesh: &str, tag: &str, method: &str, solver: &str) -> String {
    format!(
        "[mesh]\n{mesh}\n[problem]\nmethod = \"{method}\"\nconductivity = \"1 + x\"\nsource = \"1 + y\"\n\n[[boundary]]\ntag = \"{tag}\"\ntype = \"dirichlet\"\nvalue = \"x - y\"\n\n[solver]\n{solver}\n"
    )
}

/// The field `u` of a run's output.
fn field(stem: &Path) -> Result<Vec<f64>, Box<dyn std::error::Error>> {
    let file = hdf5::File::open(stem.with_extension("h5"))?;
    Ok(file.dataset("steps/0/u")?.read_raw::<f64>()?)
}

fn largest_difference(a: &[f64], b: &[f64]) -> f64 {
    a.iter()
        .zip(b)
        .map(|(x, y)| (x - y).abs())
        .fold(0.0, f64::max)
}

#[test]
fn every_method_on_one_two_and_three_ranks_gives_the_serial_solution() -> TestResult {
    let dir = Scratch::new("distributed-methods");
    std::fs::create_dir_all(&*dir)?;
    let mut compared = 0;
    let mut refused = Vec::new();
    for (mesh_name, mesh, tag) in meshes() {
        for method in ["fd", "fe", "fv", "fv-mimetic", "dec"] {
            let name = format!("{mesh_name}-{method}");
            let serial_case = dir.join(format!("{name}-serial.toml"));
            std::fs::write(&serial_case, case(&mesh, tag, method, "type = \"direct\""))?;
            let serial_stem = dir.join(format!("{name}-serial"));
            let out = Command::new(env!("CARGO_BIN_EXE_hasse"))
                .arg("run")
                .arg(&serial_case)
                .args(["-q", "-o"])
                .arg(&serial_stem)
                .output()?;
            if !out.status.success() {
                // A method that refuses the mesh: the distributed run must refuse alike.
                let petsc_case = dir.join(format!("{name}-refused.toml"));
                std::fs::write(&petsc_case, case(&mesh, tag, method, "type = \"petsc\""))?;
                let out = mpirun(2, &["run", petsc_case.to_str().ok_or("path")?, "-q"]).output()?;
                assert!(
                    !out.status.success(),
                    "{name}: serial refused, petsc ran:\n{}",
                    text(&out)
                );
                refused.push(name);
                continue;
            }
            let serial = field(&serial_stem)?;
            let scale = serial.iter().map(|v| v.abs()).fold(0.0, f64::max);
            // A distributed direct solve (MUMPS, Cholesky) on 1, 2, 3 ranks:
            // the same system up to the order of sums, so the same solution
            // to rounding (1e-10 of its size).
            for ranks in 1..=3 {
                let petsc_case = dir.join(format!("{name}-{ranks}.toml"));
                std::fs::write(
                    &petsc_case,
                    case(
                        &mesh,
                        tag,
                        method,
                        "type = \"petsc\"\nfactorization = \"llt\"",
                    ),
                )?;
                let stem = dir.join(format!("{name}-{ranks}"));
                let out = mpirun(
                    ranks,
                    &[
                        "run",
                        petsc_case.to_str().ok_or("path")?,
                        "-o",
                        stem.to_str().ok_or("path")?,
                    ],
                )
                .output()?;
                assert!(
                    out.status.success(),
                    "{name} on {ranks} ranks:\n{}",
                    text(&out)
                );
                let summary = String::from_utf8_lossy(&out.stdout);
                assert!(
                    summary.contains(&format!("on {ranks} ranks")) && summary.contains("mumps"),
                    "{name}: the summary names ranks and solver:\n{summary}"
                );
                let distributed = field(&stem)?;
                assert_eq!(distributed.len(), serial.len(), "{name} on {ranks} ranks");
                let difference = largest_difference(&distributed, &serial);
                assert!(
                    difference <= 1e-10 * scale,
                    "{name} on {ranks} ranks: largest difference {difference:e} (solution size {scale:e})"
                );
                compared += 1;
            }
            // CG + GAMG (the default) to a relative residual of 1e-10: these
            // systems have condition numbers below 1e4, so the error is
            // below 1e-6 of the solution.
            let petsc_case = dir.join(format!("{name}-gamg.toml"));
            std::fs::write(
                &petsc_case,
                case(&mesh, tag, method, "type = \"petsc\"\ntolerance = 1e-10"),
            )?;
            let stem = dir.join(format!("{name}-gamg"));
            let out = mpirun(
                2,
                &[
                    "run",
                    petsc_case.to_str().ok_or("path")?,
                    "-o",
                    stem.to_str().ok_or("path")?,
                ],
            )
            .output()?;
            assert!(out.status.success(), "{name} with GAMG:\n{}", text(&out));
            assert!(
                String::from_utf8_lossy(&out.stdout).contains("cg + gamg"),
                "{name}: {}",
                text(&out)
            );
            let difference = largest_difference(&field(&stem)?, &serial);
            assert!(
                difference <= 1e-6 * scale,
                "{name} with GAMG: largest difference {difference:e}"
            );
        }
    }
    // Finite differences need a grid of boxes and circumcentric DEC
    // simplices: the serial runs refuse these (and the distributed ones
    // alike); everything else runs.
    assert_eq!(refused, ["grid-dec", "kuhn-fd", "lshape-fd"]);
    assert_eq!(compared, 3 * 12);
    Ok(())
}

#[test]
fn petsc_options_from_the_case_reach_ksp() -> TestResult {
    let dir = Scratch::new("distributed-options");
    std::fs::create_dir_all(&*dir)?;
    let path = dir.join("options.toml");
    let (_, mesh, tag) = &meshes()[0];
    let solver =
        "type = \"petsc\"\n\n[solver.petsc]\noptions = \"-ksp_type gmres -pc_type jacobi\"";
    std::fs::write(&path, case(mesh, tag, "fv", solver))?;
    let out = mpirun(
        2,
        &[
            "run",
            path.to_str().ok_or("path")?,
            "--set",
            "output.write=false",
        ],
    )
    .output()?;
    assert!(out.status.success(), "{}", text(&out));
    assert!(
        String::from_utf8_lossy(&out.stdout).contains("gmres + jacobi"),
        "{}",
        text(&out)
    );
    // A bad option value is PETSc's error, reported, and nothing is written.
    std::fs::write(
        &path,
        case(
            mesh,
            tag,
            "fv",
            "type = \"petsc\"\n\n[solver.petsc]\noptions = \"-ksp_type no-such-method\"",
        ),
    )?;
    let stem = dir.join("bad");
    let out = mpirun(
        2,
        &[
            "run",
            path.to_str().ok_or("path")?,
            "-o",
            stem.to_str().ok_or("path")?,
        ],
    )
    .output()?;
    assert!(!out.status.success(), "{}", text(&out));
    assert!(text(&out).contains("no-such-method"), "{}", text(&out));
    assert!(!stem.with_extension("h5").exists());
    Ok(())
}

#[test]
fn more_ranks_than_top_cells_is_refused() -> TestResult {
    let dir = Scratch::new("distributed-ranks");
    std::fs::create_dir_all(&*dir)?;
    let path = dir.join("tiny.toml");
    std::fs::write(
        &path,
        case(
            "generator = \"rectangle\"\nn = [1, 2]\n",
            "boundary",
            "fv",
            "type = \"petsc\"",
        ),
    )?;
    let stem = dir.join("tiny");
    let out = mpirun(
        3,
        &[
            "run",
            path.to_str().ok_or("path")?,
            "-o",
            stem.to_str().ok_or("path")?,
        ],
    )
    .output()?;
    assert!(!out.status.success(), "{}", text(&out));
    assert!(
        text(&out).contains("3 ranks for 2 top cells"),
        "{}",
        text(&out)
    );
    assert!(!stem.with_extension("h5").exists());
    Ok(())
}

#[test]
fn a_killed_rank_leaves_no_output() -> TestResult {
    let dir = Scratch::new("distributed-killed");
    std::fs::create_dir_all(&*dir)?;
    let path = dir.join("big.toml");
    // Large enough that the ranks are still at work when one is killed.
    std::fs::write(
        &path,
        case(
            "generator = \"rectangle\"\nn = [700, 700]\n",
            "boundary",
            "fe",
            "type = \"petsc\"",
        ),
    )?;
    let stem = dir.join("big");
    let mut child = mpirun(
        2,
        &[
            "run",
            path.to_str().ok_or("path")?,
            "-q",
            "-o",
            stem.to_str().ok_or("path")?,
        ],
    )
    .stdout(Stdio::null())
    .stderr(Stdio::null())
    .spawn()?;
    // The ranks are mpirun's children named hasse; kill one of them.
    let mut killed = false;
    for _ in 0..100 {
        std::thread::sleep(std::time::Duration::from_millis(100));
        let ranks = Command::new("pgrep")
            .args(["-P", &child.id().to_string(), "hasse"])
            .output()?;
        let pids: Vec<String> = String::from_utf8_lossy(&ranks.stdout)
            .split_whitespace()
            .map(String::from)
            .collect();
        if pids.len() == 2 {
            std::thread::sleep(std::time::Duration::from_millis(500));
            Command::new("kill").args(["-KILL", &pids[1]]).status()?;
            killed = true;
            break;
        }
    }
    let status = child.wait()?;
    assert!(killed, "the ranks never appeared");
    assert!(!status.success());
    assert!(
        !stem.with_extension("h5").exists(),
        "a killed run left its output in place"
    );
    assert!(!stem.with_extension("xdmf").exists());
    Ok(())
}
