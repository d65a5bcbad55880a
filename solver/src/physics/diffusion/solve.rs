//! Solving an assembled diffusion problem: pure-Neumann compatibility,
//! the check that every part is anchored, the symbolic analysis from
//! topology beside the assembly, and the direct or multigrid-CG solve on
//! the free unknowns.

use super::*;
use crate::la::disjoint::DisjointSets;
use crate::la::fixed::FixedSplit;
use std::sync::Arc;

/// Every connected part of the free unknowns must be tied to a Dirichlet
/// value or a Robin/ghost row, or M is singular there. On a part C of the
/// graph of M that is tied to nothing, M·1 vanishes on C (constants are the
/// kernel of AᵀΩA); a tie shows as a row sum over C of the order of the
/// diagonal. This finds the floating part before the factorisation fails
/// with a message that cannot say where.
pub(super) fn check_anchored(
    complex: &Complex,
    location: Location,
    matrix: &SparseColMat<usize, f64>,
    fixed: &[Option<f64>],
) -> Result<(), DiffusionError> {
    let size = matrix.ncols();
    let mut parts = DisjointSets::new(size);
    let free = |i: usize| fixed.get(i).is_none_or(Option::is_none);
    for c in 0..size {
        if !free(c) {
            continue;
        }
        for (&r, &v) in matrix.row_idx()[matrix.col_range(c)]
            .iter()
            .zip(&matrix.val()[matrix.col_range(c)])
        {
            if r != c && v != 0.0 && free(r) {
                parts.join(r, c);
            }
        }
    }
    // Per part: the largest |Σ_{j∈C} M_ij| and the largest diagonal. Rounding
    // leaves row sums of untied rows near 1e-15 of the diagonal; a tie (a
    // Dirichlet neighbour, a Robin or ghost weight) is of its order, unless
    // the data itself is that close to singular.
    let mut row_sum = vec![0.0f64; size];
    let mut diagonal = vec![0.0f64; size];
    for c in 0..size {
        for (&r, &v) in matrix.row_idx()[matrix.col_range(c)]
            .iter()
            .zip(&matrix.val()[matrix.col_range(c)])
        {
            if r == c {
                diagonal[r] = v.abs();
            }
            if free(r) && free(c) {
                row_sum[r] += v;
            }
        }
    }
    let mut tie = vec![0.0f64; size];
    let mut scale = vec![0.0f64; size];
    let mut first = vec![usize::MAX; size];
    for i in (0..size).filter(|&i| free(i)) {
        let p = parts.root(i);
        if first[p] == usize::MAX {
            first[p] = i;
        }
        tie[p] = tie[p].max(row_sum[i].abs());
        scale[p] = scale[p].max(diagonal[i]);
    }
    for p in 0..size {
        if first[p] == usize::MAX || tie[p] > 1e-12 * scale[p] {
            continue;
        }
        let unknown = first[p];
        let n = complex.dim();
        let cells = complex.cell_count(n);
        let (what, point) = match location {
            Location::Nodal => ("vertex", complex.vertices().point(unknown).to_vec()),
            _ if unknown < cells => ("top cell", complex.centroid_of(n, unknown).to_vec()),
            _ => ("face", complex.centroid_of(n - 1, unknown - cells).to_vec()),
        };
        let unknown = match location {
            Location::Hybrid if unknown >= cells => unknown - cells,
            _ => unknown,
        };
        return Err(DiffusionError::FloatingPart {
            // Only on this error path: homology is not free on large meshes.
            parts: complex.betti_numbers_over(hasse_complex::Field::Z2)[0],
            what,
            unknown,
            point,
        });
    }
    Ok(())
}

/// Solve M u = b with the unknowns in `fixed` held at their values: the
/// fixed columns move to the right-hand side and the fixed rows are
/// dropped, so the reduced system stays symmetric (positive definite when
/// M is). Directly by `factorization` with the fill-reducing `ordering`, or
/// by conjugate gradients when `iterative` is given (its initial guess
/// restricted to the free unknowns).
pub fn solve_with_fixed(
    matrix: &SparseColMat<usize, f64>,
    rhs: &[f64],
    fixed: &[Option<f64>],
    factorization: Factorization,
    ordering: Ordering,
    iterative: Option<&Iterative>,
) -> Result<(Vec<f64>, SolveReport, Option<CgReport>), DiffusionError> {
    let (values, report, iterations, _) = solve_fixed(
        matrix,
        rhs,
        fixed,
        factorization,
        ordering,
        iterative,
        None,
        None,
    )?;
    Ok((values, report, iterations))
}

