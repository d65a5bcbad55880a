//! The metrics Ω, one module per method. Each builds a [`BlockMetric`]
//! over the rows of a topological incidence matrix A:
//!
//! | method | unknowns | A | rows of Ω |
//! |---|---|---|---|
//! | FE (P1, Q1, VEM) | vertices | δ⁰ = ∂₁ᵀ | edges |
//! | DEC | vertices | δ⁰ = ∂₁ᵀ | edges |
//! | FV two-point | top cells | ∂ₙ | (n−1)-cells |
//! | FD five/seven-point | top cells | ∂ₙ | (n−1)-cells |
//! | FV mimetic (hybrid) | top cells and (n−1)-cells | half-face incidence | half-faces |
//!
//! Coefficients arrive as one symmetric tensor per top cell, already
//! evaluated by the problem layer: [`CellTensors`], either one full tensor
//! per cell or one scalar λ per cell (K = λ·I, stored as 8 bytes a cell
//! instead of 72).
//!
//! [`BlockMetric`]: crate::operator::BlockMetric

pub mod dec;
pub mod fd;
pub mod fe;
pub mod fv;
pub mod mass;
mod method;

pub use method::{Location, Method, UnknownMethod};

use hasse_complex::ComplexError;
use rayon::prelude::*;

/// A symmetric tensor; the leading d×d block is used in R^d.
pub type Tensor = [[f64; 3]; 3];

/// λ·I as a tensor.
pub fn isotropic(lambda: f64) -> Tensor {
    [[lambda, 0.0, 0.0], [0.0, lambda, 0.0], [0.0, 0.0, lambda]]
}

/// The coefficient K of every top cell, as the metrics read it: one scalar
/// λ per cell (K = λ·I) or one symmetric tensor per cell. Slices and
/// vectors of either convert with `into()`, so every metric takes
/// `&tensors` for a `Vec<Tensor>` or a `Vec<f64>`.
///
/// ```
/// use hasse_complex::generate::rectangle;
/// use hasse_solver::metric::{fv, isotropic};
/// let k = rectangle(2, 1, [0.0, 2.0], [0.0, 1.0]).unwrap();
/// // The same two-point fluxes from scalars and from the tensors λ·I.
/// let from_scalars = fv::two_point(&k, &vec![2.0, 3.0]).unwrap();
/// let from_tensors = fv::two_point(&k, &vec![isotropic(2.0), isotropic(3.0)]).unwrap();
/// assert_eq!(from_scalars, from_tensors);
/// ```
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum CellTensors<'a> {
    /// K = λ_c·I in cell c.
    Scalar(&'a [f64]),
    /// K of cell c, symmetric; the leading d×d block is used in R^d.
    Full(&'a [Tensor]),
}

impl CellTensors<'_> {
    /// Number of cells with a coefficient.
    pub fn len(&self) -> usize {
        match self {
            Self::Scalar(values) => values.len(),
            Self::Full(tensors) => tensors.len(),
        }
    }

    /// Whether no cell has a coefficient.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// K of cell `c` as a tensor.
    pub fn get(&self, c: usize) -> Tensor {
        match self {
            Self::Scalar(values) => isotropic(values[c]),
            Self::Full(tensors) => tensors[c],
        }
    }
}

impl<'a> From<&'a [Tensor]> for CellTensors<'a> {
    fn from(tensors: &'a [Tensor]) -> Self {
        Self::Full(tensors)
    }
}

impl<'a> From<&'a Vec<Tensor>> for CellTensors<'a> {
    fn from(tensors: &'a Vec<Tensor>) -> Self {
        Self::Full(tensors)
    }
}

impl<'a, const N: usize> From<&'a [Tensor; N]> for CellTensors<'a> {
    fn from(tensors: &'a [Tensor; N]) -> Self {
        Self::Full(tensors)
    }
}

impl<'a> From<&'a [f64]> for CellTensors<'a> {
    fn from(values: &'a [f64]) -> Self {
        Self::Scalar(values)
    }
}

impl<'a> From<&'a Vec<f64>> for CellTensors<'a> {
    fn from(values: &'a Vec<f64>) -> Self {
        Self::Scalar(values)
    }
}

impl<'a, const N: usize> From<&'a [f64; N]> for CellTensors<'a> {
    fn from(values: &'a [f64; N]) -> Self {
        Self::Scalar(values)
    }
}

