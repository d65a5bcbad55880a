//! Fill-reducing orderings of a symmetric sparsity pattern.
//!
//! faer's sparse Cholesky orders by approximate minimum degree (AMD) unless
//! it is handed a permutation. AMD is a greedy, local rule; on the graphs of
//! three-dimensional meshes it leaves much more fill than nested dissection,
//! which splits the graph by small vertex separators and numbers the
//! separators last, so the factor's fill stays inside the separator blocks.
//! [`nested_dissection`] computes that ordering with METIS
//! (`METIS_NodeND`, built from source by the `metis-sys` crate) and returns
//! it as a faer [`Perm`], ready for
//! `SymmetricOrdering::Custom` (see [`crate::linear::Ordering`]).
//!
//! The permutation follows faer's (and METIS's) convention: `forward[k]` is
//! the original index of the k-th pivot and `inverse[i]` the position of
//! original index i, so the factorised matrix is A(forward, forward).

use faer::perm::Perm;
use faer::sparse::SymbolicSparseColMatRef;
use metis_sys as metis;

/// Largest adjacency (sum of vertex degrees) METIS can index: the vendored
/// METIS uses 32-bit `idx_t`.
pub const METIS_MAX_ENTRIES: usize = i32::MAX as usize;

/// Why an ordering could not be computed.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum OrderingError {
    #[error("the pattern is {rows}×{cols}; a symmetric ordering needs a square pattern")]
    NotSquare { rows: usize, cols: usize },
    #[error("the matrix graph has {vertices} vertices and {entries} adjacency entries; METIS indexes with 32-bit integers and takes at most {limit} of each. Use the AMD ordering for systems this large")]
    TooLarge {
        vertices: usize,
        entries: usize,
        limit: usize,
    },
    #[error("METIS nested dissection failed: {0}")]
    Metis(&'static str),
}

/// The adjacency graph of a symmetric pattern in METIS's CSR form: the
/// neighbours of vertex v are `adjncy[xadj[v]..xadj[v + 1]]`, sorted, without
/// v itself and without repeats.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Adjacency {
    /// Offsets, length n + 1.
    pub xadj: Vec<i32>,
    /// Neighbour lists, concatenated.
    pub adjncy: Vec<i32>,
}

impl Adjacency {
    /// The graph of the pattern of A + Aᵀ without the diagonal: an entry
    /// stored in either triangle (or both) is one edge, so a matrix stored
    /// whole and one stored as a single triangle give the same graph.
    ///
    /// ```
    /// use faer::sparse::{SparseColMat, Triplet};
    /// use hasse_solver::ordering::Adjacency;
    /// // Lower triangle of tridiag(−1, 2, −1), n = 3.
    /// let t = [(0, 0, 2.0), (1, 0, -1.0), (1, 1, 2.0), (2, 1, -1.0), (2, 2, 2.0)];
    /// let t: Vec<_> = t.iter().map(|&(i, j, v)| Triplet::new(i, j, v)).collect();
    /// let a = SparseColMat::<usize, f64>::try_new_from_triplets(3, 3, &t).unwrap();
    /// let g = Adjacency::of_pattern(a.symbolic()).unwrap();
    /// assert_eq!(g.xadj, [0, 1, 3, 4]);
    /// assert_eq!(g.adjncy, [1, 0, 2, 1]);
    /// ```
    pub fn of_pattern(pattern: SymbolicSparseColMatRef<'_, usize>) -> Result<Self, OrderingError> {
        let (rows, cols) = (pattern.nrows(), pattern.ncols());
        if rows != cols {
            return Err(OrderingError::NotSquare { rows, cols });
        }
        let n = cols;
        let too_large = |entries| OrderingError::TooLarge {
            vertices: n,
            entries,
            limit: METIS_MAX_ENTRIES,
        };
        if n > METIS_MAX_ENTRIES {
            return Err(too_large(0));
        }
        let row_idx = pattern.row_idx();
        // Every stored off-diagonal entry (i, j) is written under i and
        // under j; a symmetric matrix stored whole writes each edge twice per
        // vertex, removed by the sort-and-dedup below. Offsets are counted
        // in usize so the 32-bit check sees the true size.
        let mut start = vec![0usize; n + 1];
        for j in 0..n {
            for &i in &row_idx[pattern.col_range(j)] {
                if i != j {
                    start[i + 1] += 1;
                    start[j + 1] += 1;
                }
            }
        }
        for v in 0..n {
            start[v + 1] += start[v];
        }
        let mut next = start.clone();
        let mut adjncy = vec![0i32; start[n]];
        for j in 0..n {
            for &i in &row_idx[pattern.col_range(j)] {
                if i != j {
                    // i, j < n ≤ i32::MAX (checked above).
                    adjncy[next[i]] = j as i32;
                    next[i] += 1;
                    adjncy[next[j]] = i as i32;
                    next[j] += 1;
                }
            }
        }
        let mut xadj = Vec::with_capacity(n + 1);
        xadj.push(0i32);
        let mut write = 0usize;
        for v in 0..n {
            let list = &mut adjncy[start[v]..start[v + 1]];
            list.sort_unstable();
            let mut last = -1i32;
            for k in start[v]..start[v + 1] {
                let u = adjncy[k];
                if u != last {
                    adjncy[write] = u;
                    write += 1;
                    last = u;
                }
            }
            xadj.push(i32::try_from(write).map_err(|_| too_large(write))?);
        }
        adjncy.truncate(write);
        Ok(Self { xadj, adjncy })
    }

