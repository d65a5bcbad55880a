//! Assembly of a diffusion problem: the metric of its method, the boundary
//! rows and ghosts, the load, and the data part alone for new data on the
//! same operator.

use super::*;

/// The assembled system of a diffusion problem (see [`Diffusion::assemble`]).
#[derive(Clone, Debug)]
pub struct Assembled {
    /// Where the unknowns live.
    pub location: Location,
    /// The canonical operator, with boundary and ghost rows.
    pub canonical: Canonical,
    /// M = Aᵀ Ω A over all unknowns (full symmetric storage for symmetric Ω).
    pub matrix: SparseColMat<usize, f64>,
    /// Sources, Neumann data and lifted Dirichlet/Robin ghost values.
    pub rhs: Vec<f64>,
    /// Unknowns held at a Dirichlet value (nodal and hybrid methods).
    pub fixed: Vec<Option<f64>>,
    /// No Dirichlet or Robin boundary: M is singular (constants).
    pub pure_neumann: bool,
    /// Rows of A before the ghost rows.
    pub flux_rows: usize,
    /// Ghost values w on the rows of A (b contains Aᵀ Ω w).
    pub ghost_values: Vec<f64>,
    /// The data's flux on cell-centred Neumann faces.
    pub neumann_flux: Vec<f64>,
    /// Cell points of [`Method::Fv`] when they are not the centroids.
    pub cell_points: Option<Vec<f64>>,
    /// Seconds the assembly took.
    pub assembly_seconds: f64,
    /// What [`Diffusion::data`] needs to redo only the data part.
    layout: DataLayout,
}

/// The parts of an assembly that the data (source, boundary values) do
/// not change.
#[derive(Clone, Debug)]
pub(super) struct DataLayout {
    faces: Faces,
    /// Ω's diagonal on each conditioned face's row, in the order of
    /// `faces.condition` (cell-centred methods).
    cell_diagonal: Vec<Option<f64>>,
}

/// The boundary's contribution to an assembly.
pub(super) struct BoundaryData {
    fixed: Vec<Option<f64>>,
    /// Ghost rows: (unknown, weight, ghost value) appended to A and Ω.
    ghosts: Vec<(usize, f64, f64)>,
    /// Cell-centred boundary faces whose own row changes weight: (row,
    /// weight), by row.
    face_weight: Vec<(usize, f64)>,
    /// Ghost value of every flux row (non-zero on Dirichlet and Robin faces).
    face_value: Vec<f64>,
    /// Cell-centred Neumann faces carry no row weight; their flux (along
    /// the face's orientation) is the data's, −s g |F|.
    neumann_flux: Vec<f64>,
}

#[derive(Clone, Debug)]
pub(super) struct Faces {
    /// (face, condition index) of every conditioned boundary (n−1)-cell,
    /// by face.
    pub(super) condition: Vec<(usize, usize)>,
}

/// A conductivity evaluated at the cells, owned.
pub(super) enum CellConductivity {
    Scalar(Vec<f64>),
    Full(Vec<Tensor>),
}

impl CellConductivity {
    pub(super) fn cells(&self) -> CellTensors<'_> {
        match self {
            Self::Scalar(values) => CellTensors::scalar(values),
            Self::Full(tensors) => CellTensors::full(tensors),
        }
    }
}

/// Ω's diagonal entry (summed over its 1×1 blocks) on each of the sorted
/// `rows`, or `None` where a row has none.
pub(super) fn diagonal_on(metric: &BlockMetric, rows: &[usize]) -> Vec<Option<f64>> {
    if let Some(weights) = metric.diagonal_weights() {
        return rows.iter().map(|&r| weights.get(r).copied()).collect();
    }
    let mut diag = vec![None; rows.len()];
    for b in 0..metric.block_count() {
        let (r, s, w) = metric.block(b);
        if let ([r], [s]) = (r, s) {
            if r == s {
                if let Ok(k) = rows.binary_search(r) {
                    diag[k] = Some(diag[k].unwrap_or(0.0) + w[0]);
                }
            }
        }
    }
    diag
}

