//! Why a run failed after its case was read: the library's typed error,
//! the case key it concerns (with the line and column where the key is
//! written, or the `--set` text that gave it) and the point or cell, and
//! whether the input or the numerics are at fault.
//!
//! ```
//! use hasse_solver::frontend::{case::Case, run};
//! let text = "[mesh]\ngenerator = \"rectangle\"\nn = [4, 4]\n\n[problem]\nmethod = \"fv\"\nsource = \"ln(x - 0.5)\"\n";
//! let case = Case::from_text("log.toml", text, &[]).unwrap();
//! let complex = case.build_mesh().unwrap();
//! let error = run::solve(&case, &complex, &mut |_| {}).unwrap_err();
//! assert!(error.is_input());
//! // The line and column of `source`, its key, what and where.
//! assert!(error.to_string().starts_with("log.toml:7:10: `problem.source`: the source is not finite (NaN) at (0.125, 0.125)"));
//! ```

use crate::frontend::case::{BoundarySpec, Case, Diagnostic};
use crate::physics::coupled::CoupledError;
use crate::physics::darcy::DarcyError;
use crate::physics::diffusion::DiffusionError;
use crate::physics::elasticity::ElasticityError;
use crate::physics::gradient::GradientError;
use crate::physics::heat::HeatError;
use crate::physics::maxwell::MaxwellError;
use crate::physics::nonlinear::NonlinearError;
use crate::physics::{Datum, TagError};
use crate::refine::RefineError;
use std::fmt;

/// The library error behind a [`RunError`].
#[derive(Debug)]
pub enum Failure {
    /// A diffusion problem (also each field of a coupled one).
    Diffusion(DiffusionError),
    /// Transient heat.
    Heat(HeatError),
    /// Mixed Darcy flow.
    Darcy(DarcyError),
    /// A Maxwell cavity.
    Maxwell(MaxwellError),
    /// A Hodge Laplacian.
    Forms(crate::physics::forms::FormsError),
    /// Linear elasticity.
    Elasticity(ElasticityError),
    /// Two coupled fields.
    Coupled(CoupledError),
    /// A normal gradient.
    Gradient(GradientError),
    /// A refinement study.
    Refine(RefineError),
    /// Nonlinear diffusion (Newton or Picard).
    Nonlinear(NonlinearError),
    /// Advection–diffusion.
    Transport(crate::physics::transport::TransportError),
}

impl Failure {
    fn as_error(&self) -> &(dyn std::error::Error + 'static) {
        match self {
            Failure::Diffusion(e) => e,
            Failure::Heat(e) => e,
            Failure::Darcy(e) => e,
            Failure::Maxwell(e) => e,
            Failure::Forms(e) => e,
            Failure::Elasticity(e) => e,
            Failure::Coupled(e) => e,
            Failure::Gradient(e) => e,
            Failure::Refine(e) => e,
            Failure::Nonlinear(e) => e,
            Failure::Transport(e) => e,
        }
    }
}

macro_rules! failure_from {
    ($($error:ty => $variant:ident),*) => {$(
        impl From<$error> for Failure {
            fn from(error: $error) -> Self {
                Failure::$variant(error)
            }
        }
    )*};
}

failure_from!(
    crate::physics::forms::FormsError => Forms,
    DiffusionError => Diffusion,
    HeatError => Heat,
    DarcyError => Darcy,
    MaxwellError => Maxwell,
    ElasticityError => Elasticity,
    CoupledError => Coupled,
    GradientError => Gradient,
    RefineError => Refine,
    NonlinearError => Nonlinear,
    crate::physics::transport::TransportError => Transport
);

/// Why a run failed after the case was read: bad input found while
/// evaluating or assembling (exit code 2), or a solve that failed or is
/// not trustworthy (exit code 1). It prints as a diagnostic of the case:
/// `file:line:col: `key`: message` and a hint.
#[derive(Debug)]
pub struct RunError(Box<Inner>);

/// A [`RunError`]'s parts, boxed: errors travel through every `Result` of
/// a run, which should stay small.
#[derive(Debug)]
struct Inner {
    input: bool,
    diagnostic: Diagnostic,
    failure: Option<Failure>,
}

impl RunError {
    /// Bad input at key `key` of `case` (`""`: the case as a whole).
    pub(crate) fn input_at(
        case: &Case,
        key: &str,
        message: impl Into<String>,
        help: Option<String>,
    ) -> Self {
        Self(Box::new(Inner {
            input: true,
            diagnostic: case.diagnostic(key, message, help),
            failure: None,
        }))
    }

    /// Bad input that no single key holds (the mesh and the data
    /// together, e.g. a part of the domain without a Dirichlet boundary).
    pub(crate) fn input(case: &Case, message: impl Into<String>) -> Self {
        Self::input_at(case, "", message, None)
    }

    /// A solve that failed or is not trustworthy.
    pub(crate) fn solve(case: &Case, message: impl Into<String>, help: Option<String>) -> Self {
        Self(Box::new(Inner {
            input: false,
            diagnostic: case.diagnostic("", message, help),
            failure: None,
        }))
    }

