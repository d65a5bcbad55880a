//! Block systems: one sparse matrix assembled from blocks placed at
//! (field i, field j), each a faer sparse matrix or a canonical operator.
//!
//! As for [`Canonical`] and [`DirectSolver`], the work is split into a
//! pattern phase and a value phase: [`BlockSystem::new`] checks the block
//! sizes against the fields, builds the sparsity pattern of the whole
//! matrix and a scatter map from every block entry to its place in it;
//! [`BlockSystem::set_block`] then replaces the values of one block (same
//! pattern) and the next [`BlockSystem::factorize`] reuses the symbolic
//! analysis, so only the numeric factorisation is redone.
//!
//! In a [`Symmetry::Symmetric`] system only the blocks on and above the
//! block diagonal are given; each off-diagonal block (i, j) also stands for
//! its transpose at (j, i).

use crate::la::direct::{DirectSolver, Factor, Factorization, SolveError};
use crate::operator::Canonical;
use faer::sparse::{SparseColMat, SymbolicSparseColMat};

/// Whether the block matrix is symmetric (upper blocks given, mirrored).
///
/// ```
/// use faer::sparse::{SparseColMat, Triplet};
/// use hasse_solver::la::direct::Factorization;
/// use hasse_solver::operator::block::{BlockError, BlockSystem, Symmetry};
/// let m = |e: &[(usize, usize, f64)]| {
///     let t: Vec<_> = e.iter().map(|&(i, j, v)| Triplet::new(i, j, v)).collect();
///     SparseColMat::<usize, f64>::try_new_from_triplets(1, 1, &t).unwrap()
/// };
/// // [[1, 2], [3, 4]] over two fields of one unknown: every block given.
/// let blocks = vec![
///     (0, 0, m(&[(0, 0, 1.0)]).into()),
///     (0, 1, m(&[(0, 0, 2.0)]).into()),
///     (1, 0, m(&[(0, 0, 3.0)]).into()),
///     (1, 1, m(&[(0, 0, 4.0)]).into()),
/// ];
/// let mut system = BlockSystem::new(&[1, 1], Symmetry::General, blocks).unwrap();
/// // A general system has no symmetric factorisation; LU solves it:
/// // x = M⁻¹ (3, 7) = (1, 1).
/// assert!(matches!(system.factorize(Factorization::Llt), Err(BlockError::NeedsSymmetric { .. })));
/// let x = system.solve(Factorization::Lu, &[3.0, 7.0]).unwrap();
/// assert!((x[0] - 1.0).abs() < 1e-14 && (x[1] - 1.0).abs() < 1e-14);
/// ```
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Symmetry {
    /// Blocks (i, j) with i ≤ j are given; (j, i) is the transpose of (i, j).
    Symmetric,
    /// Every block is given where it sits.
    General,
}

/// The values of one block.
///
/// ```
/// use faer::sparse::{SparseColMat, Triplet};
/// use hasse_complex::generate::interval;
/// use hasse_solver::metric::fd;
/// use hasse_solver::operator::block::{Block, BlockSystem, Symmetry};
/// use hasse_solver::operator::Canonical;
/// // Two blocks at the same place add up: I + Aᵀ Ω A with A = δ⁰ of a
/// // path of three vertices and Ω = diag(2, 2).
/// let k = interval(2, 0.0, 1.0).unwrap();
/// let stiffness = Canonical::new(k.coboundary(0), fd::from_face_values(&[2.0, 2.0])).unwrap();
/// let identity: Vec<_> = (0..3).map(|i| Triplet::new(i, i, 1.0)).collect();
/// let identity = SparseColMat::<usize, f64>::try_new_from_triplets(3, 3, &identity).unwrap();
/// let blocks = vec![(0, 0, Block::Sparse(identity)), (0, 0, Block::Canonical(stiffness))];
/// let m = BlockSystem::new(&[3], Symmetry::Symmetric, blocks).unwrap().matrix().to_dense();
/// assert_eq!((m[(0, 0)], m[(1, 1)], m[(0, 1)]), (3.0, 5.0, -2.0));
/// ```
#[derive(Clone, Debug)]
pub enum Block {
    /// A sparse matrix, used as it is.
    Sparse(SparseColMat<usize, f64>),
    /// A canonical operator, assembled to Aᵀ Ω A.
    Canonical(Canonical),
}

