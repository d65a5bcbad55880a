//! The mimetic methods on convex cells: the hybrid diffusion metric
//! ([`mimetic_hybrid`], cell and face unknowns) and the flux mass of mixed
//! Darcy ([`flux_mass`], face fluxes). Both are one dense block per cell
//! over the cell's half-faces, built from the same half-face geometry: the
//! outward area normals N, the offsets X of the face centroids from the
//! cell centroid, and the two-point half resistances d/κ. One is the
//! inverse form of the other: T_K maps potentials to fluxes, M_K fluxes to
//! potential drops, and each is a consistency term plus a stabilisation
//! that vanishes where the consistency term is exact.

use super::{check_dimension, FaceGeometry};
use crate::metric::{CellTensors, MetricError, Tensor};
use crate::operator::BlockMetric;
use hasse_complex::{Complex, DualKind};
use nalgebra::DMatrix;
use rayon::prelude::*;
use sprs::CsMat;

/// Sizes of the hybrid unknown vector: cell values in columns
/// `0..cells`, then face values in columns `cells..cells + faces`.
///
/// ```
/// use hasse_complex::generate::rectangle;
/// use hasse_solver::metric::{fv, isotropic};
/// // One unit square: one cell unknown, then its four faces.
/// let k = rectangle(1, 1, [0.0, 1.0], [0.0, 1.0]).unwrap();
/// let (a, _, layout) = fv::mimetic_hybrid(&k, &[isotropic(1.0)]).unwrap();
/// assert_eq!((layout.cells, layout.faces, layout.unknowns()), (1, 4, 5));
/// assert_eq!(layout.face_column(3), 4);
/// // Each half-face row of A is u_K − λ_F: +1 at the cell, −1 at the face.
/// assert_eq!(a.cols(), layout.unknowns());
/// assert!(a.outer_iterator().all(|row| row.get(0) == Some(&1) && row.nnz() == 2));
/// ```
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct HybridLayout {
    /// Number of top cells (cell unknowns u_K).
    pub cells: usize,
    /// Number of (n−1)-cells (face unknowns λ_F).
    pub faces: usize,
}

impl HybridLayout {
    /// Total number of unknowns.
    pub fn unknowns(&self) -> usize {
        self.cells + self.faces
    }

    /// Column of the face unknown λ_F.
    pub fn face_column(&self, face: usize) -> usize {
        self.cells + face
    }
}

/// The half-face geometry of one cell, one row per face in the order of
/// the cell's column of ∂ₙ by cells.
struct HalfFaces {
    /// Rows |F| n_{K,F}ᵀ, outward (N).
    outward: DMatrix<f64>,
    /// Rows (x_F − x_K)ᵀ (X, or D).
    offsets: DMatrix<f64>,
    /// |F|.
    areas: Vec<f64>,
    /// d_{K,F} / κ_{K,F}: the two-point resistance of the half cell per
    /// unit face area.
    resistances: Vec<f64>,
}

/// The half faces of `cell`, with its coefficient `tensor`.
fn half_faces(
    complex: &Complex,
    geometry: &FaceGeometry,
    cell: usize,
    tensor: &Tensor,
    method: &'static str,
) -> Result<HalfFaces, MetricError> {
    let (n, d) = (complex.dim(), complex.embedding_dim());
    let by_cell = complex.boundary_csc(n);
    let range = by_cell.indptr().outer_inds_sz(cell);
    let cell_faces = &by_cell.indices()[range.clone()];
    let signs = &by_cell.data()[range];
    let m = cell_faces.len();
    let mut half = HalfFaces {
        outward: DMatrix::zeros(m, d),
        offsets: DMatrix::zeros(m, d),
        areas: Vec::with_capacity(m),
        resistances: Vec::with_capacity(m),
    };
    for (i, (&face, &sign)) in cell_faces.iter().zip(signs).enumerate() {
        let face_half = geometry.half(face, cell);
        for a in 0..d {
            half.outward[(i, a)] = f64::from(sign) * face_half.area * face_half.normal[a];
            half.offsets[(i, a)] = face_half.x_face[a] - face_half.x_cell[a];
        }
        half.areas.push(face_half.area);
        half.resistances
            .push(face_half.resistance(tensor, cell, method)?);
    }
    Ok(half)
}

