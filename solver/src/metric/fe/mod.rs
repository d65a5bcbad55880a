//! Nodal Galerkin stiffness −∇·(K∇u) written as Ω over the edges.
//!
//! Unknowns live on vertices and A = δ⁰ = ∂₁ᵀ. Every top cell c contributes
//! a local stiffness K_c (vertices × vertices) with K_c 1 = 0. Because the
//! edge graph of a cell is connected, the local incidence A_c (cell edges ×
//! cell vertices, signs from the global ∂₁) has kernel = constants, so
//!
//! ```text
//!     Ω_c = (A_c⁺)ᵀ K_c A_c⁺   gives   A_cᵀ Ω_c A_c = K_c   exactly,
//! ```
//!
//! and Σ_c A_cᵀ Ω_c A_c is the usual assembled stiffness. Which element a
//! cell gets depends on its shape:
//!
//! | cell | element | Ω_c |
//! |---|---|---|
//! | simplex (segment, triangle, tetrahedron) | P1 | diagonal |
//! | quadrilateral (2D), hexahedron (3D) | Q1, isoparametric, Gauss 2ⁿ | dense |
//! | any other convex polygon or polyhedron | lowest-order virtual element | dense |
//!
//! P1 is diagonal for every tensor K, not only a scalar one: in a simplex
//! every pair of vertices is an edge, and a symmetric K_c with zero row sums
//! is exactly the weighted graph Laplacian with ω_ab = −(K_c)_ab. For K = λI
//! these are the cotangent weights, λ/2·cot θ_e on a triangle (θ_e the angle
//! opposite e) and λ|e′|cot φ_e′ / 6 on a tetrahedron (e′ the edge opposite
//! e, φ_e′ the dihedral angle at e′).
//!
//! Simplices may be embedded in a higher-dimensional space (a triangulated
//! surface in R³): gradients are taken in the simplex's own tangent space.
//! Q1 and the virtual element need cells that fill their space (n = d).

use super::{check_tensors, CellTensors, MetricError, Tensor};
use crate::operator::{ranges, split_at_ranges, BlockMetric};
use hasse_complex::Complex;
use nalgebra::DMatrix;
use rayon::prelude::*;
use sprs::CsMat;
use std::rc::Rc;

/// A point padded to three coordinates.
pub(crate) type Point = [f64; 3];

/// Singular values of an integer cell incidence below this are its kernel;
/// the smallest nonzero one is √(algebraic connectivity of the cell's edge
/// graph), ≥ 0.1 for any cell with fewer than a few hundred vertices.
const PSEUDO_INVERSE_TOLERANCE: f64 = 1e-8;

/// Galerkin stiffness metric of −∇·(K∇u) with one tensor per top cell
/// (P1 on simplices, Q1 on quadrilaterals and hexahedra, the lowest-order
/// virtual element on every other convex polygon or polyhedron).
///
/// P1 cells add to a diagonal Ω (one 1×1 block per edge, in edge order);
/// Q1 and VEM cells push one dense block over their edges, in cell order.
/// See the [module documentation](self) for the construction.
///
/// ```
/// use hasse_complex::generate::rectangle;
/// use hasse_solver::operator::Canonical;
/// use hasse_solver::metric::{fe, isotropic};
/// // Q1 on a uniform grid: the 9-point stencil, 8/3 on the diagonal.
/// let k = rectangle(2, 2, [0.0, 1.0], [0.0, 1.0]).unwrap();
/// let omega = fe::stiffness_metric(&k, &vec![isotropic(1.0); 4]).unwrap();
/// let m = Canonical::new(k.coboundary(0), omega).unwrap().assemble().to_dense();
/// assert!((m[(4, 4)] - 8.0 / 3.0).abs() < 1e-14);
/// assert!((m[(4, 0)] + 1.0 / 3.0).abs() < 1e-14);
/// ```
pub fn stiffness_metric<'a>(
    complex: &Complex,
    tensors: impl Into<CellTensors<'a>>,
) -> Result<BlockMetric, MetricError> {
    stiffness(complex, tensors.into(), Route::ByShape, None).map(|(metric, _)| metric)
}

/// Stiffness metric from the lowest-order virtual element method on every
/// cell of dimension ≥ 2, quadrilaterals and hexahedra included (segments
/// stay P1, which is what the virtual element is in 1D).
///
/// Following Beirão da Veiga et al., "The hitchhiker's guide to the virtual
/// element method" (k = 1), with Π̃ (n × N) the gradient average
/// Π̃ u = (1/|c|) ∫_∂c u n and Π u = ū + (x − x̄)·Π̃ u the projection onto
/// linear functions (ū, x̄ the vertex averages):
///
/// ```text
///     K_c = |c| Π̃ᵀ K Π̃  +  α (I − Π)ᵀ (I − Π),    α = tr(K)/n · h_c^(n−2)
/// ```
///
/// with h_c the cell diameter; α scales the stabilisation like the
/// consistency term (entries of order tr(K)/n · h^(n−2)). The boundary
/// integrals ∫_∂c φ_i n are exact on polygon edges (φ_i is linear there);
/// on a polyhedron each face is split into the fan of triangles about its
/// vertex average, with the 3-point vertex rule on each triangle, which is
/// exact for linear functions. |c| is the volume bounded by the same fans,
/// so the divergence theorem holds exactly for the discrete surface and
/// K_c u = ∫_c K∇u·∇φ_i for every linear u (the patch test), also on
/// hexahedra with non-planar faces. On a simplex the element is P1.
///
/// ```
/// use hasse_complex::{Complex, TopCells, Vertices};
/// use hasse_solver::metric::{fe, isotropic};
/// // A unit square with one corner cut off: a pentagon.
/// let v = Vertices::from_points(&[[0.0, 0.0], [1.0, 0.0], [1.0, 0.5], [0.5, 1.0], [0.0, 1.0]]).unwrap();
/// let k = Complex::build(v, TopCells::polygons([[0, 1, 2, 3, 4]])).unwrap();
/// let omega = fe::vem_stiffness_metric(&k, &[isotropic(1.0)]).unwrap();
/// assert_eq!(omega.block_count(), 1);
/// assert!(omega.is_symmetric(1e-14));
/// ```
pub fn vem_stiffness_metric<'a>(
    complex: &Complex,
    tensors: impl Into<CellTensors<'a>>,
) -> Result<BlockMetric, MetricError> {
    stiffness(complex, tensors.into(), Route::Vem, None).map(|(metric, _)| metric)
}

/// Galerkin load vector ∫ f φ_v for every vertex v, with the quadrature of
/// the element [`stiffness_metric`] uses on each cell:
///
/// - P1: segments 2-point Gauss (degree 3), triangles the 3-point
///   edge-midpoint rule (degree 2), tetrahedra the 4-point rule with
///   barycentric coordinates (a, b, b, b), a = (5 + 3√5)/20,
///   b = (5 − √5)/20 (degree 2): exact for linear f;
/// - Q1: tensor Gauss 2×2 (2×2×2) on the isoparametric map: exact for
///   linear f on parallelograms, parallelepipeds and any quadrilateral, and
///   Σ_v load_v = ∫_c f exactly for linear f on any hexahedron;
/// - virtual elements: |c| f(x_c) / N_c at each of the N_c vertices, x_c the
///   centroid (one-point rule: Σ_v load_v = ∫_c f for linear f, the load is
///   O(h²) accurate in L²).
///
/// An f that returns a non-finite value is reported with the cell.
///
/// ```
/// use hasse_complex::generate::rectangle;
/// use hasse_solver::metric::fe;
/// let k = rectangle(3, 2, [0.0, 3.0], [0.0, 1.0]).unwrap();
/// let b = fe::load(&k, &|x: &[f64]| 1.0 + x[0]).unwrap();
/// // ∫ (1 + x) over [0, 3] × [0, 1] = 3 + 4.5.
/// assert!((b.iter().sum::<f64>() - 7.5).abs() < 1e-13);
/// ```
pub fn load(
    complex: &Complex,
    f: &(dyn Fn(&[f64]) -> f64 + Sync),
) -> Result<Vec<f64>, MetricError> {
    let top = Topology::new(complex, "FE load")?;
    let n = top.n;
    let cells = complex.cell_count(n);
    // Each cell's shares in one array laid out like the cells' vertex
    // lists (the characteristic matrix M_n), written in parallel in place;
    // then summed per vertex in cell order, so the load does not depend
    // on the thread count.
    let characteristic = complex.lar().characteristic(n)?;
    let indptr = characteristic.indptr();
    let offsets = indptr.to_proper();
    let mut shares = vec![0.0; offsets[cells]];
    let parts = ranges(cells);
    let pieces = split_at_ranges(&mut shares, &parts, |c| offsets[c]);
    // Each part stops at its first bad cell; the parts' errors come back
    // in cell order, so the first one reported is the first bad cell.
    parts
        .par_iter()
        .zip(pieces)
        .map(|(range, piece)| {
            let base = offsets[range.start];
            for c in range.clone() {
                cell_load(
                    &top,
                    c,
                    f,
                    &mut piece[offsets[c] - base..offsets[c + 1] - base],
                )?;
            }
            Ok(())
        })
        .collect::<Vec<_>>()
        .into_iter()
        .collect::<Result<(), MetricError>>()?;
    Ok(sum_shares(complex, characteristic, &shares))
}

/// [`stiffness_metric`] and [`load`] together, equal to them bit for bit:
/// when every cell is a Q1 or virtual element, one pass over the cells
/// finds each cell's element (its tensor order and, for Q1, the
/// isoparametric map at the Gauss points) once for both. On a bad
/// cell or a non-finite f the two are computed apart, so the error is the
/// one they report.
///
/// ```
/// use hasse_complex::generate::rectangle;
/// use hasse_solver::metric::{fe, isotropic};
/// let k = rectangle(3, 2, [0.0, 3.0], [0.0, 1.0]).unwrap();
/// let tensors = vec![isotropic(1.0); 6];
/// let f = |x: &[f64]| 1.0 + x[0];
/// let (omega, b) = fe::stiffness_and_load(&k, &tensors, &f).unwrap();
/// assert_eq!(omega, fe::stiffness_metric(&k, &tensors).unwrap());
/// assert_eq!(b, fe::load(&k, &f).unwrap());
/// ```
pub fn stiffness_and_load<'a>(
    complex: &Complex,
    tensors: impl Into<CellTensors<'a>>,
    f: &(dyn Fn(&[f64]) -> f64 + Sync),
) -> Result<(BlockMetric, Vec<f64>), MetricError> {
    let tensors = tensors.into();
    match stiffness(complex, tensors, Route::ByShape, Some(f)) {
        Ok((metric, Some(shares))) => Ok((metric, shares)),
        Ok((metric, None)) => Ok((metric, load(complex, f)?)),
        // A bad cell or source value: the error the two report apart.
        Err(_) => Ok((stiffness_metric(complex, tensors)?, load(complex, f)?)),
    }
}

/// Per-vertex sums of the cells' load shares (laid out like the cells'
/// vertex lists in `characteristic`), in cell order.
fn sum_shares(complex: &Complex, characteristic: &CsMat<u8>, shares: &[f64]) -> Vec<f64> {
    let mut out = crate::operator::zeroed(complex.cell_count(0));
    for (&v, &x) in characteristic.indices().iter().zip(shares) {
        out[v] += x;
    }
    out
}

#[derive(Clone, Copy, PartialEq, Eq)]
enum Route {
    ByShape,
    Vem,
}

/// The element a cell gets.
enum Element {
    P1,
    /// Local vertex positions in tensor order.
    Q1(TensorOrder),
    Vem,
}

/// The 2ⁿ local vertex positions (n ≤ 3) of a quadrilateral or hexahedron
/// in tensor order: a fixed array, since every cell of a Q1 mesh needs one.
#[derive(Clone, Copy)]
struct TensorOrder {
    slots: [usize; 8],
    len: usize,
    /// (tail, head) of each sorted edge of the cell as positions in its
    /// sorted vertex list: the cell's local incidence, found on the way
    /// (bytes, so that the element stays small to pass around).
    ends: [[u8; 2]; 12],
}

impl std::ops::Deref for TensorOrder {
    type Target = [usize];
    fn deref(&self) -> &[usize] {
        &self.slots[..self.len]
    }
}

