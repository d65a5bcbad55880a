//! Values of a discrete field at points, the way each method represents
//! it: nodal fields by interpolation in the cell that holds the point,
//! cell-centred and hybrid fields by the cell's value and reconstructed
//! gradient.
//!
//! - A simplex interpolates linearly (P1, by barycentric coordinates).
//! - A cell with 2ⁿ vertices interpolates in {1, x, y, xy} (and the
//!   trilinear terms in 3D) through its vertices: Q1 itself on the
//!   axis-aligned boxes of the grid generators; on other quadrilaterals a
//!   bilinear interpolant in physical coordinates which, like Q1, takes
//!   the vertex values and reproduces linear fields.
//! - Other polytopes (virtual elements) take the least-squares linear fit
//!   of their vertex values, exact for linear fields.
//! - A point at a vertex (within 10⁻¹² of the cell's size) takes the
//!   vertex's value exactly.
//! - Cell values: u_c + ∇u_c · (x − x_c), with the least-squares gradient
//!   of [`crate::physics::diffusion::gradient_of`].
//!
//! ```
//! use hasse_complex::generate::rectangle;
//! use hasse_solver::metric::Location;
//! use hasse_solver::physics::probe::{value_at, PointLocator};
//! let mesh = rectangle(4, 2, [0.0, 2.0], [0.0, 1.0]).unwrap();
//! let u: Vec<f64> = (0..mesh.cell_count(0)).map(|v| {
//!     let p = mesh.vertices().point(v);
//!     1.0 + 2.0 * p[0] - p[1] + p[0] * p[1]
//! }).collect();
//! let locator = PointLocator::new(&mesh).unwrap();
//! let x = [1.3, 0.7];
//! let cell = locator.locate(&x).unwrap();
//! // Q1 on a rectangle reproduces a bilinear field.
//! let value = value_at(&mesh, Location::Nodal, &u, None, cell, &x);
//! assert!((value - (1.0 + 2.6 - 0.7 + 1.3 * 0.7)).abs() < 1e-13);
//! assert_eq!(locator.locate(&[2.5, 0.5]), None);
//! ```

use crate::metric::Location;
use hasse_complex::Complex;

/// Finds the top cell that holds a point: cells are bucketed by their
/// bounding boxes on a uniform grid over the mesh (about one cell a
/// bucket), and a candidate holds the point when it lies on the inner
/// side of each of its faces (convex cells).
pub struct PointLocator<'a> {
    complex: &'a Complex,
    lower: Vec<f64>,
    step: Vec<f64>,
    divisions: Vec<usize>,
    buckets: Vec<Vec<usize>>,
    diameter: Vec<f64>,
}

/// Why points cannot be located in a complex.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum ProbeError {
    /// The cells are not full-dimensional (a surface in R³): a point of
    /// R³ is not in them.
    #[error(
        "probes need cells that fill their space; this mesh is {dim}-dimensional in R^{embedding}"
    )]
    NotFullDimensional {
        /// Dimension of the top cells.
        dim: usize,
        /// Dimension of the embedding space.
        embedding: usize,
    },
}

impl<'a> PointLocator<'a> {
    /// Bucket the top cells of `complex`.
    pub fn new(complex: &'a Complex) -> Result<Self, ProbeError> {
        let (n, d) = (complex.dim(), complex.embedding_dim());
        if n != d || n == 0 {
            return Err(ProbeError::NotFullDimensional {
                dim: n,
                embedding: d,
            });
        }
        let cells = complex.cell_count(n);
        let mut boxes = Vec::with_capacity(cells);
        let mut lower = vec![f64::INFINITY; d];
        let mut upper = vec![f64::NEG_INFINITY; d];
        let mut diameter = Vec::with_capacity(cells);
        for c in 0..cells {
            let mut lo = vec![f64::INFINITY; d];
            let mut hi = vec![f64::NEG_INFINITY; d];
            for &v in complex.cell_vertices(n, c) {
                for (a, &x) in complex.vertices().point(v).iter().enumerate() {
                    lo[a] = lo[a].min(x);
                    hi[a] = hi[a].max(x);
                }
            }
            for a in 0..d {
                lower[a] = lower[a].min(lo[a]);
                upper[a] = upper[a].max(hi[a]);
            }
            diameter.push((0..d).map(|a| (hi[a] - lo[a]).powi(2)).sum::<f64>().sqrt());
            boxes.push((lo, hi));
        }
        let per_axis = ((cells.max(1) as f64).powf(1.0 / d as f64).ceil() as usize).max(1);
        let divisions = vec![per_axis; d];
        let step: Vec<f64> = (0..d)
            .map(|a| ((upper[a] - lower[a]) / per_axis as f64).max(f64::MIN_POSITIVE))
            .collect();
        let mut locator = PointLocator {
            complex,
            lower,
            step,
            divisions,
            buckets: vec![Vec::new(); per_axis.pow(d as u32)],
            diameter,
        };
        for (c, (lo, hi)) in boxes.iter().enumerate() {
            let from = locator.bucket_coordinates(lo);
            let to = locator.bucket_coordinates(hi);
            let mut index = from.clone();
            loop {
                let b = locator.flat(&index);
                locator.buckets[b].push(c);
                // Odometer over the box of buckets.
                let mut a = 0;
                while a < d {
                    if index[a] < to[a] {
                        index[a] += 1;
                        break;
                    }
                    index[a] = from[a];
                    a += 1;
                }
                if a == d {
                    break;
                }
            }
        }
        Ok(locator)
    }

    fn bucket_coordinates(&self, x: &[f64]) -> Vec<usize> {
        (0..self.divisions.len())
            .map(|a| {
                let k = ((x[a] - self.lower[a]) / self.step[a]).floor();
                (k.max(0.0) as usize).min(self.divisions[a] - 1)
            })
            .collect()
    }

