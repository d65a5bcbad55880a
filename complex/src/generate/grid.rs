//! Structured tensor-product grids: coordinate axes, cuboidal grids, their
//! Kuhn (Freudenthal) simplicial subdivision, and a box with a cavity.

use super::structured::{self, Family};
use super::{invalid, tag_boundary};
use crate::cells::{TopCells, Vertices};
use crate::error::Result;
use crate::Complex;

/// Names of the side tags, indexed by `2 * axis + side`.
const SIDE_NAMES: [&str; 6] = ["xmin", "xmax", "ymin", "ymax", "zmin", "zmax"];

fn check_interval(n: usize, a: f64, b: f64) -> Result<()> {
    if n == 0 {
        return invalid("n must be at least 1, got 0".into());
    }
    if !(a.is_finite() && b.is_finite() && a < b) {
        return invalid(format!(
            "the interval ends must be finite with a < b, got a = {a}, b = {b}"
        ));
    }
    Ok(())
}

/// `n + 1` equally spaced coordinates from `a` to `b` (both included
/// exactly): `n` cells of width `(b − a) / n`.
///
/// ```
/// use hasse_complex::generate::uniform_axis;
/// assert_eq!(uniform_axis(4, 0.0, 1.0).unwrap(), vec![0.0, 0.25, 0.5, 0.75, 1.0]);
/// assert!(uniform_axis(0, 0.0, 1.0).is_err());
/// ```
pub fn uniform_axis(n: usize, a: f64, b: f64) -> Result<Vec<f64>> {
    check_interval(n, a, b)?;
    let mut x: Vec<f64> = (0..=n)
        .map(|k| a + (b - a) * (k as f64 / n as f64))
        .collect();
    x[n] = b;
    Ok(x)
}

/// `n + 1` geometrically graded coordinates from `a` to `b`: consecutive
/// spacings multiply by `ratio` (> 1 refines towards `a`, < 1 towards `b`,
/// 1 is uniform). The first spacing is `(b − a)(ratio − 1)/(ratio^n − 1)`.
///
/// ```
/// use hasse_complex::generate::graded_axis;
/// let x = graded_axis(3, 0.0, 7.0, 2.0).unwrap(); // spacings 1, 2, 4
/// assert_eq!(x, vec![0.0, 1.0, 3.0, 7.0]);
/// assert!(graded_axis(3, 0.0, 1.0, -1.0).is_err());
/// ```
pub fn graded_axis(n: usize, a: f64, b: f64, ratio: f64) -> Result<Vec<f64>> {
    check_interval(n, a, b)?;
    if !(ratio.is_finite() && ratio > 0.0) {
        return invalid(format!(
            "ratio must be a finite number greater than 0, got {ratio}"
        ));
    }
    // Partial sums S_k = Σ_{m<k} ratio^m; x_k = a + (b − a) S_k / S_n.
    let mut sums = Vec::with_capacity(n + 1);
    let (mut sum, mut power) = (0.0f64, 1.0f64);
    for _ in 0..=n {
        sums.push(sum);
        sum += power;
        power *= ratio;
    }
    let total = sums[n];
    if !(total.is_finite() && total > 0.0) {
        return invalid(format!(
            "ratio = {ratio} is too extreme for n = {n} cells: the spacings overflow"
        ));
    }
    let mut x: Vec<f64> = sums.iter().map(|s| a + (b - a) * (s / total)).collect();
    x[n] = b;
    if let Some(k) = (1..=n).find(|&k| x[k] <= x[k - 1]) {
        return invalid(format!(
            "ratio = {ratio} is too extreme for n = {n} cells: coordinates {} and {k} coincide in floating point",
            k - 1
        ));
    }
    Ok(x)
}

/// Validated grid layout: the axes, the vertex count per axis and strides.
pub(super) struct Layout<'a> {
    pub(super) axes: &'a [Vec<f64>],
    pub(super) counts: Vec<usize>,
    pub(super) strides: [usize; 3],
}

