//! Tests of the cell-centred metrics: FV two-point, FV mimetic (hybrid)
//! and FD five/seven-point, all as Aᵀ Ω A.
//!
//! Expected values are derived by hand from grid positions and spacings,
//! or from properties that do not depend on the code under test
//! (exactness for linear solutions, the divergence theorem, symmetry and
//! kernels), never by re-running the metric code.

use approx::{abs_diff_eq, assert_abs_diff_eq, relative_eq};
use faer::sparse::{SparseColMat, Triplet};
use hasse_complex::generate::{
    box3, delaunay, graded_axis, grid, perturb, rectangle, uniform_axis,
};
use hasse_complex::{Complex, TopCells, Vertices};
use hasse_solver::la::direct::{self, Factorization};
use hasse_solver::metric::{fd, fv, isotropic, Tensor};
use hasse_solver::operator::{BlockMetric, Canonical};
use nalgebra::DMatrix;
use sprs::{CsMat, TriMat};
use std::f64::consts::PI;

// ---------------------------------------------------------------- helpers

/// Aᵀ Ω A as a dense nalgebra matrix.
fn assemble(a: &CsMat<i8>, omega: BlockMetric) -> DMatrix<f64> {
    let m = Canonical::new(a.clone(), omega).unwrap().assemble();
    let dense = m.to_dense();
    DMatrix::from_fn(dense.nrows(), dense.ncols(), |i, j| dense[(i, j)])
}

/// The diagonal of a diagonal metric.
fn diagonal(omega: &BlockMetric) -> Vec<f64> {
    omega
        .to_dense()
        .iter()
        .enumerate()
        .map(|(i, r)| r[i])
        .collect()
}

/// A positive coefficient that varies from cell to cell without pattern.
fn coefficient(cell: usize) -> f64 {
    1.0 + 0.5 * ((cell * 7919) % 13) as f64 + 0.25 * (cell as f64).sin()
}

/// Entrywise |a − b| ≤ tol·max(|a|, |b|).
fn assert_relative_eq(a: &DMatrix<f64>, b: &DMatrix<f64>, tol: f64, what: &str) {
    assert_eq!(a.shape(), b.shape(), "{what}");
    for i in 0..a.nrows() {
        for j in 0..a.ncols() {
            let (x, y) = (a[(i, j)], b[(i, j)]);
            assert!(
                relative_eq!(x, y, epsilon = 0.0, max_relative = tol),
                "{what}: entry ({i}, {j}) is {x} vs {y}"
            );
        }
    }
}

/// (n−1)-cells on the boundary: rows of ∂ₙ with one entry.
fn boundary_faces(k: &Complex) -> Vec<usize> {
    k.boundary(k.dim())
        .outer_iterator()
        .enumerate()
        .filter(|(_, r)| r.nnz() == 1)
        .map(|(f, _)| f)
        .collect()
}

/// Solve M x = 0 with the unknowns in `fixed` set to their values: the
/// fixed columns move to the right-hand side, the reduced SPD system is
/// factorised with LLᵀ.
fn solve_dirichlet(m: &SparseColMat<usize, f64>, fixed: &[Option<f64>], rhs: &[f64]) -> Vec<f64> {
    let mut index = vec![usize::MAX; fixed.len()];
    let mut free = 0;
    for (i, f) in fixed.iter().enumerate() {
        if f.is_none() {
            index[i] = free;
            free += 1;
        }
    }
    let mut reduced_rhs = vec![0.0; free];
    for (i, f) in fixed.iter().enumerate() {
        if f.is_none() {
            reduced_rhs[index[i]] = rhs[i];
        }
    }
    let mut triplets = Vec::new();
    for t in m.triplet_iter() {
        let (i, j, v) = (t.row, t.col, *t.val);
        if fixed[i].is_some() {
            continue;
        }
        match fixed[j] {
            Some(g) => reduced_rhs[index[i]] -= v * g,
            None => triplets.push(Triplet::new(index[i], index[j], v)),
        }
    }
    let reduced = SparseColMat::try_new_from_triplets(free, free, &triplets).unwrap();
    let (y, report) = direct::solve(&reduced, &reduced_rhs, Factorization::Llt).unwrap();
    assert!(report.relative_residual < 1e-12, "{report:?}");
    fixed
        .iter()
        .enumerate()
        .map(|(i, f)| f.unwrap_or_else(|| y[index[i]]))
        .collect()
}

