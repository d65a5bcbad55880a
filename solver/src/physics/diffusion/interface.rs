//! Fluxes across tagged (n−1)-cells inside the domain, each method's own.
//!
//! Cell-centred and hybrid methods have a flux on every face
//! ([`Diffusion::face_flux`]). Nodal methods (`fe`, `dec`) do not: their
//! conservative fluxes cross the dual cells. Their flux across an interface
//! Γ comes from the same residual that gives their boundary outflow
//! ([`Diffusion::boundary_outflow`]), restricted to one side.
//!
//! In canonical form the operator is a sum over top cells,
//! Aᵀ Ω A = Σ_c Aᵀ Ω_c A, and so is the load, b = Σ_c b_c. For a set G of
//! top cells around a vertex i, the residual of G at i,
//!
//! ```text
//!     R_G(i) = (b_G − Aᵀ Ω_G A u)_i,
//! ```
//!
//! is the flux leaving the cells of G at i (for P1, (f, φ_i)_G − a_G(u, φ_i),
//! the variationally consistent flux of Green's formula; for DEC the flux
//! out of G's part of the dual cell of i). Summed over all i of G it is
//! ∫_G f, because every Ω_c annihilates constants. Around a vertex i of Γ
//! the cells fall into sides: cells joined through faces at i that are not
//! in Γ. What leaves the side G at i leaves through its faces in Γ or
//! through the domain's boundary, so the flux through Γ at i is
//! R_G(i) − S_G(i), S_G(i) being i's shares of the outflow of G's boundary
//! faces (the very shares the outflow is made of). It is split among the
//! Γ faces at i that bound G in proportion to their measures. With these
//! fluxes the balance of every part of the domain closes to the solver's
//! residual: flux out of A through Γ = ∫_A f − outflow of ∂A ∩ ∂Ω.
//!
//! Ω_G is found without opening the metric: Ω is linear in the cells'
//! conductivities, so Ω_G = Ω(K doubled on G) − Ω(K). Vertices whose sides
//! are all one (the ends of an open Γ inside the domain) have no flux
//! through Γ to give: they are left out and listed, an O(h) part of the
//! flux near each end.

use super::assemble::CellConductivity;
use super::*;
use crate::la::disjoint::DisjointSets;
use std::collections::HashMap;

/// The flux through a set of (n−1)-cells ([`Diffusion::flux_across`]).
#[derive(Clone, Debug, PartialEq)]
pub struct FacesFlux {
    /// Per face given: on the domain's boundary the outflow, inside it
    /// −K∇u·n |F| along the face's orientation (out of the cell c with
    /// ∂ₙ(F, c) = +1).
    pub flux: Vec<f64>,
    /// Vertices of the inner faces whose faces do not separate two sides
    /// (the ends of an open interface), sorted: their part of the flux is
    /// not counted.
    pub left_out: Vec<usize>,
}

/// One side of the cells around a vertex of Γ.
struct Side {
    vertex: usize,
    /// The cells of the side and the other cells around the vertex.
    cells: Vec<usize>,
    others: Vec<usize>,
    /// The measure of the Γ faces at the vertex that bound the side.
    bounding: f64,
}

