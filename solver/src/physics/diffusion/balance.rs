//! Fluxes out of the domain and the global balance, each method's own:
//! the discrete fluxes that make its equations, so that the balance
//! Σ outflow = ∫f closes to the solver's residual, not to the
//! discretisation error.
//!
//! - Cell-centred methods (`fv`, `fd`): the face flux q_F, outward from
//!   the domain as ∂ₙ(F, c) q_F for the one cell c of a boundary face.
//! - The hybrid method (`fv-mimetic`): the half-face flux of the boundary
//!   face's cell, already outward.
//! - Nodal methods (`fe`, `dec`): the residual flux. The equation of
//!   vertex v is (Aᵀ Ω A u)_v = f_v + (boundary data), so the flux leaving
//!   through v's share of the boundary is f_v − (Aᵀ q)_v with q = Ω A u
//!   (for P1/Q1 this is the variationally consistent boundary flux; for DEC
//!   the flux through the boundary part of v's dual cell). Neumann, Robin
//!   and natural faces get exactly the flux their data load at their
//!   vertices (−g, α u − g and 0 times |F|/#vertices(F)); the rest of a
//!   vertex's flux crosses its Dirichlet faces, shared among them in
//!   proportion to |F|/#vertices(F) times |−K∇u_h·n| on each (so that a
//!   corner gives its flux to the face that conducts it), or to
//!   |F|/#vertices(F) alone where none does.
//!
//! ```
//! use hasse_complex::generate::rectangle;
//! use hasse_solver::metric::Method;
//! use hasse_solver::physics::diffusion::Diffusion;
//! use hasse_solver::physics::{BoundaryKind, Conductivity};
//! use std::sync::Arc;
//! // u = x on [0, 2] × [0, 1], K = 3: 3 leaves through x = 0 (n = −x̂,
//! // −K∇u·n = 3 per unit length) and enters through x = 2.
//! let mesh = rectangle(4, 2, [0.0, 2.0], [0.0, 1.0]).unwrap();
//! for method in [Method::Fe, Method::Fv, Method::FvMimetic] {
//!     let problem = Diffusion::new(method, Conductivity::Scalar(Arc::new(|_| 3.0)), Arc::new(|_| 0.0))
//!         .with_boundary("xmin", BoundaryKind::Dirichlet(Arc::new(|_| 0.0)))
//!         .with_boundary("xmax", BoundaryKind::Dirichlet(Arc::new(|_| 2.0)));
//!     let solution = problem.solve(&mesh).unwrap();
//!     let out = problem.boundary_outflow(&mesh, &solution).unwrap();
//!     let through = |tag: &str| -> f64 { mesh.tag(tag).unwrap().cells.iter().map(|&f| out[f]).sum() };
//!     assert!((through("xmin") - 3.0).abs() < 1e-12, "{method:?}");
//!     assert!((through("xmax") + 3.0).abs() < 1e-12, "{method:?}");
//!     assert!(through("ymin").abs() < 1e-12 && through("ymax").abs() < 1e-12, "{method:?}");
//! }
//! ```

use super::assemble::CellConductivity;
use super::*;

impl Diffusion {
    /// The flux −K∇u·n leaving the domain through each (n−1)-cell, as the
    /// method's own discrete flux (module docs); zero on interior faces.
    pub fn boundary_outflow(
        &self,
        complex: &Complex,
        solution: &Solution,
    ) -> Result<Vec<f64>, DiffusionError> {
        let n = complex.dim();
        let faces = complex.cell_count(n - 1);
        let top = complex.boundary(n);
        let mut out = vec![0.0; faces];
        match solution.location {
            Location::CellCentred => {
                for (f, row) in top.outer_iterator().enumerate() {
                    if let [(_, &s)] = row.iter().collect::<Vec<_>>()[..] {
                        out[f] = f64::from(s) * solution.flux[f];
                    }
                }
            }
            Location::Hybrid => {
                // Half-face rows follow boundary_csc(n): cell by cell, its
                // faces, each already outward from its cell.
                let mut row = 0;
                for col in complex.boundary_csc(n).outer_iterator() {
                    for (f, _) in col.iter() {
                        if top.outer_view(f).is_some_and(|r| r.nnz() == 1) {
                            out[f] = solution.flux[row];
                        }
                        row += 1;
                    }
                }
            }
            Location::Nodal => self.nodal_outflow(complex, solution, &mut out)?,
        }
        Ok(out)
    }

