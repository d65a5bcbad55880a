//! The matrix form of the make operators and the Hasse transformation η
//! (seed 000 §4.2 and §5; thesis §4.4).
//!
//! The paper writes β^q, which splits a (q+1)-cell c by a new q-cell N, as
//! matrices acting on the coboundaries δ_j = ∂_{j+1}ᵀ, but prints them only
//! for one triangle (Examples 7–10). Here they are built in general. With
//! p = q + 1 the dimension of the split cell (the argument of
//! [`make`](crate::euler::make)), ρ = Σ_{f moved} s_f f the moved part of
//! ∂c, c′ the appended piece (index k_p) and N the appended (p−1)-cell
//! (index k_{p−1}):
//!
//! - δ_p (K_{p+1} × K_p) gains the column of c′: δ̃_p = δ_p C with
//!   C = [I | e_c] (k_p × (k_p+1)); every coface of c gets c′ with c's sign.
//! - δ_{p−2} (K_{p−1} × K_{p−2}, p ≥ 2) gains the row of N:
//!   δ̃_{p−2} = R δ_{p−2} with R = [I ; ρᵀ] ((k_{p−1}+1) × k_{p−1}), since
//!   ∂N = ∂ρ.
//! - δ_{p−1} (K_p × K_{p−1}) gains both: δ̃_{p−1} = Σ_{i=1}^{3} S_i δ_{p−1} T_i
//!   with the (k_p+1) × k_p matrices S_1 = e_c e_cᵀ, S_2 = e_{c′} e_cᵀ,
//!   S_3 = Σ_{j≠c} e_j e_jᵀ (term 1 the old-index piece, term 2 the new
//!   piece, term 3 every other p-cell) and the k_{p−1} × (k_{p−1}+1)
//!   matrices
//!   T_1 = Σ_{f∉ρ} e_f e_fᵀ + ν s_{f₀} e_{f₀} e_Nᵀ,
//!   T_2 = Σ_{f∈ρ} e_f e_fᵀ − ν s_{f₀} e_{f₀} e_Nᵀ,
//!   T_3 = Σ_f e_f e_fᵀ,
//!   where f₀ is the first moved facet and ν the coefficient of N in ∂c̃
//!   (1 for p ≥ 2; the sign of the moved endpoint for p = 1). Row c of
//!   δ_{p−1} is ∂cᵀ, which has s_{f₀} at f₀, so S_1 δ T_1 puts
//!   (∂c − ρ + νN)ᵀ in row c and S_2 δ T_2 puts (ρ − νN)ᵀ in row c′: the
//!   N-column entry of T_1 and T_2 only ever meets row c, which is why one
//!   moved facet is enough to carry it.
//!
//! The three families are the chain map ζ of the make read as matrices:
//! S_1 + S_2 + S_3 = ζ_p, T_3 = T_1 + T_2 = ζ_{p−1}ᵀ and C = ζ_pᵀ.
//!
//! The Hasse transformation η acts on the whole Hasse matrix H (rows K_1,
//! K_3, …, columns K_0, K_2, …; [`hasse_matrix`]): each block is
//! transformed by the matrices above (the paper's β^p(H) = β^p(H_1) +
//! β^p(H_2), the diagonal and the upper blocks separately) and H grows by
//! one row and one column, so χ = columns − rows does not change. The
//! upper blocks of H hold transposes, δ_jᵀ, so there a row gained is
//! Cᵀ δ_jᵀ and a column gained δ_jᵀ Rᵀ: the paper's Remark 1 writes these
//! as "R[δ1]ᵀ" (β0) and "[δ1]ᵀC" (β2).

use crate::error::SplitError;
use crate::euler::{hasse_matrix, plan};
use sprs::{CsMat, TriMat};

