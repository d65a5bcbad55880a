//! What a Darcy run reports when the pressure is defined only up to a
//! constant (flux conditions all round) and when f = 0 (issue 30,
//! item 6). Kept apart from `cli_physics`, which is past 800 lines.

use crate::cli_physics::{reported, run};
use std::path::PathBuf;

fn scratch(name: &str) -> PathBuf {
    let dir =
        std::env::temp_dir().join(format!("hasse-darcy-reports-{}-{name}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// Issue 30, item 6: a Darcy problem with flux conditions all round. Its
/// pressure is defined up to a constant (the solve returns the one with
/// Σ |c| p_c = 0), so the error is measured with that weighted mean
/// removed from both pressures; the exact p = x + 2y + 3 has mean 4.5 on
/// the unit square, which was reported as the error before. The mimetic
/// mass is exact for linear pressures (see `physics::darcy`), so what
/// is left is the rounding of the 8×8 solve: p ≈ 5 in size, a saddle
/// system of about 200 unknowns whose condition grows like h⁻², so
/// 1e-12 leaves a margin of about 10 over ε·|p|·cond (measured: about
/// 1e-14). With f = 0 the conservation line used to divide the
/// imbalance by the largest |∫f| or net outflow, both rounding, and
/// printed `relative 1.00e0`; relative to the cells' flux magnitudes
/// Σ_F |u_F| it is a few ε (each net outflow sums four fluxes), and
/// 1e-13 allows for the solve's residual on top.
#[test]
fn darcy_pure_flux_errors_and_conservation_are_at_rounding() {
    let dir = scratch("darcy-pure-flux");
    let case = dir.join("pure-flux.toml");
    // u = −∇p = (−1, −2); the flux values are the outward u·n per side.
    let text = r#"[mesh]
generator = "rectangle"
n = [8, 8]
[problem]
kind = "darcy"
method = "mimetic"
permeability = 1
source = 0
[[boundary]]
tag = "xmin"
type = "flux"
value = 1
[[boundary]]
tag = "xmax"
type = "flux"
value = -1
[[boundary]]
tag = "ymin"
type = "flux"
value = 2
[[boundary]]
tag = "ymax"
type = "flux"
value = -2
[exact]
solution = "x + 2*y + 3"
gradient = ["1", "2"]
"#;
    std::fs::write(&case, text).unwrap();
    let out = run(case.to_str().unwrap(), &[]);
    let l2 = reported(&out, "error", "L2");
    let max = reported(&out, "error", "max");
    assert!(l2 < 1e-12 && max < 1e-12, "pressure error\n{out}");
    // The flux needs no mean: exact for linear p on the mimetic mass.
    assert!(reported(&out, "flux error", "L2") < 1e-12, "{out}");
    let relative = reported(&out, "mass", "relative");
    assert!(relative < 1e-13, "conservation {relative}\n{out}");
}
