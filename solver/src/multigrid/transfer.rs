//! Where the prolongations of a hierarchy come from: grid levels of the
//! rectangle and box generators, SPLIT refinements (the only multigrid code
//! that knows the complex), and their restriction to free unknowns.

use super::MultigridError;
use crate::la::fixed::FixedSplit;
use crate::la::iterative::RowMatrix;
use hasse_complex::split::Refinement;
use std::sync::Arc;

/// What a prolongation's columns are: this decides which coarse unknowns a
/// Dirichlet condition on fine unknowns removes ([`restrict_to_free`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Transfer {
    /// Vertex values; a coarse vertex is also a fine vertex (its row of P
    /// is a single 1), and is fixed when that fine vertex is.
    Nodal,
    /// Cell values (piecewise constant); a coarse cell goes only when all
    /// its fine cells are fixed.
    Cells,
}

/// One prolongation P (fine × coarse) of a hierarchy.
#[derive(Clone, Debug, PartialEq)]
pub struct Prolongation {
    /// P, fine unknowns × coarse unknowns.
    pub matrix: RowMatrix,
    /// What the unknowns are, which decides how fixed ones carry over to
    /// the coarse level.
    pub transfer: Transfer,
}

/// Where the prolongations of a multigrid come from.
///
/// The hierarchy describes the whole mesh; whether its levels carry nodal
/// or cell unknowns is read from the size of the system it is used for.
///
/// ```
/// use hasse_complex::generate::rectangle;
/// use hasse_solver::metric::Method;
/// use hasse_solver::multigrid::{Hierarchy, MultigridError, SolverChoice};
/// use hasse_solver::physics::diffusion::{Diffusion, DiffusionError};
/// use hasse_solver::physics::{BoundaryKind, Conductivity};
/// use std::sync::Arc;
/// let mesh = rectangle(16, 16, [0.0, 1.0], [0.0, 1.0]).unwrap();
/// // A hierarchy of the wrong grid: 8×8 has 64 cells and 81 vertices, the
/// // system 256 cell unknowns.
/// let wrong = Hierarchy::Grid { cells: vec![8, 8] };
/// let result = Diffusion::new(Method::Fv, Conductivity::Scalar(Arc::new(|_| 1.0)), Arc::new(|_| 1.0))
///     .with_boundary("boundary", BoundaryKind::Dirichlet(Arc::new(|_| 0.0)))
///     .with_solver(SolverChoice::Multigrid(wrong), 1e-8, &mesh)
///     .solve(&mesh);
/// assert!(matches!(
///     result,
///     Err(DiffusionError::Multigrid(MultigridError::Mismatch { unknowns: 256, .. }))
/// ));
/// ```
#[derive(Clone, Debug)]
pub enum Hierarchy {
    /// A structured grid from `generate::grid`/`rectangle`/`box3` with
    /// `cells[a]` cells along axis a, numbered x fastest.
    Grid {
        /// Cells along each axis, x first. Every axis is halved as long as
        /// every count is even and the halves keep at least 2 cells.
        cells: Vec<usize>,
    },
    /// The SPLIT refinements that made the mesh, in the order they were
    /// applied (the first one refines the coarsest mesh). Compose several
    /// SPLITs of one refinement step into one with [`Refinement::compose`].
    Refinements(Arc<[Refinement]>),
    /// Smoothed aggregation from the matrix alone.
    Algebraic,
}

