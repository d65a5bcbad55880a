//! Random perturbation of interior vertices (distorted grids).

use super::{boundary_facets, invalid};
use crate::error::Result;
use crate::Complex;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// The same complex with every vertex off the boundary subcomplex moved by
/// a random vector whose components are uniform in `[−a h_v, a h_v]`,
/// `a = amplitude` and `h_v` the length of the shortest edge at that vertex.
/// Boundary vertices stay put, so the domain does not change; tags are kept.
///
/// The displacements come from a ChaCha8 stream seeded with `seed`, drawn
/// `d` components per vertex in vertex order (boundary vertices draw too and
/// discard them), so the result depends only on the complex, `amplitude`
/// and `seed`. `amplitude` must lie in `[0, 0.5)`; the moved complex is
/// re-oriented by [`Complex::with_vertices`], which reports cells that the
/// perturbation made degenerate, inverted or non-convex. Only complexes
/// that fill their space (`dim() == embedding_dim()`) can be perturbed:
/// moving the vertices of an embedded surface off-surface would change its
/// shape.
///
/// ```
/// use hasse_complex::generate::{perturb, rectangle};
/// let k = rectangle(4, 4, [0.0, 1.0], [0.0, 1.0]).unwrap();
/// let p = perturb(&k, 0.2, 7).unwrap();
/// assert_eq!(p.vertices().point(0), k.vertices().point(0)); // a corner
/// assert_ne!(p.vertices().point(6), k.vertices().point(6)); // interior
/// assert_eq!(p, perturb(&k, 0.2, 7).unwrap());
/// ```
pub fn perturb(complex: &Complex, amplitude: f64, seed: u64) -> Result<Complex> {
    if !(0.0..0.5).contains(&amplitude) {
        return invalid(format!(
            "amplitude must be in [0, 0.5) (a fraction of the shortest edge at each vertex), got {amplitude}"
        ));
    }
    let (n, d) = (complex.dim(), complex.embedding_dim());
    if n != d {
        return invalid(format!(
            "perturb needs a complex that fills its space, but this one is {n}-dimensional in R^{d}; moving vertices would leave the surface"
        ));
    }
    let k0 = complex.cell_count(0);
    let mut shortest = vec![f64::INFINITY; k0];
    let vertices = complex.vertices();
    for e in 0..complex.cell_count(1) {
        let ends = complex.cell_vertices(1, e);
        let (a, b) = (vertices.point(ends[0]), vertices.point(ends[1]));
        let length = a
            .iter()
            .zip(b)
            .map(|(x, y)| (x - y) * (x - y))
            .sum::<f64>()
            .sqrt();
        for &v in ends {
            shortest[v] = shortest[v].min(length);
        }
    }
    // Vertices of the boundary subcomplex = vertices of the boundary facets.
    let mut fixed = vec![false; k0];
    for f in boundary_facets(complex) {
        for &v in complex.cell_vertices(n - 1, f) {
            fixed[v] = true;
        }
    }
    let mut moved = vertices.clone();
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    for (v, point) in moved.as_mut_slice().chunks_exact_mut(d).enumerate() {
        let scale = amplitude * shortest[v];
        for x in point {
            let step: f64 = rng.gen_range(-1.0..=1.0);
            if !fixed[v] && scale.is_finite() {
                *x += scale * step;
            }
        }
    }
    complex.with_vertices(moved)
}
