//! The partitioned complex of distributed solves (solver/src/distributed):
//! every top cell owned once, the ghost layer the whole LAR star, local
//! incidence equal to the global one through the global ids, and — the
//! property the distributed assembly rests on — the rows of owned unknowns
//! assembled on a local complex equal the rows of the global operator.
//! None of this needs MPI: each rank's view is built here for every rank.

use hasse_complex::generate::{kuhn, rectangle, uniform_axis};
use hasse_complex::gmsh::read_msh;
use hasse_complex::{Complex, DualKind};
use hasse_solver::distributed::{partition_top_cells, LocalComplex};
use hasse_solver::metric::{Location, Method};
use hasse_solver::physics::diffusion::Diffusion;
use hasse_solver::physics::{BoundaryKind, Conductivity};
use std::collections::HashMap;
use std::path::Path;
use std::sync::Arc;

type TestResult = Result<(), Box<dyn std::error::Error>>;
/// A named mesh and the tag its Dirichlet condition goes on.
type TestMesh = (&'static str, Complex, &'static str);

/// The three meshes of the distributed tests, with a Dirichlet tag each: a
/// 2D grid, a 3D Kuhn box and the shipped Gmsh L-shape.
fn meshes() -> Result<Vec<TestMesh>, Box<dyn std::error::Error>> {
    let lshape = Path::new(env!("CARGO_MANIFEST_DIR")).join("../cases/l-shape.msh");
    let axis = uniform_axis(3, 0.0, 1.0)?;
    Ok(vec![
        ("grid 9×7", rectangle(9, 7, [0.0, 1.0], [0.0, 1.0])?, "left"),
        (
            "Kuhn box 3³",
            kuhn(&[axis.clone(), axis.clone(), axis])?,
            "boundary",
        ),
        ("Gmsh L-shape", read_msh(&lshape)?, "dirichlet"),
    ])
}

#[test]
fn every_top_cell_is_owned_once_and_the_ghost_layer_is_the_star() -> TestResult {
    for (name, mesh, _) in meshes()? {
        let n = mesh.dim();
        for ranks in 1..=3 {
            let part = partition_top_cells(&mesh, ranks)?;
            let mut owned_by = vec![Vec::new(); mesh.cell_count(n)];
            for rank in 0..ranks {
                let local = LocalComplex::new(&mesh, &part, rank)?;
                for j in local.owned(n) {
                    owned_by[local.global[n][j]].push(rank);
                }
                // The ghost layer: every top cell sharing a vertex with an
                // owned one is local (computed here from vertex lists).
                let owned_vertices: Vec<usize> = (0..mesh.cell_count(n))
                    .filter(|&c| part[c] == rank)
                    .flat_map(|c| mesh.cell_vertices(n, c).to_vec())
                    .collect();
                for c in 0..mesh.cell_count(n) {
                    let touches = mesh
                        .cell_vertices(n, c)
                        .iter()
                        .any(|v| owned_vertices.contains(v));
                    let local_has = local.global[n].binary_search(&c).is_ok();
                    assert_eq!(
                        touches, local_has,
                        "{name}, {ranks} ranks, rank {rank}, top cell {c}"
                    );
                }
            }
            assert!(
                owned_by.iter().all(|r| r.len() == 1),
                "{name}, {ranks} ranks: a top cell owned by other than one rank"
            );
        }
    }
    Ok(())
}

#[test]
fn local_incidence_is_the_global_incidence_and_squares_to_zero() -> TestResult {
    for (name, mesh, _) in meshes()? {
        let n = mesh.dim();
        let part = partition_top_cells(&mesh, 3)?;
        for rank in 0..3 {
            let local = LocalComplex::new(&mesh, &part, rank)?;
            for p in 1..=n {
                let local_boundary = local.complex.boundary_csc(p);
                let global_boundary = mesh.boundary_csc(p);
                for j in 0..local.complex.cell_count(p) {
                    let g = local.global[p][j];
                    let mut mine: Vec<(usize, i8)> = local_boundary
                        .outer_view(j)
                        .map(|c| {
                            c.iter()
                                .map(|(f, &s)| (local.global[p - 1][f], s))
                                .collect()
                        })
                        .unwrap_or_default();
                    let mut theirs: Vec<(usize, i8)> = global_boundary
                        .outer_view(g)
                        .map(|c| c.iter().map(|(f, &s)| (f, s)).collect())
                        .unwrap_or_default();
                    mine.sort_unstable();
                    theirs.sort_unstable();
                    assert_eq!(
                        mine, theirs,
                        "{name}, rank {rank}: column {j} of ∂_{p} (global {g})"
                    );
                }
                if p >= 2 {
                    let dd = &**local.complex.boundary(p - 1) * &**local.complex.boundary(p);
                    assert!(
                        dd.data().iter().all(|&x| x == 0),
                        "{name}, rank {rank}: ∂∂ ≠ 0"
                    );
                }
            }
            // Ranks agree on owners: the owner of each local cell sees it as
            // owned in its own local complex.
            for p in 0..=n {
                for (j, &owner) in local.owner[p].iter().enumerate() {
                    let theirs = LocalComplex::new(&mesh, &part, owner)?;
                    let k = theirs.global[p].binary_search(&local.global[p][j]);
                    assert!(
                        k.is_ok_and(|k| theirs.owner[p][k] == owner),
                        "{name}: rank {rank}'s {p}-cell {j} is not owned by rank {owner}, its owner"
                    );
                }
            }
        }
    }
    Ok(())
}