/// Set the diagonal weight of each listed row (sorted, distinct) of Ω: the
/// row's first 1×1 block takes the weight and its other 1×1 blocks zero.
pub(super) fn replace_row_weights(metric: &mut BlockMetric, rows: &[(usize, f64)]) {
    if metric.diagonal_weights().is_some() {
        // Block r is row r's only block.
        for &(r, weight) in rows {
            if r < metric.block_count() {
                metric.block_values_mut(r)[0] = weight;
            }
        }
        return;
    }
    let mut replaced = vec![false; rows.len()];
    for b in 0..metric.block_count() {
        let (r, s, _) = metric.block(b);
        if let ([r], [s]) = (r, s) {
            if r == s {
                if let Ok(k) = rows.binary_search_by_key(r, |&(row, _)| row) {
                    let first = !replaced[k];
                    replaced[k] = true;
                    metric.block_values_mut(b)[0] = if first { rows[k].1 } else { 0.0 };
                }
            }
        }
    }
}

/// A load whose every entry is finite (finite values can still overflow
/// when summed).
pub(super) fn finite_load(rhs: Vec<f64>) -> Result<Vec<f64>, DiffusionError> {
    if let Some(&value) = rhs.iter().find(|v| !v.is_finite()) {
        return Err(DiffusionError::NonFinite {
            datum: Datum::Source,
            point: None,
            value,
        });
    }
    Ok(rhs)
}

pub(super) fn evaluate(f: &ScalarFn, x: &[f64], datum: Datum) -> Result<f64, DiffusionError> {
    let value = f(x);
    if value.is_finite() {
        Ok(value)
    } else {
        Err(DiffusionError::NonFinite {
            datum,
            point: Some(x.to_vec()),
            value,
        })
    }
}

/// A metric's error, with a source that is not finite at a point named as
/// the problem's source.
pub(super) fn source_error(error: MetricError) -> DiffusionError {
    match error {
        MetricError::NonFiniteSource { point, value, .. } => DiffusionError::NonFinite {
            datum: Datum::Source,
            point: Some(point),
            value,
        },
        other => other.into(),
    }
}

/// The datum of the value of boundary condition `k` (its kind's name).
pub(super) fn boundary_value(bc: &BoundaryCondition, k: usize) -> Datum {
    let kind = match bc.kind {
        BoundaryKind::Dirichlet(_) => "Dirichlet",
        BoundaryKind::Neumann(_) => "Neumann",
        BoundaryKind::Robin { .. } => "Robin",
    };
    Datum::BoundaryValue { condition: k, kind }
}

/// α of Robin condition `k` at a point, which must be positive.
pub(super) fn robin_alpha(
    bc: &BoundaryCondition,
    k: usize,
    face: usize,
    alpha: &ScalarFn,
    x: &[f64],
) -> Result<f64, DiffusionError> {
    let a = evaluate(alpha, x, Datum::RobinAlpha { condition: k })?;
    if a <= 0.0 {
        return Err(DiffusionError::RobinAlpha {
            condition: k,
            tag: bc.tag.clone(),
            face,
            point: x.to_vec(),
            alpha: a,
        });
    }
    Ok(a)
}

/// A boundary condition at one unknown of a nodal or hybrid method, with
/// `weight` the part of the face it stands for: Dirichlet fixes it, Neumann
/// adds ∫g, Robin adds a ghost row of weight α·weight and value g/α.
#[allow(clippy::too_many_arguments)]
pub(super) fn apply_at_unknown(
    bc: &BoundaryCondition,
    k: usize,
    face: usize,
    unknown: usize,
    x: &[f64],
    weight: f64,
    fixed: &mut [Option<f64>],
    rhs: &mut [f64],
    ghosts: &mut Vec<(usize, f64, f64)>,
) -> Result<(), DiffusionError> {
    let datum = boundary_value(bc, k);
    match &bc.kind {
        BoundaryKind::Dirichlet(g) => fixed[unknown] = Some(evaluate(g, x, datum)?),
        BoundaryKind::Neumann(g) => rhs[unknown] += evaluate(g, x, datum)? * weight,
        BoundaryKind::Robin { alpha, value } => {
            let a = robin_alpha(bc, k, face, alpha, x)?;
            ghosts.push((unknown, a * weight, evaluate(value, x, datum)? / a));
        }
    }
    Ok(())
}

