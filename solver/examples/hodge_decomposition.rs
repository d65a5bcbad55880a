//! The Hodge decomposition and harmonic forms through the library API, on
//! the embedded torus (quads, barycentric DEC stars):
//!
//! 1. the harmonic 1-forms from tree–cotree cocycles (β₁ = 2), closed and
//!    co-closed to rounding;
//! 2. a vector field F = ∇(xyz) + (−y, x, 0) turned into the 1-cochain
//!    ω = R₁F by the de Rham map (line integrals along the edges);
//! 3. ω split into exact, coexact and harmonic parts, their ⋆-norms, the
//!    pairwise ⋆-inner products (0 to rounding) and Pythagoras;
//! 4. the harmonic part's Whitney vector in a few cells.
//!
//! ```text
//! cargo run --release -p hasse-solver --example hodge_decomposition
//! ```

use hasse_complex::dual::DualKind;
use hasse_complex::generate::torus;
use hasse_solver::physics::forms::whitney_map::{cell_vectors, de_rham, Field};
use hasse_solver::physics::forms::{Forms, Star};
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
    let complex = torus(2.0, 0.7, 32, 12)?;
    let forms = Forms::new(&complex, Star::Diagonal(DualKind::Barycentric));

    let basis = forms.harmonic_basis(1)?;
    println!(
        "{} harmonic 1-forms (β₁ = {}) on {} edges",
        basis.forms.len(),
        basis.betti,
        complex.cell_count(1)
    );
    // The torus has β₁ = 2.
    ensure(
        basis.forms.len() == 2,
        format!("{} harmonic forms, not 2", basis.forms.len()),
    )?;
    for (j, (closed, coclosed)) in basis.closed.iter().zip(&basis.coclosed).enumerate() {
        println!(
            "  h{}: ‖dh‖/‖h‖ = {closed:.1e}, ‖dᵀ⋆h‖/‖⋆h‖ = {coclosed:.1e}",
            j + 1
        );
        ensure(
            *closed < 1e-12 && *coclosed < 1e-12,
            format!("h{} is not harmonic to rounding", j + 1),
        )?;
    }

    let field = |p: &[f64]| {
        let (x, y, z) = (p[0], p[1], p[2]);
        [y * z - y, x * z + x, x * y]
    };
    let omega = de_rham(&complex, 1, Field::Vector(&field))?;
    let split = forms.hodge_decomposition(&omega)?;
    let total = forms.inner(1, &omega, &omega)?;
    let names = ["exact", "coexact", "harmonic"];
    let parts = split.parts();
    let mut squares = 0.0;
    for (name, part) in names.iter().zip(parts) {
        let norm = forms.inner(1, part, part)?;
        squares += norm;
        println!("‖{name}‖² / ‖ω‖² = {:.6}", norm / total);
    }
    for (i, j) in [(0, 1), (0, 2), (1, 2)] {
        let product = forms.inner(1, parts[i], parts[j])?;
        println!(
            "⟨{}, {}⟩ / ‖ω‖² = {:.1e}",
            names[i],
            names[j],
            product / total
        );
        ensure(
            (product / total).abs() < 1e-12,
            format!(
                "the {} and {} parts are not ⋆-orthogonal",
                names[i], names[j]
            ),
        )?;
    }
    let pythagoras = (total - squares).abs() / total;
    println!("|‖ω‖² − Σ‖part‖²| / ‖ω‖² = {pythagoras:.1e}");
    ensure(pythagoras < 1e-12, "the parts' norms do not add up".into())?;

    let vectors = cell_vectors(&complex, 1, &split.harmonic)?;
    for cell in [0, 8, 16] {
        let v = vectors[cell];
        println!(
            "harmonic part at cell {cell}: ({:.4}, {:.4}, {:.4})",
            v[0], v[1], v[2]
        );
    }
    Ok(())
}
