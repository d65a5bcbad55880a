//! Face fluxes F_f = ∫_f v·n_f, the upwind selection matrix U, the
//! advection operator ∂ₙᵀ diag(F) U and the inflow data.

use super::{FaceFlux, Peclet, Transport, TransportError};
use crate::operator::{BlockMetric, Canonical};
use crate::physics::{tagged_boundary_faces, BoundaryKind, VectorFn};
use hasse_complex::Complex;
use rayon::prelude::*;
use sprs::{CsMat, TriMat};

/// Face fluxes below this fraction of the largest are a zero normal
/// velocity evaluated with rounding.
const ZERO_FLUX: f64 = 1e-12;

/// v·n over the first d components.
fn normal_velocity(v: &[f64; 3], n: &[f64]) -> f64 {
    n.iter().zip(v).map(|(a, b)| a * b).sum()
}

/// F_f = ∫_f v·n_f on every (n−1)-cell, with n_f the face's unit normal
/// (consistent with ∂ₙ: out of the cells with ∂ₙ(f, c) = +1).
///
/// Quadrature: a point face (n = 1) takes v·n there; an edge (n = 2) three
/// Gauss–Legendre points (exact for v of degree ≤ 5 along it); a polygonal
/// face (n = 3) is fanned into triangles from its centroid over its edges,
/// each with the three-edge-midpoint rule (exact for degree ≤ 2). Higher
/// dimensions use the centroid (exact for linear v).
///
/// ```
/// use hasse_complex::generate::rectangle;
/// use hasse_solver::physics::transport::face_fluxes;
/// use hasse_solver::physics::VectorFn;
/// use std::sync::Arc;
/// // v = (x², 0) on [0, 2]×[0, 1] in 2×1 squares: the middle edge x = 1
/// // carries ∫ 1 dy = 1 along ±x, the right edge 4, the left 0.
/// let mesh = rectangle(2, 1, [0.0, 2.0], [0.0, 1.0]).unwrap();
/// let v: VectorFn = Arc::new(|x: &[f64]| [x[0] * x[0], 0.0, 0.0]);
/// let flux = face_fluxes(&mesh, &v).unwrap();
/// let mut sizes: Vec<f64> = flux.iter().map(|f| f.abs()).filter(|f| *f > 0.0).collect();
/// sizes.sort_by(f64::total_cmp);
/// assert_eq!(sizes, vec![1.0, 4.0]);
/// ```
pub fn face_fluxes(complex: &Complex, velocity: &VectorFn) -> Result<Vec<f64>, TransportError> {
    let n = complex.dim();
    let d = complex.embedding_dim();
    let faces = complex.cell_count(n - 1);
    let normals = complex.normal();
    let centroids = complex.centroid(n - 1);
    let areas = complex.measure(n - 1);
    let by_face = (n == 3).then(|| complex.boundary_csc(2));
    let point = |v: usize| complex.vertices().point(v);
    let flux_of = |f: usize| -> Result<f64, TransportError> {
        let normal = &normals[f * d..(f + 1) * d];
        let centre = &centroids[f * d..(f + 1) * d];
        let mut total = 0.0;
        let mut at = |x: &[f64], weight: f64| -> Result<(), TransportError> {
            let v = velocity(x);
            let value = normal_velocity(&v, normal);
            if !value.is_finite() {
                return Err(TransportError::NonFiniteVelocity { point: x.to_vec() });
            }
            total += weight * value;
            Ok(())
        };
        match (n, &by_face) {
            (1, _) => at(centre, 1.0)?,
            (2, _) => {
                let vs = complex.cell_vertices(1, f);
                let (a, b) = (point(vs[0]), point(vs[1]));
                let s = 0.5 * (0.6f64).sqrt();
                for (t, w) in [
                    (0.5 - s, 5.0 / 18.0),
                    (0.5, 8.0 / 18.0),
                    (0.5 + s, 5.0 / 18.0),
                ] {
                    let x: Vec<f64> = a.iter().zip(b).map(|(p, q)| p + t * (q - p)).collect();
                    at(&x, w * areas[f])?;
                }
            }
            (3, Some(by_face)) => {
                let edges = by_face.outer_view(f).map(|c| c.indices().to_vec());
                for e in edges.unwrap_or_default() {
                    let vs = complex.cell_vertices(1, e);
                    let (a, b) = (point(vs[0]), point(vs[1]));
                    let u: Vec<f64> = (0..d).map(|i| a[i] - centre[i]).collect();
                    let w: Vec<f64> = (0..d).map(|i| b[i] - centre[i]).collect();
                    let cross = [
                        u[1] * w[2] - u[2] * w[1],
                        u[2] * w[0] - u[0] * w[2],
                        u[0] * w[1] - u[1] * w[0],
                    ];
                    let area = 0.5 * cross.iter().map(|c| c * c).sum::<f64>().sqrt();
                    let mid = |p: &[f64], q: &[f64]| -> Vec<f64> {
                        p.iter().zip(q).map(|(x, y)| 0.5 * (x + y)).collect()
                    };
                    at(&mid(a, b), area / 3.0)?;
                    at(&mid(a, centre), area / 3.0)?;
                    at(&mid(b, centre), area / 3.0)?;
                }
            }
            _ => at(centre, areas[f])?,
        }
        Ok(total)
    };
    let mut flux = (0..faces)
        .into_par_iter()
        .map(flux_of)
        .collect::<Result<Vec<f64>, _>>()?;
    clean_rounding(&mut flux);
    Ok(flux)
}

