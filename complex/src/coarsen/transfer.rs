//! Fields from the fine to the coarse complex through the coarsening's
//! chain maps: the restrictions that match SPLIT's transfers
//! ([`crate::split::Refinement`]).
//!
//! - [`Coarsening::restrict_extensive`] for amounts (a cell's mass, a
//!   face's flux): the pieces add up, ζᵀ. Conservative to rounding.
//! - [`Coarsening::restrict_intensive`] for averages and densities: the
//!   measure-weighted mean of the pieces, M′⁻¹ Pᵀ M with P the intensive
//!   prolongation (a piece gets its parent's value) and M the measures.
//!   After prolongation it gives the coarse field back; a constant stays
//!   exactly constant.
//! - [`Coarsening::restrict_nodal`] for vertex values: injection at the
//!   kept vertices (exact for every field that the fine vertices sample).

use super::Coarsening;
use crate::complex::Complex;
use crate::error::SplitError;
use crate::split::Refinement;
use sprs::TriMat;

impl Coarsening {
    fn check(&self, p: usize, values: &[f64], what: &'static str) -> Result<(), SplitError> {
        let z = self
            .zeta
            .get(p)
            .ok_or(SplitError::DimensionOutOfRange { p, dim: self.dim() })?;
        if values.len() != z.rows() {
            return Err(SplitError::LengthMismatch {
                what,
                p,
                expected: z.rows(),
                found: values.len(),
            });
        }
        Ok(())
    }

    /// Amounts on fine p-cells → coarse p-cells: each coarse cell gets the
    /// signed sum of its pieces (ζᵀ); removed cells contribute nothing.
    ///
    /// ```
    /// use hasse_complex::coarsen::coarsen;
    /// use hasse_complex::generate::rectangle;
    /// use hasse_complex::refine::uniform;
    /// let k = rectangle(1, 1, [0.0, 1.0], [0.0, 1.0]).unwrap();
    /// let (fine, r) = uniform(&k).unwrap();
    /// let (_, c) = coarsen(&fine, &r, &[0]).unwrap();
    /// assert_eq!(c.restrict_extensive(2, &[1.0, 2.0, 3.0, 4.0]).unwrap(), vec![10.0]);
    /// ```
    pub fn restrict_extensive(&self, p: usize, fine: &[f64]) -> Result<Vec<f64>, SplitError> {
        self.check(p, fine, "extensive field")?;
        let z = &self.zeta[p];
        let mut out = vec![0.0; z.cols()];
        for (f, row) in z.outer_iterator().enumerate() {
            for (c, &s) in row.iter() {
                out[c] += f64::from(s) * fine[f];
            }
        }
        Ok(out)
    }

    /// Averages on fine p-cells → coarse p-cells: the mean of the pieces
    /// weighted by their measures in `fine_complex` (the fine complex of
    /// this coarsening), with the signs of ζ for oriented lower cells.
    /// Written as v₀ + Σ|f|(v_f − v₀)/Σ|f| (v₀ the first piece's value),
    /// so that equal pieces give their value exactly. Cells the kills
    /// removed carry no value into the coarse complex.
    ///
    /// ```
    /// use hasse_complex::coarsen::coarsen;
    /// use hasse_complex::generate::rectangle;
    /// use hasse_complex::refine::uniform;
    /// let k = rectangle(1, 1, [0.0, 1.0], [0.0, 1.0]).unwrap();
    /// let (fine, r) = uniform(&k).unwrap();
    /// let (_, c) = coarsen(&fine, &r, &[0]).unwrap();
    /// // Four equal quarters: the plain mean.
    /// assert_eq!(c.restrict_intensive(&fine, 2, &[1.0, 2.0, 3.0, 6.0]).unwrap(), vec![3.0]);
    /// ```
    pub fn restrict_intensive(
        &self,
        fine_complex: &Complex,
        p: usize,
        fine: &[f64],
    ) -> Result<Vec<f64>, SplitError> {
        self.check(p, fine, "intensive field")?;
        let z = &self.zeta[p];
        if p > fine_complex.dim() || fine_complex.cell_count(p) != z.rows() {
            return Err(SplitError::LengthMismatch {
                what: "fine complex",
                p,
                expected: z.rows(),
                found: fine_complex.cell_count(p),
            });
        }
        let measure = fine_complex.measure(p);
        let mut first: Vec<Option<f64>> = vec![None; z.cols()];
        let mut total = vec![0.0; z.cols()];
        let mut sum = vec![0.0; z.cols()];
        for (f, row) in z.outer_iterator().enumerate() {
            for (c, &s) in row.iter() {
                let v = f64::from(s) * fine[f];
                let v0 = *first[c].get_or_insert(v);
                total[c] += measure[f];
                sum[c] += measure[f] * (v - v0);
            }
        }
        Ok(first
            .iter()
            .zip(total.iter().zip(&sum))
            .map(|(v0, (t, s))| v0.map_or(0.0, |v0| v0 + s / t))
            .collect())
    }