impl Diffusion {
    /// The flux −K∇u·n through each of `faces`, the method's own: the
    /// outflow ([`Diffusion::boundary_outflow`], which `outflow` holds) on
    /// boundary faces, the flux along the orientation inside the domain
    /// (module docs for nodal methods).
    ///
    /// ```
    /// use hasse_complex::generate::rectangle;
    /// use hasse_solver::metric::Method;
    /// use hasse_solver::physics::diffusion::Diffusion;
    /// use hasse_solver::physics::{BoundaryKind, Conductivity};
    /// use std::sync::Arc;
    /// // u = x on [0, 2] × [0, 1], K = 3: a flux of −3 along +x through
    /// // the unit-long line x = 1 (its edges point up, out of the cells on
    /// // their left: along −x).
    /// let mut mesh = rectangle(4, 2, [0.0, 2.0], [0.0, 1.0]).unwrap();
    /// let line: Vec<usize> = (0..mesh.cell_count(1))
    ///     .filter(|&e| mesh.cell_vertices(1, e).iter().all(|&v| (mesh.vertices().point(v)[0] - 1.0).abs() < 1e-12))
    ///     .collect();
    /// let problem = Diffusion::new(Method::Fe, Conductivity::Scalar(Arc::new(|_| 3.0)), Arc::new(|_| 0.0))
    ///     .with_boundary("xmin", BoundaryKind::Dirichlet(Arc::new(|_| 0.0)))
    ///     .with_boundary("xmax", BoundaryKind::Dirichlet(Arc::new(|_| 2.0)));
    /// let solution = problem.solve(&mesh).unwrap();
    /// let outflow = problem.boundary_outflow(&mesh, &solution).unwrap();
    /// let across = problem.flux_across(&mesh, &solution, &outflow, &line).unwrap();
    /// let total: f64 = across.flux.iter().sum();
    /// assert!((total.abs() - 3.0).abs() < 1e-12 && across.left_out.is_empty());
    /// ```
    pub fn flux_across(
        &self,
        complex: &Complex,
        solution: &Solution,
        outflow: &[f64],
        faces: &[usize],
    ) -> Result<FacesFlux, DiffusionError> {
        let top = complex.boundary(complex.dim());
        let inner = |f: usize| top.outer_view(f).is_some_and(|r| r.nnz() == 2);
        let (along, left_out) = match self.face_flux(complex, solution) {
            Some(along) => (along, Vec::new()),
            None => self.nodal_flux_across(complex, solution, faces)?,
        };
        let flux = faces
            .iter()
            .map(|&f| if inner(f) { along[f] } else { outflow[f] })
            .collect();
        Ok(FacesFlux { flux, left_out })
    }

    /// Nodal fluxes along the orientation of the inner faces of `faces`
    /// (zero elsewhere), from the residual of each side, and the vertices
    /// left out.
    fn nodal_flux_across(
        &self,
        complex: &Complex,
        solution: &Solution,
        faces: &[usize],
    ) -> Result<(Vec<f64>, Vec<usize>), DiffusionError> {
        let n = complex.dim();
        let mut along = vec![0.0; complex.cell_count(n - 1)];
        let sides = interface_sides(complex, faces);
        if !sides.sides.is_empty() {
            // Each side's flux through Γ at its vertex, D = R_G(i) − S_G(i),
            // shared among the Γ faces at the vertex that bound the side.
            let escaping = self.side_residuals(complex, solution, &sides.sides)?;
            let measure = complex.measure(n - 1);
            for &(f, side) in &sides.contributions {
                let bounding = sides.sides[side].bounding;
                if bounding > 0.0 {
                    along[f] += escaping[side] * measure[f] / bounding;
                }
            }
        }
        Ok((along, sides.ends))
    }

