//! Convergence studies: solve one case on successively refined meshes with
//! one or several methods, measure the errors against the case's `[exact]`
//! solution and the observed orders of convergence.
//!
//! A [`StudyResult`] holds one [`StudyRow`] per method and level (the
//! front end's `hasse converge` fills it, see
//! `frontend::converge`). It computes the observed orders ([`Orders`],
//! from [`pairwise_orders`] and [`least_squares_order`]), checks them
//! against an [`Expectation`], and presents itself as a table
//! (`Display`), CSV, JSON and a log–log plot of error against mesh size
//! (SVG or PNG bytes); writing the files is the front end's.

mod orders;
#[cfg(feature = "cli")]
mod plot;
mod table;

pub use orders::{least_squares_order, pairwise_orders, OrderError};
#[cfg(feature = "cli")]
pub use plot::{PlotError, PlotFormat, PlotOptions};

use serde::Serialize;
use std::str::FromStr;

/// How each level is made from the previous one: a finer mesh, or (for a
/// transient case) a smaller time step on the same mesh.
///
/// ```
/// use hasse_solver::study::Refinement;
/// assert_eq!(Refinement::Uniform.name(), "uniform");
/// // Reports (the study's JSON) use the same name.
/// assert_eq!(serde_json::to_value(Refinement::Split).unwrap(), "split");
/// // A time study's orders are against Δt, not the (fixed) mesh size.
/// assert_eq!(Refinement::Time.size_name(), "Δt");
/// assert_eq!(Refinement::Split.size_name(), "h");
/// ```
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Refinement {
    /// Re-generate the case's mesh at a finer resolution: level k has
    /// 2ᵏ times the case's `mesh.n` per axis (4ᵏ times the sites of a
    /// `voronoi` mesh, whose n is a site count in 2D; 2ᵏ times a
    /// `hollow-box`'s cells and cavity indices; k more `sphere`
    /// subdivisions). A `grading` ratio r becomes r^(1/2ᵏ) so that the
    /// stretching stays that of the coarse mesh. Mesh files cannot be
    /// refined this way.
    Uniform,
    /// Level 0 is the case's mesh (generated or read from a file); each
    /// next level is the uniform SPLIT refinement of the previous one
    /// ([`hasse_complex::refine::uniform`]: every top cell cut through
    /// its centroid by the axis hyperplanes, which halves h). Simplices
    /// become convex polygons or polyhedra from level 1 on.
    Split,
    /// The same mesh on every level; level k takes Δt/2ᵏ and 2ᵏ times
    /// the steps to the same end time (transient cases only). The orders
    /// are against Δt.
    Time,
}

impl Refinement {
    /// The name used on the command line and in reports.
    pub fn name(&self) -> &'static str {
        match self {
            Refinement::Uniform => "uniform",
            Refinement::Split => "split",
            Refinement::Time => "time",
        }
    }

    /// The size that the levels halve and the orders are measured
    /// against: the mesh size h, or the time step Δt.
    pub fn size_name(&self) -> &'static str {
        match self {
            Refinement::Uniform | Refinement::Split => "h",
            Refinement::Time => "Δt",
        }
    }

    /// What the resolution column of a row holds.
    pub fn resolution_name(&self) -> &'static str {
        match self {
            Refinement::Uniform => "generator resolution (mesh.n)",
            Refinement::Split => "top cells",
            Refinement::Time => "time steps",
        }
    }
}

/// The error norms a study reports.
///
/// ```
/// use hasse_solver::study::{Norm, StudyRow};
/// let row = StudyRow {
///     method: "fe".into(), level: 0, resolution: vec![8, 8], h: 0.18, cells: 64, unknowns: 81,
///     l2: 1e-3, max: 3e-3, gradient_l2: None, flux: None, mesh_seconds: 0.0, solve_seconds: 0.0,
/// };
/// // A nodal method has no face fluxes, and this case no exact gradient.
/// let present: Vec<&str> = Norm::ALL.iter().filter(|&&n| row.error(n).is_some()).map(|n| n.key()).collect();
/// assert_eq!(present, ["l2", "max"]);
/// assert_eq!(Norm::GradientL2.label(), "H¹ error");
/// ```
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Norm {
    /// Discrete L² error of the primary field.
    L2,
    /// Largest pointwise error of the primary field.
    Max,
    /// L² error of the cell-wise reconstructed gradient (an energy-norm
    /// error), where the case gives `[exact].gradient`.
    GradientL2,
    /// L² error of the face fluxes (cell-centred and hybrid methods).
    Flux,
}

impl Norm {
    /// All norms, in table order.
    pub const ALL: [Norm; 4] = [Norm::L2, Norm::Max, Norm::GradientL2, Norm::Flux];

