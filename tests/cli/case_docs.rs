//! The minimal and the full example of `cases/README.md` are valid cases
//! that solve, and converge at the order of their elements (Q1 for the
//! minimal one, P1 on perturbed triangles for the full one).

use approx::abs_diff_eq;
use hasse_solver::frontend::case::Case;
use hasse_solver::frontend::run;

fn examples() -> Vec<String> {
    let text = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/../cases/README.md"))
        .unwrap();
    // Whole cases have a [mesh] table; the other toml blocks are
    // fragments showing one key.
    text.split("```toml\n")
        .skip(1)
        .map(|block| block.split("```").next().unwrap().to_string())
        .filter(|block| block.contains("[mesh]"))
        .collect()
}

#[test]
fn readme_examples_run() {
    let examples = examples();
    assert_eq!(
        examples.len(),
        2,
        "cases/README.md has a minimal and a full example"
    );
    // Minimal: Poisson with zero Dirichlet data; no exact solution is
    // given, but its solution is sin(πx) sin(πy), whose peak 1 sits on the
    // vertex (½, ½) of the example's even grid. Q1 nodal values converge at
    // second order: from n = 16 to the example's n = 32, |peak − 1| gives
    // the order 2 ± 0.15. (By hand, with the load integrated exactly,
    // sine vectors diagonalise the Q1 stiffness and the peak is
    // 2π² g² / λ with g = 2(1 − cos πh)/(π²h), λ = 2(2 − 2 cos πh)(4 + 2 cos πh)/6:
    // 1 + 8.03e-4 at n = 32, within 1.3e-7 of the computed peak, the
    // difference being the load's quadrature.)
    let peak = |n: usize| {
        let overrides = [format!("mesh.n=[{n},{n}]")];
        let case = Case::from_text("minimal.toml", &examples[0], &overrides).unwrap();
        let complex = case.build_mesh().unwrap();
        let result = run::solve(&case, &complex, &mut |_| {}).unwrap();
        let u = &result.fields.iter().find(|f| f.name == "u").unwrap().values;
        u.iter().cloned().fold(f64::MIN, f64::max)
    };
    let (coarse, fine) = (peak(16), peak(32));
    let p = ((coarse - 1.0).abs() / (fine - 1.0).abs()).log2();
    assert!(
        abs_diff_eq!(p, 2.0, epsilon = 0.15),
        "peak {coarse} then {fine} of sin(πx) sin(πy): order {p}"
    );

    // Full: rotated anisotropic tensor, Dirichlet/Robin/Neumann sides, P1 on
    // perturbed Kuhn triangles; the example's 64 × 32 mesh against 32 × 16
    // (same perturbation amplitude relative to the edges, same seed): P1 is
    // second order in L². A wrong sign in any boundary datum leaves an O(1)
    // error that does not converge.
    let l2 = |n: &str| {
        let case = Case::from_text("full.toml", &examples[1], &[format!("mesh.n={n}")]).unwrap();
        assert!(!case.output.write);
        let complex = case.build_mesh().unwrap();
        let result = run::solve(&case, &complex, &mut |_| {}).unwrap();
        result.errors.unwrap().l2
    };
    let (coarse, fine) = (l2("[32,16]"), l2("[64,32]"));
    let p = (coarse / fine).log2();
    assert!(
        abs_diff_eq!(p, 2.0, epsilon = 0.15),
        "L2 order {p} ({coarse} then {fine})"
    );
}
