//! Geometric coarsening: undo the SPLIT of chosen parent cells by a
//! sequence of Euler kill operators κ ([`crate::kill`]), with the composed
//! chain maps from the fine to the coarse complex.
//!
//! # What is merged
//!
//! The refinement record is the [`Refinement`] of the SPLIT (or the
//! composed SPLITs) that made the fine complex: row f of ζ_p names the
//! parent of fine p-cell f, or none for a cell the cut created. Each fine
//! cell gets a *label*, the parent cell whose interior it lies in:
//!
//! - a top cell whose parent is one of the chosen `parents` → that parent;
//!   other top cells → none (they stay);
//! - a lower p-cell with a parent (a piece of a split edge or face) → that
//!   parent p-cell;
//! - a cell the cut created (no parent) → the label shared by all its
//!   cofaces, none if they disagree (it then separates a merged region
//!   from one that stays).
//!
//! A kill κ(p, x, y) is applied across a (p−1)-cell N when N was created
//! by the cut, N bounds exactly the two p-cells x and y, and x and y have
//! the same label. So the sibling top cells merge across their interior
//! facets first; then a vertex the cut put on an edge is removed only when
//! it is left with the two halves of that edge as its only edges, i.e.
//! when no remaining fine cell still uses it. Otherwise it stays, a
//! hanging vertex of a polygonal cell (which the polygonal methods accept).
//! In 3D the same rule merges the pieces of a split face across the cut
//! edges no remaining cell uses.
//!
//! The kills are tried from the top dimension down and the scan restarts
//! after each one. A kill that would not give a cell (two pieces sharing
//! two facets, as the last quarter of a quad does until the centre vertex
//! between its two interior edges is removed) is skipped and comes back
//! when a lower kill has made it valid. A chosen parent whose pieces do not
//! end as one cell is an error.
//!
//! # Numbering and orientation
//!
//! A kill keeps the smaller index of the two merged cells and deletes the
//! other and the facet between them, later cells moving down in order.
//! SPLIT keeps a split cell's index for one piece and appends the others
//! and the cut cells, so coarsening every group of a SPLIT returns the
//! original numbering. The coarse complex is built from its LAR with
//! [`Complex::from_lar`] (the crate's orientation conventions); the kill
//! sequence's ∂_p must then equal D_{p−1} ∂_p D_p for diagonal signs D
//! (checked, an error otherwise), and D is folded into ψ and ζ.
//!
//! ```
//! use hasse_complex::coarsen::coarsen;
//! use hasse_complex::generate::rectangle;
//! use hasse_complex::refine::uniform;
//! let k = rectangle(2, 2, [0.0, 1.0], [0.0, 1.0]).unwrap();
//! let (fine, r) = uniform(&k).unwrap();
//! // Undo the split of square 0 only: 16 − 4 + 1 = 13 cells.
//! let (coarse, c) = coarsen(&fine, &r, &[0]).unwrap();
//! assert_eq!(coarse.cell_count(2), 13);
//! // The two vertices the cut put on square 0's outer sides go; the two on
//! // the sides it shares with refined squares stay (hanging), as does
//! // nothing inside: 25 − 1 (centre) − 2 = 22.
//! assert_eq!(coarse.cell_count(0), 22);
//! assert_eq!(coarse.euler_characteristic(), 1);
//! assert_eq!(c.kills(), &[0, 3, 3]);
//! ```

mod transfer;

use crate::complex::Complex;
use crate::error::SplitError;
use crate::kill::kill;
use crate::lar::Lar;
use crate::split::Refinement;
use sprs::{CsMat, TriMat};

/// The chain maps of a coarsening, from the fine complex K to the coarse
/// complex K′ (see the module documentation).
///
/// - ψ_p (|K′_p| × |K_p|) is a chain map C(K) → C(K′), ∂′ψ = ψ∂: a fine
///   cell goes to the coarse cell it was merged into (with the sign of its
///   orientation there) or, for a removed cell, to what the kill squeezed
///   it onto;
/// - ζ_p (|K_p| × |K′_p|) is the subdivision map C(K′) → C(K), a coarse
///   cell ↦ the signed sum of its fine pieces, ψζ = id;
/// - the kept vertices: coarse vertex i is fine vertex `kept_vertices()[i]`.
///
/// ```
/// use hasse_complex::coarsen::coarsen;
/// use hasse_complex::generate::rectangle;
/// use hasse_complex::refine::uniform;
/// let k = rectangle(1, 1, [0.0, 1.0], [0.0, 1.0]).unwrap();
/// let (fine, r) = uniform(&k).unwrap();
/// let (coarse, c) = coarsen(&fine, &r, &[0]).unwrap();
/// assert_eq!(coarse.cell_counts(), vec![4, 4, 1]);
/// // The square is the sum of its four quarters.
/// assert_eq!(c.zeta(2).to_dense().as_slice().unwrap(), &[1, 1, 1, 1]);
/// assert_eq!(c.kept_vertices(), &[0, 1, 2, 3]);
/// ```
#[derive(Clone, Debug, PartialEq)]
pub struct Coarsening {
    psi: Vec<CsMat<i8>>,
    zeta: Vec<CsMat<i8>>,
    vertices: Vec<usize>,
    kills: Vec<usize>,
}

