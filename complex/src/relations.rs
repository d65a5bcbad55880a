//! The LAR paper's incidence and adjacency operators (§ "Incidence and
//! adjacency operators"): every relation between cells of two dimensions is
//! one sparse product of characteristic matrices, M_p M_qᵀ, whose entry
//! (i, j) counts the vertices p-cell i and q-cell j share. A query about one
//! cell reads one row; a query about a set of cells (a chain) is one
//! product with its indicator vector. The star operator St, the cells
//! touching a given set, is built the same way.
//!
//! ```
//! use hasse_complex::{relations::Relation, generate::rectangle};
//! let k = rectangle(2, 1, [0.0, 2.0], [0.0, 1.0]).unwrap();
//! // FF = M₂M₂ᵀ: the two squares share 2 vertices.
//! let ff = k.lar().relation(Relation::FF).unwrap();
//! assert_eq!(ff.get(0, 1), Some(&2));
//! ```

use crate::error::{ComplexError, Result};
use crate::lar::Lar;
use sprs::CsMat;

/// One of the nine relations between vertices (V), edges (E) and faces
/// (F) of the paper. `XY` has a row per X-cell and a column per Y-cell:
///
/// | relation | matrix | entry (i, j) |
/// |---|---|---|
/// | VV | M₁ᵀM₁ | edges joining vertices i and j (diagonal: the degree) |
/// | VE, VF | M₁ᵀ, M₂ᵀ | 1 when vertex i is a vertex of cell j |
/// | EV, FV | M₁, M₂ | 1 when vertex j is a vertex of cell i |
/// | EE, EF, FE, FF | M_p M_qᵀ | vertices cell i and cell j share |
///
/// ```
/// use hasse_complex::relations::Relation;
/// assert_eq!(Relation::EF.dims(), (1, 2));
/// assert_eq!(Relation::ALL.len(), 9);
/// assert_eq!(Relation::FE.to_string(), "FE");
/// ```
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Relation {
    VV,
    VE,
    VF,
    EV,
    EE,
    EF,
    FV,
    FE,
    FF,
}

impl Relation {
    /// The nine relations, rows V, E, F in turn.
    pub const ALL: [Relation; 9] = [
        Relation::VV,
        Relation::VE,
        Relation::VF,
        Relation::EV,
        Relation::EE,
        Relation::EF,
        Relation::FV,
        Relation::FE,
        Relation::FF,
    ];

    /// (row dimension, column dimension).
    pub fn dims(self) -> (usize, usize) {
        match self {
            Relation::VV => (0, 0),
            Relation::VE => (0, 1),
            Relation::VF => (0, 2),
            Relation::EV => (1, 0),
            Relation::EE => (1, 1),
            Relation::EF => (1, 2),
            Relation::FV => (2, 0),
            Relation::FE => (2, 1),
            Relation::FF => (2, 2),
        }
    }
}

impl std::fmt::Display for Relation {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let letter = |p: usize| ['V', 'E', 'F'][p];
        let (p, q) = self.dims();
        write!(f, "{}{}", letter(p), letter(q))
    }
}

impl Lar {
    /// M_p with integer entries; M_0 is the identity (a vertex is its own
    /// only vertex).
    fn counting_characteristic(&self, p: usize) -> Result<CsMat<u32>> {
        if p == 0 {
            return Ok(CsMat::eye(self.cell_count(0)));
        }
        Ok(self.characteristic(p)?.map(|&x| u32::from(x)))
    }

    /// M_p M_qᵀ (|K_p| × |K_q|): entry (i, j) is the number of vertices
    /// p-cell i and q-cell j share, in ordinary integer arithmetic (not
    /// Z₂), so the LAR filtering rule can be applied to it.
    ///
    /// ```
    /// use hasse_complex::generate::rectangle;
    /// let k = rectangle(1, 1, [0.0, 1.0], [0.0, 1.0]).unwrap();
    /// let ef = k.lar().cell_product(1, 2).unwrap();
    /// // Every edge of the single square has both its vertices in it.
    /// assert!(ef.data().iter().all(|&c| c == 2));
    /// ```
    pub fn cell_product(&self, p: usize, q: usize) -> Result<CsMat<u32>> {
        let left = self.counting_characteristic(p)?;
        let right = self.counting_characteristic(q)?;
        Ok(&left * &right.transpose_view().to_csr())
    }

    /// One of the paper's nine relations (see [`Relation`]): VV is M₁ᵀM₁
    /// (adjacency through edges, degrees on the diagonal); every other XY
    /// is M_X M_Yᵀ with M_V the identity.
    ///
    /// ```
    /// use hasse_complex::{relations::Relation, generate::rectangle};
    /// let k = rectangle(1, 1, [0.0, 1.0], [0.0, 1.0]).unwrap();
    /// let vv = k.lar().relation(Relation::VV).unwrap();
    /// // Each corner of a square has degree 2.
    /// assert!((0..4).all(|v| vv.get(v, v) == Some(&2)));
    /// ```
    pub fn relation(&self, relation: Relation) -> Result<CsMat<u32>> {
        match relation {
            Relation::VV => {
                let m1 = self.counting_characteristic(1)?;
                Ok(&m1.transpose_view().to_csr() * &m1)
            }
            Relation::VE | Relation::VF => {
                let (_, q) = relation.dims();
                Ok(self.counting_characteristic(q)?.transpose_view().to_csr())
            }
            Relation::EV | Relation::FV => self.counting_characteristic(relation.dims().0),
            _ => {
                let (p, q) = relation.dims();
                self.cell_product(p, q)
            }
        }
    }

