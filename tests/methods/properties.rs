//! Property tests over random meshes (Delaunay, perturbed quads, sheared
//! graded hexes, perturbed Kuhn tetrahedra, Voronoi polygons, graded grids) and random
//! SPLIT sequences:
//!
//! - SPLIT sequences: ∂∂ = 0, χ and Betti numbers kept, ∂ζ = ζ∂ for the
//!   composed chain map, measures of the pieces sum to their ancestor's;
//! - the canonical operator M = AᵀΩA of every method without boundary
//!   conditions: symmetric, positive semi-definite, kernel exactly the
//!   constants (dense eigenvalues, so meshes are kept small);
//! - the patch test: with Dirichlet data from a linear u, no source and a
//!   constant conductivity, every method reproduces u exactly on every cell
//!   type where its documentation claims consistency (FE: P1 simplices, Q1
//!   quads and hexes, virtual elements on polygons; DEC circumcentric on
//!   triangles and tetrahedra; mimetic FV on any convex cell; two-point FV
//!   and FD on orthogonal graded grids).
//!
//! Case counts are small so the suite stays fast; PROPTEST_CASES=N runs N
//! cases of each property instead.

use approx::relative_eq;
use hasse_complex::generate::{delaunay, grid, kuhn, perturb, rectangle, uniform_axis, voronoi};
use hasse_complex::split::{split, Hyperplane, Refinement, SplitOptions};
use hasse_complex::{Complex, DualKind, Vertices};
use hasse_solver::metric::Method;
use hasse_solver::physics::diffusion::{errors, Diffusion};
use hasse_solver::physics::BoundaryKind;
use hasse_solver::physics::Conductivity;
use hasse_solver::physics::ScalarFn;
use nalgebra::DMatrix;
use proptest::prelude::*;
use sprs::CsMat;
use std::sync::Arc;

fn cases(default: u32) -> u32 {
    std::env::var("PROPTEST_CASES")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(default)
}

fn lcg(seed: u64) -> impl FnMut() -> f64 {
    let mut state = seed.wrapping_mul(6364136223846793005).wrapping_add(1);
    move || {
        state = state
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (state >> 11) as f64 / (1u64 << 53) as f64
    }
}

/// Small random meshes of every cell type; `kind` picks one.
fn mesh(kind: usize, seed: u64) -> Complex {
    let axis = |n| uniform_axis(n, 0.0, 1.0).unwrap();
    match kind % 6 {
        0 => {
            let mut next = lcg(seed);
            let mut points = vec![[0.0, 0.0], [1.0, 0.0], [0.0, 1.0], [1.0, 1.0]];
            for _ in 0..10 {
                points.push([0.05 + 0.9 * next(), 0.05 + 0.9 * next()]);
            }
            delaunay(&points).unwrap()
        }
        1 => perturb(
            &rectangle(4, 3, [0.0, 1.0], [0.0, 1.0]).unwrap(),
            0.25,
            seed,
        )
        .unwrap(),
        2 => perturb(&kuhn(&[axis(2), axis(2), axis(2)]).unwrap(), 0.2, seed).unwrap(),
        3 => {
            // Hexahedra must keep planar faces to be the convex cells SPLIT
            // and the mimetic method are defined on (a perturbed hex grid
            // warps its faces): a graded box under a random shear.
            let mut next = lcg(seed);
            let graded = |n, r: f64| hasse_complex::generate::graded_axis(n, 0.0, 1.0, r).unwrap();
            let k = grid(&[graded(2, 0.7 + next()), graded(2, 0.7 + next()), axis(2)]).unwrap();
            let shear: Vec<f64> = (0..3).map(|_| 0.4 * next() - 0.2).collect();
            let coords: Vec<f64> = (0..k.cell_count(0))
                .flat_map(|v| {
                    let x = k.vertices().point(v);
                    [
                        x[0] + shear[0] * x[1],
                        x[1] + shear[1] * x[2],
                        x[2] + shear[2] * x[0],
                    ]
                })
                .collect();
            k.with_vertices(Vertices::new(3, coords).unwrap()).unwrap()
        }
        4 => voronoi(12, [0.0, 1.0], [0.0, 1.0], seed, 1).unwrap(),
        _ => {
            // A graded grid: ratios from the seed.
            let mut next = lcg(seed);
            let graded = |n, r: f64| hasse_complex::generate::graded_axis(n, 0.0, 1.0, r).unwrap();
            grid(&[graded(4, 0.6 + next()), graded(3, 0.6 + next())]).unwrap()
        }
    }
}

