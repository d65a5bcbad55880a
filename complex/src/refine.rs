//! Refinement strategies built on [`split_cells`]: uniform and local
//! refinement, longest-edge bisection, Dörfler marking, and the division
//! rules used for growing tissues (a cell divides through its centroid,
//! normal to its longest axis, or along its shortest wall).
//!
//! Every strategy returns the refined complex and the composed
//! [`Refinement`] (ζ for every dimension and the nodal interpolation), so
//! fields move to the new complex with the transfers documented in
//! [`crate::split`].
//!
//! ```
//! use hasse_complex::generate::rectangle;
//! use hasse_complex::refine::{dorfler_mark, refine_marked};
//! let k = rectangle(4, 4, [0.0, 1.0], [0.0, 1.0]).unwrap();
//! // Refine where an indicator is large.
//! let eta: Vec<f64> = (0..16).map(|c| if c == 5 { 1.0 } else { 0.1 }).collect();
//! let marked = dorfler_mark(&eta, 0.5).unwrap();
//! assert_eq!(marked, vec![5]);
//! let (fine, _) = refine_marked(&k, &marked).unwrap();
//! assert_eq!(fine.cell_count(2), 16 + 3);
//! ```

use crate::cells::{TopCells, Vertices};
use crate::complex::Complex;
use crate::error::SplitError;
use crate::split::{split_cells, Hyperplane, Refinement, SplitOptions};
use nalgebra::{Matrix2, Matrix3, SymmetricEigen, Vector3};
use sprs::CsMat;

/// Split each listed top cell by the d axis-aligned hyperplanes through its
/// centroid (quads → 4 quads, hexes → 8 hexes, simplices → convex
/// polygons/polyhedra). Each piece is cut by its *parent's* centroid
/// planes, one axis after the other.
fn centroid_planes(
    complex: &Complex,
    cells: &[usize],
) -> Result<(Complex, Refinement), SplitError> {
    let n = complex.dim();
    let d = complex.embedding_dim();
    check_cells(complex, cells)?;
    let centroids: Vec<Vec<f64>> = cells
        .iter()
        .map(|&c| complex.centroid_of(n, c).to_vec())
        .collect();
    let mut current = complex.clone();
    let mut total = Refinement::identity(complex);
    // Pieces of cell c after each pass: the fine cells whose parent is c.
    let mut owner: Vec<Option<usize>> = vec![None; complex.cell_count(n)];
    for (k, &c) in cells.iter().enumerate() {
        owner[c] = Some(k);
    }
    // One pass per axis: a piece created by the x cut is cut again by its
    // parent's y plane in the next pass.
    #[allow(clippy::needless_range_loop)]
    for axis in 0..d {
        let mut cuts = Vec::new();
        for (j, o) in owner.iter().enumerate() {
            if let Some(k) = *o {
                cuts.push((j, Hyperplane::axis(d, axis, centroids[k][axis])?));
            }
        }
        let (fine, r) = split_cells(&current, &cuts, SplitOptions::default())?;
        owner = (0..fine.cell_count(n))
            .map(|i| r.parent(n, i).and_then(|(j, _)| owner[j]))
            .collect();
        total = total.compose(&r)?;
        current = fine;
    }
    Ok((current, total))
}

/// (n, d) of a complex that SPLIT can cut: cells filling R² or R³.
fn space_filling_dims(complex: &Complex) -> Result<(usize, usize), SplitError> {
    let n = complex.dim();
    let d = complex.embedding_dim();
    if n != d || !(2..=3).contains(&n) {
        return Err(SplitError::Unsupported {
            dim: n,
            embedding: d,
        });
    }
    Ok((n, d))
}

fn check_cells(complex: &Complex, cells: &[usize]) -> Result<(), SplitError> {
    let n = complex.dim();
    let count = complex.cell_count(n);
    match cells.iter().find(|&&c| c >= count) {
        Some(&cell) => Err(SplitError::CellOutOfRange { p: n, cell, count }),
        None => Ok(()),
    }
}

