//! The specification of a `kind = "growth"` case.

use super::expr::Expression;
use super::{BoundarySpec, Coefficient, TimeSpec};
use crate::metric::Method;
use crate::refine::growth::DivisionRule;

/// A growing, dividing tissue with a morphogen that diffuses and decays
/// on it (`kind = "growth"`, see [`crate::refine::growth`]): the vertices
/// move with `[growth] velocity`, top cells larger than
/// `[growth] divide_above` divide by `[growth] rule`, and the morphogen
/// takes one backward-Euler step of ∂c/∂t − ∇·(K∇c) + λc = f per `[time]`
/// step on cell unknowns (`fv` or `fv-mimetic`).
///
/// ```
/// use hasse_solver::frontend::case::{Case, Problem};
/// use hasse_solver::refine::growth::DivisionRule;
/// let text = r#"
/// [mesh]
/// generator = "interval"
/// n = [8]
/// [problem]
/// kind = "growth"
/// method = "fv"
/// decay = 0.5
/// initial = "1"
/// [growth]
/// velocity = ["0.2*x"]
/// divide_above = 0.2
/// [time]
/// dt = 0.1
/// end = 1.0
/// "#;
/// let case = Case::from_text("g.toml", text, &[]).unwrap();
/// let Problem::Growth(spec) = &case.problem else { panic!() };
/// assert_eq!((spec.decay, spec.divide_above, spec.time.steps), (0.5, 0.2, 10));
/// assert_eq!(spec.rule, None); // chosen by the mesh's dimension
/// let bad = Case::from_text("g.toml", &text.replace("0.2\n[time]", "-1\n[time]"), &[]).unwrap_err();
/// assert!(bad.to_string().contains("growth.divide_above"));
/// ```
#[derive(Clone, Debug)]
pub struct GrowthSpec {
    /// `problem.method`: "fv" or "fv-mimetic".
    pub method: Method,
    /// `problem.conductivity` (default 1), constant in time.
    pub conductivity: Coefficient,
    /// `problem.decay`: λ ≥ 0 (default 0).
    pub decay: f64,
    /// `problem.source`: f(x, t) (default 0).
    pub source: Expression,
    /// `problem.initial`: c(x) at t₀.
    pub initial: Expression,
    /// `[[boundary]]` conditions (none: no flux).
    pub boundary: Vec<BoundarySpec>,
    /// `growth.velocity`: v(x, t), one expression per coordinate.
    pub velocity: Vec<Expression>,
    /// `growth.divide_above`: the measure above which a cell divides.
    pub divide_above: f64,
    /// `growth.rule`; `None`: midpoint in 1D, longest axis in 2D.
    pub rule: Option<DivisionRule>,
    /// `[time]` (backward Euler, constant steps).
    pub time: TimeSpec,
}

impl GrowthSpec {
    /// The rule for a complex of dimension `dim`: the given one, or the
    /// default of the dimension.
    pub fn rule_for(&self, dim: usize) -> DivisionRule {
        match (self.rule, dim) {
            (Some(rule), _) => rule,
            (None, 1) => DivisionRule::Midpoint,
            (None, _) => DivisionRule::LongestAxis,
        }
    }
}