/// Ω by `route`, and with `load` = Some(f) also the load of f when every
/// cell has a dense block (written in the same pass; `None` otherwise).
fn stiffness(
    complex: &Complex,
    tensors: CellTensors,
    route: Route,
    load: Option<LoadFn>,
) -> Result<(BlockMetric, Option<Vec<f64>>), MetricError> {
    let top = Topology::new(complex, "FE stiffness")?;
    let n = top.n;
    let cells = complex.cell_count(n);
    check_tensors(tensors, cells, top.d)?;
    // Without P1 cells every cell pushes one dense block over its edges:
    // the blocks' sizes are known from the topology, so they are written
    // straight into Ω's storage.
    let all_dense = match route {
        Route::Vem => n > 1,
        Route::ByShape => !(0..cells).into_par_iter().any(|c| top.is_simplex(c)),
    };
    if all_dense {
        let Some(f) = load else {
            return Ok((dense_stiffness(&top, tensors, route, None)?, None));
        };
        let characteristic = complex.lar().characteristic(n)?;
        let indptr = characteristic.indptr();
        let offsets = indptr.to_proper();
        let mut shares = vec![0.0; offsets[cells]];
        let metric = dense_stiffness(&top, tensors, route, Some((f, &offsets, &mut shares)))?;
        return Ok((metric, Some(sum_shares(complex, characteristic, &shares))));
    }
    let locals = (0..cells)
        .into_par_iter()
        .map_init(CellScratch::default, |scratch, c| {
            let k = &tensors.get(c);
            match top.element_with(c, route, &mut scratch.edges, &mut scratch.q1)? {
                Element::P1 => p1_weights(&top, c, k),
                element => {
                    dense_block(&top, c, element, k, scratch)?;
                    Ok(Local::Dense {
                        edges: scratch.edges.clone(),
                        values: scratch.omega.clone(),
                    })
                }
            }
        })
        .collect::<Vec<Result<_, _>>>()
        .into_iter()
        .collect::<Result<Vec<_>, _>>()?;
    Ok((gather(complex.cell_count(1), &locals), None))
}

/// Scratch vectors reused from cell to cell by one thread.
#[derive(Default)]
struct CellScratch {
    edges: Vec<usize>,
    /// Local stiffness K_c (vertices × vertices, row-major).
    kc: Vec<f64>,
    /// (A_c⁺)ᵀ K_c (edges × vertices).
    half: Vec<f64>,
    /// Local incidence pattern, the key of the A_c⁺ cache.
    key: Vec<usize>,
    /// Ω_c (edges × edges, row-major).
    omega: Vec<f64>,
    /// The last Q1 cell's local incidence and what it fixes.
    q1: Q1Memo,
}

/// What the local incidence of a Q1 cell fixes (its tensor order and
/// A_c⁺), kept from the last cell looked up: neighbouring cells of a
/// structured grid have the same local incidence, and comparing it is
/// cheaper than finding the order again and looking A_c⁺ up by key.
#[derive(Default)]
struct Q1Memo {
    /// Vertex count and each edge's (tail, head) in the sorted vertex
    /// list, for the last cell whose order was found.
    ends: Option<(usize, [[u8; 2]; 12])>,
    order: Option<TensorOrder>,
    /// A_c⁺ with its rows in tensor order (`pinv[l][e]`), valid when
    /// `pinv_valid`, for the local incidence in `ends`.
    pinv: [[f64; 12]; 8],
    pinv_valid: bool,
    /// S_ab = (A_c⁺)ᵀ R_ab A_c⁺ of [`affine_block`] for every axis pair,
    /// E × E each, valid for the same local incidence when `affine_valid`.
    affine: Vec<f64>,
    affine_valid: bool,
    /// Scratch for the A_c⁺ cache's key.
    key: Vec<usize>,
}

impl Q1Memo {
    /// The tensor order of a cell with `m` vertices, n-dimensional, whose
    /// edges have the local `ends` (unused entries zero).
    fn order(
        &mut self,
        m: usize,
        n: usize,
        ends: &[[u8; 2]; 12],
        edges: usize,
    ) -> Option<TensorOrder> {
        if self.ends == Some((m, *ends)) {
            return self.order;
        }
        self.order = tensor_order_of(m, n, ends, edges);
        self.ends = Some((m, *ends));
        self.pinv_valid = false;
        self.affine_valid = false;
        self.order
    }

    /// Make A_c⁺ (and with `affine` the S_ab) those of a Q1 cell with N
    /// corners, E edges and tensor order `order`, unless they already are.
    fn refresh<const N: usize, const E: usize>(
        &mut self,
        order: &TensorOrder,
        c: usize,
        affine: bool,
    ) -> Result<(), MetricError> {
        if !(self.pinv_valid && self.ends == Some((N, order.ends))) {
            let key = &mut self.key;
            key.clear();
            key.push(N);
            for &[t, h] in &order.ends[..E] {
                key.extend([usize::from(t), usize::from(h)]);
            }
            let pinv = pseudo_inverse_of_key(key, c, "Q1")?;
            for (row, &o) in self.pinv.iter_mut().zip(order.iter()) {
                for (e, entry) in row.iter_mut().take(E).enumerate() {
                    *entry = pinv[(o, e)];
                }
            }
            self.ends = Some((N, order.ends));
            self.order = Some(*order);
            self.pinv_valid = true;
            self.affine_valid = false;
        }
        if affine && !self.affine_valid {
            let n = N.trailing_zeros() as usize;
            let reference = q1_reference(n);
            let p = self.tensor_pinv::<N, E>();
            self.affine.clear();
            self.affine.resize(axis_pairs(n).len() * E * E, 0.0);
            for (&(a, b), sum) in axis_pairs(n)
                .iter()
                .zip(self.affine.chunks_exact_mut(E * E))
            {
                let mut r = [[0.0; N]; N];
                for (l, row) in r.iter_mut().enumerate() {
                    for (j, entry) in row.iter_mut().enumerate() {
                        *entry = reference.products[a][b][l][j];
                        if a != b {
                            *entry += reference.products[b][a][l][j];
                        }
                    }
                }
                congruence::<N, E>(&r, &p, sum);
            }
            self.affine_valid = true;
        }
        Ok(())
    }

    /// A_c⁺ in tensor order (N × E), as [`Q1Memo::refresh`] left it.
    fn tensor_pinv<const N: usize, const E: usize>(&self) -> [[f64; E]; N] {
        let mut p = [[0.0; E]; N];
        for (row, memo_row) in p.iter_mut().zip(&self.pinv) {
            row.copy_from_slice(&memo_row[..E]);
        }
        p
    }
}

/// Ω_c of a Q1 or virtual-element cell `c` into `scratch.omega`, over its
/// sorted edges, left in `scratch.edges`.
fn dense_block(
    top: &Topology,
    c: usize,
    element: Element,
    k: &Tensor,
    scratch: &mut CellScratch,
) -> Result<(), MetricError> {
    let method = match element {
        // Q1 cells exist in 2D and 3D only (`Topology::tensor_order`).
        Element::Q1(order) => {
            // The sorted edges are already in `scratch.edges`: the tensor
            // order was found from them (`Topology::element_with`).
            debug_assert_eq!(scratch.edges, top.edges_of(c));
            let edges = scratch.edges.len();
            scratch.omega.clear();
            scratch.omega.resize(edges * edges, 0.0);
            return q1_cell(top, c, &order, k, &mut scratch.q1, &mut scratch.omega, None);
        }
        _ => {
            let kc = vem_stiffness(top, c, k)?;
            let m = kc.nrows();
            scratch.kc.clear();
            scratch
                .kc
                .extend((0..m * m).map(|idx| kc[(idx / m, idx % m)]));
            "VEM"
        }
    };
    top.edges_into(c, &mut scratch.edges);
    edge_block(top, c, scratch, method)
}

/// Ω with one dense block per top cell, in cell order, every cell a Q1 or
/// virtual element: the block sizes (edges per cell) are counted first, and
/// each thread then writes its cells' edge lists and blocks in place.
///
/// With `load` = (f, offsets, shares), each cell's load shares ∫_c f φ_v
/// are also written to `shares[offsets[c]..offsets[c + 1]]` (the layout of
/// the cells' vertex lists), from the element found for the stiffness.
fn dense_stiffness(
    top: &Topology,
    tensors: CellTensors,
    route: Route,
    load: Option<(LoadFn, &[usize], &mut [f64])>,
) -> Result<BlockMetric, MetricError> {
    let cells = top.complex.cell_count(top.n);
    // A 2D cell's sorted edges are its column of ∂₂ by cells: Ω's blocks
    // take their rows from that matrix, shared, and no edge list is
    // written. In 3D the faces' edges are merged per cell.
    let by_cell = (top.n == 2).then(|| top.complex.shared_boundary_csc(2));
    let edge_ptr: std::borrow::Cow<[usize]> = match &by_cell {
        Some(by_cell) => by_cell.proper_indptr(),
        None => {
            let sizes: Vec<usize> = (0..cells)
                .into_par_iter()
                .map_init(Vec::new, |scratch, c| top.edge_count(c, scratch))
                .collect();
            let mut edge_ptr = Vec::with_capacity(cells + 1);
            edge_ptr.push(0);
            for &m in &sizes {
                edge_ptr.push(edge_ptr[edge_ptr.len() - 1] + m);
            }
            edge_ptr.into()
        }
    };
    let mut value_ptr = Vec::with_capacity(cells + 1);
    value_ptr.push(0);
    for w in edge_ptr.windows(2) {
        let m = w[1] - w[0];
        value_ptr.push(value_ptr[value_ptr.len() - 1] + m * m);
    }
    let listed = by_cell.is_none();
    let mut indices = vec![0usize; if listed { edge_ptr[cells] } else { 0 }];
    let mut values = vec![0.0; value_ptr[cells]];
    let parts = ranges(cells);
    let index_parts = split_at_ranges(
        &mut indices,
        &parts,
        |c| {
            if listed {
                edge_ptr[c]
            } else {
                0
            }
        },
    );
    let value_parts = split_at_ranges(&mut values, &parts, |c| value_ptr[c]);
    let (f, share_parts) = match load {
        Some((f, offsets, shares)) => (
            Some((f, offsets)),
            split_at_ranges(shares, &parts, |c| offsets[c])
                .into_iter()
                .map(Some)
                .collect(),
        ),
        None => (None, parts.iter().map(|_| None).collect::<Vec<_>>()),
    };
    // Each part stops at its first bad cell; the parts' errors come back
    // in cell order, so the first one reported is the first bad cell.
    parts
        .par_iter()
        .zip(index_parts)
        .zip(value_parts)
        .zip(share_parts)
        .map(|(((range, index_out), value_out), mut share_out)| {
            let mut scratch = CellScratch::default();
            let (edge_base, value_base) = (edge_ptr[range.start], value_ptr[range.start]);
            for c in range.clone() {
                let element = top.element_with(c, route, &mut scratch.edges, &mut scratch.q1)?;
                let share = match (f, share_out.as_deref_mut()) {
                    (Some((f, offsets)), Some(out)) => {
                        let base = offsets[range.start];
                        Some((f, &mut out[offsets[c] - base..offsets[c + 1] - base]))
                    }
                    _ => None,
                };
                let omega =
                    &mut value_out[value_ptr[c] - value_base..value_ptr[c + 1] - value_base];
                let k = tensors.get(c);
                // Q1 blocks are written in place, with the load from the
                // same map.
                match element {
                    Element::Q1(order) => {
                        q1_cell(top, c, &order, &k, &mut scratch.q1, omega, share)?
                    }
                    element => {
                        if let Some((f, out)) = share {
                            element_load(top, c, &element, f, out)?;
                        }
                        dense_block(top, c, element, &k, &mut scratch)?;
                        omega.copy_from_slice(&scratch.omega);
                    }
                }
                if listed {
                    index_out[edge_ptr[c] - edge_base..edge_ptr[c + 1] - edge_base]
                        .copy_from_slice(&scratch.edges);
                } else {
                    debug_assert_eq!(scratch.edges, top.facets_of(2, c).0);
                }
            }
            Ok(())
        })
        .collect::<Vec<_>>()
        .into_iter()
        .collect::<Result<(), MetricError>>()?;
    let edges = top.complex.cell_count(1);
    Ok(match by_cell {
        Some(by_cell) => {
            BlockMetric::from_symmetric_column_blocks(edges, by_cell, value_ptr, values, true)
        }
        None => BlockMetric::from_symmetric_blocks(
            edges,
            edge_ptr.into_owned(),
            value_ptr,
            indices,
            values,
            true,
        ),
    })
}