impl<'a> Layout<'a> {
    pub(super) fn new(axes: &'a [Vec<f64>]) -> Result<Self> {
        if !(1..=3).contains(&axes.len()) {
            return invalid(format!(
                "a grid needs 1 to 3 coordinate axes, got {}",
                axes.len()
            ));
        }
        for (a, axis) in axes.iter().enumerate() {
            if axis.len() < 2 {
                return invalid(format!(
                    "axis {a} must have at least 2 coordinates (one cell), got {}",
                    axis.len()
                ));
            }
            if let Some(k) = axis.iter().position(|x| !x.is_finite()) {
                return invalid(format!(
                    "axis {a}: coordinate {k} is {}, coordinates must be finite",
                    axis[k]
                ));
            }
            if let Some(k) = (1..axis.len()).find(|&k| axis[k] <= axis[k - 1]) {
                return invalid(format!(
                    "axis {a} must be strictly increasing: coordinate {k} ({}) does not exceed coordinate {} ({})",
                    axis[k],
                    k - 1,
                    axis[k - 1]
                ));
            }
        }
        let counts: Vec<usize> = axes.iter().map(Vec::len).collect();
        let mut strides = [0; 3];
        let mut acc = 1usize;
        for (a, &c) in counts.iter().enumerate() {
            strides[a] = acc;
            acc = acc.saturating_mul(c);
        }
        if acc > u32::MAX as usize {
            return invalid(format!(
                "the grid has {acc} vertices; at most {} are supported",
                u32::MAX
            ));
        }
        Ok(Self {
            axes,
            counts,
            strides,
        })
    }

    pub(super) fn dim(&self) -> usize {
        self.axes.len()
    }

    pub(super) fn vertex_count(&self) -> usize {
        self.counts.iter().product()
    }

    pub(super) fn vertices(&self) -> Result<Vertices> {
        let d = self.dim();
        let mut coords = Vec::with_capacity(self.vertex_count() * d);
        let one = [0.0];
        let y: &[f64] = self.axes.get(1).map_or(&one, Vec::as_slice);
        let z: &[f64] = self.axes.get(2).map_or(&one, Vec::as_slice);
        for &zk in z {
            for &yj in y {
                for &xi in &self.axes[0] {
                    coords.extend_from_slice(&[xi, yj, zk][..d]);
                }
            }
        }
        Vertices::new(d, coords)
    }

    /// Integer grid index of vertex `v` along `axis`.
    fn index(&self, v: usize, axis: usize) -> usize {
        (v / self.strides[axis]) % self.counts[axis]
    }

    /// Lowest-corner vertices of every cell, x fastest.
    fn cell_origins(&self) -> impl ExactSizeIterator<Item = usize> + '_ {
        let cells = |a: usize| self.counts.get(a).map_or(1, |c| c - 1);
        let (nx, ny, nz) = (cells(0), cells(1), cells(2));
        // One flat range (rather than nested loops) so the count is known
        // up front and the cell lists are allocated once.
        (0..nx * ny * nz).map(move |c| {
            let (i, j, k) = (c % nx, (c / nx) % ny, c / (nx * ny));
            i + j * self.strides[1] + k * self.strides[2]
        })
    }

    /// Offset of local tensor-order corner `l` of a cell.
    fn corner(&self, l: usize) -> usize {
        (0..self.dim())
            .filter(|a| (l >> a) & 1 == 1)
            .map(|a| self.strides[a])
            .sum()
    }

    /// Which side tag a boundary facet belongs to: all its vertices share
    /// the first or last index along one axis.
    fn side(&self, facet: &[usize]) -> Option<usize> {
        (0..self.dim()).find_map(|a| {
            let last = self.counts[a] - 1;
            if facet.iter().all(|&v| self.index(v, a) == 0) {
                Some(2 * a)
            } else if facet.iter().all(|&v| self.index(v, a) == last) {
                Some(2 * a + 1)
            } else {
                None
            }
        })
    }

    pub(super) fn tag(&self, complex: &mut Complex) -> Result<()> {
        tag_boundary(complex, &SIDE_NAMES[..2 * self.dim()], |f| self.side(f))
    }
}

