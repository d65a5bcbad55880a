//! What a solution yields besides its values: cell-wise gradients, error
//! norms against an exact solution, face-flux errors and per-cell
//! conservation residuals.

use super::*;

/// Cell-wise gradient of a discrete field, by least squares over the
/// points that carry values: the cell's vertices (nodal), the centroids of
/// the neighbouring cells (cell-centred) or of the cell's faces (hybrid).
/// Exact for linear fields (for cell-centred values wherever a cell has at
/// least d neighbours in general position).
pub fn reconstruct_gradient(complex: &Complex, solution: &Solution) -> Vec<[f64; 3]> {
    gradient_of(
        complex,
        solution.location,
        &solution.values,
        solution.cell_points.as_deref(),
    )
}

/// [`reconstruct_gradient`] of any field laid out as `location` says (all
/// unknowns), e.g. a level of a transient run; `cell_points` are the cell
/// points of a cell-centred field when they are not the centroids.
pub fn gradient_of(
    complex: &Complex,
    location: Location,
    values: &[f64],
    cell_points: Option<&[f64]>,
) -> Vec<[f64; 3]> {
    let n = complex.dim();
    let d = complex.embedding_dim();
    let cells = complex.cell_count(n);
    let centre = match location {
        Location::CellCentred => cell_points.unwrap_or(complex.centroid(n)),
        _ => complex.centroid(n),
    };
    let face_centre = complex.centroid(n - 1);
    let by_cell = complex.boundary_csc(n);
    let top = complex.boundary(n);
    let at = |x: &[f64]| -> [f64; 3] {
        let mut p = [0.0; 3];
        p[..d].copy_from_slice(&x[..d]);
        p
    };
    // Cells are independent; each worker keeps one point buffer.
    (0..cells)
        .into_par_iter()
        .map_init(Vec::new, |points: &mut Vec<([f64; 3], f64)>, c| {
            points.clear();
            let xc = &centre[c * d..(c + 1) * d];
            match location {
                Location::Nodal => {
                    let vertices = complex.cell_vertices(n, c);
                    // A simplex carries the P1 field: its gradient exactly,
                    // tangent to the cell on a surface (a least-squares fit
                    // there leans on a pseudo-inverse cutoff).
                    if vertices.len() == n + 1 {
                        if let Some(g) = p1_gradient(complex, vertices, values) {
                            return g;
                        }
                    }
                    for &v in vertices {
                        points.push((at(complex.vertices().point(v)), values[v]));
                    }
                }
                Location::Hybrid => {
                    if let Some(col) = by_cell.outer_view(c) {
                        for (f, _) in col.iter() {
                            points.push((at(&face_centre[f * d..(f + 1) * d]), values[cells + f]));
                        }
                    }
                }
                Location::CellCentred => {
                    points.push((at(xc), values[c]));
                    if let Some(col) = by_cell.outer_view(c) {
                        for (f, _) in col.iter() {
                            if let Some(row) = top.outer_view(f) {
                                for (other, _) in row.iter() {
                                    if other != c {
                                        points.push((
                                            at(&centre[other * d..(other + 1) * d]),
                                            values[other],
                                        ));
                                    }
                                }
                            }
                        }
                    }
                }
            }
            least_squares_gradient(points, d)
        })
        .collect()
}

/// Where each top cell's value and gradient stand: the cell points of a
/// cell-centred solution (centroids unless [`Solution::cell_points`] says
/// otherwise), the centroids for the others, as coordinates in a row.
pub(super) fn cell_centres<'a>(complex: &'a Complex, solution: &'a Solution) -> &'a [f64] {
    let n = complex.dim();
    match solution.location {
        Location::CellCentred => solution
            .cell_points
            .as_deref()
            .unwrap_or(complex.centroid(n)),
        _ => complex.centroid(n),
    }
}

