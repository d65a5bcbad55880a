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

pub mod advection;
pub(crate) mod field;
mod load;
mod p1;
mod q1;
pub(crate) mod rules;
#[cfg(test)]
mod tests;
mod topology;
mod vem;

use super::{CellTensors, MetricError, Tensor};
use crate::la::parallel::{ranges, split_at_ranges};
use crate::operator::BlockMetric;
use hasse_complex::Complex;
use load::{cell_load, element_load, evaluate, LoadFn};
use nalgebra::DMatrix;
use p1::p1_weights;
pub(crate) use p1::{k_dot, simplex_gradients};
use q1::{q1_cell, q1_gradients, q1_load, Q1Memo};
use rayon::prelude::*;
use sprs::CsMat;
use std::rc::Rc;
use std::sync::Arc;
use topology::{edge_block, pseudo_inverse_of_key, tensor_order_of};
pub(crate) use topology::{edge_pseudo_inverse, Topology};
use vem::vem_stiffness;

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
    load_in_cells(complex, &|_, x| f(x))
}

/// [`load()`] of a source that depends on the top cell as well as the
/// position (data given per region): cell c's quadrature evaluates
/// f(c, x).
///
/// ```
/// use hasse_complex::generate::rectangle;
/// use hasse_solver::metric::fe;
/// let k = rectangle(3, 2, [0.0, 3.0], [0.0, 1.0]).unwrap();
/// // f = 2 in cell 0 (of area 1 × 1/2), 0 elsewhere: a total load of 1.
/// let b = fe::load_in_cells(&k, &|c, _| if c == 0 { 2.0 } else { 0.0 }).unwrap();
/// assert!((b.iter().sum::<f64>() - 1.0).abs() < 1e-14);
/// ```
pub fn load_in_cells(
    complex: &Complex,
    f: &(dyn Fn(usize, &[f64]) -> f64 + Sync),
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
                    &|x| f(c, x),
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

/// [`stiffness_metric`] and [`load()`] together, equal to them bit for bit:
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
    let mut out = crate::la::parallel::zeroed(complex.cell_count(0));
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
    let tensors = tensors.checked(cells, top.d)?;
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
    let by_cell = (top.n == 2).then(|| Arc::clone(top.complex.boundary_csc(2)));
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