/// consistency + (I − QQᵀ) S (I − QQᵀ), symmetrised, with Q an orthonormal
/// basis of the columns of `span` and S = diag(`stabilisation`): the
/// stabilisation vanishes on span, where the consistency term is exact. A
/// `span` that lost rank (a degenerate cell) is refused, naming what
/// should have spanned the space.
fn stabilised(
    consistency: DMatrix<f64>,
    span: &DMatrix<f64>,
    stabilisation: &[f64],
    cell: usize,
    method: &'static str,
    needs: &'static str,
) -> Result<DMatrix<f64>, MetricError> {
    let (m, d) = span.shape();
    let qr = span.clone().qr();
    let r = qr.r();
    let diagonal: Vec<f64> = (0..d).map(|i| r[(i, i)].abs()).collect();
    let largest = diagonal.iter().fold(0.0f64, |a, &b| a.max(b));
    // A zero or NaN diagonal of R means the span lost rank.
    if diagonal.iter().any(|&v| v.is_nan() || v <= 1e-12 * largest) {
        return Err(MetricError::UnsupportedCell {
            method,
            needs,
            cell,
        });
    }
    let q = qr.q();
    let projector = DMatrix::<f64>::identity(m, m) - &q * q.transpose();
    let s = DMatrix::from_diagonal(&nalgebra::DVector::from_column_slice(stabilisation));
    let block = consistency + &projector * s * &projector;
    // Symmetrise away rounding so the block is symmetric bit for bit.
    Ok((&block + block.transpose()) * 0.5)
}

/// The mimetic transmissibility matrix T_K of one cell (see
/// [`mimetic_hybrid`]): (1/|K|) N K Nᵀ + (I − P_D) W (I − P_D) with
/// W = diag(|F| κ / d).
fn transmissibility(
    tensor: &Tensor,
    volume: f64,
    half: &HalfFaces,
    cell: usize,
) -> Result<DMatrix<f64>, MetricError> {
    let d = half.outward.ncols();
    let k = DMatrix::from_fn(d, d, |i, j| 0.5 * (tensor[i][j] + tensor[j][i]));
    // Consistency: NᵀD = |K| I (the divergence theorem for linear
    // functions), so T₀ D = N K — exact fluxes for linear u.
    let consistency = &half.outward * &k * half.outward.transpose() / volume;
    // Stabilisation W = diag(|F| κ_F / d_F), the two-point half
    // transmissibilities: it has the scale of T₀ on every cell shape, and
    // on a box with a diagonal tensor T₀ + (I − QQᵀ) W (I − QQᵀ) is exactly
    // W, so the method reduces to TPFA where TPFA is consistent.
    let w: Vec<f64> = half
        .areas
        .iter()
        .zip(&half.resistances)
        .map(|(a, r)| a / r)
        .collect();
    stabilised(
        consistency,
        &half.offsets,
        &w,
        cell,
        "mimetic finite differences",
        "a non-degenerate cell (face centroids spanning the space)",
    )
}

/// One dense block per top cell over the cell's half-faces (rows of ∂ₙ by
/// cells, cell after cell), computed in parallel by `block`.
fn cell_blocks(
    complex: &Complex,
    block: impl Fn(usize) -> Result<DMatrix<f64>, MetricError> + Sync + Send,
) -> Result<BlockMetric, MetricError> {
    let n = complex.dim();
    let _ = (complex.measure(n), complex.measure(n - 1), complex.normal());
    let _ = (complex.centroid(n), complex.centroid(n - 1));
    let by_cell = complex.boundary_csc(n);
    let indptr = by_cell.indptr();
    let blocks = (0..complex.cell_count(n))
        .into_par_iter()
        .map(&block)
        .collect::<Result<Vec<_>, MetricError>>()?;
    let mut omega = BlockMetric::new(by_cell.nnz());
    let mut rows: Vec<usize> = Vec::new();
    for (cell, t) in blocks.iter().enumerate() {
        rows.clear();
        rows.extend(indptr.outer_inds_sz(cell));
        // nalgebra is column-major; the block is symmetric, so its
        // column-major storage is also its row-major storage.
        omega.push_symmetric(&rows, t.as_slice());
    }
    Ok(omega)
}

