//! Harmonic 1-forms through the library API: Δ₁ on the embedded torus
//! (quads, barycentric DEC stars), on the flat torus (squares) and on the
//! flat torus cut into triangles with the Whitney stars (the mixed block
//! form). Each prints dim ker Δ₁ next to β₁ = 2, the lowest nonzero
//! eigenvalues, and checks that a harmonic form h is closed (d₁h = 0) and
//! co-closed (δ₁h = 0) to rounding.
//!
//! ```text
//! cargo run --release -p hasse-solver --example hodge_torus
//! ```

use hasse_complex::dual::DualKind;
use hasse_complex::generate::{torus, torus_flat};
use hasse_complex::Complex;
use hasse_solver::physics::forms::{Boundary, Forms, Star};
use std::error::Error;

/// Rounding-level checks: an example that prints a wrong number fails
/// (CI runs every example).
fn ensure(ok: bool, what: String) -> Result<(), Box<dyn Error>> {
    if ok {
        Ok(())
    } else {
        Err(what.into())
    }
}

/// Δ₁'s kernel and lowest eigenvalues; returns the eigenvalues.
fn report(name: &str, complex: &Complex, star: Star) -> Result<Vec<f64>, Box<dyn Error>> {
    let forms = Forms::new(complex, star);
    let laplacian = forms.hodge_laplacian(1, Boundary::Natural)?;
    let modes = laplacian.modes(4, &laplacian.default_options())?;
    println!(
        "{name}: {} edges, dim ker Δ₁ = {} (β₁ = {}), λ = {:.6?}",
        laplacian.unknowns(),
        modes.kernel,
        laplacian.betti(),
        modes.eigenvalues
    );
    ensure(
        modes.kernel == laplacian.betti(),
        format!("{name}: dim ker Δ₁ = {} ≠ β₁", modes.kernel),
    )?;
    let d1 = forms.d(1)?;
    for (j, h) in modes.harmonic.iter().enumerate() {
        // d₁h: integers times values, summed per face.
        let curl = d1
            .outer_iterator()
            .map(|row| {
                row.iter()
                    .map(|(e, &s)| f64::from(s) * h[e])
                    .sum::<f64>()
                    .abs()
            })
            .fold(0.0, f64::max);
        let size = h.iter().fold(0.0f64, |m, x| m.max(x.abs()));
        print!("  h{}: max |d₁h| / max |h| = {:.1e}", j + 1, curl / size);
        ensure(
            curl / size < 1e-12,
            format!("{name}: h{} is not closed", j + 1),
        )?;
        if star.is_diagonal() {
            let delta = forms.codifferential(1)?;
            let mut div = vec![0.0; delta.nrows()];
            for (e, &he) in h.iter().enumerate() {
                let range = delta.col_range(e);
                for (&v, &x) in delta.row_idx()[range.clone()]
                    .iter()
                    .zip(&delta.val()[range])
                {
                    div[v] += x * he;
                }
            }
            let worst = div.iter().fold(0.0f64, |m, x| m.max(x.abs()));
            print!(", max |δ₁h| = {worst:.1e}");
        }
        println!();
    }
    Ok(modes.eigenvalues.clone())
}

fn main() -> Result<(), Box<dyn Error>> {
    let barycentric = Star::Diagonal(DualKind::Barycentric);
    report(
        "embedded torus 32 × 12",
        &torus(2.0, 0.7, 32, 12)?,
        barycentric,
    )?;
    let flat = report(
        "flat torus 16 × 8 squares",
        &torus_flat(16, 8, [0.0, 2.0], [0.0, 1.0], false)?,
        barycentric,
    )?;
    // The lowest nonzero eigenvalue of the periodic 5-point Laplacian with
    // 16 cells of h = 1/8 along x (the longer side): (2/h)² sin²(π/16).
    let exact = (2.0 * 8.0 * (std::f64::consts::PI / 16.0).sin()).powi(2);
    ensure(
        (flat[0] - exact).abs() < 1e-10 * exact,
        format!("flat torus: λ = {} ≠ (2/h)² sin²(π/16) = {exact}", flat[0]),
    )?;
    report(
        "flat torus 16 × 8 triangles, Whitney",
        &torus_flat(16, 8, [0.0, 2.0], [0.0, 1.0], true)?,
        Star::Whitney,
    )?;
    Ok(())
}
