//! One SPLIT pass: every accepted top cell is cut by its own hyperplane,
//! bottom-up by dimension (edges, then faces, then volumes), and the new
//! incidence matrices are assembled column by column without touching the
//! geometry of cells that are not cut.
//!
//! Numbering (so that ζ is [I; ·] and unsplit cells keep their index): a
//! split p-cell keeps its index for the piece on the negative side of its
//! plane; the positive pieces are appended in the order of their parents,
//! then the new cut cells (the vertex of an edge, the edge of a polygon, the
//! polygon of a polyhedron) in the order of the cells they cut.
//!
//! Orientation: below the top dimension a cell's orientation is that of the
//! frame of its sorted vertex list (crate convention), so a piece carries a
//! sign ε = ±1 relative to its parent and ζ(c) = ε⁻ c⁻ + ε⁺ c⁺. A piece's
//! boundary, oriented like the parent, is the part of ζ(∂c) on its side plus
//! ±N; the sign of N is fixed by ∂∂ = 0 on one face of N, so it needs no
//! geometry. Geometry enters only to compare the frames of a piece and its
//! parent, to orient a new cut polygon, and for the positivity flag of new
//! top cells.

use super::cut::{cut_cell, union_sets, Pieces, Scratch};
use super::{Hyperplane, Refinement};
use crate::cells::{FlatSets, Vertices};
use crate::complex::Complex;
use crate::error::SplitError;
use crate::frame::{self, Frame, Point};
use crate::lar::{characteristic_matrix, Lar};
use crate::tags::{CellTag, Tags};
use nalgebra::Vector3;
use rayon::prelude::*;
use sprs::CsMat;
use std::ops::Range;

const NONE: u32 = u32::MAX;

/// A signed list of cells (a chain), sorted by cell id.
pub(super) type Chain = Vec<(usize, i8)>;

pub(super) struct Round {
    pub complex: Complex,
    pub refinement: Refinement,
    /// Cuts that conflicted with an accepted neighbour (a shared lower cell
    /// cut by two different planes); top-cell ids are valid in `complex`.
    pub deferred: Vec<(usize, u32)>,
}

/// Columns of one ∂_p under construction (CSC) together with the vertex
/// sets of the p-cells (rows of M_p).
#[derive(Default)]
pub(super) struct Level {
    ptr: Vec<usize>,
    rows: Vec<usize>,
    signs: Vec<i8>,
    set_ptr: Vec<usize>,
    set: Vec<u32>,
}

impl Level {
    fn with_capacity(cells: usize, nnz: usize, set_len: usize) -> Self {
        let mut l = Self {
            ptr: Vec::with_capacity(cells + 1),
            rows: Vec::with_capacity(nnz),
            signs: Vec::with_capacity(nnz),
            set_ptr: Vec::with_capacity(cells + 1),
            set: Vec::with_capacity(set_len),
        };
        l.ptr.push(0);
        l.set_ptr.push(0);
        l
    }

    fn len(&self) -> usize {
        self.ptr.len() - 1
    }

    /// `column` must be sorted by row; `set` sorted.
    fn push(&mut self, column: &[(usize, i8)], set: &[u32]) {
        for &(r, s) in column {
            self.rows.push(r);
            self.signs.push(s);
        }
        self.ptr.push(self.rows.len());
        self.set.extend_from_slice(set);
        self.set_ptr.push(self.set.len());
    }

    pub(super) fn column(&self, j: usize) -> (&[usize], &[i8]) {
        let r = self.ptr[j]..self.ptr[j + 1];
        (&self.rows[r.clone()], &self.signs[r])
    }

    pub(super) fn set(&self, j: usize) -> &[u32] {
        &self.set[self.set_ptr[j]..self.set_ptr[j + 1]]
    }

    fn append(&mut self, other: Level) {
        let base = self.rows.len();
        self.ptr.extend(other.ptr[1..].iter().map(|&o| o + base));
        self.rows.extend(other.rows);
        self.signs.extend(other.signs);
        let base = self.set.len();
        self.set_ptr
            .extend(other.set_ptr[1..].iter().map(|&o| o + base));
        self.set.extend(other.set);
    }
}

