//! Partitions of the top cells among ranks: METIS k-way on the dual graph
//! (top cells adjacent through an (n−1)-cell, read off ∂ₙ).

use super::DistributedError;
use hasse_complex::Complex;
use metis_sys as metis;

/// The rank of every top cell of `complex` among `parts` ranks.
///
/// One part gives every cell to rank 0. More parts than top cells is
/// refused: a rank without cells would own no unknowns and PETSc's row
/// layout would have empty ranks that carry no work (and METIS refuses it).
///
/// ```
/// use hasse_complex::generate::rectangle;
/// use hasse_solver::distributed::partition_top_cells;
/// let mesh = rectangle(8, 8, [0.0, 1.0], [0.0, 1.0]).unwrap();
/// let part = partition_top_cells(&mesh, 3).unwrap();
/// // Every rank gets cells, and about a third of them.
/// for rank in 0..3 {
///     let owned = part.iter().filter(|&&p| p == rank).count();
///     assert!(owned > 15 && owned < 28);
/// }
/// ```
pub fn partition_top_cells(
    complex: &Complex,
    parts: usize,
) -> Result<Vec<usize>, DistributedError> {
    let n = complex.dim();
    let cells = complex.cell_count(n);
    if parts == 0 || parts > cells {
        return Err(DistributedError::TooManyRanks {
            ranks: parts,
            cells,
        });
    }
    if parts == 1 {
        return Ok(vec![0; cells]);
    }
    // The dual graph: two top cells are neighbours when they share an
    // (n−1)-cell, i.e. when a row of ∂ₙ has both.
    let mut neighbours: Vec<Vec<metis::idx_t>> = vec![Vec::new(); cells];
    if n >= 1 {
        let top = complex.boundary(n);
        for row in top.outer_iterator() {
            let adjacent = row.indices();
            for (a, &i) in adjacent.iter().enumerate() {
                for &j in &adjacent[a + 1..] {
                    neighbours[i].push(j as metis::idx_t);
                    neighbours[j].push(i as metis::idx_t);
                }
            }
        }
    }
    let mut xadj: Vec<metis::idx_t> = Vec::with_capacity(cells + 1);
    let mut adjncy: Vec<metis::idx_t> = Vec::new();
    xadj.push(0);
    for list in &mut neighbours {
        list.sort_unstable();
        list.dedup();
        adjncy.extend_from_slice(list);
        xadj.push(adjncy.len() as metis::idx_t);
    }
    if adjncy.is_empty() {
        // No adjacency (a single top cell per part is then the only sane
        // split): consecutive blocks.
        return Ok((0..cells).map(|c| c * parts / cells).collect());
    }
    let mut nvtxs = cells as metis::idx_t;
    let mut ncon: metis::idx_t = 1;
    let mut nparts = parts as metis::idx_t;
    let mut objval: metis::idx_t = 0;
    let mut part = vec![0 as metis::idx_t; cells];
    let mut options = [0 as metis::idx_t; metis::METIS_NOPTIONS as usize];
    // SAFETY: `options` has METIS_NOPTIONS entries; xadj has nvtxs + 1
    // nondecreasing offsets into adjncy, whose entries lie in 0..nvtxs and
    // differ from their own vertex (cells are not their own neighbours);
    // part has nvtxs entries; the weights and target fractions may be null
    // (uniform). METIS keeps no pointer past the call.
    let status = unsafe {
        metis::METIS_SetDefaultOptions(options.as_mut_ptr());
        options[metis::moptions_et_METIS_OPTION_NUMBERING as usize] = 0;
        // A fixed seed: every rank that partitions the same mesh gets the
        // same partition.
        options[metis::moptions_et_METIS_OPTION_SEED as usize] = 1;
        metis::METIS_PartGraphKway(
            &mut nvtxs,
            &mut ncon,
            xadj.as_mut_ptr(),
            adjncy.as_mut_ptr(),
            std::ptr::null_mut(),
            std::ptr::null_mut(),
            std::ptr::null_mut(),
            &mut nparts,
            std::ptr::null_mut(),
            std::ptr::null_mut(),
            options.as_mut_ptr(),
            &mut objval,
            part.as_mut_ptr(),
        )
    };
    if status != metis::rstatus_et_METIS_OK {
        return Err(DistributedError::Partition(format!(
            "METIS_PartGraphKway returned status {status}"
        )));
    }
    let part: Vec<usize> = part.iter().map(|&p| p as usize).collect();
    let mut counts = vec![0usize; parts];
    for &p in &part {
        match counts.get_mut(p) {
            Some(c) => *c += 1,
            None => {
                return Err(DistributedError::Partition(format!(
                    "METIS put a cell in part {p} of {parts}"
                )))
            }
        }
    }
    if let Some(empty) = counts.iter().position(|&c| c == 0) {
        return Err(DistributedError::Partition(format!(
            "METIS left part {empty} of {parts} without cells ({cells} top cells); run on fewer ranks"
        )));
    }
    Ok(part)
}