/// The parent cell a fine cell lies in: (dimension, index in the complex
/// the refinement starts from).
type Label = Option<(usize, usize)>;

/// Undo the SPLIT of the coarse top cells `parents`: merge their pieces in
/// `fine` (the complex `refinement` refined to) back into one cell each,
/// and the pieces of lower cells that no remaining fine cell still needs.
/// Returns the coarse complex and the chain maps from `fine` to it.
///
/// Errors: a refinement made for another complex, a parent out of range,
/// a parent whose pieces could not be merged into one cell, or (internal)
/// a kill sequence that disagrees with the orientation of the rebuilt
/// complex.
pub fn coarsen(
    fine: &Complex,
    refinement: &Refinement,
    parents: &[usize],
) -> Result<(Complex, Coarsening), SplitError> {
    coarsen_traced(fine, refinement, parents, &mut |_, _| {})
}

/// [`coarsen`], calling `after_kill(p, boundaries)` with ∂_1 … ∂_n after
/// every kill (p the dimension of the merged cells), e.g. to check
/// ∂∂ = 0 along the way.
///
/// ```
/// use hasse_complex::coarsen::coarsen_traced;
/// use hasse_complex::generate::rectangle;
/// use hasse_complex::refine::uniform;
/// let k = rectangle(1, 1, [0.0, 1.0], [0.0, 1.0]).unwrap();
/// let (fine, r) = uniform(&k).unwrap();
/// let mut steps = Vec::new();
/// coarsen_traced(&fine, &r, &[0], &mut |p, _| steps.push(p)).unwrap();
/// // Three merges of quarters, the centre vertex, then the four sides.
/// assert_eq!(steps.iter().filter(|&&p| p == 2).count(), 3);
/// assert_eq!(steps.iter().filter(|&&p| p == 1).count(), 5);
/// ```
pub fn coarsen_traced(
    fine: &Complex,
    refinement: &Refinement,
    parents: &[usize],
    after_kill: &mut dyn FnMut(usize, &[CsMat<i8>]),
) -> Result<(Complex, Coarsening), SplitError> {
    let n = fine.dim();
    let (coarse_counts, fine_counts) = refinement.counts();
    if refinement.dim() != n || fine_counts != fine.cell_counts() {
        return Err(SplitError::Incompatible {
            first: fine_counts,
            second: fine.cell_counts(),
        });
    }
    let mut chosen = vec![false; coarse_counts[n]];
    for &c in parents {
        let slot = chosen.get_mut(c).ok_or(SplitError::CellOutOfRange {
            p: n,
            cell: c,
            count: coarse_counts[n],
        })?;
        *slot = true;
    }
    let mut state = State {
        boundaries: (1..=n).map(|p| (**fine.boundary(p)).clone()).collect(),
        origin: fine_counts.iter().map(|&k| (0..k).collect()).collect(),
        psi: fine_counts.iter().map(|&k| CsMat::eye(k)).collect(),
        zeta: fine_counts.iter().map(|&k| CsMat::eye(k)).collect(),
        kills: vec![0; n + 1],
    };
    'scan: loop {
        let labels = state.labels(refinement, &chosen);
        for p in (1..=n).rev() {
            // Candidate facets N: made by the cut, bounding exactly two
            // p-cells of one label.
            let rows = &state.boundaries[p - 1];
            let columns = rows.to_csc();
            // Pieces that share more than this facet cannot merge yet (a
            // kill would refuse them); telling them apart here keeps a
            // scan from paying a whole kill for each of them.
            let shared = |x: usize, y: usize| -> usize {
                match (columns.outer_view(x), columns.outer_view(y)) {
                    (Some(a), Some(b)) => a
                        .indices()
                        .iter()
                        .filter(|i| b.indices().binary_search(i).is_ok())
                        .count(),
                    _ => 0,
                }
            };
            let mut candidates = Vec::new();
            for (facet, row) in rows.outer_iterator().enumerate() {
                if refinement
                    .parent(p - 1, state.origin[p - 1][facet])
                    .is_some()
                {
                    continue;
                }
                if let [x, y] = row.indices() {
                    let (x, y) = ((*x).min(*y), (*x).max(*y));
                    if labels[p][x].is_some() && labels[p][x] == labels[p][y] && shared(x, y) == 1 {
                        candidates.push((x, y));
                    }
                }
            }
            for (x, y) in candidates {
                // A refused kill (the pair shares more than this facet, or
                // the union would be pinched) waits for a lower kill.
                let Ok(done) = kill(&state.boundaries, p, x, y) else {
                    continue;
                };
                state.apply(p, y, done);
                after_kill(p, &state.boundaries);
                continue 'scan;
            }
        }
        break;
    }
    let labels = state.labels(refinement, &chosen);
    for (c, _) in chosen.iter().enumerate().filter(|(_, &on)| on) {
        let left = labels[n].iter().filter(|&&l| l == Some((n, c))).count();
        if left > 1 {
            return Err(SplitError::Invalid(format!(
                "the {left} remaining pieces of {n}-cell {c} could not be merged into one cell by kills (is {n}-cell {c} a parent of this refinement whose pieces form one convex cell?)"
            )));
        }
    }
    state.finish(fine)
}