/// The matrices C, R, S_1..S_3 and T_1..T_3 of one make operator β^{p−1}.
///
/// Built from the same arguments as [`make`](crate::euler::make); applying
/// them to the coboundaries ([`MakeMatrices::coboundaries`]) or to the Hasse
/// matrix ([`MakeMatrices::hasse`]) gives what `make` gives.
///
/// ```
/// use hasse_complex::hasse_transform::MakeMatrices;
/// use sprs::CsMat;
/// // One edge v0 → v1 (∂_1 = [−1; 1]); β⁰ splits it, the head moves.
/// let d1 = CsMat::new((2, 1), vec![0, 1, 2], vec![0, 0], vec![-1i8, 1]);
/// let m = MakeMatrices::new(&[d1], 1, 0, &[1]).unwrap();
/// // C = [I | e_0]: the new edge is a second copy of edge 0 for its cofaces.
/// assert_eq!(m.c().to_dense().as_slice().unwrap(), &[1, 1]);
/// assert!(m.r().is_none()); // there is no δ_{−1}
/// ```
#[derive(Clone, Debug, PartialEq)]
pub struct MakeMatrices {
    p: usize,
    counts: Vec<usize>,
    c: CsMat<i8>,
    r: Option<CsMat<i8>>,
    s: [CsMat<i8>; 3],
    t: [CsMat<i8>; 3],
}

/// A CSR matrix from (row, column, value) triplets.
fn matrix(
    shape: (usize, usize),
    entries: impl IntoIterator<Item = (usize, usize, i8)>,
) -> CsMat<i8> {
    let mut t = TriMat::new(shape);
    for (i, j, v) in entries {
        t.add_triplet(i, j, v);
    }
    t.to_csr()
}

/// Drops the explicit zeros a sparse product leaves where terms cancel
/// (∂ρ cancels at the inner faces of ρ), so results compare equal to
/// matrices that never stored them.
fn prune(m: CsMat<i8>) -> CsMat<i8> {
    if m.data().iter().all(|&v| v != 0) {
        return m;
    }
    matrix(
        m.shape(),
        m.iter()
            .filter(|(&v, _)| v != 0)
            .map(|(&v, (i, j))| (i, j, v)),
    )
}

impl MakeMatrices {
    /// The matrices of β^{p−1} splitting p-cell `cell`, the facets `moved`
    /// going to the appended piece (the arguments and errors of
    /// [`make`](crate::euler::make)).
    ///
    /// ```
    /// use hasse_complex::hasse_transform::MakeMatrices;
    /// use sprs::CsMat;
    /// let d1 = CsMat::new((2, 1), vec![0, 1, 2], vec![0, 0], vec![-1i8, 1]);
    /// // Vertex 2 is not on edge 0.
    /// assert!(MakeMatrices::new(&[d1], 1, 0, &[2]).is_err());
    /// ```
    pub fn new(
        boundaries: &[CsMat<i8>],
        p: usize,
        cell: usize,
        moved: &[usize],
    ) -> Result<Self, SplitError> {
        let plan = plan(boundaries, p, cell, moved)?;
        let counts = plan.counts;
        let (kp, kf) = (counts[p], counts[p - 1]);
        let (piece, new_face) = (kp, kf);
        let c = matrix(
            (kp, kp + 1),
            (0..kp).map(|j| (j, j, 1)).chain([(cell, piece, 1)]),
        );
        let r = (p >= 2).then(|| {
            matrix(
                (kf + 1, kf),
                (0..kf)
                    .map(|f| (f, f, 1))
                    .chain(plan.moving.iter().map(|&(f, s)| (new_face, f, s))),
            )
        });
        let s = [
            matrix((kp + 1, kp), [(cell, cell, 1)]),
            matrix((kp + 1, kp), [(piece, cell, 1)]),
            matrix(
                (kp + 1, kp),
                (0..kp).filter(|&j| j != cell).map(|j| (j, j, 1)),
            ),
        ];
        let is_moved = |f: usize| plan.moving.binary_search_by_key(&f, |&(g, _)| g).is_ok();
        // `plan` guarantees at least one moved facet.
        let (f0, s0) = plan.moving[0];
        let carry = plan.nu * s0;
        let t = [
            matrix(
                (kf, kf + 1),
                (0..kf)
                    .filter(|&f| !is_moved(f))
                    .map(|f| (f, f, 1))
                    .chain([(f0, new_face, carry)]),
            ),
            matrix(
                (kf, kf + 1),
                plan.moving
                    .iter()
                    .map(|&(f, _)| (f, f, 1))
                    .chain([(f0, new_face, -carry)]),
            ),
            matrix((kf, kf + 1), (0..kf).map(|f| (f, f, 1))),
        ];
        Ok(MakeMatrices {
            p,
            counts,
            c,
            r,
            s,
            t,
        })
    }

