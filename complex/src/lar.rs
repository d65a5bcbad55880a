//! Linear Algebraic Representation: a complex as its characteristic
//! matrices M_p (p-cells × vertices, binary CSR), and the unoriented
//! boundary ∂_p read off the product M_{p-1} M_pᵀ.
//!
//! Entry (i, j) of M_{p-1} M_pᵀ counts the vertices that (p-1)-cell i and
//! p-cell j share; i lies on the boundary of j exactly when that count equals
//! the number of vertices of i (the LAR filtering rule).

use crate::cells::{FlatSets, Vertices};
use crate::error::{ComplexError, Result};
use rayon::prelude::*;
use sprs::{CsMat, TriMat};
use std::sync::Arc;

/// Vertex coordinates plus the characteristic matrices M_1 … M_n.
/// M_0 is the identity and is not stored.
///
/// The worked example of the LAR paper (two non-convex faces):
/// ```
/// use hasse_complex::{Lar, Vertices};
/// let v = Vertices::new(2, vec![0.0; 16]).unwrap();
/// let ev = vec![vec![0, 1], vec![0, 2], vec![0, 6], vec![1, 3], vec![2, 3],
///               vec![3, 5], vec![4, 5], vec![4, 6], vec![5, 7], vec![6, 7]];
/// let fv = vec![vec![0, 1, 3, 5, 6, 7], vec![0, 2, 3, 4, 5, 6]];
/// let lar = Lar::from_vertex_sets(v, vec![ev, fv]).unwrap();
/// let d2 = lar.unoriented_boundary(2).unwrap();
/// assert_eq!(d2.outer_view(2).unwrap().nnz(), 2); // edge (0,6) bounds both faces
/// ```
#[derive(Clone, Debug, PartialEq)]
pub struct Lar {
    vertices: Vertices,
    /// Shared, so that operators built on a cell's vertex list use it in place.
    characteristic: Vec<Arc<CsMat<u8>>>,
    /// 0..k0, so that rows of the identity M_0 can be borrowed like other rows.
    vertex_ids: Vec<usize>,
}

/// Build a binary CSR matrix from sorted vertex sets.
pub(crate) fn characteristic_matrix(sets: FlatSets, vertex_count: usize) -> CsMat<u8> {
    let rows = sets.len();
    let FlatSets { offsets, vertices } = sets;
    let indices = widen(&offsets, &vertices, false);
    drop(vertices);
    let nnz = indices.len();
    // Rows are sorted and in range by construction.
    CsMat::new((rows, vertex_count), offsets, indices, vec![1u8; nnz])
}

/// The vertex lists `vertices[offsets[i]..offsets[i + 1]]` as `usize`
/// column indices, each list sorted when `sort` is set; in parallel over
/// blocks of lists.
pub(crate) fn widen(offsets: &[usize], vertices: &[u32], sort: bool) -> Vec<usize> {
    const CHUNK: usize = 8192;
    let lists = offsets.len().saturating_sub(1);
    let mut out = vec![0usize; vertices.len()];
    let mut jobs = Vec::with_capacity(lists.div_ceil(CHUNK));
    let mut rest = out.as_mut_slice();
    for first in (0..lists).step_by(CHUNK) {
        let last = (first + CHUNK).min(lists);
        let (block, tail) = rest.split_at_mut(offsets[last] - offsets[first]);
        jobs.push((first, last, block));
        rest = tail;
    }
    jobs.into_par_iter().for_each(|(first, last, block)| {
        let base = offsets[first];
        for (slot, &v) in block.iter_mut().zip(&vertices[base..offsets[last]]) {
            *slot = v as usize;
        }
        if sort {
            for i in first..last {
                block[offsets[i] - base..offsets[i + 1] - base].sort_unstable();
            }
        }
    });
    out
}

impl Lar {
    /// A LAR from its characteristic matrices `[M_1, …, M_n]` (CSR, binary).
    pub fn new(vertices: Vertices, characteristic: Vec<CsMat<u8>>) -> Result<Self> {
        if characteristic.is_empty() {
            return Err(ComplexError::NoCells);
        }
        for (k, m) in characteristic.iter().enumerate() {
            if m.cols() != vertices.len() {
                return Err(ComplexError::CharacteristicShape {
                    p: k + 1,
                    expected: vertices.len(),
                    found: m.cols(),
                });
            }
        }
        let characteristic = characteristic
            .into_iter()
            .map(|m| Arc::new(if m.is_csr() { m } else { m.to_csr() }))
            .collect();
        Ok(Self {
            vertex_ids: (0..vertices.len()).collect(),
            vertices,
            characteristic,
        })
    }

