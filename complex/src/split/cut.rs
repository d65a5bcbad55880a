//! Cutting one cell by one hyperplane: the two pieces of a straddled
//! p-cell and the (p−1)-cell where the plane meets it, with their
//! boundary chains and orientations (used by each round of SPLIT).

use super::round::{relative_orientation, sign_of, Chain, Classifier, Level};
use crate::cells::Vertices;
use crate::complex::Complex;
use crate::error::{ComplexError, SplitError};
use crate::frame;
use nalgebra::Vector3;

#[derive(Default)]
pub(super) struct Scratch {
    pub(super) column: Vec<(usize, i8)>,
    pub(super) set: Vec<u32>,
    pub(super) tally: Vec<(usize, i8, u8)>,
}

#[derive(Default)]
pub(super) struct Pieces {
    pub(super) ids: Vec<usize>,
    pub(super) cut: Vec<usize>,
    pub(super) minus: Vec<(usize, i8)>,
    pub(super) plus: Vec<(usize, i8)>,
    pub(super) minus_set: Vec<u32>,
    pub(super) plus_set: Vec<u32>,
    pub(super) cut_column: Vec<(usize, i8)>,
    pub(super) cut_set: Vec<u32>,
    /// Sign of the cut cell in ∂(negative piece oriented like the parent).
    pub(super) cut_sign: i8,
    pub(super) eps_minus: i8,
    pub(super) eps_plus: i8,
    pub(super) top_minus: i8,
    pub(super) top_plus: i8,
}

pub(super) fn union_sets(level: &Level, cells: impl Iterator<Item = usize>, out: &mut Vec<u32>) {
    out.clear();
    for f in cells {
        out.extend_from_slice(level.set(f));
    }
    out.sort_unstable();
    out.dedup();
}

/// Cut p-cell `c` (its new boundary chain in `scratch.column`) by plane `id`.
#[allow(clippy::too_many_arguments)]
pub(super) fn cut_cell(
    k: &Complex,
    vertices: &Vertices,
    cls: &Classifier,
    edges: &Level,
    lower: &Level,
    p: usize,
    n: usize,
    c: usize,
    id: u32,
    scratch: &mut Scratch,
    out: &mut Pieces,
) -> Result<(), SplitError> {
    let ambiguous = || SplitError::AmbiguousCut { dim: p, cell: c };
    let Pieces {
        ids,
        cut,
        minus,
        plus,
        minus_set,
        plus_set,
        cut_column,
        cut_set,
        ..
    } = out;
    minus.clear();
    plus.clear();
    // Facets with a vertex strictly below go to the negative piece, the rest
    // (positive or lying in the plane) to the positive one.
    scratch.tally.clear();
    for &(f, r) in &scratch.column {
        let (neg, pos) = cls.sides(lower.set(f).iter().map(|&v| v as usize), id);
        if neg && pos {
            return Err(ambiguous());
        }
        let side = if neg { 1u8 } else { 2u8 };
        if neg {
            minus.push((f, r));
        } else {
            plus.push((f, r));
        }
        // The cut is made of the (p−2)-cells met by facets of both sides.
        for &g in lower.column(f).0 {
            match scratch.tally.iter_mut().find(|t| t.0 == g) {
                Some(t) => t.2 |= side,
                None => scratch.tally.push((g, 0, side)),
            }
        }
    }
    if minus.is_empty() || plus.is_empty() {
        return Err(ambiguous());
    }
    cut.clear();
    cut.extend(scratch.tally.iter().filter(|t| t.2 == 3).map(|t| t.0));
    cut.sort_unstable();
    // The new (p−1)-cell N and its boundary in its own orientation.
    if p == 2 {
        if cut.len() != 2 {
            return Err(ambiguous());
        }
        cut_column.clear();
        cut_column.extend([(cut[0], -1), (cut[1], 1)]);
        cut_set.clear();
        cut_set.extend([cut[0] as u32, cut[1] as u32]);
    } else {
        (*cut_column, *cut_set) = cut_polygon(vertices, edges, cut, p, c)?;
    }
    // ∂∂ = 0 on the negative piece fixes the sign of N: the coefficient of
    // the first face g of N in ∂(minus part) must cancel with ∂N.
    let (g, ng) = cut_column[0];
    let mut coef: i32 = 0;
    for &(f, r) in minus.iter() {
        let (rows, signs) = lower.column(f);
        if let Ok(pos) = rows.binary_search(&g) {
            coef += i32::from(r) * i32::from(signs[pos]);
        }
    }
    if coef.abs() != 1 {
        return Err(ambiguous());
    }
    let cut_sign = -(coef as i8) * ng;
    union_sets(lower, minus.iter().map(|x| x.0), minus_set);
    union_sets(lower, plus.iter().map(|x| x.0), plus_set);
    let degenerate = |set: &[u32]| {
        SplitError::Complex(ComplexError::DegenerateCell {
            dim: p,
            cell: c,
            vertices: set.iter().map(|&v| v as usize).collect(),
        })
    };
    let mut frame_of = |set: &[u32]| {
        ids.clear();
        ids.extend(set.iter().map(|&v| v as usize));
        frame::frame(vertices, ids, p).ok_or_else(|| degenerate(set))
    };
    let fm = frame_of(minus_set)?;
    let fp = frame_of(plus_set)?;
    let (eps_minus, eps_plus, top_minus, top_plus) = if p == n {
        // Top cells are stored positively oriented: the pieces keep the
        // parent's orientation; only the flag relative to the sorted frame is new.
        (
            1,
            1,
            sign_of(frame::det(n, &fm.basis)),
            sign_of(frame::det(n, &fp.basis)),
        )
    } else {
        let parent = frame::frame(vertices, k.cell_vertices(p, c), p)
            .ok_or_else(|| degenerate(minus_set))?;
        (
            relative_orientation(&fm, &parent),
            relative_orientation(&fp, &parent),
            1,
            1,
        )
    };
    out.cut_sign = cut_sign;
    out.eps_minus = eps_minus;
    out.eps_plus = eps_plus;
    out.top_minus = top_minus;
    out.top_plus = top_plus;
    Ok(())
}

