//! The flat torus: a rectangle with opposite sides identified.

use super::{invalid, positive};
use crate::cells::{TopCells, Vertices};
use crate::error::Result;
use crate::Complex;

/// A uniform `nx × ny` grid of the rectangle `x × y` with opposite sides
/// identified: the flat torus R²/(L_x Z × L_y Z). Vertex `(i, j)` (index
/// `i + nx j`) sits at `(x₀ + i h_x, y₀ + j h_y)`; the last row and column
/// of the rectangle are the first ones again, so there are `nx ny`
/// vertices, `2 nx ny` edges and `nx ny` squares (or `2 nx ny` triangles
/// when `triangles`: each square cut along its diagonal from `(i, j)` to
/// `(i+1, j+1)`).
///
/// The vertices carry the periods ([`Vertices::with_period`]): a cell that
/// wraps around is measured from its unwrapped points, so every measure,
/// centre, dual cell and Hodge star is that of the flat metric, e.g. every
/// square has area h_x h_y. χ = 0 and β = (1, 2, 1); there is no boundary
/// and no tag. At least 3 cells per axis, so that no cell meets itself and
/// unwrapping is unambiguous.
///
/// ```
/// use hasse_complex::{dual::DualKind, generate::torus_flat};
/// let k = torus_flat(4, 3, [0.0, 2.0], [0.0, 1.5], false).unwrap();
/// assert_eq!(k.cell_counts(), vec![12, 24, 12]);
/// assert_eq!(k.betti_numbers(), vec![1, 2, 1]);
/// // Every dual cell of a vertex is a 0.5 × 0.5 square.
/// let star0 = k.hodge_star(DualKind::Barycentric, 0).unwrap();
/// assert!(star0.iter().all(|s| (s - 0.25).abs() < 1e-14));
/// ```
pub fn torus_flat(
    nx: usize,
    ny: usize,
    x: [f64; 2],
    y: [f64; 2],
    triangles: bool,
) -> Result<Complex> {
    for (name, n) in [("nx", nx), ("ny", ny)] {
        if n < 3 {
            return invalid(format!(
                "{name} must be at least 3 on a flat torus (a cell must not wrap onto itself), got {n}"
            ));
        }
    }
    for (name, [lo, hi]) in [("x", x), ("y", y)] {
        if !(lo.is_finite() && hi.is_finite()) {
            return invalid(format!(
                "{name} must be two finite numbers, got [{lo}, {hi}]"
            ));
        }
        positive(&format!("the length of {name} (max − min)"), hi - lo)?;
    }
    let (lx, ly) = (x[1] - x[0], y[1] - y[0]);
    let (hx, hy) = (lx / nx as f64, ly / ny as f64);
    let mut coords = Vec::with_capacity(2 * nx * ny);
    for j in 0..ny {
        for i in 0..nx {
            coords.extend([x[0] + i as f64 * hx, y[0] + j as f64 * hy]);
        }
    }
    let vertices = Vertices::new(2, coords)?.with_period(&[lx, ly])?;
    let index = |i: usize, j: usize| (i % nx) + nx * (j % ny);
    let mut cells = TopCells::default();
    for j in 0..ny {
        for i in 0..nx {
            let (a, b, c, d) = (
                index(i, j),
                index(i + 1, j),
                index(i, j + 1),
                index(i + 1, j + 1),
            );
            if triangles {
                cells.push_simplex(&[a, b, d]);
                cells.push_simplex(&[a, c, d]);
            } else {
                cells.push_cuboid(&[a, b, c, d]);
            }
        }
    }
    Complex::build(vertices, cells)
}

