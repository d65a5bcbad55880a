//! [`Canonical`]: A and Ω, the pattern of Aᵀ Ω A, and the products that
//! need no assembled matrix.

use super::pattern::{matrix_pattern, Assembly, CellSides, Columns, GatheredPattern, LocalPattern};
use super::{BlockMetric, CanonicalError, IntoIncidence};
use crate::la::parallel::zeroed;
use faer::sparse::{SparseColMat, SymbolicSparseColMat};
use rayon::prelude::*;
use sprs::CsMat;
use std::sync::{Arc, OnceLock};

/// M = Aᵀ Ω A with its assembly pattern, or, for a block that couples two
/// sets of unknowns (the flux–pressure block of mixed Darcy flow), M =
/// Aᵀ Ω B with a second incidence matrix B over the same rows.
///
/// ```
/// use hasse_solver::metric::fd;
/// use hasse_solver::operator::Canonical;
/// // A = ∂_1ᵀ of a path of 3 vertices (2 edges), Ω = identity:
/// // Aᵀ A is the graph Laplacian tridiag(−1, 2, −1) without the end rows.
/// let a = sprs::CsMat::new((2, 3), vec![0, 2, 4], vec![0, 1, 1, 2], vec![-1i8, 1, -1, 1]);
/// let op = Canonical::new(a, fd::from_face_values(&[1.0, 1.0])).unwrap();
/// let m = op.assemble();
/// assert_eq!(m.to_dense()[(1, 1)], 2.0);
/// assert_eq!(m.to_dense()[(0, 1)], -1.0);
/// ```
#[derive(Clone, Debug)]
pub struct Canonical {
    /// A (CSR). Shared, so that a boundary matrix of the complex is used
    /// in place.
    pub(super) incidence: Arc<CsMat<i8>>,
    /// B (CSR) when M = Aᵀ Ω B couples two sets of unknowns; `None` for
    /// Aᵀ Ω A.
    pub(super) right: Option<Arc<CsMat<i8>>>,
    pub(super) metric: BlockMetric,
    /// The pattern of M, built with the operator; [`Canonical::assemble_owned`]
    /// hands it over to the matrix, and a later assembly builds it again.
    pub(super) symbolic: OnceLock<SymbolicSparseColMat<usize>>,
    pub(super) nonzeros: usize,
    /// How values reach M (boxed: it is large and `Canonical` sits in
    /// enums next to small variants).
    pub(super) assembly: Box<Assembly>,
}

/// Ω fits A's rows and holds finite values inside them.
fn check_sizes(incidence: &CsMat<i8>, metric: &BlockMetric) -> Result<(), CanonicalError> {
    if metric.size() != incidence.rows() {
        return Err(CanonicalError::SizeMismatch {
            metric: metric.size(),
            rows: incidence.rows(),
        });
    }
    metric.validate()
}

/// `a` in CSR storage, converted only when it is not.
fn by_rows(a: Arc<CsMat<i8>>) -> Arc<CsMat<i8>> {
    if a.is_csr() {
        a
    } else {
        Arc::new(a.to_csr())
    }
}

impl Canonical {
    /// Build the operator and its assembly pattern. `incidence` is A
    /// (rows: metric rows, columns: unknowns), exact integers: the
    /// complex's own matrix (`k.boundary(n)`, `k.coboundary(0)`, kept
    /// without a copy), an `Arc` of one, or a matrix built by the caller
    /// (see [`IntoIncidence`]).
    pub fn new(incidence: impl IntoIncidence, metric: BlockMetric) -> Result<Self, CanonicalError> {
        Self::build(incidence.into_incidence(), None, metric)
    }

    /// [`Canonical::new`] with A also given in CSC storage, `by_columns`,
    /// which must be the same matrix (a complex keeps ∂ₙ both ways: see
    /// `Complex::boundary_csc`). A diagonal Ω over every row of A is
    /// then assembled from it in place instead of from a copy of A by
    /// columns. Only the shapes are checked, so this stays in the crate.
    pub(crate) fn with_columns(
        incidence: Arc<CsMat<i8>>,
        by_columns: Arc<CsMat<i8>>,
        metric: BlockMetric,
    ) -> Result<Self, CanonicalError> {
        debug_assert_eq!(by_columns.nnz(), incidence.nnz());
        Self::build(incidence, Some(by_columns), metric)
    }