// ------------------------------------------------------------------ meshes

/// A hand-built polygon mesh: one irregular hexagon surrounded by six
/// convex pentagons (spokes out of the hexagon corners, the outer side of
/// each pentagon bent outward). Radii and angles are irregular so that
/// no symmetry hides a sign error.
fn polygon_mesh() -> Complex {
    let inner = [1.0, 1.1, 0.9, 1.05, 0.95, 1.12];
    let spoke = [2.0, 2.2, 1.9, 2.1, 2.05, 1.95];
    let bend = [2.6, 2.5, 2.7, 2.45, 2.55, 2.65];
    let shift = [0.0, 0.05, -0.04, 0.03, -0.02, 0.06];
    let at = |r: f64, a: f64| [r * a.cos(), r * a.sin()];
    let mut points = Vec::new();
    for k in 0..6 {
        points.push(at(inner[k], PI / 3.0 * k as f64 + shift[k]));
    }
    for k in 0..6 {
        points.push(at(spoke[k], PI / 3.0 * k as f64 + shift[k]));
    }
    for (k, &r) in bend.iter().enumerate() {
        points.push(at(r, PI / 3.0 * k as f64 + PI / 6.0));
    }
    let mut cells = TopCells::polygons([[0, 1, 2, 3, 4, 5]]);
    for k in 0..6 {
        let next = (k + 1) % 6;
        cells.push_polygon(&[k, 6 + k, 12 + k, 6 + next, next]);
    }
    Complex::build(Vertices::from_points(&points).unwrap(), cells).unwrap()
}

/// A strongly distorted quadrilateral grid of the unit square.
fn distorted_quads(n: usize, amplitude: f64, seed: u64) -> Complex {
    perturb(
        &rectangle(n, n, [0.0, 1.0], [0.0, 1.0]).unwrap(),
        amplitude,
        seed,
    )
    .unwrap()
}

/// Delaunay triangles of a jittered point set in the unit square.
fn triangles() -> Complex {
    let mut points = Vec::new();
    for j in 0..6 {
        for i in 0..6 {
            let (mut x, mut y) = (i as f64 / 5.0, j as f64 / 5.0);
            if (1..5).contains(&i) && (1..5).contains(&j) {
                x += 0.06 * ((7 * i + 3 * j) as f64).sin();
                y += 0.06 * ((5 * i + 11 * j) as f64).cos();
            }
            points.push([x, y]);
        }
    }
    delaunay(&points).unwrap()
}

/// Distorted hexahedra with planar faces: a distorted quad grid extruded
/// between tilted planes z = 0.4 k + α_k x + β_k y. Vertical faces lie in
/// vertical planes and horizontal ones in the tilted planes, so every
/// face is planar while no cell is a box.
fn planar_hexes() -> Complex {
    let (nx, ny, nz) = (3, 3, 2);
    let base = perturb(&rectangle(nx, ny, [0.0, 1.0], [0.0, 1.0]).unwrap(), 0.3, 5).unwrap();
    let layer = (nx + 1) * (ny + 1);
    let tilt = [(0.05, 0.02), (0.1, -0.06), (-0.04, 0.03)];
    let mut points = Vec::new();
    for (k, (alpha, beta)) in tilt.iter().enumerate() {
        for v in 0..layer {
            let p = base.vertices().point(v);
            points.push([p[0], p[1], 0.4 * k as f64 + alpha * p[0] + beta * p[1]]);
        }
    }
    let mut cells = TopCells::default();
    for k in 0..nz {
        for j in 0..ny {
            for i in 0..nx {
                let o = i + (nx + 1) * j + k * layer;
                let quad = [o, o + 1, o + nx + 1, o + nx + 2];
                let hex: Vec<usize> = quad
                    .iter()
                    .chain(&quad.map(|v| v + layer))
                    .copied()
                    .collect();
                cells.push_cuboid(&hex);
            }
        }
    }
    Complex::build(Vertices::from_points(&points).unwrap(), cells).unwrap()
}