/// Uniform refinement: every top cell split by the axis-aligned hyperplanes
/// through its centroid. Quads and hexes of an axis-aligned grid become 4
/// or 8 equal children; simplices become convex polygons or polyhedra.
///
/// ```
/// use hasse_complex::generate::rectangle;
/// use hasse_complex::refine::uniform;
/// let k = rectangle(2, 2, [0.0, 1.0], [0.0, 1.0]).unwrap();
/// let (fine, r) = uniform(&k).unwrap();
/// assert_eq!(fine.cell_counts(), vec![25, 40, 16]);
/// assert_eq!(r.zeta(2).nnz(), 16);
/// ```
pub fn uniform(complex: &Complex) -> Result<(Complex, Refinement), SplitError> {
    let all: Vec<usize> = (0..complex.cell_count(complex.dim())).collect();
    centroid_planes(complex, &all)
}

/// Local refinement: only the marked top cells are split (as in
/// [`uniform`]); their neighbours keep their index and receive the new
/// vertices on shared faces (hanging nodes are legal here: cells are
/// convex polytopes, not fixed shapes).
///
/// ```
/// use hasse_complex::generate::rectangle;
/// use hasse_complex::refine::refine_marked;
/// let k = rectangle(2, 1, [0.0, 2.0], [0.0, 1.0]).unwrap();
/// let (fine, _) = refine_marked(&k, &[0]).unwrap();
/// assert_eq!(fine.cell_count(2), 5);
/// // The right square now has a vertex in the middle of its left side.
/// assert_eq!(fine.cell_vertices(2, 1).len(), 5);
/// ```
pub fn refine_marked(
    complex: &Complex,
    marked: &[usize],
) -> Result<(Complex, Refinement), SplitError> {
    let mut cells = marked.to_vec();
    cells.sort_unstable();
    cells.dedup();
    centroid_planes(complex, &cells)
}

/// Longest-edge bisection of the listed top cells: a simplex is cut through
/// the midpoint of its longest edge and its vertices off that edge (so a
/// triangle gives two triangles, a tetrahedron two tetrahedra); any other
/// cell by the plane through that midpoint normal to the edge. Neighbours
/// that share the bisected edge and bisect it too share the midpoint.
///
/// ```
/// use hasse_complex::generate::{kuhn, uniform_axis};
/// use hasse_complex::refine::bisect_longest_edge;
/// let x = uniform_axis(1, 0.0, 1.0).unwrap();
/// let k = kuhn(&[x.clone(), x]).unwrap(); // two triangles sharing the diagonal
/// let (fine, _) = bisect_longest_edge(&k, &[0, 1]).unwrap();
/// assert_eq!(fine.cell_counts(), vec![5, 8, 4]);
/// assert!((0..4).all(|c| fine.cell_vertices(2, c).len() == 3));
/// ```
pub fn bisect_longest_edge(
    complex: &Complex,
    cells: &[usize],
) -> Result<(Complex, Refinement), SplitError> {
    let (n, d) = space_filling_dims(complex)?;
    check_cells(complex, cells)?;
    let point = |v: usize| Vector3::from(padded(complex.vertices().point(v)));
    let mut cuts = Vec::with_capacity(cells.len());
    for &c in cells {
        let verts = complex.cell_vertices(n, c);
        let (mut best, mut best_len) = ((verts[0], verts[0]), -1.0);
        for (i, &a) in verts.iter().enumerate() {
            for &b in &verts[i + 1..] {
                let len = (point(b) - point(a)).norm();
                if len > best_len && is_edge(complex, a, b) {
                    (best, best_len) = ((a, b), len);
                }
            }
        }
        let (a, b) = best;
        let mid: Vec<f64> = (0..d).map(|k| 0.5 * (point(a)[k] + point(b)[k])).collect();
        let others: Vec<usize> = verts
            .iter()
            .copied()
            .filter(|&v| v != a && v != b)
            .collect();
        let normal = if verts.len() == n + 1 {
            // The plane spanned by the midpoint and the opposite vertices.
            let m = Vector3::from(padded(&mid));
            match n {
                2 => {
                    let t = point(others[0]) - m;
                    vec![-t[1], t[0]]
                }
                _ => {
                    let u = point(others[0]) - m;
                    let w = point(others[1]) - m;
                    u.cross(&w).as_slice().to_vec()
                }
            }
        } else {
            (point(b) - point(a)).as_slice()[..d].to_vec()
        };
        cuts.push((c, Hyperplane::through(&mid, &normal)?));
    }
    split_cells(complex, &cuts, SplitOptions::default())
}