/// The kill sequence so far.
struct State {
    /// ∂_1 … ∂_n of the current complex.
    boundaries: Vec<CsMat<i8>>,
    /// `origin[p][i]`: the fine p-cell that current p-cell i kept.
    origin: Vec<Vec<usize>>,
    /// Composed ψ (current × fine) and ζ (fine × current).
    psi: Vec<CsMat<i8>>,
    zeta: Vec<CsMat<i8>>,
    kills: Vec<usize>,
}

impl State {
    /// Every current cell's label (see the module documentation), top
    /// dimension first so that cut cells can read their cofaces'.
    fn labels(&self, refinement: &Refinement, chosen: &[bool]) -> Vec<Vec<Label>> {
        let n = self.boundaries.len();
        let mut labels: Vec<Vec<Label>> = vec![Vec::new(); n + 1];
        for p in (0..=n).rev() {
            let cofaces = (p < n).then(|| &self.boundaries[p]);
            labels[p] = self.origin[p]
                .iter()
                .enumerate()
                .map(|(i, &f)| match refinement.parent(p, f) {
                    Some((q, _)) if p == n => {
                        chosen.get(q).copied().unwrap_or(false).then_some((n, q))
                    }
                    Some((q, _)) => Some((p, q)),
                    None => {
                        let row = cofaces.and_then(|b| b.outer_view(i));
                        let mut shared: Option<Label> = None;
                        for &j in row.iter().flat_map(|r| r.indices()) {
                            let l = labels[p + 1][j];
                            match shared {
                                None => shared = Some(l),
                                Some(s) if s != l => return None,
                                Some(_) => {}
                            }
                        }
                        shared.flatten()
                    }
                })
                .collect();
        }
        labels
    }

    /// Take a kill of p-cells (the larger index `removed` into the smaller).
    fn apply(&mut self, p: usize, removed: usize, done: crate::kill::Kill) {
        self.origin[p].remove(removed);
        self.origin[p - 1].remove(done.facet);
        for (q, (psi, zeta)) in done.psi.iter().zip(&done.zeta).enumerate() {
            self.psi[q] = psi * &self.psi[q];
            self.zeta[q] = &self.zeta[q] * zeta;
        }
        self.boundaries = done.boundaries;
        self.kills[p] += 1;
    }

