//! The refinement map of a SPLIT (ζ per dimension, plus linear
//! interpolation at new vertices) and the transfer of fields from the
//! coarse to the refined complex.
//!
//! Which transfer to use:
//!
//! - [`Refinement::intensive`] for cell averages and other densities (a
//!   temperature averaged over a cell, a conductivity, a flux density): a
//!   piece gets its parent's value. Oriented quantities on lower cells
//!   (p < n) change sign with the piece's orientation, which ζ records.
//! - [`Refinement::extensive`] for integrated quantities (a mass or heat
//!   content of a cell, the flux through a face, a circulation along an
//!   edge): a piece gets its parent's value times its share of the parent's
//!   measure, so the pieces add up to the parent — exactly ζᵀ(fine) = coarse
//!   up to rounding.
//! - [`Refinement::nodal`] for point values at vertices (P1/DEC nodal
//!   unknowns): old vertices keep their value, a vertex created at parameter
//!   t on edge (a, b) gets (1 − t) u_a + t u_b. Exact for affine fields.
//!
//! New cut cells (an edge inside a split polygon, a polygon inside a split
//! polyhedron) have no parent: the coarse field carries no value for them and
//! both cell transfers return 0 there. Use [`Refinement::parent`] to fill
//! them otherwise.

use crate::complex::Complex;
use crate::error::SplitError;
use sprs::CsMat;

/// ζ_0 … ζ_n (|K̃_p| × |K_p|, entries in {−1, 0, 1}, at most one per row)
/// and the nodal interpolation matrix (|K̃_0| × |K_0|).
///
/// ```
/// use hasse_complex::generate::rectangle;
/// use hasse_complex::split::{split, Hyperplane};
/// let k = rectangle(1, 1, [0.0, 1.0], [0.0, 1.0]).unwrap();
/// let h = Hyperplane::axis(2, 0, 0.25).unwrap();
/// let (fine, r) = split(&k, &h, None, Default::default()).unwrap();
/// // Mass 4 splits 1 : 3 by area; the average copies.
/// assert_eq!(r.extensive(&fine, 2, &[4.0]).unwrap(), vec![1.0, 3.0]);
/// assert_eq!(r.intensive(&fine, 2, &[4.0]).unwrap(), vec![4.0, 4.0]);
/// // u = x at the vertices interpolates exactly.
/// let u: Vec<f64> = (0..4).map(|v| k.vertices().point(v)[0]).collect();
/// let fine_u = r.nodal(&u).unwrap();
/// for v in 0..fine.cell_count(0) {
///     assert!((fine_u[v] - fine.vertices().point(v)[0]).abs() < 1e-15);
/// }
/// ```
#[derive(Clone, Debug, PartialEq)]
pub struct Refinement {
    zeta: Vec<CsMat<i8>>,
    nodal: CsMat<f64>,
}

impl Refinement {
    pub(crate) fn from_parts(zeta: Vec<CsMat<i8>>, nodal: CsMat<f64>) -> Self {
        Self { zeta, nodal }
    }

    /// The identity refinement of a complex (nothing split).
    ///
    /// ```
    /// use hasse_complex::generate::rectangle;
    /// use hasse_complex::split::Refinement;
    /// let k = rectangle(2, 1, [0.0, 1.0], [0.0, 1.0]).unwrap();
    /// assert_eq!(Refinement::identity(&k).zeta(1).nnz(), 7);
    /// ```
    pub fn identity(complex: &Complex) -> Self {
        let zeta = complex
            .cell_counts()
            .into_iter()
            .map(CsMat::<i8>::eye)
            .collect();
        Self {
            zeta,
            nodal: CsMat::eye(complex.cell_count(0)),
        }
    }

