//! Methods that run but are inconsistent on the mesh they were given say
//! so in the summary (issue 30, items 4 and 8), and stay silent where they
//! are consistent.
//!
//! The figures in the expected messages are hand computations on the Kuhn
//! triangles of `mesh.cells = "simplex"` (each square split along its
//! v00–v11 diagonal):
//!
//! - two-point flux with centroid points: the centroids of the triangles
//!   on either side of a leg, e.g. (2/3, 1/3)h and (4/3, 2/3)h across
//!   x = h, differ by (2/3, 1/3)h, atan(1/2) = 26.565° off the leg's
//!   normal (1, 0); a boundary leg sees the same angle from its
//!   triangle's centroid, (2/3, 1/3)h − (1/2, 0)h = (1/6, 1/3)h. The
//!   diagonals are orthogonal (centroids (2/3, 1/3)h and (1/3, 2/3)h).
//! - barycentric DEC at an interior vertex: the legs get
//!   ω = 2·(√5/6)h / h (centroid to mid-leg is √5 h/6 in each of two
//!   triangles), the diagonals ω = 2·(√2/6)h / (√2 h) = 1/3, and
//!   |⋆v| = 6 · (h²/2)/3 = h², so
//!   K_eff = Σ ω_e d_e d_eᵀ / (2|⋆v|) = [[(1+√5)/3, 1/3], [1/3, (1+√5)/3]]
//!   = [[1.079, 0.333], [0.333, 1.079]], ‖K_eff − I‖₂ = (√5 − 1)/3 = 0.412.

use crate::hasse::summary as run;

/// The summary's warning lines.
fn warnings(stdout: &str) -> Vec<&str> {
    stdout
        .lines()
        .filter(|l| l.starts_with("warning"))
        .collect()
}

#[test]
fn two_point_flux_warns_on_centroid_triangles_only() {
    let squares = run(
        "cases/poisson-square.toml",
        &["problem.method=\"fv\"", "mesh.n=[8,8]"],
    );
    assert!(warnings(&squares).is_empty(), "{squares}");
    let triangles = run(
        "cases/poisson-square.toml",
        &[
            "problem.method=\"fv\"",
            "mesh.n=[8,8]",
            "mesh.cells=\"simplex\"",
        ],
    );
    let found = warnings(&triangles);
    let line = found
        .iter()
        .find(|l| l.contains("two-point flux"))
        .unwrap_or_else(|| panic!("no two-point warning in\n{triangles}"));
    // atan(1/2) = 26.565…°, printed with two decimals.
    assert!(line.contains("26.57° off"), "{line}");
    assert!(line.contains("use fv-mimetic"), "{line}");
    // The face is named by number and midpoint: a leg, whose midpoint has
    // one coordinate on the grid lines (multiples of 1/8) and the other
    // half-way between them.
    let at = line.split(" at (").nth(1).unwrap();
    let coordinates: Vec<f64> = at[..at.find(')').unwrap()]
        .split(", ")
        .map(|x| x.parse().unwrap())
        .collect();
    let on_lines = coordinates
        .iter()
        .filter(|x| (*x * 8.0).fract() == 0.0)
        .count();
    assert_eq!(on_lines, 1, "{line}");
}

#[test]
fn barycentric_dec_warns_on_kuhn_triangles_only() {
    let squares = run(
        "cases/poisson-square.toml",
        &["problem.method=\"dec-barycentric\"", "mesh.n=[8,8]"],
    );
    assert!(warnings(&squares).is_empty(), "{squares}");
    let circumcentric = run(
        "cases/poisson-square.toml",
        &[
            "problem.method=\"dec\"",
            "mesh.n=[8,8]",
            "mesh.cells=\"simplex\"",
        ],
    );
    assert!(warnings(&circumcentric).is_empty(), "{circumcentric}");
    let triangles = run(
        "cases/poisson-square.toml",
        &[
            "problem.method=\"dec-barycentric\"",
            "mesh.n=[8,8]",
            "mesh.cells=\"simplex\"",
        ],
    );
    let found = warnings(&triangles);
    let line = found
        .iter()
        .find(|l| l.contains("dec-barycentric"))
        .unwrap_or_else(|| panic!("no barycentric warning in\n{triangles}"));
    assert!(
        line.contains("K_eff = [[1.079, 0.333], [0.333, 1.079]]"),
        "{line}"
    );
    assert!(line.contains("‖K_eff − I‖ = 0.412"), "{line}");
    // Every interior vertex has this K_eff (up to rounding, which picks
    // the one named): it is interior, and its number and coordinates
    // agree (9 × 9 vertices, x fastest, spacing 1/8).
    let named = line.split("at vertex ").nth(1).unwrap();
    let vertex: usize = named.split(' ').next().unwrap().parse().unwrap();
    let (i, j) = (vertex % 9, vertex / 9);
    assert!((1..8).contains(&i) && (1..8).contains(&j), "{line}");
    let point = format!("vertex {vertex} ({}, {})", i as f64 / 8.0, j as f64 / 8.0);
    assert!(line.contains(&point), "{point} in {line}");
    // The heat path uses the same stiffness and says the same.
    let heat = run(
        "cases/heat-square.toml",
        &[
            "problem.method=\"dec-barycentric\"",
            "mesh.n=[8,8]",
            "mesh.cells=\"simplex\"",
            "time.end=0.01",
        ],
    );
    assert!(
        warnings(&heat)
            .iter()
            .any(|l| l.contains("K_eff = [[1.079, 0.333], [0.333, 1.079]]")),
        "{heat}"
    );
}

#[test]
fn barycentric_maxwell_mass_warns_on_kuhn_triangles_only() {
    let squares = run("cases/maxwell-square.toml", &["mesh.n=[8,8]"]);
    assert!(warnings(&squares).is_empty(), "{squares}");
    let triangles = run(
        "cases/maxwell-square.toml",
        &["mesh.n=[8,8]", "mesh.cells=\"simplex\""],
    );
    let found = warnings(&triangles);
    assert!(
        found.iter().any(|l| l.contains("inconsistent mass")
            && l.contains("K_eff = [[1.079, 0.333], [0.333, 1.079]]")
            && l.contains("whitney")),
        "{triangles}"
    );
    // The Whitney mass is consistent: no warning.
    let whitney = run(
        "cases/maxwell-square.toml",
        &[
            "mesh.n=[8,8]",
            "mesh.cells=\"simplex\"",
            "problem.mass=\"whitney\"",
        ],
    );
    assert!(!whitney.contains("inconsistent mass"), "{whitney}");
}