    /// A LAR from vertex lists per dimension: `cells[p-1]` lists the p-cells.
    pub fn from_vertex_sets(vertices: Vertices, cells: Vec<Vec<Vec<usize>>>) -> Result<Self> {
        let k0 = vertices.len();
        let mut matrices = Vec::with_capacity(cells.len());
        for (k, level) in cells.iter().enumerate() {
            let mut sets = FlatSets {
                offsets: vec![0],
                vertices: Vec::new(),
            };
            for (j, cell) in level.iter().enumerate() {
                let mut set = Vec::with_capacity(cell.len());
                for &v in cell {
                    if v >= k0 {
                        return Err(ComplexError::VertexOutOfRange {
                            cell: j,
                            vertex: v,
                            vertex_count: k0,
                        });
                    }
                    set.push(v as u32);
                }
                set.sort_unstable();
                set.dedup();
                if set.len() != cell.len() {
                    return Err(ComplexError::Invalid(format!(
                        "{}-cell {j} lists a vertex more than once",
                        k + 1
                    )));
                }
                sets.vertices.extend(set);
                sets.offsets.push(sets.vertices.len());
            }
            matrices.push(characteristic_matrix(sets, k0));
        }
        Self::new(vertices, matrices)
    }

    /// Dimension n of the highest cells.
    pub fn dim(&self) -> usize {
        self.characteristic.len()
    }

    /// The vertices.
    pub fn vertices(&self) -> &Vertices {
        &self.vertices
    }

    /// Number of p-cells.
    pub fn cell_count(&self, p: usize) -> usize {
        match p {
            0 => self.vertices.len(),
            _ => self.characteristic.get(p - 1).map_or(0, |m| m.rows()),
        }
    }

    /// M_p for p ≥ 1 (p-cells × vertices).
    pub fn characteristic(&self, p: usize) -> Result<&CsMat<u8>> {
        if p == 0 || p > self.dim() {
            return Err(ComplexError::DimensionOutOfRange { p, dim: self.dim() });
        }
        Ok(&self.characteristic[p - 1])
    }

    /// M_p, shared (see [`Lar::characteristic`]).
    pub fn shared_characteristic(&self, p: usize) -> Result<Arc<CsMat<u8>>> {
        self.characteristic(p)?;
        Ok(Arc::clone(&self.characteristic[p - 1]))
    }

    /// The edges' vertex pairs as one flat slice (edge e is entries 2e and
    /// 2e + 1, lower vertex first): M₁'s own column indices, when every row
    /// of M₁ holds exactly two entries. `None` for a complex without edges
    /// or with an edge that is not a vertex pair.
    ///
    /// ```
    /// use hasse_complex::generate::rectangle;
    /// let k = rectangle(1, 1, [0.0, 1.0], [0.0, 1.0]).unwrap();
    /// let pairs = k.lar().edge_vertex_pairs().unwrap();
    /// assert_eq!(pairs.len(), 2 * 4);
    /// assert!(pairs.chunks(2).all(|e| e[0] < e[1]));
    /// ```
    pub fn edge_vertex_pairs(&self) -> Option<&[usize]> {
        let edges = self.characteristic.first()?;
        let indptr = edges.indptr();
        // A parallel check: on a 10⁶-cell mesh M₁ has 2·10⁶ rows.
        let uniform = indptr.raw_storage().first() == Some(&0)
            && (0..=edges.rows())
                .into_par_iter()
                .all(|e| indptr.index(e) == 2 * e);
        uniform.then(|| &edges.indices()[..2 * edges.rows()])
    }

    /// Sorted vertices of p-cell `i`.
    #[inline]
    pub fn cell_vertices(&self, p: usize, i: usize) -> &[usize] {
        if p == 0 {
            // Row i of the identity M_0.
            return &self.vertex_ids[i..i + 1];
        }
        let m = &self.characteristic[p - 1];
        let range = m.indptr().outer_inds_sz(i);
        &m.indices()[range]
    }

    /// M_{p-1} M_pᵀ: shared-vertex counts between (p-1)-cells and p-cells.
    pub fn incidence_counts(&self, p: usize) -> Result<CsMat<u32>> {
        let upper = self.characteristic(p)?.map(|&x| u32::from(x));
        let lower = if p == 1 {
            CsMat::eye(self.vertices.len())
        } else {
            self.characteristic(p - 1)?.map(|&x| u32::from(x))
        };
        Ok(&lower * &upper.transpose_view().to_csr())
    }

