//! A rank's part of the complex: its owned top cells and one layer of
//! ghost cells around them, with the global id and the owner rank of every
//! cell of every dimension.

use super::DistributedError;
use hasse_complex::{Complex, Lar, Vertices};

/// The local complex of one rank (see [`LocalComplex::new`]).
#[derive(Clone, Debug)]
pub struct LocalComplex {
    /// The owned top cells and the ghost layer, as a complex of its own.
    /// Its cells are numbered in increasing global id in every dimension,
    /// and so inherit the global orientations.
    pub complex: Complex,
    /// `global[p][j]`: the global id of local p-cell j.
    pub global: Vec<Vec<usize>>,
    /// `owner[p][j]`: the rank owning local p-cell j.
    pub owner: Vec<Vec<usize>>,
    /// This rank.
    pub rank: usize,
}

/// The rank that owns each p-cell: the rank of the lowest-numbered top cell
/// that contains it. Every rank that sees a cell sees all top cells around
/// it whenever it owns one of them (the ghost layer is the whole star), so
/// the ranks agree on the owner of every cell they share with an owned one.
fn owners(global: &Complex, part: &[usize], p: usize) -> Vec<usize> {
    let n = global.dim();
    if p == n {
        return part.to_vec();
    }
    let star = global.vertex_star(n);
    (0..global.cell_count(p))
        .map(|c| {
            let vertices = global.cell_vertices(p, c);
            let first = vertices[0];
            star.outer_view(first)
                .map(|row| {
                    row.indices()
                        .iter()
                        .copied()
                        .filter(|&t| {
                            let top = global.cell_vertices(n, t);
                            vertices.iter().all(|v| top.binary_search(v).is_ok())
                        })
                        .min()
                        .map_or(0, |t| part[t])
                })
                .unwrap_or(0)
        })
        .collect()
}

impl LocalComplex {
    /// The local complex of `rank` under the partition `part` of the top
    /// cells of `global`: the owned top cells, every top cell that shares a
    /// vertex with one of them (the LAR star of the owned cells), and all
    /// their faces. Tags are carried over cell by cell, so a boundary tag
    /// holds only cells of the global boundary: the ghost layer's outer
    /// faces are not boundary faces of the problem.
    ///
    /// ```
    /// use hasse_complex::generate::rectangle;
    /// use hasse_solver::distributed::{partition_top_cells, LocalComplex};
    /// let mesh = rectangle(6, 6, [0.0, 1.0], [0.0, 1.0]).unwrap();
    /// let part = partition_top_cells(&mesh, 2).unwrap();
    /// let local = LocalComplex::new(&mesh, &part, 0).unwrap();
    /// let owned = local.owner[2].iter().filter(|&&r| r == 0).count();
    /// assert_eq!(owned, part.iter().filter(|&&r| r == 0).count());
    /// // The ghost layer: more top cells than owned, fewer than all.
    /// assert!(local.complex.cell_count(2) > owned && local.complex.cell_count(2) < 36);
    /// ```
    pub fn new(global: &Complex, part: &[usize], rank: usize) -> Result<Self, DistributedError> {
        let n = global.dim();
        if part.len() != global.cell_count(n) {
            return Err(DistributedError::Partition(format!(
                "the partition lists {} top cells, the mesh has {}",
                part.len(),
                global.cell_count(n)
            )));
        }
        let star = global.vertex_star(n);
        // Top cells: the owned ones and everything sharing a vertex with them.
        let mut in_local = vec![false; global.cell_count(n)];
        for (c, _) in part.iter().enumerate().filter(|(_, &r)| r == rank) {
            for &v in global.cell_vertices(n, c) {
                if let Some(row) = star.outer_view(v) {
                    for &t in row.indices() {
                        in_local[t] = true;
                    }
                }
            }
        }
        let mut cells: Vec<Vec<usize>> = vec![Vec::new(); n + 1];
        cells[n] = (0..in_local.len()).filter(|&t| in_local[t]).collect();
        if cells[n].is_empty() {
            return Err(DistributedError::Partition(format!(
                "rank {rank} owns no top cell"
            )));
        }
        // Faces of the local p-cells, from ∂_p by columns.
        for p in (1..=n).rev() {
            let by_cell = global.boundary_csc(p);
            let mut mark = vec![false; global.cell_count(p - 1)];
            for &c in &cells[p] {
                if let Some(column) = by_cell.outer_view(c) {
                    for &f in column.indices() {
                        mark[f] = true;
                    }
                }
            }
            cells[p - 1] = (0..mark.len()).filter(|&f| mark[f]).collect();
        }
        // Local numbers of the global vertices.
        let mut local_vertex = vec![usize::MAX; global.cell_count(0)];
        for (j, &v) in cells[0].iter().enumerate() {
            local_vertex[v] = j;
        }
        let d = global.embedding_dim();
        let coordinates = global.vertices().as_slice();
        let coords: Vec<f64> = cells[0]
            .iter()
            .flat_map(|&v| coordinates[v * d..(v + 1) * d].iter().copied())
            .collect();
        let vertices = Vertices::new(d, coords)?;
        let sets: Vec<Vec<Vec<usize>>> = (1..=n)
            .map(|p| {
                cells[p]
                    .iter()
                    .map(|&c| {
                        global
                            .cell_vertices(p, c)
                            .iter()
                            .map(|&v| local_vertex[v])
                            .collect()
                    })
                    .collect()
            })
            .collect();
        let mut complex = Complex::from_lar(Lar::from_vertex_sets(vertices, sets)?)?;
        for (name, tag) in global.tags().iter() {
            let local: Vec<usize> = tag
                .cells
                .iter()
                .filter_map(|g| cells[tag.dim].binary_search(g).ok())
                .collect();
            complex.set_tag(name, tag.dim, local)?;
        }
        let owner = (0..=n)
            .map(|p| {
                let all = owners(global, part, p);
                cells[p].iter().map(|&c| all[c]).collect()
            })
            .collect();
        Ok(LocalComplex {
            complex,
            global: cells,
            owner,
            rank,
        })
    }

    /// The local p-cells this rank owns.
    pub fn owned(&self, p: usize) -> impl Iterator<Item = usize> + '_ {
        self.owner[p]
            .iter()
            .enumerate()
            .filter(move |(_, &r)| r == self.rank)
            .map(|(j, _)| j)
    }
}