/// Cuboidal grid on the tensor product of 1 to 3 strictly increasing
/// coordinate arrays: segments, quads or hexahedra.
///
/// Vertices and top cells are numbered x fastest, then y, then z: vertex
/// `(i, j, k)` is `i + nx1 (j + ny1 k)` with `nx1 = axes[0].len()`,
/// `ny1 = axes[1].len()`; each cell lists its corners in tensor order
/// (`[v00, v10, v01, v11]`). Lower cells are numbered by the complex
/// (by sorted vertex list). The boundary (n−1)-cells are tagged
/// `"xmin"`, `"xmax"` (and `"ymin"`, `"ymax"`, `"zmin"`, `"zmax"` in 2D/3D)
/// and all of them `"boundary"`.
///
/// The cells, ∂_p and orientation are written directly from the grid's
/// index arithmetic, equal bit for bit to what [`Complex::build`] makes of
/// the same top cells, at a fraction of its cost.
///
/// ```
/// use hasse_complex::generate::{grid, graded_axis, uniform_axis};
/// let x = uniform_axis(3, 0.0, 1.0).unwrap();
/// let y = graded_axis(2, 0.0, 1.0, 1.5).unwrap();
/// let k = grid(&[x, y]).unwrap();
/// assert_eq!(k.cell_counts(), vec![12, 17, 6]);
/// assert_eq!(k.tag("ymax").unwrap().cells.len(), 3);
/// assert_eq!(k.tag("boundary").unwrap().cells.len(), 10);
/// ```
pub fn grid(axes: &[Vec<f64>]) -> Result<Complex> {
    let layout = Layout::new(axes)?;
    if structured::well_shaped(&layout) {
        return structured::build(&layout, Family::Cuboid);
    }
    grid_general(&layout)
}

/// [`grid`] through the general path: top cells handed to
/// [`Complex::build`] (facet extraction, LAR products, geometric signs).
/// The direct builder must reproduce it exactly; it also serves cells too
/// thin for the direct builder's combinatorial signs to be certain.
pub(super) fn grid_general(layout: &Layout) -> Result<Complex> {
    let corners: Vec<usize> = (0..1usize << layout.dim())
        .map(|l| layout.corner(l))
        .collect();
    let cells = match layout.dim() {
        1 => TopCells::cuboids(layout.cell_origins().map(|o| [o, o + 1])),
        2 => TopCells::cuboids(
            layout
                .cell_origins()
                .map(|o| std::array::from_fn::<usize, 4, _>(|l| o + corners[l])),
        ),
        _ => TopCells::cuboids(
            layout
                .cell_origins()
                .map(|o| std::array::from_fn::<usize, 8, _>(|l| o + corners[l])),
        ),
    };
    let mut complex = Complex::build(layout.vertices()?, cells)?;
    layout.tag(&mut complex)?;
    Ok(complex)
}

/// `n` equal segments on `[a, b]`; tags `"xmin"`, `"xmax"`, `"boundary"`.
///
/// ```
/// let k = hasse_complex::generate::interval(5, 0.0, 1.0).unwrap();
/// assert_eq!(k.cell_counts(), vec![6, 5]);
/// assert_eq!(k.tag("xmax").unwrap().cells, vec![5]);
/// ```
pub fn interval(n: usize, a: f64, b: f64) -> Result<Complex> {
    grid(&[uniform_axis(n, a, b)?])
}

