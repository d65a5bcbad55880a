//! `hasse info` run as a user runs it: on every shipped mesh case, on a
//! Gmsh file, and on bad input (exit code 2, message naming file and key).

use std::path::PathBuf;
use std::process::Command;

fn hasse() -> Command {
    Command::new(env!("CARGO_BIN_EXE_hasse"))
}

fn repo(path: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("..")
        .join(path)
}

fn info(path: &PathBuf) -> (i32, String, String) {
    let out = hasse().arg("info").arg(path).output().expect("hasse runs");
    (
        out.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

#[test]
fn shipped_cases_report_their_topology() {
    // (case, cell counts line, χ, Betti numbers), derived by hand:
    // torus 50×5 quads: V = E/2 = F = 250; box 16³: (17³, 3·16·17², 3·16²·17, 16³);
    // hollow box 8³ minus 2³ cells: 504 cells, cavity of 24 faces.
    let expected = [
        (
            "cases/torus.toml",
            "K0 = 250   K1 = 500   K2 = 250",
            "χ = 0",
            "β = (1, 2, 1)",
        ),
        (
            "cases/box-3d.toml",
            "K0 = 4913   K1 = 13872   K2 = 13056   K3 = 4096",
            "χ = 1",
            "β = (1, 0, 0, 0)",
        ),
        (
            "cases/hollow-box.toml",
            "K3 = 504",
            "χ = 2",
            "β = (1, 0, 1, 0)",
        ),
        ("cases/l-shape.toml", "K2 = 96", "χ = 1", "β = (1, 0, 0)"),
        (
            "cases/distorted-quads.toml",
            "K0 = 1089   K1 = 2112   K2 = 1024",
            "χ = 1",
            "β = (1, 0, 0)",
        ),
        // 400 sites give 400 polygons filling the unit square (a disk).
        ("cases/voronoi.toml", "K2 = 400", "χ = 1", "β = (1, 0, 0)"),
    ];
    for (case, cells, euler, betti) in expected {
        let (code, out, err) = info(&repo(case));
        assert_eq!(code, 0, "{case}: {err}");
        assert!(out.contains(cells), "{case}: {out}");
        assert!(out.contains(euler), "{case}: {out}");
        assert!(out.contains(betti), "{case}: {out}");
    }
    let (_, out, _) = info(&repo("cases/torus.toml"));
    assert!(out.contains("(closed)"), "{out}");
    let (_, out, _) = info(&repo("cases/voronoi.toml"));
    assert!(out.contains("total area 1.000000e0"), "{out}");
    let (_, out, _) = info(&repo("cases/hollow-box.toml"));
    assert!(out.contains("tag        cavity: 24 2-cells"), "{out}");
}

#[test]
fn gmsh_files_are_read_directly() {
    let (code, out, err) = info(&repo("cases/l-shape.msh"));
    assert_eq!(code, 0, "{err}");
    assert!(out.contains("tag        dirichlet: 32 1-cells"), "{out}");
    assert!(out.contains("total area 7.500000e-1"), "{out}");
}

#[test]
fn bad_input_exits_2_naming_file_and_key() {
    let dir = std::env::temp_dir().join(format!("hasse-info-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let cases = [
        (
            "typo.toml",
            "[mesh]\ngenerator = \"rectangle\"\nnx = [4, 4]\n",
            "line 3",
        ),
        (
            "unknown.toml",
            "[mesh]\ngenerator = \"rectangel\"\nn = [4, 4]\n",
            "mesh.generator",
        ),
        (
            "zero.toml",
            "[mesh]\ngenerator = \"box\"\nn = [4, 0, 2]\n",
            "mesh.n",
        ),
        (
            "missing.toml",
            "[mesh]\nfile = \"does-not-exist.msh\"\n",
            "does-not-exist.msh",
        ),
        ("empty.toml", "title = \"no mesh\"\n", "no [mesh] table"),
        (
            "no-sites.toml",
            "[mesh]\ngenerator = \"voronoi\"\nn = [0]\n",
            "mesh.n",
        ),
    ];
    for (name, text, needle) in cases {
        let path = dir.join(name);
        std::fs::write(&path, text).unwrap();
        let (code, _, err) = info(&path);
        assert_eq!(code, 2, "{name}: {err}");
        assert!(
            err.contains(name),
            "{name}: message does not name the file: {err}"
        );
        assert!(
            err.contains(needle),
            "{name}: expected '{needle}' in: {err}"
        );
    }
    std::fs::remove_dir_all(&dir).unwrap();
}