/// A full symmetric positive definite tensor.
const ANISOTROPIC: Tensor = [[2.0, 0.5, 0.1], [0.5, 1.0, 0.2], [0.1, 0.2, 1.5]];

// --------------------------------------------------- FV = FD equivalence

/// TPFA and the five/seven-point stencil give the same Ω and the same
/// Aᵀ Ω A (to 1e-12 relative per entry) for a per-cell scalar coefficient.
fn assert_two_point_equals_five_point(k: &Complex) {
    let n = k.dim();
    let tensors: Vec<Tensor> = (0..k.cell_count(n))
        .map(|c| isotropic(coefficient(c)))
        .collect();
    let a = k.boundary(n).clone();
    let fv_omega = fv::two_point(k, &tensors).unwrap();
    let fd_omega = fd::five_point(k, &tensors).unwrap();
    let (s_fv, s_fd) = (diagonal(&fv_omega), diagonal(&fd_omega));
    let to_column = |s: &[f64]| DMatrix::from_column_slice(s.len(), 1, s);
    assert_relative_eq(&to_column(&s_fv), &to_column(&s_fd), 1e-12, "Ω");
    assert_relative_eq(
        &assemble(&a, fv_omega),
        &assemble(&a, fd_omega),
        1e-12,
        "AᵀΩA",
    );
}

#[test]
fn two_point_equals_five_point_on_a_uniform_rectangle() {
    // 7 × 5 cells of 0.2 × 0.1 (h_x ≠ h_y).
    assert_two_point_equals_five_point(&rectangle(7, 5, [0.0, 1.4], [0.0, 0.5]).unwrap());
}

#[test]
fn two_point_equals_seven_point_on_uniform_and_graded_boxes() {
    assert_two_point_equals_five_point(&box3(3, 4, 2, [0.0, 1.0], [0.0, 2.0], [0.0, 0.5]).unwrap());
    let graded = grid(&[
        graded_axis(4, 0.0, 1.0, 1.7).unwrap(),
        uniform_axis(3, 0.0, 2.0).unwrap(),
        graded_axis(3, -1.0, 1.0, 0.6).unwrap(),
    ])
    .unwrap();
    assert_two_point_equals_five_point(&graded);
}

#[test]
fn two_point_equals_three_and_five_point_on_graded_1d_and_2d_grids() {
    assert_two_point_equals_five_point(&grid(&[graded_axis(6, 0.0, 1.0, 1.4).unwrap()]).unwrap());
    assert_two_point_equals_five_point(
        &grid(&[
            graded_axis(5, 0.0, 1.0, 0.7).unwrap(),
            graded_axis(4, 0.0, 3.0, 2.0).unwrap(),
        ])
        .unwrap(),
    );
}

// ------------------------------------------------------- thesis §5.4