fn is_edge(complex: &Complex, a: usize, b: usize) -> bool {
    complex.find_cell(1, &[a, b]).is_some()
}

/// Dörfler (bulk) marking: the smallest set M of cells, taken in order of
/// decreasing indicator, with Σ_{M} η² ≥ θ Σ η². Returns cell ids sorted by
/// decreasing indicator (ties by id). `theta` must lie in (0, 1] and every
/// indicator must be finite and non-negative.
///
/// ```
/// use hasse_complex::refine::dorfler_mark;
/// // η² = 9, 1, 4, 0 (total 14): half of it needs the first cell only.
/// assert_eq!(dorfler_mark(&[3.0, 1.0, 2.0, 0.0], 0.5).unwrap(), vec![0]);
/// assert_eq!(dorfler_mark(&[3.0, 1.0, 2.0, 0.0], 0.7).unwrap(), vec![0, 2]);
/// assert!(dorfler_mark(&[1.0], 0.0).is_err());
/// ```
pub fn dorfler_mark(indicators: &[f64], theta: f64) -> Result<Vec<usize>, SplitError> {
    if !(theta > 0.0 && theta <= 1.0) {
        return Err(SplitError::Invalid(format!(
            "Dörfler fraction θ = {theta} must lie in (0, 1]"
        )));
    }
    if let Some(i) = indicators
        .iter()
        .position(|&e| !(e.is_finite() && e >= 0.0))
    {
        return Err(SplitError::Invalid(format!(
            "indicator of cell {i} is {}, expected a finite value ≥ 0",
            indicators[i]
        )));
    }
    let mut order: Vec<usize> = (0..indicators.len()).collect();
    order.sort_by(|&a, &b| indicators[b].total_cmp(&indicators[a]).then(a.cmp(&b)));
    // Summed in the marking order, so that θ = 1 is reached exactly at the
    // last non-zero indicator.
    let total: f64 = order.iter().map(|&i| indicators[i] * indicators[i]).sum();
    let goal = theta * total;
    let mut acc = 0.0;
    let mut marked = Vec::new();
    for i in order {
        if acc >= goal {
            break;
        }
        acc += indicators[i] * indicators[i];
        marked.push(i);
    }
    Ok(marked)
}

/// Division rule (a): each listed cell divides by the plane through its
/// centroid normal to its longest axis — the principal axis of largest
/// variance of its vertex cloud.
///
/// ```
/// use hasse_complex::generate::rectangle;
/// use hasse_complex::refine::divide_longest_axis;
/// let k = rectangle(1, 1, [0.0, 2.0], [0.0, 1.0]).unwrap();
/// let (fine, _) = divide_longest_axis(&k, &[0]).unwrap();
/// assert_eq!(fine.measure(2), &[1.0, 1.0]); // cut by x = 1
/// ```
pub fn divide_longest_axis(
    complex: &Complex,
    cells: &[usize],
) -> Result<(Complex, Refinement), SplitError> {
    let n = complex.dim();
    let d = complex.embedding_dim();
    check_cells(complex, cells)?;
    let mut cuts = Vec::with_capacity(cells.len());
    for &c in cells {
        let verts = complex.cell_vertices(n, c);
        let centroid = complex.centroid_of(n, c).to_vec();
        let mut mean = [0.0; 3];
        for &v in verts {
            for (k, x) in complex.vertices().point(v).iter().enumerate() {
                mean[k] += x / verts.len() as f64;
            }
        }
        let mut cov = [[0.0; 3]; 3];
        for &v in verts {
            let x = complex.vertices().point(v);
            for i in 0..d {
                for j in 0..d {
                    cov[i][j] += (x[i] - mean[i]) * (x[j] - mean[j]);
                }
            }
        }
        let axis = principal_axis(d, &cov);
        cuts.push((c, Hyperplane::through(&centroid, &axis)?));
    }
    split_cells(complex, &cuts, SplitOptions::default())
}

