//! Mixed Darcy on the unit square (p = 1 − x, no-flow top and bottom):
//! assemble the saddle point once per flux mass and factorise it with each
//! of faer's factorisations, printing the error and relative residual.
//!
//! Run: `cargo run -p hasse-solver --example darcy_factorizations -- 16`

use hasse_complex::generate::{perturb, rectangle};
use hasse_complex::DualKind;
use hasse_solver::la::direct::Factorization;
use hasse_solver::metric::fv::FluxMass;
use hasse_solver::metric::isotropic;
use hasse_solver::physics::darcy::{self, BoundaryConditions, FaceCondition};

fn main() {
    let n: usize = std::env::args()
        .nth(1)
        .and_then(|a| a.parse().ok())
        .unwrap_or(16);
    let amplitude: f64 = std::env::args()
        .nth(2)
        .and_then(|a| a.parse().ok())
        .unwrap_or(0.0);
    let k = rectangle(n, n, [0.0, 1.0], [0.0, 1.0]).expect("grid");
    // Optionally distorted: the mimetic mass stays exact for linear p.
    let k = perturb(&k, amplitude, 1).expect("perturbed grid");
    let bc = BoundaryConditions::from_fn(&k, |x| {
        if x[0] < 1e-12 {
            Some(FaceCondition::Pressure(1.0))
        } else if x[0] > 1.0 - 1e-12 {
            Some(FaceCondition::Pressure(0.0))
        } else {
            None
        }
    });
    let cells = n * n;
    for mass in [FluxMass::Dec(DualKind::Barycentric), FluxMass::Mimetic] {
        let system = darcy::assemble(
            &k,
            &vec![isotropic(1.0); cells],
            mass,
            &vec![0.0; cells],
            &bc,
        )
        .expect("assembly");
        let runs = [
            ("LDLᵀ, constrained AMD (darcy::solve)", system.solve_ldlt()),
            ("LBLᵀ, AMD", system.solve(Factorization::Lblt)),
            ("LDLᵀ, AMD", system.solve(Factorization::Ldlt)),
            ("LU", system.solve(Factorization::Lu)),
        ];
        for (kind, result) in runs {
            match result {
                Ok(s) => {
                    let err = (0..cells)
                        .map(|c| (s.pressure[c] - (1.0 - k.centroid_of(2, c)[0])).abs())
                        .fold(0.0f64, f64::max);
                    println!(
                        "{mass:?} {kind}: max pressure error {err:.2e}, residual {:.2e}",
                        s.report.relative_residual
                    );
                }
                Err(e) => println!("{mass:?} {kind}: {e}"),
            }
        }
    }
}