    /// [`Canonical::new`] for a metric with one block per top cell of
    /// `complex`, block b over the edges of cell b (a nodal element
    /// metric: A = δ⁰, Ω from [`crate::metric::fe::stiffness_metric`]):
    /// the blocks' unknowns are read from the complex's characteristic
    /// matrix M_n and vertex star (its transpose) instead of being
    /// gathered from A's rows, which at 10⁶ Q1 cells is half the pattern's
    /// time and 80 MB. The same M to the bit; falls back to
    /// [`Canonical::new`] unless Ω was built with one block per cell and
    /// the shapes fit.
    ///
    /// ```
    /// use hasse_complex::generate::rectangle;
    /// use hasse_solver::operator::Canonical;
    /// use hasse_solver::metric::fe;
    /// let k = rectangle(2, 2, [0.0, 1.0], [0.0, 1.0]).unwrap();
    /// let omega = fe::stiffness_metric(&k, &[1.0; 4]).unwrap();
    /// let m = Canonical::with_cell_blocks(k.coboundary(0), omega.clone(), &k).unwrap().assemble();
    /// let plain = Canonical::new(k.coboundary(0), omega).unwrap().assemble();
    /// assert_eq!(m.val(), plain.val());
    /// ```
    pub fn with_cell_blocks(
        incidence: impl IntoIncidence,
        metric: BlockMetric,
        complex: &hasse_complex::Complex,
    ) -> Result<Self, CanonicalError> {
        let incidence = incidence.into_incidence();
        let n = complex.dim();
        let Ok(vertices) = complex.lar().shared_characteristic(n) else {
            return Self::new(incidence, metric);
        };
        let star = complex.shared_vertex_star(n);
        let fits = incidence.is_csr()
            && metric.per_cell
            && metric.diagonal_weights().is_none()
            && metric.block_count() == vertices.rows()
            && vertices.is_csr()
            && star.is_csr()
            && vertices.cols() == incidence.cols()
            && star.rows() == incidence.cols()
            && star.cols() == vertices.rows()
            && (0..metric.block_count())
                .into_par_iter()
                .all(|b| metric.rows_are_columns(b));
        if !fits {
            return Self::new(incidence, metric);
        }
        check_sizes(&incidence, &metric)?;
        let local = LocalPattern::Cells(CellSides { vertices, star });
        debug_assert!(
            {
                let gathered = GatheredPattern::new(&incidence, None, &metric);
                (0..metric.block_count()).all(|b| gathered.sides(b) == local.sides(b))
            },
            "a block's edges do not touch exactly its cell's vertices"
        );
        Self::finish(incidence, metric, Assembly::Blocks(local))
    }

    /// M = Aᵀ Ω B: the block that couples the unknowns of B's columns (M's
    /// columns) to those of A's columns (M's rows) through the same rows,
    /// e.g. the flux–pressure block of a mixed problem or the weights of a
    /// mean-value constraint. A and B are exact integer incidence matrices
    /// with as many rows as Ω; the pattern is built once, as for
    /// [`Canonical::new`].
    ///
    /// ```
    /// use hasse_complex::generate::rectangle;
    /// use hasse_solver::operator::{BlockMetric, Canonical};
    /// // Two squares: ∂₂ is 7 edges × 2 cells. With A = I on the edges and
    /// // Ω = −I, Aᵀ Ω ∂₂ = −∂₂, the flux–pressure block of mixed Darcy.
    /// let k = rectangle(2, 1, [0.0, 2.0], [0.0, 1.0]).unwrap();
    /// let edges = k.cell_count(1);
    /// let b = Canonical::coupling(
    ///     sprs::CsMat::<i8>::eye(edges),
    ///     BlockMetric::diagonal(&vec![-1.0; edges]),
    ///     k.boundary(2),
    /// )
    /// .unwrap();
    /// let m = b.assemble().to_dense();
    /// assert_eq!((m.nrows(), m.ncols()), (7, 2));
    /// for (v, (e, c)) in k.boundary(2).iter() {
    ///     assert_eq!(m[(e, c)], -f64::from(*v));
    /// }
    /// ```
    pub fn coupling(
        left: impl IntoIncidence,
        metric: BlockMetric,
        right: impl IntoIncidence,
    ) -> Result<Self, CanonicalError> {
        let (left, right) = (
            by_rows(left.into_incidence()),
            by_rows(right.into_incidence()),
        );
        check_sizes(&left, &metric)?;
        check_sizes(&right, &metric)?;
        let assembly = match metric.diagonal_weights() {
            Some(weights) => Assembly::Diagonal(Columns::new(&right, weights.len())),
            None => Assembly::Blocks(LocalPattern::Gathered(GatheredPattern::new(
                &left,
                Some(&right),
                &metric,
            ))),
        };
        let symbolic = matrix_pattern(&left, &right, &assembly);
        Ok(Self {
            incidence: left,
            right: Some(right),
            metric,
            nonzeros: symbolic.row_idx().len(),
            symbolic: OnceLock::from(symbolic),
            assembly: Box::new(assembly),
        })
    }