    fn flat(&self, index: &[usize]) -> usize {
        index
            .iter()
            .zip(&self.divisions)
            .rev()
            .fold(0, |acc, (&i, &k)| acc * k + i)
    }

    /// The top cell holding `x` (the first found when `x` is on a face
    /// shared by several), or `None` outside the mesh.
    pub fn locate(&self, x: &[f64]) -> Option<usize> {
        let complex = self.complex;
        let (n, d) = (complex.dim(), complex.embedding_dim());
        if x.len() != d {
            return None;
        }
        let bucket = self.flat(&self.bucket_coordinates(x));
        let by_cell = complex.boundary_csc(n);
        let normal = complex.normal();
        let face_centre = complex.centroid(n - 1);
        self.buckets[bucket].iter().copied().find(|&c| {
            let tolerance = 1e-10 * self.diameter[c];
            by_cell.outer_view(c).is_some_and(|col| {
                col.iter().all(|(f, &s)| {
                    let outward: f64 = (0..d)
                        .map(|a| (x[a] - face_centre[f * d + a]) * f64::from(s) * normal[f * d + a])
                        .sum();
                    outward <= tolerance
                })
            })
        })
    }
}

/// The value at `x` (in top cell `cell`) of a field laid out as `location`
/// says (all unknowns); `gradient` is the cell-wise gradient of a
/// cell-centred or hybrid field ([`crate::physics::diffusion::gradient_of`]),
/// unused for nodal ones. Cell values stand at the centroids.
pub fn value_at(
    complex: &Complex,
    location: Location,
    values: &[f64],
    gradient: Option<&[[f64; 3]]>,
    cell: usize,
    x: &[f64],
) -> f64 {
    let (n, d) = (complex.dim(), complex.embedding_dim());
    match location {
        Location::Nodal => nodal_value(complex, values, cell, x),
        Location::CellCentred | Location::Hybrid => {
            let centre = complex.centroid_of(n, cell);
            let g = gradient.map_or([0.0; 3], |g| g[cell]);
            values[cell] + (0..d).map(|a| g[a] * (x[a] - centre[a])).sum::<f64>()
        }
    }
}

fn nodal_value(complex: &Complex, values: &[f64], cell: usize, x: &[f64]) -> f64 {
    let (n, d) = (complex.dim(), complex.embedding_dim());
    let vertices = complex.cell_vertices(n, cell);
    let points: Vec<&[f64]> = vertices
        .iter()
        .map(|&v| complex.vertices().point(v))
        .collect();
    let centre = complex.centroid_of(n, cell);
    let size = points
        .iter()
        .map(|p| {
            (0..d)
                .map(|a| (p[a] - centre[a]).powi(2))
                .sum::<f64>()
                .sqrt()
        })
        .fold(0.0, f64::max)
        .max(f64::MIN_POSITIVE);
    for (p, &v) in points.iter().zip(vertices) {
        let distance = (0..d).map(|a| (p[a] - x[a]).powi(2)).sum::<f64>().sqrt();
        if distance <= 1e-12 * size {
            return values[v];
        }
    }
    // Local coordinates, centred and scaled, keep the small systems well
    // conditioned whatever the mesh's units.
    let local = |p: &[f64]| -> Vec<f64> { (0..d).map(|a| (p[a] - centre[a]) / size).collect() };
    let basis = |y: &[f64]| -> Vec<f64> {
        let mut b = vec![1.0];
        b.extend_from_slice(y);
        if vertices.len() == 1 << n && vertices.len() > n + 1 {
            match d {
                2 => b.push(y[0] * y[1]),
                3 => b.extend([y[0] * y[1], y[1] * y[2], y[0] * y[2], y[0] * y[1] * y[2]]),
                _ => {}
            }
        }
        b
    };
    let rows: Vec<Vec<f64>> = points.iter().map(|p| basis(&local(p))).collect();
    let m = rows[0].len();
    // Normal equations (square and exact when there are as many vertices
    // as basis functions: P1 on a simplex, the (tri)linear space on 2ⁿ).
    let mut a = vec![vec![0.0; m + 1]; m];
    for (row, &v) in rows.iter().zip(vertices) {
        for i in 0..m {
            for j in 0..m {
                a[i][j] += row[i] * row[j];
            }
            a[i][m] += row[i] * values[v];
        }
    }
    let Some(coefficients) = solve_dense(a) else {
        return f64::NAN;
    };
    basis(&local(x))
        .iter()
        .zip(&coefficients)
        .map(|(b, c)| b * c)
        .sum()
}

/// Gaussian elimination with partial pivoting of an augmented m×(m+1)
/// system; `None` when singular.
fn solve_dense(mut a: Vec<Vec<f64>>) -> Option<Vec<f64>> {
    let m = a.len();
    let scale = a.iter().flatten().fold(0.0f64, |s, v| s.max(v.abs()));
    for k in 0..m {
        let pivot = (k..m).max_by(|&i, &j| a[i][k].abs().total_cmp(&a[j][k].abs()))?;
        if a[pivot][k].abs() <= 1e-13 * scale {
            return None;
        }
        a.swap(k, pivot);
        let (upper, lower) = a.split_at_mut(k + 1);
        let pivot_row = &upper[k];
        for row in lower.iter_mut() {
            let factor = row[k] / pivot_row[k];
            for (r, p) in row[k..].iter_mut().zip(&pivot_row[k..]) {
                *r -= factor * p;
            }
        }
    }
    let mut x = vec![0.0; m];
    for k in (0..m).rev() {
        let sum: f64 = (k + 1..m).map(|j| a[k][j] * x[j]).sum();
        x[k] = (a[k][m] - sum) / a[k][k];
    }
    Some(x)
}