/// Signed distances and classes of vertices with respect to the planes of
/// this round. Classes depend only on (vertex, plane), so every cell that
/// shares a vertex sees the same class.
pub(super) struct Classifier<'a> {
    planes: &'a [Hyperplane],
    coords: &'a [f64],
    dim: usize,
    /// snap × (shortest edge at the vertex).
    threshold: Vec<f64>,
    /// The plane whose cut created a vertex (NONE for old vertices): such a
    /// vertex lies on that plane by construction, whatever rounding says.
    creator: Vec<u32>,
}

impl Classifier<'_> {
    fn distance(&self, v: usize, plane: u32) -> f64 {
        // Only the first `dim` normal components are non-zero.
        self.planes[plane as usize].distance(&self.coords[v * self.dim..(v + 1) * self.dim])
    }

    fn class(&self, v: usize, plane: u32) -> i8 {
        if self.creator[v] == plane {
            return 0;
        }
        let d = self.distance(v, plane);
        if d.abs() <= self.threshold[v] {
            0
        } else if d > 0.0 {
            1
        } else {
            -1
        }
    }

    /// (has a vertex strictly below, has one strictly above).
    pub(super) fn sides<I: IntoIterator<Item = usize>>(
        &self,
        verts: I,
        plane: u32,
    ) -> (bool, bool) {
        let (mut neg, mut pos) = (false, false);
        for v in verts {
            match self.class(v, plane) {
                -1 => neg = true,
                1 => pos = true,
                _ => {}
            }
        }
        (neg, pos)
    }

    fn point(&self, v: usize) -> Point {
        let mut x = [0.0; 3];
        x[..self.dim].copy_from_slice(&self.coords[v * self.dim..(v + 1) * self.dim]);
        x
    }
}

pub(super) fn sign_of(x: f64) -> i8 {
    if x > 0.0 {
        1
    } else {
        -1
    }
}

/// Orientation of frame `a` relative to frame `b` spanning the same p-plane.
pub(super) fn relative_orientation(a: &Frame, b: &Frame) -> i8 {
    let mut m = [[0.0; 3]; 3];
    for (i, row) in m.iter_mut().enumerate().take(a.dim) {
        for (j, slot) in row.iter_mut().enumerate().take(b.dim) {
            *slot = Vector3::from(a.basis[i]).dot(&Vector3::from(b.basis[j]));
        }
    }
    sign_of(frame::det(a.dim, &m))
}

/// Per-level bookkeeping of the old p-cells: which plane splits them, the
/// index of the positive piece and the two ζ signs.
struct Splits {
    plane: Vec<u32>,
    /// Unsplit cells whose vertex set grew (a face of theirs was split, so
    /// they received a new vertex).
    grown: Vec<bool>,
    plus: Vec<usize>,
    eps_minus: Vec<i8>,
    eps_plus: Vec<i8>,
}

impl Splits {
    fn new(count: usize) -> Self {
        Self {
            plane: vec![NONE; count],
            grown: vec![false; count],
            plus: Vec::new(),
            eps_minus: Vec::new(),
            eps_plus: Vec::new(),
        }
    }
}

