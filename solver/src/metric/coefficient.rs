//! The coefficient K of every top cell, as the metrics read it, and the
//! one check that it is symmetric positive definite: made once per
//! assembly ([`CellTensors::checked`]), after which the metrics reuse it.

use super::MetricError;
use rayon::prelude::*;

/// A symmetric tensor; the leading d×d block is used in R^d.
pub type Tensor = [[f64; 3]; 3];

/// λ·I as a tensor.
pub fn isotropic(lambda: f64) -> Tensor {
    [[lambda, 0.0, 0.0], [0.0, lambda, 0.0], [0.0, 0.0, lambda]]
}

/// The coefficient K of every top cell, as the metrics read it: one scalar
/// λ per cell (K = λ·I, 8 bytes a cell instead of 72) or one symmetric
/// tensor per cell. Slices and vectors of either convert with `into()`, so
/// every metric takes `&tensors` for a `Vec<Tensor>` or a `Vec<f64>`.
///
/// A value remembers that it passed the check of [`check_tensors`] for a
/// number of cells and a dimension: the problem layer checks once per
/// assembly, and a metric given such a value does not check it again.
///
/// ```
/// use hasse_complex::generate::rectangle;
/// use hasse_solver::metric::{check_tensors, fv, isotropic, CellTensors};
/// let k = rectangle(2, 1, [0.0, 2.0], [0.0, 1.0]).unwrap();
/// // The same two-point fluxes from scalars and from the tensors λ·I.
/// let from_scalars = fv::two_point(&k, &vec![2.0, 3.0]).unwrap();
/// let from_tensors = fv::two_point(&k, &vec![isotropic(2.0), isotropic(3.0)]).unwrap();
/// assert_eq!(from_scalars, from_tensors);
/// // A check names the first bad cell.
/// let bad = check_tensors(CellTensors::from(&[1.0, -1.0][..]), 2, 2).unwrap_err();
/// assert!(bad.to_string().contains("top cell 1"));
/// ```
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CellTensors<'a> {
    values: Values<'a>,
    /// (cells, d) of a check this value passed.
    checked: Option<(usize, usize)>,
}

#[derive(Clone, Copy, Debug, PartialEq)]
enum Values<'a> {
    /// K = λ_c·I in cell c.
    Scalar(&'a [f64]),
    /// K of cell c, symmetric; the leading d×d block is used in R^d.
    Full(&'a [Tensor]),
}

impl<'a> CellTensors<'a> {
    /// K = λ_c·I in cell c.
    pub fn scalar(values: &'a [f64]) -> Self {
        Self {
            values: Values::Scalar(values),
            checked: None,
        }
    }

    /// K_c in cell c, symmetric.
    pub fn full(tensors: &'a [Tensor]) -> Self {
        Self {
            values: Values::Full(tensors),
            checked: None,
        }
    }

    /// Number of cells with a coefficient.
    pub fn len(&self) -> usize {
        match self.values {
            Values::Scalar(values) => values.len(),
            Values::Full(tensors) => tensors.len(),
        }
    }

    /// Whether no cell has a coefficient.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// K of cell `c` as a tensor.
    pub fn get(&self, c: usize) -> Tensor {
        match self.values {
            Values::Scalar(values) => isotropic(values[c]),
            Values::Full(tensors) => tensors[c],
        }
    }

    /// The scalars λ_c when K = λ_c·I was given that way.
    pub fn scalars(&self) -> Option<&'a [f64]> {
        match self.values {
            Values::Scalar(values) => Some(values),
            Values::Full(_) => None,
        }
    }

    /// The same coefficients, checked to be one symmetric positive definite
    /// tensor per each of `cells` top cells in R^`d`: the first bad cell in
    /// cell order is reported. A value already checked for the same cells
    /// and dimension is returned as it is, without a second pass.
    pub fn checked(self, cells: usize, d: usize) -> Result<Self, MetricError> {
        if self.checked == Some((cells, d)) {
            return Ok(self);
        }
        if self.len() != cells {
            return Err(MetricError::CoefficientCount {
                count: self.len(),
                cells,
            });
        }
        // In parallel; the first bad cell in cell order is the one reported.
        let problem = match self.values {
            // λ·I is positive definite exactly when λ > 0; the error is the
            // one `tensor_problem` gives for λ·I (its first minor is λ).
            Values::Scalar(values) => {
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
            Values::Full(all) => all
                .par_iter()
                .enumerate()
                .find_map_first(|(cell, t)| tensor_problem(t, cell, d)),
        };
        match problem {
            Some(problem) => Err(problem),
            None => Ok(Self {
                checked: Some((cells, d)),
                ..self
            }),
        }
    }
}

impl<'a> From<&'a [Tensor]> for CellTensors<'a> {
    fn from(tensors: &'a [Tensor]) -> Self {
        Self::full(tensors)
    }
}

impl<'a> From<&'a Vec<Tensor>> for CellTensors<'a> {
    fn from(tensors: &'a Vec<Tensor>) -> Self {
        Self::full(tensors)
    }
}

impl<'a, const N: usize> From<&'a [Tensor; N]> for CellTensors<'a> {
    fn from(tensors: &'a [Tensor; N]) -> Self {
        Self::full(tensors)
    }
}

impl<'a> From<&'a [f64]> for CellTensors<'a> {
    fn from(values: &'a [f64]) -> Self {
        Self::scalar(values)
    }
}

impl<'a> From<&'a Vec<f64>> for CellTensors<'a> {
    fn from(values: &'a Vec<f64>) -> Self {
        Self::scalar(values)
    }
}

impl<'a, const N: usize> From<&'a [f64; N]> for CellTensors<'a> {
    fn from(values: &'a [f64; N]) -> Self {
        Self::scalar(values)
    }
}

/// Check that there is one coefficient per each of `cells` top cells and
/// that each is symmetric positive definite in R^`d` (its leading d×d
/// block, by Sylvester's criterion on the symmetric part); the first bad
/// cell in cell order is reported. Every metric makes this check itself,
/// once per assembly.
///
/// ```
/// use hasse_solver::metric::{check_tensors, isotropic, MetricError};
/// // [[1, 2], [2, 1]] has eigenvalues 3 and −1: not positive definite.
/// let bad = [[1.0, 2.0, 0.0], [2.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
/// assert!(check_tensors(&vec![isotropic(1.0), isotropic(2.0)], 2, 2).is_ok());
/// let error = check_tensors(&vec![isotropic(1.0), bad], 2, 2).unwrap_err();
/// assert!(matches!(error, MetricError::NotPositive { cell: 1, .. }));
/// // In R¹ only the leading 1×1 block counts.
/// assert!(check_tensors(&vec![bad], 1, 1).is_ok());
/// ```
pub fn check_tensors<'a>(
    tensors: impl Into<CellTensors<'a>>,
    cells: usize,
    d: usize,
) -> Result<(), MetricError> {
    tensors.into().checked(cells, d).map(|_| ())
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