/// One cell's share of Ω.
pub(crate) enum Local {
    /// (edge, weight) pairs added to the diagonal.
    Diagonal(Vec<(usize, f64)>),
    /// A dense symmetric block over `edges` (row-major).
    Dense { edges: Vec<usize>, values: Vec<f64> },
}

/// Diagonal weights summed per edge first (one 1×1 block per edge that any
/// cell touched, in edge order), then the dense blocks in cell order: the
/// result does not depend on the thread count.
pub(crate) fn gather(edges: usize, locals: &[Local]) -> BlockMetric {
    let mut diagonal = vec![0.0; edges];
    let mut touched = vec![false; edges];
    for local in locals {
        if let Local::Diagonal(weights) = local {
            for &(e, w) in weights {
                diagonal[e] += w;
                touched[e] = true;
            }
        }
    }
    let mut metric = BlockMetric::new(edges);
    for (e, (&w, &t)) in diagonal.iter().zip(&touched).enumerate() {
        if t {
            metric.push_symmetric(&[e], &[w]);
        }
    }
    for local in locals {
        if let Local::Dense { edges, values } = local {
            metric.push_symmetric(edges, values);
        }
    }
    metric
}

/// Incidence access shared by the nodal metrics.
pub(crate) struct Topology<'a> {
    pub(crate) complex: &'a Complex,
    /// Topological dimension.
    pub(crate) n: usize,
    /// Embedding dimension.
    pub(crate) d: usize,
    /// δ⁰ (rows: edges), to read each edge's tail (−1) and head (+1).
    delta0: std::sync::Arc<CsMat<i8>>,
    /// ∂_p in CSC storage for p = 2..=n, at index p − 2.
    facets: Vec<&'a CsMat<i8>>,
}

impl<'a> Topology<'a> {
    pub(crate) fn new(complex: &'a Complex, method: &'static str) -> Result<Self, MetricError> {
        let n = complex.dim();
        if n == 0 {
            return Err(MetricError::UnsupportedMesh {
                method,
                needs: "a complex with edges",
                detail: "this complex has vertices only".into(),
            });
        }
        Ok(Self {
            complex,
            n,
            d: complex.embedding_dim(),
            delta0: complex.shared_coboundary(0),
            facets: (2..=n).map(|p| complex.boundary_csc(p)).collect(),
        })
    }

    /// Facets of p-cell `j` (2 ≤ p ≤ n) with their signs.
    pub(crate) fn facets_of(&self, p: usize, j: usize) -> (&[usize], &[i8]) {
        let m = &self.facets[p - 2];
        let range = m.indptr().outer_inds_sz(j);
        (&m.indices()[range.clone()], &m.data()[range])
    }

    /// (tail, head) of edge `e`: the vertices where ∂₁ is −1 and +1.
    pub(crate) fn ends(&self, e: usize) -> (usize, usize) {
        let range = self.delta0.indptr().outer_inds_sz(e);
        let vertices = &self.delta0.indices()[range.clone()];
        let signs = &self.delta0.data()[range];
        // Every edge of a nodal metric has one tail and one head: read
        // them from δ⁰ alone (this runs several times per cell).
        if let ([a, b], [sa, sb]) = (vertices, signs) {
            if *sa < 0 && *sb > 0 {
                return (*a, *b);
            }
            if *sa > 0 && *sb < 0 {
                return (*b, *a);
            }
        }
        let ends = self.complex.cell_vertices(1, e);
        let (mut tail, mut head) = (ends[0], ends[ends.len() - 1]);
        for (&v, &s) in vertices.iter().zip(signs) {
            if s < 0 {
                tail = v;
            } else {
                head = v;
            }
        }
        (tail, head)
    }

    /// Positions of edge `e`'s tail and head in the sorted list `vertices`.
    pub(crate) fn local_ends(
        &self,
        e: usize,
        vertices: &[usize],
        cell: usize,
    ) -> Result<(usize, usize), MetricError> {
        let (t, h) = self.ends(e);
        // A cell has a handful of vertices: a scan beats a binary search.
        let find = |v: usize| vertices.iter().position(|&x| x == v);
        match (find(t), find(h)) {
            (Some(a), Some(b)) => Ok((a, b)),
            _ => Err(MetricError::UnsupportedMesh {
                method: "nodal metric",
                needs: "cells whose edges join their own vertices",
                detail: format!("edge {e} of top cell {cell} has a vertex outside the cell"),
            }),
        }
    }

    /// Sorted edges of top cell `c`.
    pub(crate) fn edges_of(&self, c: usize) -> Vec<usize> {
        let mut edges = Vec::new();
        self.edges_into(c, &mut edges);
        edges
    }

    /// Sorted edges of top cell `c`, written over `edges` (a scratch
    /// vector reused across cells, so that a mesh of many cells does not
    /// allocate one list per cell).
    pub(crate) fn edges_into(&self, c: usize, edges: &mut Vec<usize>) {
        edges.clear();
        match self.n {
            1 => edges.push(c),
            2 => edges.extend_from_slice(self.facets_of(2, c).0),
            _ => {
                for &f in self.facets_of(3, c).0 {
                    edges.extend_from_slice(self.facets_of(2, f).0);
                }
                edges.sort_unstable();
                edges.dedup();
            }
        }
    }

    /// The number of edges [`Topology::edges_into`] gives top cell `c`:
    /// in 2D the length of its column of ∂₂, without forming the list
    /// (`scratch` is used in 3D, where the faces' edges are merged).
    pub(crate) fn edge_count(&self, c: usize, scratch: &mut Vec<usize>) -> usize {
        match self.n {
            1 => 1,
            2 => self.facets_of(2, c).0.len(),
            _ => {
                self.edges_into(c, scratch);
                scratch.len()
            }
        }
    }

    pub(crate) fn is_simplex(&self, c: usize) -> bool {
        self.complex.cell_vertices(self.n, c).len() == self.n + 1
    }

    pub(crate) fn point(&self, v: usize) -> Point {
        // Fixed lengths: a copy of unknown length is a call to memcpy,
        // and this runs for every corner of every cell.
        match *self.complex.vertices().point(v) {
            [x] => [x, 0.0, 0.0],
            [x, y] => [x, y, 0.0],
            [x, y, z, ..] => [x, y, z],
            [] => [0.0; 3],
        }
    }

    fn points(&self, c: usize) -> Vec<Point> {
        self.complex
            .cell_vertices(self.n, c)
            .iter()
            .map(|&v| self.point(v))
            .collect()
    }

    fn element(&self, c: usize, route: Route) -> Result<Element, MetricError> {
        self.element_with(c, route, &mut Vec::new(), &mut Q1Memo::default())
    }

    /// [`Topology::element`] with a scratch vector for the cell's edges
    /// and the last Q1 cell's local incidence.
    fn element_with(
        &self,
        c: usize,
        route: Route,
        edges: &mut Vec<usize>,
        memo: &mut Q1Memo,
    ) -> Result<Element, MetricError> {
        if self.is_simplex(c) && (route == Route::ByShape || self.n == 1) {
            return Ok(Element::P1);
        }
        if self.n != self.d {
            return Err(MetricError::UnsupportedMesh {
                method: "FE (Q1, VEM)",
                needs: "non-simplicial cells that fill their space (n = d)",
                detail: format!(
                    "top cell {c} is not a simplex and the complex is {}-dimensional in R^{}",
                    self.n, self.d
                ),
            });
        }
        if route == Route::Vem {
            return Ok(Element::Vem);
        }
        Ok(match self.tensor_order(c, edges, memo) {
            Some(order) => Element::Q1(order),
            None => Element::Vem,
        })
    }

    /// Local vertex positions of a quadrilateral or hexahedron in tensor
    /// order (bit a of the index = side along local axis a), recovered from
    /// its edge graph; `None` when the graph is not a square or a cube.
    fn tensor_order(
        &self,
        c: usize,
        edges: &mut Vec<usize>,
        memo: &mut Q1Memo,
    ) -> Option<TensorOrder> {
        let vertices = self.complex.cell_vertices(self.n, c);
        let m = vertices.len();
        if m != 1 << self.n || self.n < 2 || self.n > 3 {
            return None;
        }
        self.edges_into(c, edges);
        if edges.len() != self.n * m / 2 {
            return None;
        }
        let mut ends = [[0u8; 2]; 12];
        for (k, &e) in edges.iter().enumerate() {
            let (a, b) = self.local_ends(e, vertices, c).ok()?;
            // a, b < m ≤ 8.
            ends[k] = [a as u8, b as u8];
        }
        memo.order(m, self.n, &ends, edges.len())
    }
}

/// The tensor order of a cell with `m` = 2ⁿ vertices from its local
/// incidence: `ends[k]` = (tail, head) of its k-th edge (k < `edges`) as
/// positions in its sorted vertex list. `None` when the edge graph is not
/// a square or a cube.
fn tensor_order_of(m: usize, n: usize, ends: &[[u8; 2]; 12], edges: usize) -> Option<TensorOrder> {
    // At most 8 corners with 3 neighbours each: fixed arrays, since this
    // runs for every cell of a Q1 mesh whose local incidence changes.
    let mut adjacent = [[0usize; 3]; 8];
    let mut degree = [0usize; 8];
    for &[a, b] in &ends[..edges] {
        let (a, b) = (usize::from(a), usize::from(b));
        for (x, y) in [(a, b), (b, a)] {
            if degree[x] == n {
                return None;
            }
            adjacent[x][degree[x]] = y;
            degree[x] += 1;
        }
    }
    if degree[..m].iter().any(|&g| g != n) {
        return None;
    }
    let neighbours = |x: usize| &adjacent[x][..n];
    let mut order = [usize::MAX; 8];
    order[0] = 0;
    for (axis, &b) in neighbours(0).iter().enumerate() {
        order[1 << axis] = b;
    }
    // Increasing index visits every corner after the corners one step
    // closer to corner 0. A corner with two set bits a, b is the common
    // neighbour of corners l^a and l^b other than l^a^b.
    for l in 0..m {
        if l.count_ones() < 2 {
            continue;
        }
        let a = l.trailing_zeros();
        let b = (l & !(1 << a)).trailing_zeros();
        let (p, q, back) = (
            order[l ^ (1 << a)],
            order[l ^ (1 << b)],
            order[l ^ (1 << a) ^ (1 << b)],
        );
        order[l] = *neighbours(p)
            .iter()
            .find(|&&x| x != back && neighbours(q).contains(&x))?;
    }
    let order = &order[..m];
    let mut seen = [false; 8];
    for &o in order {
        if std::mem::replace(&mut seen[o], true) {
            return None;
        }
    }
    let mut slot = [0usize; 8];
    for (l, &o) in order.iter().enumerate() {
        slot[o] = l;
    }
    for &[a, b] in &ends[..edges] {
        if (slot[usize::from(a)] ^ slot[usize::from(b)]).count_ones() != 1 {
            return None;
        }
    }
    let mut slots = [0; 8];
    slots[..m].copy_from_slice(order);
    Some(TensorOrder {
        slots,
        len: m,
        ends: *ends,
    })
}

/// Measure of a simplex and the gradients of its barycentric coordinates,
/// tangent to the simplex (so embedded simplices work); `None` when the
/// simplex is degenerate.
pub(crate) fn simplex_gradients(x: &[Point], d: usize) -> Option<(f64, Vec<Point>)> {
    let n = x.len().checked_sub(1)?;
    if n == 0 {
        return None;
    }
    let factorial: f64 = (1..=n).map(|k| k as f64).product();
    let edges = DMatrix::from_fn(d, n, |i, j| x[j + 1][i] - x[0][i]);
    // Rows: ∇λ_1 … ∇λ_n, the pseudo-inverse of the edge matrix. A
    // full-dimensional simplex inverts it directly; an embedded one goes
    // through E = QR (E⁺ = R⁻¹Qᵀ), whose conditioning is that of E and not
    // of the Gram matrix EᵀE.
    let (measure, rows) = if n == d {
        let det = edges.determinant();
        (det.abs() / factorial, edges.try_inverse()?)
    } else {
        let qr = edges.qr();
        let r = qr.r();
        let det = r.determinant();
        (det.abs() / factorial, r.try_inverse()? * qr.q().transpose())
    };
    if measure.is_nan() || measure <= 0.0 {
        return None;
    }
    let mut gradients = vec![[0.0; 3]; n + 1];
    for k in 0..n {
        for i in 0..d {
            gradients[k + 1][i] = rows[(k, i)];
            gradients[0][i] -= rows[(k, i)];
        }
    }
    Some((measure, gradients))
}