/// The global id of local unknown `u` in the serial layout of `location`.
fn global_unknown(local: &LocalComplex, location: Location, global_top: usize, u: usize) -> usize {
    let n = local.complex.dim();
    let top = local.complex.cell_count(n);
    match location {
        Location::Nodal => local.global[0][u],
        Location::CellCentred => local.global[n][u],
        Location::Hybrid if u < top => local.global[n][u],
        Location::Hybrid => global_top + local.global[n - 1][u - top],
    }
}

fn rows(matrix: &faer::sparse::SparseColMat<usize, f64>) -> Vec<Vec<(usize, f64)>> {
    let mut rows = vec![Vec::new(); matrix.nrows()];
    for c in 0..matrix.ncols() {
        let range = matrix.col_range(c);
        for (&r, &v) in matrix.row_idx()[range.clone()]
            .iter()
            .zip(&matrix.val()[range])
        {
            rows[r].push((c, v));
        }
    }
    rows
}

#[test]
fn owned_rows_assembled_on_a_local_complex_are_the_global_rows() -> TestResult {
    let methods = [
        Method::Fd,
        Method::Fe,
        Method::Fv,
        Method::FvMimetic,
        Method::Dec(DualKind::Circumcentric),
    ];
    let mut compared = 0;
    for (name, mesh, tag) in meshes()? {
        let n = mesh.dim();
        for method in methods {
            let problem = Diffusion::new(
                method,
                Conductivity::Scalar(Arc::new(|x: &[f64]| 1.0 + x[0])),
                Arc::new(|x: &[f64]| x[1] - x[0] * x[0]),
            )
            .with_boundary(
                tag,
                BoundaryKind::Dirichlet(Arc::new(|x: &[f64]| x[0] + 2.0 * x[1])),
            );
            // A method that refuses the mesh (FD off grids) refuses it
            // whole; nothing to compare.
            let Ok(global) = problem.assemble(&mesh) else {
                continue;
            };
            let global_rows = rows(&global.matrix);
            let part = partition_top_cells(&mesh, 3)?;
            for rank in 0..3 {
                let local = LocalComplex::new(&mesh, &part, rank)?;
                let system = problem.assemble(&local.complex)?;
                let location = system.location;
                let owned_unknowns: Vec<usize> = (0..system.rhs.len())
                    .filter(|&u| {
                        let top = local.complex.cell_count(n);
                        let (p, j) = match location {
                            Location::Nodal => (0, u),
                            Location::CellCentred => (n, u),
                            Location::Hybrid if u < top => (n, u),
                            Location::Hybrid => (n - 1, u - top),
                        };
                        local.owner[p][j] == rank
                    })
                    .collect();
                let local_rows = rows(&system.matrix);
                for u in owned_unknowns {
                    let g = global_unknown(&local, location, mesh.cell_count(n), u);
                    let mine: HashMap<usize, f64> = local_rows[u]
                        .iter()
                        .map(|&(c, v)| (global_unknown(&local, location, mesh.cell_count(n), c), v))
                        .collect();
                    let scale = global_rows[g]
                        .iter()
                        .map(|(_, v)| v.abs())
                        .fold(0.0, f64::max);
                    assert_eq!(
                        mine.len(),
                        global_rows[g].len(),
                        "{name} {method:?}: row {g} pattern"
                    );
                    for &(c, v) in &global_rows[g] {
                        let w = mine.get(&c).copied().unwrap_or(f64::NAN);
                        // The same element contributions, summed in another
                        // order: equal to a few ulps of the row's size.
                        assert!(
                            (w - v).abs() <= 1e-13 * scale,
                            "{name} {method:?}: M[{g}, {c}] = {w} locally, {v} globally"
                        );
                    }
                    let b_scale = global.rhs.iter().map(|b| b.abs()).fold(1e-300, f64::max);
                    assert!(
                        (system.rhs[u] - global.rhs[g]).abs() <= 1e-13 * b_scale,
                        "{name} {method:?}: b[{g}]"
                    );
                    assert_eq!(
                        system.fixed[u], global.fixed[g],
                        "{name} {method:?}: fixed value of {g}"
                    );
                    compared += 1;
                }
            }
        }
    }
    // Grid: 5 methods; Kuhn box and L-shape: all but FD (grids only).
    assert!(compared > 1000, "only {compared} rows compared");
    Ok(())
}