    /// Vertex values → coarse vertices by injection (each coarse vertex is
    /// a fine one).
    ///
    /// ```
    /// use hasse_complex::coarsen::coarsen;
    /// use hasse_complex::generate::rectangle;
    /// use hasse_complex::refine::uniform;
    /// let k = rectangle(1, 1, [0.0, 1.0], [0.0, 1.0]).unwrap();
    /// let (fine, r) = uniform(&k).unwrap();
    /// let (_, c) = coarsen(&fine, &r, &[0]).unwrap();
    /// let u: Vec<f64> = (0..9).map(|v| v as f64).collect();
    /// assert_eq!(c.restrict_nodal(&u).unwrap(), vec![0.0, 1.0, 2.0, 3.0]);
    /// ```
    pub fn restrict_nodal(&self, fine: &[f64]) -> Result<Vec<f64>, SplitError> {
        self.check(0, fine, "nodal field")?;
        Ok(self.vertices.iter().map(|&v| fine[v]).collect())
    }

    /// The refinement from an earlier complex K₀ to the coarse complex,
    /// given the refinement `earlier` from K₀ to the fine complex: ζ′ = ψζ
    /// and the nodal interpolation's rows at the kept vertices. Valid when
    /// the coarsening only undid splits of that refinement (so a coarse
    /// cell is again a union of pieces of one K₀ cell); an error otherwise.
    ///
    /// ```
    /// use hasse_complex::coarsen::coarsen;
    /// use hasse_complex::generate::rectangle;
    /// use hasse_complex::refine::uniform;
    /// let k = rectangle(2, 1, [0.0, 2.0], [0.0, 1.0]).unwrap();
    /// let (fine, r) = uniform(&k).unwrap();
    /// let (coarse, c) = coarsen(&fine, &r, &[1]).unwrap();
    /// let from_k = c.after(&r).unwrap();
    /// // Square 0 is still in its four quarters, square 1 is whole again.
    /// assert_eq!(from_k.zeta(2).nnz(), coarse.cell_count(2));
    /// assert_eq!(coarse.cell_count(2), 5);
    /// ```
    pub fn after(&self, earlier: &Refinement) -> Result<Refinement, SplitError> {
        let (_, fine) = earlier.counts();
        let (mine, _) = self.counts();
        if fine != mine {
            return Err(SplitError::Incompatible {
                first: fine,
                second: mine,
            });
        }
        let mut zeta = Vec::with_capacity(self.psi.len());
        for (p, psi) in self.psi.iter().enumerate() {
            let z = (psi * earlier.zeta(p)).to_csr();
            if let Some((row, _)) = z
                .outer_iterator()
                .enumerate()
                .find(|(_, r)| r.nnz() > 1 || r.data().iter().any(|v| v.abs() != 1))
            {
                return Err(SplitError::Invalid(format!(
                    "coarse {p}-cell {row} is not a piece of one cell of the earlier complex"
                )));
            }
            zeta.push(z);
        }
        let nodal = earlier.nodal_matrix();
        let mut t = TriMat::new((self.vertices.len(), nodal.cols()));
        for (i, &v) in self.vertices.iter().enumerate() {
            if let Some(row) = nodal.outer_view(v) {
                for (j, &w) in row.iter() {
                    t.add_triplet(i, j, w);
                }
            }
        }
        Ok(Refinement::from_parts(zeta, t.to_csr()))
    }
}
