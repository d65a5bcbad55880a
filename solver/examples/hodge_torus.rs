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

fn report(name: &str, complex: &Complex, star: Star) -> Result<(), Box<dyn Error>> {
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
    Ok(())
}

fn main() -> Result<(), Box<dyn Error>> {
    let barycentric = Star::Diagonal(DualKind::Barycentric);
    report(
        "embedded torus 32 × 12",
        &torus(2.0, 0.7, 32, 12)?,
        barycentric,
    )?;
    report(
        "flat torus 16 × 8 squares",
        &torus_flat(16, 8, [0.0, 2.0], [0.0, 1.0], false)?,
        barycentric,
    )?;
    report(
        "flat torus 16 × 8 triangles, Whitney",
        &torus_flat(16, 8, [0.0, 2.0], [0.0, 1.0], true)?,
        Star::Whitney,
    )?;
    Ok(())
}