fn dense_i8(m: &CsMat<i8>) -> Vec<Vec<i8>> {
    m.to_dense()
        .rows()
        .into_iter()
        .map(|r| r.to_vec())
        .collect()
}

fn plane(d: usize, a: f64, b: f64, offset: f64) -> Hyperplane {
    let normal: Vec<f64> = if d == 2 {
        vec![a.cos(), a.sin()]
    } else {
        vec![a.cos() * b.sin(), a.sin() * b.sin(), b.cos()]
    };
    let point: Vec<f64> = normal.iter().map(|h| 0.5 + (offset - 0.5) * h).collect();
    Hyperplane::through(&point, &normal).unwrap()
}

fn check_refinement(coarse: &Complex, fine: &Complex, r: &Refinement) -> Result<(), TestCaseError> {
    let n = coarse.dim();
    for p in 2..=n {
        let product = &**fine.boundary(p - 1) * &**fine.boundary(p);
        prop_assert!(product.data().iter().all(|&v| v == 0), "∂∂ ≠ 0 at {p}");
    }
    prop_assert_eq!(fine.euler_characteristic(), coarse.euler_characteristic());
    prop_assert_eq!(fine.betti_numbers(), coarse.betti_numbers());
    for p in 1..=n {
        let left = &**fine.boundary(p) * r.zeta(p);
        let right = r.zeta(p - 1) * &**coarse.boundary(p);
        prop_assert_eq!(dense_i8(&left), dense_i8(&right), "∂ζ ≠ ζ∂ at {}", p);
        let mut sum = vec![0.0; coarse.cell_count(p)];
        for i in 0..fine.cell_count(p) {
            if let Some((j, _)) = r.parent(p, i) {
                sum[j] += fine.measure(p)[i];
            }
        }
        for (j, (s, m)) in sum.iter().zip(coarse.measure(p)).enumerate() {
            prop_assert!(
                relative_eq!(s, m, epsilon = 0.0, max_relative = 1e-11),
                "{p}-cell {j}: pieces {s}, cell {m}"
            );
        }
    }
    Ok(())
}

fn methods_for(kind: usize) -> Vec<Method> {
    let circumcentric = Method::Dec(DualKind::Circumcentric);
    match kind % 6 {
        // Delaunay triangles: P1, DEC (= P1 in 2D), mimetic, two-point.
        0 => vec![Method::Fe, circumcentric, Method::FvMimetic, Method::Fv],
        // Quads and hexes, polygons: Q1 / VEM and mimetic.
        1 | 3 | 4 => vec![Method::Fe, Method::FvMimetic, Method::Fv],
        2 => vec![Method::Fe, circumcentric, Method::FvMimetic, Method::Fv],
        _ => vec![
            Method::Fe,
            Method::Fd,
            Method::Fv,
            Method::FvMimetic,
            Method::Dec(DualKind::Barycentric),
        ],
    }
}

/// Methods whose documentation claims exactness for linear solutions on
/// the meshes of `kind`.
fn consistent_methods(kind: usize) -> Vec<Method> {
    match kind % 6 {
        0 | 2 => vec![
            Method::Fe,
            Method::Dec(DualKind::Circumcentric),
            Method::FvMimetic,
        ],
        1 | 3 | 4 => vec![Method::Fe, Method::FvMimetic],
        _ => vec![Method::Fe, Method::Fd, Method::Fv, Method::FvMimetic],
    }
}