/// A symbolic analysis made from topology before M was assembled, and the
/// pattern it was made for.
pub(super) struct TopologyAnalysis {
    pattern: SymbolicSparseColMat<usize>,
    solver: DirectSolver,
}

impl TopologyAnalysis {
    /// Whether it holds for `matrix`: same pattern, entry for entry.
    pub(super) fn fits(&self, matrix: &SparseColMat<usize, f64>) -> bool {
        let assembled = matrix.symbolic();
        assembled.nrows() == self.pattern.nrows()
            && assembled.col_ptr() == self.pattern.col_ptr()
            && assembled.col_nnz().is_none()
            && assembled.row_idx() == self.pattern.row_idx()
    }
}

/// [`solve_with_fixed`], with an analysis made beforehand, used by a
/// direct solve when it was made for the pattern of the system solved
/// (the free unknowns' block: see [`TopologyAnalysis::fits`]); the last
/// value says whether it was. Without such an analysis, the free
/// unknowns' `points` (given for all unknowns) go to the ordering.
#[allow(clippy::too_many_arguments)]
pub(super) fn solve_fixed(
    matrix: &SparseColMat<usize, f64>,
    rhs: &[f64],
    fixed: &[Option<f64>],
    factorization: Factorization,
    ordering: Ordering,
    iterative: Option<&Iterative>,
    analysis: Option<TopologyAnalysis>,
    points: Option<UnknownPoints<'_>>,
) -> Result<(Vec<f64>, SolveReport, Option<CgReport>, bool), DiffusionError> {
    let n = rhs.len();
    let split = FixedSplit::new(fixed);
    let free = split.free();
    let reduced_rhs = split.reduced_rhs(matrix, rhs, fixed);
    if free.is_empty() {
        let values = split.lift(&[], fixed);
        let report = SolveReport {
            factorization,
            ordering: None,
            unknowns: 0,
            nonzeros: 0,
            symbolic_seconds: 0.0,
            numeric_seconds: 0.0,
            solve_seconds: 0.0,
            relative_residual: 0.0,
            factor_entries: None,
            factor_flops: None,
        };
        return Ok((values, report, None, false));
    }
    // Without fixed unknowns the matrix is used as it is.
    let reduced: std::borrow::Cow<'_, SparseColMat<usize, f64>> = if split.all_free() {
        std::borrow::Cow::Borrowed(matrix)
    } else {
        std::borrow::Cow::Owned(split.free_block(matrix))
    };
    let analysis = analysis.filter(|a| a.fits(&reduced)).map(|a| a.solver);
    let analysed = analysis.is_some();
    let (x, report, iterations) = match iterative {
        None => {
            let (x, report) = match analysis {
                Some(analysis) => direct::solve_analyzed(&analysis, &reduced, &reduced_rhs)?,
                None => {
                    let free_points: Option<Vec<f64>> =
                        points.map(|p| points_of(p, free.iter().copied()));
                    let points = free_points
                        .as_deref()
                        .zip(points)
                        .map(|(c, p)| UnknownPoints {
                            coordinates: c,
                            ..p
                        });
                    let solver = DirectSolver::analyze_pattern_at(
                        reduced.symbolic(),
                        factorization,
                        ordering,
                        points,
                    )?;
                    direct::solve_analyzed(&solver, &reduced, &reduced_rhs)?
                }
            };
            (x, report, None)
        }
        Some(settings) => {
            let guess: Option<Vec<f64>> = settings.initial.as_ref().map(|all| {
                free.iter()
                    .map(|&i| all.get(i).copied().unwrap_or(0.0))
                    .collect()
            });
            let nonzeros = reduced.compute_nnz();
            let (x, cg, setup) = match &settings.preconditioner {
                Preconditioning::Jacobi => {
                    let (x, cg) = conjugate_gradient(
                        &reduced,
                        &reduced_rhs,
                        guess.as_deref(),
                        &settings.options,
                    )?;
                    (x, cg, 0.0)
                }
                Preconditioning::Multigrid { hierarchy, options } => {
                    let rows = RowMatrix::from_symmetric(&reduced)?;
                    // The row copy replaces the faer matrix for the solve.
                    drop(reduced);
                    let prolongations =
                        multigrid::restrict_to_free(&hierarchy.prolongations(n)?, &split)?;
                    let mg = Multigrid::new(rows, prolongations, options)?;
                    let (x, cg) = mg.solve(&reduced_rhs, guess.as_deref(), &settings.options)?;
                    (x, cg, mg.setup_seconds)
                }
            };
            let report = SolveReport {
                factorization,
                ordering: None,
                unknowns: free.len(),
                nonzeros,
                symbolic_seconds: 0.0,
                numeric_seconds: setup,
                solve_seconds: cg.seconds,
                relative_residual: cg.relative_residual,
                factor_entries: None,
                factor_flops: None,
            };
            (x, report, Some(cg))
        }
    };
    Ok((split.lift(&x, fixed), report, iterations, analysed))
}