    /// The unoriented ∂_p: entries of M_{p-1} M_pᵀ equal to the vertex count
    /// of the (p-1)-cell become 1, all others 0.
    pub fn unoriented_boundary(&self, p: usize) -> Result<CsMat<u8>> {
        let counts = self.incidence_counts(p)?;
        let mut tri = TriMat::new(counts.shape());
        for (row, vec) in counts.outer_iterator().enumerate() {
            let size = self.cell_vertices(p - 1, row).len() as u32;
            for (col, &c) in vec.iter() {
                if c == size {
                    tri.add_triplet(row, col, 1u8);
                }
            }
        }
        Ok(tri.to_csr())
    }

    /// Vertex → p-cells map (M_pᵀ in CSR), used by the filtered product.
    pub(crate) fn cells_by_vertex(&self, p: usize) -> CsMat<u8> {
        self.characteristic[p - 1].transpose_view().to_csr()
    }

    /// Vertex → p-cells lists (M_pᵀ as CSR pattern, 32-bit cell ids): a
    /// counting-sort transpose of M_p with no values and no sprs
    /// conversion, cells listed in increasing order.
    fn star_lists(&self, p: usize) -> (Vec<usize>, Vec<u32>) {
        let m = &self.characteristic[p - 1];
        let mut start = vec![0usize; self.vertices.len() + 1];
        for &v in m.indices() {
            start[v + 1] += 1;
        }
        for v in 0..self.vertices.len() {
            start[v + 1] += start[v];
        }
        let mut cells = vec![0u32; m.nnz()];
        // start[v] serves as v's cursor and ends at v's end, the start of
        // v + 1: shifting by one slot restores the pointers.
        for (j, row) in m.indptr().raw_storage().windows(2).enumerate() {
            for &v in &m.indices()[row[0]..row[1]] {
                cells[start[v]] = j as u32;
                start[v] += 1;
            }
        }
        start.rotate_right(1);
        start[0] = 0;
        (start, cells)
    }

    /// Sparsity pattern of the unoriented ∂_p as CSR (indptr, column
    /// indices), computed row by row as the filtered product M_{p-1} M_pᵀ.
    #[cfg(test)]
    pub(crate) fn boundary_pattern(&self, p: usize) -> (Vec<usize>, Vec<usize>) {
        let (indptr, indices, _) = self
            .boundary_pattern_with(p, |_, columns, out: &mut Vec<()>| {
                out.extend(columns.iter().map(|_| ()));
                Ok(())
            })
            .unwrap_or_default();
        (indptr, indices)
    }