fn constant(v: f64) -> ScalarFn {
    Arc::new(move |_: &[f64]| v)
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(cases(12)))]

    /// Up to four planes in a row, each on all cells or on every other one.
    #[test]
    fn split_sequences_keep_the_invariants(
        kind in prop_oneof![Just(0usize), Just(1), Just(2), Just(3), Just(5)],
        seed in 0u64..1000,
        planes in proptest::collection::vec((0.0f64..6.3, 0.2f64..2.9, 0.1f64..0.9, any::<bool>()), 1..4),
    ) {
        let coarse = mesh(kind, seed);
        let d = coarse.embedding_dim();
        let mut k = coarse.clone();
        let mut total = Refinement::identity(&k);
        for (a, b, offset, restricted) in planes {
            let h = plane(d, a, b, offset);
            let some: Vec<usize> = (0..k.cell_count(d)).step_by(2).collect();
            let (fine, r) = split(&k, &h, restricted.then_some(&some[..]), SplitOptions::default()).unwrap();
            check_refinement(&k, &fine, &r)?;
            total = total.compose(&r).unwrap();
            k = fine;
        }
        check_refinement(&coarse, &k, &total)?;
    }

    /// M = AᵀΩA with no boundary condition is symmetric positive
    /// semi-definite with the constants as its whole kernel (the meshes are
    /// connected).
    #[test]
    fn canonical_operators_are_spsd_with_constant_kernel(
        kind in 0usize..6,
        seed in 0u64..1000,
        lambda in 0.1f64..10.0,
    ) {
        let k = mesh(kind, seed);
        for method in methods_for(kind) {
            let problem = Diffusion::new(method, Conductivity::Scalar(constant(lambda)), constant(0.0));
            let system = problem.assemble(&k).unwrap();
            prop_assert!(system.pure_neumann, "{}", method.name());
            let size = system.matrix.nrows();
            let mut m = DMatrix::<f64>::zeros(size, size);
            for c in 0..size {
                let range = system.matrix.col_range(c);
                for (&r, &v) in system.matrix.row_idx()[range.clone()].iter().zip(&system.matrix.val()[range]) {
                    m[(r, c)] += v;
                }
            }
            let scale = m.amax();
            prop_assert!((&m - m.transpose()).amax() <= 1e-12 * scale, "{} not symmetric", method.name());
            let ones = DMatrix::<f64>::from_element(size, 1, 1.0);
            prop_assert!((&m * ones).amax() <= 1e-11 * scale, "{}: M·1 ≠ 0", method.name());
            let mut eigen: Vec<f64> = m.symmetric_eigenvalues().iter().copied().collect();
            eigen.sort_by(f64::total_cmp);
            prop_assert!(eigen[0] >= -1e-10 * scale, "{}: eigenvalue {}", method.name(), eigen[0]);
            prop_assert!(eigen[1] > 1e-8 * scale, "{}: kernel larger than the constants ({:?})", method.name(), &eigen[..3]);
        }
    }

    /// The patch test: u = a + b·x is reproduced to rounding.
    #[test]
    fn consistent_methods_reproduce_linear_solutions(
        kind in 0usize..6,
        seed in 0u64..1000,
        a in -2.0f64..2.0,
        b in proptest::array::uniform3(-3.0f64..3.0),
        lambda in 0.1f64..10.0,
    ) {
        let k = mesh(kind, seed);
        let exact: ScalarFn = Arc::new(move |x: &[f64]| a + x.iter().zip(&b).map(|(x, b)| x * b).sum::<f64>());
        for method in consistent_methods(kind) {
            let problem = Diffusion::new(method, Conductivity::Scalar(constant(lambda)), constant(0.0))
                .with_boundary("boundary", BoundaryKind::Dirichlet(exact.clone()));
            let solution = problem.solve(&k).unwrap();
            let e = errors(&k, &solution, &exact, None);
            prop_assert!(e.max <= 1e-9 * (1.0 + a.abs() + b.iter().map(|v| v.abs()).sum::<f64>()),
                "{} on mesh kind {kind}: max error {:e}", method.name(), e.max);
        }
    }
}