    /// The flux −K∇u·n through each (n−1)-cell along its orientation (out
    /// of the cell c with ∂ₙ(F, c) = +1), for the methods whose unknowns
    /// make face fluxes: cell-centred and hybrid. `None` for nodal methods,
    /// whose conservative fluxes cross the dual cells' faces, not the
    /// primal (n−1)-cells.
    pub fn face_flux(&self, complex: &Complex, solution: &Solution) -> Option<Vec<f64>> {
        let n = complex.dim();
        match solution.location {
            Location::CellCentred => Some(solution.flux.clone()),
            Location::Hybrid => {
                let mut flux = vec![0.0; complex.cell_count(n - 1)];
                let mut row = 0;
                for col in complex.boundary_csc(n).outer_iterator() {
                    for (f, &s) in col.iter() {
                        // The half-face of the cell the face points out of
                        // (a boundary face's only cell, whatever its sign).
                        let single = complex
                            .boundary(n)
                            .outer_view(f)
                            .is_some_and(|r| r.nnz() == 1);
                        if s > 0 || single {
                            flux[f] = f64::from(s) * solution.flux[row];
                        }
                        row += 1;
                    }
                }
                Some(flux)
            }
            Location::Nodal => None,
        }
    }

    /// −K∇u·n through every (n−1)-cell along its orientation, for every
    /// method: [`Diffusion::face_flux`] where the unknowns make face fluxes;
    /// for nodal methods `outflow` (what [`Diffusion::boundary_outflow`]
    /// returned for this solution) on boundary faces and, on interior faces, |F| times the mean of the
    /// two cells' −K∇u_h·n (a reconstruction: the conservative fluxes of
    /// nodal methods cross the dual cells). `None` for a nodal method on a
    /// surface, whose faces have no normal in the embedding space.
    pub fn oriented_flux(
        &self,
        complex: &Complex,
        solution: &Solution,
        outflow: &[f64],
    ) -> Result<Option<Vec<f64>>, DiffusionError> {
        if let Some(flux) = self.face_flux(complex, solution) {
            return Ok(Some(flux));
        }
        let (n, d) = (complex.dim(), complex.embedding_dim());
        if n != d {
            return Ok(None);
        }
        let gradient = post::reconstruct_gradient(complex, solution);
        let conductivity = self.cell_conductivity(complex)?;
        let normal = complex.normal();
        let measure = complex.measure(n - 1);
        let flux = complex
            .boundary(n)
            .outer_iterator()
            .enumerate()
            .map(|(f, row)| {
                let cells: Vec<(usize, i8)> = row.iter().map(|(c, &s)| (c, s)).collect();
                match cells[..] {
                    [(_, s)] => f64::from(s) * outflow[f],
                    _ => {
                        let density = |c: usize| -> f64 {
                            let k = match &conductivity {
                                CellConductivity::Scalar(l) => metric::isotropic(l[c]),
                                CellConductivity::Full(t) => t[c],
                            };
                            let g = gradient[c];
                            -(0..d)
                                .map(|a| {
                                    (0..d).map(|b| k[a][b] * g[b]).sum::<f64>() * normal[f * d + a]
                                })
                                .sum::<f64>()
                        };
                        let sum: f64 = cells.iter().map(|&(c, _)| density(c)).sum();
                        measure[f] * sum / cells.len().max(1) as f64
                    }
                }
            })
            .collect();
        Ok(Some(flux))
    }

    /// K in every top cell, as the assembly evaluates it (at the
    /// centroid): one scalar a cell when every K is isotropic, else the
    /// tensors.
    pub fn cell_coefficients(&self, complex: &Complex) -> Result<CellCoefficients, DiffusionError> {
        Ok(match self.cell_conductivity(complex)? {
            CellConductivity::Scalar(v) => CellCoefficients::Scalar(v),
            CellConductivity::Full(t) => CellCoefficients::Tensor(t),
        })
    }

    /// ∫f as the method loads it: Σ of the source's load over the unknowns.
    pub fn source_total(&self, complex: &Complex) -> Result<f64, DiffusionError> {
        let n = complex.dim();
        let unknowns = match self.location() {
            Location::Nodal => complex.cell_count(0),
            Location::CellCentred => complex.cell_count(n),
            Location::Hybrid => complex.cell_count(n) + complex.cell_count(n - 1),
        };
        Ok(self.source_load(complex, unknowns)?.iter().sum())
    }

    fn nodal_outflow(
        &self,
        complex: &Complex,
        solution: &Solution,
        out: &mut [f64],
    ) -> Result<(), DiffusionError> {
        for (f, _, q) in self.nodal_outflow_shares(complex, solution)? {
            out[f] += q;
        }
        Ok(())
    }

