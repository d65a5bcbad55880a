//! The Poisson problem for 1-forms, Δ₁u = f, through the library API on
//! the embedded torus (quads, barycentric DEC stars), which has two
//! harmonic 1-forms:
//!
//! 1. f = R₁F, the de Rham cochain of F = ∇(xyz) + (−y, x, 0) (the second
//!    term has a harmonic part along the tube's long way round);
//! 2. Δ₁u = f − P_ℌ f solved with u ⊥ ℌ; the harmonic part P_ℌ f taken
//!    out of the source is compared with the harmonic part of the Hodge
//!    decomposition of f (another solve: they must agree to rounding);
//! 3. u is orthogonal to both harmonic forms; δu is printed.
//!
//! ```text
//! cargo run --release -p hasse-solver --example form_poisson
//! ```

use hasse_complex::dual::DualKind;
use hasse_complex::generate::torus;
use hasse_solver::physics::forms::whitney_map::{de_rham, Field};
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

fn main() -> Result<(), Box<dyn Error>> {
    let complex = torus(2.0, 0.7, 48, 16)?;
    let forms = Forms::new(&complex, Star::Diagonal(DualKind::Barycentric));
    let field = |p: &[f64]| {
        let (x, y, z) = (p[0], p[1], p[2]);
        [y * z - y, x * z + x, x * y]
    };
    let f = de_rham(&complex, 1, Field::Vector(&field))?;
    let solved = forms.poisson(1, Boundary::Natural, &f)?;
    let norm = |a: &[f64]| forms.inner(1, a, a).map(f64::sqrt);
    println!(
        "Δ₁u = f on {} edges: {} harmonic 1-forms, ‖P_ℌ f‖/‖f‖ = {:.6}, relative residual {:.1e} ({})",
        complex.cell_count(1),
        solved.harmonic.len(),
        norm(&solved.source_harmonic)? / norm(&f)?,
        solved.residual,
        solved.factorization
    );
    ensure(
        solved.harmonic.len() == 2,
        format!("{} harmonic forms, not β₁ = 2", solved.harmonic.len()),
    )?;
    ensure(
        solved.residual < 1e-12,
        format!("residual {:.1e}", solved.residual),
    )?;

    // The decomposition's harmonic part comes from other solves (the
    // exact and coexact parts): it must equal P_ℌ f.
    let parts = forms.hodge_decomposition(&f)?;
    let difference: Vec<f64> = parts
        .harmonic
        .iter()
        .zip(&solved.source_harmonic)
        .map(|(a, b)| a - b)
        .collect();
    let agreement = norm(&difference)? / norm(&parts.harmonic)?;
    println!("P_ℌ f against the decomposition's harmonic part: {agreement:.1e} relative");
    ensure(agreement < 1e-10, format!("they differ by {agreement:.1e}"))?;

    let u_norm = norm(&solved.solution)?;
    for (j, h) in solved.harmonic.iter().enumerate() {
        let overlap = forms.inner(1, &solved.solution, h)? / u_norm;
        println!("⟨u, h{}⟩ / ‖u‖ = {overlap:.1e}", j + 1);
        ensure(overlap.abs() < 1e-12, format!("u is not ⊥ h{}", j + 1))?;
    }
    println!(
        "‖u‖_⋆ = {u_norm:.6}, ‖δu‖_⋆ = {:.6}",
        forms
            .inner(0, &solved.codifferential, &solved.codifferential)?
            .sqrt()
    );
    Ok(())
}