pub(super) fn round(
    k: &Complex,
    cuts: &[(usize, u32)],
    planes: &[Hyperplane],
    snap: f64,
) -> Result<Round, SplitError> {
    let n = k.dim();
    let d = k.embedding_dim();
    let counts = k.cell_counts();
    let k0 = counts[0];
    let mut clock = Phases::new();

    // Local length scale: the shortest edge at each vertex.
    let mut shortest = vec![f64::INFINITY; k0];
    for e in 0..counts[1] {
        let ends = k.cell_vertices(1, e);
        let (a, b) = (ends[0], ends[1]);
        let r = Vector3::from(frame::point(k.vertices(), a))
            - Vector3::from(frame::point(k.vertices(), b));
        let len = r.norm();
        shortest[a] = shortest[a].min(len);
        shortest[b] = shortest[b].min(len);
    }
    let mut cls = Classifier {
        planes,
        coords: k.vertices().as_slice(),
        dim: d,
        threshold: shortest
            .iter()
            .map(|&l| if l.is_finite() { snap * l } else { 0.0 })
            .collect(),
        creator: vec![NONE; k0],
    };

    // Acceptance: a cut is taken when none of the lower cells it straddles
    // is already claimed by a different plane.
    let mut splits: Vec<Splits> = counts.iter().map(|&c| Splits::new(c)).collect();
    let mut deferred = Vec::new();
    let mut straddled: Vec<(usize, usize)> = Vec::new();
    let mut stack: Vec<(usize, usize)> = Vec::new();
    let csc: Vec<Option<&CsMat<i8>>> = (0..=n)
        .map(|p| (p >= 1).then(|| &**k.boundary_csc(p)))
        .collect();
    for &(c, id) in cuts {
        if splits[n].plane[c] != NONE {
            continue;
        }
        let (neg, pos) = cls.sides(k.cell_vertices(n, c).iter().copied(), id);
        if !(neg && pos) {
            continue;
        }
        straddled.clear();
        collect_straddled(k, &csc, &cls, n, c, id, &mut stack, &mut straddled);
        let conflict = straddled.iter().any(|&(p, i)| {
            let claim = splits[p].plane[i];
            claim != NONE && claim != id && !compatible(k, &cls, p, i, claim, id)
        });
        if conflict {
            deferred.push((c, id));
            continue;
        }
        // A compatible claim stays with the first plane: its cut point is the
        // one the compatibility test measured against.
        for &(p, i) in &straddled {
            if splits[p].plane[i] == NONE {
                splits[p].plane[i] = id;
            }
        }
        splits[n].plane[c] = id;
    }
    clock.lap("classify and accept");
    if splits[n].plane.iter().all(|&x| x == NONE) {
        // Nothing is crossed: the complex is its own refinement.
        return Ok(Round {
            complex: k.clone(),
            refinement: Refinement::identity(k),
            deferred,
        });
    }
    // Ranks: the positive piece of the r-th split p-cell is k_p + r.
    let split_count: Vec<usize> = splits
        .iter()
        .map(|s| s.plane.iter().filter(|&&x| x != NONE).count())
        .collect();
    for (p, s) in splits.iter_mut().enumerate().skip(1) {
        s.plus = vec![usize::MAX; counts[p]];
        s.eps_minus = vec![1; counts[p]];
        s.eps_plus = vec![1; counts[p]];
        let mut next = counts[p];
        for i in 0..counts[p] {
            if s.plane[i] != NONE {
                s.plus[i] = next;
                next += 1;
            }
        }
    }
    // New cell counts: k_p + (split p-cells) + (split (p+1)-cells, each cut by a new p-cell).
    let new_counts: Vec<usize> = (0..=n)
        .map(|p| {
            counts[p]
                + if p >= 1 { split_count[p] } else { 0 }
                + split_count.get(p + 1).copied().unwrap_or(0)
        })
        .collect();

    // ---- Level 1: edges; new vertices on cut edges. Chunks of edges are
    // processed in parallel; the r-th cut edge creates vertex k0 + r and
    // positive piece k1 + r, so chunks need no coordination.
    let edge_chunks: Vec<EdgeChunk> = (0..counts[1].div_ceil(CHUNK))
        .into_par_iter()
        .map(|i| {
            cut_edges(
                k,
                &cls,
                &splits[1],
                i * CHUNK..((i + 1) * CHUNK).min(counts[1]),
            )
        })
        .collect();
    let mut nodal: Vec<(usize, usize, f64)> = Vec::with_capacity(split_count[1]);
    let mut coords = Vec::with_capacity((k0 + split_count[1]) * d);
    coords.extend_from_slice(k.vertices().as_slice());
    let mut levels: Vec<Level> = Vec::with_capacity(n + 1);
    levels.push(Level::default());
    {
        let mut main = Level::with_capacity(new_counts[1], 2 * new_counts[1], 2 * new_counts[1]);
        let mut plus = Level::with_capacity(split_count[1], 2 * split_count[1], 2 * split_count[1]);
        coords.reserve_exact(split_count[1] * d);
        for chunk in edge_chunks {
            main.append(chunk.main);
            plus.append(chunk.plus);
            coords.extend(chunk.coords);
            for (e, em, ep) in chunk.eps {
                splits[1].eps_minus[e] = em;
                splits[1].eps_plus[e] = ep;
            }
            for &(a, b, t, id) in &chunk.nodal {
                cls.threshold.push(cls.threshold[a].min(cls.threshold[b]));
                cls.creator.push(id);
                nodal.push((a, b, t));
            }
        }
        main.append(plus);
        levels.push(main);
    }
    let vertices = Vertices::new(d, coords)?;
    // From here on new vertices are classified too.
    let cls = Classifier {
        planes,
        coords: vertices.as_slice(),
        dim: d,
        threshold: std::mem::take(&mut cls.threshold),
        creator: std::mem::take(&mut cls.creator),
    };
    clock.lap("edges");

    // ---- Levels 2..=n, in parallel chunks of cells.
    let mut top_orientation: Vec<i8> = k.top_orientation().to_vec();
    top_orientation.resize(counts[n] + split_count[n], 1);
    for p in 2..=n {
        let old = csc[p].ok_or(SplitError::Invalid("internal: missing ∂".into()))?;
        let ctx = CellPass {
            k,
            vertices: &vertices,
            cls: &cls,
            edges: &levels[1],
            lower: &levels[p - 1],
            below: &splits[p - 1],
            here: &splits[p],
            old,
            p,
            n,
            cut_base: counts[p - 1] + split_count[p - 1],
            first_plus: counts[p],
        };
        let chunks: Vec<CellChunk> = (0..counts[p].div_ceil(CHUNK))
            .into_par_iter()
            .map(|i| ctx.run(i * CHUNK..((i + 1) * CHUNK).min(counts[p])))
            .collect::<Result<_, SplitError>>()?;
        let mut main = Level::with_capacity(new_counts[p], old.nnz() * 2, old.nnz() * 2);
        let mut plus = Level::with_capacity(split_count[p], 0, 0);
        let mut cut_cells = Level::with_capacity(split_count[p], 0, 0);
        let here = &mut splits[p];
        for chunk in chunks {
            main.append(chunk.main);
            plus.append(chunk.plus);
            cut_cells.append(chunk.cuts);
            for c in chunk.grown {
                here.grown[c] = true;
            }
            for (c, em, ep, tm, tp) in chunk.eps {
                here.eps_minus[c] = em;
                here.eps_plus[c] = ep;
                if p == n {
                    top_orientation[c] = tm;
                    top_orientation[here.plus[c]] = tp;
                }
            }
        }
        main.append(plus);
        levels.push(main);
        // The cut cells of this level are (p−1)-cells: they follow the
        // positive pieces of level p−1.
        levels[p - 1].append(cut_cells);
    }

    clock.lap("faces and cells");
    // ---- Assemble matrices.
    let mut boundaries = Vec::with_capacity(n);
    let mut characteristic = Vec::with_capacity(n);
    for p in 1..=n {
        let level = std::mem::take(&mut levels[p]);
        debug_assert_eq!(level.len(), new_counts[p]);
        let rows = new_counts[p - 1];
        let cols = level.len();
        let dp = CsMat::try_new_csc((rows, cols), level.ptr, level.rows, level.signs)
            .map_err(|e| SplitError::Invalid(format!("internal: ∂_{p} after split: {}", e.3)))?;
        boundaries.push(dp.to_csr());
        let sets = FlatSets {
            offsets: level.set_ptr,
            vertices: level.set,
        };
        characteristic.push(characteristic_matrix(sets, new_counts[0]));
    }
    let lar = Lar::new(vertices, characteristic)?;

    clock.lap("assemble ∂ and M");
    // ---- ζ and the nodal interpolation.
    let mut zeta = Vec::with_capacity(n + 1);
    zeta.push(identity_rows(new_counts[0], counts[0], &[], &[], &[]));
    for p in 1..=n {
        let s = &splits[p];
        zeta.push(identity_rows(
            new_counts[p],
            counts[p],
            &s.plus,
            &s.eps_minus,
            &s.eps_plus,
        ));
    }
    let nodal = nodal_matrix(counts[0], &nodal);

    clock.lap("ζ and nodal interpolation");
    // ---- Tags: a tagged cell's pieces keep the tag.
    let mut tags = Tags::default();
    for (name, tag) in k.tags().iter() {
        let mut cells = Vec::with_capacity(tag.cells.len());
        for &c in &tag.cells {
            cells.push(c);
            if tag.dim >= 1 && splits[tag.dim].plane[c] != NONE {
                cells.push(splits[tag.dim].plus[c]);
            }
        }
        tags.insert(name, CellTag::new(tag.dim, cells));
    }
    let complex = Complex::from_parts(lar, boundaries, top_orientation, tags);
    clock.lap("tags");
    Ok(Round {
        complex,
        refinement: Refinement::from_parts(zeta, nodal),
        deferred,
    })
}