/// Σ_v u_v ∇λ_v on the simplex with `vertices`; `None` if degenerate.
fn p1_gradient(complex: &Complex, vertices: &[usize], values: &[f64]) -> Option<[f64; 3]> {
    let d = complex.embedding_dim();
    let corners: Vec<[f64; 3]> = vertices
        .iter()
        .map(|&v| {
            let mut x = [0.0; 3];
            x[..d].copy_from_slice(complex.vertices().point(v));
            x
        })
        .collect();
    let (_, gradients) = fe::simplex_gradients(&corners, d)?;
    let mut g = [0.0; 3];
    for (&v, gv) in vertices.iter().zip(&gradients) {
        for a in 0..3 {
            g[a] += values[v] * gv[a];
        }
    }
    Some(g)
}

/// The gradient g minimising Σ (u_i − ū − g·(x_i − x̄))² over `points`
/// (coordinates padded to three, the first `d` used), on the stack. The
/// normal equations' matrix is symmetric positive semidefinite, so its
/// pseudo-inverse comes from its eigenvalues, with those below 1e-14 of its
/// Frobenius norm dropped: a rank-deficient fit (too few points, or points
/// on an embedded surface) gets the minimum-norm solution. Below three
/// dimensions the unused rows are zero, whose eigenvalues are dropped too.
pub(super) fn least_squares_gradient(points: &[([f64; 3], f64)], d: usize) -> [f64; 3] {
    let m = points.len() as f64;
    let mut mean_x = nalgebra::Vector3::<f64>::zeros();
    let mut mean_u = 0.0;
    for (x, u) in points {
        for a in 0..d {
            mean_x[a] += x[a] / m;
        }
        mean_u += u / m;
    }
    let mut normal = nalgebra::Matrix3::<f64>::zeros();
    let mut right = nalgebra::Vector3::<f64>::zeros();
    for (x, u) in points {
        for a in 0..d {
            for b in 0..d {
                normal[(a, b)] += (x[a] - mean_x[a]) * (x[b] - mean_x[b]);
            }
            right[a] += (x[a] - mean_x[a]) * (u - mean_u);
        }
    }
    let cutoff = 1e-14 * normal.norm().max(f64::MIN_POSITIVE);
    let eigen = normal.symmetric_eigen();
    let mut solution = nalgebra::Vector3::<f64>::zeros();
    for (k, &lambda) in eigen.eigenvalues.iter().enumerate() {
        if lambda > cutoff {
            let v = eigen.eigenvectors.column(k);
            solution += v * (v.dot(&right) / lambda);
        }
    }
    let mut g = [0.0; 3];
    g[..d].copy_from_slice(&solution.as_slice()[..d]);
    g
}