impl Block {
    fn matrix(&self) -> SparseColMat<usize, f64> {
        match self {
            Block::Sparse(m) => m.clone(),
            Block::Canonical(op) => op.assemble(),
        }
    }
}

impl From<SparseColMat<usize, f64>> for Block {
    fn from(m: SparseColMat<usize, f64>) -> Self {
        Block::Sparse(m)
    }
}

impl From<Canonical> for Block {
    fn from(op: Canonical) -> Self {
        Block::Canonical(op)
    }
}

/// Why a block system could not be built or solved.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum BlockError {
    /// A block is placed at a field the system does not have.
    #[error("block {block} is placed at field ({row_field}, {col_field}), but there are only {fields} fields")]
    FieldOutOfRange {
        /// The block, in the order given.
        block: usize,
        /// Its row field.
        row_field: usize,
        /// Its column field.
        col_field: usize,
        /// Fields of the system.
        fields: usize,
    },
    /// A block's shape is not (unknowns of its row field) × (unknowns of
    /// its column field).
    #[error("block {block} at ({row_field}, {col_field}) is {rows}×{cols}, but fields {row_field} and {col_field} have {expected_rows} and {expected_cols} unknowns")]
    SizeMismatch {
        /// The block, in the order given.
        block: usize,
        /// Its row field.
        row_field: usize,
        /// Its column field.
        col_field: usize,
        /// Its rows.
        rows: usize,
        /// Its columns.
        cols: usize,
        /// Unknowns of the row field.
        expected_rows: usize,
        /// Unknowns of the column field.
        expected_cols: usize,
    },
    /// A symmetric system was given a block below the block diagonal; only
    /// the upper ones are given, each mirrored.
    #[error("block {block} sits below the diagonal at ({row_field}, {col_field}) of a symmetric system; give the block at ({col_field}, {row_field}) instead (it is mirrored)")]
    LowerBlock {
        /// The block, in the order given.
        block: usize,
        /// Its row field.
        row_field: usize,
        /// Its column field, smaller than the row field.
        col_field: usize,
    },
    /// A diagonal block of a symmetric system differs from its transpose by
    /// more than 10⁻¹² of its largest entry.
    #[error(
        "block {block} on the diagonal of a symmetric system (field {field}) is not symmetric"
    )]
    NotSymmetric {
        /// The block, in the order given.
        block: usize,
        /// The field it sits on.
        field: usize,
    },
    /// A block holds NaN or ±∞.
    #[error("block {block} has a non-finite value")]
    NonFinite {
        /// The block, in the order given.
        block: usize,
    },
    /// New values of a block ([`BlockSystem::set_block`]) have another
    /// sparsity pattern than the block was placed with, so they have no
    /// place in the system's pattern.
    #[error("new values of block {block} do not have the sparsity pattern it was placed with")]
    PatternChanged {
        /// The block.
        block: usize,
    },
    /// [`BlockSystem::set_block`] was given a block number the system
    /// does not have.
    #[error("there is no block {block} (the system has {count})")]
    NoSuchBlock {
        /// The block number given.
        block: usize,
        /// Blocks of the system.
        count: usize,
    },
    /// A symmetric factorisation (LLᵀ, LDLᵀ, LBLᵀ) was asked for a
    /// [`Symmetry::General`] system.
    #[error("{factorization} needs a symmetric system; use Factorization::Lu for a general one")]
    NeedsSymmetric {
        /// The factorisation asked for.
        factorization: Factorization,
    },
    /// The analysis, factorisation or solve failed.
    #[error(transparent)]
    Solve(#[from] SolveError),
}

struct Placed {
    row_field: usize,
    col_field: usize,
    /// The block's own pattern, to check new values against.
    pattern: SymbolicSparseColMat<usize>,
    /// Place in the system's value array of every stored entry, in the
    /// block's column-major order.
    scatter: Vec<usize>,
    /// For a mirrored off-diagonal block: the place of each entry's transpose.
    mirror: Option<Vec<usize>>,
    values: Vec<f64>,
}