    /// The residual flux of every boundary vertex of a nodal method, split
    /// among its boundary faces: (face, vertex, share), each face's shares
    /// in the order of its vertices (the outflow of a face is their sum).
    /// The interface fluxes ([`Diffusion::flux_across`]) take the shares of
    /// a vertex's faces on one side.
    pub(super) fn nodal_outflow_shares(
        &self,
        complex: &Complex,
        solution: &Solution,
    ) -> Result<Vec<(usize, usize, f64)>, DiffusionError> {
        let n = complex.dim();
        let d = complex.embedding_dim();
        let vertices = complex.cell_count(0);
        let mut shares = Vec::new();
        // f_v − (Aᵀ q)_v, with A = δ⁰ (so Aᵀ q = ∂₁ q).
        let mut remainder = self.source_load(complex, vertices)?;
        for (v, row) in complex.boundary(1).outer_iterator().enumerate() {
            for (e, &s) in row.iter() {
                remainder[v] -= f64::from(s) * solution.flux[e];
            }
        }
        // Each boundary face's condition (a later one replaces an earlier
        // one, as in the assembly); none is the natural condition, no flux.
        let mut condition: Vec<Option<usize>> = vec![None; complex.cell_count(n - 1)];
        for (f, k) in self.boundary_faces(complex)?.condition {
            condition[f] = Some(k);
        }
        let top = complex.boundary(n);
        let measure = complex.measure(n - 1);
        let point = |v: usize| complex.vertices().point(v);
        // Faces whose flux the data give, with the shares the assembly
        // loads at their vertices (weight |F|/#vertices at each): Neumann
        // −g, Robin α u − g, natural 0. What remains at a vertex crosses
        // its Dirichlet faces.
        let mut dirichlet: Vec<(usize, usize, f64)> = Vec::new(); // (face, cell, weight)
        for (f, row) in top.outer_iterator().enumerate() {
            let [(c, _)] = row.iter().collect::<Vec<_>>()[..] else {
                continue;
            };
            let verts = complex.cell_vertices(n - 1, f);
            let weight = measure[f] / verts.len().max(1) as f64;
            let kind = condition[f].map(|k| &self.boundary[k].kind);
            let share = |v: usize| -> Option<f64> {
                match kind {
                    None => Some(0.0),
                    Some(BoundaryKind::Neumann(g)) => Some(-g(point(v)) * weight),
                    Some(BoundaryKind::Robin { alpha, value }) => {
                        Some(weight * (alpha(point(v)) * solution.values[v] - value(point(v))))
                    }
                    Some(BoundaryKind::Dirichlet(_)) => None,
                }
            };
            if matches!(kind, Some(BoundaryKind::Dirichlet(_))) {
                dirichlet.push((f, c, weight));
                continue;
            }
            for &v in verts {
                let q = share(v).unwrap_or(0.0);
                shares.push((f, v, q));
                remainder[v] -= q;
            }
        }
        // A vertex on several Dirichlet faces shares its remainder among
        // them in proportion to weight × |−K∇u_h·n| on each (a corner
        // between a conducting and a non-conducting Dirichlet face gives
        // its flux to the conducting one), or to the weight alone where no
        // such face carries flux.
        let gradient = post::reconstruct_gradient(complex, solution);
        let conductivity = self.cell_conductivity(complex)?;
        let normal = if n == d { complex.normal() } else { &[] };
        let informed: Vec<f64> = dirichlet
            .iter()
            .map(|&(f, c, weight)| {
                if normal.is_empty() {
                    return 0.0;
                }
                let k = match &conductivity {
                    CellConductivity::Scalar(l) => metric::isotropic(l[c]),
                    CellConductivity::Full(t) => t[c],
                };
                let g = gradient[c];
                let density: f64 = (0..d)
                    .map(|a| (0..d).map(|b| k[a][b] * g[b]).sum::<f64>() * normal[f * d + a])
                    .sum();
                if density.is_finite() {
                    weight * density.abs()
                } else {
                    0.0
                }
            })
            .collect();
        let mut plain_sum = vec![0.0; vertices];
        let mut informed_sum = vec![0.0; vertices];
        for (&(f, _, weight), &w) in dirichlet.iter().zip(&informed) {
            for &v in complex.cell_vertices(n - 1, f) {
                plain_sum[v] += weight;
                informed_sum[v] += w;
            }
        }
        for (&(f, _, weight), &w) in dirichlet.iter().zip(&informed) {
            for &v in complex.cell_vertices(n - 1, f) {
                let share = if informed_sum[v] > 0.0 {
                    w / informed_sum[v]
                } else {
                    weight / plain_sum[v]
                };
                shares.push((f, v, remainder[v] * share));
            }
        }
        Ok(shares)
    }
}

/// The conductivity of every top cell ([`Diffusion::cell_coefficients`]).
#[derive(Clone, Debug, PartialEq)]
pub enum CellCoefficients {
    /// K = λ_c I.
    Scalar(Vec<f64>),
    /// K_c, symmetric (the leading d×d block is used in R^d).
    Tensor(Vec<Tensor>),
}
