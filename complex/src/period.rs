//! Periodic vertices (the flat torus): the periods of the identified axes
//! and the minimum image through which every cell is seen unwrapped.

use crate::cells::Vertices;
use crate::error::{ComplexError, Result};

impl Vertices {
    /// The same points on a flat torus: axis a is identified modulo
    /// `period[a]` (0 leaves it open). A vertex has one position, but a
    /// cell that wraps around has its points unwrapped near its first
    /// vertex (the minimum image) wherever the complex computes geometry,
    /// so measures, centres, duals and stars are those of the flat metric.
    /// Cells must be smaller than half a period along every periodic axis.
    ///
    /// ```
    /// use hasse_complex::Vertices;
    /// let v = Vertices::from_points(&[[0.0, 0.0], [0.9, 0.0]]).unwrap().with_period(&[1.0, 0.0]).unwrap();
    /// // 0.9 seen from 0 on a circle of length 1 is −0.1.
    /// assert!((v.nearest(&[0.9, 0.0, 0.0], &[0.0; 3])[0] + 0.1).abs() < 1e-15);
    /// ```
    pub fn with_period(mut self, period: &[f64]) -> Result<Self> {
        if period.len() != self.dim() || period.iter().any(|p| !p.is_finite() || *p < 0.0) {
            return Err(ComplexError::Invalid(format!(
                "a period needs {} finite values ≥ 0 (0: not periodic), got {period:?}",
                self.dim()
            )));
        }
        let mut padded = [0.0; 3];
        padded[..self.dim()].copy_from_slice(period);
        self.period = padded.iter().any(|&p| p > 0.0).then_some(padded);
        Ok(self)
    }

    /// The periods of a flat torus ([`Vertices::with_period`]), padded to
    /// three axes; `None` when no axis is periodic.
    pub fn period(&self) -> Option<[f64; 3]> {
        self.period
    }

    /// The image of `x` closest to `reference` (padded points): `x` itself
    /// unless the vertices are periodic.
    pub fn nearest(&self, x: &[f64; 3], reference: &[f64; 3]) -> [f64; 3] {
        let mut out = *x;
        if let Some(period) = &self.period {
            for a in 0..3 {
                if period[a] > 0.0 {
                    out[a] -= period[a] * ((out[a] - reference[a]) / period[a]).round();
                }
            }
        }
        out
    }
}