    /// C = [I | e_c], k_p × (k_p + 1): δ̃_p = δ_p C (the paper's Example 8).
    /// It is ζ_pᵀ, so it is returned also when p = n and δ_p does not exist.
    ///
    /// ```
    /// use hasse_complex::hasse_transform::MakeMatrices;
    /// use sprs::CsMat;
    /// let d1 = CsMat::new((2, 1), vec![0, 1, 2], vec![0, 0], vec![-1i8, 1]);
    /// assert_eq!(MakeMatrices::new(&[d1], 1, 0, &[1]).unwrap().c().shape(), (1, 2));
    /// ```
    pub fn c(&self) -> &CsMat<i8> {
        &self.c
    }

    /// R = [I ; ρᵀ], (k_{p−1} + 1) × k_{p−1}: δ̃_{p−2} = R δ_{p−2} (the
    /// paper's Example 9). `None` for p = 1, where there is no δ_{−1}.
    ///
    /// ```
    /// use hasse_complex::hasse_transform::MakeMatrices;
    /// use sprs::CsMat;
    /// // A triangle v0 v1 v2 with edges v0→v1, v1→v2, v0→v2 and ∂f = e0 + e1 − e2;
    /// // split it moving e1 and e2: ρ = e1 − e2.
    /// let d1 = CsMat::new_csc((3, 3), vec![0, 2, 4, 6], vec![0, 1, 1, 2, 0, 2],
    ///                         vec![-1i8, 1, -1, 1, -1, 1]).to_csr();
    /// let d2 = CsMat::new((3, 1), vec![0, 1, 2, 3], vec![0, 0, 0], vec![1i8, 1, -1]);
    /// let m = MakeMatrices::new(&[d1, d2], 2, 0, &[1, 2]).unwrap();
    /// let r = m.r().unwrap().to_dense();
    /// assert_eq!(r.row(3).to_vec(), vec![0, 1, -1]);
    /// ```
    pub fn r(&self) -> Option<&CsMat<i8>> {
        self.r.as_ref()
    }

    /// S_i (i = 1, 2, 3), (k_p + 1) × k_p: which row of δ_{p−1} goes where
    /// (the paper's Example 7). Returns `None` unless 1 ≤ i ≤ 3.
    ///
    /// ```
    /// use hasse_complex::hasse_transform::MakeMatrices;
    /// use sprs::CsMat;
    /// let d1 = CsMat::new((2, 1), vec![0, 1, 2], vec![0, 0], vec![-1i8, 1]);
    /// let m = MakeMatrices::new(&[d1], 1, 0, &[1]).unwrap();
    /// // S_2 sends the split edge's row to the appended edge's row.
    /// assert_eq!(m.s(2).unwrap().to_dense().as_slice().unwrap(), &[0, 1]);
    /// assert!(m.s(4).is_none());
    /// ```
    pub fn s(&self, i: usize) -> Option<&CsMat<i8>> {
        i.checked_sub(1).and_then(|k| self.s.get(k))
    }

    /// T_i (i = 1, 2, 3), k_{p−1} × (k_{p−1} + 1): how the facets of each
    /// term map to the refined facets. Returns `None` unless 1 ≤ i ≤ 3.
    ///
    /// ```
    /// use hasse_complex::hasse_transform::MakeMatrices;
    /// use sprs::CsMat;
    /// let d1 = CsMat::new((2, 1), vec![0, 1, 2], vec![0, 0], vec![-1i8, 1]);
    /// let m = MakeMatrices::new(&[d1], 1, 0, &[1]).unwrap();
    /// // T_1: the old edge keeps its tail v0 and ends at the new vertex v2.
    /// let t1 = m.t(1).unwrap().to_dense();
    /// assert_eq!(t1.as_slice().unwrap(), &[1, 0, 0, 0, 0, 1]);
    /// ```
    pub fn t(&self, i: usize) -> Option<&CsMat<i8>> {
        i.checked_sub(1).and_then(|k| self.t.get(k))
    }