    /// Top dimension n.
    ///
    /// ```
    /// use hasse_complex::generate::rectangle;
    /// use hasse_complex::split::{split, Hyperplane};
    /// let k = rectangle(1, 1, [0.0, 1.0], [0.0, 1.0]).unwrap();
    /// let (fine, r) = split(&k, &Hyperplane::axis(2, 1, 0.5).unwrap(), None, Default::default()).unwrap();
    /// assert_eq!(r.dim(), 2);
    /// ```
    pub fn dim(&self) -> usize {
        self.zeta.len() - 1
    }

    /// ζ_p (refined p-cells × coarse p-cells, CSR).
    ///
    /// ```
    /// use hasse_complex::generate::rectangle;
    /// use hasse_complex::split::{split, Hyperplane};
    /// let k = rectangle(1, 1, [0.0, 1.0], [0.0, 1.0]).unwrap();
    /// let (fine, r) = split(&k, &Hyperplane::axis(2, 1, 0.5).unwrap(), None, Default::default()).unwrap();
    /// // The square maps to both halves, the bottom edge to itself.
    /// assert_eq!(r.zeta(2).to_dense().as_slice().unwrap(), &[1, 1]);
    /// assert_eq!(r.zeta(1).shape(), (fine.cell_count(1), 4));
    /// ```
    ///
    /// # Panics
    /// When p > n.
    pub fn zeta(&self, p: usize) -> &CsMat<i8> {
        &self.zeta[p]
    }

    /// The nodal interpolation matrix (refined vertices × coarse vertices).
    ///
    /// ```
    /// use hasse_complex::generate::rectangle;
    /// use hasse_complex::split::{split, Hyperplane};
    /// let k = rectangle(1, 1, [0.0, 1.0], [0.0, 1.0]).unwrap();
    /// let (fine, r) = split(&k, &Hyperplane::axis(2, 1, 0.5).unwrap(), None, Default::default()).unwrap();
    /// // Each new vertex is the midpoint of a vertical side: weights ½, ½.
    /// let row = r.nodal_matrix().outer_view(4).unwrap();
    /// assert_eq!(row.data(), &[0.5, 0.5]);
    /// ```
    pub fn nodal_matrix(&self) -> &CsMat<f64> {
        &self.nodal
    }

    /// (coarse cell counts, refined cell counts).
    ///
    /// ```
    /// use hasse_complex::generate::rectangle;
    /// use hasse_complex::split::{split, Hyperplane};
    /// let k = rectangle(1, 1, [0.0, 1.0], [0.0, 1.0]).unwrap();
    /// let (fine, r) = split(&k, &Hyperplane::axis(2, 1, 0.5).unwrap(), None, Default::default()).unwrap();
    /// assert_eq!(r.counts(), (vec![4, 4, 1], fine.cell_counts()));
    /// ```
    pub fn counts(&self) -> (Vec<usize>, Vec<usize>) {
        (
            self.zeta.iter().map(|z| z.cols()).collect(),
            self.zeta.iter().map(|z| z.rows()).collect(),
        )
    }

    /// `self` followed by `later` (a refinement of `self`'s result): ζ and
    /// the interpolation are multiplied, so repeated SPLITs compose into one
    /// map from the first complex to the last.
    ///
    /// ```
    /// use hasse_complex::generate::rectangle;
    /// use hasse_complex::split::{split, Hyperplane};
    /// let k = rectangle(1, 1, [0.0, 1.0], [0.0, 1.0]).unwrap();
    /// let (k1, r1) = split(&k, &Hyperplane::axis(2, 0, 0.5).unwrap(), None, Default::default()).unwrap();
    /// let (k2, r2) = split(&k1, &Hyperplane::axis(2, 1, 0.5).unwrap(), None, Default::default()).unwrap();
    /// let r = r1.compose(&r2).unwrap();
    /// assert_eq!(r.zeta(2).rows(), k2.cell_count(2));
    /// assert_eq!(r.zeta(2).nnz(), 4); // the square maps to its four quarters
    /// ```
    pub fn compose(&self, later: &Refinement) -> Result<Refinement, SplitError> {
        let (_, mine) = self.counts();
        let (theirs, _) = later.counts();
        if mine != theirs {
            return Err(SplitError::Incompatible {
                first: mine,
                second: theirs,
            });
        }
        Ok(Self {
            zeta: later
                .zeta
                .iter()
                .zip(&self.zeta)
                .map(|(b, a)| b * a)
                .collect(),
            nodal: &later.nodal * &self.nodal,
        })
    }

