//! Linear elasticity −∇·σ(u) = f, σ = λ (∇·u) I + μ (∇u + ∇uᵀ), with the
//! displacement u on the vertices of a 2- or 3-dimensional mesh, in
//! canonical form.
//!
//! The unknowns are the d components of u on every vertex, component by
//! component (index a·|K₀| + v). The incidence is the edge difference
//! applied to each component,
//!
//! ```text
//!     A = I_d ⊗ δ⁰        (row a·|K₁| + e: component a of u_head − u_tail)
//! ```
//!
//! and every top cell c adds a dense block over the d·|edges of c| rows of
//! its own edges. With K_c the element stiffness (P1 on triangles and
//! tetrahedra, Q1 on quadrilaterals and hexahedra, integrated with the
//! quadrature of the scalar FE metric) and A_c = I_d ⊗ (local δ⁰),
//!
//! ```text
//!     Ω_c = (A_c⁺)ᵀ K_c A_c⁺     and     A_cᵀ Ω_c A_c = K_c   exactly,
//! ```
//!
//! because the kernel of A_c (a constant per component: the translations)
//! lies in the kernel of K_c. Rotations are not in ker A_c: A_c maps them
//! to nonzero edge vectors, which Ω_c sends to zero.
//!
//! Boundary conditions act on tagged (n−1)-cells: a prescribed displacement
//! (all components, or one component, for rollers and symmetry planes) is
//! eliminated symmetrically, so the reduced system is symmetric positive
//! definite; a traction σn = t adds ∫_F t φ_v, lumped as t(x_v)|F|/(vertices
//! of F) on each face vertex (exact for constant t on segments and
//! triangles). Unlisted boundary faces are traction-free. Before solving,
//! the prescribed components are checked to fix every rigid-body motion
//! (d translations, d(d−1)/2 rotations) of every connected part of the
//! mesh; a problem that leaves one free is reported, not sent to LLᵀ.

use crate::la::direct::{Factorization, SolveError, SolveReport};
use crate::la::ordering::Ordering;
use crate::metric::fe;
use crate::metric::mass::lumped_vertex_volumes;
use crate::metric::MetricError;
use crate::operator::{Canonical, CanonicalError};
use crate::physics::diffusion::{self, DiffusionError};
use crate::physics::VectorFn;
use crate::physics::{
    non_finite_text, point_text, tagged_boundary_faces, Datum, ScalarFn, TagError,
};
use faer::sparse::SparseColMat;
use hasse_complex::Complex;
use std::sync::Arc;
use std::time::Instant;

mod operator;
mod rigid;

pub use operator::{incidence, stiffness_metric};
use rigid::check_rigid_modes;
pub use rigid::rigid_modes;

/// A material coefficient: a function of position evaluated at each top
/// cell's centroid, or one value per top cell.
///
/// ```
/// use hasse_complex::generate::rectangle;
/// use hasse_solver::physics::elasticity::{Coefficient, Elasticity, ElasticityError, Material};
/// use std::sync::Arc;
/// // Two materials side by side: stiff on the left half, soft on the right.
/// let mesh = rectangle(2, 1, [0.0, 2.0], [0.0, 1.0]).unwrap();
/// let by_position = Coefficient::Function(Arc::new(|x| if x[0] < 1.0 { 10.0 } else { 1.0 }));
/// let by_cell = Coefficient::PerCell(Arc::from([10.0, 1.0]));
/// let lame = |mu| {
///     let material = Material::Lame { lambda: Coefficient::constant(1.0), mu };
///     Elasticity::new(material, Arc::new(|_| [0.0; 3])).lame(&mesh)
/// };
/// assert_eq!(lame(by_position).unwrap(), lame(by_cell).unwrap());
/// // Per-cell values must match the top cells one to one.
/// let short = Coefficient::PerCell(Arc::from([10.0]));
/// assert_eq!(lame(short).unwrap_err(), ElasticityError::CoefficientCount { count: 1, cells: 2 });
/// ```
#[derive(Clone)]
pub enum Coefficient {
    /// A function of position, evaluated at each top cell's centroid.
    Function(ScalarFn),
    /// One value per top cell, in cell order (e.g. a material read from a
    /// file of regions).
    PerCell(Arc<[f64]>),
}