    /// The refined coboundaries δ̃_0 … δ̃_{n−1} from δ_0 … δ_{n−1}
    /// (δ_j = ∂_{j+1}ᵀ, |K_{j+1}| × |K_j|). Only δ_{p−2}, δ_{p−1} and δ_p
    /// change. Errors with [`SplitError::Shape`] when the matrices do not
    /// have the shapes of the complex the operator was built for.
    ///
    /// ```
    /// use hasse_complex::hasse_transform::MakeMatrices;
    /// use sprs::CsMat;
    /// let d1 = CsMat::new((2, 1), vec![0, 1, 2], vec![0, 0], vec![-1i8, 1]);
    /// let m = MakeMatrices::new(&[d1.clone()], 1, 0, &[1]).unwrap();
    /// let delta = m.coboundaries(&[d1.transpose_view().to_csr()]).unwrap();
    /// // e0 = v2 − v0, e1 = v1 − v2.
    /// assert_eq!(delta[0].to_dense().as_slice().unwrap(), &[-1, 0, 1, 0, 1, -1]);
    /// ```
    pub fn coboundaries(&self, delta: &[CsMat<i8>]) -> Result<Vec<CsMat<i8>>, SplitError> {
        let n = self.counts.len() - 1;
        if delta.len() != n {
            return Err(SplitError::Shape {
                what: "the list of coboundaries δ_0 … δ_{n−1}".into(),
                expected: (n, 0),
                found: (delta.len(), 0),
            });
        }
        let p = self.p;
        delta
            .iter()
            .enumerate()
            .map(|(j, d)| {
                let expected = (self.counts[j + 1], self.counts[j]);
                if d.shape() != expected {
                    return Err(SplitError::Shape {
                        what: format!("δ_{j}"),
                        expected,
                        found: d.shape(),
                    });
                }
                let d = d.to_csr();
                Ok(prune(if j == p {
                    &d * &self.c
                } else if j + 1 == p {
                    let terms: Vec<CsMat<i8>> = self
                        .s
                        .iter()
                        .zip(&self.t)
                        .map(|(s, t)| &(s * &d) * t)
                        .collect();
                    &(&terms[0] + &terms[1]) + &terms[2]
                } else if j + 2 == p {
                    match &self.r {
                        Some(r) => r * &d,
                        None => d,
                    }
                } else {
                    d
                }))
            })
            .collect()
    }

    /// The refined boundaries ∂̃_1 … ∂̃_n, by transposing
    /// [`MakeMatrices::coboundaries`].
    ///
    /// ```
    /// use hasse_complex::{euler::make, hasse_transform::MakeMatrices};
    /// use sprs::CsMat;
    /// let d1 = CsMat::new((2, 1), vec![0, 1, 2], vec![0, 0], vec![-1i8, 1]);
    /// let m = MakeMatrices::new(&[d1.clone()], 1, 0, &[0]).unwrap();
    /// assert_eq!(m.boundaries(&[d1.clone()]).unwrap(), make(&[d1], 1, 0, &[0]).unwrap().boundaries);
    /// ```
    pub fn boundaries(&self, boundaries: &[CsMat<i8>]) -> Result<Vec<CsMat<i8>>, SplitError> {
        let delta: Vec<CsMat<i8>> = boundaries
            .iter()
            .map(|b| b.transpose_view().to_csr())
            .collect();
        Ok(self
            .coboundaries(&delta)?
            .iter()
            .map(|d| d.transpose_view().to_csr())
            .collect())
    }

    /// η: the Hasse matrix of the refined complex from the Hasse matrix `h`
    /// of the old one, block by block (seed 000 §5, Remark 1). `h` has rows
    /// K_1, K_3, … and columns K_0, K_2, … as in [`hasse_matrix`]; the result
    /// has one more row and one more column. Errors with
    /// [`SplitError::Shape`] when `h` does not have the complex's shape or
    /// has an entry outside its blocks.
    ///
    /// ```
    /// use hasse_complex::euler::{hasse_matrix, make};
    /// use hasse_complex::hasse_transform::MakeMatrices;
    /// use sprs::CsMat;
    /// let d1 = CsMat::new((2, 1), vec![0, 1, 2], vec![0, 0], vec![-1i8, 1]);
    /// let m = MakeMatrices::new(&[d1.clone()], 1, 0, &[1]).unwrap();
    /// let h = m.hasse(&hasse_matrix(&[d1.clone()])).unwrap();
    /// assert_eq!(h.shape(), (2, 3));
    /// assert_eq!(h, hasse_matrix(&make(&[d1], 1, 0, &[1]).unwrap().boundaries));
    /// ```
    pub fn hasse(&self, h: &CsMat<i8>) -> Result<CsMat<i8>, SplitError> {
        let delta = hasse_blocks(h, &self.counts)?;
        let refined = self.coboundaries(&delta)?;
        let boundaries: Vec<CsMat<i8>> = refined
            .iter()
            .map(|d| d.transpose_view().to_csr())
            .collect();
        Ok(hasse_matrix(&boundaries))
    }
}