/// A sparse block matrix over fields, with its pattern kept for re-assembly
/// and its symbolic factorisation kept for re-factorisation.
///
/// ```
/// use faer::sparse::{SparseColMat, Triplet};
/// use hasse_solver::operator::block::{BlockSystem, Symmetry};
/// use hasse_solver::la::direct::Factorization;
/// let m = |r, c, e: &[(usize, usize, f64)]| {
///     let t: Vec<_> = e.iter().map(|&(i, j, v)| Triplet::new(i, j, v)).collect();
///     SparseColMat::try_new_from_triplets(r, c, &t).unwrap()
/// };
/// // [[2I, B], [Bᵀ, 0]] with B = (1, 1)ᵀ: a small saddle point.
/// let mut system = BlockSystem::new(
///     &[2, 1],
///     Symmetry::Symmetric,
///     vec![
///         (0, 0, m(2, 2, &[(0, 0, 2.0), (1, 1, 2.0)]).into()),
///         (0, 1, m(2, 1, &[(0, 0, 1.0), (1, 0, 1.0)]).into()),
///     ],
/// )
/// .unwrap();
/// assert_eq!(system.matrix().to_dense()[(2, 1)], 1.0);
/// let x = system.solve(Factorization::Lblt, &[1.0, 1.0, 1.0]).unwrap();
/// // 2x₀ + p = 1, 2x₁ + p = 1, x₀ + x₁ = 1: x = (½, ½), p = 0.
/// assert!((x[0] - 0.5).abs() < 1e-14 && x[2].abs() < 1e-14);
/// ```
pub struct BlockSystem {
    fields: Vec<usize>,
    symmetry: Symmetry,
    blocks: Vec<Placed>,
    symbolic: SymbolicSparseColMat<usize>,
    analysis: Option<DirectSolver>,
    analyses: usize,
}

impl BlockSystem {
    /// Place `blocks` (row field, column field, values) over fields of the
    /// given sizes and build the pattern. Blocks at the same place add up.
    pub fn new(
        fields: &[usize],
        symmetry: Symmetry,
        blocks: Vec<(usize, usize, Block)>,
    ) -> Result<Self, BlockError> {
        let mut offset = vec![0usize; fields.len() + 1];
        for (k, &size) in fields.iter().enumerate() {
            offset[k + 1] = offset[k] + size;
        }
        let total = offset[fields.len()];
        let mut matrices = Vec::with_capacity(blocks.len());
        for (b, (i, j, block)) in blocks.iter().enumerate() {
            let (i, j) = (*i, *j);
            if i >= fields.len() || j >= fields.len() {
                return Err(BlockError::FieldOutOfRange {
                    block: b,
                    row_field: i,
                    col_field: j,
                    fields: fields.len(),
                });
            }
            if symmetry == Symmetry::Symmetric && i > j {
                return Err(BlockError::LowerBlock {
                    block: b,
                    row_field: i,
                    col_field: j,
                });
            }
            let m = block.matrix();
            if m.nrows() != fields[i] || m.ncols() != fields[j] {
                return Err(BlockError::SizeMismatch {
                    block: b,
                    row_field: i,
                    col_field: j,
                    rows: m.nrows(),
                    cols: m.ncols(),
                    expected_rows: fields[i],
                    expected_cols: fields[j],
                });
            }
            matrices.push(m);
        }
        // Every global (row, col) position, bucketed by column.
        let mut columns: Vec<Vec<usize>> = vec![Vec::new(); total];
        for ((i, j, _), m) in blocks.iter().zip(&matrices) {
            let mirrored = symmetry == Symmetry::Symmetric && i != j;
            for t in m.triplet_iter() {
                let (r, c) = (offset[*i] + t.row, offset[*j] + t.col);
                columns[c].push(r);
                if mirrored {
                    columns[r].push(c);
                }
            }
        }
        let mut col_ptr = Vec::with_capacity(total + 1);
        col_ptr.push(0);
        let mut row_idx = Vec::new();
        for c in &mut columns {
            c.sort_unstable();
            c.dedup();
            row_idx.extend_from_slice(c);
            col_ptr.push(row_idx.len());
        }
        let place = |r: usize, c: usize| -> usize {
            let col = &row_idx[col_ptr[c]..col_ptr[c + 1]];
            // Present by construction.
            col_ptr[c] + col.binary_search(&r).unwrap_or(0)
        };
        let mut placed = Vec::with_capacity(blocks.len());
        for ((i, j, _), m) in blocks.iter().zip(matrices) {
            let mirrored = symmetry == Symmetry::Symmetric && i != j;
            let mut scatter = Vec::with_capacity(m.compute_nnz());
            let mut mirror = Vec::new();
            for c in 0..m.ncols() {
                for &r in &m.row_idx()[m.col_range(c)] {
                    let (gr, gc) = (offset[*i] + r, offset[*j] + c);
                    scatter.push(place(gr, gc));
                    if mirrored {
                        mirror.push(place(gc, gr));
                    }
                }
            }
            placed.push(Placed {
                row_field: *i,
                col_field: *j,
                pattern: m
                    .symbolic()
                    .to_owned()
                    .map_err(|_| SolveError::OutOfMemory)?,
                scatter,
                mirror: mirrored.then_some(mirror),
                values: m.val().to_vec(),
            });
        }
        let symbolic = SymbolicSparseColMat::new_checked(total, total, col_ptr, None, row_idx);
        let system = Self {
            fields: fields.to_vec(),
            symmetry,
            blocks: placed,
            symbolic,
            analysis: None,
            analyses: 0,
        };
        for b in 0..system.blocks.len() {
            system.check_values(b)?;
        }
        Ok(system)
    }