    /// Column name in CSV and JSON.
    pub fn key(&self) -> &'static str {
        match self {
            Norm::L2 => "l2",
            Norm::Max => "max",
            Norm::GradientL2 => "gradient_l2",
            Norm::Flux => "flux",
        }
    }

    /// Human label, as in the table and the plot legend.
    pub fn label(&self) -> &'static str {
        match self {
            Norm::L2 => "L²",
            Norm::Max => "max",
            Norm::GradientL2 => "H¹ error",
            Norm::Flux => "flux",
        }
    }
}

/// One method on one level.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct StudyRow {
    /// Method name as in case files.
    pub method: String,
    /// 0 = the case's own mesh.
    pub level: usize,
    /// What the level refines: the generator's resolution (`mesh.n`, or
    /// the subdivisions of a sphere) in a uniform study, the number of top
    /// cells in a SPLIT study, the number of time steps in a time study
    /// ([`Refinement::resolution_name`]).
    pub resolution: Vec<usize>,
    /// The size the orders are measured against
    /// ([`Refinement::size_name`]): the mesh size, the largest diameter of
    /// a top cell ([`hasse_complex::Complex::mesh_size`]), or the time
    /// step Δt in a time study (whose mesh is fixed).
    pub h: f64,
    /// Number of top cells.
    pub cells: usize,
    /// Unknowns of the solved system.
    pub unknowns: usize,
    /// L² error of the method's field, by quadrature on each cell (see
    /// [`Errors::l2`](crate::physics::diffusion::Errors::l2)).
    pub l2: f64,
    /// Largest error at the unknowns' points.
    pub max: f64,
    /// H¹-seminorm error ‖∇u_h − ∇u‖ by quadrature, when the case gives
    /// the exact gradient.
    pub gradient_l2: Option<f64>,
    /// Face-flux L² error, where the method defines it.
    pub flux: Option<f64>,
    /// Seconds to build the mesh (shared by the methods of a level).
    pub mesh_seconds: f64,
    /// Seconds of assembly, factorisation, solve and error evaluation.
    pub solve_seconds: f64,
}

impl StudyRow {
    /// The error in `norm`, if this row has it.
    pub fn error(&self, norm: Norm) -> Option<f64> {
        match norm {
            Norm::L2 => Some(self.l2),
            Norm::Max => Some(self.max),
            Norm::GradientL2 => self.gradient_l2,
            Norm::Flux => self.flux,
        }
    }
}

/// Observed orders of one method in one norm.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Orders {
    /// The method's name.
    pub method: String,
    /// The norm the errors were measured in.
    pub norm: Norm,
    /// Between level k and k + 1 (None where undefined, e.g. a zero error).
    pub pairwise: Vec<Option<f64>>,
    /// Least-squares slope over all levels.
    pub least_squares: Option<f64>,
}

/// The rows of a study, method by method, each method's levels in order.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct StudyResult {
    /// The case file as named.
    pub case: String,
    /// The case's title, if it has one and the study runs the case's own
    /// method (a title describes the case as written, not other methods).
    pub title: Option<String>,
    /// How the meshes of the levels were made.
    pub refinement: Refinement,
    /// Number of levels (meshes), the case's own included.
    pub levels: usize,
    /// Method names in the order studied.
    pub methods: Vec<String>,
    /// One row per method and level: the first method's levels in order,
    /// then the next method's.
    pub rows: Vec<StudyRow>,
}

/// A minimum order that a study must reach: `ORDER[:TOL]`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Expectation {
    /// The order the least-squares L² slope should reach.
    pub order: f64,
    /// Slack below `order` (default 0.15, the design's tolerance).
    pub tolerance: f64,
}

impl Expectation {
    /// The default tolerance.
    pub const DEFAULT_TOLERANCE: f64 = 0.15;
}

/// An expectation that is not `ORDER` or `ORDER:TOLERANCE`.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("`{0}` is not ORDER or ORDER:TOLERANCE with numbers (tolerance ≥ 0), e.g. 2 or 2:0.1")]
pub struct BadExpectation(
    /// The text as given.
    pub String,
);

impl FromStr for Expectation {
    type Err = BadExpectation;

    /// ```
    /// use hasse_solver::study::Expectation;
    /// let e: Expectation = "2".parse().unwrap();
    /// assert_eq!((e.order, e.tolerance), (2.0, 0.15));
    /// let e: Expectation = "1:0.3".parse().unwrap();
    /// assert_eq!((e.order, e.tolerance), (1.0, 0.3));
    /// assert!("two".parse::<Expectation>().is_err());
    /// ```
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        let bad = || BadExpectation(s.to_string());
        let (order, tolerance) = match s.split_once(':') {
            Some((o, t)) => (o, Some(t)),
            None => (s, None),
        };
        let order: f64 = order.trim().parse().map_err(|_| bad())?;
        let tolerance: f64 = match tolerance {
            Some(t) => t.trim().parse().map_err(|_| bad())?,
            None => Self::DEFAULT_TOLERANCE,
        };
        if !order.is_finite() || !tolerance.is_finite() || tolerance < 0.0 {
            return Err(bad());
        }
        Ok(Self { order, tolerance })
    }
}