/// gᵀ K h over the leading d coordinates.
pub(crate) fn k_dot(g: &Point, k: &Tensor, h: &Point, d: usize) -> f64 {
    (0..d)
        .map(|i| g[i] * (0..d).map(|j| k[i][j] * h[j]).sum::<f64>())
        .sum()
}

fn p1_weights(top: &Topology, c: usize, k: &Tensor) -> Result<Local, MetricError> {
    let vertices = top.complex.cell_vertices(top.n, c);
    let (measure, gradients) =
        simplex_gradients(&top.points(c), top.d).ok_or(MetricError::UnsupportedCell {
            method: "P1",
            needs: "a simplex of positive measure",
            cell: c,
        })?;
    top.edges_of(c)
        .into_iter()
        .map(|e| {
            let (a, b) = top.local_ends(e, vertices, c)?;
            Ok((e, -measure * k_dot(&gradients[a], k, &gradients[b], top.d)))
        })
        .collect::<Result<Vec<_>, _>>()
        .map(Local::Diagonal)
}

/// The pseudo-inverse A_c⁺ (cell vertices × cell edges, vertices in the
/// cell's sorted order) of the local edge incidence of cell `c` over its
/// sorted `edges`, signs from the global ∂₁; `key` is scratch.
pub(crate) fn edge_pseudo_inverse(
    top: &Topology,
    c: usize,
    edges: &[usize],
    key: &mut Vec<usize>,
    method: &'static str,
) -> Result<Rc<DMatrix<f64>>, MetricError> {
    let vertices = top.complex.cell_vertices(top.n, c);
    // A_c is pure topology: the vertex count and each edge's local (tail,
    // head). Cells with the same local incidence (every cell of a
    // structured grid, up to a few orientation patterns) share A_c⁺, so it
    // is computed once per pattern and thread.
    key.clear();
    key.push(vertices.len());
    for &e in edges {
        let (t, h) = top.local_ends(e, vertices, c)?;
        key.extend([t, h]);
    }
    pseudo_inverse_of_key(key, c, method)
}

/// A_c⁺ of the local incidence `key` (vertex count, then each edge's
/// local tail and head), from the per-thread cache or computed.
fn pseudo_inverse_of_key(
    key: &[usize],
    c: usize,
    method: &'static str,
) -> Result<Rc<DMatrix<f64>>, MetricError> {
    let cached = PSEUDO_INVERSES.with(|cache| cache.borrow_mut().get(key));
    if let Some(pinv) = cached {
        return Ok(pinv);
    }
    let mut a = DMatrix::zeros((key.len() - 1) / 2, key[0]);
    for (r, ends) in key[1..].chunks_exact(2).enumerate() {
        a[(r, ends[0])] = -1.0;
        a[(r, ends[1])] = 1.0;
    }
    let pinv = Rc::new(a.pseudo_inverse(PSEUDO_INVERSE_TOLERANCE).map_err(|_| {
        MetricError::UnsupportedCell {
            method,
            needs: "a cell whose edge incidence has a pseudo-inverse",
            cell: c,
        }
    })?);
    PSEUDO_INVERSES.with(|cache| cache.borrow_mut().insert(key, &pinv));
    Ok(pinv)
}

/// Most local incidence patterns kept per thread.
const PSEUDO_INVERSE_CACHE_SIZE: usize = 1024;

/// A_c⁺ by local incidence pattern (vertex count, then the local tail and
/// head of each edge in the cell's edge order), with the last pattern
/// looked up kept apart: neighbouring cells of a structured grid mostly
/// share it, and comparing one key is cheaper than hashing it.
#[derive(Default)]
struct PseudoInverseCache {
    map: std::collections::HashMap<Vec<usize>, Rc<DMatrix<f64>>>,
    last_key: Vec<usize>,
    last: Option<Rc<DMatrix<f64>>>,
}

impl PseudoInverseCache {
    fn get(&mut self, key: &[usize]) -> Option<Rc<DMatrix<f64>>> {
        if let Some(last) = &self.last {
            if self.last_key == key {
                return Some(Rc::clone(last));
            }
        }
        let found = Rc::clone(self.map.get(key)?);
        self.remember(key, &found);
        Some(found)
    }

    fn insert(&mut self, key: &[usize], pinv: &Rc<DMatrix<f64>>) {
        // Unstructured polytopal meshes have few repeats: bound the memory.
        if self.map.len() >= PSEUDO_INVERSE_CACHE_SIZE {
            self.map.clear();
        }
        self.map.insert(key.to_vec(), Rc::clone(pinv));
        self.remember(key, pinv);
    }

    fn remember(&mut self, key: &[usize], pinv: &Rc<DMatrix<f64>>) {
        self.last_key.clear();
        self.last_key.extend_from_slice(key);
        self.last = Some(Rc::clone(pinv));
    }
}

thread_local! {
    /// Shared (`Rc`): a cell borrows its pattern's A_c⁺ without a copy.
    static PSEUDO_INVERSES: std::cell::RefCell<PseudoInverseCache> =
        std::cell::RefCell::new(PseudoInverseCache::default());
}

/// Ω_c = (A_c⁺)ᵀ K_c A_c⁺ over the edges `scratch.edges` of cell `c`, from
/// K_c in `scratch.kc` (indexed by the cell's sorted vertex list), written
/// into `scratch.omega` (edges × edges, row-major) and made exactly
/// symmetric.
fn edge_block(
    top: &Topology,
    c: usize,
    scratch: &mut CellScratch,
    method: &'static str,
) -> Result<(), MetricError> {
    let pinv = edge_pseudo_inverse(top, c, &scratch.edges, &mut scratch.key, method)?;
    let (v, m) = (pinv.nrows(), pinv.ncols());
    let kc = &scratch.kc;
    let out = &mut scratch.omega;
    out.clear();
    out.resize(m * m, 0.0);
    // (A_c⁺)ᵀ K_c first, then times A_c⁺.
    let half = &mut scratch.half;
    half.clear();
    half.resize(m * v, 0.0);
    for i in 0..m {
        for b in 0..v {
            half[i * v + b] = (0..v).map(|a| pinv[(a, i)] * kc[a * v + b]).sum();
        }
    }
    for i in 0..m {
        for j in 0..m {
            out[i * m + j] = (0..v).map(|b| half[i * v + b] * pinv[(b, j)]).sum();
        }
    }
    for i in 0..m {
        for j in 0..i {
            let mean = 0.5 * (out[i * m + j] + out[j * m + i]);
            out[i * m + j] = mean;
            out[j * m + i] = mean;
        }
    }
    if out.iter().any(|v| !v.is_finite()) {
        return Err(MetricError::UnsupportedCell {
            method,
            needs: "a non-degenerate cell (finite local stiffness)",
            cell: c,
        });
    }
    Ok(())
}

/// [`q1_block`] of a quadrilateral (n = 2) or hexahedron (n = 3).
fn q1_cell(
    top: &Topology,
    c: usize,
    order: &TensorOrder,
    k: &Tensor,
    memo: &mut Q1Memo,
    out: &mut [f64],
    load: Option<(LoadFn, &mut [f64])>,
) -> Result<(), MetricError> {
    match top.n {
        2 => q1_block::<4, 4>(top, c, order, k, memo, out, load),
        _ => q1_block::<8, 12>(top, c, order, k, memo, out, load),
    }
}

/// Ω_c of a Q1 cell with N = 2ⁿ corners and E edges (n = 2: 4, 4; n = 3:
/// 8, 12) into `out` (E × E), over its sorted edges (left in the scratch
/// by the element lookup that found the tensor order), in fixed arrays,
/// with A_c's pattern taken from the tensor order (no second walk of the
/// edges): for a parallelogram or parallelepiped from its one Jacobian
/// ([`affine_block`]), for any other cell K_c from the 2ⁿ Gauss points
/// and then (A_c⁺)ᵀ K_c A_c⁺ as in [`edge_block`] ([`gauss_block`]).
/// Either way Ω_c is exactly symmetric. With `load` = (f, shares), the
/// cell's load shares are written too, from the same map (as
/// [`q1_load`]).
fn q1_block<const N: usize, const E: usize>(
    top: &Topology,
    c: usize,
    order: &TensorOrder,
    k: &Tensor,
    memo: &mut Q1Memo,
    out: &mut [f64],
    load: Option<(LoadFn, &mut [f64])>,
) -> Result<(), MetricError> {
    let n = N.trailing_zeros() as usize;
    debug_assert_eq!((order.len(), n << (n - 1), out.len()), (N, E, E * E));
    let x = tensor_points(top, c, order);
    let geometry = q1_geometry::<N>(&x, c)?;
    if let Some((f, shares)) = load {
        q1_shares(top, c, order, &x, &geometry.weights(), f, shares)?;
    }
    match &geometry {
        Q1Geometry::Affine { det, inverse } => {
            memo.refresh::<N, E>(order, c, true)?;
            affine_block::<N, E>(inverse, det.abs(), k, memo, out);
        }
        Q1Geometry::General(map) => {
            memo.refresh::<N, E>(order, c, false)?;
            gauss_block::<N, E>(map, k, memo, out);
        }
    }
    if out.iter().any(|v| !v.is_finite()) {
        return Err(MetricError::UnsupportedCell {
            method: "Q1",
            needs: "a non-degenerate cell (finite local stiffness)",
            cell: c,
        });
    }
    Ok(())
}

/// The error of a Q1 cell whose isoparametric map folds or collapses.
fn q1_inverted(cell: usize) -> MetricError {
    MetricError::UnsupportedCell {
        method: "Q1",
        needs: "a quadrilateral or hexahedron whose isoparametric map keeps one orientation (convex, not inverted)",
        cell,
    }
}

/// The map of a Q1 cell at its Gauss points: one constant Jacobian for a
/// parallelogram or parallelepiped ([`affine_jacobian`]), else the full
/// isoparametric map.
enum Q1Geometry<const N: usize> {
    Affine { det: f64, inverse: [[f64; 3]; 3] },
    General(Q1Map<N>),
}

impl<const N: usize> Q1Geometry<N> {
    /// |det J| at each Gauss point.
    fn weights(&self) -> [f64; N] {
        match self {
            Self::Affine { det, .. } => [det.abs(); N],
            Self::General(map) => map.weights,
        }
    }
}

/// [`Q1Geometry`] of the cell with corners `x` (tensor order).
fn q1_geometry<const N: usize>(x: &[Point; N], cell: usize) -> Result<Q1Geometry<N>, MetricError> {
    match affine_jacobian::<N>(x) {
        Some(jacobian) => {
            let (det, inverse) = determinant_and_inverse(&jacobian, N.trailing_zeros() as usize);
            if det == 0.0 || !det.is_finite() {
                return Err(q1_inverted(cell));
            }
            Ok(Q1Geometry::Affine { det, inverse })
        }
        None => Ok(Q1Geometry::General(q1_map::<N>(x, cell)?)),
    }
}

/// The constant Jacobian of the map from [−1, 1]ⁿ onto a Q1 cell with
/// corners `x` (tensor order) when the cell is a parallelogram or
/// parallelepiped: every corner is corner 0 plus the edges along its set
/// axes, to within 16 ulp of the largest coordinate. Coordinates
/// carry that rounding already, so the Jacobian's differences do too and
/// the Gauss rule could not resolve a bilinear part that small. `None`
/// for any other cell. J is taken at the centre, from all corners, as the
/// Gauss rule's mean Jacobian.
fn affine_jacobian<const N: usize>(x: &[Point; N]) -> Option<[[f64; 3]; 3]> {
    let n = N.trailing_zeros() as usize;
    let mut size = 0.0f64;
    for p in x {
        for &xi in &p[..n] {
            size = size.max(xi.abs());
        }
    }
    let tolerance = 16.0 * f64::EPSILON * size;
    for (l, p) in x.iter().enumerate().skip(3) {
        if l.count_ones() < 2 {
            continue;
        }
        for i in 0..n {
            let along: f64 = (0..n)
                .filter(|&a| (l >> a) & 1 == 1)
                .map(|a| x[1 << a][i] - x[0][i])
                .sum();
            if (p[i] - x[0][i] - along).abs() > tolerance {
                return None;
            }
        }
    }
    let mut jacobian = [[0.0; 3]; 3];
    let scale = 1.0 / N as f64;
    for (l, p) in x.iter().enumerate() {
        for a in 0..n {
            let s = scale * corner_sign(l, a);
            for (row, &pi) in jacobian.iter_mut().zip(&p[..n]) {
                row[a] += s * pi;
            }
        }
    }
    Some(jacobian)
}