    /// Σ_k c_k A_kᵀ Ω_k A_k over the same unknowns, as one operator: A is
    /// the A_k stacked row block after row block and Ω the c_k Ω_k placed
    /// along the diagonal, so the sum is again Aᵀ Ω A. A transient step
    /// matrix M/Δt + θK is the sum of a mass (A = I) and a stiffness.
    ///
    /// ```
    /// use hasse_complex::generate::interval;
    /// use hasse_solver::operator::{BlockMetric, Canonical};
    /// let k = interval(2, 0.0, 1.0).unwrap();
    /// let stiffness = Canonical::new(k.coboundary(0), BlockMetric::diagonal(&[2.0, 2.0])).unwrap();
    /// let mass = Canonical::new(sprs::CsMat::<i8>::eye(3), BlockMetric::diagonal(&[0.25, 0.5, 0.25])).unwrap();
    /// let step = Canonical::sum(&[(4.0, &mass), (0.5, &stiffness)]).unwrap();
    /// let m = step.assemble().to_dense();
    /// // 4·0.5 + 0.5·(2 + 2) at the middle vertex, 0.5·(−2) beside it.
    /// assert_eq!((m[(1, 1)], m[(0, 1)]), (4.0, -1.0));
    /// ```
    pub fn sum(terms: &[(f64, &Canonical)]) -> Result<Self, CanonicalError> {
        let unknowns = terms.first().map_or(0, |(_, op)| op.unknowns());
        if let Some((_, op)) = terms
            .iter()
            .find(|(_, op)| op.unknowns() != unknowns || op.right.is_some())
        {
            return Err(CanonicalError::SumMismatch {
                unknowns,
                found: op.unknowns(),
            });
        }
        let rows: usize = terms.iter().map(|(_, op)| op.incidence.rows()).sum();
        let nnz: usize = terms.iter().map(|(_, op)| op.incidence.nnz()).sum();
        let mut indptr = Vec::with_capacity(rows + 1);
        let mut indices = Vec::with_capacity(nnz);
        let mut data = Vec::with_capacity(nnz);
        indptr.push(0);
        for (_, op) in terms {
            for row in op.incidence.outer_iterator() {
                indices.extend_from_slice(row.indices());
                data.extend_from_slice(row.data());
                indptr.push(indices.len());
            }
        }
        let stacked = CsMat::new((rows, unknowns), indptr, indices, data);
        let metrics: Vec<(f64, &BlockMetric)> =
            terms.iter().map(|(c, op)| (*c, &op.metric)).collect();
        Self::new(stacked, BlockMetric::stacked(&metrics))
    }

    fn build(
        incidence: Arc<CsMat<i8>>,
        by_columns: Option<Arc<CsMat<i8>>>,
        metric: BlockMetric,
    ) -> Result<Self, CanonicalError> {
        let incidence = by_rows(incidence);
        check_sizes(&incidence, &metric)?;
        let assembly = match metric.diagonal_weights() {
            Some(weights) => {
                let columns = match by_columns {
                    Some(by_columns)
                        if weights.len() == incidence.rows()
                            && by_columns.is_csc()
                            && by_columns.shape() == incidence.shape() =>
                    {
                        Columns::Shared(by_columns)
                    }
                    _ => Columns::new(&incidence, weights.len()),
                };
                Assembly::Diagonal(columns)
            }
            None => Assembly::Blocks(LocalPattern::Gathered(GatheredPattern::new(
                &incidence, None, &metric,
            ))),
        };
        Self::finish(incidence, metric, assembly)
    }

    fn finish(
        incidence: Arc<CsMat<i8>>,
        metric: BlockMetric,
        assembly: Assembly,
    ) -> Result<Self, CanonicalError> {
        let symbolic = matrix_pattern(&incidence, &incidence, &assembly);
        Ok(Self {
            incidence,
            right: None,
            metric,
            nonzeros: symbolic.row_idx().len(),
            symbolic: OnceLock::from(symbolic),
            assembly: Box::new(assembly),
        })
    }

    /// The pattern of M, built again if [`Canonical::assemble_owned`] gave
    /// it away.
    pub(super) fn pattern(&self) -> &SymbolicSparseColMat<usize> {
        self.symbolic
            .get_or_init(|| matrix_pattern(&self.incidence, self.right(), &self.assembly))
    }

    /// Number of unknowns M acts on: its columns, the columns of A (of B
    /// for a coupling block).
    pub fn unknowns(&self) -> usize {
        self.right().cols()
    }

    /// M's shape: (columns of A, columns of B); square for Aᵀ Ω A.
    pub fn shape(&self) -> (usize, usize) {
        (self.incidence.cols(), self.right().cols())
    }

