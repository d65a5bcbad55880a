//! What each fuzz target does with its bytes. Shared by the cargo-fuzz
//! targets (nightly, `scripts/fuzz`) and by `tests/cli/fuzz_regressions.rs`,
//! which replays every kept input on stable. A harness may return early on
//! input it cannot use, but any panic is a bug: all of this is reachable
//! from a case file or a mesh file.

#![allow(dead_code)]

use hasse_complex::{Complex, TopCells, Vertices};
use hasse_solver::frontend::case::expr::Scope;
use hasse_solver::frontend::case::Case;

/// The case-file reader must turn any text into a case or diagnostics.
/// Meshes small enough to build quickly are built too, which exercises the
/// `[mesh]` checks behind `hasse check`.
pub fn case_file(data: &[u8]) {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    let case = match Case::from_text("fuzz.toml", text, &[]) {
        Ok(case) => case,
        Err(diagnostics) => {
            // Every diagnostic renders (positions inside the text).
            let _ = diagnostics.to_string();
            return;
        }
    };
    // Overrides re-parse the text through toml_edit.
    let _ = Case::from_text("fuzz.toml", text, &["mesh.n=[2,2]".into()]);
    let spec = &case.mesh;
    // A mesh file would be read from the working directory: not fuzzed here.
    if spec.file.is_some() {
        return;
    }
    let cells: usize = spec
        .n
        .as_deref()
        .unwrap_or(&[])
        .iter()
        .try_fold(1usize, |a, &n| a.checked_mul(n))
        .unwrap_or(usize::MAX);
    let small = cells <= 256
        && spec.subdivisions.unwrap_or(0) <= 2
        && spec.lloyd.unwrap_or(0) <= 2
        && spec.cavity.is_none_or(|[a, b]| a <= 16 && b <= 16);
    if small {
        if let Ok(complex) = case.build_mesh() {
            check_complex(&complex);
        }
    }
}

/// An expression parses or is refused; a parsed one evaluates anywhere
/// without panicking, and one that claims to be constant is.
/// Input: the expression on the first line, an optional definition
/// `name = text` on the second.
pub fn expression(data: &[u8]) {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    let mut lines = text.splitn(2, '\n');
    let expression = lines.next().unwrap_or("");
    let mut scope = Scope::new();
    scope.add_constant("k", 2.5).expect("k is a valid name");
    if let Some((name, definition)) = lines.next().and_then(|l| l.split_once('=')) {
        let _ = scope.add_definition(name.trim(), definition.trim());
    }
    let Ok(e) = scope.parse(expression) else {
        return;
    };
    let points: [&[f64]; 6] = [
        &[],
        &[0.0, 0.0, 0.0],
        &[0.5, -0.25, 1.0],
        &[-1e300, 1e300, 0.0],
        &[f64::NAN, 1.0],
        &[f64::INFINITY, f64::NEG_INFINITY, 0.0],
    ];
    let values: Vec<f64> = points.iter().map(|p| e.eval(p, 0.5)).collect();
    if e.is_constant() {
        let first = values[0];
        assert!(
            values
                .iter()
                .all(|v| v.to_bits() == first.to_bits() || (v.is_nan() && first.is_nan())),
            "`{expression}` claims to be constant but gives {values:?}"
        );
    }
}

/// The Gmsh reader turns any bytes into a complex or an error; a complex it
/// returns satisfies ∂∂ = 0 and has finite geometry.
pub fn gmsh(data: &[u8]) {
    if let Ok(complex) = hasse_complex::gmsh::read_msh_bytes(data, "fuzz.msh") {
        check_complex(&complex);
    }
}

/// Reads bytes one at a time, zero when they run out.
struct Bytes<'a>(&'a [u8]);

impl Bytes<'_> {
    fn next(&mut self) -> u8 {
        match self.0.split_first() {
            Some((&b, rest)) => {
                self.0 = rest;
                b
            }
            None => 0,
        }
    }
}

/// `Complex::build` on arbitrary vertices and cells: coordinates on a small
/// lattice (so duplicates, collinear and degenerate cells are common) with
/// the odd NaN or infinity, cell shapes and vertex lists of any length,
/// indices a little beyond the vertex count. Whatever it accepts must
/// satisfy the complex's invariants.
pub fn complex_build(data: &[u8]) {
    let mut b = Bytes(data);
    let d = 1 + usize::from(b.next() % 3);
    let vertex_count = 1 + usize::from(b.next() % 16);
    let coords: Vec<f64> = (0..vertex_count * d)
        .map(|_| match b.next() {
            255 => f64::NAN,
            254 => f64::INFINITY,
            253 => 1e-300,
            v => f64::from(v as i8) / 4.0,
        })
        .collect();
    let Ok(vertices) = Vertices::new(d, coords) else {
        return;
    };
    let index = |b: &mut Bytes| usize::from(b.next()) % (vertex_count + 2);
    let mut cells = TopCells::default();
    let shape = b.next() % 4;
    let cell_count = 1 + usize::from(b.next() % 8);
    for _ in 0..cell_count {
        match shape {
            3 => {
                let faces: Vec<Vec<usize>> = (0..b.next() % 8)
                    .map(|_| (0..b.next() % 6).map(|_| index(&mut b)).collect())
                    .collect();
                cells.push_polyhedron(&faces);
            }
            _ => {
                let vs: Vec<usize> = (0..b.next() % 10).map(|_| index(&mut b)).collect();
                match shape {
                    0 => cells.push_simplex(&vs),
                    1 => cells.push_cuboid(&vs),
                    _ => cells.push_polygon(&vs),
                }
            }
        }
    }
    if let Ok(complex) = Complex::build(vertices, cells) {
        check_complex(&complex);
    }
}

/// Invariants of any complex the library hands out.
fn check_complex(k: &Complex) {
    let n = k.dim();
    for p in 2..=n {
        let product = &**k.boundary(p - 1) * &**k.boundary(p);
        assert!(product.data().iter().all(|&v| v == 0), "∂∂ ≠ 0 at p = {p}");
    }
    for p in 0..=n {
        assert!(
            k.measure(p).iter().all(|m| m.is_finite()),
            "non-finite {p}-measure"
        );
    }
    let _ = k.euler_characteristic();
}