impl Diffusion {
    /// The conductivity at every cell centroid: scalars stay scalars (8
    /// bytes a cell instead of a 72-byte tensor).
    pub(super) fn cell_conductivity(
        &self,
        complex: &Complex,
    ) -> Result<CellConductivity, DiffusionError> {
        let n = complex.dim();
        let d = complex.embedding_dim();
        let centroids = complex.centroid(n);
        let at = |c: usize| &centroids[c * d..(c + 1) * d];
        let cells = 0..complex.cell_count(n);
        let conductivity = match &self.conductivity {
            Conductivity::Scalar(f) => {
                CellConductivity::Scalar(cells.into_par_iter().map(|c| f(at(c))).collect())
            }
            Conductivity::Tensor(f) => {
                CellConductivity::Full(cells.into_par_iter().map(|c| f(at(c))).collect())
            }
            Conductivity::Regional(regional) => regional_conductivity(regional, complex)?,
        };
        Ok(conductivity)
    }

    /// `tensors` checked once for the whole assembly (the metrics then
    /// skip their own check), a bad cell reported at its centroid.
    pub(super) fn checked_conductivity<'a>(
        &self,
        complex: &Complex,
        tensors: CellTensors<'a>,
    ) -> Result<CellTensors<'a>, DiffusionError> {
        let (n, d) = (complex.dim(), complex.embedding_dim());
        tensors
            .checked(complex.cell_count(n), d)
            .map_err(|e| match e {
                MetricError::NotPositive { cell, .. } | MetricError::NonFinite { cell } => {
                    DiffusionError::Coefficient {
                        cell,
                        point: complex.centroid_of(n, cell).to_vec(),
                        source: e,
                    }
                }
                other => other.into(),
            })
    }

    pub(super) fn boundary_faces(&self, complex: &Complex) -> Result<Faces, DiffusionError> {
        let condition =
            tagged_boundary_faces(complex, self.boundary.iter().map(|b| b.tag.as_str()))?;
        Ok(Faces { condition })
    }

    /// Assemble the system on `complex` without solving it: the operator
    /// M = Aᵀ Ω A (boundary rows and ghosts included), the right-hand side
    /// and the unknowns held fixed by Dirichlet conditions. [`Diffusion::solve`]
    /// is this followed by [`solve_with_fixed`]; transient problems reuse M
    /// as their stiffness.
    ///
    /// ```
    /// use hasse_complex::generate::rectangle;
    /// use hasse_solver::physics::diffusion::Diffusion;
    /// use hasse_solver::physics::BoundaryKind;
    /// use hasse_solver::physics::Conductivity;
    /// use hasse_solver::metric::Method;
    /// use std::sync::Arc;
    /// let mesh = rectangle(2, 2, [0.0, 1.0], [0.0, 1.0]).unwrap();
    /// let problem = Diffusion::new(Method::Fe, Conductivity::Scalar(Arc::new(|_| 1.0)), Arc::new(|_| 1.0))
    ///     .with_boundary("boundary", BoundaryKind::Dirichlet(Arc::new(|_| 0.0)));
    /// let system = problem.assemble(&mesh).unwrap();
    /// // 3×3 vertices, only the centre is free.
    /// assert_eq!(system.fixed.iter().filter(|g| g.is_none()).count(), 1);
    /// assert_eq!(system.matrix.nrows(), 9);
    /// ```
    pub fn assemble(&self, complex: &Complex) -> Result<Assembled, DiffusionError> {
        let started = Instant::now();
        let n = complex.dim();
        if self.location() == Location::Nodal && n >= 2 {
            // A nodal assembly needs ∂ₙ by cells (for the centroids and the
            // elements' edges), the vertex star (for the pattern) and δ⁰
            // (its A). Each is built when first asked for, mostly serially
            // (two transposes, a copy and sprs's check) and bound by page
            // faults: side by side they took 0.13-0.15 s on the 2D 1000²
            // grid, one after the other about 0.17 s.
            rayon::join(
                || complex.boundary_csc(n),
                || {
                    rayon::join(
                        || complex.shared_vertex_star(n),
                        || Arc::clone(complex.coboundary(0)),
                    )
                },
            );
        }
        let conductivity = self.cell_conductivity(complex)?;
        let tensors = self.checked_conductivity(complex, conductivity.cells())?;
        let faces = self.boundary_faces(complex)?;
        let location = self.location();
        let cells = complex.cell_count(n);
        let face_count = complex.cell_count(n - 1);
        let cell_points = self.cell_points(complex)?;

        // Nodal FE finds each cell's element once for Ω and the load.
        let mut fe_load = None;
        let (incidence, metric, unknowns) = match self.method {
            // A source per region is loaded apart ([`Self::source_load`]).
            Method::Fe if self.source_by_region.is_some() => (
                Arc::clone(complex.coboundary(0)),
                fe::stiffness_metric(complex, tensors)?,
                complex.cell_count(0),
            ),
            Method::Fe => {
                let (metric, load) =
                    fe::stiffness_and_load(complex, tensors, &|x| (self.source)(x))
                        .map_err(source_error)?;
                fe_load = Some(load);
                (
                    Arc::clone(complex.coboundary(0)),
                    metric,
                    complex.cell_count(0),
                )
            }
            Method::Dec(kind) => (
                Arc::clone(complex.coboundary(0)),
                dec::hodge_metric(complex, kind, tensors)?,
                complex.cell_count(0),
            ),
            Method::Fv => (
                Arc::clone(complex.boundary(n)),
                match &cell_points {
                    None => fv::two_point(complex, tensors)?,
                    Some(points) => fv::two_point_at(complex, tensors, points)?,
                },
                cells,
            ),
            Method::Fd => (
                Arc::clone(complex.boundary(n)),
                fd::five_point(complex, tensors)?,
                cells,
            ),
            Method::FvMimetic => {
                let (a, omega, layout) = fv::mimetic_hybrid(complex, tensors)?;
                (Arc::new(a), omega, layout.cells + layout.faces)
            }
        };
        let flux_rows = incidence.rows();
        if self.factorization != Factorization::Lu && !metric.is_symmetric(1e-12) {
            return Err(DiffusionError::NotSymmetric {
                method: self.method.name(),
                factorization: self.factorization,
            });
        }

        let top = complex.boundary(n);
        let cell_diagonal = match location {
            Location::CellCentred => {
                let rows: Vec<usize> = faces.condition.iter().map(|&(f, _)| f).collect();
                diagonal_on(&metric, &rows)
            }
            _ => Vec::new(),
        };
        let layout = DataLayout {
            faces,
            cell_diagonal,
        };
        let mut rhs = match fe_load {
            Some(load) => finite_load(load)?,
            None => self.source_load(complex, unknowns)?,
        };
        let BoundaryData {
            fixed,
            ghosts,
            mut face_weight,
            face_value,
            neumann_flux,
        } = self.boundary_data(
            complex,
            location,
            &layout,
            &cell_points,
            flux_rows,
            &mut rhs,
        )?;
        let faces = &layout.faces;
        let indptr = top.indptr();
        let on_boundary = |f: usize| indptr.outer_inds_sz(f).len() == 1;
        let conditioned = |f: usize| faces.condition.binary_search_by_key(&f, |c| c.0).is_ok();
        if location == Location::CellCentred {
            // Boundary faces without a condition are homogeneous Neumann.
            let untagged: Vec<(usize, f64)> = (0..face_count)
                .filter(|&f| on_boundary(f) && !conditioned(f))
                .map(|f| (f, 0.0))
                .collect();
            if !untagged.is_empty() {
                face_weight.extend(untagged);
                face_weight.sort_by_key(|&(f, _)| f);
            }
        }

        // A and Ω with the boundary changes and the ghost rows.
        let mut metric_final = metric;
        replace_row_weights(&mut metric_final, &face_weight);
        metric_final.add_rows(ghosts.len());
        let mut ghost_values = face_value;
        let incidence = if ghosts.is_empty() {
            incidence
        } else {
            let mut tri = TriMat::new((flux_rows + ghosts.len(), unknowns));
            for (v, (i, j)) in incidence.iter() {
                tri.add_triplet(i, j, *v);
            }
            for (k, &(u, weight, value)) in ghosts.iter().enumerate() {
                tri.add_triplet(flux_rows + k, u, 1i8);
                metric_final.push_block(&[flux_rows + k], &[flux_rows + k], &[weight]);
                ghost_values.push(value);
            }
            Arc::new(tri.to_csr())
        };
        // The cell-centred methods' A is ∂ₙ itself, which the complex also
        // keeps by columns; a nodal element metric's blocks are the top
        // cells, whose vertex lists the complex keeps.
        let mut canonical = if ghosts.is_empty() && matches!(self.method, Method::Fv | Method::Fd) {
            Canonical::with_columns(incidence, Arc::clone(complex.boundary_csc(n)), metric_final)?
        } else if location == Location::Nodal {
            Canonical::with_cell_blocks(incidence, metric_final, complex)?
        } else {
            Canonical::new(incidence, metric_final)?
        };
        // b += Aᵀ Ω w for ghost values w (Dirichlet faces, Robin ghosts).
        if ghost_values.iter().any(|&v| v != 0.0) {
            let lifted = canonical.sum_transpose(&canonical.metric().apply(&ghost_values));
            for (b, l) in rhs.iter_mut().zip(lifted) {
                *b += l;
            }
        }
        let matrix = canonical.assemble_owned();
        let pure_neumann = fixed.iter().all(Option::is_none)
            && ghosts.is_empty()
            && (location != Location::CellCentred
                || (0..face_count).filter(|&f| on_boundary(f)).all(|f| {
                    face_weight
                        .binary_search_by_key(&f, |w| w.0)
                        .is_ok_and(|k| face_weight[k].1 == 0.0)
                }));
        let assembly_seconds = started.elapsed().as_secs_f64();
        Ok(Assembled {
            location,
            canonical,
            matrix,
            rhs,
            fixed,
            pure_neumann,
            flux_rows,
            ghost_values,
            neumann_flux,
            cell_points,
            assembly_seconds,
            layout,
        })
    }

    /// The checks of the data that an assembly makes before it builds any
    /// matrix: the conductivity at every cell (finite, symmetric positive
    /// definite) and the source wherever this method's load evaluates it
    /// (centroids, vertices or quadrature points). The errors are those
    /// [`Diffusion::assemble`] would give, found without its cost, so that
    /// bad data can be refused before solving.
    ///
    /// ```
    /// use hasse_complex::generate::rectangle;
    /// use hasse_solver::metric::Method;
    /// use hasse_solver::physics::diffusion::{Diffusion, DiffusionError};
    /// use hasse_solver::physics::{Conductivity, Datum};
    /// use std::sync::Arc;
    /// let mesh = rectangle(4, 4, [0.0, 1.0], [0.0, 1.0]).unwrap();
    /// let problem = Diffusion::new(Method::Fv, Conductivity::Scalar(Arc::new(|_| 1.0)), Arc::new(|x| x[0].ln()));
    /// assert!(problem.check_data(&mesh).is_ok()); // x > 0 at every centroid
    /// let problem = Diffusion::new(Method::Fv, Conductivity::Scalar(Arc::new(|_| 1.0)), Arc::new(|x| (x[0] - 0.5).ln()));
    /// let error = problem.check_data(&mesh).unwrap_err();
    /// assert!(matches!(error, DiffusionError::NonFinite { datum: Datum::Source, .. }));
    /// ```
    pub fn check_data(&self, complex: &Complex) -> Result<(), DiffusionError> {
        let conductivity = self.cell_conductivity(complex)?;
        self.checked_conductivity(complex, conductivity.cells())?;
        let n = complex.dim();
        let unknowns = match self.location() {
            Location::Nodal => complex.cell_count(0),
            Location::CellCentred => complex.cell_count(n),
            Location::Hybrid => complex.cell_count(n) + complex.cell_count(n - 1),
        };
        self.source_load(complex, unknowns).map(|_| ())
    }

    /// The source's load on the unknowns.
    pub(super) fn source_load(
        &self,
        complex: &Complex,
        unknowns: usize,
    ) -> Result<Vec<f64>, DiffusionError> {
        let n = complex.dim();
        let d = complex.embedding_dim();
        let cells = complex.cell_count(n);
        let mut rhs = crate::la::parallel::zeroed(unknowns);
        let sources = self.cell_sources(complex)?;
        let in_cell = |c: usize, x: &[f64]| sources[c](x);
        match (self.method, &self.source_by_region) {
            (Method::Fe, None) => {
                rhs = fe::load(complex, &|x| (self.source)(x)).map_err(source_error)?
            }
            (Method::Fe, Some(_)) => {
                rhs = fe::load_in_cells(complex, &in_cell).map_err(source_error)?
            }
            (Method::Dec(kind), None) => {
                rhs = dec::load(complex, kind, &|x| (self.source)(x)).map_err(source_error)?
            }
            (Method::Dec(kind), Some(_)) => {
                rhs = dec::load_in_cells(complex, kind, &in_cell).map_err(source_error)?
            }
            _ => {
                let volume = complex.measure(n);
                let centre = complex.centroid(n);
                let at = |c: usize| &centre[c * d..(c + 1) * d];
                let values: Vec<f64> = (0..cells)
                    .into_par_iter()
                    .map(|c| sources[c](at(c)))
                    .collect();
                // The first bad cell in cell order, whatever the threads did.
                for (c, &v) in values.iter().enumerate() {
                    let v = if v.is_finite() {
                        v
                    } else {
                        evaluate(sources[c], at(c), Datum::Source)?
                    };
                    rhs[c] += v * volume[c];
                }
            }
        }
        finite_load(rhs)
    }

    /// Boundary values and data on the faces of `layout`: Dirichlet values
    /// of fixed unknowns, ghost rows, and the Neumann and Robin data added
    /// to `rhs`.
    pub(super) fn boundary_data(
        &self,
        complex: &Complex,
        location: Location,
        layout: &DataLayout,
        cell_points: &Option<Vec<f64>>,
        flux_rows: usize,
        rhs: &mut [f64],
    ) -> Result<BoundaryData, DiffusionError> {
        let n = complex.dim();
        let d = complex.embedding_dim();
        let cells = complex.cell_count(n);
        let unknowns = rhs.len();
        let (faces, cell_diagonal) = (&layout.faces, &layout.cell_diagonal);
        // Only the conditioned faces' geometry, by slot: computing that of
        // every face would cost a nodal problem, which needs nothing else
        // of it, a pass over all (n−1)-cells.
        let conditioned: Vec<usize> = faces.condition.iter().map(|&(f, _)| f).collect();
        let (face_area, face_centre) = complex
            .geometry_of(n - 1, &conditioned)
            .map_err(MetricError::from)?;
        let x_face = |slot: usize| &face_centre[slot * d..(slot + 1) * d];
        let top = complex.boundary(n);
        let mut fixed: Vec<Option<f64>> = vec![None; unknowns];
        let mut ghosts: Vec<(usize, f64, f64)> = Vec::new();
        let mut face_weight: Vec<(usize, f64)> = Vec::new();
        let mut face_value = vec![0.0; flux_rows];
        let mut neumann_flux = vec![0.0; flux_rows];
        for (slot, &(f, k)) in faces.condition.iter().enumerate() {
            let bc = &self.boundary[k];
            let area = face_area[slot];
            let xf = x_face(slot);
            match location {
                Location::Nodal => {
                    let verts = complex.cell_vertices(n - 1, f);
                    let share = area / verts.len() as f64;
                    for &v in verts {
                        let xv = complex.vertices().point(v);
                        apply_at_unknown(bc, k, f, v, xv, share, &mut fixed, rhs, &mut ghosts)?;
                    }
                }
                Location::Hybrid => {
                    apply_at_unknown(bc, k, f, cells + f, xf, area, &mut fixed, rhs, &mut ghosts)?;
                }
                Location::CellCentred => {
                    let (cell, sign) = top
                        .outer_view(f)
                        .and_then(|r| r.iter().next().map(|(c, &s)| (c, f64::from(s))))
                        .ok_or(DiffusionError::Tag(TagError::InteriorFace {
                            tag: bc.tag.clone(),
                            face: f,
                        }))?;
                    let sigma = cell_diagonal[slot].ok_or(DiffusionError::Unsupported {
                        method: self.method.name(),
                        what: "boundary conditions with a non-diagonal boundary metric",
                    })?;
                    // The ghost value sits where the two-point flux measures
                    // the gradient: the foot of the perpendicular from the
                    // cell point to the face (the centroid's foot is taken
                    // as the face centroid, as on a box).
                    let foot: Vec<f64> = match &cell_points {
                        None => xf.to_vec(),
                        Some(points) => {
                            let p = &points[cell * d..(cell + 1) * d];
                            let normal = &complex.normal()[f * d..(f + 1) * d];
                            let s = fv::signed_distance(xf, p, normal, sign as i8);
                            (0..d).map(|a| p[a] + s * sign * normal[a]).collect()
                        }
                    };
                    let xg = foot.as_slice();
                    match &bc.kind {
                        BoundaryKind::Dirichlet(g) => {
                            face_value[f] = sign * evaluate(g, xg, boundary_value(bc, k))?
                        }
                        BoundaryKind::Neumann(g) => {
                            face_weight.push((f, 0.0));
                            let outward = evaluate(g, xf, boundary_value(bc, k))? * area;
                            rhs[cell] += outward;
                            neumann_flux[f] = -sign * outward;
                        }
                        BoundaryKind::Robin { alpha, value } => {
                            let a = robin_alpha(bc, k, f, alpha, xg)?;
                            face_weight.push((f, sigma * a * area / (sigma + a * area)));
                            face_value[f] = sign * evaluate(value, xg, boundary_value(bc, k))? / a;
                        }
                    }
                }
            }
        }
        Ok(BoundaryData {
            fixed,
            ghosts,
            face_weight,
            face_value,
            neumann_flux,
        })
    }

    /// The right-hand side and fixed values of this problem on the
    /// operator of `assembled`, without rebuilding Ω or M: for data that
    /// change (a time-dependent source or boundary value) on a problem
    /// whose method, conductivity, boundary tags and kinds and Robin α are
    /// those `assembled` was made with.
    pub fn data(
        &self,
        complex: &Complex,
        assembled: &Assembled,
    ) -> Result<(Vec<f64>, Vec<Option<f64>>), DiffusionError> {
        let unknowns = assembled.rhs.len();
        let mut rhs = self.source_load(complex, unknowns)?;
        let boundary = self.boundary_data(
            complex,
            assembled.location,
            &assembled.layout,
            &assembled.cell_points,
            assembled.flux_rows,
            &mut rhs,
        )?;
        let mut ghost_values = boundary.face_value;
        ghost_values.extend(boundary.ghosts.iter().map(|g| g.2));
        if ghost_values.len() != assembled.ghost_values.len() {
            return Err(DiffusionError::Unsupported {
                method: self.method.name(),
                what: "new data with other boundary kinds than the assembled operator's",
            });
        }
        if ghost_values.iter().any(|&v| v != 0.0) {
            let canonical = &assembled.canonical;
            let lifted = canonical.sum_transpose(&canonical.metric().apply(&ghost_values));
            for (b, l) in rhs.iter_mut().zip(lifted) {
                *b += l;
            }
        }
        Ok((rhs, boundary.fixed))
    }
}