/// A uniform `nx × ny` quad grid on `[x0, x1] × [y0, y1]` (see [`grid`]).
///
/// ```
/// let k = hasse_complex::generate::rectangle(2, 3, [0.0, 1.0], [-1.0, 1.0]).unwrap();
/// assert_eq!(k.cell_counts(), vec![12, 17, 6]);
/// assert_eq!(k.euler_characteristic(), 1);
/// ```
pub fn rectangle(nx: usize, ny: usize, x: [f64; 2], y: [f64; 2]) -> Result<Complex> {
    grid(&[axis("nx", nx, x)?, axis("ny", ny, y)?])
}

/// A uniform `nx × ny × nz` hexahedral grid on `[x0, x1] × [y0, y1] × [z0, z1]`
/// (see [`grid`]).
///
/// ```
/// let k = hasse_complex::generate::box3(2, 2, 1, [0.0, 1.0], [0.0, 1.0], [0.0, 0.5]).unwrap();
/// assert_eq!(k.cell_counts(), vec![18, 33, 20, 4]);
/// assert_eq!(k.tag("zmin").unwrap().cells.len(), 4);
/// ```
pub fn box3(
    nx: usize,
    ny: usize,
    nz: usize,
    x: [f64; 2],
    y: [f64; 2],
    z: [f64; 2],
) -> Result<Complex> {
    grid(&[axis("nx", nx, x)?, axis("ny", ny, y)?, axis("nz", nz, z)?])
}

/// A uniform axis with errors naming the caller's parameters.
fn axis(name: &str, n: usize, ends: [f64; 2]) -> Result<Vec<f64>> {
    if n == 0 {
        return invalid(format!("{name} must be at least 1, got 0"));
    }
    let range = name.trim_start_matches('n');
    if !(ends[0].is_finite() && ends[1].is_finite() && ends[0] < ends[1]) {
        return invalid(format!(
            "{range} = [{}, {}] must be finite with {range}[0] < {range}[1]",
            ends[0], ends[1]
        ));
    }
    uniform_axis(n, ends[0], ends[1])
}

/// Kuhn (Freudenthal) simplicial subdivision of [`grid`]`(axes)`: the same
/// vertices, each square split into 2 triangles along its `v00–v11`
/// diagonal and each cube into 6 tetrahedra, one per permutation π of the
/// axes (the path `v000 → +e_π1 → +e_π2 → +e_π3`). All cells of a cube share
/// its main diagonal, and neighbouring cubes agree on the diagonals of
/// their common faces, so the result is a simplicial complex. Top cells are
/// numbered grid cell by grid cell (x fastest), 2 or 6 per cell; the tags
/// are those of [`grid`].
///
/// ```
/// use hasse_complex::generate::{kuhn, uniform_axis};
/// let x = uniform_axis(2, 0.0, 1.0).unwrap();
/// let k = kuhn(&[x.clone(), x.clone(), x]).unwrap();
/// assert_eq!(k.cell_count(3), 48);
/// assert_eq!(k.euler_characteristic(), 1);
/// ```
pub fn kuhn(axes: &[Vec<f64>]) -> Result<Complex> {
    let layout = Layout::new(axes)?;
    if structured::well_shaped(&layout) {
        return structured::build(&layout, Family::Kuhn);
    }
    kuhn_general(&layout)
}

/// [`kuhn`] through the general path (see [`grid_general`]).
pub(super) fn kuhn_general(layout: &Layout) -> Result<Complex> {
    let c = |l: usize| layout.corner(l);
    let cells = match layout.dim() {
        1 => TopCells::simplices(layout.cell_origins().map(|o| [o, o + 1])),
        2 => {
            let tris = [[c(0), c(1), c(3)], [c(0), c(2), c(3)]];
            TopCells::simplices(
                layout
                    .cell_origins()
                    .flat_map(|o| tris.map(|t| t.map(|x| x + o))),
            )
        }
        _ => {
            const PERMUTATIONS: [[usize; 3]; 6] = [
                [0, 1, 2],
                [0, 2, 1],
                [1, 0, 2],
                [1, 2, 0],
                [2, 0, 1],
                [2, 1, 0],
            ];
            let tets =
                PERMUTATIONS.map(|[a, b, _]| [c(0), c(1 << a), c((1 << a) | (1 << b)), c(7)]);
            TopCells::simplices(
                layout
                    .cell_origins()
                    .flat_map(|o| tets.map(|t| t.map(|x| x + o))),
            )
        }
    };
    let mut complex = Complex::build(layout.vertices()?, cells)?;
    layout.tag(&mut complex)?;
    Ok(complex)
}