    /// Number of vertices.
    pub fn vertices(&self) -> usize {
        self.xadj.len().saturating_sub(1)
    }
}

/// The METIS nested-dissection ordering of a symmetric pattern (either
/// triangle or both may be stored; the diagonal is ignored).
///
/// Vertices without neighbours and several connected components are
/// allowed; a pattern with no off-diagonal entry (n = 0 and n = 1 included)
/// needs no ordering and gets the identity. METIS is seeded with a fixed
/// value, so the ordering is the same on every run.
///
/// ```
/// use faer::sparse::{SparseColMat, Triplet};
/// use hasse_solver::ordering::nested_dissection;
/// // The five-point Laplacian's pattern on a 20×20 grid.
/// let m = 20;
/// let mut t = Vec::new();
/// for j in 0..m * m {
///     t.push(Triplet::new(j, j, 4.0));
///     if j % m + 1 < m { t.push(Triplet::new(j + 1, j, -1.0)); }
///     if j + m < m * m { t.push(Triplet::new(j + m, j, -1.0)); }
/// }
/// let a = SparseColMat::<usize, f64>::try_new_from_triplets(m * m, m * m, &t).unwrap();
/// let perm = nested_dissection(a.symbolic()).unwrap();
/// let (forward, inverse) = perm.arrays();
/// assert!((0..m * m).all(|k| inverse[forward[k]] == k));
/// ```
pub fn nested_dissection(
    pattern: SymbolicSparseColMatRef<'_, usize>,
) -> Result<Perm<usize>, OrderingError> {
    let mut graph = Adjacency::of_pattern(pattern)?;
    let n = graph.vertices();
    if graph.adjncy.is_empty() {
        // METIS has nothing to separate (and older releases mishandle a
        // graph without edges): every order gives a diagonal factor.
        let identity: Box<[usize]> = (0..n).collect();
        return Ok(Perm::new_checked(identity.clone(), identity, n));
    }
    let mut options = [0 as metis::idx_t; metis::METIS_NOPTIONS as usize];
    let mut nvtxs = graph.xadj.len() as metis::idx_t - 1;
    let mut perm = vec![0 as metis::idx_t; n];
    let mut iperm = vec![0 as metis::idx_t; n];
    // SAFETY: `options` has METIS_NOPTIONS entries; xadj has nvtxs + 1
    // nondecreasing offsets into adjncy, every neighbour lies in 0..nvtxs
    // and differs from its vertex (Adjacency::of_pattern), perm and iperm
    // have nvtxs entries, and vwgt may be null. METIS keeps no pointer past
    // the call.
    let status = unsafe {
        metis::METIS_SetDefaultOptions(options.as_mut_ptr());
        options[metis::moptions_et_METIS_OPTION_NUMBERING as usize] = 0;
        metis::METIS_NodeND(
            &mut nvtxs,
            graph.xadj.as_mut_ptr(),
            graph.adjncy.as_mut_ptr(),
            std::ptr::null_mut(),
            options.as_mut_ptr(),
            perm.as_mut_ptr(),
            iperm.as_mut_ptr(),
        )
    };
    match status {
        metis::rstatus_et_METIS_OK => {}
        metis::rstatus_et_METIS_ERROR_INPUT => return Err(OrderingError::Metis("invalid input")),
        metis::rstatus_et_METIS_ERROR_MEMORY => return Err(OrderingError::Metis("out of memory")),
        _ => return Err(OrderingError::Metis("unspecified error")),
    }
    // METIS's perm[k] is the original vertex in position k (faer's
    // forward). Both arrays are checked rather than trusted, so a bad
    // result is an error here and not a panic in faer.
    let forward: Box<[usize]> = perm.iter().map(|&v| v as usize).collect();
    let inverse: Box<[usize]> = iperm.iter().map(|&v| v as usize).collect();
    let consistent = forward.iter().enumerate().all(|(k, &v)| {
        v < n && inverse[v] == k // inverse[forward[k]] = k for all k ⇒ bijection
    });
    if !consistent {
        return Err(OrderingError::Metis("returned an invalid permutation"));
    }
    Ok(Perm::new_checked(forward, inverse, n))
}

