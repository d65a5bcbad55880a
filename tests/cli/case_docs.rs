//! The minimal and the full example of `cases/README.md` are valid cases
//! that solve; the full one has a manufactured solution and must meet the
//! accuracy of P1 elements on its mesh.

use approx::abs_diff_eq;
use hasse_solver::frontend::case::Case;
use hasse_solver::frontend::run;

fn examples() -> Vec<String> {
    let text = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/../cases/README.md"))
        .unwrap();
    text.split("```toml\n")
        .skip(1)
        .map(|block| block.split("```").next().unwrap().to_string())
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
    // Minimal: Poisson with zero Dirichlet data; no exact solution is given,
    // but its solution is sin(πx) sin(πy) > 0 inside: check positivity.
    let case = Case::from_text("minimal.toml", &examples[0], &[]).unwrap();
    let complex = case.build_mesh().unwrap();
    let result = run::solve(&case, &complex, &mut |_| {}).unwrap();
    let u = &result.fields.iter().find(|f| f.name == "u").unwrap().values;
    let peak = u.iter().cloned().fold(f64::MIN, f64::max);
    assert!(
        abs_diff_eq!(peak, 1.0, epsilon = 5e-3),
        "peak {peak} of sin(πx) sin(πy)"
    );

    // Full: rotated anisotropic tensor, Dirichlet/Robin/Neumann sides, P1 on
    // perturbed Kuhn triangles with h = 1/32: observed L² error 3.9e-4, and
    // 1.4e-3 / 3.4e-4 / 8.3e-5 on unperturbed 32×16, 64×32, 128×64 meshes
    // (order 2). A wrong sign in any boundary datum leaves an O(1) error.
    let case = Case::from_text("full.toml", &examples[1], &[]).unwrap();
    assert!(!case.output.write);
    let complex = case.build_mesh().unwrap();
    let result = run::solve(&case, &complex, &mut |_| {}).unwrap();
    let errors = result.errors.unwrap();
    assert!(errors.l2 < 1e-3, "L2 error {}", errors.l2);
}