/// The thesis's worked five-point example (§5.4, eqs. 5.10–5.17) on 3×3
/// cells: centre cell 5 with neighbours 1 (N), 6 (E), 9 (S), 4 (W); the
/// corner cells 2, 3, 7, 8 (our labels) are its diagonal neighbours.
#[test]
fn thesis_five_point_example_entry_by_entry() {
    let (hx, hy) = (0.5, 0.25);
    let k = rectangle(3, 3, [0.0, 3.0 * hx], [0.0, 3.0 * hy]).unwrap();
    // Grid position of each cell from its lowest vertex coordinates.
    let position: Vec<(i32, i32)> = (0..9)
        .map(|c| {
            let corner = k
                .cell_vertices(2, c)
                .iter()
                .fold([f64::INFINITY; 2], |m, &v| {
                    let p = k.vertices().point(v);
                    [m[0].min(p[0]), m[1].min(p[1])]
                });
            (
                (corner[0] / hx).round() as i32,
                (corner[1] / hy).round() as i32,
            )
        })
        .collect();
    let label: Vec<usize> = position
        .iter()
        .map(|p| match p {
            (1, 2) => 1,
            (2, 1) => 6,
            (1, 0) => 9,
            (0, 1) => 4,
            (1, 1) => 5,
            (0, 2) => 2,
            (2, 2) => 3,
            (0, 0) => 7,
            _ => 8,
        })
        .collect();
    let cell = |l: usize| label.iter().position(|&x| x == l).unwrap();
    // Cell conductivity λ_i = i; face conductivity λ_ij their harmonic mean.
    let lambda = |i: usize, j: usize| 2.0 * (i * j) as f64 / (i + j) as f64;
    // σ = λ/h (5.17): h_y across horizontal faces (N/S), h_x across vertical.
    let sigma_between = |a: usize, b: usize| {
        let (pa, pb) = (position[a], position[b]);
        let h = if pa.1 != pb.1 { hy } else { hx };
        lambda(label[a], label[b]) / h
    };

    // A = ∂₂ restricted to the interior faces (rows with two entries).
    let full = k.boundary(2);
    let mut tri = TriMat::new((12, 9));
    let mut sigma = Vec::new();
    let mut face_length = Vec::new();
    let mut interior = Vec::new();
    for (f, row) in full
        .outer_iterator()
        .enumerate()
        .filter(|(_, r)| r.nnz() == 2)
    {
        for (c, &s) in row.iter() {
            tri.add_triplet(sigma.len(), c, s);
        }
        let (a, b) = (row.indices()[0], row.indices()[1]);
        sigma.push(sigma_between(a, b));
        face_length.push(if position[a].1 != position[b].1 {
            hx
        } else {
            hy
        });
        interior.push(f);
    }
    assert_eq!(sigma.len(), 12);
    let a: CsMat<i8> = tri.to_csr();
    let m = assemble(&a, fd::from_face_values(&sigma));

    // Row of cell 5, eqs. (5.10)–(5.11) with (5.17).
    let c5 = cell(5);
    let s15 = lambda(1, 5) / hy;
    let s65 = lambda(6, 5) / hx;
    let s95 = lambda(9, 5) / hy;
    let s45 = lambda(4, 5) / hx;
    let close = |x: f64, y: f64| relative_eq!(x, y, epsilon = 1e-14, max_relative = 1e-14);
    assert!(close(m[(c5, c5)], s15 + s65 + s95 + s45));
    for (l, s) in [(1, s15), (6, s65), (9, s95), (4, s45)] {
        assert!(close(m[(c5, cell(l))], -s), "row 5, column {l}");
    }
    for l in [2, 3, 7, 8] {
        assert_eq!(m[(c5, cell(l))], 0.0, "row 5, diagonal neighbour {l}");
    }
    // The balance (5.11) for a temperature field: q15 + q65 + q95 + q45
    // with the fluxes of (5.10), q = σ (T5 − T_neighbour) in all four.
    let t: Vec<f64> = (0..9).map(|c| (label[c] * label[c]) as f64 - 3.0).collect();
    let t5 = t[c5];
    let balance = s15 * (t5 - t[cell(1)])
        + s65 * (t5 - t[cell(6)])
        + s95 * (t5 - t[cell(9)])
        + s45 * (t5 - t[cell(4)]);
    let mt = &m * DMatrix::from_column_slice(9, 1, &t);
    assert!(close(mt[c5], balance));

    // Every other row by the same hand formula.
    for i in 0..9 {
        let mut diagonal = 0.0;
        for j in 0..9 {
            let (dx, dy) = (position[i].0 - position[j].0, position[i].1 - position[j].1);
            if dx.abs() + dy.abs() == 1 {
                diagonal += sigma_between(i, j);
                assert!(close(m[(i, j)], -sigma_between(i, j)), "({i}, {j})");
            } else if i != j {
                assert_eq!(m[(i, j)], 0.0, "({i}, {j})");
            }
        }
        assert!(close(m[(i, i)], diagonal), "diagonal {i}");
    }

    // σ = λ/h has no face length: the thesis's remark λ_ij ∝ Vol(F_ij)
    // restores it. With λ_ij·|F_ij| the thesis Ω is the five-point Ω (the
    // flux balance) on the interior faces.
    let tensors: Vec<Tensor> = (0..9).map(|c| isotropic(label[c] as f64)).collect();
    let five = diagonal(&fd::five_point(&k, &tensors).unwrap());
    for (r, &f) in interior.iter().enumerate() {
        assert!(close(five[f], sigma[r] * face_length[r]), "face {f}");
    }
}

// ------------------------------------------------------- TPFA by hand