    /// D = R_G(i) − S_G(i) of every side (module docs), computed in passes:
    /// one pass takes sides whose cell sets agree on every cell they share,
    /// so that one Ω_G with G their union gives each its own R_G(i).
    fn side_residuals(
        &self,
        complex: &Complex,
        solution: &Solution,
        sides: &[Side],
    ) -> Result<Vec<f64>, DiffusionError> {
        let n = complex.dim();
        let cells = complex.cell_count(n);
        // Passes: each a cell → (in G?) constraint map and its sides.
        let mut passes: Vec<(HashMap<usize, bool>, Vec<usize>)> = Vec::new();
        for (s, side) in sides.iter().enumerate() {
            let fits = |constraint: &HashMap<usize, bool>| {
                side.cells.iter().all(|c| constraint.get(c) != Some(&false))
                    && side.others.iter().all(|c| constraint.get(c) != Some(&true))
            };
            let pass = match passes.iter().position(|(constraint, _)| fits(constraint)) {
                Some(p) => p,
                None => {
                    passes.push((HashMap::new(), Vec::new()));
                    passes.len() - 1
                }
            };
            let (constraint, members) = &mut passes[pass];
            constraint.extend(side.cells.iter().map(|&c| (c, true)));
            constraint.extend(side.others.iter().map(|&c| (c, false)));
            members.push(s);
        }
        // S_G(i): the outflow shares of i's boundary faces, by their cell.
        let top = complex.boundary(n);
        let mut boundary_shares: HashMap<usize, Vec<(usize, f64)>> = HashMap::new();
        let wanted: std::collections::HashSet<usize> = sides.iter().map(|s| s.vertex).collect();
        for (f, v, q) in self.nodal_outflow_shares(complex, solution)? {
            if wanted.contains(&v) {
                if let Some(c) = top
                    .outer_view(f)
                    .and_then(|r| r.iter().next().map(|(c, _)| c))
                {
                    boundary_shares.entry(v).or_default().push((c, q));
                }
            }
        }
        let conductivity = self.cell_conductivity(complex)?;
        let mut gradient = vec![0.0; complex.cell_count(1)];
        for (e, row) in complex.coboundary(0).outer_iterator().enumerate() {
            gradient[e] = row
                .iter()
                .map(|(v, &s)| f64::from(s) * solution.values[v])
                .sum();
        }
        let base = self.nodal_metric(complex, &conductivity)?.apply(&gradient);
        let sources = self.cell_sources(complex)?;
        let vertex_edges = complex.boundary(1);
        let mut escaping = vec![0.0; sides.len()];
        for (constraint, members) in passes {
            let mut in_g = vec![false; cells];
            for (c, inside) in constraint {
                in_g[c] = inside;
            }
            let doubled = match &conductivity {
                CellConductivity::Scalar(v) => CellConductivity::Scalar(
                    v.iter()
                        .zip(&in_g)
                        .map(|(&k, &g)| if g { 2.0 * k } else { k })
                        .collect(),
                ),
                CellConductivity::Full(t) => CellConductivity::Full(
                    t.iter()
                        .zip(&in_g)
                        .map(|(k, &g)| {
                            if g {
                                k.map(|row| row.map(|x| 2.0 * x))
                            } else {
                                *k
                            }
                        })
                        .collect(),
                ),
            };
            let flux = self.nodal_metric(complex, &doubled)?.apply(&gradient);
            let in_side = |c: usize, x: &[f64]| if in_g[c] { sources[c](x) } else { 0.0 };
            let load = match self.method {
                Method::Dec(kind) => dec::load_in_cells(complex, kind, &in_side),
                _ => fe::load_in_cells(complex, &in_side),
            }
            .map_err(assemble::source_error)?;
            for s in members {
                let i = sides[s].vertex;
                let mut residual = load[i];
                if let Some(row) = vertex_edges.outer_view(i) {
                    for (e, &sign) in row.iter() {
                        residual -= f64::from(sign) * (flux[e] - base[e]);
                    }
                }
                let shares: f64 = boundary_shares.get(&i).map_or(0.0, |list| {
                    list.iter().filter(|(c, _)| in_g[*c]).map(|(_, q)| q).sum()
                });
                escaping[s] = residual - shares;
            }
        }
        Ok(escaping)
    }

    /// Ω of a nodal method for the given conductivities.
    fn nodal_metric(
        &self,
        complex: &Complex,
        conductivity: &CellConductivity,
    ) -> Result<BlockMetric, DiffusionError> {
        Ok(match self.method {
            Method::Dec(kind) => dec::hodge_metric(complex, kind, conductivity.cells())?,
            _ => fe::stiffness_metric(complex, conductivity.cells())?,
        })
    }
}