impl Hierarchy {
    /// The prolongations for a system on all `unknowns` of the mesh (before
    /// Dirichlet unknowns are removed), finest first. Nodal or cell unknowns
    /// are told apart by their number.
    pub fn prolongations(&self, unknowns: usize) -> Result<Vec<Prolongation>, MultigridError> {
        match self {
            Hierarchy::Algebraic => Ok(Vec::new()),
            Hierarchy::Grid { cells } => {
                let vertices: usize = cells.iter().map(|n| n + 1).product();
                let count: usize = cells.iter().product();
                let transfer = if unknowns == count {
                    Transfer::Cells
                } else if unknowns == vertices {
                    Transfer::Nodal
                } else {
                    return Err(MultigridError::Mismatch {
                        unknowns,
                        detail: format!(
                            "a grid of {cells:?} cells has {count} cells and {vertices} vertices"
                        ),
                    });
                };
                grid_prolongations(cells, transfer)
            }
            Hierarchy::Refinements(list) => {
                let Some(last) = list.last() else {
                    return Ok(Vec::new());
                };
                let n = last.dim();
                let (_, fine) = last.counts();
                let transfer = match (unknowns == fine[n], unknowns == fine[0]) {
                    (true, false) => Transfer::Cells,
                    (false, true) => Transfer::Nodal,
                    _ => {
                        return Err(MultigridError::Mismatch {
                            unknowns,
                            detail: format!(
                                "the last refinement makes {} vertices and {} top cells{}",
                                fine[0],
                                fine[n],
                                if fine[0] == fine[n] {
                                    ": equal counts, the kind of unknown is ambiguous"
                                } else {
                                    ""
                                }
                            ),
                        })
                    }
                };
                refinement_prolongations(list, transfer)
            }
        }
    }
}

/// Prolongations of a structured grid with `cells[a]` cells per axis (x
/// fastest), finest first, halving every axis while all counts are even
/// and at least 2 after halving.
pub fn grid_prolongations(
    cells: &[usize],
    transfer: Transfer,
) -> Result<Vec<Prolongation>, MultigridError> {
    if cells.is_empty() || cells.len() > 3 || cells.contains(&0) {
        return Err(MultigridError::Option {
            option: "grid cells",
            detail: format!("1 to 3 positive counts are needed, got {cells:?}"),
        });
    }
    let mut out = Vec::new();
    let mut fine = cells.to_vec();
    while fine.iter().all(|&n| n % 2 == 0 && n >= 4) {
        let coarse: Vec<usize> = fine.iter().map(|n| n / 2).collect();
        out.push(Prolongation {
            matrix: grid_prolongation(&fine, &coarse, transfer)?,
            transfer,
        });
        fine = coarse;
    }
    Ok(out)
}

/// P from a grid with `fine` cells per axis to one with `coarse = fine/2`.
pub(super) fn grid_prolongation(
    fine: &[usize],
    coarse: &[usize],
    transfer: Transfer,
) -> Result<RowMatrix, MultigridError> {
    let d = fine.len();
    // Per axis: for each fine index, the coarse indices and weights.
    let axis_weights = |a: usize| -> Vec<Vec<(usize, f64)>> {
        match transfer {
            Transfer::Cells => (0..fine[a]).map(|i| vec![(i / 2, 1.0)]).collect(),
            Transfer::Nodal => (0..=fine[a])
                .map(|i| {
                    if i % 2 == 0 {
                        vec![(i / 2, 1.0)]
                    } else {
                        vec![(i / 2, 0.5), (i / 2 + 1, 0.5)]
                    }
                })
                .collect(),
        }
    };
    let weights: Vec<Vec<Vec<(usize, f64)>>> = (0..d).map(axis_weights).collect();
    let extent = |n: &[usize], a: usize| match transfer {
        Transfer::Cells => n.get(a).copied().unwrap_or(1),
        Transfer::Nodal => n.get(a).map_or(1, |n| n + 1),
    };
    let (fx, fy, fz) = (extent(fine, 0), extent(fine, 1), extent(fine, 2));
    let (cx, cy) = (extent(coarse, 0), extent(coarse, 1));
    let unit = vec![vec![(0usize, 1.0)]];
    let wy = weights.get(1).unwrap_or(&unit);
    let wz = weights.get(2).unwrap_or(&unit);
    let mut rows = Vec::with_capacity(fx * fy * fz);
    for zk in wz.iter().take(fz) {
        for yj in wy.iter().take(fy) {
            for xi in weights[0].iter().take(fx) {
                let mut row = Vec::with_capacity(8);
                for &(c, w3) in zk {
                    for &(b, w2) in yj {
                        for &(a, w1) in xi {
                            row.push((a + cx * (b + cy * c), w1 * w2 * w3));
                        }
                    }
                }
                row.sort_by_key(|e| e.0);
                rows.push(row);
            }
        }
    }
    let coarse_count = (0..3).map(|a| extent(coarse, a)).product();
    let m = RowMatrix::from_rows(coarse_count, rows)?;
    Ok(m)
}