/// A conductivity per region at every cell centroid: scalars stay scalars
/// when every region's is one.
fn regional_conductivity(
    regional: &Regional<Conductivity>,
    complex: &Complex,
) -> Result<CellConductivity, DiffusionError> {
    let n = complex.dim();
    let d = complex.embedding_dim();
    let owner = regional.piece_per_cell(complex)?;
    let centroids = complex.centroid(n);
    let at = |c: usize| &centroids[c * d..(c + 1) * d];
    // A region's own conductivity may be per region again (a library
    // user's choice; case files cannot write it): resolved once per such
    // piece, on the whole complex.
    let pieces = regional.pieces().len() + usize::from(regional.default().is_some());
    let mut nested = Vec::with_capacity(pieces);
    for i in 0..pieces {
        nested.push(match regional.piece(i) {
            Conductivity::Regional(inner) => Some(regional_conductivity(inner, complex)?),
            _ => None,
        });
    }
    let all_scalar = (0..pieces).all(|i| match regional.piece(i) {
        Conductivity::Scalar(_) => true,
        Conductivity::Tensor(_) => false,
        Conductivity::Regional(_) => matches!(nested[i], Some(CellConductivity::Scalar(_))),
    });
    let scalar = |c: usize| -> f64 {
        match (regional.piece(owner[c]), &nested[owner[c]]) {
            (Conductivity::Scalar(f), _) => f(at(c)),
            (_, Some(CellConductivity::Scalar(v))) => v[c],
            _ => f64::NAN,
        }
    };
    let tensor = |c: usize| -> Tensor {
        match (regional.piece(owner[c]), &nested[owner[c]]) {
            (Conductivity::Scalar(f), _) => metric::isotropic(f(at(c))),
            (Conductivity::Tensor(f), _) => f(at(c)),
            (_, Some(CellConductivity::Scalar(v))) => metric::isotropic(v[c]),
            (_, Some(CellConductivity::Full(t))) => t[c],
            (_, None) => [[f64::NAN; 3]; 3],
        }
    };
    let cells = 0..owner.len();
    Ok(if all_scalar {
        CellConductivity::Scalar(cells.into_par_iter().map(scalar).collect())
    } else {
        CellConductivity::Full(cells.into_par_iter().map(tensor).collect())
    })
}
