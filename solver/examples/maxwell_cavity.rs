//! Resonant modes of the [0, π]² and [0, π]³ cavities with perfectly
//! conducting walls: computed ω² next to the analytic m² + n² (+ p²), and
//! the observed order of the relative error under refinement.
//!
//! ```text
//! cargo run --release -p hasse-solver --example maxwell_cavity
//! ```

use hasse_complex::dual::DualKind;
use hasse_complex::generate::{box3, kuhn, rectangle, uniform_axis};
use hasse_solver::physics::maxwell::{Cavity, Mass};
use std::f64::consts::PI;

fn table(title: &str, exact: &[f64], levels: &[usize], build: impl Fn(usize) -> Cavity) {
    println!("\n{title}");
    let mut previous: Option<Vec<f64>> = None;
    for &n in levels {
        let cavity = build(n);
        let modes = cavity
            .modes(exact.len(), &cavity.default_options())
            .expect("cavity modes");
        let errors: Vec<f64> = modes
            .eigenvalues
            .iter()
            .zip(exact)
            .map(|(g, e)| (g - e).abs() / e)
            .collect();
        print!(
            "n={n:3} unknowns={:6} gradients={:6} basis={:4} |",
            cavity.unknowns(),
            cavity.gradient_count(),
            modes.basis
        );
        for (j, value) in modes.eigenvalues.iter().enumerate() {
            match &previous {
                Some(p) => print!(" {value:.6} (p={:.3})", (p[j] / errors[j]).log2()),
                None => print!(" {value:.6}"),
            }
        }
        println!();
        previous = Some(errors);
    }
    println!("exact      {exact:?}");
}

fn main() {
    table(
        "[0,π]² DEC (Yee) on n×n squares",
        &[1.0, 1.0, 2.0, 4.0, 4.0, 5.0, 5.0, 8.0],
        &[8, 16, 32, 64, 128],
        |n| {
            let k = rectangle(n, n, [0.0, PI], [0.0, PI]).unwrap();
            Cavity::new(&k, DualKind::Barycentric, Mass::Hodge).unwrap()
        },
    );
    table(
        "[0,π]² Nédélec (Whitney mass) on Kuhn triangles",
        &[1.0, 1.0, 2.0, 4.0, 4.0, 5.0, 5.0, 8.0],
        &[8, 16, 32, 64],
        |n| {
            let x = uniform_axis(n, 0.0, PI).unwrap();
            let k = kuhn(&[x.clone(), x]).unwrap();
            Cavity::new(&k, DualKind::Circumcentric, Mass::Whitney).unwrap()
        },
    );
    table(
        "[0,π]³ DEC (Yee) on n×n×n cubes",
        &[2.0, 2.0, 2.0, 3.0, 3.0, 5.0, 5.0, 5.0, 5.0, 5.0, 5.0],
        &[4, 8, 16],
        |n| {
            let k = box3(n, n, n, [0.0, PI], [0.0, PI], [0.0, PI]).unwrap();
            Cavity::new(&k, DualKind::Barycentric, Mass::Hodge).unwrap()
        },
    );
}
