//! Mesh generators: structured grids (cuboidal and Kuhn-simplicial),
//! Delaunay triangulations of point sets, an annulus, a torus and a sphere
//! surface, a box with a closed cavity, Voronoi polygon meshes of random
//! sites, and random interior perturbation of an existing mesh.
//!
//! Every generator returns a [`Complex`](crate::Complex) whose boundary
//! (n−1)-cells are tagged (at least `"boundary"`; grids also name each
//! side), so boundary conditions can be attached by name. Parameters are
//! checked and a bad one is reported as
//! [`ComplexError::Invalid`](crate::ComplexError::Invalid) naming the
//! parameter and its allowed range; no generator panics on user input.
//!
//! | generator | cells | tags |
//! |-----------|-------|------|
//! | [`grid`], [`interval`], [`rectangle`], [`box3`] | segments / quads / hexes | `xmin` … `zmax`, `boundary` |
//! | [`kuhn`] | segments / triangles / tetrahedra | as [`grid`] |
//! | [`delaunay`] | triangles | `boundary` |
//! | [`delaunay_rectangle`] | triangles (random points in a rectangle) | `xmin` … `ymax`, `boundary` |
//! | [`voronoi`] | convex polygons (clipped Voronoi cells of random sites) | `xmin` … `ymax`, `boundary` |
//! | [`annulus`] | quads | `inner`, `outer`, `boundary` |
//! | [`torus`], [`sphere`] | closed quad / triangle surfaces in R^3 | none (no boundary) |
//! | [`hollow_box`] | hexes | `outer`, `cavity`, `boundary` |
//! | [`torus_flat`], [`torus_flat_box`] | quads or triangles of a periodic rectangle, cubes or Kuhn tetrahedra of a periodic box (flat metric) | none (no boundary) |
//!
//! ```
//! use hasse_complex::generate;
//! let k = generate::rectangle(4, 3, [0.0, 2.0], [0.0, 1.0]).unwrap();
//! assert_eq!(k.cell_counts(), vec![20, 31, 12]);
//! assert_eq!(k.tag("xmin").unwrap().cells.len(), 3);
//! let x = generate::uniform_axis(4, 0.0, 1.0).unwrap();
//! let t = generate::kuhn(&[x.clone(), x]).unwrap();
//! assert_eq!(t.cell_count(2), 32);
//! ```

mod delaunay;
mod grid;
mod periodic;
mod perturb;
mod structured;
mod surfaces;
mod voronoi;

pub use delaunay::{delaunay, delaunay_rectangle};
pub use grid::{box3, graded_axis, grid, hollow_box, interval, kuhn, rectangle, uniform_axis};
pub use periodic::{torus_flat, torus_flat_box};
pub use perturb::perturb;
pub use surfaces::{annulus, sphere, torus};
pub use voronoi::{voronoi, voronoi_with_sites};

use crate::error::{ComplexError, Result};
use crate::Complex;

/// Shorthand for a parameter error.
pub(crate) fn invalid<T>(message: String) -> Result<T> {
    Err(ComplexError::Invalid(message))
}

/// The boundary (n−1)-cells of `complex`: rows of ∂_n with exactly one entry.
/// Cheaper than [`Complex::boundary_subcomplex`], which also collects the
/// lower-dimensional faces.
pub(crate) fn boundary_facets(complex: &Complex) -> Vec<usize> {
    complex
        .boundary(complex.dim())
        .outer_iterator()
        .enumerate()
        .filter(|(_, row)| row.nnz() == 1)
        .map(|(i, _)| i)
        .collect()
}

/// Tag the boundary facets: `"boundary"` gets all of them, and each facet
/// also goes to the tag `names[classify(vertices)]` when that is `Some`.
pub(crate) fn tag_boundary(
    complex: &mut Complex,
    names: &[&str],
    classify: impl Fn(&[usize]) -> Option<usize>,
) -> Result<()> {
    let facets = boundary_facets(complex);
    let p = complex.dim() - 1;
    let mut groups: Vec<Vec<usize>> = vec![Vec::new(); names.len()];
    for &f in &facets {
        if let Some(g) = classify(complex.cell_vertices(p, f)) {
            groups[g].push(f);
        }
    }
    for (name, cells) in names.iter().zip(groups) {
        complex.set_tag(name, p, cells)?;
    }
    complex.set_tag("boundary", p, facets)
}

/// Check that a real parameter is finite and positive.
pub(crate) fn positive(name: &str, value: f64) -> Result<()> {
    if value.is_finite() && value > 0.0 {
        Ok(())
    } else {
        invalid(format!(
            "{name} must be a finite number greater than 0, got {value}"
        ))
    }
}
