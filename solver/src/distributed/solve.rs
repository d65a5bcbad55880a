//! Distributed diffusion: each rank assembles Aᵀ Ω A on its local complex
//! with the serial code, keeps the rows it owns, and PETSc solves the
//! global system; the solution is gathered on rank 0.

use super::petsc::{self, Defaults, KspReport, Matrix, Petsc, Vector};
use super::{partition_top_cells, DistributedError, LocalComplex};
use crate::metric::Location;
use crate::physics::diffusion::Diffusion;
use hasse_complex::Complex;
use mpi::datatype::{Partition, PartitionMut};
use mpi::traits::*;
use std::collections::HashMap;
use std::time::Instant;

/// What a distributed solve gives back.
#[derive(Clone, Debug)]
pub struct DistributedSolve {
    /// All unknowns in the serial layout of the method (vertices, top
    /// cells, or top cells then (n−1)-cells), on rank 0; empty elsewhere.
    pub values: Vec<f64>,
    /// How KSP ended.
    pub ksp: KspReport,
    /// Number of ranks.
    pub ranks: usize,
    /// Unknowns owned per rank (rank 0 only; empty elsewhere).
    pub owned: Vec<usize>,
    /// Top cells of this rank's local complex, owned and ghost.
    pub local_top_cells: (usize, usize),
    /// Seconds of partitioning, the local complex and the local assembly
    /// (this rank).
    pub assembly_seconds: f64,
    /// Seconds of the PETSc solve.
    pub solve_seconds: f64,
}

/// The local unknown `u` of a method with unknowns at `location`: which
/// cells it sits on (dimension, local cell), and its global id in the
/// serial layout.
fn unknown_cell(location: Location, local: &LocalComplex, u: usize) -> (usize, usize, usize) {
    let n = local.complex.dim();
    match location {
        Location::Nodal => (0, u, local.global[0][u]),
        Location::CellCentred => (n, u, local.global[n][u]),
        Location::Hybrid => {
            let top = local.complex.cell_count(n);
            if u < top {
                (n, u, local.global[n][u])
            } else {
                // Faces come after all global top cells in the serial layout.
                (n - 1, u - top, usize::MAX)
            }
        }
    }
}

/// The global id of a local unknown in the serial layout.
fn global_unknown(location: Location, local: &LocalComplex, global_top: usize, u: usize) -> usize {
    let (p, j, g) = unknown_cell(location, local, u);
    if g == usize::MAX {
        global_top + local.global[p][j]
    } else {
        g
    }
}

/// Exchange by all-to-all: `requests[r]` goes to rank r; returns what
/// each rank sent here, concatenated by rank, with the counts.
fn exchange<T: Equivalence + Default + Clone>(
    world: &impl Communicator,
    requests: &[Vec<T>],
) -> (Vec<T>, Vec<i32>) {
    let size = world.size() as usize;
    let send_counts: Vec<i32> = requests.iter().map(|r| r.len() as i32).collect();
    let mut recv_counts = vec![0i32; size];
    world.all_to_all_into(&send_counts[..], &mut recv_counts[..]);
    let displs = |counts: &[i32]| {
        counts
            .iter()
            .scan(0i32, |acc, &c| {
                let d = *acc;
                *acc += c;
                Some(d)
            })
            .collect::<Vec<i32>>()
    };
    let send: Vec<T> = requests.iter().flatten().cloned().collect();
    let mut received = vec![T::default(); recv_counts.iter().map(|&c| c as usize).sum()];
    {
        let send_displs = displs(&send_counts);
        let recv_displs = displs(&recv_counts);
        let partition = Partition::new(&send[..], &send_counts[..], &send_displs[..]);
        let mut out = PartitionMut::new(&mut received[..], &recv_counts[..], &recv_displs[..]);
        world.all_to_all_varcount_into(&partition, &mut out);
    }
    (received, recv_counts)
}