/// Can a lower cell claimed by plane `a` also serve a cell cut by plane `b`?
/// Yes when both planes see its vertices on the same sides (up to the
/// orientation of the normals) and, for an edge, `a`'s cut point lies on `b`
/// within the snap tolerance — so `b` will classify that new vertex as on
/// its plane. Planes that differ in the last bits (centroids of a column of
/// cells computed from different vertices) thus share their cuts.
fn compatible(k: &Complex, cls: &Classifier, p: usize, i: usize, a: u32, b: u32) -> bool {
    let (na, nb) = (
        Vector3::from(cls.planes[a as usize].normal),
        Vector3::from(cls.planes[b as usize].normal),
    );
    let sigma = if na.dot(&nb) >= 0.0 { 1 } else { -1 };
    let verts = k.cell_vertices(p, i);
    if verts
        .iter()
        .any(|&v| cls.class(v, b) != sigma * cls.class(v, a))
    {
        return false;
    }
    if p != 1 {
        return true;
    }
    let (u, w) = (verts[0], verts[1]);
    let (du, dw) = (cls.distance(u, a), cls.distance(w, a));
    let t = du / (du - dw);
    let (xu, xw) = (cls.point(u), cls.point(w));
    let mut m = [0.0; 3];
    for axis in 0..cls.dim {
        m[axis] = xu[axis] + t * (xw[axis] - xu[axis]);
    }
    let threshold = cls.threshold[u].min(cls.threshold[w]);
    cls.planes[b as usize].distance(&m[..cls.dim]).abs() <= threshold
}