/// A point of each unknown of `location`, for the geometric ordering: the
/// vertices themselves for nodal unknowns, the mean of each cell's
/// vertices for cell-centred ones (then each face's for the hybrid
/// method's face unknowns). Any point inside a cell would do, and the mean
/// costs no geometry.
pub(super) fn unknown_points(complex: &Complex, location: Location) -> std::borrow::Cow<'_, [f64]> {
    let n = complex.dim();
    let vertex_means = |p: usize| -> Vec<f64> {
        let d = complex.embedding_dim();
        let mut means = vec![0.0; complex.cell_count(p) * d];
        means
            .par_chunks_mut(d.max(1))
            .enumerate()
            .for_each(|(c, mean)| {
                let vertices = complex.cell_vertices(p, c);
                for &v in vertices {
                    for (m, x) in mean.iter_mut().zip(complex.vertices().point(v)) {
                        *m += x;
                    }
                }
                for m in mean {
                    *m /= vertices.len() as f64;
                }
            });
        means
    };
    match location {
        Location::Nodal => std::borrow::Cow::Borrowed(complex.vertices().as_slice()),
        Location::CellCentred => std::borrow::Cow::Owned(vertex_means(n)),
        Location::Hybrid => {
            let mut points = vertex_means(n);
            points.extend(vertex_means(n - 1));
            std::borrow::Cow::Owned(points)
        }
    }
}

/// The coordinates of the unknowns `kept`, in that order.
pub(super) fn points_of(points: UnknownPoints<'_>, kept: impl Iterator<Item = usize>) -> Vec<f64> {
    let d = points.dimension;
    kept.flat_map(|i| &points.coordinates[i * d..(i + 1) * d])
        .copied()
        .collect()
}

/// The method's flux Ω A u on the flux rows of A; on cell-centred
/// boundary faces with the ghost part of Dirichlet/Robin data, Ω(Au − w),
/// and the data's own flux on Neumann faces.
fn method_flux(
    location: Location,
    canonical: &Canonical,
    values: &[f64],
    flux_rows: usize,
    ghost_values: &[f64],
    neumann_flux: &[f64],
) -> Vec<f64> {
    let flux_all = canonical.flux(values);
    let mut flux = flux_all[..flux_rows].to_vec();
    if location == Location::CellCentred {
        let lifted = canonical.metric().apply(ghost_values);
        for ((q, l), g) in flux.iter_mut().zip(lifted).zip(neumann_flux) {
            *q += g - l;
        }
    }
    flux
}

impl Diffusion {
    /// Assemble and solve on `complex`.
    pub fn solve(&self, complex: &Complex) -> Result<Solution, DiffusionError> {
        // Assembly and the checks before a solve; only their result is
        // needed by the factorisation.
        let prepare = || -> Result<(Assembled, f64, f64), DiffusionError> {
            let mut system = self.assemble(complex)?;
            let neumann_imbalance = self.make_compatible(complex, &mut system)?;
            if !system.pure_neumann {
                check_anchored(complex, system.location, &system.matrix, &system.fixed)?;
            }
            let condition_bound = diagonal_condition_bound(&system.matrix, &system.fixed);
            Ok((system, neumann_imbalance, condition_bound))
        };
        // The analysis reads only M's pattern; when topology alone fixes it,
        // it runs on one thread while the geometry, Ω, the values and the
        // checks are computed on the other.
        // Only a direct solve orders its unknowns.
        let coordinates = self
            .iterative
            .is_none()
            .then(|| unknown_points(complex, self.location()));
        let points = coordinates.as_deref().map(|coordinates| UnknownPoints {
            coordinates,
            dimension: complex.embedding_dim(),
        });
        let (prepared, analysis) = if self.pattern_from_topology(complex) {
            rayon::join(prepare, || self.analyze_topology(complex, points?))
        } else {
            (prepare(), None)
        };
        let (system, neumann_imbalance, condition_bound) = prepared?;
        let Assembled {
            location,
            canonical,
            matrix,
            rhs,
            fixed,
            pure_neumann,
            flux_rows,
            ghost_values,
            neumann_flux,
            cell_points,
            assembly_seconds,
            ..
        } = system;
        let unknowns = rhs.len();
        let (mut values, report, iterations, analyzed_during_assembly) = solve_fixed(
            &matrix,
            &rhs,
            &fixed,
            self.factorization,
            self.ordering,
            self.iterative.as_ref(),
            analysis,
            points,
        )?;
        if pure_neumann {
            let weights = self.mean_weights(complex, location, unknowns);
            let wsum: f64 = weights.iter().sum();
            let mean: f64 = values.iter().zip(&weights).map(|(u, w)| u * w).sum::<f64>() / wsum;
            for u in &mut values {
                *u -= mean;
            }
        }
        let flux = method_flux(
            location,
            &canonical,
            &values,
            flux_rows,
            &ghost_values,
            &neumann_flux,
        );
        Ok(Solution {
            method: self.method,
            location,
            values,
            flux,
            report,
            iterations,
            assembly_seconds,
            analyzed_during_assembly,
            pure_neumann,
            neumann_imbalance,
            cell_points,
            condition_bound,
        })
    }