/// Why a metric could not be built.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum MetricError {
    #[error("{method} needs {needs}; top cell {cell} is not one")]
    UnsupportedCell {
        method: &'static str,
        needs: &'static str,
        cell: usize,
    },
    #[error("{method} needs {needs}: {detail}")]
    UnsupportedMesh {
        method: &'static str,
        needs: &'static str,
        detail: String,
    },
    #[error("coefficient in top cell {cell} is not symmetric positive definite (eigenvalue estimate {value:e}); diffusion coefficients must be > 0")]
    NotPositive { cell: usize, value: f64 },
    #[error("coefficient in top cell {cell} is not finite")]
    NonFinite { cell: usize },
    #[error("{count} coefficients given for {cells} top cells")]
    CoefficientCount { count: usize, cells: usize },
    #[error(transparent)]
    Geometry(#[from] ComplexError),
}

/// Check one tensor per top cell, symmetric positive definite in R^d.
pub fn check_tensors<'a>(
    tensors: impl Into<CellTensors<'a>>,
    cells: usize,
    d: usize,
) -> Result<(), MetricError> {
    let tensors = tensors.into();
    if tensors.len() != cells {
        return Err(MetricError::CoefficientCount {
            count: tensors.len(),
            cells,
        });
    }
    // In parallel; the first bad cell in cell order is the one reported.
    let problem = match tensors {
        // λ·I is positive definite exactly when λ > 0; the error is the
        // one `tensor_problem` gives for λ·I (its first minor is λ).
        CellTensors::Scalar(values) => {
            values
                .par_iter()
                .enumerate()
                .find_map_first(|(cell, &lambda)| {
                    if !lambda.is_finite() {
                        Some(MetricError::NonFinite { cell })
                    } else if lambda <= 0.0 {
                        Some(MetricError::NotPositive {
                            cell,
                            value: lambda,
                        })
                    } else {
                        None
                    }
                })
        }
        CellTensors::Full(all) => all
            .par_iter()
            .enumerate()
            .find_map_first(|(cell, t)| tensor_problem(t, cell, d)),
    };
    match problem {
        Some(problem) => Err(problem),
        None => Ok(()),
    }
}

/// Why tensor `t` of `cell` is not symmetric positive definite in R^d, if
/// it is not.
fn tensor_problem(t: &Tensor, cell: usize, d: usize) -> Option<MetricError> {
    if t.iter().flatten().any(|v| !v.is_finite()) {
        return Some(MetricError::NonFinite { cell });
    }
    // Leading principal minors > 0 (Sylvester) on the symmetric part,
    // scaled to unit size first: the minors of a valid K = 1e-200·I
    // would otherwise underflow to zero.
    let scale = t[..d]
        .iter()
        .flat_map(|row| row[..d].iter())
        .fold(0.0f64, |a, v| a.max(v.abs()));
    let scale = if scale > 0.0 { scale } else { 1.0 };
    let m = |i: usize, j: usize| 0.5 * (t[i][j] + t[j][i]) / scale;
    let minors = [
        m(0, 0),
        m(0, 0) * m(1, 1) - m(0, 1) * m(1, 0),
        m(0, 0) * (m(1, 1) * m(2, 2) - m(1, 2) * m(2, 1))
            - m(0, 1) * (m(1, 0) * m(2, 2) - m(1, 2) * m(2, 0))
            + m(0, 2) * (m(1, 0) * m(2, 1) - m(1, 1) * m(2, 0)),
    ];
    minors[..d]
        .iter()
        .find(|&&v| v <= 0.0)
        .map(|&bad| MetricError::NotPositive {
            cell,
            value: bad * scale,
        })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn scalar_coefficients_are_checked_like_their_isotropic_tensors() {
        // λ·I is positive definite exactly when λ > 0; the reported value
        // is λ itself (the first leading minor), and the first bad cell in
        // cell order is named.
        let cases: [(&[f64], Option<MetricError>); 5] = [
            (&[1.0, 2.0, 1e-200], None),
            (
                &[1.0, -2.0, 0.0],
                Some(MetricError::NotPositive {
                    cell: 1,
                    value: -2.0,
                }),
            ),
            (
                &[1.0, 1.0, 0.0],
                Some(MetricError::NotPositive {
                    cell: 2,
                    value: 0.0,
                }),
            ),
            (&[f64::NAN, -1.0], Some(MetricError::NonFinite { cell: 0 })),
            (
                &[1.0, f64::INFINITY],
                Some(MetricError::NonFinite { cell: 1 }),
            ),
        ];
        for (values, expected) in cases {
            let tensors: Vec<Tensor> = values.iter().map(|&v| isotropic(v)).collect();
            for d in 1..=3 {
                let scalar = check_tensors(values, values.len(), d).err();
                let full = check_tensors(&tensors, values.len(), d).err();
                assert_eq!(scalar, expected, "{values:?} in R^{d}");
                assert_eq!(full, expected, "{values:?} in R^{d}");
            }
        }
        assert_eq!(
            check_tensors(&[1.0, 2.0][..], 3, 2),
            Err(MetricError::CoefficientCount { count: 2, cells: 3 })
        );
    }
}