#[cfg(test)]
mod tests {
    use super::*;
    use faer::sparse::{SparseColMat, SymbolicSparseColMat};

    /// A symbolic pattern from (row, col) pairs.
    fn pattern(n: usize, entries: &[(usize, usize)]) -> SymbolicSparseColMat<usize> {
        let mut cols: Vec<Vec<usize>> = vec![Vec::new(); n];
        for &(i, j) in entries {
            cols[j].push(i);
        }
        let mut col_ptr = vec![0];
        let mut row_idx = Vec::new();
        for mut c in cols {
            c.sort_unstable();
            c.dedup();
            row_idx.extend(c);
            col_ptr.push(row_idx.len());
        }
        SymbolicSparseColMat::new_checked(n, n, col_ptr, None, row_idx)
    }

    fn assert_bijection(perm: &Perm<usize>, n: usize) {
        let (forward, inverse) = perm.arrays();
        assert_eq!((forward.len(), inverse.len()), (n, n));
        let mut seen = vec![false; n];
        for (k, &v) in forward.iter().enumerate() {
            assert!(v < n && !seen[v], "{forward:?}");
            seen[v] = true;
            assert_eq!(inverse[v], k);
        }
    }

    #[test]
    fn whole_and_one_triangle_patterns_give_the_same_graph() {
        // A 4-cycle 0-1-2-3-0 with a diagonal.
        let edges = [(1, 0), (2, 1), (3, 2), (3, 0)];
        let mut lower: Vec<(usize, usize)> = edges.to_vec();
        lower.extend((0..4).map(|i| (i, i)));
        let mut whole = lower.clone();
        whole.extend(edges.iter().map(|&(i, j)| (j, i)));
        let upper: Vec<(usize, usize)> = lower.iter().map(|&(i, j)| (j, i)).collect();
        let expected = Adjacency {
            xadj: vec![0, 2, 4, 6, 8],
            adjncy: vec![1, 3, 0, 2, 1, 3, 0, 2],
        };
        for entries in [&lower, &whole, &upper] {
            let p = pattern(4, entries);
            assert_eq!(Adjacency::of_pattern(p.as_ref()).unwrap(), expected);
        }
    }

    #[test]
    fn nested_dissection_is_a_bijection_on_small_and_disconnected_graphs() {
        // n = 0, n = 1, a diagonal-only pattern: the identity.
        for n in [0, 1, 5] {
            let diagonal: Vec<(usize, usize)> = (0..n).map(|i| (i, i)).collect();
            let perm = nested_dissection(pattern(n, &diagonal).as_ref()).unwrap();
            assert_bijection(&perm, n);
            assert_eq!(perm.arrays().0, (0..n).collect::<Vec<_>>().as_slice());
        }
        // Two paths of 150 vertices (large enough for METIS to bisect
        // rather than hand the graph to minimum degree), three isolated
        // vertices between and after them, a triangle.
        let mut entries = Vec::new();
        let n = 150 + 2 + 150 + 1 + 3;
        for i in 0..n {
            entries.push((i, i));
        }
        for i in 0..149 {
            entries.push((i + 1, i));
            entries.push((152 + i + 1, 152 + i));
        }
        entries.extend([(304, 303), (305, 304), (305, 303)]);
        let perm = nested_dissection(pattern(n, &entries).as_ref()).unwrap();
        assert_bijection(&perm, n);
    }

    #[test]
    fn a_path_is_ordered_with_its_middle_last() {
        // Nested dissection numbers the top-level separator last; an end
        // of a path separates nothing, so the last pivot is interior.
        // (Minimum degree would end on whichever vertex remains, often an
        // end.)
        let n = 400;
        let mut entries: Vec<(usize, usize)> = (0..n).map(|i| (i, i)).collect();
        entries.extend((0..n - 1).map(|i| (i + 1, i)));
        let p = pattern(n, &entries);
        let perm = nested_dissection(p.as_ref()).unwrap();
        assert_bijection(&perm, n);
        let last = perm.arrays().0[n - 1];
        assert!(last > 0 && last < n - 1, "last pivot {last}");
    }

    #[test]
    fn non_square_patterns_are_refused() {
        let a = SparseColMat::<usize, f64>::try_new_from_triplets(2, 3, &[]).unwrap();
        assert_eq!(
            nested_dissection(a.symbolic()).unwrap_err(),
            OrderingError::NotSquare { rows: 2, cols: 3 }
        );
    }
}