#[test]
fn two_point_rows_on_a_uniform_grid_match_the_hand_formula() {
    let (nx, ny, hx, hy, lambda) = (5, 4, 0.3, 0.2, 2.5);
    let k = rectangle(nx, ny, [0.0, nx as f64 * hx], [0.0, ny as f64 * hy]).unwrap();
    let omega = fv::two_point(&k, &vec![isotropic(lambda); nx * ny]).unwrap();
    let m = assemble(k.boundary(2), omega);
    // Cell (i, j) is top cell i + nx j (x fastest). A side with a
    // neighbour adds λ|F|/h to the diagonal and −λ|F|/h off it; a boundary
    // side adds λ|F|/(h/2).
    let (tx, ty) = (lambda * hy / hx, lambda * hx / hy);
    let mut expected = DMatrix::<f64>::zeros(nx * ny, nx * ny);
    for j in 0..ny {
        for i in 0..nx {
            let c = i + nx * j;
            for (di, dj, t) in [(-1i64, 0i64, tx), (1, 0, tx), (0, -1, ty), (0, 1, ty)] {
                let (ni, nj) = (i as i64 + di, j as i64 + dj);
                if (0..nx as i64).contains(&ni) && (0..ny as i64).contains(&nj) {
                    expected[(c, c)] += t;
                    expected[(c, ni as usize + nx * nj as usize)] -= t;
                } else {
                    expected[(c, c)] += 2.0 * t;
                }
            }
        }
    }
    // An interior row is λ(2/h_x² + 2/h_y²)|K| on the diagonal.
    let interior = 2 + nx;
    let volume = hx * hy;
    assert_abs_diff_eq!(
        m[(interior, interior)],
        lambda * (2.0 / (hx * hx) + 2.0 / (hy * hy)) * volume,
        epsilon = 1e-12
    );
    for i in 0..nx * ny {
        for j in 0..nx * ny {
            assert!(
                relative_eq!(
                    m[(i, j)],
                    expected[(i, j)],
                    epsilon = 1e-12,
                    max_relative = 1e-12
                ),
                "({i}, {j})"
            );
        }
    }
}

// -------------------------------------------- TPFA patch test (known loss)

/// Cell-centred TPFA with Dirichlet data u(x_F) on every boundary face
/// (right-hand side Aᵀ Ω w, w_F = ∂ₙ(F, K) u(x_F)); the largest error at
/// the cell centroids.
fn two_point_linear_error(k: &Complex) -> f64 {
    let u = |x: &[f64]| 1.0 + 2.0 * x[0] - 3.0 * x[1];
    let n = k.dim();
    let cells = k.cell_count(n);
    let a = k.boundary(n).clone();
    let mut w = vec![0.0; a.rows()];
    for f in boundary_faces(k) {
        let row = a.outer_view(f).unwrap();
        w[f] = f64::from(row.data()[0]) * u(k.centroid_of(n - 1, f));
    }
    let op = Canonical::new(a, fv::two_point(k, &vec![isotropic(1.0); cells]).unwrap()).unwrap();
    let rhs = op.sum_transpose(&op.metric().apply(&w));
    let (x, _) = direct::solve(&op.assemble(), &rhs, Factorization::Llt).unwrap();
    (0..cells)
        .map(|c| (x[c] - u(k.centroid_of(n, c))).abs())
        .fold(0.0, f64::max)
}

#[test]
fn two_point_is_exact_for_linear_solutions_only_on_orthogonal_grids() {
    let uniform = rectangle(8, 8, [0.0, 1.0], [0.0, 1.0]).unwrap();
    let graded = grid(&[
        graded_axis(7, 0.0, 1.0, 1.5).unwrap(),
        graded_axis(6, 0.0, 1.0, 0.7).unwrap(),
    ])
    .unwrap();
    assert!(two_point_linear_error(&uniform) < 1e-10);
    assert!(two_point_linear_error(&graded) < 1e-10);
    // The known loss of consistency on distorted cells.
    let distorted = two_point_linear_error(&distorted_quads(8, 0.4, 3));
    assert!(
        distorted > 1e-3,
        "TPFA error on distorted quads: {distorted:e}"
    );
}

// ------------------------------------------------------------- mimetic