    /// Rebuild the coarse complex from its LAR, fold the orientation signs
    /// into the maps and carry the tags over.
    fn finish(mut self, fine: &Complex) -> Result<(Complex, Coarsening), SplitError> {
        let n = self.boundaries.len();
        let d = fine.embedding_dim();
        let mut coords = Vec::with_capacity(self.origin[0].len() * d);
        for &v in &self.origin[0] {
            coords.extend_from_slice(fine.vertices().point(v));
        }
        let mut vertices = crate::cells::Vertices::new(d, coords)?;
        vertices.period = fine.vertices().period;
        // Vertex sets of every cell, from the closures.
        let mut sets: Vec<Vec<Vec<usize>>> = Vec::with_capacity(n);
        for p in 1..=n {
            let csc = self.boundaries[p - 1].to_csc();
            let level: Vec<Vec<usize>> = csc
                .outer_iterator()
                .map(|col| {
                    let mut set: Vec<usize> = if p == 1 {
                        col.indices().to_vec()
                    } else {
                        col.indices()
                            .iter()
                            .flat_map(|&f| sets[p - 2][f].iter().copied())
                            .collect()
                    };
                    set.sort_unstable();
                    set.dedup();
                    set
                })
                .collect();
            sets.push(level);
        }
        let mut coarse = Complex::from_lar(Lar::from_vertex_sets(vertices, sets)?)?;
        // D_p: the sign of each rebuilt cell against the kills' cell.
        let mut signs: Vec<Vec<i8>> = vec![vec![1; self.origin[0].len()]];
        for p in 1..=n {
            let mine = self.boundaries[p - 1].to_csc();
            let theirs = coarse.boundary(p).to_csc();
            let below = &signs[p - 1];
            let mut here = Vec::with_capacity(mine.cols());
            for (j, (a, b)) in mine
                .outer_iterator()
                .zip(theirs.outer_iterator())
                .enumerate()
            {
                let s = match (a.iter().next(), b.iter().next()) {
                    (Some((i, &v)), Some((_, &w))) => w * v * below[i],
                    _ => 0,
                };
                let agrees = a.indices() == b.indices()
                    && a.iter()
                        .zip(b.iter())
                        .all(|((i, &v), (_, &w))| w == s * below[i] * v);
                if s == 0 || !agrees {
                    return Err(SplitError::Invalid(format!(
                        "internal: the kills' boundary of {p}-cell {j} is not the rebuilt complex's up to orientation"
                    )));
                }
                here.push(s);
            }
            signs.push(here);
        }
        for (p, s) in signs.iter().enumerate() {
            self.psi[p] = scale_rows(&self.psi[p], s);
            self.zeta[p] = scale_rows(&self.zeta[p].transpose_view().to_csr(), s)
                .transpose_view()
                .to_csr();
        }
        // A coarse cell carries a tag when any of its fine pieces did.
        for (name, tag) in fine.tags().iter() {
            let z = &self.zeta[tag.dim];
            let mut cells: Vec<usize> = tag
                .cells
                .iter()
                .filter_map(|&f| {
                    z.outer_view(f)
                        .and_then(|row| row.indices().first().copied())
                })
                .collect();
            cells.sort_unstable();
            cells.dedup();
            coarse.set_tag(name, tag.dim, cells)?;
        }
        let out = Coarsening {
            psi: self.psi.into_iter().map(|m| m.to_csr()).collect(),
            zeta: self.zeta.into_iter().map(|m| m.to_csr()).collect(),
            vertices: self.origin.swap_remove(0),
            kills: self.kills,
        };
        Ok((coarse, out))
    }
}

/// diag(s) · m.
fn scale_rows(m: &CsMat<i8>, s: &[i8]) -> CsMat<i8> {
    let mut t = TriMat::new(m.shape());
    for (&v, (i, j)) in m.iter() {
        t.add_triplet(i, j, s[i] * v);
    }
    t.to_csr()
}

impl Coarsening {
    /// Top dimension n.
    ///
    /// ```
    /// use hasse_complex::coarsen::coarsen;
    /// use hasse_complex::generate::rectangle;
    /// use hasse_complex::refine::uniform;
    /// let k = rectangle(1, 1, [0.0, 1.0], [0.0, 1.0]).unwrap();
    /// let (fine, r) = uniform(&k).unwrap();
    /// assert_eq!(coarsen(&fine, &r, &[0]).unwrap().1.dim(), 2);
    /// ```
    pub fn dim(&self) -> usize {
        self.psi.len() - 1
    }

    /// ψ_p: coarse p-cells × fine p-cells, the chain map C(K) → C(K′).
    ///
    /// ```
    /// use hasse_complex::coarsen::coarsen;
    /// use hasse_complex::generate::rectangle;
    /// use hasse_complex::refine::uniform;
    /// let k = rectangle(1, 1, [0.0, 1.0], [0.0, 1.0]).unwrap();
    /// let (fine, r) = uniform(&k).unwrap();
    /// let (coarse, c) = coarsen(&fine, &r, &[0]).unwrap();
    /// // ∂′ψ = ψ∂ on the top cells.
    /// let left = &**coarse.boundary(2) * c.psi(2);
    /// let right = c.psi(1) * &**fine.boundary(2);
    /// assert_eq!(left.to_dense(), right.to_dense());
    /// ```
    ///
    /// # Panics
    /// When p > n.
    pub fn psi(&self, p: usize) -> &CsMat<i8> {
        &self.psi[p]
    }