    /// Alias of [`Refinement::compose`], reading left to right.
    ///
    /// ```
    /// use hasse_complex::generate::rectangle;
    /// use hasse_complex::split::{split, Hyperplane};
    /// let k = rectangle(1, 1, [0.0, 1.0], [0.0, 1.0]).unwrap();
    /// let (fine, r) = split(&k, &Hyperplane::axis(2, 1, 0.5).unwrap(), None, Default::default()).unwrap();
    /// let same = Refinement::identity(&k).then(&r).unwrap();
    /// assert_eq!(same, r);
    /// # use hasse_complex::split::Refinement;
    /// ```
    pub fn then(&self, later: &Refinement) -> Result<Refinement, SplitError> {
        self.compose(later)
    }

    /// The coarse p-cell a refined p-cell comes from, with the sign of the
    /// piece relative to it; `None` for new cut cells.
    ///
    /// ```
    /// use hasse_complex::generate::rectangle;
    /// use hasse_complex::split::{split, Hyperplane};
    /// let k = rectangle(1, 1, [0.0, 1.0], [0.0, 1.0]).unwrap();
    /// let (fine, r) = split(&k, &Hyperplane::axis(2, 0, 0.5).unwrap(), None, Default::default()).unwrap();
    /// assert_eq!(r.parent(2, 1), Some((0, 1)));
    /// assert_eq!(r.parent(1, fine.cell_count(1) - 1), None); // the new edge
    /// ```
    pub fn parent(&self, p: usize, fine: usize) -> Option<(usize, i8)> {
        let z = self.zeta.get(p)?;
        let row = z.outer_view(fine)?;
        row.iter().next().map(|(j, &s)| (j, s))
    }

    fn check(&self, p: usize, values: &[f64], what: &'static str) -> Result<(), SplitError> {
        let z = self
            .zeta
            .get(p)
            .ok_or(SplitError::DimensionOutOfRange { p, dim: self.dim() })?;
        if values.len() != z.cols() {
            return Err(SplitError::LengthMismatch {
                what,
                p,
                expected: z.cols(),
                found: values.len(),
            });
        }
        Ok(())
    }

    /// `fine` is the refined complex this map was made for (its p-cells
    /// are the rows of ζ_p).
    fn check_fine(&self, fine: &Complex, p: usize) -> Result<(), SplitError> {
        let rows = self.zeta[p].rows();
        if p > fine.dim() || fine.cell_count(p) != rows {
            return Err(SplitError::LengthMismatch {
                what: "refined complex",
                p,
                expected: rows,
                found: fine.cell_count(p),
            });
        }
        Ok(())
    }

    /// Intensive values (averages, densities) on coarse p-cells → refined
    /// p-cells: each piece gets ε × its parent's value; new cut cells get 0.
    /// Takes the same arguments as [`Refinement::extensive`] (the refined
    /// complex is only checked here), so a caller can pick either by the
    /// kind of field.
    ///
    /// ```
    /// use hasse_complex::generate::rectangle;
    /// use hasse_complex::split::{split, Hyperplane};
    /// let k = rectangle(1, 1, [0.0, 1.0], [0.0, 1.0]).unwrap();
    /// let (fine, r) = split(&k, &Hyperplane::axis(2, 1, 0.5).unwrap(), None, Default::default()).unwrap();
    /// assert_eq!(r.intensive(&fine, 2, &[7.0]).unwrap(), vec![7.0, 7.0]);
    /// ```
    pub fn intensive(
        &self,
        fine: &Complex,
        p: usize,
        coarse: &[f64],
    ) -> Result<Vec<f64>, SplitError> {
        self.check(p, coarse, "intensive field")?;
        self.check_fine(fine, p)?;
        let z = &self.zeta[p];
        Ok(z.outer_iterator()
            .map(|row| {
                row.iter()
                    .next()
                    .map_or(0.0, |(j, &s)| f64::from(s) * coarse[j])
            })
            .collect())
    }