/// Set the fluxes below [`ZERO_FLUX`] of the largest to zero.
fn clean_rounding(flux: &mut [f64]) {
    let largest = flux.iter().fold(0.0f64, |m, f| m.max(f.abs()));
    for f in flux.iter_mut() {
        if f.abs() <= ZERO_FLUX * largest {
            *f = 0.0;
        }
    }
}

/// An inflow face: flow enters `cell` through `face`; `weight` = |s F_f|
/// (positive) and `value` the Dirichlet value there, so the cell gains
/// `weight · value`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct Inflow {
    pub(super) face: usize,
    pub(super) cell: usize,
    pub(super) weight: f64,
    pub(super) value: f64,
}

/// The advection part of a problem on a mesh.
pub(super) struct Advection {
    pub(super) flux: Vec<f64>,
    /// U (faces × cells, CSR).
    pub(super) upwind: CsMat<i8>,
    pub(super) inflow: Vec<Inflow>,
}

impl Transport {
    /// F_f on every face, from the velocity or as given.
    pub(super) fn fluxes(&self, complex: &Complex) -> Result<Vec<f64>, TransportError> {
        match &self.flux {
            FaceFlux::Velocity(v) => face_fluxes(complex, v),
            FaceFlux::Given(values) => {
                let n = complex.dim();
                let expected = complex.cell_count(n - 1);
                if values.len() != expected {
                    return Err(TransportError::FluxSize {
                        expected,
                        found: values.len(),
                    });
                }
                let d = complex.embedding_dim();
                if let Some(f) = values.iter().position(|v| !v.is_finite()) {
                    return Err(TransportError::NonFiniteVelocity {
                        point: complex.centroid(n - 1)[f * d..(f + 1) * d].to_vec(),
                    });
                }
                let mut flux = values.to_vec();
                clean_rounding(&mut flux);
                Ok(flux)
            }
        }
    }

