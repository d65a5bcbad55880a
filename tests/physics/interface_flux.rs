//! Fluxes across an interface inside the domain (issue 29): each method's
//! own, balancing each side to the solver's residual.
//!
//! On the unit cube, A = {x < 1/2} and B = {x > 1/2} meet in the plane
//! x = 1/2. What leaves A through the plane is what A produces less what
//! leaves A through the outer boundary:
//!
//!     flux out of A = ∫_A f − outflow(∂A ∩ ∂Ω),
//!
//! and likewise for B with the opposite sign. With f = 1, ∫_A f = |A| = 1/2
//! exactly as P1 loads it and as the barycentric DEC star does on
//! simplices (a vertex's barycentric dual cell takes |c|/(n+1) of every
//! simplex c around it, which is the weight the per-cell load gives). The
//! Kuhn tetrahedra orient the plane's triangles both ways, so the test also
//! covers faces whose +1 cell lies on either side.

use hasse_complex::dual::DualKind;
use hasse_complex::generate::{kuhn, uniform_axis};
use hasse_complex::Complex;
use hasse_solver::metric::Method;
use hasse_solver::physics::diffusion::Diffusion;
use hasse_solver::physics::{BoundaryKind, Conductivity};
use std::sync::Arc;

/// The triangles of the plane x = 1/2, and each one's sign: +1 where the
/// cell it points out of (∂₃ entry +1) lies in A.
fn plane(mesh: &Complex) -> (Vec<usize>, Vec<f64>) {
    let at_half = |v: usize| (mesh.vertices().point(v)[0] - 0.5).abs() < 1e-12;
    let faces: Vec<usize> = (0..mesh.cell_count(2))
        .filter(|&f| mesh.cell_vertices(2, f).iter().all(|&v| at_half(v)))
        .collect();
    let top = mesh.boundary(3);
    let signs = faces
        .iter()
        .map(|&f| {
            let row = top.outer_view(f).unwrap();
            let (plus, _) = row.iter().find(|(_, &s)| s > 0).unwrap();
            if mesh.centroid_of(3, plus)[0] < 0.5 {
                1.0
            } else {
                -1.0
            }
        })
        .collect();
    (faces, signs)
}

#[test]
fn the_flux_across_a_plane_balances_each_side_for_nodal_methods() {
    let x = uniform_axis(4, 0.0, 1.0).unwrap();
    let mesh = kuhn(&[x.clone(), x.clone(), x]).unwrap();
    let (faces, signs) = plane(&mesh);
    assert_eq!(
        faces.len(),
        2 * 4 * 4,
        "two triangles per square of the plane"
    );
    // Both orientations occur (the test's point).
    assert!(signs.contains(&1.0) && signs.contains(&-1.0));
    let top = mesh.boundary(3);
    for method in [Method::Fe, Method::Dec(DualKind::Barycentric)] {
        // Every kind of boundary face on both sides of the plane.
        let problem = Diffusion::new(
            method,
            Conductivity::Scalar(Arc::new(|x: &[f64]| 1.0 + x[0] + 0.5 * x[1])),
            Arc::new(|_| 1.0),
        )
        .with_boundary("xmin", BoundaryKind::Dirichlet(Arc::new(|x: &[f64]| x[1])))
        .with_boundary(
            "ymin",
            BoundaryKind::Neumann(Arc::new(|x: &[f64]| 0.3 + x[0])),
        )
        .with_boundary(
            "xmax",
            BoundaryKind::Dirichlet(Arc::new(|x: &[f64]| 2.0 + x[2])),
        )
        .with_boundary(
            "ymax",
            BoundaryKind::Robin {
                alpha: Arc::new(|_| 2.0),
                value: Arc::new(|x: &[f64]| x[2]),
            },
        )
        .with_boundary("zmax", BoundaryKind::Dirichlet(Arc::new(|_| 0.5)));
        let solution = problem.solve(&mesh).unwrap();
        let outflow = problem.boundary_outflow(&mesh, &solution).unwrap();
        let across = problem
            .flux_across(&mesh, &solution, &outflow, &faces)
            .unwrap();
        assert!(across.left_out.is_empty(), "the plane ends on the boundary");
        let out_of_a: f64 = across.flux.iter().zip(&signs).map(|(q, s)| q * s).sum();
        // The outflow of each side's part of the boundary.
        let (mut outflow_a, mut outflow_b) = (0.0, 0.0);
        for (f, &q) in outflow.iter().enumerate() {
            if let Some(c) = top
                .outer_view(f)
                .filter(|r| r.nnz() == 1)
                .and_then(|r| r.iter().next().map(|(c, _)| c))
            {
                if mesh.centroid_of(3, c)[0] < 0.5 {
                    outflow_a += q;
                } else {
                    outflow_b += q;
                }
            }
        }
        let scale = outflow.iter().map(|q| q.abs()).sum::<f64>();
        // Balances close to the direct solve's residual (≈ 1e-15 relative)
        // times the operator's norm: 1e-12 of the boundary terms.
        assert!(
            (out_of_a - (0.5 - outflow_a)).abs() < 1e-12 * scale,
            "{method:?}: {out_of_a} vs {}",
            0.5 - outflow_a
        );
        assert!(
            (-out_of_a - (0.5 - outflow_b)).abs() < 1e-12 * scale,
            "{method:?}: {} vs {}",
            -out_of_a,
            0.5 - outflow_b
        );
        // Not a vanishing flux: heat crosses the plane.
        // Not a vanishing flux: about K·Δu/Δx ≈ 2 × 2 enters A through the
        // plane (−K∇u·n out of A with u rising toward x = 1).
        assert!(out_of_a < -1.0, "{method:?}: {out_of_a}");
    }
}