/// Division of a 1-complex (a filament: a chain of edges, in R^d): each
/// listed edge divides at its midpoint. SPLIT cuts cells by hyperplanes and
/// needs n = d ≥ 2; an edge has one possible cut, its midpoint, so this is
/// the rule of every 1D division (the thesis's Anabaena cells divide in
/// half). A divided edge keeps its index for the piece at its lower vertex
/// and the piece at its higher vertex is appended; the midpoints are
/// appended to the vertices. ζ_1 maps the edge to its two pieces (signed by
/// their direction relative to it), ζ_0 keeps the old vertices (midpoints
/// are new cells, without a parent) and the nodal interpolation gives a
/// midpoint ½, ½ of its edge's ends. Tags are kept; a tagged edge's pieces
/// keep its tag.
///
/// ```
/// use hasse_complex::generate::interval;
/// use hasse_complex::refine::divide_midpoint;
/// let k = interval(2, 0.0, 2.0).unwrap();
/// let (fine, r) = divide_midpoint(&k, &[1]).unwrap();
/// assert_eq!(fine.cell_counts(), vec![4, 3]);
/// assert_eq!(fine.measure(1), &[1.0, 0.5, 0.5]);
/// assert_eq!(r.parent(1, 2), Some((1, 1)));
/// assert!(divide_midpoint(&hasse_complex::generate::rectangle(1, 1, [0.0, 1.0], [0.0, 1.0]).unwrap(), &[0]).is_err());
/// ```
pub fn divide_midpoint(
    complex: &Complex,
    cells: &[usize],
) -> Result<(Complex, Refinement), SplitError> {
    if complex.dim() != 1 {
        return Err(SplitError::Invalid(format!(
            "midpoint division divides the edges of a 1-complex (a filament); this complex has dimension {}",
            complex.dim()
        )));
    }
    check_cells(complex, cells)?;
    let mut cells = cells.to_vec();
    cells.sort_unstable();
    cells.dedup();
    let d = complex.embedding_dim();
    let (v0, e0) = (complex.cell_count(0), complex.cell_count(1));
    let mut coords = complex.vertices().as_slice().to_vec();
    let mut edges: Vec<[usize; 2]> = (0..e0)
        .map(|e| {
            let v = complex.cell_vertices(1, e);
            [v[0], v[1]]
        })
        .collect();
    // parent[i] for every fine edge; the midpoint's ends for the nodal rows.
    let mut parent: Vec<usize> = (0..e0).collect();
    let mut ends = Vec::with_capacity(cells.len());
    for (k, &c) in cells.iter().enumerate() {
        let [a, b] = edges[c];
        let m = v0 + k;
        let (xa, xb) = (complex.vertices().point(a), complex.vertices().point(b));
        coords.extend(xa.iter().zip(xb).map(|(p, q)| 0.5 * (p + q)));
        edges[c] = [a, m];
        edges.push([m, b]);
        parent.push(c);
        ends.push((a, b));
    }
    let vertices = Vertices::new(d, coords)?;
    let mut fine = Complex::build(vertices, TopCells::simplices(&edges))?;
    for (name, tag) in complex.tags().iter() {
        let mut tagged = tag.cells.clone();
        if tag.dim == 1 {
            tagged.extend((e0..edges.len()).filter(|&i| tag.contains(parent[i])));
        }
        fine.set_tag(name, tag.dim, tagged)?;
    }
    // The sign of a piece: whether it runs the way its parent does (the
    // direction of an edge is head − tail of its column of ∂_1).
    let direction = |k: &Complex, e: usize| -> Vec<f64> {
        let mut dir = vec![0.0; d];
        if let Some(col) = k.boundary_csc(1).outer_view(e) {
            for (v, &s) in col.iter() {
                for (x, p) in dir.iter_mut().zip(k.vertices().point(v)) {
                    *x += f64::from(s) * p;
                }
            }
        }
        dir
    };
    let mut zeta1 = Vec::with_capacity(edges.len());
    for (i, &c) in parent.iter().enumerate() {
        let (piece, whole) = (direction(&fine, i), direction(complex, c));
        let dot: f64 = piece.iter().zip(&whole).map(|(a, b)| a * b).sum();
        zeta1.push(if dot > 0.0 { 1i8 } else { -1 });
    }
    let fine_edges = fine.cell_count(1);
    if fine_edges != edges.len() {
        return Err(SplitError::Invalid(format!(
            "dividing {} edges gave {fine_edges} edges instead of {}: the filament has repeated edges",
            cells.len(),
            edges.len()
        )));
    }
    let zeta1 = CsMat::new(
        (edges.len(), e0),
        (0..=edges.len()).collect(),
        parent.clone(),
        zeta1,
    );
    let zeta0 = CsMat::new(
        (v0 + cells.len(), v0),
        (0..=v0)
            .chain(std::iter::repeat_n(v0, cells.len()))
            .collect(),
        (0..v0).collect(),
        vec![1i8; v0],
    );
    let mut indptr: Vec<usize> = (0..=v0).collect();
    let mut indices: Vec<usize> = (0..v0).collect();
    let mut data = vec![1.0; v0];
    for &(a, b) in &ends {
        indices.extend([a.min(b), a.max(b)]);
        data.extend([0.5, 0.5]);
        indptr.push(indices.len());
    }
    let nodal = CsMat::new((v0 + cells.len(), v0), indptr, indices, data);
    Ok((fine, Refinement::from_parts(vec![zeta0, zeta1], nodal)))
}

