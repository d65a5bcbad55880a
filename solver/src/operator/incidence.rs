//! How an operator receives the incidence matrix A it keeps.
//!
//! A [`Canonical`](super::Canonical) operator holds its A for as long as it
//! lives, and A is usually a boundary or coboundary matrix the complex
//! already stores. Taking it by shared pointer lets the operator and the
//! complex hold one copy; this trait lets a caller hand over whatever it
//! has — the complex's `&Arc` (`k.boundary(2)`, `k.coboundary(0)`), an
//! `Arc` it already owns, or a matrix it built itself — without spelling
//! out the conversion.

use sprs::CsMat;
use std::sync::Arc;

/// A signed incidence matrix an operator can keep without copying it when
/// it is already shared.
///
/// ```
/// use hasse_complex::generate::rectangle;
/// use hasse_solver::operator::IntoIncidence;
/// let k = rectangle(2, 1, [0.0, 2.0], [0.0, 1.0]).unwrap();
/// let kept = k.boundary(2).into_incidence(); // the complex's own ∂₂
/// assert!(std::sync::Arc::ptr_eq(&kept, k.boundary(2)));
/// let built = k.boundary(2).transpose_view().to_csr().into_incidence(); // a new matrix
/// assert_eq!(built.shape(), (2, 7));
/// ```
pub trait IntoIncidence {
    /// The matrix as a shared pointer (a pointer copy when it already is one).
    fn into_incidence(self) -> Arc<CsMat<i8>>;
}

impl IntoIncidence for Arc<CsMat<i8>> {
    fn into_incidence(self) -> Arc<CsMat<i8>> {
        self
    }
}

impl IntoIncidence for &Arc<CsMat<i8>> {
    fn into_incidence(self) -> Arc<CsMat<i8>> {
        Arc::clone(self)
    }
}

impl IntoIncidence for CsMat<i8> {
    fn into_incidence(self) -> Arc<CsMat<i8>> {
        Arc::new(self)
    }
}