impl Coefficient {
    /// The same value everywhere.
    pub fn constant(value: f64) -> Self {
        Coefficient::Function(Arc::new(move |_| value))
    }

    fn values(&self, complex: &Complex) -> Result<Vec<f64>, ElasticityError> {
        let n = complex.dim();
        let cells = complex.cell_count(n);
        match self {
            Coefficient::Function(f) => {
                Ok((0..cells).map(|c| f(complex.centroid_of(n, c))).collect())
            }
            Coefficient::PerCell(values) if values.len() == cells => Ok(values.to_vec()),
            Coefficient::PerCell(values) => Err(ElasticityError::CoefficientCount {
                count: values.len(),
                cells,
            }),
        }
    }
}

/// The elastic material, by Lamé parameters or by Young's modulus and
/// Poisson's ratio (λ = Eν/((1+ν)(1−2ν)), μ = E/(2(1+ν))).
///
/// ```
/// use hasse_complex::generate::box3;
/// use hasse_solver::physics::elasticity::{Coefficient, Elasticity, Lame, Material};
/// use std::sync::Arc;
/// // E = 2.5, ν = 0.25: λ = 0.625 / (1.25 · 0.5) = 1, μ = 2.5 / 2.5 = 1.
/// let mesh = box3(1, 1, 1, [0.0, 1.0], [0.0, 1.0], [0.0, 1.0]).unwrap();
/// let material = Material::Young { young: Coefficient::constant(2.5), poisson: Coefficient::constant(0.25) };
/// let lame = Elasticity::new(material, Arc::new(|_| [0.0; 3])).lame(&mesh).unwrap();
/// assert_eq!(lame, vec![Lame { lambda: 1.0, mu: 1.0 }]);
/// ```
#[derive(Clone)]
pub enum Material {
    /// By the Lamé parameters: λ, and μ the shear modulus. They must give
    /// μ > 0 and a positive bulk modulus λ + 2μ/d.
    Lame {
        /// The first Lamé parameter λ.
        lambda: Coefficient,
        /// The shear modulus μ.
        mu: Coefficient,
    },
    /// By Young's modulus E > 0 and Poisson's ratio ν ∈ (−1, ½) (ν → ½ is
    /// incompressible, where λ → ∞).
    Young {
        /// Young's modulus E.
        young: Coefficient,
        /// Poisson's ratio ν.
        poisson: Coefficient,
    },
}

/// The Lamé parameters of one top cell (see [`Elasticity::lame`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Lame {
    /// The first Lamé parameter λ.
    pub lambda: f64,
    /// The shear modulus μ.
    pub mu: f64,
}

/// What a 2D problem stands for.
///
/// ```
/// use hasse_complex::generate::rectangle;
/// use hasse_solver::physics::elasticity::{Coefficient, Elasticity, Material, PlaneModel};
/// use std::sync::Arc;
/// let mesh = rectangle(1, 1, [0.0, 1.0], [0.0, 1.0]).unwrap();
/// let material = Material::Lame { lambda: Coefficient::constant(1.0), mu: Coefficient::constant(1.0) };
/// let problem = Elasticity::new(material, Arc::new(|_| [0.0; 3]));
/// assert_eq!(problem.lame(&mesh).unwrap()[0].lambda, 1.0);
/// // Plane stress: λ* = 2λμ / (λ + 2μ) = 2/3; μ is unchanged.
/// let stress = problem.with_plane(PlaneModel::Stress).lame(&mesh).unwrap();
/// assert!((stress[0].lambda - 2.0 / 3.0).abs() < 1e-15 && stress[0].mu == 1.0);
/// ```
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum PlaneModel {
    /// Plane strain (ε_zz = 0): λ and μ as given.
    #[default]
    Strain,
    /// Plane stress (σ_zz = 0): λ replaced by 2λμ/(λ + 2μ).
    Stress,
}

impl PlaneModel {
    /// Both models, in the order help texts list them.
    pub const ALL: [PlaneModel; 2] = [PlaneModel::Strain, PlaneModel::Stress];