/// A complex that fills its space, as the mimetic methods need.
fn check_volume(complex: &Complex, method: &'static str) -> Result<usize, MetricError> {
    let n = check_dimension(complex, method)?;
    let d = complex.embedding_dim();
    if n != d {
        return Err(MetricError::UnsupportedMesh {
            method,
            needs: "a complex that fills its space (n = d)",
            detail: format!("the complex is {n}-dimensional in R^{d}"),
        });
    }
    Ok(n)
}

/// Mimetic finite differences (lowest order) in hybrid form, consistent on
/// every mesh of convex cells with planar faces.
///
/// Unknowns are cell values u_K (columns `0..cells`) and face values λ_F
/// (columns `cells..cells + faces`, see [`HybridLayout`]). The returned
/// incidence A has one row per half-face (K, F ∈ ∂K), cells in order and
/// each cell's faces in the order of column K of `boundary_csc(n)`, with
/// +1 in column K and −1 in column `cells + F`: (A x)_{K,F} = u_K − λ_F.
///
/// Ω is block diagonal, one |∂K| × |∂K| block T_K per cell (block K of the
/// metric), mapping u_K 1 − λ_K to the outward fluxes of −K∇u through the
/// faces of K:
///
/// T_K = (1/|K|) N K Nᵀ + (I − QQᵀ) W (I − QQᵀ),
///
/// with N rows |F| n_{K,F}ᵀ (outward), D rows (x_F − x_K)ᵀ (face and cell
/// centroids), Q an orthonormal basis of span(D) and
/// W = diag(|F| κ_{K,F} / d_{K,F}) the two-point half transmissibilities.
/// The divergence theorem gives Nᵀ D = |K| I for planar faces, hence the
/// consistency condition T_K D = N K: the fluxes are exact whenever u is
/// linear in K. T_K is symmetric positive definite: the first term
/// vanishes only on ker Nᵀ, the second only on span(D), and the two meet
/// only in 0 because Nᵀ D = |K| I. So Aᵀ Ω A is symmetric positive
/// semi-definite with the constants as kernel (on a connected mesh).
///
/// Row K of Aᵀ Ω A is the flux balance of cell K; row `cells + F` is minus
/// the sum of the half-face fluxes through F, i.e. flux continuity on an
/// interior face. Dirichlet data fix λ_F on boundary faces; a Neumann flux
/// g_F enters the right-hand side of row `cells + F`.
///
/// On axis-aligned boxes with a diagonal tensor, T_K = W: eliminating the
/// face unknowns gives the two-point scheme [`two_point`](super::two_point).
///
/// Non-planar faces (e.g. the warped quadrilateral faces of a randomly
/// perturbed hexahedral grid) are described by the geometry module's unit
/// normal and fan area, for which Nᵀ D = |K| I holds only up to the face
/// warping. Exactness is then lost in proportion to warping / h: no
/// symmetric T_K can satisfy T_K D = N K unless (Nᵀ D)ᵀ K is symmetric,
/// with one point per face. Meshes from smooth mappings (warping O(h²))
/// keep first-order consistency; meshes warped by O(h) at every level do
/// not converge for linear solutions.
///
/// ```
/// use hasse_complex::generate::rectangle;
/// use hasse_solver::operator::Canonical;
/// use hasse_solver::metric::{fv, isotropic};
/// let k = rectangle(2, 2, [0.0, 1.0], [0.0, 1.0]).unwrap();
/// let (a, omega, layout) = fv::mimetic_hybrid(&k, &[isotropic(1.0); 4]).unwrap();
/// assert_eq!((layout.cells, layout.faces), (4, 12));
/// assert_eq!(a.rows(), 16); // four half-faces per square
/// let op = Canonical::new(a, omega).unwrap();
/// // Constants are in the kernel: u_K = λ_F = 1 carries no flux.
/// assert!(op.apply(&vec![1.0; layout.unknowns()]).iter().all(|v| v.abs() < 1e-12));
/// ```
pub fn mimetic_hybrid<'a>(
    complex: &Complex,
    tensors: impl Into<CellTensors<'a>>,
) -> Result<(CsMat<i8>, BlockMetric, HybridLayout), MetricError> {
    let tensors = tensors.into();
    const METHOD: &str = "mimetic finite differences";
    let n = check_volume(complex, METHOD)?;
    crate::metric::require_convex(complex, METHOD)?;
    let cells = complex.cell_count(n);
    let tensors = tensors.checked(cells, complex.embedding_dim())?;
    let faces = complex.try_boundary(n)?.rows();
    let layout = HybridLayout { cells, faces };
    let geometry = FaceGeometry::new(complex);
    let omega = cell_blocks(complex, |cell| {
        let tensor = tensors.get(cell);
        let half = half_faces(complex, &geometry, cell, &tensor, METHOD)?;
        transmissibility(&tensor, complex.measure(n)[cell], &half, cell)
    })?;
    let by_cell = complex.boundary_csc(n);
    let indptr = by_cell.indptr();
    let half_faces = by_cell.nnz();
    let mut row_ptr = Vec::with_capacity(half_faces + 1);
    let mut columns = Vec::with_capacity(2 * half_faces);
    let mut values = Vec::with_capacity(2 * half_faces);
    row_ptr.push(0);
    for cell in 0..cells {
        for &face in &by_cell.indices()[indptr.outer_inds_sz(cell)] {
            columns.extend_from_slice(&[cell, layout.face_column(face)]);
            values.extend_from_slice(&[1i8, -1]);
            row_ptr.push(columns.len());
        }
    }
    let a = CsMat::new((half_faces, layout.unknowns()), row_ptr, columns, values);
    Ok((a, omega, layout))
}

