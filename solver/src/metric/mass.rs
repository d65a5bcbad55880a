//! Lumped masses: the diagonal Ω of A = I that weighs each unknown by the
//! measure it stands for (time derivatives, reaction terms, mean values).

use super::Location;
use hasse_complex::Complex;

/// |c|/(vertices of c) summed over the top cells around each vertex: the
/// barycentric-dual volume of a vertex on simplices, its share of the
/// cells' measure on any cell.
///
/// ```
/// use hasse_complex::generate::rectangle;
/// use hasse_solver::metric::mass::lumped_vertex_volumes;
/// // A 2×1 grid of unit squares: corners hold ¼, the two middle vertices ½.
/// let k = rectangle(2, 1, [0.0, 2.0], [0.0, 1.0]).unwrap();
/// let w = lumped_vertex_volumes(&k);
/// assert_eq!(w.iter().sum::<f64>(), 2.0);
/// assert_eq!(w.iter().filter(|&&v| v == 0.5).count(), 2);
/// ```
pub fn lumped_vertex_volumes(complex: &Complex) -> Vec<f64> {
    let n = complex.dim();
    let volume = complex.measure(n);
    let mut w = crate::la::parallel::zeroed(complex.cell_count(0));
    for (c, &vol) in volume.iter().enumerate() {
        let verts = complex.cell_vertices(n, c);
        for &v in verts {
            w[v] += vol / verts.len() as f64;
        }
    }
    w
}

/// The lumped mass of each unknown of `location`: the vertex volumes of
/// [`lumped_vertex_volumes`] for nodal unknowns, the cell measures for
/// cell-centred ones; `None` for the hybrid unknowns, whose face unknowns
/// carry no volume.
pub fn lumped(complex: &Complex, location: Location) -> Option<Vec<f64>> {
    match location {
        Location::Nodal => Some(lumped_vertex_volumes(complex)),
        Location::CellCentred => Some(complex.measure(complex.dim()).to_vec()),
        Location::Hybrid => None,
    }
}