/// Eigenvector of the largest eigenvalue of the leading d × d block.
fn principal_axis(d: usize, cov: &[[f64; 3]; 3]) -> Vec<f64> {
    if d == 2 {
        let m = Matrix2::new(cov[0][0], cov[0][1], cov[1][0], cov[1][1]);
        let e = SymmetricEigen::new(m);
        let k = e.eigenvalues.imax();
        e.eigenvectors.column(k).iter().copied().collect()
    } else {
        let m = Matrix3::from_fn(|i, j| cov[i][j]);
        let e = SymmetricEigen::new(m);
        let k = e.eigenvalues.imax();
        e.eigenvectors.column(k).iter().copied().collect()
    }
}

/// Division rule (b): each listed cell divides by the plane through its
/// centroid whose wall (the section of the cell) is smallest, searched over
/// `directions` normals: equally spaced angles in [0, π) in 2D, a
/// Fibonacci half-sphere in 3D. Returns an error when `directions` is 0.
///
/// ```
/// use hasse_complex::generate::rectangle;
/// use hasse_complex::refine::divide_shortest_wall;
/// let k = rectangle(1, 1, [0.0, 3.0], [0.0, 1.0]).unwrap();
/// let (fine, _) = divide_shortest_wall(&k, &[0], 36).unwrap();
/// // The shortest wall through the centre is the vertical one, length 1.
/// assert_eq!(fine.measure(2), &[1.5, 1.5]);
/// ```
pub fn divide_shortest_wall(
    complex: &Complex,
    cells: &[usize],
    directions: usize,
) -> Result<(Complex, Refinement), SplitError> {
    if directions == 0 {
        return Err(SplitError::Invalid(
            "the shortest-wall search needs at least one direction".into(),
        ));
    }
    let (n, d) = space_filling_dims(complex)?;
    check_cells(complex, cells)?;
    let normals: Vec<[f64; 3]> = (0..directions)
        .map(|k| {
            if d == 2 {
                let a = std::f64::consts::PI * k as f64 / directions as f64;
                [a.cos(), a.sin(), 0.0]
            } else {
                // Fibonacci points on the upper half-sphere (z ≥ 0).
                let z = 1.0 - (k as f64 + 0.5) / directions as f64;
                let r = (1.0 - z * z).sqrt();
                let phi = k as f64 * std::f64::consts::PI * (3.0 - 5f64.sqrt());
                [r * phi.cos(), r * phi.sin(), z]
            }
        })
        .collect();
    let mut cuts = Vec::with_capacity(cells.len());
    for &c in cells {
        let centroid = padded(complex.centroid_of(n, c));
        let mut best = (f64::INFINITY, normals[0]);
        for normal in &normals {
            let wall = section_measure(complex, c, &centroid, normal)?;
            if wall < best.0 {
                best = (wall, *normal);
            }
        }
        cuts.push((c, Hyperplane::through(&centroid[..d], &best.1[..d])?));
    }
    split_cells(complex, &cuts, SplitOptions::default())
}