const CHUNK: usize = 16384;

struct EdgeChunk {
    main: Level,
    plus: Level,
    coords: Vec<f64>,
    /// (edge, ε⁻, ε⁺) of the cut edges.
    eps: Vec<(usize, i8, i8)>,
    /// (a, b, t, plane) of each new vertex, in order.
    nodal: Vec<(usize, usize, f64, u32)>,
}

/// Cut the claimed edges of `range`: the new vertex m = a + t (b − a) at
/// the plane's crossing; the piece (x, m) is oriented x → m (m is the
/// largest index), which agrees with the parent a → b exactly when x = a.
fn cut_edges(k: &Complex, cls: &Classifier, s: &Splits, range: Range<usize>) -> EdgeChunk {
    let len = range.len();
    let mut out = EdgeChunk {
        main: Level::with_capacity(len, 2 * len, 2 * len),
        plus: Level::with_capacity(0, 0, 0),
        coords: Vec::new(),
        eps: Vec::new(),
        nodal: Vec::new(),
    };
    let k0 = k.cell_count(0);
    let k1 = k.cell_count(1);
    for e in range {
        let ends = k.cell_vertices(1, e);
        let (a, b) = (ends[0], ends[1]);
        let id = s.plane[e];
        if id == NONE {
            out.main.push(&[(a, -1), (b, 1)], &[a as u32, b as u32]);
            continue;
        }
        let (da, db) = (cls.distance(a, id), cls.distance(b, id));
        let t = da / (da - db);
        let m = k0 + (s.plus[e] - k1);
        let (xa, xb) = (cls.point(a), cls.point(b));
        for axis in 0..cls.dim {
            out.coords.push(xa[axis] + t * (xb[axis] - xa[axis]));
        }
        out.nodal.push((a, b, t, id));
        let (minus_end, plus_end) = if da < 0.0 { (a, b) } else { (b, a) };
        let eps = |x: usize| if x == a { 1 } else { -1 };
        out.eps.push((e, eps(minus_end), eps(plus_end)));
        out.main
            .push(&[(minus_end, -1), (m, 1)], &[minus_end as u32, m as u32]);
        out.plus
            .push(&[(plus_end, -1), (m, 1)], &[plus_end as u32, m as u32]);
    }
    out
}