/// Per cell: T_K D = N K (exact fluxes for linear functions) with N, D
/// recomputed from the geometry; T_K symmetric positive definite; the
/// half-face rows of A are +1 on the cell and −1 on the face.
fn assert_mimetic_consistent(k: &Complex, tensor: Tensor) {
    let (n, d) = (k.dim(), k.embedding_dim());
    let cells = k.cell_count(n);
    let (a, omega, layout) = fv::mimetic_hybrid(k, &vec![tensor; cells]).unwrap();
    assert_eq!((layout.cells, layout.faces), (cells, k.cell_count(n - 1)));
    assert_eq!(omega.block_count(), cells);
    assert!(omega.is_symmetric(0.0));
    let kk = DMatrix::from_fn(d, d, |i, j| tensor[i][j]);
    let csc = k.boundary_csc(n);
    let mut row = 0;
    for cell in 0..cells {
        let (rows, cols, values) = omega.block(cell);
        let col = csc.outer_view(cell).unwrap();
        let m = col.nnz();
        assert_eq!(rows, cols);
        assert_eq!(rows, (row..row + m).collect::<Vec<_>>().as_slice());
        let t = DMatrix::from_row_slice(m, m, values);
        let mut nn = DMatrix::zeros(m, d);
        let mut dd = DMatrix::zeros(m, d);
        for (i, (f, &s)) in col.iter().enumerate() {
            let half = a.outer_view(row + i).unwrap();
            assert_eq!(half.indices(), &[cell, layout.face_column(f)]);
            assert_eq!(half.data(), &[1, -1]);
            for x in 0..d {
                nn[(i, x)] = f64::from(s) * k.measure(n - 1)[f] * k.normal()[f * d + x];
                dd[(i, x)] = k.centroid_of(n - 1, f)[x] - k.centroid_of(n, cell)[x];
            }
        }
        let exact = &nn * &kk;
        let residual = (&t * &dd - &exact).amax();
        assert!(
            residual <= 1e-12 * exact.amax(),
            "cell {cell}: |T D − N K| = {residual:e}"
        );
        let eigen = t.symmetric_eigen().eigenvalues;
        assert!(
            eigen.min() > 1e-8 * eigen.max(),
            "cell {cell}: T not positive definite"
        );
        row += m;
    }
    assert_eq!(row, a.rows());
}

#[test]
fn mimetic_transmissibility_is_consistent_on_distorted_and_polygonal_cells() {
    for tensor in [isotropic(1.0), ANISOTROPIC] {
        assert_mimetic_consistent(&distorted_quads(5, 0.4, 7), tensor);
        assert_mimetic_consistent(&polygon_mesh(), tensor);
        assert_mimetic_consistent(&triangles(), tensor);
        assert_mimetic_consistent(&planar_hexes(), tensor);
    }
}

/// Hybrid patch test: Dirichlet values of the linear `u` fixed on the
/// boundary faces, −∇·(K∇u) = 0 solved for cell and interior face values.
/// Returns the largest error at cell centroids and at face centroids.
fn mimetic_linear_error(k: &Complex, tensor: Tensor, u: impl Fn(&[f64]) -> f64) -> (f64, f64) {
    let n = k.dim();
    let (a, omega, layout) = fv::mimetic_hybrid(k, &vec![tensor; k.cell_count(n)]).unwrap();
    let m = Canonical::new(a, omega).unwrap().assemble();
    let mut fixed = vec![None; layout.unknowns()];
    for f in boundary_faces(k) {
        fixed[layout.face_column(f)] = Some(u(k.centroid_of(n - 1, f)));
    }
    let x = solve_dirichlet(&m, &fixed, &vec![0.0; layout.unknowns()]);
    let cell_error = (0..layout.cells)
        .map(|c| (x[c] - u(k.centroid_of(n, c))).abs())
        .fold(0.0, f64::max);
    let face_error = (0..layout.faces)
        .map(|f| (x[layout.face_column(f)] - u(k.centroid_of(n - 1, f))).abs())
        .fold(0.0, f64::max);
    (cell_error, face_error)
}