/// The three-dimensional flat torus R³/(L_x Z × L_y Z × L_z Z): a uniform
/// `n[0] × n[1] × n[2]` grid of the box `extent[0] × extent[1] ×
/// extent[2]` with opposite faces identified, as cubes or (with
/// `simplices`) the six Kuhn tetrahedra of each cube (the paths from its
/// lowest to its highest corner, one per order of the axes; translation
/// invariant, so they match across the identified faces). Vertex
/// `(i, j, k)` has index `i + n₀ (j + n₁ k)`. Geometry as for
/// [`torus_flat`]: per cell, from unwrapped points. χ = 0 and
/// β = (1, 3, 3, 1); at least 3 cells per axis.
///
/// ```
/// use hasse_complex::generate::torus_flat_box;
/// let k = torus_flat_box([3, 3, 4], [[0.0, 3.0], [0.0, 3.0], [0.0, 4.0]], false).unwrap();
/// assert_eq!(k.cell_counts(), vec![36, 108, 108, 36]);
/// assert_eq!(k.betti_numbers(), vec![1, 3, 3, 1]);
/// assert!(k.measure(3).iter().all(|v| (v - 1.0).abs() < 1e-13));
/// ```
pub fn torus_flat_box(n: [usize; 3], extent: [[f64; 2]; 3], simplices: bool) -> Result<Complex> {
    for (name, (&cells, [lo, hi])) in ["x", "y", "z"].iter().zip(n.iter().zip(extent)) {
        if cells < 3 {
            return invalid(format!(
                "n along {name} must be at least 3 on a flat torus (a cell must not wrap onto itself), got {cells}"
            ));
        }
        if !(lo.is_finite() && hi.is_finite()) {
            return invalid(format!(
                "{name} must be two finite numbers, got [{lo}, {hi}]"
            ));
        }
        positive(&format!("the length of {name} (max − min)"), hi - lo)?;
    }
    let length = extent.map(|[lo, hi]| hi - lo);
    let h: Vec<f64> = (0..3).map(|a| length[a] / n[a] as f64).collect();
    let mut coords = Vec::with_capacity(3 * n[0] * n[1] * n[2]);
    for k in 0..n[2] {
        for j in 0..n[1] {
            for i in 0..n[0] {
                coords.extend([
                    extent[0][0] + i as f64 * h[0],
                    extent[1][0] + j as f64 * h[1],
                    extent[2][0] + k as f64 * h[2],
                ]);
            }
        }
    }
    let vertices = Vertices::new(3, coords)?.with_period(&length)?;
    let index = |c: [usize; 3]| (c[0] % n[0]) + n[0] * ((c[1] % n[1]) + n[1] * (c[2] % n[2]));
    let mut cells = TopCells::default();
    let orders = [
        [0, 1, 2],
        [0, 2, 1],
        [1, 0, 2],
        [1, 2, 0],
        [2, 0, 1],
        [2, 1, 0],
    ];
    for k in 0..n[2] {
        for j in 0..n[1] {
            for i in 0..n[0] {
                if simplices {
                    for order in orders {
                        let mut corner = [i, j, k];
                        let mut tet = vec![index(corner)];
                        for axis in order {
                            corner[axis] += 1;
                            tet.push(index(corner));
                        }
                        cells.push_simplex(&tet);
                    }
                } else {
                    // Tensor order: bit a of the local index is the side along axis a.
                    let cube: Vec<usize> = (0..8)
                        .map(|b| index([i + (b & 1), j + ((b >> 1) & 1), k + ((b >> 2) & 1)]))
                        .collect();
                    cells.push_cuboid(&cube);
                }
            }
        }
    }
    Complex::build(vertices, cells)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::dual::DualKind;

    /// The flat torus is closed, has the torus's Betti numbers, and its
    /// cells are measured unwrapped: total area L_x L_y, every edge of
    /// length h, every dual edge of the squares of length h (so ⋆₁ = 1).
    #[test]
    fn flat_torus_is_measured_unwrapped() -> Result<()> {
        for triangles in [false, true] {
            let k = torus_flat(3, 5, [0.0, 3.0], [1.0, 6.0], triangles)?;
            assert_eq!(k.betti_numbers(), vec![1, 2, 1]);
            assert_eq!(k.boundary_subcomplex().cells(1).len(), 0);
            let area: f64 = k.measure(2).iter().sum();
            assert!((area - 15.0).abs() < 1e-12, "area {area}");
            let kind = if triangles {
                DualKind::Circumcentric
            } else {
                DualKind::Barycentric
            };
            let star0: f64 = k.dual_measure(kind, 0)?.iter().sum();
            assert!((star0 - 15.0).abs() < 1e-12, "Σ⋆₀ {star0}");
            if !triangles {
                let star1 = k.hodge_star(kind, 1)?;
                assert!(star1.iter().all(|s| (s - 1.0).abs() < 1e-14));
            }
        }
        Ok(())
    }

    /// The 3D flat torus: β = (1, 3, 3, 1), total volume, and every cube's
    /// dual quantities those of the flat metric (⋆₁ = h², ⋆₂ = 1 for unit
    /// cubes); on Kuhn tetrahedra the volumes of the six add up.
    #[test]
    fn flat_box_is_measured_unwrapped() -> Result<()> {
        let extent = [[0.0, 3.0], [0.0, 3.0], [0.0, 3.0]];
        for simplices in [false, true] {
            let k = torus_flat_box([3, 3, 3], extent, simplices)?;
            assert_eq!(k.betti_numbers(), vec![1, 3, 3, 1]);
            let volume: f64 = k.measure(3).iter().sum();
            assert!((volume - 27.0).abs() < 1e-12, "volume {volume}");
            let kind = if simplices {
                DualKind::Circumcentric
            } else {
                DualKind::Barycentric
            };
            let star0: f64 = k.dual_measure(kind, 0)?.iter().sum();
            assert!((star0 - 27.0).abs() < 1e-12, "Σ⋆₀ {star0}");
            if !simplices {
                for p in 1..=2 {
                    let star = k.hodge_star(kind, p)?;
                    assert!(star.iter().all(|s| (s - 1.0).abs() < 1e-13), "⋆{p}");
                }
            }
        }
        Ok(())
    }

    #[test]
    fn flat_torus_needs_three_cells_per_axis() {
        assert!(torus_flat(2, 3, [0.0, 1.0], [0.0, 1.0], false).is_err());
        assert!(torus_flat(3, 3, [0.0, 0.0], [0.0, 1.0], false).is_err());
    }
}