    /// The name case files use (`problem.plane`).
    ///
    /// ```
    /// use hasse_solver::physics::elasticity::PlaneModel;
    /// assert_eq!(PlaneModel::ALL.map(|p| p.name()), ["strain", "stress"]);
    /// ```
    pub fn name(&self) -> &'static str {
        match self {
            PlaneModel::Strain => "strain",
            PlaneModel::Stress => "stress",
        }
    }
}

/// A boundary condition's kind and data.
///
/// ```
/// use hasse_complex::generate::rectangle;
/// use hasse_solver::physics::elasticity::{Coefficient, ElasticBoundary, Elasticity, Material, PlaneModel};
/// use std::sync::Arc;
/// // Uniaxial tension on rollers: u_x = 0 on the left, u_y = 0 at the
/// // bottom, σn = (1, 0) on the right. Plane stress with E = 1, ν = ¼
/// // gives ε_xx = 1, ε_yy = −¼: u = (x, −y/4), reproduced exactly.
/// let mesh = rectangle(4, 2, [0.0, 2.0], [0.0, 1.0]).unwrap();
/// let material = Material::Young { young: Coefficient::constant(1.0), poisson: Coefficient::constant(0.25) };
/// let u = Elasticity::new(material, Arc::new(|_| [0.0; 3]))
///     .with_plane(PlaneModel::Stress)
///     .with_boundary("xmin", ElasticBoundary::Component { component: 0, value: Arc::new(|_| 0.0) })
///     .with_boundary("ymin", ElasticBoundary::Component { component: 1, value: Arc::new(|_| 0.0) })
///     .with_boundary("xmax", ElasticBoundary::Traction(Arc::new(|_| [1.0, 0.0, 0.0])))
///     .solve(&mesh)
///     .unwrap();
/// for v in 0..mesh.cell_count(0) {
///     let x = mesh.vertices().point(v);
///     let [ux, uy, _] = u.at(v);
///     assert!((ux - x[0]).abs() < 1e-12 && (uy + x[1] / 4.0).abs() < 1e-12);
/// }
/// ```
#[derive(Clone)]
pub enum ElasticBoundary {
    /// u = g (every component).
    Displacement(VectorFn),
    /// u_a = g for one component a (a roller, a symmetry plane); the other
    /// components are traction-free.
    Component {
        /// The component a: 0 for x, 1 for y, 2 for z.
        component: usize,
        /// g, its prescribed value.
        value: ScalarFn,
    },
    /// σ n = t, n the outward normal.
    Traction(VectorFn),
}

/// Linear elasticity −∇·σ(u) = f with boundary conditions on tags.
///
/// ```
/// use hasse_complex::generate::rectangle;
/// use hasse_solver::physics::elasticity::{Coefficient, ElasticBoundary, Elasticity, Material};
/// use std::sync::Arc;
/// // A bar clamped at x = 0 and pulled at x = 2 by a unit traction:
/// // σ_xx = 1, so u_x(2, y) = 2/E. With ν = 0 there is no lateral
/// // contraction (and plane strain and plane stress agree).
/// let mesh = rectangle(8, 2, [0.0, 2.0], [0.0, 0.5]).unwrap();
/// let material = Material::Young { young: Coefficient::constant(4.0), poisson: Coefficient::constant(0.0) };
/// let problem = Elasticity::new(material, Arc::new(|_| [0.0; 3]))
///     .with_boundary("xmin", ElasticBoundary::Displacement(Arc::new(|_| [0.0; 3])))
///     .with_boundary("xmax", ElasticBoundary::Traction(Arc::new(|_| [1.0, 0.0, 0.0])));
/// let u = problem.solve(&mesh).unwrap();
/// let corner = 8; // vertex (2, 0)
/// assert!((u.at(corner)[0] - 0.5).abs() < 1e-12);
/// ```
#[derive(Clone)]
pub struct Elasticity {
    /// λ and μ (or E and ν), per top cell.
    pub material: Material,
    /// Body force f (the first d components are used).
    pub body_force: VectorFn,
    /// (tag, condition), applied in order; a later condition on the same
    /// face replaces an earlier one.
    pub boundary: Vec<(String, ElasticBoundary)>,
    /// Plane strain or plane stress (2D only).
    pub plane: PlaneModel,
    /// Direct factorisation (default LLᵀ: the reduced system is SPD).
    pub factorization: Factorization,
    /// Its fill-reducing ordering (default automatic).
    pub ordering: Ordering,
}