    /// ζ_p: fine p-cells × coarse p-cells, a coarse cell ↦ its pieces.
    ///
    /// ```
    /// use hasse_complex::coarsen::coarsen;
    /// use hasse_complex::generate::rectangle;
    /// use hasse_complex::refine::uniform;
    /// let k = rectangle(1, 1, [0.0, 1.0], [0.0, 1.0]).unwrap();
    /// let (fine, r) = uniform(&k).unwrap();
    /// let (_, c) = coarsen(&fine, &r, &[0]).unwrap();
    /// // Each side of the square is the sum of its two halves.
    /// assert_eq!(c.zeta(1).nnz(), 8);
    /// ```
    ///
    /// # Panics
    /// When p > n.
    pub fn zeta(&self, p: usize) -> &CsMat<i8> {
        &self.zeta[p]
    }

    /// The fine vertex each coarse vertex is (coarse vertices are a subset
    /// of the fine ones, in the same order).
    ///
    /// ```
    /// use hasse_complex::coarsen::coarsen;
    /// use hasse_complex::generate::rectangle;
    /// use hasse_complex::refine::uniform;
    /// let k = rectangle(2, 1, [0.0, 2.0], [0.0, 1.0]).unwrap();
    /// let (fine, r) = uniform(&k).unwrap();
    /// let (_, c) = coarsen(&fine, &r, &[0, 1]).unwrap();
    /// assert_eq!(c.kept_vertices(), &[0, 1, 2, 3, 4, 5]);
    /// ```
    pub fn kept_vertices(&self) -> &[usize] {
        &self.vertices
    }

    /// How many kills merged p-cells, per p (index 0 is always 0).
    ///
    /// ```
    /// use hasse_complex::coarsen::coarsen;
    /// use hasse_complex::generate::rectangle;
    /// use hasse_complex::refine::uniform;
    /// let k = rectangle(1, 1, [0.0, 1.0], [0.0, 1.0]).unwrap();
    /// let (fine, r) = uniform(&k).unwrap();
    /// assert_eq!(coarsen(&fine, &r, &[0]).unwrap().1.kills(), &[0, 5, 3]);
    /// ```
    pub fn kills(&self) -> &[usize] {
        &self.kills
    }

    /// (fine cell counts, coarse cell counts).
    ///
    /// ```
    /// use hasse_complex::coarsen::coarsen;
    /// use hasse_complex::generate::rectangle;
    /// use hasse_complex::refine::uniform;
    /// let k = rectangle(1, 1, [0.0, 1.0], [0.0, 1.0]).unwrap();
    /// let (fine, r) = uniform(&k).unwrap();
    /// let (_, c) = coarsen(&fine, &r, &[0]).unwrap();
    /// assert_eq!(c.counts(), (vec![9, 12, 4], vec![4, 4, 1]));
    /// ```
    pub fn counts(&self) -> (Vec<usize>, Vec<usize>) {
        (
            self.zeta.iter().map(|z| z.rows()).collect(),
            self.zeta.iter().map(|z| z.cols()).collect(),
        )
    }

    /// The coarse p-cell fine p-cell `fine` was merged into (itself, when
    /// it stayed), with the sign of its orientation there; `None` for a
    /// cell the kills removed (a facet between merged pieces).
    ///
    /// ```
    /// use hasse_complex::coarsen::coarsen;
    /// use hasse_complex::generate::rectangle;
    /// use hasse_complex::refine::uniform;
    /// let k = rectangle(1, 1, [0.0, 1.0], [0.0, 1.0]).unwrap();
    /// let (fine, r) = uniform(&k).unwrap();
    /// let (_, c) = coarsen(&fine, &r, &[0]).unwrap();
    /// assert_eq!(c.coarse_cell(2, 3), Some((0, 1)));
    /// assert_eq!(c.coarse_cell(0, 8), None); // the centre vertex
    /// ```
    pub fn coarse_cell(&self, p: usize, fine: usize) -> Option<(usize, i8)> {
        let row = self.zeta.get(p)?.outer_view(fine)?;
        row.iter().next().map(|(j, &s)| (j, s))
    }
}