/// Ω_c of an affine Q1 cell: with the constant J the Gauss rule gives
/// K_c = Σ_ab C_ab R_ab, C = |det J| J⁻¹ k J⁻ᵀ and R_ab the reference
/// products of the a- and b-derivatives of the shape functions (weight 1
/// per Gauss point), so Ω_c = Σ_{a≤b} C_ab S_ab with S_ab = (A_c⁺)ᵀ R_ab
/// A_c⁺ (R_ab + R_ba off the diagonal), kept in the memo for the cell's
/// local incidence. Every S_ab is exactly symmetric, so Ω_c is.
fn affine_block<const N: usize, const E: usize>(
    inverse: &[[f64; 3]; 3],
    weight: f64,
    k: &Tensor,
    memo: &Q1Memo,
    out: &mut [f64],
) {
    let n = N.trailing_zeros() as usize;
    // J⁻¹ k, then C's entries on and above the diagonal, in pair order.
    let mut inverse_k = [[0.0; 3]; 3];
    for (row, inv) in inverse_k.iter_mut().zip(inverse) {
        for (j, entry) in row.iter_mut().enumerate().take(n) {
            *entry = (0..n).map(|i| inv[i] * k[i][j]).sum();
        }
    }
    let mut coefficients = [0.0; 6];
    for (coefficient, &(a, b)) in coefficients.iter_mut().zip(axis_pairs(n)) {
        *coefficient = weight * (0..n).map(|j| inverse_k[a][j] * inverse[b][j]).sum::<f64>();
    }
    out.fill(0.0);
    for (coefficient, sum) in coefficients.iter().zip(memo.affine.chunks_exact(E * E)) {
        for (o, s) in out.iter_mut().zip(sum) {
            *o += coefficient * s;
        }
    }
}

/// The axis pairs (a, b), a ≤ b, of n dimensions, in the order of the
/// memo's S_ab.
fn axis_pairs(n: usize) -> &'static [(usize, usize)] {
    match n {
        2 => &[(0, 0), (0, 1), (1, 1)],
        _ => &[(0, 0), (0, 1), (0, 2), (1, 1), (1, 2), (2, 2)],
    }
}

/// Ω_c of any Q1 cell from its isoparametric map: K_c from the 2ⁿ Gauss
/// points, then (A_c⁺)ᵀ K_c A_c⁺, both formed on and above the diagonal
/// and mirrored.
fn gauss_block<const N: usize, const E: usize>(
    map: &Q1Map<N>,
    k: &Tensor,
    memo: &Q1Memo,
    out: &mut [f64],
) {
    let n = N.trailing_zeros() as usize;
    // K_c in tensor order.
    let mut kc = [[0.0; N]; N];
    for (&weight, gradients) in map.weights[..N].iter().zip(&map.gradients) {
        let mut flux = [[0.0; 3]; N];
        for (f, g) in flux.iter_mut().zip(gradients) {
            for (i, fi) in f.iter_mut().enumerate().take(n) {
                *fi = weight * (0..n).map(|j| k[i][j] * g[j]).sum::<f64>();
            }
        }
        for l in 0..N {
            for j in l..N {
                kc[l][j] += (0..n).map(|i| gradients[l][i] * flux[j][i]).sum::<f64>();
            }
        }
    }
    let upper = kc;
    for (l, row) in kc.iter_mut().enumerate() {
        for (j, entry) in row.iter_mut().enumerate().take(l) {
            *entry = upper[j][l];
        }
    }
    let p = memo.tensor_pinv::<N, E>();
    congruence::<N, E>(&kc, &p, out);
}

/// Pᵀ K P (E × E, row-major, into `out`) of a symmetric N × N matrix K,
/// formed on and above the diagonal and mirrored.
fn congruence<const N: usize, const E: usize>(
    kc: &[[f64; N]; N],
    p: &[[f64; E]; N],
    out: &mut [f64],
) {
    // K P (N × E), then Pᵀ (K P) on and above the diagonal.
    let mut half = [[0.0; E]; N];
    for (h, kl) in half.iter_mut().zip(kc) {
        for (a, pa) in kl.iter().zip(p) {
            for (he, pe) in h.iter_mut().zip(pa) {
                *he += a * pe;
            }
        }
    }
    for e in 0..E {
        for f in e..E {
            let value: f64 = (0..N).map(|l| p[l][e] * half[l][f]).sum();
            out[e * E + f] = value;
            out[f * E + e] = value;
        }
    }
}

/// Sign (±1) of corner `l` along local axis `a`.
fn corner_sign(l: usize, a: usize) -> f64 {
    if (l >> a) & 1 == 1 {
        1.0
    } else {
        -1.0
    }
}

/// Q1 shape functions and their reference gradients at ξ ∈ [−1, 1]^n.
fn q1_shape(xi: &[f64], n: usize) -> (Vec<f64>, Vec<[f64; 3]>) {
    let m = 1 << n;
    let scale = 1.0 / m as f64;
    let factor = |l: usize, b: usize| 1.0 + corner_sign(l, b) * xi[b];
    let values = (0..m)
        .map(|l| scale * (0..n).map(|b| factor(l, b)).product::<f64>())
        .collect();
    let gradients = (0..m)
        .map(|l| {
            let mut g = [0.0; 3];
            for (a, ga) in g.iter_mut().enumerate().take(n) {
                *ga = scale
                    * corner_sign(l, a)
                    * (0..n)
                        .filter(|&b| b != a)
                        .map(|b| factor(l, b))
                        .product::<f64>();
            }
            g
        })
        .collect();
    (values, gradients)
}

/// The isoparametric map of a Q1 cell with N = 2ⁿ corners at its N Gauss
/// points: |det J| (the reference weight is 1) and the physical shape
/// gradients, both in tensor order. Fixed arrays of the cell's own size:
/// every cell of a Q1 mesh needs one.
struct Q1Map<const N: usize> {
    weights: [f64; N],
    gradients: [[Point; N]; N],
}

/// [`Q1Map`] of the cell with corners `x` in tensor order (2 Gauss points
/// per axis, weight 1 each on [−1, 1]^n, N = 2ⁿ). The dimension is read
/// from N, so every loop below has a length known at compile time and is
/// unrolled: this runs for every cell of a Q1 mesh.
#[inline(always)]
fn q1_map<const N: usize>(x: &[Point; N], cell: usize) -> Result<Q1Map<N>, MetricError> {
    let n = N.trailing_zeros() as usize;
    let bad = q1_inverted(cell);
    let mut map = Q1Map {
        weights: [0.0; N],
        gradients: [[[0.0; 3]; N]; N],
    };
    let reference = q1_reference(n);
    let mut orientation = 0.0;
    for q in 0..N {
        let shape_gradients = &reference.gradients[q];
        let mut jacobian = [[0.0; 3]; 3];
        for (xl, gl) in x.iter().zip(shape_gradients) {
            for (i, row) in jacobian.iter_mut().enumerate().take(n) {
                for (a, entry) in row.iter_mut().enumerate().take(n) {
                    *entry += xl[i] * gl[a];
                }
            }
        }
        let (det, inverse) = determinant_and_inverse(&jacobian, n);
        if det.is_nan() || det == 0.0 || det * orientation < 0.0 || !det.is_finite() {
            return Err(bad);
        }
        orientation = det.signum();
        map.weights[q] = det.abs();
        // ∇φ = J⁻ᵀ ∇̂φ.
        for (p, r) in map.gradients[q].iter_mut().zip(shape_gradients) {
            for (i, pi) in p.iter_mut().enumerate().take(n) {
                *pi = (0..n).map(|a| inverse[a][i] * r[a]).sum();
            }
        }
    }
    Ok(map)
}

/// Shape values (`values[q][l]`, corner l) and reference gradients at the
/// 2ⁿ Gauss points q of [−1, 1]^n, in arrays of the largest size (n = 3)
/// whose first 2ⁿ entries are used: the same for every cell, so computed
/// once per dimension, and fixed-size so that the per-cell loops over
/// them have known lengths.
struct Q1Reference {
    values: [[f64; 8]; 8],
    gradients: [[Point; 8]; 8],
    /// R_ab of [`affine_block`]: `products[a][b][l][j]` = Σ_q ∂_a N̂_l(q)
    /// ∂_b N̂_j(q) over the Gauss points.
    products: [[[[f64; 8]; 8]; 3]; 3],
}

fn q1_reference(n: usize) -> &'static Q1Reference {
    static REFERENCE: [std::sync::OnceLock<Q1Reference>; 4] = [
        std::sync::OnceLock::new(),
        std::sync::OnceLock::new(),
        std::sync::OnceLock::new(),
        std::sync::OnceLock::new(),
    ];
    REFERENCE[n.min(3)].get_or_init(|| {
        let g = 1.0 / 3f64.sqrt();
        let mut reference = Q1Reference {
            values: [[0.0; 8]; 8],
            gradients: [[[0.0; 3]; 8]; 8],
            products: [[[[0.0; 8]; 8]; 3]; 3],
        };
        let corners = 1usize << n;
        for q in 0..corners {
            let xi: Vec<f64> = (0..n).map(|a| g * corner_sign(q, a)).collect();
            let (values, gradients) = q1_shape(&xi, n);
            reference.values[q][..values.len()].copy_from_slice(&values);
            reference.gradients[q][..gradients.len()].copy_from_slice(&gradients);
            for a in 0..n {
                for b in 0..n {
                    for l in 0..corners {
                        for j in 0..corners {
                            reference.products[a][b][l][j] += gradients[l][a] * gradients[j][b];
                        }
                    }
                }
            }
        }
        reference
    })
}

/// det J and J⁻¹ of the leading n×n block (n ≤ 3), by cofactors; the
/// inverse is meaningless when det J = 0 (the caller refuses those cells).
fn determinant_and_inverse(j: &[[f64; 3]; 3], n: usize) -> (f64, [[f64; 3]; 3]) {
    let mut inverse = [[0.0; 3]; 3];
    match n {
        1 => {
            inverse[0][0] = 1.0 / j[0][0];
            (j[0][0], inverse)
        }
        2 => {
            let det = j[0][0] * j[1][1] - j[0][1] * j[1][0];
            inverse[0][0] = j[1][1] / det;
            inverse[0][1] = -j[0][1] / det;
            inverse[1][0] = -j[1][0] / det;
            inverse[1][1] = j[0][0] / det;
            (det, inverse)
        }
        _ => {
            let cofactor = |r: usize, c: usize| {
                let (r1, r2) = ((r + 1) % 3, (r + 2) % 3);
                let (c1, c2) = ((c + 1) % 3, (c + 2) % 3);
                j[r1][c1] * j[r2][c2] - j[r1][c2] * j[r2][c1]
            };
            let det = (0..3).map(|c| j[0][c] * cofactor(0, c)).sum::<f64>();
            for (r, row) in inverse.iter_mut().enumerate() {
                for (c, entry) in row.iter_mut().enumerate() {
                    *entry = cofactor(c, r) / det;
                }
            }
            (det, inverse)
        }
    }
}

/// The N corners of cell `c` in tensor order.
fn tensor_points<const N: usize>(top: &Topology, c: usize, order: &[usize]) -> [Point; N] {
    let vertices = top.complex.cell_vertices(top.n, c);
    let mut points = [[0.0; 3]; N];
    for (p, &o) in points.iter_mut().zip(order) {
        *p = top.point(vertices[o]);
    }
    points
}

/// A quadrature weight and the shape gradients at its point.
pub(crate) type WeightedGradients = (f64, Vec<Point>);