/// Prolongations from SPLIT refinements (listed coarse to fine), finest
/// first: |ζ_n| for cells, the nodal interpolation for vertices.
pub fn refinement_prolongations(
    refinements: &[Refinement],
    transfer: Transfer,
) -> Result<Vec<Prolongation>, MultigridError> {
    let mut out = Vec::with_capacity(refinements.len());
    for (level, r) in refinements.iter().rev().enumerate() {
        let (coarse, _) = r.counts();
        let rows: Vec<Vec<(usize, f64)>> = match transfer {
            Transfer::Cells => {
                let z = r.zeta(r.dim()).to_csr();
                z.outer_iterator()
                    .map(|row| row.iter().map(|(j, _)| (j, 1.0)).collect())
                    .collect()
            }
            Transfer::Nodal => {
                let z = r.nodal_matrix().to_csr();
                z.outer_iterator()
                    .map(|row| row.iter().map(|(j, &w)| (j, w)).collect())
                    .collect()
            }
        };
        let width = match transfer {
            Transfer::Cells => coarse[r.dim()],
            Transfer::Nodal => coarse[0],
        };
        if let Some(prev) = out.last() {
            let prev: &Prolongation = prev;
            if prev.matrix.ncols() != rows.len() {
                return Err(MultigridError::Size {
                    level,
                    expected: prev.matrix.ncols(),
                    found: rows.len(),
                });
            }
        }
        let mut rows = rows;
        for row in &mut rows {
            row.sort_by_key(|e| e.0);
        }
        out.push(Prolongation {
            matrix: RowMatrix::from_rows(width, rows)?,
            transfer,
        });
    }
    Ok(out)
}

/// The prolongations restricted to the free unknowns of `split` (on the
/// finest level; the coarse levels' fixed unknowns follow from the
/// [`Transfer`] rule). Dropping a coarse unknown whose support is all
/// fixed keeps the coarse operators nonsingular.
pub fn restrict_to_free(
    prolongations: &[Prolongation],
    split: &FixedSplit,
) -> Result<Vec<Prolongation>, MultigridError> {
    let mut fixed: Vec<bool> = (0..split.unknowns()).map(|i| split.is_fixed(i)).collect();
    let mut out = Vec::with_capacity(prolongations.len());
    for (level, p) in prolongations.iter().enumerate() {
        let m = &p.matrix;
        if m.nrows() != fixed.len() {
            return Err(MultigridError::Size {
                level,
                expected: fixed.len(),
                found: m.nrows(),
            });
        }
        let mut coarse_fixed = vec![true; m.ncols()];
        let mut twin_fixed = vec![false; m.ncols()];
        for (i, &fix) in fixed.iter().enumerate() {
            let (c, v) = m.row(i);
            if !fix {
                for &j in c {
                    coarse_fixed[j as usize] = false;
                }
            } else if p.transfer == Transfer::Nodal && c.len() == 1 && v[0] == 1.0 {
                twin_fixed[c[0] as usize] = true;
            }
        }
        for (f, t) in coarse_fixed.iter_mut().zip(&twin_fixed) {
            *f |= *t;
        }
        let keep_rows: Vec<bool> = fixed.iter().map(|f| !f).collect();
        let keep_cols: Vec<bool> = coarse_fixed.iter().map(|f| !f).collect();
        out.push(Prolongation {
            matrix: m.restrict(&keep_rows, &keep_cols),
            transfer: p.transfer,
        });
        fixed = coarse_fixed;
    }
    Ok(out)
}