    fn check_values(&self, b: usize) -> Result<(), BlockError> {
        let block = &self.blocks[b];
        if block.values.iter().any(|v| !v.is_finite()) {
            return Err(BlockError::NonFinite { block: b });
        }
        if self.symmetry == Symmetry::Symmetric && block.row_field == block.col_field {
            // Entry (r, c) against (c, r), looked up in column r of the
            // sorted pattern (a missing entry is a zero): no dense copy,
            // which for a diagonal block of 10⁵ faces would be 80 GB.
            let pattern = &block.pattern;
            let row_idx = pattern.row_idx();
            let value = |r: usize, c: usize| {
                let range = pattern.col_range(c);
                row_idx[range.clone()]
                    .binary_search(&r)
                    .map_or(0.0, |k| block.values[range.start + k])
            };
            let scale = block.values.iter().fold(0.0f64, |s, v| s.max(v.abs()));
            for c in 0..pattern.ncols() {
                for &r in &row_idx[pattern.col_range(c)] {
                    if (value(r, c) - value(c, r)).abs() > 1e-12 * scale {
                        return Err(BlockError::NotSymmetric {
                            block: b,
                            field: block.row_field,
                        });
                    }
                }
            }
        }
        Ok(())
    }

    /// Sizes of the fields.
    pub fn fields(&self) -> &[usize] {
        &self.fields
    }

    /// First unknown of each field, and the total at the end.
    pub fn offsets(&self) -> Vec<usize> {
        let mut offset = vec![0];
        for &size in &self.fields {
            offset.push(offset.last().copied().unwrap_or(0) + size);
        }
        offset
    }

    /// Whether the system is symmetric.
    pub fn symmetry(&self) -> Symmetry {
        self.symmetry
    }

    /// How many symbolic analyses have been made (one, however many times
    /// the values change).
    pub fn symbolic_analyses(&self) -> usize {
        self.analyses
    }

    /// Replace the values of block `b`; the new values must have the
    /// pattern the block was placed with (a canonical operator with the same
    /// A and the same Ω blocks has).
    pub fn set_block(&mut self, b: usize, values: impl Into<Block>) -> Result<(), BlockError> {
        let count = self.blocks.len();
        let block = self
            .blocks
            .get_mut(b)
            .ok_or(BlockError::NoSuchBlock { block: b, count })?;
        let m = values.into().matrix();
        if m.nrows() != block.pattern.nrows()
            || m.ncols() != block.pattern.ncols()
            || m.col_ptr() != block.pattern.col_ptr()
            || m.row_idx() != block.pattern.row_idx()
        {
            return Err(BlockError::PatternChanged { block: b });
        }
        let old = std::mem::replace(&mut block.values, m.val().to_vec());
        if let Err(e) = self.check_values(b) {
            self.blocks[b].values = old;
            return Err(e);
        }
        Ok(())
    }

    /// The assembled matrix (full storage, both triangles, when symmetric).
    pub fn matrix(&self) -> SparseColMat<usize, f64> {
        let mut values = vec![0.0; self.symbolic.row_idx().len()];
        for block in &self.blocks {
            for (&p, &v) in block.scatter.iter().zip(&block.values) {
                values[p] += v;
            }
            if let Some(mirror) = &block.mirror {
                for (&p, &v) in mirror.iter().zip(&block.values) {
                    values[p] += v;
                }
            }
        }
        SparseColMat::new(self.symbolic.clone(), values)
    }