/// The flux mass matrix M_u of mixed Darcy flow. See
/// [`crate::physics::darcy`] for the formulas.
///
/// ```
/// use hasse_complex::DualKind;
/// use hasse_solver::metric::fv::FluxMass;
/// // Delaunay triangulations: circumcentric dual; uniform boxes: barycentric.
/// let dec: FluxMass = "dec".parse().unwrap();
/// assert_eq!(dec, FluxMass::Dec(DualKind::Circumcentric));
/// assert_eq!(FluxMass::Mimetic.to_string(), "mimetic");
/// ```
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FluxMass {
    /// Diagonal DEC / two-point mass with pressures at the dual vertices
    /// of the given kind.
    Dec(DualKind),
    /// Mimetic (RT0-type) mass, one dense block per cell, pressures at the
    /// centroids.
    Mimetic,
}

impl FluxMass {
    /// Every flux mass, in the order help texts list them.
    pub const ALL: [FluxMass; 3] = [
        FluxMass::Mimetic,
        FluxMass::Dec(DualKind::Circumcentric),
        FluxMass::Dec(DualKind::Barycentric),
    ];

    /// The name case files use (`problem.method` of a Darcy problem).
    pub fn name(&self) -> &'static str {
        match self {
            FluxMass::Mimetic => "mimetic",
            // The DEC masses are named as the DEC methods of their dual.
            FluxMass::Dec(kind) => crate::metric::Method::Dec(*kind).name(),
        }
    }
}

impl std::fmt::Display for FluxMass {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

impl std::str::FromStr for FluxMass {
    type Err = String;