/// Errors of `solution` against the exact field `u` (and its gradient, if
/// given). For pure-Neumann problems the mean of the difference is removed
/// first (the solution is only defined up to a constant).
///
/// The L² and H¹-seminorm errors integrate on every top cell the field the
/// method represents: P1 on simplices, the isoparametric Q1 map on
/// quadrilaterals and hexahedra, the piecewise-linear fan interpolant on
/// other cells (virtual elements, cells of surfaces), and for cell values
/// u_c + g_c·(x − x_c) with the reconstructed gradient g_c; see
/// [`Errors`] for the sampled figures kept beside them.
///
/// ```
/// use hasse_complex::generate::rectangle;
/// use hasse_solver::metric::Method;
/// use hasse_solver::physics::diffusion::{errors, Diffusion};
/// use hasse_solver::physics::{BoundaryKind, Conductivity, ScalarFn, VectorFn};
/// use std::f64::consts::PI;
/// use std::sync::Arc;
/// let exact: ScalarFn = Arc::new(|x| (PI * x[0]).sin() * (PI * x[1]).sin());
/// let gradient: VectorFn = Arc::new(|x| {
///     let (s, c) = ((PI * x[0]).sin_cos(), (PI * x[1]).sin_cos());
///     [PI * s.1 * c.0, PI * s.0 * c.1, 0.0]
/// });
/// let l2 = |n: usize| {
///     let mesh = rectangle(n, n, [0.0, 1.0], [0.0, 1.0]).unwrap();
///     let solution = Diffusion::new(Method::Fe, Conductivity::Scalar(Arc::new(|_| 1.0)),
///         Arc::new(|x: &[f64]| 2.0 * PI * PI * (PI * x[0]).sin() * (PI * x[1]).sin()))
///         .with_boundary("boundary", BoundaryKind::Dirichlet(Arc::new(|_| 0.0)))
///         .solve(&mesh)
///         .unwrap();
///     let e = errors(&mesh, &solution, &exact, Some(&gradient));
///     assert!(e.max >= e.l2 && e.gradient_l2.is_finite());
///     e.l2
/// };
/// // Q1 elements converge at second order in L²: halving h quarters the error.
/// let order = (l2(8) / l2(16)).log2();
/// assert!((order - 2.0).abs() < 0.15);
/// ```
pub fn errors(
    complex: &Complex,
    solution: &Solution,
    exact: &ScalarFn,
    exact_gradient: Option<&VectorFn>,
) -> Errors {
    let n = complex.dim();
    let d = complex.embedding_dim();
    let (points, weights): (Vec<Vec<f64>>, Vec<f64>) = match solution.location {
        Location::Nodal => (
            (0..complex.cell_count(0))
                .map(|v| complex.vertices().point(v).to_vec())
                .collect(),
            lumped_vertex_volumes(complex),
        ),
        _ => (
            solution
                .cell_points
                .as_deref()
                .unwrap_or(complex.centroid(n))
                .chunks(d)
                .map(<[f64]>::to_vec)
                .collect(),
            complex.measure(n).to_vec(),
        ),
    };
    let field = solution.field(complex);
    let mut diff: Vec<f64> = points
        .iter()
        .zip(field)
        .map(|(x, u)| u - exact(x))
        .collect();
    if solution.pure_neumann {
        let wsum: f64 = weights.iter().sum();
        let mean: f64 = diff.iter().zip(&weights).map(|(e, w)| e * w).sum::<f64>() / wsum;
        for e in &mut diff {
            *e -= mean;
        }
    }
    let l2 = diff
        .iter()
        .zip(&weights)
        .map(|(e, w)| e * e * w)
        .sum::<f64>()
        .sqrt();
    let max = diff.iter().fold(0.0f64, |m, e| m.max(e.abs()));
    // One reconstruction serves the sampled figure and the quadrature.
    let cell_gradients = match (solution.location, exact_gradient) {
        (Location::Nodal, None) => Vec::new(),
        _ => reconstruct_gradient(complex, solution),
    };
    let gradient_l2 = exact_gradient.map_or(f64::NAN, |grad| {
        let volume = complex.measure(n);
        let centre = complex.centroid(n);
        (0..complex.cell_count(n))
            .map(|c| {
                let e = grad(&centre[c * d..(c + 1) * d]);
                let s: f64 = (0..d).map(|a| (cell_gradients[c][a] - e[a]).powi(2)).sum();
                s * volume[c]
            })
            .sum::<f64>()
            .sqrt()
    });
    let quadrature = norms::quadrature_errors(
        complex,
        solution,
        &cell_gradients,
        exact,
        exact_gradient,
        solution.pure_neumann,
    );
    let (quadrature_l2, quadrature_gradient) = quadrature.unwrap_or((l2, gradient_l2));
    Errors {
        l2: quadrature_l2,
        max,
        gradient_l2: quadrature_gradient,
        l2_sampled: l2,
        gradient_sampled: gradient_l2,
        quadrature: quadrature.is_some(),
    }
}