/// A method whose least-squares L² order missed an [`Expectation`].
#[derive(Clone, Debug, PartialEq)]
pub struct Shortfall {
    /// The method's name.
    pub method: String,
    /// None when the order could not be computed (e.g. a zero error).
    pub observed: Option<f64>,
}

impl StudyResult {
    /// The rows of one method, by level.
    pub fn method_rows<'a>(&'a self, method: &'a str) -> impl Iterator<Item = &'a StudyRow> + 'a {
        self.rows.iter().filter(move |r| r.method == method)
    }

    /// Observed orders of `method` in `norm`. Where some level lacks the
    /// norm (no exact gradient, no flux for this method), every order is
    /// None.
    ///
    /// ```
    /// use hasse_solver::study::{Norm, Refinement, StudyResult, StudyRow};
    /// let row = |level: usize, h: f64, l2: f64| StudyRow {
    ///     method: "fv".into(), level, resolution: vec![], h, cells: 0, unknowns: 0,
    ///     l2, max: l2, gradient_l2: None, flux: Some(l2.sqrt()), mesh_seconds: 0.0, solve_seconds: 0.0,
    /// };
    /// let result = StudyResult {
    ///     case: "demo".into(), title: None, refinement: Refinement::Uniform, levels: 3,
    ///     methods: vec!["fv".into()],
    ///     rows: vec![row(0, 0.2, 1.6e-3), row(1, 0.1, 4e-4), row(2, 0.05, 1e-4)],
    /// };
    /// // e = 0.04 h²: order 2 in L², and the square root of it order 1.
    /// let l2 = result.orders("fv", Norm::L2);
    /// assert!(l2.pairwise.iter().all(|p| (p.unwrap() - 2.0).abs() < 1e-12));
    /// assert!((result.orders("fv", Norm::Flux).least_squares.unwrap() - 1.0).abs() < 1e-12);
    /// assert_eq!(result.orders("fv", Norm::GradientL2).least_squares, None);
    /// ```
    pub fn orders(&self, method: &str, norm: Norm) -> Orders {
        let rows: Vec<&StudyRow> = self.method_rows(method).collect();
        let h: Vec<f64> = rows.iter().map(|r| r.h).collect();
        let e: Option<Vec<f64>> = rows.iter().map(|r| r.error(norm)).collect();
        let (pairwise, least_squares) = match e {
            Some(e) if rows.len() >= 2 => {
                let pairwise = (0..rows.len() - 1)
                    .map(|k| {
                        pairwise_orders(&h[k..k + 2], &e[k..k + 2])
                            .ok()
                            .map(|p| p[0])
                    })
                    .collect();
                (pairwise, least_squares_order(&h, &e).ok())
            }
            _ => (vec![None; rows.len().saturating_sub(1)], None),
        };
        Orders {
            method: method.to_string(),
            norm,
            pairwise,
            least_squares,
        }
    }

    /// The norms that every level of `method` has.
    pub fn norms(&self, method: &str) -> Vec<Norm> {
        Norm::ALL
            .into_iter()
            .filter(|&n| {
                let mut rows = self.method_rows(method).peekable();
                rows.peek().is_some() && rows.all(|r| r.error(n).is_some())
            })
            .collect()
    }

    /// The methods whose least-squares L² order is below
    /// `expect.order − expect.tolerance` (or cannot be computed).
    ///
    /// ```
    /// use hasse_solver::study::{Expectation, Refinement, StudyResult, StudyRow};
    /// let row = |level: usize, h: f64, l2: f64| StudyRow {
    ///     method: "fv".into(), level, resolution: vec![], h, cells: 0, unknowns: 0,
    ///     l2, max: l2, gradient_l2: None, flux: None, mesh_seconds: 0.0, solve_seconds: 0.0,
    /// };
    /// let result = StudyResult {
    ///     case: "demo".into(), title: None, refinement: Refinement::Uniform, levels: 2,
    ///     methods: vec!["fv".into()], rows: vec![row(0, 0.1, 1e-2), row(1, 0.05, 2.5e-3)],
    /// };
    /// assert!(result.shortfalls(Expectation { order: 2.0, tolerance: 0.15 }).is_empty());
    /// assert_eq!(result.shortfalls("3".parse().unwrap())[0].method, "fv");
    /// ```
    pub fn shortfalls(&self, expect: Expectation) -> Vec<Shortfall> {
        self.methods
            .iter()
            .filter_map(|m| {
                let observed = self.orders(m, Norm::L2).least_squares;
                match observed {
                    Some(p) if p >= expect.order - expect.tolerance => None,
                    _ => Some(Shortfall {
                        method: m.clone(),
                        observed,
                    }),
                }
            })
            .collect()
    }
}