    /// The flux mass of this name; the error lists the names.
    fn from_str(name: &str) -> Result<Self, Self::Err> {
        Self::ALL
            .into_iter()
            .find(|m| m.name() == name.trim())
            .ok_or_else(|| {
                let names: Vec<&str> = Self::ALL.iter().map(FluxMass::name).collect();
                format!(
                    "unknown flux mass \"{}\"; the flux masses are {}",
                    name.trim(),
                    names.join(", ")
                )
            })
    }
}

/// The half-face incidence S: one row per half-face (cell after cell, each
/// cell's faces in the order of its column of ∂ₙ by cells) holding its one
/// entry ∂ₙ(F, K) in the face's column, so (S u)_{K,F} is the flux u_F
/// counted outward from K.
pub fn half_face_incidence(complex: &Complex) -> CsMat<i8> {
    let n = complex.dim();
    let by_cell = complex.boundary_csc(n);
    let half_faces = by_cell.nnz();
    let row_ptr: Vec<usize> = (0..=half_faces).collect();
    let columns = by_cell.indices()[..half_faces].to_vec();
    let signs = by_cell.data()[..half_faces].to_vec();
    CsMat::new((half_faces, by_cell.rows()), row_ptr, columns, signs)
}

/// The flux mass M_u = Aᵀ Ω A of mixed Darcy flow over the (n−1)-cells,
/// as (A, Ω): for [`FluxMass::Dec`], A = I and Ω the diagonal inverse of
/// the two-point transmissibility at the dual vertices; for
/// [`FluxMass::Mimetic`], A the half-face incidence (one row per
/// half-face, holding ∂ₙ(F, K) in the face's column) and Ω one block M_c
/// per cell in outward
/// fluxes, M_c = (1/|c|) X K⁻¹ Xᵀ + (I − P_N) S (I − P_N) with
/// S = diag(d/(κ|F|)).
///
/// ```
/// use hasse_complex::{generate::rectangle, DualKind};
/// use hasse_solver::metric::{fv, isotropic};
/// use hasse_solver::operator::Canonical;
/// // Two unit squares, K = 2: the shared face has dual edge 1, so
/// // M = 1 / (2 · 1); a boundary face has half a dual edge: 1/4.
/// let k = rectangle(2, 1, [0.0, 2.0], [0.0, 1.0]).unwrap();
/// let (a, omega) = fv::flux_mass(&k, &[isotropic(2.0); 2], fv::FluxMass::Dec(DualKind::Barycentric)).unwrap();
/// let m = Canonical::new(a, omega).unwrap().assemble().to_dense();
/// let shared = k.boundary(2).outer_iterator().position(|r| r.nnz() == 2).unwrap();
/// for f in 0..k.cell_count(1) {
///     assert!((m[(f, f)] - if f == shared { 0.5 } else { 0.25 }).abs() < 1e-15);
/// }
/// // On these boxes with a diagonal K, the mimetic mass is the same.
/// let (a, omega) = fv::flux_mass(&k, &[isotropic(2.0); 2], fv::FluxMass::Mimetic).unwrap();
/// let mimetic = Canonical::new(a, omega).unwrap().assemble().to_dense();
/// assert!((0..7).all(|i| (0..7).all(|j| (mimetic[(i, j)] - m[(i, j)]).abs() < 1e-15)));
/// ```
pub fn flux_mass<'a>(
    complex: &Complex,
    tensors: impl Into<CellTensors<'a>>,
    mass: FluxMass,
) -> Result<(CsMat<i8>, BlockMetric), MetricError> {
    let tensors = tensors.into();
    const METHOD: &str = "mimetic Darcy flux mass";
    let n = check_volume(complex, METHOD)?;
    let tensors = tensors.checked(complex.cell_count(n), complex.embedding_dim())?;
    match mass {
        FluxMass::Dec(kind) => {
            let points = complex.dual_vertices(kind)?;
            let sigma = super::two_point_at(complex, tensors, points)?;
            // The two-point metric is diagonal, one 1×1 block per face in
            // order; its inverse is the series resistance Σ s/(κ|F|).
            let faces = sigma.size();
            let resistance: Vec<f64> = (0..sigma.block_count())
                .map(|b| 1.0 / sigma.block(b).2[0])
                .collect();
            Ok((CsMat::eye(faces), BlockMetric::from_weights(resistance)))
        }
        FluxMass::Mimetic => {
            let geometry = FaceGeometry::new(complex);
            let omega = cell_blocks(complex, |cell| {
                let tensor = tensors.get(cell);
                let half = half_faces(complex, &geometry, cell, &tensor, METHOD)?;
                mimetic_mass(&tensor, complex.measure(n)[cell], &half, cell)
            })?;
            Ok((half_face_incidence(complex), omega))
        }
    }
}