struct CellChunk {
    main: Level,
    plus: Level,
    cuts: Level,
    grown: Vec<usize>,
    /// (cell, ε⁻, ε⁺, top flag⁻, top flag⁺) of the cut cells.
    eps: Vec<(usize, i8, i8, i8, i8)>,
}

/// Everything one pass over the p-cells reads.
struct CellPass<'a> {
    k: &'a Complex,
    vertices: &'a Vertices,
    cls: &'a Classifier<'a>,
    edges: &'a Level,
    lower: &'a Level,
    below: &'a Splits,
    here: &'a Splits,
    old: &'a CsMat<i8>,
    p: usize,
    n: usize,
    cut_base: usize,
    first_plus: usize,
}

impl CellPass<'_> {
    /// New columns and vertex sets of the p-cells in `range`: ζ(∂c) for an
    /// uncut cell, the two pieces and the cut cell for a cut one.
    fn run(&self, range: Range<usize>) -> Result<CellChunk, SplitError> {
        let len = range.len();
        let mut out = CellChunk {
            main: Level::with_capacity(len, 6 * len, 6 * len),
            plus: Level::with_capacity(0, 0, 0),
            cuts: Level::with_capacity(0, 0, 0),
            grown: Vec::new(),
            eps: Vec::new(),
        };
        let mut scratch = Scratch::default();
        let mut pieces = Pieces::default();
        let mut side = Vec::new();
        for c in range {
            let (facets, signs) = crate::geometry::column(self.old, c);
            scratch.column.clear();
            let mut changed = false;
            for (&f, &s) in facets.iter().zip(signs) {
                if self.below.plane[f] == NONE {
                    changed |= self.below.grown[f];
                    scratch.column.push((f, s));
                } else {
                    changed = true;
                    scratch.column.push((f, s * self.below.eps_minus[f]));
                    scratch
                        .column
                        .push((self.below.plus[f], s * self.below.eps_plus[f]));
                }
            }
            scratch.column.sort_unstable();
            let id = self.here.plane[c];
            if id == NONE {
                if changed {
                    out.grown.push(c);
                    union_sets(
                        self.lower,
                        scratch.column.iter().map(|x| x.0),
                        &mut scratch.set,
                    );
                    out.main.push(&scratch.column, &scratch.set);
                } else {
                    scratch.set.clear();
                    scratch
                        .set
                        .extend(self.k.cell_vertices(self.p, c).iter().map(|&v| v as u32));
                    out.main.push(&scratch.column, &scratch.set);
                }
                continue;
            }
            cut_cell(
                self.k,
                self.vertices,
                self.cls,
                self.edges,
                self.lower,
                self.p,
                self.n,
                c,
                id,
                &mut scratch,
                &mut pieces,
            )?;
            let cut_index = self.cut_base + (self.here.plus[c] - self.first_plus);
            out.cuts.push(&pieces.cut_column, &pieces.cut_set);
            for (part, cut_sign, eps, level, set) in [
                (
                    &pieces.minus,
                    pieces.cut_sign,
                    pieces.eps_minus,
                    0,
                    &pieces.minus_set,
                ),
                (
                    &pieces.plus,
                    -pieces.cut_sign,
                    pieces.eps_plus,
                    1,
                    &pieces.plus_set,
                ),
            ] {
                side.clear();
                side.extend(part.iter().map(|&(f, r)| (f, r * eps)));
                side.push((cut_index, cut_sign * eps));
                side.sort_unstable();
                if level == 0 {
                    out.main.push(&side, set);
                } else {
                    out.plus.push(&side, set);
                }
            }
            out.eps.push((
                c,
                pieces.eps_minus,
                pieces.eps_plus,
                pieces.top_minus,
                pieces.top_plus,
            ));
        }
        Ok(out)
    }
}

