//! Warnings for a method that runs but is inconsistent on the mesh it was
//! given: the error it leaves does not shrink with h, and nothing else in
//! the summary would show it.
//!
//! - `fv` (two-point flux) with an off-diagonal conductivity tensor, and
//!   on a mesh whose cell-point lines are not orthogonal to the faces
//!   ([`fv::non_orthogonality`], tolerance
//!   [`fv::NON_ORTHOGONALITY_TOLERANCE`]);
//! - `dec-barycentric` with its diagonal star where the star's effective
//!   conductivity is not I ([`dec::worst_effective_conductivity`],
//!   tolerance [`dec::EFFECTIVE_CONDUCTIVITY_TOLERANCE`]), for diffusion
//!   (and heat, coupled fields) and for the Maxwell mass.
//!
//! The rule is to warn, not refuse: the run goes on, and the summary's
//! `warning` lines name the worst face or vertex and the remedy.
//! Measurements that fail (a mesh the method itself will refuse) give no
//! warning; the solve reports the error.

use crate::frontend::case::Coefficient;
use crate::metric::{dec, fv, Method, Tensor};
use crate::physics::point_text;
use hasse_complex::{Complex, DualKind};

/// The warnings for a diffusion operator of `method` with `conductivity`
/// on `complex` (two-point unknowns at circumcentres when `circumcentres`).
pub(super) fn diffusion_warnings(
    complex: &Complex,
    method: Method,
    conductivity: &Coefficient,
    circumcentres: bool,
) -> Vec<String> {
    let mut warnings = Vec::new();
    match method {
        Method::Fv => {
            if let Coefficient::Tensor(rows) = conductivity {
                let off_diagonal_zero = rows.iter().enumerate().all(|(i, row)| {
                    row.iter()
                        .enumerate()
                        .all(|(j, e)| i == j || (e.is_constant() && e.eval(&[], 0.0) == 0.0))
                });
                if !off_diagonal_zero {
                    warnings.push(
                        "the two-point flux (fv) sees only n·K·n: with off-diagonal K it is inconsistent; use fv-mimetic or fe".into(),
                    );
                }
            }
            let points = if circumcentres {
                match complex.circumcentre(complex.dim()) {
                    Ok(points) => Some(points),
                    Err(_) => return warnings,
                }
            } else {
                None
            };
            if let Ok(Some(worst)) = fv::non_orthogonality(complex, points) {
                if worst.angle > fv::NON_ORTHOGONALITY_TOLERANCE || worst.angle.is_nan() {
                    let at = if circumcentres {
                        "circumcentres"
                    } else {
                        "centroids"
                    };
                    warnings.push(format!(
                        "the two-point flux (fv) is consistent only where the line between cell points is orthogonal to the face, and this mesh is not (cell points at the {at}): face {} at {} is {:.2}° off (the worst; tolerance {:.0e} rad), so fv loses its order of convergence here; use fv-mimetic or fe",
                        worst.face,
                        point_text(&worst.midpoint),
                        worst.angle.to_degrees(),
                        fv::NON_ORTHOGONALITY_TOLERANCE,
                    ));
                }
            }
        }
        Method::Dec(DualKind::Barycentric) if diagonal_star(conductivity) => {
            if let Some(text) = barycentric_text(complex) {
                warnings.push(format!(
                    "the barycentric Hodge star (dec-barycentric) is inconsistent on this mesh: {text}, so u converges to the solution of −∇·(K_eff ∇u) = f, not of the problem posed; use fe (or dec on a Delaunay triangulation)"
                ));
            }
        }
        _ => {}
    }
    warnings
}

/// The warning for a Maxwell cavity whose mass is the barycentric
/// diagonal ⋆₁.
pub(super) fn maxwell_warning(complex: &Complex) -> Option<String> {
    barycentric_text(complex).map(|text| format!(
        "the barycentric Hodge star (dec-barycentric) is an inconsistent mass on this mesh: {text}, so the cavity behaves as if filled with an anisotropic medium K_eff (double eigenvalues split); use problem.mass = \"whitney\" (simplices), or dec on a well-centred mesh"
    ))
}

/// "at vertex v (x) K_eff = …" when the barycentric star's worst interior
/// vertex is beyond the tolerance.
fn barycentric_text(complex: &Complex) -> Option<String> {
    let worst = dec::worst_effective_conductivity(complex, DualKind::Barycentric).ok()??;
    if worst.deviation <= dec::EFFECTIVE_CONDUCTIVITY_TOLERANCE {
        return None;
    }
    Some(format!(
        "at vertex {} {} its effective conductivity is K_eff = {} instead of I (‖K_eff − I‖ = {:.3}, the worst interior vertex; tolerance {:.0e})",
        worst.vertex,
        point_text(&worst.point),
        tensor_text(&worst.tensor, complex.embedding_dim()),
        worst.deviation,
        dec::EFFECTIVE_CONDUCTIVITY_TOLERANCE,
    ))
}

/// Whether DEC uses its diagonal star for this conductivity: always for a
/// scalar; for a tensor only where it is λI (otherwise the Whitney star,
/// which is the consistent P1 stiffness), read here from the expressions:
/// off-diagonal entries constant zero and the diagonal entries one text.
fn diagonal_star(conductivity: &Coefficient) -> bool {
    match conductivity {
        Coefficient::Scalar(_) => true,
        Coefficient::Tensor(rows) => rows.iter().enumerate().all(|(i, row)| {
            row.iter().enumerate().all(|(j, e)| {
                if i == j {
                    e.text() == rows[0][0].text()
                } else {
                    e.is_constant() && e.eval(&[], 0.0) == 0.0
                }
            })
        }),
    }
}

/// `[[a, b], [b, c]]` with three decimals, over the leading d×d block.
fn tensor_text(t: &Tensor, d: usize) -> String {
    let rows: Vec<String> = t
        .iter()
        .take(d)
        .map(|row| {
            let entries: Vec<String> = row.iter().take(d).map(|x| format!("{x:.3}")).collect();
            format!("[{}]", entries.join(", "))
        })
        .collect();
    format!("[{}]", rows.join(", "))
}