    /// The face fluxes, U and the inflow faces with their Dirichlet values.
    /// Errors: an inflow face without a Dirichlet condition.
    pub(super) fn advection(&self, complex: &Complex) -> Result<Advection, TransportError> {
        let n = complex.dim();
        let d = complex.embedding_dim();
        let flux = self.fluxes(complex)?;
        let top = complex.boundary(n);
        let conditions =
            tagged_boundary_faces(complex, self.boundary.iter().map(|b| b.tag.as_str()))?;
        let condition_of = |f: usize| {
            conditions
                .binary_search_by_key(&f, |c| c.0)
                .ok()
                .map(|k| conditions[k].1)
        };
        let centroids = complex.centroid(n - 1);
        let mut tri = TriMat::new((top.rows(), top.cols()));
        let mut inflow = Vec::new();
        for (f, row) in top.outer_iterator().enumerate() {
            let flow = flux[f];
            if flow == 0.0 {
                continue;
            }
            // The cell the flow leaves: ∂ = +1 for F > 0, −1 for F < 0.
            let leaving = if flow > 0.0 { 1 } else { -1 };
            match row.iter().find(|(_, &s)| s == leaving) {
                Some((c, _)) => tri.add_triplet(f, c, 1i8),
                None => {
                    // Only a boundary face lacks the cell upwind of it.
                    let Some((cell, &s)) = row.iter().next() else {
                        continue;
                    };
                    let x = &centroids[f * d..(f + 1) * d];
                    let k = condition_of(f);
                    let value = match k.map(|k| &self.boundary[k].kind) {
                        Some(BoundaryKind::Dirichlet(g)) => g(x),
                        other => {
                            return Err(TransportError::InflowWithoutDirichlet {
                                face: f,
                                point: x.to_vec(),
                                flux: f64::from(s) * flow,
                                condition: other.map(|kind| {
                                    let tag =
                                        k.map_or(String::new(), |k| self.boundary[k].tag.clone());
                                    let name = match kind {
                                        BoundaryKind::Dirichlet(_) => "Dirichlet",
                                        BoundaryKind::Neumann(_) => "Neumann",
                                        BoundaryKind::Robin { .. } => "Robin",
                                    };
                                    (tag, name)
                                }),
                            })
                        }
                    };
                    if !value.is_finite() {
                        return Err(TransportError::NonFiniteData {
                            what: "a Dirichlet value",
                            point: x.to_vec(),
                        });
                    }
                    inflow.push(Inflow {
                        face: f,
                        cell,
                        weight: (f64::from(s) * flow).abs(),
                        value,
                    });
                }
            }
        }
        Ok(Advection {
            flux,
            upwind: tri.to_csr(),
            inflow,
        })
    }
}

impl Advection {
    /// ∂ₙᵀ diag(F) U as a canonical coupling operator.
    pub(super) fn operator(&self, complex: &Complex) -> Result<Canonical, TransportError> {
        let n = complex.dim();
        Ok(Canonical::coupling(
            complex.boundary(n),
            BlockMetric::diagonal(&self.flux),
            self.upwind.clone(),
        )?)
    }

    /// The inflow's load: Σ |F| g on each cell.
    pub(super) fn inflow_load(&self, cells: usize) -> Vec<f64> {
        let mut load = vec![0.0; cells];
        for i in &self.inflow {
            load[i.cell] += i.weight * i.value;
        }
        load
    }

    /// Σ of the flux leaving each cell (through interior and boundary
    /// faces), the diagonal of the upwind operator.
    pub(super) fn outflow(&self, complex: &Complex) -> Vec<f64> {
        let n = complex.dim();
        let top = complex.boundary(n);
        let mut out = vec![0.0; top.cols()];
        for (f, row) in top.outer_iterator().enumerate() {
            for (c, &s) in row.iter() {
                let leaving = f64::from(s) * self.flux[f];
                if leaving > 0.0 {
                    out[c] += leaving;
                }
            }
        }
        out
    }

    /// Cell Péclet numbers for cell conductivities `k` (None: pure
    /// advection, infinite).
    pub(super) fn peclet(&self, complex: &Complex, k: Option<&[f64]>) -> Peclet {
        let n = complex.dim();
        let by_cell = complex.boundary_csc(n);
        let volume = complex.measure(n);
        let area = complex.measure(n - 1);
        let (mut min, mut max) = (f64::INFINITY, 0.0f64);
        for (c, column) in by_cell.outer_iterator().enumerate() {
            let speed = column
                .iter()
                .map(|(f, _)| {
                    if area[f] > 0.0 {
                        self.flux[f].abs() / area[f]
                    } else {
                        0.0
                    }
                })
                .fold(0.0f64, f64::max);
            let h = volume[c].powf(1.0 / n as f64);
            let pe = match k {
                Some(k) if k[c] > 0.0 => speed * h / k[c],
                _ if speed == 0.0 => 0.0,
                _ => f64::INFINITY,
            };
            min = min.min(pe);
            max = max.max(pe);
        }
        if min > max {
            min = 0.0;
        }
        Peclet { min, max }
    }
}