/// Why an elasticity problem could not be solved.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ElasticityError {
    /// The mesh is not a 2D or 3D volume mesh (n = d ∈ {2, 3}): a
    /// surface or a curve has no in-plane elasticity here.
    #[error("elasticity needs a 2- or 3-dimensional mesh that fills its space; this one is {n}-dimensional in R^{d}")]
    Dimension {
        /// Dimension of the complex.
        n: usize,
        /// Dimension of the space it lies in.
        d: usize,
    },
    /// A [`Coefficient::PerCell`] has not one value per top cell.
    #[error("{count} material values given for {cells} top cells")]
    CoefficientCount {
        /// Values given.
        count: usize,
        /// Top cells of the mesh.
        cells: usize,
    },
    /// A material parameter is NaN or ±∞ in a cell.
    #[error("material parameter {what} = {value} in top cell {cell} is not finite")]
    NonFiniteMaterial {
        /// `"λ"`, `"μ"`, `"E"` or `"ν"`.
        what: &'static str,
        /// The top cell.
        cell: usize,
        /// The value there.
        value: f64,
    },
    /// The Lamé parameters of a cell make the stiffness indefinite.
    #[error("Lamé parameters λ = {lambda}, μ = {mu} in top cell {cell}: need μ > 0 and λ + 2μ/{d} > 0 (positive shear and bulk moduli)")]
    Lame {
        /// The top cell.
        cell: usize,
        /// Its λ.
        lambda: f64,
        /// Its μ.
        mu: f64,
        /// The space dimension, which sets the bulk modulus λ + 2μ/d.
        d: usize,
    },
    /// Young's modulus is zero or negative in a cell.
    #[error("Young's modulus E = {young} in top cell {cell} must be positive")]
    Young {
        /// The top cell.
        cell: usize,
        /// Its E.
        young: f64,
    },
    /// Poisson's ratio lies outside (−1, ½) in a cell (½ would make λ
    /// infinite).
    #[error("Poisson's ratio ν = {poisson} in top cell {cell} must lie in (−1, 0.5)")]
    Poisson {
        /// The top cell.
        cell: usize,
        /// Its ν.
        poisson: f64,
    },
    /// A boundary condition names a tag the mesh does not have, or one
    /// that does not tag boundary faces.
    #[error(transparent)]
    Tag(#[from] TagError),
    /// An [`ElasticBoundary::Component`] names a component ≥ d.
    #[error("boundary condition on tag '{tag}' fixes component {component}, but displacements have {d} components (0..{d})")]
    Component {
        /// The condition's tag.
        tag: String,
        /// The component it names.
        component: usize,
        /// Components of the displacement.
        d: usize,
    },
    /// A given function (body force, boundary displacement or traction)
    /// is NaN or ±∞ at a point.
    #[error("{datum} is not finite ({}) at {}", non_finite_text(*.value), point_text(.point))]
    NonFinite {
        /// Which input gave the value.
        datum: Datum,
        /// Where it was evaluated.
        point: Vec<f64>,
        /// The value (NaN or ±∞).
        value: f64,
    },
    /// The prescribed displacements do not hold some rigid-body motion of
    /// a connected part of the mesh, so K is singular there.
    #[error("the prescribed displacements leave {free} of the {modes} rigid-body modes (translations and rotations) of part {part} of the mesh free, so the solution is not unique; prescribe displacements on enough of its boundary (pure traction problems have no unique solution)")]
    RigidModes {
        /// Index of the connected part, parts numbered in the order
        /// of their lowest vertex.
        part: usize,
        /// How many rigid-body modes are left free.
        free: usize,
        /// How many the part has: d(d+1)/2.
        modes: usize,
    },
    /// The element stiffness refused the mesh (cells of an unsupported
    /// shape, degenerate cells).
    #[error(transparent)]
    Metric(#[from] MetricError),
    /// A and Ω do not fit together.
    #[error(transparent)]
    Canonical(#[from] CanonicalError),
    /// The factorisation or solve failed.
    #[error(transparent)]
    Solve(#[from] SolveError),
    /// Another failure of the shared solve with fixed unknowns.
    #[error(transparent)]
    Diffusion(DiffusionError),
}

/// The assembled system (see [`Elasticity::assemble`]).
#[derive(Clone, Debug)]
pub struct ElasticSystem {
    /// Space dimension d (components per vertex).
    pub dim: usize,
    /// A = I_d ⊗ δ⁰ and the block metric Ω.
    pub canonical: Canonical,
    /// K = Aᵀ Ω A over all d·|K₀| unknowns (component-major).
    pub matrix: SparseColMat<usize, f64>,
    /// Body force and traction loads.
    pub rhs: Vec<f64>,
    /// Prescribed values of the fixed unknowns.
    pub fixed: Vec<Option<f64>>,
    /// Seconds the assembly took.
    pub assembly_seconds: f64,
}

/// The displacement and how it was obtained.
#[derive(Clone, Debug)]
pub struct Displacement {
    /// Components per vertex.
    pub dim: usize,
    /// Component-major: u_a at vertex v is `values[a * vertices + v]`.
    pub values: Vec<f64>,
    /// The linear solve: sizes, seconds and relative residual.
    pub report: SolveReport,
    /// Seconds to assemble K and the loads.
    pub assembly_seconds: f64,
}

impl Displacement {
    /// Number of vertices.
    pub fn vertices(&self) -> usize {
        self.values.len() / self.dim
    }

    /// Component a on every vertex.
    pub fn component(&self, a: usize) -> &[f64] {
        let n = self.vertices();
        &self.values[a * n..(a + 1) * n]
    }

    /// u at vertex v (zero beyond the d components).
    pub fn at(&self, v: usize) -> [f64; 3] {
        let mut u = [0.0; 3];
        for (a, ua) in u.iter_mut().enumerate().take(self.dim) {
            *ua = self.values[a * self.vertices() + v];
        }
        u
    }

    /// Discrete L² error (lumped vertex volumes) and the largest pointwise
    /// error of |u_h − u| against an exact displacement.
    pub fn errors(&self, complex: &Complex, exact: &VectorFn) -> (f64, f64) {
        let weights = lumped_vertex_volumes(complex);
        let (mut l2, mut max) = (0.0, 0.0f64);
        for (v, w) in weights.iter().enumerate() {
            let e = exact(complex.vertices().point(v));
            let u = self.at(v);
            let s: f64 = (0..self.dim).map(|a| (u[a] - e[a]).powi(2)).sum();
            l2 += w * s;
            max = max.max(s.sqrt());
        }
        (l2.sqrt(), max)
    }
}

fn evaluate(value: f64, datum: Datum, x: &[f64]) -> Result<f64, ElasticityError> {
    if value.is_finite() {
        Ok(value)
    } else {
        Err(ElasticityError::NonFinite {
            datum,
            point: x.to_vec(),
            value,
        })
    }
}

impl Elasticity {
    /// A problem without boundary conditions (add them with
    /// [`Elasticity::with_boundary`]), plane strain in 2D, solved by LLᵀ.
    pub fn new(material: Material, body_force: VectorFn) -> Self {
        Self {
            material,
            body_force,
            boundary: Vec::new(),
            plane: PlaneModel::Strain,
            factorization: Factorization::Llt,
            ordering: Ordering::Automatic,
        }
    }

    /// Add a boundary condition on a tag.
    pub fn with_boundary(mut self, tag: &str, kind: ElasticBoundary) -> Self {
        self.boundary.push((tag.to_string(), kind));
        self
    }

    /// Plane strain or plane stress (2D).
    pub fn with_plane(mut self, plane: PlaneModel) -> Self {
        self.plane = plane;
        self
    }

    /// The Lamé parameters used in each top cell (after the plane-stress
    /// reduction in 2D), checked.
    pub fn lame(&self, complex: &Complex) -> Result<Vec<Lame>, ElasticityError> {
        let d = dimension(complex)?;
        let finite = |what, cell: usize, value: f64| {
            if value.is_finite() {
                Ok(value)
            } else {
                Err(ElasticityError::NonFiniteMaterial { what, cell, value })
            }
        };
        let lame: Vec<Lame> = match &self.material {
            Material::Lame { lambda, mu } => lambda
                .values(complex)?
                .into_iter()
                .zip(mu.values(complex)?)
                .enumerate()
                .map(|(c, (l, m))| {
                    Ok(Lame {
                        lambda: finite("λ", c, l)?,
                        mu: finite("μ", c, m)?,
                    })
                })
                .collect::<Result<_, ElasticityError>>()?,
            Material::Young { young, poisson } => young
                .values(complex)?
                .into_iter()
                .zip(poisson.values(complex)?)
                .enumerate()
                .map(|(c, (e, nu))| {
                    let (e, nu) = (finite("E", c, e)?, finite("ν", c, nu)?);
                    if e <= 0.0 {
                        return Err(ElasticityError::Young { cell: c, young: e });
                    }
                    if !(nu > -1.0 && nu < 0.5) {
                        return Err(ElasticityError::Poisson {
                            cell: c,
                            poisson: nu,
                        });
                    }
                    Ok(Lame {
                        lambda: e * nu / ((1.0 + nu) * (1.0 - 2.0 * nu)),
                        mu: e / (2.0 * (1.0 + nu)),
                    })
                })
                .collect::<Result<_, ElasticityError>>()?,
        };
        lame.into_iter()
            .enumerate()
            .map(|(cell, Lame { lambda, mu })| {
                // Coercivity needs a positive shear modulus and a positive
                // bulk modulus λ + 2μ/d; a negative λ (auxetic, ν < 0) is
                // allowed, as ν ∈ (−1, 0) is.
                if !(mu > 0.0 && lambda + 2.0 * mu / d as f64 > 0.0) {
                    return Err(ElasticityError::Lame {
                        cell,
                        lambda,
                        mu,
                        d,
                    });
                }
                let lambda = match (d, self.plane) {
                    (2, PlaneModel::Stress) => 2.0 * lambda * mu / (lambda + 2.0 * mu),
                    _ => lambda,
                };
                Ok(Lame { lambda, mu })
            })
            .collect()
    }

    /// The material in every cell and the body force's load, checked as
    /// [`Elasticity::assemble`] checks them, without building the
    /// stiffness: bad data refused before solving.
    pub fn check_data(&self, complex: &Complex) -> Result<(), ElasticityError> {
        self.lame(complex)?;
        self.body_load(complex).map(|_| ())
    }

    /// ∫ f_a φ_v for every component a, component after component.
    fn body_load(&self, complex: &Complex) -> Result<Vec<f64>, ElasticityError> {
        let d = complex.embedding_dim();
        let mut rhs = Vec::with_capacity(d * complex.cell_count(0));
        for a in 0..d {
            let force = &self.body_force;
            let load = fe::load(complex, &|x| force(x)[a]).map_err(|e| match e {
                MetricError::NonFiniteSource { point, value, .. } => ElasticityError::NonFinite {
                    datum: Datum::BodyForce,
                    point,
                    value,
                },
                other => other.into(),
            })?;
            rhs.extend(load);
        }
        Ok(rhs)
    }

    /// Assemble K = Aᵀ Ω A, the loads and the prescribed components.
    ///
    /// ```
    /// use hasse_complex::generate::rectangle;
    /// use hasse_solver::physics::elasticity::{rigid_modes, Coefficient, ElasticBoundary, Elasticity, Material};
    /// use std::sync::Arc;
    /// let mesh = rectangle(2, 1, [0.0, 2.0], [0.0, 1.0]).unwrap();
    /// let material = Material::Lame { lambda: Coefficient::constant(1.0), mu: Coefficient::constant(1.0) };
    /// let system = Elasticity::new(material, Arc::new(|_| [0.0; 3]))
    ///     .with_boundary("xmin", ElasticBoundary::Displacement(Arc::new(|_| [0.0; 3])))
    ///     .assemble(&mesh)
    ///     .unwrap();
    /// // 6 vertices × 2 components; the 2 clamped vertices fix 4 of them.
    /// assert_eq!((system.dim, system.matrix.nrows()), (2, 12));
    /// assert_eq!(system.fixed.iter().filter(|g| g.is_some()).count(), 4);
    /// // Rigid motions strain nothing: K r = 0 for both translations and
    /// // the rotation.
    /// let k = system.matrix.to_dense();
    /// for r in rigid_modes(&mesh) {
    ///     assert!((0..12).all(|i| (0..12).map(|j| k[(i, j)] * r[j]).sum::<f64>().abs() < 1e-12));
    /// }
    /// ```
    pub fn assemble(&self, complex: &Complex) -> Result<ElasticSystem, ElasticityError> {
        let started = Instant::now();
        let d = dimension(complex)?;
        let n = complex.dim();
        let vertices = complex.cell_count(0);
        let lame = self.lame(complex)?;
        let metric = stiffness_metric(complex, &lame)?;
        let mut canonical = Canonical::new(incidence(complex), metric)?;

        let mut rhs = self.body_load(complex)?;

        let mut fixed = vec![None; d * vertices];
        let condition = self.boundary_faces(complex, d)?;
        let area = complex.measure(n - 1);
        for &(f, k) in &condition {
            let face = complex.cell_vertices(n - 1, f);
            let share = area[f] / face.len() as f64;
            for &v in face {
                let x = complex.vertices().point(v);
                let displacement = Datum::BoundaryValue {
                    condition: k,
                    kind: "displacement",
                };
                let traction = Datum::BoundaryValue {
                    condition: k,
                    kind: "traction",
                };
                match &self.boundary[k].1 {
                    ElasticBoundary::Displacement(g) => {
                        let g = g(x);
                        for (a, &ga) in g.iter().enumerate().take(d) {
                            fixed[a * vertices + v] = Some(evaluate(ga, displacement, x)?);
                        }
                    }
                    ElasticBoundary::Component { component, value } => {
                        fixed[component * vertices + v] =
                            Some(evaluate(value(x), displacement, x)?);
                    }
                    ElasticBoundary::Traction(t) => {
                        let t = t(x);
                        for (a, &ta) in t.iter().enumerate().take(d) {
                            rhs[a * vertices + v] += evaluate(ta, traction, x)? * share;
                        }
                    }
                }
            }
        }
        let matrix = canonical.assemble_owned();
        Ok(ElasticSystem {
            dim: d,
            canonical,
            matrix,
            rhs,
            fixed,
            assembly_seconds: started.elapsed().as_secs_f64(),
        })
    }

    /// Assemble, check that no rigid-body mode is left free, and solve.
    pub fn solve(&self, complex: &Complex) -> Result<Displacement, ElasticityError> {
        let system = self.assemble(complex)?;
        check_rigid_modes(complex, &system.fixed)?;
        let (values, report, _) = diffusion::solve_with_fixed(
            &system.matrix,
            &system.rhs,
            &system.fixed,
            self.factorization,
            self.ordering,
            None,
        )
        .map_err(|e| match e {
            DiffusionError::Solve(e) => ElasticityError::Solve(e),
            other => ElasticityError::Diffusion(other),
        })?;
        Ok(Displacement {
            dim: system.dim,
            values,
            report,
            assembly_seconds: system.assembly_seconds,
        })
    }

    /// (face, condition index into `boundary`) for every conditioned
    /// (n−1)-cell, by face.
    fn boundary_faces(
        &self,
        complex: &Complex,
        d: usize,
    ) -> Result<Vec<(usize, usize)>, ElasticityError> {
        let condition =
            tagged_boundary_faces(complex, self.boundary.iter().map(|(name, _)| name.as_str()))?;
        for (name, kind) in &self.boundary {
            if let ElasticBoundary::Component { component, .. } = kind {
                if *component >= d {
                    return Err(ElasticityError::Component {
                        tag: name.clone(),
                        component: *component,
                        d,
                    });
                }
            }
        }
        Ok(condition)
    }
}

fn dimension(complex: &Complex) -> Result<usize, ElasticityError> {
    let (n, d) = (complex.dim(), complex.embedding_dim());
    if n != d || !(2..=3).contains(&n) {
        return Err(ElasticityError::Dimension { n, d });
    }
    Ok(d)
}