/// Length (2D) or area (3D) of the section of convex top cell `c` by the
/// plane through `point` with unit normal `normal` (coordinates padded to
/// three components). Errors when `c` is not a top cell.
///
/// ```
/// use hasse_complex::generate::rectangle;
/// use hasse_complex::refine::section_measure;
/// let k = rectangle(1, 1, [0.0, 3.0], [0.0, 1.0]).unwrap();
/// let across = section_measure(&k, 0, &[1.5, 0.5, 0.0], &[1.0, 0.0, 0.0]).unwrap();
/// let along = section_measure(&k, 0, &[1.5, 0.5, 0.0], &[0.0, 1.0, 0.0]).unwrap();
/// assert!(section_measure(&k, 1, &[0.0; 3], &[1.0, 0.0, 0.0]).is_err());
/// assert!((across - 1.0).abs() < 1e-15 && (along - 3.0).abs() < 1e-15);
/// ```
pub fn section_measure(
    complex: &Complex,
    c: usize,
    point: &[f64; 3],
    normal: &[f64; 3],
) -> Result<f64, SplitError> {
    check_cells(complex, &[c])?;
    Ok(section(complex, c, point, normal))
}

fn section(complex: &Complex, c: usize, point: &[f64; 3], normal: &[f64; 3]) -> f64 {
    let n = complex.dim();
    let (point, normal) = (Vector3::from(*point), Vector3::from(*normal));
    // Crossing points of the plane with the cell's edges.
    let mut points: Vec<Vector3<f64>> = Vec::new();
    let dist = |x: &Vector3<f64>| (x - point).dot(&normal);
    let edges = cell_edges(complex, c);
    for (a, b) in edges {
        let (xa, xb) = (
            Vector3::from(padded(complex.vertices().point(a))),
            Vector3::from(padded(complex.vertices().point(b))),
        );
        let (da, db) = (dist(&xa), dist(&xb));
        if (da <= 0.0 && db >= 0.0) || (da >= 0.0 && db <= 0.0) {
            let t = if da == db { 0.0 } else { da / (da - db) };
            points.push(xa + (xb - xa) * t);
        }
    }
    if points.len() < 2 {
        return 0.0;
    }
    if n == 2 {
        let mut longest: f64 = 0.0;
        for (i, a) in points.iter().enumerate() {
            for b in &points[i + 1..] {
                longest = longest.max((b - a).norm());
            }
        }
        return longest;
    }
    // 3D: the section is a convex polygon; order its points by angle about
    // their mean in the plane and sum the fan.
    let mean: Vector3<f64> = points.iter().map(|x| x / points.len() as f64).sum();
    let helper = if normal[0].abs() < 0.9 {
        Vector3::x()
    } else {
        Vector3::y()
    };
    let u = normal.cross(&helper).normalize();
    let w = normal.cross(&u);
    let mut angled: Vec<(f64, Vector3<f64>)> = points
        .iter()
        .map(|x| {
            let r = x - mean;
            (r.dot(&w).atan2(r.dot(&u)), *x)
        })
        .collect();
    angled.sort_by(|a, b| a.0.total_cmp(&b.0));
    let mut area = 0.0;
    for i in 0..angled.len() {
        let a = angled[i].1 - mean;
        let b = angled[(i + 1) % angled.len()].1 - mean;
        area += 0.5 * a.cross(&b).dot(&normal);
    }
    area.abs()
}

/// The edges (as vertex pairs) of top cell `c`, read from the boundary
/// matrices.
fn cell_edges(complex: &Complex, c: usize) -> Vec<(usize, usize)> {
    let n = complex.dim();
    let mut cells = vec![c];
    for p in (2..=n).rev() {
        cells = crate::split::makes::facets_of_all(&cells, complex.boundary_csc(p));
    }
    cells
        .into_iter()
        .map(|e| {
            let v = complex.cell_vertices(1, e);
            (v[0], v[1])
        })
        .collect()
}