    /// The incidence matrix A.
    pub fn incidence(&self) -> &CsMat<i8> {
        &self.incidence
    }

    /// B of a coupling block Aᵀ Ω B; A itself for Aᵀ Ω A.
    pub fn right(&self) -> &CsMat<i8> {
        self.right.as_deref().unwrap_or(&self.incidence)
    }

    /// The incidence matrix A, shared.
    pub fn shared_incidence(&self) -> Arc<CsMat<i8>> {
        Arc::clone(&self.incidence)
    }

    /// The metric Ω.
    pub fn metric(&self) -> &BlockMetric {
        &self.metric
    }

    /// Replace Ω by one with the same blocks and new values; the assembly
    /// pattern is kept.
    pub fn set_metric(&mut self, metric: BlockMetric) -> Result<(), CanonicalError> {
        if !metric.same_pattern(&self.metric) {
            return Err(CanonicalError::PatternChanged);
        }
        metric.validate()?;
        self.metric = metric;
        Ok(())
    }

    /// Number of stored entries of M.
    pub fn nonzeros(&self) -> usize {
        self.nonzeros
    }

    /// M = Aᵀ Ω A (full symmetric storage when Ω is symmetric).
    ///
    /// Each block's dense A_Rᵀ W A_S is formed first and then added to M,
    /// block after block, so the sums (and so the bits) are the same for
    /// any thread count.
    pub fn assemble(&self) -> SparseColMat<usize, f64> {
        SparseColMat::new(self.pattern().clone(), self.values())
    }

    /// [`Canonical::assemble`] for the last (or only) assembly: the matrix
    /// takes the operator's copy of the pattern instead of a new one (at
    /// 10⁶ cells, 50–80 MB of fresh memory and its page faults). A later
    /// `assemble` builds the pattern again.
    ///
    /// ```
    /// use hasse_complex::generate::rectangle;
    /// use hasse_solver::metric::fd;
    /// use hasse_solver::operator::Canonical;
    /// let k = rectangle(2, 2, [0.0, 1.0], [0.0, 1.0]).unwrap();
    /// let faces = k.cell_count(1);
    /// let mut op = Canonical::new(k.boundary(2), fd::from_face_values(&vec![1.0; faces])).unwrap();
    /// let last = op.assemble_owned();
    /// // A later assembly builds the same pattern again.
    /// let again = op.assemble();
    /// assert_eq!(last.symbolic().row_idx(), again.symbolic().row_idx());
    /// assert_eq!(last.val(), again.val());
    /// ```
    pub fn assemble_owned(&mut self) -> SparseColMat<usize, f64> {
        let values = self.values();
        let symbolic = match self.symbolic.take() {
            Some(symbolic) => symbolic,
            None => matrix_pattern(&self.incidence, self.right(), &self.assembly),
        };
        SparseColMat::new(symbolic, values)
    }

    /// A u (B u for a coupling block): the differences of `u` across every
    /// metric row.
    pub fn difference(&self, u: &[f64]) -> Vec<f64> {
        self.right()
            .outer_iterator()
            .map(|r| r.iter().map(|(j, &x)| f64::from(x) * u[j]).sum())
            .collect()
    }

    /// Aᵀ g for a cochain g on the metric rows.
    pub fn sum_transpose(&self, g: &[f64]) -> Vec<f64> {
        let mut out = zeroed(self.incidence.cols());
        for (r, row) in self.incidence.outer_iterator().enumerate() {
            for (j, &x) in row.iter() {
                out[j] += f64::from(x) * g[r];
            }
        }
        out
    }

    /// The flux cochain Ω A u (Ω B u for a coupling block).
    pub fn flux(&self, u: &[f64]) -> Vec<f64> {
        self.metric.apply(&self.difference(u))
    }

    /// M u computed as Aᵀ (Ω (A u)) (Aᵀ (Ω (B u))), without the assembled
    /// matrix.
    pub fn apply(&self, u: &[f64]) -> Vec<f64> {
        self.sum_transpose(&self.flux(u))
    }
}

/// Theorem 1 of the thesis: when A has trivial kernel, any matrix M of the
/// same unknowns is Aᵀ Ω A with Ω = Cᵀ M C for a left inverse C of A; here
/// C = (AᵀA)⁻¹Aᵀ. Returns the dense Ω, or `None` when A has a kernel.
pub fn metric_from_matrix(
    incidence: &nalgebra::DMatrix<f64>,
    matrix: &nalgebra::DMatrix<f64>,
) -> Option<nalgebra::DMatrix<f64>> {
    let gram = incidence.transpose() * incidence;
    let left_inverse = gram.try_inverse()? * incidence.transpose();
    Some(left_inverse.transpose() * matrix * left_inverse)
}