    /// The star St λ of a set λ of p-cells: for every dimension q = 0 …
    /// n, the sorted q-cells that share a vertex with some cell of λ, i.e.
    /// the support of [λ]ᵀ M_p M_qᵀ. On top cells this is the layer of
    /// neighbours a partition needs as ghosts.
    ///
    /// ```
    /// use hasse_complex::generate::rectangle;
    /// let k = rectangle(3, 1, [0.0, 3.0], [0.0, 1.0]).unwrap();
    /// let star = k.lar().star(2, &[0]).unwrap();
    /// // The first square touches itself and its right neighbour only.
    /// assert_eq!(star[2], vec![0, 1]);
    /// assert_eq!(star[0].len(), 4);
    /// ```
    pub fn star(&self, p: usize, cells: &[usize]) -> Result<Vec<Vec<usize>>> {
        if p > self.dim() {
            return Err(ComplexError::DimensionOutOfRange { p, dim: self.dim() });
        }
        let count = self.cell_count(p);
        if let Some(&bad) = cells.iter().find(|&&c| c >= count) {
            return Err(ComplexError::Invalid(format!(
                "star: {p}-cell {bad} does not exist (there are {count})"
            )));
        }
        let mut marked = vec![false; self.cell_count(0)];
        for &c in cells {
            for &v in self.cell_vertices(p, c) {
                marked[v] = true;
            }
        }
        let mut star = Vec::with_capacity(self.dim() + 1);
        star.push((0..marked.len()).filter(|&v| marked[v]).collect());
        for q in 1..=self.dim() {
            let members: Vec<usize> = (0..self.cell_count(q))
                .filter(|&j| self.cell_vertices(q, j).iter().any(|&v| marked[v]))
                .collect();
            star.push(members);
        }
        Ok(star)
    }
}

impl crate::Complex {
    /// ∂_p with `i32` entries, for products that may exceed `i8`.
    fn wide_boundary(&self, p: usize) -> Result<CsMat<i32>> {
        Ok(self.try_boundary(p)?.map(|&x| i32::from(x)))
    }

    /// [∂_{p+1}][δ_p] (|K_p| × |K_p|): adjacency of p-cells through the
    /// (p+1)-cells they bound, under the standard metric (seed 000,
    /// Appendix A). Zero for the top dimension.
    ///
    /// ```
    /// use hasse_complex::generate::interval;
    /// let k = interval(2, 0.0, 1.0).unwrap();
    /// // Vertices of a path: the graph Laplacian [[1,-1,0],[-1,2,-1],[0,-1,1]].
    /// let up = k.up_adjacency(0).unwrap();
    /// assert_eq!((up.get(1, 1), up.get(0, 1)), (Some(&2), Some(&-1)));
    /// ```
    pub fn up_adjacency(&self, p: usize) -> Result<CsMat<i32>> {
        if p > self.dim() {
            return Err(ComplexError::DimensionOutOfRange { p, dim: self.dim() });
        }
        if p == self.dim() {
            return Ok(CsMat::zero((self.cell_count(p), self.cell_count(p))));
        }
        let d = self.wide_boundary(p + 1)?;
        Ok(&d * &d.transpose_view().to_csr())
    }

    /// [δ_{p−1}][∂_p] (|K_p| × |K_p|): adjacency of p-cells through their
    /// common (p−1)-faces, under the standard metric. Zero for p = 0.
    ///
    /// ```
    /// use hasse_complex::generate::interval;
    /// let k = interval(2, 0.0, 1.0).unwrap();
    /// // The two edges share the middle vertex, with opposite signs.
    /// let down = k.down_adjacency(1).unwrap();
    /// assert_eq!((down.get(0, 0), down.get(0, 1)), (Some(&2), Some(&-1)));
    /// ```
    pub fn down_adjacency(&self, p: usize) -> Result<CsMat<i32>> {
        if p > self.dim() {
            return Err(ComplexError::DimensionOutOfRange { p, dim: self.dim() });
        }
        if p == 0 {
            return Ok(CsMat::zero((self.cell_count(0), self.cell_count(0))));
        }
        let d = self.wide_boundary(p)?;
        Ok(&d.transpose_view().to_csr() * &d)
    }

    /// The discrete Laplace–de Rham operator on p-cochains under the
    /// standard metric, [∂_{p+1}][δ_p] + [δ_{p−1}][∂_p]; the dimension of
    /// its kernel is the Betti number β_p.
    ///
    /// ```
    /// use hasse_complex::generate::rectangle;
    /// let k = rectangle(1, 1, [0.0, 1.0], [0.0, 1.0]).unwrap();
    /// let laplacian = k.laplace_de_rham(2).unwrap();
    /// assert_eq!(laplacian.get(0, 0), Some(&4)); // four edges
    /// ```
    pub fn laplace_de_rham(&self, p: usize) -> Result<CsMat<i32>> {
        Ok(&self.up_adjacency(p)? + &self.down_adjacency(p)?)
    }
}