fn padded(x: &[f64]) -> [f64; 3] {
    let mut out = [0.0; 3];
    for (o, v) in out.iter_mut().zip(x) {
        *o = *v;
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::generate::interval;

    /// ∂_1 ζ_1 = ζ_0 ∂_1, compared entry by entry (integers).
    fn commutes(coarse: &Complex, fine: &Complex, r: &Refinement) -> bool {
        let left = &**fine.boundary(1) * r.zeta(1);
        let right = r.zeta(0) * &**coarse.boundary(1);
        left.to_dense() == right.to_dense()
    }

    #[test]
    fn midpoint_division_of_a_straight_filament() {
        // Three unit edges on [0, 3]; dividing the first and the last by
        // hand gives 6 vertices, 5 edges (χ = 6 − 5 = 1, as before) and
        // lengths 0.5, 1, 0.5, 0.5, 0.5 in the documented numbering.
        let k = interval(3, 0.0, 3.0).unwrap();
        let (fine, r) = divide_midpoint(&k, &[2, 0]).unwrap();
        assert_eq!(fine.cell_counts(), vec![6, 5]);
        assert_eq!(fine.euler_characteristic(), 1);
        assert_eq!(fine.measure(1), &[0.5, 1.0, 0.5, 0.5, 0.5]);
        assert_eq!(fine.vertices().point(4), &[0.5]);
        assert_eq!(fine.vertices().point(5), &[2.5]);
        assert!(commutes(&k, &fine, &r));
        // Every edge of a filament in R¹ runs towards +x (positive).
        for e in 0..fine.cell_count(1) {
            let col = fine.boundary_csc(1).outer_view(e).unwrap();
            let head_minus_tail: f64 = col
                .iter()
                .map(|(v, &s)| f64::from(s) * fine.vertices().point(v)[0])
                .sum();
            assert!(head_minus_tail > 0.0);
        }
        // The boundary tags keep their vertices, the end points 0 and 3.
        assert_eq!(fine.tag("xmin").unwrap().cells, vec![0]);
        assert_eq!(fine.tag("xmax").unwrap().cells, vec![3]);
        // Midpoint values interpolate ½, ½.
        let u = r.nodal(&[0.0, 1.0, 2.0, 3.0]).unwrap();
        assert_eq!(u, vec![0.0, 1.0, 2.0, 3.0, 0.5, 2.5]);
    }

    #[test]
    fn midpoint_division_of_a_bent_filament_in_the_plane() {
        // An L-shaped chain (0,0) → (1,0) → (1,1): each edge halves, and ζ
        // carries each piece's direction relative to its parent, so ∂ζ = ζ∂
        // whatever orientation the embedded edges got.
        let v = Vertices::from_points(&[[0.0, 0.0], [1.0, 0.0], [1.0, 1.0]]).unwrap();
        let k = Complex::build(v, TopCells::simplices([[0, 1], [1, 2]])).unwrap();
        let (fine, r) = divide_midpoint(&k, &[0, 1]).unwrap();
        assert_eq!(fine.cell_counts(), vec![5, 4]);
        assert!(commutes(&k, &fine, &r));
        assert_eq!(fine.measure(1), &[0.5, 0.5, 0.5, 0.5]);
        // Every piece has a parent (no new edges): 0, 1 and their halves.
        let parents: Vec<usize> = (0..4).map(|e| r.parent(1, e).unwrap().0).collect();
        assert_eq!(parents, vec![0, 1, 0, 1]);
    }

    #[test]
    fn midpoint_division_refuses_other_dimensions_and_bad_cells() {
        let square = crate::generate::rectangle(1, 1, [0.0, 1.0], [0.0, 1.0]).unwrap();
        assert!(divide_midpoint(&square, &[0]).is_err());
        let k = interval(2, 0.0, 1.0).unwrap();
        assert!(matches!(
            divide_midpoint(&k, &[2]),
            Err(SplitError::CellOutOfRange {
                p: 1,
                cell: 2,
                count: 2
            })
        ));
        // Nothing listed: the same filament and the identity map.
        let (same, r) = divide_midpoint(&k, &[]).unwrap();
        assert_eq!(same.cell_counts(), k.cell_counts());
        assert_eq!(r, Refinement::identity(&k));
    }
}