    /// Extensive values (integrals over the cell: masses, fluxes) on coarse
    /// p-cells → refined p-cells: ε × value × |piece| / Σ|pieces|, so the
    /// pieces sum (with the signs of ζ) to the parent; new cut cells get 0.
    /// `fine` must be the refined complex (its measures are used).
    ///
    /// ```
    /// use hasse_complex::generate::rectangle;
    /// use hasse_complex::split::{split, Hyperplane};
    /// let k = rectangle(1, 1, [0.0, 1.0], [0.0, 1.0]).unwrap();
    /// let (fine, r) = split(&k, &Hyperplane::axis(2, 1, 0.5).unwrap(), None, Default::default()).unwrap();
    /// // A flux of 2 through the left side (edge 1, v0 → v2) splits 1 + 1
    /// // between its halves; the upper half {2, 4} runs against its parent,
    /// // so it stores −1, and ζᵀ adds the pieces back to 2.
    /// let left = r.extensive(&fine, 1, &[0.0, 2.0, 0.0, 0.0]).unwrap();
    /// let back: f64 = (0..fine.cell_count(1))
    ///     .filter_map(|i| r.parent(1, i).map(|(_, s)| f64::from(s) * left[i]))
    ///     .sum();
    /// assert_eq!(back, 2.0);
    /// assert_eq!(left.iter().filter(|&&x| x != 0.0).count(), 2);
    /// ```
    pub fn extensive(
        &self,
        fine: &Complex,
        p: usize,
        coarse: &[f64],
    ) -> Result<Vec<f64>, SplitError> {
        self.check(p, coarse, "extensive field")?;
        self.check_fine(fine, p)?;
        let z = &self.zeta[p];
        let measure = fine.measure(p);
        let mut total = vec![0.0; z.cols()];
        for (i, row) in z.outer_iterator().enumerate() {
            if let Some((j, _)) = row.iter().next() {
                total[j] += measure[i];
            }
        }
        Ok(z.outer_iterator()
            .enumerate()
            .map(|(i, row)| {
                row.iter().next().map_or(0.0, |(j, &s)| {
                    f64::from(s) * coarse[j] * measure[i] / total[j]
                })
            })
            .collect())
    }

    /// Nodal values → refined vertices by linear interpolation along the
    /// cut edges.
    ///
    /// ```
    /// use hasse_complex::generate::rectangle;
    /// use hasse_complex::split::{split, Hyperplane};
    /// let k = rectangle(1, 1, [0.0, 1.0], [0.0, 1.0]).unwrap();
    /// let (fine, r) = split(&k, &Hyperplane::axis(2, 1, 0.5).unwrap(), None, Default::default()).unwrap();
    /// // u = y: the midpoints of the vertical sides get ½.
    /// assert_eq!(r.nodal(&[0.0, 0.0, 1.0, 1.0]).unwrap(), vec![0.0, 0.0, 1.0, 1.0, 0.5, 0.5]);
    /// ```
    pub fn nodal(&self, coarse: &[f64]) -> Result<Vec<f64>, SplitError> {
        if coarse.len() != self.nodal.cols() {
            return Err(SplitError::LengthMismatch {
                what: "nodal field",
                p: 0,
                expected: self.nodal.cols(),
                found: coarse.len(),
            });
        }
        Ok(self
            .nodal
            .outer_iterator()
            .map(|row| row.iter().map(|(j, &w)| w * coarse[j]).sum())
            .collect())
    }
}