    /// The [`Solution`] made of values for every unknown solved elsewhere
    /// (by PETSc across ranks, say): the system is assembled here to give
    /// the fluxes, exactly as [`Diffusion::solve`] gives them, and the
    /// relative residual ‖b − M u‖ / ‖b‖ of the values on the free
    /// unknowns, an independent check of the other solver. Fixed unknowns
    /// take their Dirichlet values whatever `values` holds.
    pub fn solution_from_values(
        &self,
        complex: &Complex,
        mut values: Vec<f64>,
        solve_seconds: f64,
    ) -> Result<Solution, DiffusionError> {
        let Assembled {
            location,
            canonical,
            matrix,
            rhs,
            fixed,
            pure_neumann,
            flux_rows,
            ghost_values,
            neumann_flux,
            cell_points,
            assembly_seconds,
            ..
        } = self.assemble(complex)?;
        if values.len() != rhs.len() {
            return Err(DiffusionError::Unsupported {
                method: self.method.name(),
                what: "values whose count differs from the number of unknowns",
            });
        }
        for (u, g) in values.iter_mut().zip(&fixed) {
            if let Some(g) = g {
                *u = *g;
            }
        }
        // r = b − M u on the free rows; the reduced right-hand side is
        // b − M_fixed g there.
        let mut product = vec![0.0; rhs.len()];
        let mut lifted = vec![0.0; rhs.len()];
        for column in 0..matrix.ncols() {
            let range = matrix.col_range(column);
            for (&row, &m) in matrix.row_idx()[range.clone()]
                .iter()
                .zip(&matrix.val()[range])
            {
                product[row] += m * values[column];
                if fixed[column].is_some() {
                    lifted[row] += m * values[column];
                }
            }
        }
        let (mut residual, mut reduced) = (0.0f64, 0.0f64);
        let mut free = 0;
        for u in 0..rhs.len() {
            if fixed[u].is_none() {
                free += 1;
                residual += (rhs[u] - product[u]).powi(2);
                reduced += (rhs[u] - lifted[u]).powi(2);
            }
        }
        let relative_residual = if reduced > 0.0 {
            (residual / reduced).sqrt()
        } else {
            residual.sqrt()
        };
        let flux = method_flux(
            location,
            &canonical,
            &values,
            flux_rows,
            &ghost_values,
            &neumann_flux,
        );
        let condition_bound = diagonal_condition_bound(&matrix, &fixed);
        Ok(Solution {
            method: self.method,
            location,
            values,
            flux,
            report: SolveReport {
                factorization: self.factorization,
                ordering: None,
                unknowns: free,
                nonzeros: matrix.compute_nnz(),
                symbolic_seconds: 0.0,
                numeric_seconds: 0.0,
                solve_seconds,
                relative_residual,
                factor_entries: None,
                factor_flops: None,
            },
            iterations: None,
            assembly_seconds,
            analyzed_during_assembly: false,
            pure_neumann,
            neumann_imbalance: 0.0,
            cell_points,
            condition_bound,
        })
    }

