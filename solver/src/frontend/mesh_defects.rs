//! Defects of a mesh file that make a valid complex but a wrong domain
//! for the solver (coincident vertices, …), found before solving.

use hasse_complex::Complex;

/// Defects of a mesh file that make a valid complex but a wrong domain for
/// the solver; generated meshes have none by construction.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum MeshDefect {
    /// Two vertices at the same place (within 10⁻¹⁰ of the mesh's
    /// extent): the mesh is cut there.
    #[error("vertices {first} and {second} coincide at {point:?}: the cells on either side are not connected there (a crack); merge duplicate nodes (Gmsh: Geometry.Tolerance / Coherence Mesh) or remesh")]
    DuplicateVertices {
        /// The lower vertex id.
        first: usize,
        /// The higher vertex id.
        second: usize,
        /// Where the first one is.
        point: Vec<f64>,
    },
    /// An (n−1)-cell bounds more than two top cells.
    #[error("{dim}-cell {face} (vertices {vertices:?}) bounds {count} top cells ({cells:?}): the mesh is not a manifold there, and fluxes through a face need exactly one cell on each side; split the mesh into separate surfaces or remesh")]
    NonManifold {
        /// Its dimension, n − 1.
        dim: usize,
        /// The face's id.
        face: usize,
        /// Its vertices.
        vertices: Vec<usize>,
        /// How many top cells it bounds.
        count: usize,
        /// Those top cells.
        cells: Vec<usize>,
    },
}

/// Check a mesh read from a file for coincident vertices and faces shared
/// by more than two cells.
///
/// ```
/// use hasse_complex::{Complex, TopCells, Vertices};
/// use hasse_solver::frontend::mesh_spec::{check_mesh, MeshDefect};
/// // Two triangles whose common diagonal has a duplicated end.
/// let v = Vertices::from_points(&[[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0], [1.0, 1.0]]).unwrap();
/// let k = Complex::build(v, TopCells::simplices([[0, 1, 2], [0, 4, 3]])).unwrap();
/// assert!(matches!(check_mesh(&k), Err(MeshDefect::DuplicateVertices { first: 2, second: 4, .. })));
/// ```
pub fn check_mesh(complex: &Complex) -> Result<(), MeshDefect> {
    let n = complex.dim();
    if n > 0 {
        let top = complex.boundary(n);
        for (face, row) in top.outer_iterator().enumerate() {
            if row.nnz() > 2 {
                return Err(MeshDefect::NonManifold {
                    dim: n - 1,
                    face,
                    vertices: complex.cell_vertices(n - 1, face).to_vec(),
                    count: row.nnz(),
                    cells: row.indices().to_vec(),
                });
            }
        }
    }
    duplicate_vertices(complex)
}

/// Vertices closer than 1e-10 of the mesh's extent, found by hashing
/// points into boxes of that size and comparing with neighbouring boxes
/// (linear time, unlike comparing all pairs).
fn duplicate_vertices(complex: &Complex) -> Result<(), MeshDefect> {
    use std::collections::HashMap;
    let vertices = complex.vertices();
    let d = vertices.dim();
    let count = vertices.len();
    let mut lo = [f64::INFINITY; 3];
    let mut hi = [f64::NEG_INFINITY; 3];
    for v in 0..count {
        for (a, &x) in vertices.point(v).iter().enumerate() {
            lo[a] = lo[a].min(x);
            hi[a] = hi[a].max(x);
        }
    }
    let extent = (0..d).map(|a| hi[a] - lo[a]).fold(0.0, f64::max);
    if extent.is_nan() || extent <= 0.0 {
        return Ok(());
    }
    let tolerance = 1e-10 * extent;
    let key = |v: usize| -> [i64; 3] {
        let mut k = [0i64; 3];
        for (a, &x) in vertices.point(v).iter().enumerate() {
            k[a] = ((x - lo[a]) / tolerance).floor() as i64;
        }
        k
    };
    let mut boxes: HashMap<[i64; 3], Vec<usize>> = HashMap::with_capacity(count);
    for v in 0..count {
        boxes.entry(key(v)).or_default().push(v);
    }
    let offsets: Vec<[i64; 3]> = (0..3i64.pow(d as u32))
        .map(|mut i| {
            let mut o = [0i64; 3];
            for slot in o.iter_mut().take(d) {
                *slot = i % 3 - 1;
                i /= 3;
            }
            o
        })
        .collect();
    for v in 0..count {
        let k = key(v);
        let x = vertices.point(v);
        for o in &offsets {
            let neighbour = [k[0] + o[0], k[1] + o[1], k[2] + o[2]];
            for &w in boxes.get(&neighbour).map_or(&[][..], Vec::as_slice) {
                if w <= v {
                    continue;
                }
                let y = vertices.point(w);
                let distance = x
                    .iter()
                    .zip(y)
                    .map(|(a, b)| (a - b).powi(2))
                    .sum::<f64>()
                    .sqrt();
                if distance <= tolerance {
                    return Err(MeshDefect::DuplicateVertices {
                        first: v,
                        second: w,
                        point: x.to_vec(),
                    });
                }
            }
        }
    }
    Ok(())
}