/// Every lower cell of top cell `c` that straddles plane `id` (vertices
/// strictly on both sides).
#[allow(clippy::too_many_arguments)]
fn collect_straddled(
    k: &Complex,
    csc: &[Option<&CsMat<i8>>],
    cls: &Classifier,
    n: usize,
    c: usize,
    id: u32,
    stack: &mut Vec<(usize, usize)>,
    out: &mut Vec<(usize, usize)>,
) {
    stack.clear();
    stack.push((n, c));
    while let Some((p, cell)) = stack.pop() {
        let Some(m) = csc[p] else { continue };
        for &f in crate::geometry::column(m, cell).0 {
            if out.contains(&(p - 1, f)) {
                continue;
            }
            let (neg, pos) = cls.sides(k.cell_vertices(p - 1, f).iter().copied(), id);
            if neg && pos {
                out.push((p - 1, f));
                if p > 2 {
                    stack.push((p - 1, f));
                }
            }
        }
    }
}

/// ζ_p as CSR: old cell i ↦ ε⁻ i (+ ε⁺ plus(i) when split), new cut cells empty.
fn identity_rows(
    rows: usize,
    cols: usize,
    plus: &[usize],
    eps_minus: &[i8],
    eps_plus: &[i8],
) -> CsMat<i8> {
    // Rows in order: old cells (their negative piece or themselves), the
    // positive pieces in the order of their parents, then empty rows for the
    // new cut cells.
    let mut indptr = Vec::with_capacity(rows + 1);
    let mut indices = Vec::with_capacity(rows);
    let mut data = Vec::with_capacity(rows);
    indptr.push(0);
    for i in 0..cols {
        indices.push(i);
        data.push(eps_minus.get(i).copied().unwrap_or(1));
        indptr.push(indices.len());
    }
    for (i, &q) in plus.iter().enumerate() {
        if q != usize::MAX {
            indices.push(i);
            data.push(eps_plus[i]);
            indptr.push(indices.len());
        }
    }
    indptr.resize(rows + 1, indices.len());
    CsMat::new((rows, cols), indptr, indices, data)
}

fn nodal_matrix(old: usize, new: &[(usize, usize, f64)]) -> CsMat<f64> {
    let rows = old + new.len();
    let mut indptr = Vec::with_capacity(rows + 1);
    let mut indices = Vec::with_capacity(old + 2 * new.len());
    let mut data = Vec::with_capacity(old + 2 * new.len());
    indptr.push(0);
    for i in 0..old {
        indices.push(i);
        data.push(1.0);
        indptr.push(indices.len());
    }
    for &(a, b, t) in new {
        // a < b: the edge's vertices are sorted.
        indices.push(a);
        data.push(1.0 - t);
        indices.push(b);
        data.push(t);
        indptr.push(indices.len());
    }
    CsMat::new((rows, old), indptr, indices, data)
}

/// Phase timings printed on stderr when `HASSE_SPLIT_PROFILE` is set (used
/// by the `split_timing` example to attribute the cost of a SPLIT).
struct Phases {
    last: Option<std::time::Instant>,
}

impl Phases {
    fn new() -> Self {
        Self {
            last: std::env::var_os("HASSE_SPLIT_PROFILE").map(|_| std::time::Instant::now()),
        }
    }

    fn lap(&mut self, what: &str) {
        if let Some(last) = self.last {
            let now = std::time::Instant::now();
            eprintln!("  split: {what:<28} {:8.3} s", (now - last).as_secs_f64());
            self.last = Some(now);
        }
    }
}