    /// A pure-Neumann system made solvable: a connected complex is
    /// required, the data's imbalance Σb must be within the tolerance and is
    /// removed in proportion to each unknown's weight, and unknown 0 is
    /// pinned (the zero-mean shift follows the solve). Returns the relative
    /// imbalance removed (0 when the system is not pure Neumann).
    pub(super) fn make_compatible(
        &self,
        complex: &Complex,
        system: &mut Assembled,
    ) -> Result<f64, DiffusionError> {
        if !system.pure_neumann {
            return Ok(0.0);
        }
        let components = complex.betti_numbers_over(hasse_complex::Field::Z2)[0];
        if components != 1 {
            return Err(DiffusionError::Disconnected { components });
        }
        let rhs = &mut system.rhs;
        let total: f64 = rhs.iter().sum();
        let scale: f64 = rhs.iter().map(|b| b.abs()).sum();
        let relative = if scale > 0.0 {
            total.abs() / scale
        } else {
            0.0
        };
        if relative > self.neumann_tolerance {
            return Err(DiffusionError::IncompatibleNeumann {
                imbalance: total,
                relative,
                tolerance: self.neumann_tolerance,
            });
        }
        let weights = self.mean_weights(complex, system.location, rhs.len());
        let wsum: f64 = weights.iter().sum();
        for (b, w) in rhs.iter_mut().zip(&weights) {
            *b -= total * w / wsum;
        }
        system.fixed[0] = Some(0.0);
        Ok(relative)
    }

    /// Whether the solved matrix's pattern is known before assembly. For
    /// the cell-centred two-point methods it is that of ∂ₙᵀ∂ₙ (cells
    /// coupled through their faces), whatever the conductivity and the
    /// boundary conditions, whose ghost rows touch one cell each and so add
    /// only to the diagonal. For nodal FE every top cell couples all its
    /// vertices (Q1 and virtual-element blocks over the cell, P1 weights
    /// on every edge of a simplex), and the Dirichlet vertices, which the
    /// solve drops, are those of the Dirichlet faces. So does DEC on a
    /// simplicial complex, whose edges join every two vertices of a cell.
    pub(super) fn pattern_from_topology(&self, complex: &Complex) -> bool {
        let n = complex.dim();
        self.iterative.is_none()
            && match self.method {
                Method::Fv | Method::Fd | Method::Fe => true,
                Method::Dec(_) => {
                    (0..complex.cell_count(n)).all(|c| complex.cell_vertices(n, c).len() == n + 1)
                }
                Method::FvMimetic => false,
            }
    }

    /// The pattern the solve will factorise, predicted from topology (see
    /// [`Diffusion::pattern_from_topology`]: ∂ₙᵀ∂ₙ cell-centred, the free
    /// vertices' cell cliques nodal), and its symbolic analysis for this
    /// problem's factorisation and ordering. The nodal prediction restates
    /// which vertices the boundary data and `make_compatible` hold; the
    /// solve uses it only where it matches entry for entry. `None` when the
    /// analysis fails: the solve then analyses the assembled matrix and
    /// reports the failure itself.
    pub(super) fn analyze_topology(
        &self,
        complex: &Complex,
        points: UnknownPoints<'_>,
    ) -> Option<TopologyAnalysis> {
        let n = complex.dim();
        let mut free_points = Vec::new();
        let pattern = if self.location() == Location::Nodal {
            // A boundary tag that names nothing is reported by the assembly.
            let faces = self.boundary_faces(complex).ok()?;
            let mut free = vec![true; complex.cell_count(0)];
            let mut anchored = false;
            for &(f, k) in &faces.condition {
                match self.boundary[k].kind {
                    BoundaryKind::Dirichlet(_) => {
                        anchored = true;
                        for &v in complex.cell_vertices(n - 1, f) {
                            free[v] = false;
                        }
                    }
                    BoundaryKind::Robin { .. } => anchored = true,
                    BoundaryKind::Neumann(_) => {}
                }
            }
            // Without Dirichlet or Robin faces the problem is pure Neumann,
            // and the solve pins vertex 0 (`make_compatible`).
            if !anchored {
                if let Some(first) = free.first_mut() {
                    *first = false;
                }
            }
            free_points = points_of(points, (0..free.len()).filter(|&v| free[v]));
            crate::operator::clique_pattern(
                complex.vertex_star(n),
                |c| complex.cell_vertices(n, c),
                &free,
            )
        } else {
            crate::operator::diagonal_pattern(
                &Arc::clone(complex.boundary(n)),
                &Arc::clone(complex.boundary_csc(n)),
            )
        };
        let points = if self.location() == Location::Nodal {
            UnknownPoints {
                coordinates: &free_points,
                ..points
            }
        } else {
            points
        };
        let solver = DirectSolver::analyze_pattern_at(
            pattern.as_ref(),
            self.factorization,
            self.ordering,
            Some(points),
        )
        .ok()?;
        Some(TopologyAnalysis { pattern, solver })
    }
}