#[test]
fn mimetic_hybrid_reproduces_linear_solutions_on_distorted_quads_and_polygons() {
    let u = |x: &[f64]| 1.0 + 2.0 * x[0] - 3.0 * x[1];
    for (name, k) in [
        ("distorted quads", distorted_quads(8, 0.4, 3)),
        ("hexagon and pentagons", polygon_mesh()),
        ("Delaunay triangles", triangles()),
    ] {
        for tensor in [isotropic(1.0), ANISOTROPIC] {
            let (cells, faces) = mimetic_linear_error(&k, tensor, u);
            assert!(
                cells < 1e-10 && faces < 1e-10,
                "{name}: errors {cells:e}, {faces:e}"
            );
        }
    }
}

#[test]
fn mimetic_hybrid_reproduces_linear_solutions_on_distorted_hexes() {
    let u = |x: &[f64]| 1.0 + 2.0 * x[0] - 3.0 * x[1] + 0.5 * x[2];
    let k = planar_hexes();
    for tensor in [isotropic(1.0), ANISOTROPIC] {
        let (cells, faces) = mimetic_linear_error(&k, tensor, u);
        assert!(
            cells < 1e-10 && faces < 1e-10,
            "errors {cells:e}, {faces:e}"
        );
    }
}

#[test]
fn mimetic_hybrid_matrix_is_symmetric_semidefinite_with_constant_kernel() {
    for k in [distorted_quads(4, 0.4, 9), polygon_mesh()] {
        let cells = k.cell_count(2);
        let (a, omega, layout) = fv::mimetic_hybrid(&k, &vec![ANISOTROPIC; cells]).unwrap();
        let op = Canonical::new(a.clone(), omega.clone()).unwrap();
        let m = assemble(&a, omega);
        let scale = m.amax();
        assert!((&m - m.transpose()).amax() <= 1e-14 * scale);
        let ones = op.apply(&vec![1.0; layout.unknowns()]);
        assert!(ones.iter().all(|v| v.abs() <= 1e-13 * scale), "M·1 ≠ 0");
        let mut eigen: Vec<f64> = m.symmetric_eigen().eigenvalues.iter().copied().collect();
        eigen.sort_by(f64::total_cmp);
        assert_abs_diff_eq!(eigen[0], 0.0, epsilon = 1e-12 * scale);
        assert!(
            eigen[1] > 1e-6 * scale,
            "kernel larger than the constants: {:e}",
            eigen[1]
        );
    }
}

/// On boxes with a diagonal tensor the stabilisation makes T_K diagonal
/// (the two-point half transmissibilities), so the hybrid cell values are
/// the TPFA solution for any Dirichlet data, here a non-linear one.
#[test]
fn mimetic_hybrid_reduces_to_two_point_on_a_graded_grid() {
    let k = grid(&[
        graded_axis(6, 0.0, 1.2, 1.3).unwrap(),
        uniform_axis(4, 0.0, 0.6).unwrap(),
    ])
    .unwrap();
    let cells = k.cell_count(2);
    let tensors: Vec<Tensor> = (0..cells)
        .map(|c| {
            [
                [coefficient(c), 0.0, 0.0],
                [0.0, 2.0 * coefficient(c + 5), 0.0],
                [0.0, 0.0, 1.0],
            ]
        })
        .collect();
    let g = |x: &[f64]| (3.0 * x[0]).sin() * x[1].exp();

    let (a, omega, layout) = fv::mimetic_hybrid(&k, &tensors).unwrap();
    let m = Canonical::new(a, omega).unwrap().assemble();
    let mut fixed = vec![None; layout.unknowns()];
    let mut w = vec![0.0; layout.faces];
    let d2 = k.boundary(2);
    for f in boundary_faces(&k) {
        let value = g(k.centroid_of(1, f));
        fixed[layout.face_column(f)] = Some(value);
        w[f] = f64::from(d2.outer_view(f).unwrap().data()[0]) * value;
    }
    let hybrid = solve_dirichlet(&m, &fixed, &vec![0.0; layout.unknowns()]);

    let op = Canonical::new(d2.clone(), fv::two_point(&k, &tensors).unwrap()).unwrap();
    let rhs = op.sum_transpose(&op.metric().apply(&w));
    let (tpfa, _) = direct::solve(&op.assemble(), &rhs, Factorization::Llt).unwrap();
    for c in 0..cells {
        assert!(
            abs_diff_eq!(hybrid[c], tpfa[c], epsilon = 1e-10),
            "cell {c}: {} vs {}",
            hybrid[c],
            tpfa[c]
        );
    }
}