/// The coboundaries δ_0 … δ_{n−1} read off the blocks of a Hasse matrix
/// `h` of a complex with `counts` = (|K_0|, …, |K_n|): the block at rows
/// K_{j+1}, columns K_j (j even) is δ_j, the block at rows K_j, columns
/// K_{j+1} (j odd) is δ_jᵀ. The inverse of [`hasse_matrix`].
///
/// ```
/// use hasse_complex::euler::hasse_matrix;
/// use hasse_complex::hasse_transform::hasse_blocks;
/// use sprs::CsMat;
/// let d1 = CsMat::new((2, 1), vec![0, 1, 2], vec![0, 0], vec![-1i8, 1]);
/// let delta = hasse_blocks(&hasse_matrix(&[d1.clone()]), &[2, 1]).unwrap();
/// assert_eq!(delta[0], d1.transpose_view().to_csr());
/// ```
pub fn hasse_blocks(h: &CsMat<i8>, counts: &[usize]) -> Result<Vec<CsMat<i8>>, SplitError> {
    let n = counts.len().saturating_sub(1);
    // Where each dimension starts within the rows (odd) or columns (even).
    let mut start = vec![0usize; counts.len()];
    let (mut rows, mut cols) = (0usize, 0usize);
    for (j, &k) in counts.iter().enumerate() {
        let acc = if j % 2 == 1 { &mut rows } else { &mut cols };
        start[j] = *acc;
        *acc += k;
    }
    if h.shape() != (rows, cols) {
        return Err(SplitError::Shape {
            what: "the Hasse matrix".into(),
            expected: (rows, cols),
            found: h.shape(),
        });
    }
    // The dimension of a row (odd) or column (even) index and its local index.
    let locate = |index: usize, parity: usize| {
        (parity..=n)
            .step_by(2)
            .find(|&j| index >= start[j] && index < start[j] + counts[j])
            .map(|j| (j, index - start[j]))
    };
    let mut entries: Vec<Vec<(usize, usize, i8)>> = vec![Vec::new(); n];
    for (&v, (i, k)) in h.iter() {
        let outside = || SplitError::Shape {
            what: format!("the Hasse matrix entry at ({i}, {k}), outside every block,"),
            expected: (0, 0),
            found: (i, k),
        };
        let ((a, ia), (b, kb)) = locate(i, 1).zip(locate(k, 0)).ok_or_else(outside)?;
        if b + 1 == a {
            entries[b].push((ia, kb, v));
        } else if a + 1 == b {
            entries[a].push((kb, ia, v));
        } else {
            return Err(outside());
        }
    }
    Ok(entries
        .into_iter()
        .enumerate()
        .map(|(j, e)| matrix((counts[j + 1], counts[j]), e))
        .collect())
}

/// The Hasse transformation η of one make operator on a Hasse matrix
/// alone: `counts` = (|K_0|, …, |K_n|) says where its blocks are, the
/// operator (the arguments of [`make`](crate::euler::make)) is read off its
/// blocks and applied to them ([`MakeMatrices::hasse`]).
///
/// ```
/// use hasse_complex::euler::hasse_matrix;
/// use hasse_complex::hasse_transform::eta;
/// use sprs::CsMat;
/// let d1 = CsMat::new((2, 1), vec![0, 1, 2], vec![0, 0], vec![-1i8, 1]);
/// let h = eta(&hasse_matrix(&[d1]), &[2, 1], 1, 0, &[1]).unwrap();
/// assert_eq!(h.shape(), (2, 3));
/// assert_eq!(h.cols() as i64 - h.rows() as i64, 1); // χ of a segment
/// ```
pub fn eta(
    h: &CsMat<i8>,
    counts: &[usize],
    p: usize,
    cell: usize,
    moved: &[usize],
) -> Result<CsMat<i8>, SplitError> {
    let boundaries: Vec<CsMat<i8>> = hasse_blocks(h, counts)?
        .iter()
        .map(|d| d.transpose_view().to_csr())
        .collect();
    MakeMatrices::new(&boundaries, p, cell, moved)?.hasse(h)
}