/// The cut polygon of a polyhedron: its edges `cut` form one cycle; walk it
/// and orient the chain like the frame of the polygon's sorted vertices.
pub(super) fn cut_polygon(
    vertices: &Vertices,
    edges: &Level,
    cut: &[usize],
    p: usize,
    c: usize,
) -> Result<(Chain, Vec<u32>), SplitError> {
    let ambiguous = || SplitError::AmbiguousCut { dim: p, cell: c };
    let ends: Vec<[usize; 2]> = cut
        .iter()
        .map(|&e| {
            let s = edges.set(e);
            [s[0] as usize, s[1] as usize]
        })
        .collect();
    if ends.len() < 3 {
        return Err(ambiguous());
    }
    let mut chain = Vec::with_capacity(cut.len());
    let mut order = Vec::with_capacity(cut.len());
    let mut used = vec![false; cut.len()];
    let start = ends[0][0];
    let mut at = ends[0][1];
    used[0] = true;
    chain.push((cut[0], 1i8));
    order.push(start);
    while at != start {
        order.push(at);
        let next = (0..cut.len()).find(|&i| !used[i] && (ends[i][0] == at || ends[i][1] == at));
        let Some(i) = next else {
            return Err(ambiguous());
        };
        used[i] = true;
        if ends[i][0] == at {
            chain.push((cut[i], 1));
            at = ends[i][1];
        } else {
            chain.push((cut[i], -1));
            at = ends[i][0];
        }
    }
    if used.iter().any(|&u| !u) {
        return Err(ambiguous());
    }
    let mut set: Vec<u32> = order.iter().map(|&v| v as u32).collect();
    set.sort_unstable();
    let ids: Vec<usize> = set.iter().map(|&v| v as usize).collect();
    let f = frame::frame(vertices, &ids, 2).ok_or(SplitError::Complex(
        ComplexError::DegenerateCell {
            dim: 2,
            cell: c,
            vertices: ids.clone(),
        },
    ))?;
    // Newell's normal of the walk against the normal of the sorted frame.
    let mut newell = Vector3::zeros();
    for w in 0..order.len() {
        let a = Vector3::from(frame::point(vertices, order[w]));
        let b = Vector3::from(frame::point(vertices, order[(w + 1) % order.len()]));
        newell += a.cross(&b);
    }
    let normal = Vector3::from(f.basis[0]).cross(&Vector3::from(f.basis[1]));
    let eps = sign_of(newell.dot(&normal));
    let mut column: Vec<(usize, i8)> = chain.into_iter().map(|(e, s)| (e, s * eps)).collect();
    column.sort_unstable();
    Ok((column, set))
}