    /// The same error, caused by the library error `failure`.
    pub(crate) fn because(mut self, failure: impl Into<Failure>) -> Self {
        self.0.failure = Some(failure.into());
        self
    }

    /// Whether the user's input is at fault (as opposed to the numerics).
    pub fn is_input(&self) -> bool {
        self.0.input
    }

    /// Where in the case the error points, what it says and how to fix it.
    pub fn diagnostic(&self) -> &Diagnostic {
        &self.0.diagnostic
    }

    /// The library error behind this one, if any.
    pub fn failure(&self) -> Option<&Failure> {
        self.0.failure.as_ref()
    }
}

impl fmt::Display for RunError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        self.0.diagnostic.fmt(f)
    }
}

impl std::error::Error for RunError {
    fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
        self.0.failure.as_ref().map(Failure::as_error)
    }
}

/// The keys of a scalar problem's data in its case: `prefix.source`,
/// `prefix.<coefficient>`, `prefix.initial` and the boundary conditions'
/// own keys (`boundary[k]`, `field[i].boundary[k]`).
pub(crate) struct Keys<'a> {
    /// `problem` or `field[i]`.
    pub prefix: String,
    /// `conductivity` or `permeability`.
    pub coefficient: &'static str,
    pub boundary: &'a [BoundarySpec],
}

impl Keys<'_> {
    /// The key that holds `datum`.
    pub fn of(&self, datum: Datum) -> String {
        let boundary = |k: usize, part: &str| match self.boundary.get(k) {
            Some(b) => format!("{}.{part}", b.key),
            None => format!("boundary[{k}].{part}"),
        };
        match datum {
            Datum::Source => format!("{}.source", self.prefix),
            Datum::Coefficient => format!("{}.{}", self.prefix, self.coefficient),
            Datum::Initial => format!("{}.initial", self.prefix),
            Datum::BoundaryValue { condition, .. } => boundary(condition, "value"),
            Datum::RobinAlpha { condition } => boundary(condition, "alpha"),
            Datum::Parameter(name) => format!("{}.{name}", self.prefix),
            Datum::BodyForce => format!("{}.body_force", self.prefix),
        }
    }

    /// The key of the boundary condition on tag `tag`.
    fn tag(&self, tag: &str) -> String {
        self.boundary
            .iter()
            .find(|b| b.tag == tag)
            .map_or_else(|| "boundary".into(), |b| format!("{}.tag", b.key))
    }
}

/// What to check in a given function that was not finite somewhere.
pub(crate) const FINITE_HELP: &str =
    "the expression must be finite wherever the method evaluates it (cell centroids, vertices or quadrature points): check divisions, square roots and logarithms there";

/// A diffusion problem's error in the terms of its case: located at the
/// key of the datum it concerns, input or solve failure as the error is.
pub(crate) fn diffusion_error(case: &Case, keys: &Keys, error: DiffusionError) -> RunError {
    let message = error.to_string();
    let at = |key: &str, help: Option<String>| RunError::input_at(case, key, &message, help);
    let method = format!("{}.method", keys.prefix);
    let located = match &error {
        DiffusionError::NonFinite { datum, .. } => at(&keys.of(*datum), Some(FINITE_HELP.into())),
        DiffusionError::Coefficient { .. } => at(
            &keys.of(Datum::Coefficient),
            Some(format!(
                "the {} must be finite and positive (a tensor: symmetric positive definite) in every cell",
                keys.coefficient
            )),
        ),
        DiffusionError::RobinAlpha { condition, .. } => at(
            &keys.of(Datum::RobinAlpha {
                condition: *condition,
            }),
            Some("α must be positive: K∇u·n + α u = g with α ≤ 0 is not a Robin condition".into()),
        ),
        DiffusionError::Tag(tag) => {
            let key = match tag {
                TagError::UnknownTag { tag, .. }
                | TagError::TagDimension { tag, .. }
                | TagError::InteriorFace { tag, .. } => keys.tag(tag),
            };
            at(&key, None)
        }
        DiffusionError::NotSymmetric { .. } | DiffusionError::Unsupported { .. } => {
            at(&method, None)
        }
        // Regions are checked against the mesh when it is built, so this
        // is reached only by a mesh changed afterwards.
        DiffusionError::Region(_) => at(
            &format!("{}.{}", keys.prefix, keys.coefficient),
            Some("regions are tags of top cells; add `default = …` for the cells in none".into()),
        ),
        DiffusionError::Metric(_) => at(
            &method,
            Some("choose a method that supports this mesh (fe and fv-mimetic take any convex cells)".into()),
        ),
        DiffusionError::IncompatibleNeumann { .. } => RunError::input_at(
            case,
            "problem.neumann",
            &message,
            Some("make the data balance, or let hasse project the imbalance away: `neumann = \"project\"`, or a larger `neumann_tolerance` in [problem]".into()),
        ),
        DiffusionError::Disconnected { .. }
        | DiffusionError::FloatingPart { .. }
        | DiffusionError::Multigrid(_) => RunError::input(case, &message),
        DiffusionError::Canonical(_) | DiffusionError::Solve(_) | DiffusionError::Iterative(_) => {
            RunError::solve(case, &message, None)
        }
    };
    located.because(error)
}