/// Quadrature weights and the physical gradients of the nodal shape
/// functions of top cell `c` (indexed by the cell's sorted vertex list) at
/// each point: one point of weight |c| for a P1 simplex (constant
/// gradients), the 2ⁿ Gauss points of the isoparametric map for a Q1
/// quadrilateral or hexahedron. `None` for a cell [`stiffness_metric`]
/// would give the virtual element. Other nodal stiffnesses (elasticity)
/// integrate their own bilinear forms with these.
pub(crate) fn shape_gradients(
    top: &Topology,
    c: usize,
) -> Result<Option<Vec<WeightedGradients>>, MetricError> {
    match top.element(c, Route::ByShape)? {
        Element::P1 => {
            let (measure, gradients) =
                simplex_gradients(&top.points(c), top.d).ok_or(MetricError::UnsupportedCell {
                    method: "P1",
                    needs: "a simplex of positive measure",
                    cell: c,
                })?;
            Ok(Some(vec![(measure, gradients)]))
        }
        Element::Q1(order) if top.n == 2 => Ok(Some(q1_gradients::<4>(top, c, &order)?)),
        Element::Q1(order) => Ok(Some(q1_gradients::<8>(top, c, &order)?)),
        Element::Vem => Ok(None),
    }
}

/// [`shape_gradients`] of a Q1 cell with N = 2ⁿ corners: each Gauss
/// point's |det J| and physical gradients, moved from tensor order to the
/// cell's sorted vertex order.
fn q1_gradients<const N: usize>(
    top: &Topology,
    c: usize,
    order: &TensorOrder,
) -> Result<Vec<WeightedGradients>, MetricError> {
    let map = q1_map::<N>(&tensor_points(top, c, order), c)?;
    Ok(map
        .weights
        .iter()
        .zip(&map.gradients)
        .map(|(&weight, gradients)| {
            let mut sorted = vec![[0.0; 3]; N];
            for (&o, g) in order.iter().zip(gradients) {
                sorted[o] = *g;
            }
            (weight, sorted)
        })
        .collect())
}