/// The unit cube `[0, 1]^3` as an `n × n × n` hexahedral grid with a closed
/// cubical cavity: the cells `(i, j, k)` with all three indices in
/// `cavity[0]..cavity[1]` (half-open) are removed, together with the
/// vertices strictly inside them. The cavity must not touch the outer
/// boundary: `1 ≤ cavity[0] < cavity[1] ≤ n − 1`.
///
/// Remaining vertices keep the x-fastest order of the full grid. Tags:
/// `"outer"` (faces on the cube's surface), `"cavity"` (faces of the
/// cavity wall, `6 c²` for `c = cavity[1] − cavity[0]`) and `"boundary"`.
///
/// ```
/// let k = hasse_complex::generate::hollow_box(3, [1, 2]).unwrap();
/// assert_eq!(k.cell_count(3), 26);
/// assert_eq!(k.euler_characteristic(), 2); // a sphere shell
/// assert_eq!(k.tag("cavity").unwrap().cells.len(), 6);
/// ```
pub fn hollow_box(n: usize, cavity: [usize; 2]) -> Result<Complex> {
    if n < 3 {
        return invalid(format!(
            "n must be at least 3 for a cavity to fit strictly inside the box, got {n}"
        ));
    }
    let [c0, c1] = cavity;
    if !(1 <= c0 && c0 < c1 && c1 < n) {
        return invalid(format!(
            "cavity must satisfy 1 <= cavity[0] < cavity[1] <= n - 1 = {} so that it is non-empty and does not touch the outer boundary, got [{c0}, {c1}]",
            n - 1
        ));
    }
    let axis = uniform_axis(n, 0.0, 1.0)?;
    let axes = [axis.clone(), axis.clone(), axis];
    let layout = Layout::new(&axes)?;
    let removed = |i: usize, j: usize, k: usize| {
        (c0..c1).contains(&i) && (c0..c1).contains(&j) && (c0..c1).contains(&k)
    };
    // Vertices strictly inside the cavity belong to no remaining cell.
    let hidden = |v: usize| (0..3).all(|a| (c0 + 1..c1).contains(&layout.index(v, a)));
    let old_ids: Vec<usize> = (0..layout.vertex_count()).filter(|&v| !hidden(v)).collect();
    let mut new_id = vec![usize::MAX; layout.vertex_count()];
    for (new, &old) in old_ids.iter().enumerate() {
        new_id[old] = new;
    }
    let full = layout.vertices()?;
    let coords: Vec<f64> = old_ids
        .iter()
        .flat_map(|&v| full.point(v).iter().copied())
        .collect();
    let corners: [usize; 8] = std::array::from_fn(|l| layout.corner(l));
    let cells = TopCells::cuboids(
        layout
            .cell_origins()
            .filter(|&o| !removed(layout.index(o, 0), layout.index(o, 1), layout.index(o, 2)))
            .map(|o| corners.map(|c| new_id[o + c])),
    );
    let mut complex = Complex::build(Vertices::new(3, coords)?, cells)?;
    // Cavity faces have every index in [c0, c1] ⊂ [1, n − 1]; outer faces
    // lie on a plane where some index is 0 or n.
    tag_boundary(&mut complex, &["outer", "cavity"], |facet| {
        let outer = facet.iter().any(|&v| {
            (0..3).any(|a| {
                let i = layout.index(old_ids[v], a);
                i == 0 || i == n
            })
        });
        Some(if outer { 0 } else { 1 })
    })?;
    Ok(complex)
}