    /// Numeric factorisation of the current values. The symbolic analysis
    /// is made on the first call and reused while the kind stays the same.
    pub fn factorize(&mut self, kind: Factorization) -> Result<Factor, BlockError> {
        if kind != Factorization::Lu && self.symmetry != Symmetry::Symmetric {
            return Err(BlockError::NeedsSymmetric {
                factorization: kind,
            });
        }
        let matrix = self.matrix();
        if self.analysis.as_ref().map(DirectSolver::kind) != Some(kind) {
            self.analysis = Some(DirectSolver::analyze(matrix.as_ref(), kind)?);
            self.analyses += 1;
        }
        let solver = self
            .analysis
            .as_ref()
            .ok_or(BlockError::Solve(SolveError::Symbolic(
                "no analysis".into(),
            )))?;
        Ok(solver.factorize(matrix.as_ref())?)
    }

    /// Factorise and solve once for `rhs`.
    pub fn solve(&mut self, kind: Factorization, rhs: &[f64]) -> Result<Vec<f64>, BlockError> {
        Ok(self.factorize(kind)?.solve(rhs)?)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::operator::BlockMetric;
    use faer::sparse::Triplet;

    fn sparse(
        rows: usize,
        cols: usize,
        entries: &[(usize, usize, f64)],
    ) -> SparseColMat<usize, f64> {
        let t: Vec<_> = entries
            .iter()
            .map(|&(i, j, v)| Triplet::new(i, j, v))
            .collect();
        SparseColMat::try_new_from_triplets(rows, cols, &t).unwrap()
    }

    /// A = [[4, 1], [1, 3]], B = [[1, 0, 2], [0, 1, 0]] (2×3), C = 5 I₃.
    fn blocks() -> Vec<(usize, usize, Block)> {
        vec![
            (
                0,
                0,
                sparse(2, 2, &[(0, 0, 4.0), (0, 1, 1.0), (1, 0, 1.0), (1, 1, 3.0)]).into(),
            ),
            (
                0,
                1,
                sparse(2, 3, &[(0, 0, 1.0), (0, 2, 2.0), (1, 1, 1.0)]).into(),
            ),
            (
                1,
                1,
                sparse(3, 3, &[(0, 0, 5.0), (1, 1, 5.0), (2, 2, 5.0)]).into(),
            ),
        ]
    }

    /// The same block matrix written out by hand.
    const DENSE: [[f64; 5]; 5] = [
        [4.0, 1.0, 1.0, 0.0, 2.0],
        [1.0, 3.0, 0.0, 1.0, 0.0],
        [1.0, 0.0, 5.0, 0.0, 0.0],
        [0.0, 1.0, 0.0, 5.0, 0.0],
        [2.0, 0.0, 0.0, 0.0, 5.0],
    ];

    #[test]
    fn symmetric_and_general_assembly_equal_the_dense_block_matrix() {
        let symmetric = BlockSystem::new(&[2, 3], Symmetry::Symmetric, blocks()).unwrap();
        let mut general_blocks = blocks();
        general_blocks.push((
            1,
            0,
            sparse(3, 2, &[(0, 0, 1.0), (2, 0, 2.0), (1, 1, 1.0)]).into(),
        ));
        let general = BlockSystem::new(&[2, 3], Symmetry::General, general_blocks).unwrap();
        for system in [symmetric, general] {
            let m = system.matrix().to_dense();
            for (i, row) in DENSE.iter().enumerate() {
                for (j, &v) in row.iter().enumerate() {
                    assert_eq!(m[(i, j)], v, "({i}, {j})");
                }
            }
        }
    }

    #[test]
    fn reassembly_reuses_the_analysis_and_solves_correctly() {
        let mut system = BlockSystem::new(&[2, 3], Symmetry::Symmetric, blocks()).unwrap();
        let exact = [1.0, -2.0, 0.5, 3.0, -1.0];
        let product = |m: &[[f64; 5]; 5]| -> Vec<f64> {
            m.iter()
                .map(|row| row.iter().zip(&exact).map(|(a, x)| a * x).sum())
                .collect()
        };
        let x = system.solve(Factorization::Llt, &product(&DENSE)).unwrap();
        for (a, b) in x.iter().zip(&exact) {
            assert!((a - b).abs() < 1e-13, "{x:?}");
        }
        // C = 5 I → 7 I: only the diagonal of the second field changes.
        system
            .set_block(2, sparse(3, 3, &[(0, 0, 7.0), (1, 1, 7.0), (2, 2, 7.0)]))
            .unwrap();
        let mut changed = DENSE;
        for (k, row) in changed.iter_mut().enumerate().skip(2) {
            row[k] = 7.0;
        }
        let x = system
            .solve(Factorization::Llt, &product(&changed))
            .unwrap();
        for (a, b) in x.iter().zip(&exact) {
            assert!((a - b).abs() < 1e-13, "{x:?}");
        }
        assert_eq!(system.symbolic_analyses(), 1);
        // A different pattern is refused and the old values are kept.
        assert_eq!(
            system.set_block(2, sparse(3, 3, &[(0, 0, 1.0), (0, 1, 1.0), (1, 0, 1.0)])),
            Err(BlockError::PatternChanged { block: 2 })
        );
        assert_eq!(system.matrix().to_dense()[(2, 2)], 7.0);
    }

    #[test]
    fn canonical_blocks_are_assembled_and_updated() {
        // A = δ⁰ of a path 0 — 1 — 2, Ω = diag(1, 2): M = [[1,−1,0],[−1,3,−2],[0,−2,2]].
        let a = sprs::TriMat::from_triplets(
            (2, 3),
            vec![0, 0, 1, 1],
            vec![0, 1, 1, 2],
            vec![-1i8, 1, -1, 1],
        )
        .to_csr();
        let op = Canonical::new(a.clone(), BlockMetric::diagonal(&[1.0, 2.0])).unwrap();
        let identity = sparse(3, 3, &[(0, 0, 1.0), (1, 1, 1.0), (2, 2, 1.0)]);
        let mut system = BlockSystem::new(
            &[3],
            Symmetry::Symmetric,
            vec![(0, 0, op.into()), (0, 0, identity.into())],
        )
        .unwrap();
        let m = system.matrix().to_dense();
        let expected = [[2.0, -1.0, 0.0], [-1.0, 4.0, -2.0], [0.0, -2.0, 3.0]];
        for i in 0..3 {
            for j in 0..3 {
                assert_eq!(m[(i, j)], expected[i][j]);
            }
        }
        let op = Canonical::new(a, BlockMetric::diagonal(&[3.0, 2.0])).unwrap();
        system.set_block(0, op).unwrap();
        assert_eq!(system.matrix().to_dense()[(0, 0)], 4.0);
        assert_eq!(system.matrix().to_dense()[(1, 1)], 6.0);
    }

    #[test]
    fn bad_placements_are_named() {
        let wrong = vec![(0, 1, sparse(2, 2, &[(0, 0, 1.0)]).into())];
        assert_eq!(
            BlockSystem::new(&[2, 3], Symmetry::General, wrong).err(),
            Some(BlockError::SizeMismatch {
                block: 0,
                row_field: 0,
                col_field: 1,
                rows: 2,
                cols: 2,
                expected_rows: 2,
                expected_cols: 3,
            })
        );
        let lower = vec![(1, 0, sparse(3, 2, &[(0, 0, 1.0)]).into())];
        assert!(matches!(
            BlockSystem::new(&[2, 3], Symmetry::Symmetric, lower),
            Err(BlockError::LowerBlock { block: 0, .. })
        ));
        let outside = vec![(0, 2, sparse(2, 2, &[(0, 0, 1.0)]).into())];
        assert!(matches!(
            BlockSystem::new(&[2, 3], Symmetry::General, outside),
            Err(BlockError::FieldOutOfRange {
                block: 0,
                fields: 2,
                ..
            })
        ));
        let skew = vec![(0, 0, sparse(2, 2, &[(0, 1, 1.0), (1, 0, -1.0)]).into())];
        assert_eq!(
            BlockSystem::new(&[2], Symmetry::Symmetric, skew).err(),
            Some(BlockError::NotSymmetric { block: 0, field: 0 })
        );
        let mut general = BlockSystem::new(
            &[1],
            Symmetry::General,
            vec![(0, 0, sparse(1, 1, &[(0, 0, 2.0)]).into())],
        )
        .unwrap();
        assert!(matches!(
            general.factorize(Factorization::Llt),
            Err(BlockError::NeedsSymmetric { .. })
        ));
        assert_eq!(general.solve(Factorization::Lu, &[4.0]).unwrap(), vec![2.0]);
    }
}