fn sub(a: &Point, b: &Point) -> Point {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

fn dot(a: &Point, b: &Point) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

fn cross(a: &Point, b: &Point) -> Point {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

fn average(points: impl ExactSizeIterator<Item = Point>) -> Point {
    let count = points.len() as f64;
    let mut sum = [0.0; 3];
    for p in points {
        for i in 0..3 {
            sum[i] += p[i];
        }
    }
    sum.map(|s| s / count)
}

/// ∫_∂c φ_i n for every vertex of a polygon (exact: φ_i is linear on each
/// edge) and the polygon's area, both from the outward edge normals.
fn polygon_moments(
    top: &Topology,
    c: usize,
    x: &[Point],
    centre: &Point,
) -> Result<(Vec<Point>, f64), MetricError> {
    let vertices = top.complex.cell_vertices(2, c);
    let mut moments = vec![[0.0; 3]; x.len()];
    let mut area = 0.0;
    for e in top.edges_of(c) {
        let (a, b) = top.local_ends(e, vertices, c)?;
        let t = sub(&x[b], &x[a]);
        let mid = [0.5 * (x[a][0] + x[b][0]), 0.5 * (x[a][1] + x[b][1]), 0.0];
        let mut normal = [t[1], -t[0], 0.0];
        if dot(&normal, &sub(&mid, centre)) < 0.0 {
            normal = normal.map(|v| -v);
        }
        for i in [a, b] {
            for (mi, ni) in moments[i].iter_mut().zip(&normal) {
                *mi += 0.5 * ni;
            }
        }
        area += 0.5 * dot(&sub(&mid, centre), &normal);
    }
    Ok((moments, area))
}

/// ∫_∂c φ_i n for every vertex of a polyhedron and its volume, over the
/// faces split into fans of triangles about their vertex averages, with the
/// vertex rule on each triangle (exact for functions linear on it).
fn polyhedron_moments(
    top: &Topology,
    c: usize,
    x: &[Point],
    centre: &Point,
) -> Result<(Vec<Point>, f64), MetricError> {
    let vertices = top.complex.cell_vertices(3, c);
    let mut moments = vec![[0.0; 3]; x.len()];
    let mut volume = 0.0;
    for &f in top.facets_of(3, c).0 {
        let face: Vec<usize> = top
            .complex
            .cell_vertices(2, f)
            .iter()
            .map(|v| {
                vertices
                    .binary_search(v)
                    .map_err(|_| MetricError::UnsupportedMesh {
                        method: "VEM",
                        needs: "cells whose faces use their own vertices",
                        detail: format!("face {f} of top cell {c} has a vertex outside the cell"),
                    })
            })
            .collect::<Result<_, _>>()?;
        let apex = average(face.iter().map(|&i| x[i]));
        // Fan triangles (apex, tail, head), all turning the face's way.
        let (edges, signs) = top.facets_of(2, f);
        let mut fan = Vec::with_capacity(edges.len());
        let mut total = [0.0; 3];
        for (&e, &s) in edges.iter().zip(signs) {
            let (a, b) = top.local_ends(e, vertices, c)?;
            let (t, h) = if s > 0 { (a, b) } else { (b, a) };
            let area = cross(&sub(&x[t], &apex), &sub(&x[h], &apex)).map(|v| 0.5 * v);
            for i in 0..3 {
                total[i] += area[i];
            }
            fan.push((t, h, area));
        }
        let outward = match dot(&total, &sub(&apex, centre)) {
            s if s > 0.0 => 1.0,
            s if s < 0.0 => -1.0,
            _ => {
                return Err(MetricError::UnsupportedCell {
                    method: "VEM",
                    needs: "a convex polyhedron (a face is edge-on to the cell centre)",
                    cell: c,
                })
            }
        };
        let share = 1.0 / (3 * face.len()) as f64;
        for (t, h, area) in fan {
            let area = area.map(|v| outward * v);
            for i in 0..3 {
                moments[t][i] += area[i] / 3.0;
                moments[h][i] += area[i] / 3.0;
                for &j in &face {
                    moments[j][i] += area[i] * share;
                }
            }
            let centroid = average([apex, x[t], x[h]].into_iter());
            volume += dot(&sub(&centroid, centre), &area) / 3.0;
        }
    }
    Ok((moments, volume))
}

fn vem_stiffness(top: &Topology, c: usize, k: &Tensor) -> Result<DMatrix<f64>, MetricError> {
    let n = top.n;
    let x = top.points(c);
    let m = x.len();
    let centre = average(x.iter().copied());
    let (moments, measure) = if n == 2 {
        polygon_moments(top, c, &x, &centre)?
    } else {
        polyhedron_moments(top, c, &x, &centre)?
    };
    if measure.is_nan() || measure <= 0.0 {
        return Err(MetricError::UnsupportedCell {
            method: "VEM",
            needs: "a convex cell of positive measure",
            cell: c,
        });
    }
    // Π̃ (n × m): gradient of the projection, column i = ∫_∂c φ_i n / |c|.
    let pit = DMatrix::from_fn(n, m, |a, i| moments[i][a] / measure);
    let kn = DMatrix::from_fn(n, n, |a, b| k[a][b]);
    let consistency = pit.transpose() * &kn * &pit * measure;
    let offsets = DMatrix::from_fn(m, n, |i, a| x[i][a] - centre[a]);
    let projection = DMatrix::from_element(m, m, 1.0 / m as f64) + &offsets * &pit;
    let residual = DMatrix::identity(m, m) - projection;
    let diameter = x
        .iter()
        .flat_map(|a| x.iter().map(move |b| dot(&sub(a, b), &sub(a, b))))
        .fold(0.0f64, f64::max)
        .sqrt();
    let alpha = kn.trace() / n as f64 * diameter.powi(n as i32 - 2);
    Ok(consistency + residual.transpose() * residual * alpha)
}

/// Barycentric quadrature on the n-simplex, (coordinates, weight / |c|)
/// with the coordinates in the first n + 1 entries: the P1 rules of
/// [`load`], the same for every cell, so built once per dimension.
fn simplex_rule(n: usize) -> &'static [([f64; 4], f64)] {
    type Rule = Vec<([f64; 4], f64)>;
    static RULES: [std::sync::OnceLock<Rule>; 4] = [
        std::sync::OnceLock::new(),
        std::sync::OnceLock::new(),
        std::sync::OnceLock::new(),
        std::sync::OnceLock::new(),
    ];
    RULES[n.min(3)].get_or_init(|| match n {
        1 => {
            let s = 3f64.sqrt() / 6.0;
            vec![
                ([0.5 + s, 0.5 - s, 0.0, 0.0], 0.5),
                ([0.5 - s, 0.5 + s, 0.0, 0.0], 0.5),
            ]
        }
        2 => vec![
            ([0.5, 0.5, 0.0, 0.0], 1.0 / 3.0),
            ([0.0, 0.5, 0.5, 0.0], 1.0 / 3.0),
            ([0.5, 0.0, 0.5, 0.0], 1.0 / 3.0),
        ],
        _ => {
            let root5 = 5f64.sqrt();
            let (a, b) = ((5.0 + 3.0 * root5) / 20.0, (5.0 - root5) / 20.0);
            (0..4)
                .map(|k| {
                    let mut beta = [b; 4];
                    beta[k] = a;
                    (beta, 0.25)
                })
                .collect()
        }
    })
}

fn evaluate(
    f: &(dyn Fn(&[f64]) -> f64 + Sync),
    x: &Point,
    d: usize,
    cell: usize,
) -> Result<f64, MetricError> {
    let value = f(&x[..d]);
    if value.is_finite() {
        Ok(value)
    } else {
        Err(MetricError::NonFinite { cell })
    }
}

/// Cell `c`'s load shares ∫_c f φ_v, written over `out` in the order of
/// the cell's vertex list.
fn cell_load(
    top: &Topology,
    c: usize,
    f: &(dyn Fn(&[f64]) -> f64 + Sync),
    out: &mut [f64],
) -> Result<(), MetricError> {
    element_load(top, c, &top.element(c, Route::ByShape)?, f, out)
}

/// A source f as the loads take it.
type LoadFn<'f> = &'f (dyn Fn(&[f64]) -> f64 + Sync);

/// [`cell_load`] of cell `c` with its element already found.
fn element_load(
    top: &Topology,
    c: usize,
    element: &Element,
    f: LoadFn,
    out: &mut [f64],
) -> Result<(), MetricError> {
    let (n, d) = (top.n, top.d);
    out.fill(0.0);
    match element {
        Element::P1 => {
            let x = top.points(c);
            let (measure, _) = simplex_gradients(&x, d).ok_or(MetricError::UnsupportedCell {
                method: "P1",
                needs: "a simplex of positive measure",
                cell: c,
            })?;
            for (beta, w) in simplex_rule(n) {
                let mut p = [0.0; 3];
                for (xi, bi) in x.iter().zip(beta) {
                    for a in 0..3 {
                        p[a] += bi * xi[a];
                    }
                }
                let value = w * measure * evaluate(f, &p, d, c)?;
                for (o, bi) in out.iter_mut().zip(beta) {
                    *o += value * bi;
                }
            }
        }
        Element::Q1(order) if n == 2 => q1_load::<4>(top, c, order, f, out)?,
        Element::Q1(order) => q1_load::<8>(top, c, order, f, out)?,
        Element::Vem => {
            let measure = top.complex.measure(n)[c];
            let mut p = [0.0; 3];
            p[..d].copy_from_slice(top.complex.centroid_of(n, c));
            let share = measure * evaluate(f, &p, d, c)? / out.len() as f64;
            out.fill(share);
        }
    }
    Ok(())
}

/// [`cell_load`] of a Q1 cell with N = 2ⁿ corners, tensor Gauss rule.
fn q1_load<const N: usize>(
    top: &Topology,
    c: usize,
    order: &TensorOrder,
    f: &(dyn Fn(&[f64]) -> f64 + Sync),
    out: &mut [f64],
) -> Result<(), MetricError> {
    let x = tensor_points(top, c, order);
    let weights = q1_geometry::<N>(&x, c)?.weights();
    q1_shares(top, c, order, &x, &weights, f, out)
}

/// The tensor Gauss rule of [`q1_load`] on corners `x` (tensor order) with
/// the map's weights |det J|, written over `out` (sorted vertex order).
fn q1_shares<const N: usize>(
    top: &Topology,
    c: usize,
    order: &TensorOrder,
    x: &[Point; N],
    weights: &[f64; N],
    f: LoadFn,
    out: &mut [f64],
) -> Result<(), MetricError> {
    let (n, d) = (N.trailing_zeros() as usize, top.d);
    out.fill(0.0);
    let reference = q1_reference(n);
    for (values, &weight) in reference.values.iter().zip(weights) {
        let mut point = [0.0; 3];
        for (xl, &v) in x.iter().zip(values) {
            for i in 0..n {
                point[i] += v * xl[i];
            }
        }
        let value = weight * evaluate(f, &point, d, c)?;
        for (&o, v) in order.iter().zip(values) {
            out[o] += value * v;
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::metric::isotropic;
    use hasse_complex::{TopCells, Vertices};

    fn weights(complex: &Complex) -> Vec<f64> {
        let cells = complex.cell_count(complex.dim());
        let omega = stiffness_metric(complex, &vec![isotropic(1.0); cells]).unwrap();
        let dense = omega.to_dense();
        (0..omega.size()).map(|e| dense[e][e]).collect()
    }

    fn angle(apex: [f64; 2], a: [f64; 2], b: [f64; 2]) -> f64 {
        let (u, v) = (
            [a[0] - apex[0], a[1] - apex[1]],
            [b[0] - apex[0], b[1] - apex[1]],
        );
        (u[0] * v[1] - u[1] * v[0])
            .abs()
            .atan2(u[0] * v[0] + u[1] * v[1])
    }

    #[test]
    fn right_triangle_has_no_weight_on_the_hypotenuse() {
        let v = Vertices::from_points(&[[0.0, 0.0], [3.0, 0.0], [0.0, 2.0]]).unwrap();
        let k = Complex::build(v, TopCells::simplices([[0, 1, 2]])).unwrap();
        let w = weights(&k);
        let hypotenuse = k.find_cell(1, &[1, 2]).unwrap();
        assert!(w[hypotenuse].abs() < 1e-15);
        // Leg {0,1} is opposite the angle at 2: cot = 2/3, weight 1/3.
        assert!((w[k.find_cell(1, &[0, 1]).unwrap()] - 1.0 / 3.0).abs() < 1e-15);
        assert!((w[k.find_cell(1, &[0, 2]).unwrap()] - 0.75).abs() < 1e-15);
    }

    #[test]
    fn triangle_weights_are_half_cotangents() {
        let p = [[0.1, -0.2], [2.3, 0.4], [0.7, 1.9]];
        let v = Vertices::from_points(&p).unwrap();
        let k = Complex::build(v, TopCells::simplices([[0, 1, 2]])).unwrap();
        let w = weights(&k);
        for (a, b, o) in [(0, 1, 2), (1, 2, 0), (0, 2, 1)] {
            let e = k.find_cell(1, &[a, b]).unwrap();
            let expected = 0.5 / angle(p[o], p[a], p[b]).tan();
            assert!(
                (w[e] - expected).abs() < 1e-14,
                "{a}{b}: {} vs {expected}",
                w[e]
            );
        }
    }

    #[test]
    fn tetrahedron_weights_are_opposite_edge_cotangents() {
        let p = [
            [0.0, 0.0, 0.0],
            [1.2, 0.1, -0.1],
            [0.3, 0.9, 0.2],
            [0.2, 0.3, 1.1],
        ];
        let v = Vertices::from_points(&p).unwrap();
        let k = Complex::build(v, TopCells::simplices([[0, 1, 2, 3]])).unwrap();
        let w = weights(&k);
        let sub3 = |a: usize, b: usize| [p[a][0] - p[b][0], p[a][1] - p[b][1], p[a][2] - p[b][2]];
        let cross3 = |u: [f64; 3], v: [f64; 3]| {
            [
                u[1] * v[2] - u[2] * v[1],
                u[2] * v[0] - u[0] * v[2],
                u[0] * v[1] - u[1] * v[0],
            ]
        };
        let dot3 = |u: [f64; 3], v: [f64; 3]| u[0] * v[0] + u[1] * v[1] + u[2] * v[2];
        for (a, b) in [(0, 1), (0, 2), (0, 3), (1, 2), (1, 3), (2, 3)] {
            // Opposite edge {c, d}; the dihedral angle there is between the
            // faces {c, d, a} and {c, d, b}.
            let others: Vec<usize> = (0..4).filter(|&i| i != a && i != b).collect();
            let (c, d) = (others[0], others[1]);
            let axis = sub3(d, c);
            let unit = dot3(axis, axis).sqrt();
            let reject = |x: usize| {
                let r = sub3(x, c);
                let t = dot3(r, axis) / (unit * unit);
                [r[0] - t * axis[0], r[1] - t * axis[1], r[2] - t * axis[2]]
            };
            let (ra, rb) = (reject(a), reject(b));
            let phi = dot3(cross3(ra, rb), cross3(ra, rb))
                .sqrt()
                .atan2(dot3(ra, rb));
            let expected = unit / phi.tan() / 6.0;
            let e = k.find_cell(1, &[a, b]).unwrap();
            assert!(
                (w[e] - expected).abs() < 1e-14,
                "{a}{b}: {} vs {expected}",
                w[e]
            );
        }
    }

    #[test]
    fn unit_square_q1_block_reproduces_the_element_matrix() {
        let v = Vertices::from_points(&[[0.0, 0.0], [1.0, 0.0], [0.0, 1.0], [1.0, 1.0]]).unwrap();
        let k = Complex::build(v, TopCells::cuboids([[0, 1, 2, 3]])).unwrap();
        let omega = stiffness_metric(&k, &[isotropic(1.0)]).unwrap();
        assert_eq!(omega.block_count(), 1);
        let op = crate::operator::Canonical::new(k.coboundary(0), omega).unwrap();
        let m = op.assemble().to_dense();
        // 4/6 on the diagonal, −1/6 along edges, −2/6 across the diagonal.
        for i in 0..4usize {
            for j in 0..4usize {
                let expected = match (i ^ j).count_ones() {
                    0 => 4.0 / 6.0,
                    1 => -1.0 / 6.0,
                    _ => -2.0 / 6.0,
                };
                assert!((m[(i, j)] - expected).abs() < 1e-14, "({i},{j})");
            }
        }
    }

    /// uᵀ M v for the one-cell operator M = Aᵀ Ω A of Q1 on the cell with
    /// corners `x0 + Σ_{a ∈ l} axes[a]` (corner l in tensor order, stored
    /// as vertex (5 l + 2) mod 2ⁿ) and conductivity `k`, for corner values
    /// `modes` given per tensor corner.
    fn one_cell_forms(
        x0: [f64; 3],
        axes: &[[f64; 3]],
        k: Tensor,
        modes: &[Vec<f64>],
    ) -> Vec<Vec<f64>> {
        let n = axes.len();
        let corners = 1usize << n;
        let vertex = |l: usize| (5 * l + 2) % corners;
        let mut coordinates = vec![0.0; corners * n];
        for i in 0..n {
            for (l, x) in coordinate_mode(x0, axes, i).into_iter().enumerate() {
                coordinates[vertex(l) * n + i] = x;
            }
        }
        let v = Vertices::new(n, coordinates).unwrap();
        let cell: Vec<usize> = (0..corners).map(vertex).collect();
        let complex = Complex::build(v, TopCells::cuboids([cell])).unwrap();
        let omega = stiffness_metric(&complex, &[k]).unwrap();
        let m = crate::operator::Canonical::new(complex.coboundary(0), omega)
            .unwrap()
            .assemble()
            .to_dense();
        let by_vertex = |mode: &[f64]| {
            let mut u = vec![0.0; corners];
            for (l, &value) in mode.iter().enumerate() {
                u[vertex(l)] = value;
            }
            u
        };
        modes
            .iter()
            .map(|a| {
                let u = by_vertex(a);
                modes
                    .iter()
                    .map(|b| {
                        let w = by_vertex(b);
                        (0..corners)
                            .map(|i| (0..corners).map(|j| u[i] * m[(i, j)] * w[j]).sum::<f64>())
                            .sum()
                    })
                    .collect()
            })
            .collect()
    }

    /// The corner values (tensor order) of ξ_a ξ_b … on [−1, 1]ⁿ for the
    /// reference axes in `axes`.
    fn reference_mode(n: usize, axes: &[usize]) -> Vec<f64> {
        (0..1usize << n)
            .map(|l| axes.iter().map(|&a| corner_sign(l, a)).product())
            .collect()
    }

    /// The corner values (tensor order) of the physical coordinate x_i on
    /// the cell of [`one_cell_forms`].
    fn coordinate_mode(x0: [f64; 3], axes: &[[f64; 3]], i: usize) -> Vec<f64> {
        (0..1usize << axes.len())
            .map(|l| {
                x0[i]
                    + (0..axes.len())
                        .filter(|&a| (l >> a) & 1 == 1)
                        .map(|a| axes[a][i])
                        .sum::<f64>()
            })
            .collect()
    }

    fn assert_forms(label: &str, forms: &[Vec<f64>], expected: &[&[f64]]) {
        for (a, row) in expected.iter().enumerate() {
            for (b, &value) in row.iter().enumerate() {
                assert!(
                    (forms[a][b] - value).abs() < 1e-13,
                    "{label} ({a}, {b}): {} vs {value}",
                    forms[a][b]
                );
            }
        }
    }

    #[test]
    fn q1_on_parallelograms_is_the_exact_galerkin_stiffness() {
        // A sheared cell, edges e1 = (2, 0), e2 = (1, 1) from (0.5, −1),
        // area 2, with k = [[2, ½], [½, 1]]. By hand: J = [e1 e2]/2,
        // det J = ½, J⁻¹ = [[1, −1], [0, 2]], C = det J · J⁻¹ k J⁻ᵀ =
        // [[1, −½], [−½, 2]]. Linear u, v: uᵀ M v = area · ∇uᵀ k ∇v, so
        // 4, 1, 2 for (x, x), (x, y), (y, y). The hourglass ξ1ξ2 has
        // ∇̂ = (ξ2, ξ1): ∫ over [−1, 1]² of ξ2² C11 + ξ1² C22 = 4/3 · 3 = 4,
        // and it is orthogonal to linear modes and constants.
        let x0 = [0.5, -1.0, 0.0];
        let axes = [[2.0, 0.0, 0.0], [1.0, 1.0, 0.0]];
        let k = [[2.0, 0.5, 0.0], [0.5, 1.0, 0.0], [0.0; 3]];
        let modes = [
            coordinate_mode(x0, &axes, 0),
            coordinate_mode(x0, &axes, 1),
            reference_mode(2, &[0, 1]),
            vec![1.0; 4],
        ];
        assert_forms(
            "2D",
            &one_cell_forms(x0, &axes, k, &modes),
            &[
                &[4.0, 1.0, 0.0, 0.0],
                &[1.0, 2.0, 0.0, 0.0],
                &[0.0, 0.0, 4.0, 0.0],
                &[0.0; 4],
            ],
        );
        // A parallelepiped: e1 = (2, 0, 0), e2 = (0, 2, 0), e3 = (1, 0, 2),
        // volume 8, k = I. J = [e1 e2 e3]/2 has det 1 and J⁻¹ rows
        // (1, 0, −½), (0, 1, 0), (0, 0, 1), so C = J⁻¹ J⁻ᵀ has C11 = 5/4,
        // C13 = −½, C22 = C33 = 1 and C12 = C23 = 0. Over [−1, 1]³ with
        // ∫ ξ² = 8/3 and ∫ ξ²η² = 8/9: ξ1ξ2 gives 8/3 (C11 + C22) = 6,
        // ξ1ξ3 gives 6, ξ2ξ3 gives 16/3, ξ1ξ2ξ3 gives 8/9 · 13/4 = 26/9;
        // ξ1ξ2 against ξ2ξ3 is ∫ ξ2² C13 = −4/3; u = x gives the volume.
        let x0 = [1.0, 0.0, -2.0];
        let axes = [[2.0, 0.0, 0.0], [0.0, 2.0, 0.0], [1.0, 0.0, 2.0]];
        let identity = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
        let modes = [
            reference_mode(3, &[0, 1]),
            reference_mode(3, &[0, 2]),
            reference_mode(3, &[1, 2]),
            reference_mode(3, &[0, 1, 2]),
            coordinate_mode(x0, &axes, 0),
            vec![1.0; 8],
        ];
        assert_forms(
            "3D",
            &one_cell_forms(x0, &axes, identity, &modes),
            &[
                &[6.0, 0.0, -4.0 / 3.0, 0.0, 0.0, 0.0],
                &[0.0, 6.0, 0.0, 0.0, 0.0, 0.0],
                &[-4.0 / 3.0, 0.0, 16.0 / 3.0, 0.0, 0.0, 0.0],
                &[0.0, 0.0, 0.0, 26.0 / 9.0, 0.0, 0.0],
                &[0.0, 0.0, 0.0, 0.0, 8.0, 0.0],
                &[0.0; 6],
            ],
        );
    }

    #[test]
    fn only_parallelograms_and_parallelepipeds_take_the_constant_jacobian() {
        let square = [
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [1.0, 1.0, 0.0],
        ];
        let jacobian = affine_jacobian::<4>(&square).unwrap();
        assert_eq!(
            (
                jacobian[0][0],
                jacobian[0][1],
                jacobian[1][0],
                jacobian[1][1]
            ),
            (0.5, 0.0, 0.0, 0.5)
        );
        // Corner 3 moved by 10⁻¹², far above 16 ulp of the unit size: a
        // trapezoid, for the Gauss rule.
        let mut moved = square;
        moved[3][0] += 1e-12;
        assert!(affine_jacobian::<4>(&moved).is_none());
        // A unit cube with only corner 7 (all three axes) moved.
        let mut cube = [[0.0; 3]; 8];
        for (l, p) in cube.iter_mut().enumerate() {
            for (a, x) in p.iter_mut().enumerate() {
                *x = ((l >> a) & 1) as f64;
            }
        }
        assert!(affine_jacobian::<8>(&cube).is_some());
        cube[7][2] -= 1e-12;
        assert!(affine_jacobian::<8>(&cube).is_none());
    }

    /// Unit cells of an `sides` grid (2 or 3 axes) with vertex v renumbered
    /// (7 v + 3) mod |V|, so that neighbouring cells see their vertices in
    /// different sorted orders and have different local incidences: the
    /// last cell's tensor order and A_c⁺ are reused when it matches and
    /// found again when not. Returns the complex and each cell's corners
    /// in tensor order, renumbered.
    fn scrambled_grid(sides: &[usize]) -> (Complex, Vec<Vec<usize>>) {
        let n = sides.len();
        let stride: Vec<usize> = (0..n)
            .map(|a| sides[..a].iter().map(|s| s + 1).product())
            .collect();
        let count: usize = sides.iter().map(|s| s + 1).product();
        assert!(count % 7 != 0);
        let renumber = |v: usize| (7 * v + 3) % count;
        let mut points = vec![[0.0; 3]; count];
        for v in 0..count {
            for a in 0..n {
                points[renumber(v)][a] = ((v / stride[a]) % (sides[a] + 1)) as f64;
            }
        }
        let mut cells = Vec::new();
        let cell_count: usize = sides.iter().product();
        for c in 0..cell_count {
            let mut base = 0;
            let mut rest = c;
            for a in 0..n {
                base += (rest % sides[a]) * stride[a];
                rest /= sides[a];
            }
            let corners: Vec<usize> = (0..1usize << n)
                .map(|l| {
                    let offset: usize = (0..n)
                        .filter(|&a| (l >> a) & 1 == 1)
                        .map(|a| stride[a])
                        .sum();
                    renumber(base + offset)
                })
                .collect();
            cells.push(corners);
        }
        let coordinates: Vec<f64> = points.iter().flat_map(|p| p[..n].to_vec()).collect();
        let vertices = Vertices::new(n, coordinates).unwrap();
        let complex = Complex::build(vertices, TopCells::cuboids(cells.clone())).unwrap();
        (complex, cells)
    }

    #[test]
    fn q1_on_a_scrambled_numbering_is_the_element_matrix_summed() {
        // The unit square's and the unit cube's Q1 stiffness, by the number
        // of local axes along which corners i and j differ: 2/3, −1/6, −1/3
        // in 2D; 1/3, 0, −1/12, −1/12 in 3D.
        for (sides, element) in [
            (vec![5, 4], vec![2.0 / 3.0, -1.0 / 6.0, -1.0 / 3.0]),
            (
                vec![3, 3, 2],
                vec![1.0 / 3.0, 0.0, -1.0 / 12.0, -1.0 / 12.0],
            ),
        ] {
            let (k, cells) = scrambled_grid(&sides);
            let omega = stiffness_metric(&k, &vec![isotropic(1.0); cells.len()]).unwrap();
            let m = crate::operator::Canonical::new(k.coboundary(0), omega)
                .unwrap()
                .assemble()
                .to_dense();
            let vertices = k.cell_count(0);
            let mut expected = vec![vec![0.0; vertices]; vertices];
            for corners in &cells {
                for (l, &u) in corners.iter().enumerate() {
                    for (q, &w) in corners.iter().enumerate() {
                        expected[u][w] += element[(l ^ q).count_ones() as usize];
                    }
                }
            }
            for u in 0..vertices {
                for w in 0..vertices {
                    assert!(
                        (m[(u, w)] - expected[u][w]).abs() < 1e-14,
                        "{sides:?}: ({u}, {w}) is {} instead of {}",
                        m[(u, w)],
                        expected[u][w]
                    );
                }
            }
        }
    }

    /// A 6 × 5 grid of [0, 3] × [0, 2] with its interior vertices moved
    /// (by a fixed pattern, up to 0.15 of a cell): convex quadrilaterals
    /// that are not parallelograms, so the Gauss points see four maps.
    fn distorted_quads() -> Complex {
        let k = hasse_complex::generate::rectangle(6, 5, [0.0, 3.0], [0.0, 2.0]).unwrap();
        let moved: Vec<[f64; 2]> = (0..k.cell_count(0))
            .map(|v| {
                let p = k.vertices().point(v);
                let inside = p[0] > 0.0 && p[0] < 3.0 && p[1] > 0.0 && p[1] < 2.0;
                let s = if inside { 0.15 * 0.5 } else { 0.0 };
                let t = v as f64;
                [p[0] + s * (1.7 * t).sin(), p[1] + s * (2.3 * t).cos()]
            })
            .collect();
        k.with_vertices(Vertices::from_points(&moved).unwrap())
            .unwrap()
    }

    #[test]
    fn stiffness_and_load_together_are_the_two_apart() {
        let f = |x: &[f64]| 1.0 + 2.0 * x[0] - x[1];
        let quads = distorted_quads();
        let axis = hasse_complex::generate::uniform_axis(3, 0.0, 1.0).unwrap();
        let hexes =
            hasse_complex::generate::box3(3, 2, 2, [0.0, 1.0], [0.0, 2.0], [0.0, 1.0]).unwrap();
        let tets = hasse_complex::generate::kuhn(&[axis.clone(), axis.clone(), axis]).unwrap();
        for k in [&quads, &hexes, &tets] {
            let n = k.dim();
            let cells = k.cell_count(n);
            let tensors: Vec<Tensor> = (0..cells)
                .map(|c| isotropic(1.0 + (c % 3) as f64))
                .collect();
            let (omega, b) = stiffness_and_load(k, &tensors, &f).unwrap();
            assert_eq!(omega, stiffness_metric(k, &tensors).unwrap());
            assert_eq!(b, load(k, &f).unwrap());
            // Independently: the shares of a linear f sum to its integral,
            // which the tensor Gauss rule and the P1 rules give exactly;
            // ∫ f = |Ω| f(centre of mass).
            let (volume, centre) = match n {
                2 => (6.0, [1.5, 1.0]),
                _ if k.cell_count(n) == 12 => (2.0, [0.5, 1.0]),
                _ => (1.0, [0.5, 0.5]),
            };
            let expected = volume * f(&centre);
            let total: f64 = b.iter().sum();
            assert!(
                (total - expected).abs() < 1e-12 * expected,
                "{total} against {expected}"
            );
        }
    }

    #[test]
    fn stiffness_and_load_report_what_they_report_apart() {
        let k = hasse_complex::generate::rectangle(40, 25, [0.0, 1.0], [0.0, 1.0]).unwrap();
        let mut tensors = vec![isotropic(1.0); 1000];
        tensors[700] = isotropic(f64::MAX);
        // A source that fails at a cell before the bad stiffness: the
        // stiffness error still comes first, as when computed apart.
        let f = |x: &[f64]| {
            if x[0] < 0.1 && x[1] < 0.1 {
                f64::NAN
            } else {
                1.0
            }
        };
        let error = stiffness_and_load(&k, &tensors, &f).unwrap_err();
        assert!(
            matches!(
                error,
                MetricError::UnsupportedCell {
                    method: "Q1",
                    cell: 700,
                    ..
                }
            ),
            "{error:?}"
        );
        // With a sound stiffness the source's first bad cell is named.
        let error = stiffness_and_load(&k, &vec![isotropic(1.0); 1000], &f).unwrap_err();
        assert_eq!(error, load(&k, &f).unwrap_err());
        assert!(
            matches!(error, MetricError::NonFinite { cell: 0 }),
            "{error:?}"
        );
    }

    #[test]
    fn non_cube_octagon_falls_back_to_the_virtual_element() {
        // Eight vertices in 2D are not a Q1 cell.
        let p: Vec<[f64; 2]> = (0..8)
            .map(|i| {
                let t = std::f64::consts::PI * i as f64 / 4.0;
                [t.cos(), t.sin()]
            })
            .collect();
        let v = Vertices::from_points(&p).unwrap();
        let k = Complex::build(v, TopCells::polygons([[0, 1, 2, 3, 4, 5, 6, 7]])).unwrap();
        let top = Topology::new(&k, "test").unwrap();
        assert!(matches!(top.element(0, Route::ByShape), Ok(Element::Vem)));
    }

    #[test]
    fn the_first_bad_cell_in_cell_order_is_reported() {
        // A conductivity near the largest double passes the tensor check
        // (finite, symmetric, positive) but overflows the local stiffness
        // of cells 300 and 700 of a 40 × 25 grid. Cells are computed in
        // parallel parts; the error must still name the first bad cell,
        // whatever part finishes first.
        let k = hasse_complex::generate::rectangle(40, 25, [0.0, 1.0], [0.0, 1.0]).unwrap();
        let mut tensors = vec![isotropic(1.0); 1000];
        tensors[300] = isotropic(f64::MAX);
        tensors[700] = isotropic(f64::MAX);
        for _ in 0..5 {
            let error = stiffness_metric(&k, &tensors).unwrap_err();
            assert!(
                matches!(
                    error,
                    MetricError::UnsupportedCell {
                        method: "Q1",
                        cell: 300,
                        ..
                    }
                ),
                "{error:?}"
            );
        }
    }

    #[test]
    fn bad_input_is_a_typed_error() {
        let v = Vertices::from_points(&[[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]]).unwrap();
        let k = Complex::build(v, TopCells::simplices([[0, 1, 2]])).unwrap();
        assert!(matches!(
            stiffness_metric(&k, &[] as &[Tensor]),
            Err(MetricError::CoefficientCount { count: 0, cells: 1 })
        ));
        assert!(matches!(
            load(&k, &|x: &[f64]| 1.0 / (x[0] - x[0])),
            Err(MetricError::NonFinite { cell: 0 })
        ));
    }

    #[test]
    fn a_cell_edge_count_is_its_edge_list_length() {
        use hasse_complex::generate::{box3, interval, rectangle, voronoi};
        // A polygon has as many edges as vertices; a hexahedron 12 edges.
        let polygons = voronoi(40, [0.0, 1.0], [0.0, 1.0], 11, 2).unwrap();
        let quads = rectangle(3, 2, [0.0, 1.0], [0.0, 1.0]).unwrap();
        let hexes = box3(2, 2, 1, [0.0, 1.0], [0.0, 1.0], [0.0, 1.0]).unwrap();
        let line = interval(3, 0.0, 1.0).unwrap();
        let mut scratch = Vec::new();
        for (k, expected) in [
            (&polygons, None),
            (&quads, Some(4)),
            (&hexes, Some(12)),
            (&line, Some(1)),
        ] {
            let top = Topology::new(k, "test").unwrap();
            for c in 0..k.cell_count(k.dim()) {
                let count = top.edge_count(c, &mut scratch);
                let expected = expected.unwrap_or_else(|| k.cell_vertices(2, c).len());
                assert_eq!(count, expected, "cell {c} of a {}-complex", k.dim());
                let mut edges = Vec::new();
                top.edges_into(c, &mut edges);
                assert_eq!(count, edges.len());
            }
        }
    }
}