    /// The unoriented ∂_p as CSR (indptr, column indices) together with one
    /// value per entry: `value(i, columns, out)` appends to `out` the values
    /// of row i, whose column indices are `columns`. Rows are the filtered
    /// product M_{p-1} M_pᵀ: every p-cell containing (p-1)-cell i contains
    /// its first vertex, so only the p-cells around that vertex can reach
    /// the full count. Blocks of rows run in parallel; the blocks are then
    /// copied, also in parallel, into the final arrays.
    pub(crate) fn boundary_pattern_with<T, F>(
        &self,
        p: usize,
        value: F,
    ) -> Result<(Vec<usize>, Vec<usize>, Vec<T>)>
    where
        T: Copy + Default + Send + Sync,
        F: Fn(usize, &[u32], &mut Vec<T>) -> Result<()> + Sync,
    {
        const CHUNK: usize = 8192;
        let (star_ptr, star_cells) = self.star_lists(p);
        let upper = &self.characteristic[p - 1];
        let rows = self.cell_count(p - 1);
        type Block<T> = (Vec<u32>, Vec<u32>, Vec<T>);
        let blocks: Vec<Block<T>> = (0..rows.div_ceil(CHUNK))
            .into_par_iter()
            .map(|chunk| {
                let mut lengths = Vec::with_capacity(CHUNK);
                let mut entries: Vec<u32> = Vec::with_capacity(CHUNK * 2);
                let mut values = Vec::with_capacity(CHUNK * 2);
                for i in chunk * CHUNK..((chunk + 1) * CHUNK).min(rows) {
                    let before = entries.len();
                    let lower = self.cell_vertices(p - 1, i);
                    if let Some(&first) = lower.first() {
                        let star = &star_cells[star_ptr[first]..star_ptr[first + 1]];
                        entries.extend(star.iter().copied().filter(|&j| {
                            let cell = &upper.indices()[upper.indptr().outer_inds_sz(j as usize)];
                            lower[1..].iter().all(|v| cell.binary_search(v).is_ok())
                        }));
                    }
                    value(i, &entries[before..], &mut values)?;
                    lengths.push((entries.len() - before) as u32);
                }
                Ok((lengths, entries, values))
            })
            .collect::<Result<_>>()?;
        drop((star_ptr, star_cells));
        let nnz: usize = blocks.iter().map(|b| b.1.len()).sum();
        let mut indptr = vec![0usize; rows + 1];
        let mut indices = vec![0usize; nnz];
        let mut data = vec![T::default(); nnz];
        let mut jobs = Vec::with_capacity(blocks.len());
        let (mut p_rest, mut i_rest, mut d_rest) = (
            &mut indptr[1..],
            indices.as_mut_slice(),
            data.as_mut_slice(),
        );
        let mut base = 0;
        for block in &blocks {
            let (ptr, p_tail) = p_rest.split_at_mut(block.0.len());
            let (ind, i_tail) = i_rest.split_at_mut(block.1.len());
            let (dat, d_tail) = d_rest.split_at_mut(block.1.len());
            (p_rest, i_rest, d_rest) = (p_tail, i_tail, d_tail);
            jobs.push((block, base, ptr, ind, dat));
            base += block.1.len();
        }
        jobs.into_par_iter()
            .for_each(|((lengths, entries, values), base, ptr, ind, dat)| {
                let mut end = base;
                for (slot, &len) in ptr.iter_mut().zip(lengths) {
                    end += len as usize;
                    *slot = end;
                }
                for (slot, &j) in ind.iter_mut().zip(entries) {
                    *slot = j as usize;
                }
                dat.copy_from_slice(values);
            });
        Ok((indptr, indices, data))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The worked example of the LAR paper (Figure 2d): two non-convex faces.
    fn paper_example() -> Lar {
        let v = Vertices::new(2, vec![0.0; 16]).unwrap();
        let ev = vec![
            vec![0, 1],
            vec![0, 2],
            vec![0, 6],
            vec![1, 3],
            vec![2, 3],
            vec![3, 5],
            vec![4, 5],
            vec![4, 6],
            vec![5, 7],
            vec![6, 7],
        ];
        let fv = vec![vec![0, 1, 3, 5, 6, 7], vec![0, 2, 3, 4, 5, 6]];
        Lar::from_vertex_sets(v, vec![ev, fv]).unwrap()
    }

    #[test]
    fn lar_paper_incidence_counts() {
        let counts = paper_example().incidence_counts(2).unwrap().to_dense();
        // [EF]ᵀ as printed in the paper.
        let expected_t = [
            [2u32, 1, 2, 2, 1, 2, 1, 1, 2, 2],
            [1, 2, 2, 1, 2, 2, 2, 2, 1, 1],
        ];
        for (face, row) in expected_t.iter().enumerate() {
            for (edge, &c) in row.iter().enumerate() {
                assert_eq!(counts[[edge, face]], c, "edge {edge}, face {face}");
            }
        }
    }

    #[test]
    fn lar_paper_unoriented_boundary_and_total_boundary_chain() {
        let lar = paper_example();
        let d2 = lar.unoriented_boundary(2).unwrap().to_dense();
        let expected_t = [
            [1u8, 0, 1, 1, 0, 1, 0, 0, 1, 1],
            [0, 1, 1, 0, 1, 1, 1, 1, 0, 0],
        ];
        for (face, row) in expected_t.iter().enumerate() {
            for (edge, &b) in row.iter().enumerate() {
                assert_eq!(d2[[edge, face]], b, "edge {edge}, face {face}");
            }
        }
        // [∂2][Λ2] mod 2 = {e0, e1, e3, e4, e6, e7, e8, e9}.
        let total: Vec<u8> = (0..10).map(|e| (d2[[e, 0]] + d2[[e, 1]]) % 2).collect();
        assert_eq!(total, vec![1, 1, 0, 1, 1, 0, 1, 1, 1, 1]);
    }

    #[test]
    fn fused_pattern_equals_filtered_product() {
        let lar = paper_example();
        for p in 1..=2 {
            let (indptr, indices) = lar.boundary_pattern(p);
            let filtered = lar.unoriented_boundary(p).unwrap();
            assert_eq!(indptr, filtered.indptr().raw_storage());
            assert_eq!(indices, filtered.indices());
        }
    }
}