/// The sides of the cells around the vertices of an interface's inner
/// faces.
struct InterfaceSides {
    sides: Vec<Side>,
    /// (face, side): the inner face's share at the side's vertex comes
    /// from the side of its cell with ∂ₙ(F, c) = +1.
    contributions: Vec<(usize, usize)>,
    /// Vertices around which the faces separate nothing.
    ends: Vec<usize>,
}

/// Around each vertex of the inner faces of `faces`, the cells joined
/// through faces at the vertex that are not in `faces` (a union–find over
/// the vertex's cells).
fn interface_sides(complex: &Complex, faces: &[usize]) -> InterfaceSides {
    let n = complex.dim();
    let top = complex.boundary(n);
    let measure = complex.measure(n - 1);
    let mut in_gamma = vec![false; complex.cell_count(n - 1)];
    for &f in faces {
        if f < in_gamma.len() {
            in_gamma[f] = true;
        }
    }
    let cells_of = |f: usize| -> Vec<(usize, i8)> {
        top.outer_view(f)
            .map(|r| r.iter().map(|(c, &s)| (c, s)).collect())
            .unwrap_or_default()
    };
    let mut by_vertex: std::collections::BTreeMap<usize, Vec<usize>> = Default::default();
    for &f in faces {
        if cells_of(f).len() == 2 {
            for &v in complex.cell_vertices(n - 1, f) {
                by_vertex.entry(v).or_default().push(f);
            }
        }
    }
    let cell_star = complex.vertex_star(n);
    let face_star = complex.vertex_star(n - 1);
    let mut result = InterfaceSides {
        sides: Vec::new(),
        contributions: Vec::new(),
        ends: Vec::new(),
    };
    for (v, gamma_faces) in by_vertex {
        let around: Vec<usize> = cell_star
            .outer_view(v)
            .map(|r| r.indices().to_vec())
            .unwrap_or_default();
        let local = |c: usize| around.binary_search(&c).ok();
        let mut sides = DisjointSets::new(around.len());
        let at_vertex: Vec<usize> = face_star
            .outer_view(v)
            .map(|r| r.indices().to_vec())
            .unwrap_or_default();
        for f in at_vertex {
            if in_gamma[f] {
                continue;
            }
            if let [(a, _), (b, _)] = cells_of(f)[..] {
                if let (Some(a), Some(b)) = (local(a), local(b)) {
                    sides.join(a, b);
                }
            }
        }
        // The Γ faces at this vertex with the roots of their two cells'
        // sides (+1 cell first); a face with both cells on one side
        // separates nothing here.
        let mut split = Vec::new();
        for f in gamma_faces {
            let cells = cells_of(f);
            let plus = cells.iter().find(|&&(_, s)| s > 0).map(|&(c, _)| c);
            let minus = cells.iter().find(|&&(_, s)| s < 0).map(|&(c, _)| c);
            let (Some(plus), Some(minus)) = (plus.and_then(local), minus.and_then(local)) else {
                continue;
            };
            let (rp, rm) = (sides.root(plus), sides.root(minus));
            if rp == rm {
                if result.ends.last() != Some(&v) {
                    result.ends.push(v);
                }
            } else {
                split.push((f, rp, rm));
            }
        }
        let roots: Vec<usize> = (0..around.len()).map(|l| sides.root(l)).collect();
        let mut side_of_root: HashMap<usize, usize> = HashMap::new();
        for &(f, rp, _) in &split {
            let side = *side_of_root.entry(rp).or_insert_with(|| {
                let (cells, others): (Vec<usize>, Vec<usize>) = around
                    .iter()
                    .partition(|&&c| local(c).is_some_and(|l| roots[l] == rp));
                let bounding = split
                    .iter()
                    .filter(|&&(_, a, b)| a == rp || b == rp)
                    .map(|&(g, _, _)| measure[g])
                    .sum();
                result.sides.push(Side {
                    vertex: v,
                    cells,
                    others,
                    bounding,
                });
                result.sides.len() - 1
            });
            result.contributions.push((f, side));
        }
    }
    result
}
