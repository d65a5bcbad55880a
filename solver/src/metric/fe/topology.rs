//! The topology an element reads: a top cell's vertices and edges in the
//! complex's numbering, its local incidence A_c and the cached
//! pseudo-inverse A_c⁺ that turns an element matrix into Ω_c.

use super::*;
use std::sync::Arc;

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
            delta0: Arc::clone(complex.coboundary(0)),
            facets: (2..=n).map(|p| &**complex.boundary_csc(p)).collect(),
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

    pub(super) fn points(&self, c: usize) -> Vec<Point> {
        self.complex
            .cell_vertices(self.n, c)
            .iter()
            .map(|&v| self.point(v))
            .collect()
    }

    pub(super) fn element(&self, c: usize, route: Route) -> Result<Element, MetricError> {
        self.element_with(c, route, &mut Vec::new(), &mut Q1Memo::default())
    }

    /// [`Topology::element`] with a scratch vector for the cell's edges
    /// and the last Q1 cell's local incidence.
    pub(super) fn element_with(
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

    /// [`Topology::tensor_order`] with its own scratch space.
    pub(super) fn element_order(&self, c: usize) -> Option<Vec<usize>> {
        self.tensor_order(c, &mut Vec::new(), &mut Q1Memo::default())
            .map(|order| order.to_vec())
    }

    /// Local vertex positions of a quadrilateral or hexahedron in tensor
    /// order (bit a of the index = side along local axis a), recovered from
    /// its edge graph; `None` when the graph is not a square or a cube.
    pub(super) fn tensor_order(
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
pub(super) fn tensor_order_of(
    m: usize,
    n: usize,
    ends: &[[u8; 2]; 12],
    edges: usize,
) -> Option<TensorOrder> {
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
pub(super) fn pseudo_inverse_of_key(
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
pub(super) const PSEUDO_INVERSE_CACHE_SIZE: usize = 1024;

/// A_c⁺ by local incidence pattern (vertex count, then the local tail and
/// head of each edge in the cell's edge order), with the last pattern
/// looked up kept apart: neighbouring cells of a structured grid mostly
/// share it, and comparing one key is cheaper than hashing it.
#[derive(Default)]
pub(super) struct PseudoInverseCache {
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
pub(super) fn edge_block(
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