/// The mimetic flux mass block M_c of one cell in outward fluxes (see
/// [`flux_mass`]).
fn mimetic_mass(
    tensor: &Tensor,
    volume: f64,
    half: &HalfFaces,
    cell: usize,
) -> Result<DMatrix<f64>, MetricError> {
    let d = half.outward.ncols();
    let k = DMatrix::from_fn(d, d, |i, j| 0.5 * (tensor[i][j] + tensor[j][i]));
    // K was checked positive definite, so it has an inverse.
    let k_inv = k
        .try_inverse()
        .ok_or(MetricError::NotPositive { cell, value: 0.0 })?;
    let consistency = &half.offsets * &k_inv * half.offsets.transpose() / volume;
    // Half resistance of the two-point scheme: sets the scale of the
    // stabilisation and makes M_c = S on K-orthogonal boxes.
    let s: Vec<f64> = half
        .resistances
        .iter()
        .zip(&half.areas)
        .map(|(r, a)| r / a)
        .collect();
    stabilised(
        consistency,
        &half.outward,
        &s,
        cell,
        "mimetic Darcy flux mass",
        "a non-degenerate cell (face normals spanning the space)",
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::metric::isotropic;
    use hasse_complex::generate::{perturb, rectangle};
    use hasse_complex::{TopCells, Vertices};

    /// N, D, areas, resistances of cell `cell`, recomputed from geometry.
    fn cell_geometry(
        complex: &Complex,
        tensor: &Tensor,
        cell: usize,
    ) -> (DMatrix<f64>, DMatrix<f64>, Vec<f64>, Vec<f64>) {
        let (n, d) = (complex.dim(), complex.embedding_dim());
        let csc = complex.boundary_csc(n);
        let col = csc.outer_view(cell).unwrap();
        let m = col.nnz();
        let (mut nn, mut dd) = (DMatrix::zeros(m, d), DMatrix::zeros(m, d));
        let (mut areas, mut res) = (vec![], vec![]);
        let geometry = FaceGeometry::new(complex);
        for (i, (face, &s)) in col.iter().enumerate() {
            let h = geometry.half(face, cell);
            for a in 0..d {
                nn[(i, a)] = f64::from(s) * h.area * h.normal[a];
                dd[(i, a)] = h.x_face[a] - h.x_cell[a];
            }
            areas.push(h.area);
            res.push(h.resistance(tensor, cell, "test").unwrap());
        }
        (nn, dd, areas, res)
    }

    #[test]
    fn divergence_theorem_gives_n_transpose_d_equal_volume_identity() {
        let k = perturb(&rectangle(3, 3, [0.0, 1.0], [0.0, 1.0]).unwrap(), 0.3, 4).unwrap();
        for cell in 0..k.cell_count(2) {
            let (nn, dd, _, _) = cell_geometry(&k, &isotropic(1.0), cell);
            let g = nn.transpose() * dd / k.measure(2)[cell];
            assert!((g - DMatrix::identity(2, 2)).amax() < 1e-13, "cell {cell}");
        }
    }

    #[test]
    fn transmissibility_is_exact_for_linear_functions_on_a_pentagon() {
        let v =
            Vertices::from_points(&[[0.0, 0.0], [2.0, 0.2], [2.5, 1.5], [1.0, 2.2], [-0.3, 1.1]])
                .unwrap();
        let k = Complex::build(v, TopCells::polygons([[0, 1, 2, 3, 4]])).unwrap();
        let tensor = [[2.0, 0.6, 0.0], [0.6, 1.0, 0.0], [0.0, 0.0, 1.0]];
        let (nn, dd, areas, res) = cell_geometry(&k, &tensor, 0);
        let half = HalfFaces {
            outward: nn.clone(),
            offsets: dd.clone(),
            areas,
            resistances: res,
        };
        let t = transmissibility(&tensor, k.measure(2)[0], &half, 0).unwrap();
        let kk = DMatrix::from_fn(2, 2, |i, j| tensor[i][j]);
        assert!((&t * &dd - &nn * kk).amax() < 1e-12);
        // Symmetric positive definite.
        assert!((&t - t.transpose()).amax() == 0.0);
        assert!(t.clone().symmetric_eigen().eigenvalues.min() > 0.0);
    }

    #[test]
    fn transmissibility_of_a_rectangle_with_diagonal_tensor_is_two_point() {
        // hx = 2, hy = 0.5, K = diag(3, 5): TPFA half transmissibilities are
        // |F| κ / (h/2): x-faces 0.5·3/1 = 1.5, y-faces 2·5/0.25 = 40.
        let k = rectangle(1, 1, [0.0, 2.0], [0.0, 0.5]).unwrap();
        let tensor = [[3.0, 0.0, 0.0], [0.0, 5.0, 0.0], [0.0, 0.0, 1.0]];
        let (nn, dd, areas, res) = cell_geometry(&k, &tensor, 0);
        let half = HalfFaces {
            outward: nn.clone(),
            offsets: dd,
            areas,
            resistances: res,
        };
        let t = transmissibility(&tensor, 1.0, &half, 0).unwrap();
        for i in 0..4 {
            let expected = if nn[(i, 0)].abs() > 0.0 { 1.5 } else { 40.0 };
            for j in 0..4 {
                let e = if i == j { expected } else { 0.0 };
                assert!((t[(i, j)] - e).abs() < 1e-12, "T[{i}][{j}] = {}", t[(i, j)]);
            }
        }
    }
}
