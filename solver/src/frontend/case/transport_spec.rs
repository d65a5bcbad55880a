//! The specification of a `kind = "transport"` case.

use super::expr::Expression;
use super::{BoundarySpec, Coefficient, TimeSpec};
use crate::metric::Method;
use crate::physics::transport::nodal::Stabilisation;
use crate::physics::transport::Scheme;

/// −∇·(K∇u) + ∇·(v u) = f (`kind = "transport"`) on cell-centred
/// finite volumes (`method = "fv"`), steady, or in time with a `[time]`
/// table; or on nodal finite elements (`method = "fe"`, steady or with
/// the θ-scheme of `[time]`), Galerkin or with SUPG (`stabilisation =
/// "supg"`, the default, or `"none"`).
///
/// ```
/// use hasse_solver::frontend::case::{Case, Problem};
/// use hasse_solver::physics::transport::Scheme;
/// let text = r#"
/// [mesh]
/// generator = "rectangle"
/// n = [8, 2]
/// [problem]
/// kind = "transport"
/// method = "fv"
/// velocity = ["1", "0"]
/// conductivity = 0
/// initial = "x < 0.5"
/// scheme = "limited"
/// [[boundary]]
/// tag = "xmin"
/// type = "dirichlet"
/// value = 1
/// [time]
/// dt = 0.01
/// steps = 10
/// "#;
/// let case = Case::from_text("t.toml", text, &[]).unwrap();
/// let Problem::Transport(spec) = &case.problem else { panic!() };
/// assert!(spec.conductivity.is_none()); // pure advection
/// assert_eq!((spec.velocity.len(), spec.scheme), (2, Scheme::Limited));
/// assert_eq!(spec.time.as_ref().map(|t| t.steps), Some(10));
/// // Nodal elements with SUPG (the default stabilisation) or without.
/// let fe = text.replace("\"fv\"", "\"fe\"").replace("conductivity = 0", "conductivity = 0.01")
///     .replace("initial = \"x < 0.5\"\nscheme = \"limited\"", "stabilisation = \"none\"")
///     .replace("[time]\ndt = 0.01\nsteps = 10\n", "");
/// let case = Case::from_text("t.toml", &fe, &[]).unwrap();
/// let Problem::Transport(spec) = &case.problem else { panic!() };
/// assert_eq!(spec.stabilisation.name(), "none");
/// ```
#[derive(Clone, Debug)]
pub struct TransportSpec {
    /// `problem.method`: "fv" (cell-centred, upwind or limited) or "fe"
    /// (nodal, Galerkin or SUPG).
    pub method: Method,
    /// `problem.stabilisation` of `method = "fe"`: "supg" (default) or
    /// "none".
    pub stabilisation: Stabilisation,
    /// `problem.conductivity` (default 1); `None` when it is the number
    /// 0: pure advection.
    pub conductivity: Option<Coefficient>,
    /// `problem.velocity`: one expression per coordinate of the mesh.
    pub velocity: Vec<Expression>,
    /// `problem.source` (default 0).
    pub source: Expression,
    /// Dirichlet (required on inflow faces), Neumann or Robin (diffusion
    /// only).
    pub boundary: Vec<BoundarySpec>,
    /// `problem.scheme`: "upwind" (default) or "limited" (transient only).
    pub scheme: Scheme,
    /// `problem.initial`: u at t = 0 (transient runs).
    pub initial: Option<Expression>,
    /// `[time]`: present for a transient run.
    pub time: Option<TimeSpec>,
}