/// Solve `problem` on `global` across the ranks of `world`.
///
/// Every rank partitions the same mesh the same way (METIS with a fixed
/// seed), builds its local complex (owned cells and the ghost star) and
/// assembles the serial Aᵀ Ω A on it. The rows of owned unknowns are
/// exact: every cell around an owned unknown is local. Unknowns fixed by a
/// Dirichlet condition are told by their owners (a ghost may lie on a
/// global Dirichlet face that this rank does not see), eliminated
/// symmetrically from the owned rows and given identity rows, so the
/// global matrix stays symmetric positive definite for CG.
pub fn solve_diffusion(
    world: &impl Communicator,
    petsc: &Petsc,
    problem: &Diffusion,
    global: &Complex,
    defaults: Defaults,
) -> Result<DistributedSolve, DistributedError> {
    let started = Instant::now();
    let rank = world.rank() as usize;
    let size = world.size() as usize;
    let n = global.dim();
    let part = partition_top_cells(global, size)?;
    let local = LocalComplex::new(global, &part, rank)?;
    let system = problem.assemble(&local.complex)?;
    let location = system.location;
    let global_top = global.cell_count(n);
    let unknowns = system.rhs.len();

    // Pure Neumann is global: every rank must see no Dirichlet or Robin face.
    let mut any_anchor = 0i32;
    world.all_reduce_into(
        &i32::from(!system.pure_neumann),
        &mut any_anchor,
        mpi::collective::SystemOperation::max(),
    );
    if any_anchor == 0 {
        return Err(DistributedError::PureNeumann);
    }

    // Owned unknowns in increasing global id: their PETSc rows.
    let owner_of = |u: usize| {
        let (p, j, _) = unknown_cell(location, &local, u);
        local.owner[p][j]
    };
    let mut owned: Vec<(usize, usize)> = (0..unknowns)
        .filter(|&u| owner_of(u) == rank)
        .map(|u| (global_unknown(location, &local, global_top, u), u))
        .collect();
    owned.sort_unstable();
    let mut counts = vec![0u64; size];
    world.all_gather_into(&(owned.len() as u64), &mut counts[..]);
    let first: usize = counts[..rank].iter().map(|&c| c as usize).sum();
    let total: usize = counts.iter().map(|&c| c as usize).sum();
    if total > i32::MAX as usize {
        return Err(DistributedError::TooLarge { unknowns: total });
    }
    let mut petsc_row = vec![usize::MAX; unknowns];
    let mut by_global: HashMap<u64, usize> = HashMap::with_capacity(owned.len());
    for (k, &(g, u)) in owned.iter().enumerate() {
        petsc_row[u] = first + k;
        by_global.insert(g as u64, u);
    }
    // Fixed values of every local unknown: own ones from the assembly,
    // ghosts from their owners.
    let mut fixed: Vec<Option<f64>> = vec![None; unknowns];
    for &(_, u) in &owned {
        fixed[u] = system.fixed.get(u).copied().flatten();
    }
    let mut requests: Vec<Vec<u64>> = vec![Vec::new(); size];
    let mut asked: Vec<Vec<usize>> = vec![Vec::new(); size];
    for u in 0..unknowns {
        let r = owner_of(u);
        if r != rank {
            requests[r].push(global_unknown(location, &local, global_top, u) as u64);
            asked[r].push(u);
        }
    }
    let (wanted, wanted_counts) = exchange(world, &requests);
    // Answers in the order asked: the PETSc row, whether fixed, the value.
    let mut rows_back: Vec<Vec<i64>> = vec![Vec::new(); size];
    let mut values_back: Vec<Vec<f64>> = vec![Vec::new(); size];
    let mut at = 0usize;
    for (r, &count) in wanted_counts.iter().enumerate() {
        for &g in &wanted[at..at + count as usize] {
            let Some(&u) = by_global.get(&g) else {
                return Err(DistributedError::Partition(format!(
                    "rank {r} asked rank {rank} for unknown {g}, which it does not own"
                )));
            };
            let value = fixed[u];
            rows_back[r].push(petsc_row[u] as i64);
            rows_back[r].push(i64::from(value.is_some()));
            values_back[r].push(value.unwrap_or(0.0));
        }
        at += count as usize;
    }
    let (rows, _) = exchange(world, &rows_back);
    let (values, _) = exchange(world, &values_back);
    for (k, &u) in asked.iter().flatten().enumerate() {
        petsc_row[u] = rows[2 * k] as usize;
        if rows[2 * k + 1] != 0 {
            fixed[u] = Some(values[k]);
        }
    }

    // The owned rows of M, with fixed columns moved to the right-hand side.
    let matrix = &system.matrix;
    let mut row_entries: Vec<Vec<(i32, f64)>> = vec![Vec::new(); unknowns];
    let is_owned = |u: usize| petsc_row[u] >= first && petsc_row[u] < first + owned.len();
    for column in 0..matrix.ncols() {
        let range = matrix.col_range(column);
        for (&row, &value) in matrix.row_idx()[range.clone()]
            .iter()
            .zip(&matrix.val()[range])
        {
            if is_owned(row) {
                row_entries[row].push((column as i32, value));
            }
        }
    }
    let mut diagonal = Vec::with_capacity(owned.len());
    let mut off_diagonal = Vec::with_capacity(owned.len());
    let mut rhs = Vec::with_capacity(owned.len());
    let mut rows_out: Vec<(Vec<i32>, Vec<f64>)> = Vec::with_capacity(owned.len());
    for &(_, u) in &owned {
        if let Some(value) = fixed[u] {
            rows_out.push((vec![petsc_row[u] as i32], vec![1.0]));
            rhs.push(value);
            diagonal.push(1);
            off_diagonal.push(0);
            continue;
        }
        let mut b = system.rhs[u];
        let (mut columns, mut entries) = (Vec::new(), Vec::new());
        for &(j, value) in &row_entries[u] {
            let j = j as usize;
            match fixed[j] {
                Some(g) => b -= value * g,
                None => {
                    columns.push(petsc_row[j] as i32);
                    entries.push(value);
                }
            }
        }
        let inside = columns
            .iter()
            .filter(|&&c| (c as usize) >= first && (c as usize) < first + owned.len())
            .count() as i32;
        diagonal.push(inside);
        off_diagonal.push(columns.len() as i32 - inside);
        rows_out.push((columns, entries));
        rhs.push(b);
    }
    let assembly_seconds = started.elapsed().as_secs_f64();

    let solving = Instant::now();
    let mut m = Matrix::new(petsc, owned.len(), total, &diagonal, &off_diagonal)?;
    for (k, (columns, entries)) in rows_out.iter().enumerate() {
        m.set_row((first + k) as i32, columns, entries)?;
    }
    m.assemble()?;
    let mut b = Vector::new(petsc, owned.len(), total)?;
    let indices: Vec<i32> = (first..first + owned.len()).map(|r| r as i32).collect();
    b.add(&indices, &rhs)?;
    let (mut x, ksp) = petsc::solve(petsc, &m, &b, defaults)?;
    let solve_seconds = solving.elapsed().as_secs_f64();
    if ksp.reason < 0 {
        return Err(DistributedError::Diverged(ksp));
    }
    // Fixed rows are identities: their exact values, not KSP's approximation.
    for (k, &(_, u)) in owned.iter().enumerate() {
        if let Some(value) = fixed[u] {
            x[k] = value;
        }
    }

    // Gather (global id, value) on rank 0.
    let ids: Vec<u64> = owned.iter().map(|&(g, _)| g as u64).collect();
    let root = world.process_at_rank(0);
    let serial_unknowns = match location {
        Location::Nodal => global.cell_count(0),
        Location::CellCentred => global_top,
        Location::Hybrid => global_top + global.cell_count(n - 1),
    };
    let counts_i32: Vec<i32> = counts.iter().map(|&c| c as i32).collect();
    let displs: Vec<i32> = counts_i32
        .iter()
        .scan(0i32, |acc, &c| {
            let d = *acc;
            *acc += c;
            Some(d)
        })
        .collect();
    let mut values = Vec::new();
    if rank == 0 {
        let mut all_ids = vec![0u64; total];
        let mut all_values = vec![0f64; total];
        {
            let mut out = PartitionMut::new(&mut all_ids[..], &counts_i32[..], &displs[..]);
            root.gather_varcount_into_root(&ids[..], &mut out);
        }
        {
            let mut out = PartitionMut::new(&mut all_values[..], &counts_i32[..], &displs[..]);
            root.gather_varcount_into_root(&x[..], &mut out);
        }
        values = vec![f64::NAN; serial_unknowns];
        for (&g, &v) in all_ids.iter().zip(&all_values) {
            if let Some(slot) = values.get_mut(g as usize) {
                *slot = v;
            }
        }
        if let Some(missing) = values.iter().position(|v| v.is_nan()) {
            return Err(DistributedError::Partition(format!(
                "no rank owns unknown {missing} of {serial_unknowns}"
            )));
        }
    } else {
        root.gather_varcount_into(&ids[..]);
        root.gather_varcount_into(&x[..]);
    }
    let local_owned = local.owned(n).count();
    Ok(DistributedSolve {
        values,
        ksp,
        ranks: size,
        owned: if rank == 0 {
            counts.iter().map(|&c| c as usize).collect()
        } else {
            Vec::new()
        },
        local_top_cells: (local_owned, local.complex.cell_count(n) - local_owned),
        assembly_seconds,
        solve_seconds,
    })
}
