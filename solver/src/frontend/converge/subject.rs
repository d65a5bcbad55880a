//! What a study solves and measures: the problem kinds a study accepts,
//! the refinements each can take, the methods it compares, and the errors
//! each run reports.

use super::{levels, StudyError};
use crate::frontend::case::{Case, Problem};
use crate::frontend::run::RunResult;
use crate::metric::Method;
use crate::study::Refinement;

/// The kinds of problem a study measures.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Kind {
    /// Steady diffusion: the L², H¹ and max errors of each method.
    Diffusion,
    /// Transient heat: the errors at the last step (sampled at the
    /// unknowns' points).
    Heat,
    /// Mixed Darcy: pressure errors at the cell points and the flux error.
    Darcy,
    /// Two coupled fields: each field's errors at the unknowns' points, a
    /// row of its own.
    Coupled,
    /// The Poisson problem for k-forms: the star-norm error of the cochain
    /// and its largest value per cell measure.
    Forms,
}

/// One row's errors.
pub(super) struct LevelErrors {
    pub l2: f64,
    pub max: f64,
    pub gradient_l2: Option<f64>,
}

/// The case a study runs, checked against the study before any solve.
pub(super) struct Subject {
    kind: Kind,
    /// The case's own method, as `problem.method` names it (coupled:
    /// `fe/fe`, the fields' methods).
    pub own: String,
    /// Coupled fields that have an exact solution: (name, method).
    fields: Vec<(String, String)>,
}

impl Subject {
    /// Check that `base` can be studied with `refinement` and `methods`:
    /// a kind the study measures, an exact solution, a mesh or time step
    /// the refinement can refine (every level's overrides are computed
    /// here, so that an overflowing level is refused before level 0 is
    /// solved).
    pub fn of(
        file: &str,
        base: &Case,
        refinement: Refinement,
        levels: usize,
        methods: &[Method],
    ) -> Result<Self, StudyError> {
        let case = || file.to_string();
        let (kind, own, fields) = match &base.problem {
            Problem::Diffusion(d) => (Kind::Diffusion, d.method.name().to_string(), vec![]),
            Problem::Heat(h) => (Kind::Heat, h.method.name().to_string(), vec![]),
            Problem::Darcy(d) => (Kind::Darcy, d.mass.name().to_string(), vec![]),
            Problem::FormDiffusion(d) => (Kind::Forms, d.method.name().to_string(), vec![]),
            Problem::Coupled(c) => {
                let own = format!(
                    "{}/{}",
                    c.fields[0].diffusion.method.name(),
                    c.fields[1].diffusion.method.name()
                );
                let fields = c
                    .fields
                    .iter()
                    .filter(|f| f.exact.is_some())
                    .map(|f| (f.name.clone(), f.diffusion.method.name().to_string()))
                    .collect();
                (Kind::Coupled, own, fields)
            }
            other => {
                return Err(StudyError::Unsupported {
                    case: case(),
                    kind: other.kind(),
                })
            }
        };
        // Darcy's methods (flux masses), a coupled case's per-field
        // methods and the stars of k-forms are not the diffusion methods
        // `--methods` names.
        if !methods.is_empty() && matches!(kind, Kind::Darcy | Kind::Coupled | Kind::Forms) {
            return Err(StudyError::MethodsNotApplicable {
                case: case(),
                kind: base.problem.kind(),
            });
        }
        match kind {
            Kind::Coupled if fields.is_empty() => {
                return Err(StudyError::NoFieldExact { case: case() })
            }
            Kind::Coupled => {}
            Kind::Forms if base.exact.as_ref().and_then(|e| e.form.as_ref()).is_none() => {
                return Err(StudyError::NoExact { case: case() })
            }
            Kind::Forms => {}
            _ if base
                .exact
                .as_ref()
                .and_then(|e| e.solution.as_ref())
                .is_none() =>
            {
                return Err(StudyError::NoExact { case: case() })
            }
            _ => {}
        }
        if levels > 0 {
            let last = levels - 1;
            match (refinement, &base.problem) {
                (Refinement::Time, Problem::Heat(h)) => {
                    levels::time_overrides(file, &h.time, last)?;
                }
                (Refinement::Time, other) => {
                    return Err(StudyError::NotTransient {
                        case: case(),
                        kind: other.kind(),
                    })
                }
                (Refinement::Uniform, _) => {
                    levels::uniform_overrides(file, &base.mesh, last)?;
                }
                (Refinement::Split, _) => {}
            }
        }
        Ok(Subject { kind, own, fields })
    }

    /// The methods solved: those asked for, or the case's own.
    pub fn methods(&self, requested: &[Method]) -> Vec<String> {
        if requested.is_empty() {
            vec![self.own.clone()]
        } else {
            requested.iter().map(|m| m.name().to_string()).collect()
        }
    }

    /// Whether each level's cases take `problem.method` from the study.
    pub fn sets_method(&self) -> bool {
        matches!(self.kind, Kind::Diffusion | Kind::Heat | Kind::Darcy)
    }

    /// The rows of one run: (row name, errors). One row named after the
    /// method, or one per coupled field with an exact solution, named
    /// `FIELD (METHOD)`.
    pub fn errors(
        &self,
        file: &str,
        method: &str,
        result: &RunResult,
    ) -> Result<Vec<(String, LevelErrors)>, StudyError> {
        let missing = || StudyError::NoExact {
            case: file.to_string(),
        };
        if self.kind != Kind::Coupled {
            let e = result.errors.as_ref().ok_or_else(missing)?;
            return Ok(vec![(
                method.to_string(),
                LevelErrors {
                    l2: e.l2,
                    max: e.max,
                    gradient_l2: e.gradient_l2.is_finite().then_some(e.gradient_l2),
                },
            )]);
        }
        // The coupled run reports each field's errors (L² with the
        // lumped or cell-volume weights, max at the unknowns) in its
        // report, under `errors_FIELD`.
        self.fields
            .iter()
            .map(|(name, field_method)| {
                let entry = result.report.get(&format!("errors_{name}"));
                let get = |key: &str| entry.and_then(|e| e.get(key)).and_then(|v| v.as_f64());
                match (get("l2"), get("max")) {
                    (Some(l2), Some(max)) => Ok((
                        format!("{name} ({field_method})"),
                        LevelErrors {
                            l2,
                            max,
                            gradient_l2: None,
                        },
                    )),
                    _ => Err(missing()),
                }
            })
            .collect()
    }
}