/// Discrete L² error of the face fluxes of a cell-centred or hybrid
/// solution against the exact flux −∫_F K∇u·n ≈ −|F| K(x_F)∇u(x_F)·n_F:
/// sqrt(Σ_F w_F ((q_F − q_F^exact)/|F|)²) with w_F = |F| d_F, d_F the
/// distance between the centroids on either side of F (cell to face on the
/// boundary, and for the half-faces of the hybrid method). Boundary faces
/// without flux (Neumann) are included: their exact flux is the data's.
/// `None` for nodal methods, whose edge cochain is not a face flux.
pub fn flux_error(
    complex: &Complex,
    solution: &Solution,
    problem: &Diffusion,
    exact_gradient: &VectorFn,
) -> Option<f64> {
    let n = complex.dim();
    let d = complex.embedding_dim();
    let area = complex.measure(n - 1);
    let face_centre = complex.centroid(n - 1);
    let cell_centre = complex.centroid(n);
    let normal = complex.normal();
    // Per region, a face takes the conductivity of the cell whose flux is
    // measured (where K jumps, the exact K∇u·n is continuous but ∇u is not;
    // the exact gradient is the user's to give on the cell's side).
    let owner = match &problem.conductivity {
        Conductivity::Regional(r) => r.piece_per_cell(complex).ok(),
        _ => None,
    };
    let exact_density = |f: usize, cell: usize| -> f64 {
        let x = &face_centre[f * d..(f + 1) * d];
        let g = exact_gradient(x);
        let k = conductivity_at(&problem.conductivity, owner.as_deref(), cell, x);
        let mut kg = [0.0; 3];
        for a in 0..d {
            for b in 0..d {
                kg[a] += k[a][b] * g[b];
            }
        }
        -(0..d).map(|a| kg[a] * normal[f * d + a]).sum::<f64>()
    };
    let distance = |x: &[f64], y: &[f64]| -> f64 {
        x.iter()
            .zip(y)
            .map(|(a, b)| (a - b) * (a - b))
            .sum::<f64>()
            .sqrt()
    };
    let top = complex.boundary(n);
    let mut sum = 0.0;
    match solution.location {
        Location::Nodal => return None,
        Location::CellCentred => {
            for (f, row) in top.outer_iterator().enumerate() {
                let xf = &face_centre[f * d..(f + 1) * d];
                let cells: Vec<usize> = row.indices().to_vec();
                let d_f = match cells.as_slice() {
                    [k, l] => distance(
                        &cell_centre[k * d..(k + 1) * d],
                        &cell_centre[l * d..(l + 1) * d],
                    ),
                    [k] => distance(&cell_centre[k * d..(k + 1) * d], xf),
                    _ => continue,
                };
                let e = solution.flux[f] / area[f] - exact_density(f, cells[0]);
                sum += area[f] * d_f * e * e;
            }
        }
        Location::Hybrid => {
            // Half-face rows follow boundary_csc(n): cell by cell, its faces;
            // the sign turns the face normal into the cell's outward normal.
            let by_cell = complex.boundary_csc(n);
            let mut row = 0;
            for (k, col) in by_cell.outer_iterator().enumerate() {
                for (f, &s) in col.iter() {
                    let xf = &face_centre[f * d..(f + 1) * d];
                    let d_f = distance(&cell_centre[k * d..(k + 1) * d], xf);
                    let e = solution.flux[row] / area[f] - f64::from(s) * exact_density(f, k);
                    sum += area[f] * d_f * e * e;
                    row += 1;
                }
            }
        }
    }
    Some(sum.sqrt())
}

/// K at `x` in top cell `cell`; `owner` is the region index of every cell
/// for a conductivity per region (a region's own regional conductivity,
/// which case files cannot write, gives NaN here).
fn conductivity_at(k: &Conductivity, owner: Option<&[usize]>, cell: usize, x: &[f64]) -> Tensor {
    match (k, owner) {
        (Conductivity::Scalar(l), _) => metric::isotropic(l(x)),
        (Conductivity::Tensor(t), _) => t(x),
        (Conductivity::Regional(r), Some(owner)) => match r.piece(owner[cell]) {
            Conductivity::Regional(_) => [[f64::NAN; 3]; 3],
            piece => conductivity_at(piece, None, cell, x),
        },
        (Conductivity::Regional(_), None) => [[f64::NAN; 3]; 3],
    }
}

/// Per-cell conservation residual of cell-centred fluxes: for every top
/// cell, Σ_F ∂(F,c) q_F − ∫_c f (zero to rounding for FV/FD).
pub fn conservation_residual(
    complex: &Complex,
    solution: &Solution,
    source: &ScalarFn,
) -> Vec<f64> {
    let n = complex.dim();
    let d = complex.embedding_dim();
    let volume = complex.measure(n);
    let centre = complex.centroid(n);
    let by_cell = complex.boundary_csc(n);
    (0..complex.cell_count(n))
        .map(|c| {
            let out: f64 = by_cell.outer_view(c).map_or(0.0, |col| {
                col.iter()
                    .map(|(f, &s)| f64::from(s) * solution.flux[f])
                    .sum()
            });
            out - source(&centre[c * d..(c + 1) * d]) * volume[c]
        })
        .collect()
}
