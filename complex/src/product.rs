//! The product of complexes (LAR paper, "Product of complexes"): C = A × B
//! has a cell λ × μ of dimension p + q for every p-cell λ of A and q-cell μ
//! of B, with vertex set V(λ) × V(μ). Vertex (u, v) of the product is
//! numbered u·|V(B)| + v and sits at (x_u, y_v) in R^(d_A + d_B).
//!
//! The product itself is combinatorial and has no dimension limit (the
//! paper's triangle × triangle is a 4-cell with 9 vertices in E⁴); an
//! oriented [`Complex`] is made from it when it fits in R³, e.g. a 2D mesh
//! × an interval gives a layer of prisms or hexahedra.
//!
//! ```
//! use hasse_complex::generate::{interval, rectangle};
//! use hasse_complex::product::CellProduct;
//! let square = rectangle(2, 2, [0.0, 1.0], [0.0, 1.0]).unwrap();
//! let layer = interval(3, 0.0, 0.3).unwrap();
//! let prisms = CellProduct::new(square.lar(), layer.lar()).to_complex().unwrap();
//! assert_eq!(prisms.cell_count(3), 4 * 3);
//! assert_eq!(prisms.euler_characteristic(), 1);
//! ```

use crate::cells::Vertices;
use crate::complex::Complex;
use crate::error::Result;
use crate::lar::Lar;

/// Which cells of the factors a product cell comes from: (p, i, q, j) for
/// p-cell i of A times q-cell j of B.
pub type Factors = (usize, usize, usize, usize);

/// The cells of A × B by dimension, with their vertex sets and factors.
///
/// ```
/// use hasse_complex::{product::CellProduct, Lar, Vertices};
/// // The paper's example: two triangles give one 4-cell with 9 vertices.
/// let triangle = |x: f64| {
///     let v = Vertices::new(2, vec![x, 0.0, x + 1.0, 0.0, x, 1.0]).unwrap();
///     Lar::from_vertex_sets(v, vec![vec![vec![0, 1], vec![0, 2], vec![1, 2]], vec![vec![0, 1, 2]]])
///         .unwrap()
/// };
/// let c = CellProduct::new(&triangle(0.0), &triangle(5.0));
/// assert_eq!((c.dim(), c.embedding_dim()), (4, 4));
/// assert_eq!(c.cell_vertices(4, 0).len(), 9);
/// assert_eq!(c.cell_counts(), vec![9, 18, 15, 6, 1]);
/// ```
#[derive(Clone, Debug, PartialEq)]
pub struct CellProduct {
    embedding_dim: usize,
    coords: Vec<f64>,
    /// `cells[k]`: sorted vertex sets of the k-cells (k = 0 included).
    cells: Vec<Vec<Vec<usize>>>,
    factors: Vec<Vec<Factors>>,
}

impl CellProduct {
    /// A × B. Cells of dimension k are listed by the dimension of their A
    /// factor (highest first), then by A cell, then by B cell.
    pub fn new(a: &Lar, b: &Lar) -> Self {
        let (da, db) = (a.vertices().dim(), b.vertices().dim());
        let nb = b.cell_count(0);
        let mut coords = Vec::with_capacity(a.cell_count(0) * nb * (da + db));
        for u in 0..a.cell_count(0) {
            for v in 0..nb {
                coords.extend_from_slice(a.vertices().point(u));
                coords.extend_from_slice(b.vertices().point(v));
            }
        }
        let n = a.dim() + b.dim();
        let mut cells = vec![Vec::new(); n + 1];
        let mut factors = vec![Vec::new(); n + 1];
        for k in 0..=n {
            for p in (0..=k.min(a.dim())).rev() {
                let q = k - p;
                if q > b.dim() {
                    continue;
                }
                for i in 0..a.cell_count(p) {
                    for j in 0..b.cell_count(q) {
                        // u ascending, then v ascending: already sorted.
                        let set = a
                            .cell_vertices(p, i)
                            .iter()
                            .flat_map(|&u| b.cell_vertices(q, j).iter().map(move |&v| u * nb + v))
                            .collect();
                        cells[k].push(set);
                        factors[k].push((p, i, q, j));
                    }
                }
            }
        }
        Self {
            embedding_dim: da + db,
            coords,
            cells,
            factors,
        }
    }

    /// Dimension of the product (dim A + dim B).
    pub fn dim(&self) -> usize {
        self.cells.len() - 1
    }

    /// Dimension of the space of its vertices (d_A + d_B).
    pub fn embedding_dim(&self) -> usize {
        self.embedding_dim
    }

    /// Number of k-cells.
    pub fn cell_count(&self, k: usize) -> usize {
        self.cells.get(k).map_or(0, Vec::len)
    }

    /// Number of cells of every dimension 0 … n.
    pub fn cell_counts(&self) -> Vec<usize> {
        self.cells.iter().map(Vec::len).collect()
    }

    /// Sorted vertices of k-cell `i`.
    pub fn cell_vertices(&self, k: usize, i: usize) -> &[usize] {
        &self.cells[k][i]
    }

    /// The factors of k-cell `i`.
    pub fn factors(&self, k: usize, i: usize) -> Factors {
        self.factors[k][i]
    }

    /// Coordinates of vertex `v`: those of its A vertex, then its B vertex.
    pub fn point(&self, v: usize) -> &[f64] {
        &self.coords[v * self.embedding_dim..(v + 1) * self.embedding_dim]
    }

    /// Euler characteristic Σ (−1)^k |C_k| (= χ(A) χ(B)).
    pub fn euler_characteristic(&self) -> i64 {
        self.cells
            .iter()
            .enumerate()
            .map(|(k, c)| {
                if k % 2 == 0 {
                    c.len() as i64
                } else {
                    -(c.len() as i64)
                }
            })
            .sum()
    }

    /// The oriented complex, when the product fits in R³ (d_A + d_B ≤ 3).
    /// Products of convex cells are convex, so every cell is oriented from
    /// its geometry like any polytope.
    pub fn to_complex(&self) -> Result<Complex> {
        let vertices = Vertices::new(self.embedding_dim, self.coords.clone())?;
        let lar = Lar::from_vertex_sets(vertices, self.cells[1..].to_vec())?;
        Complex::from_lar(lar)
    }
}
