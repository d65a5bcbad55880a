//! Reading `kind = "growth"`: a growing, dividing tissue (`[growth]`)
//! with a morphogen stepped by backward Euler (`[problem]`, `[time]`).

use super::kinds::Conditions;
use super::Reader;
use crate::frontend::case::expr::Scope;
use crate::frontend::case::{Coefficient, GrowthSpec, Problem};
use crate::metric::Method;
use crate::refine::growth::DivisionRule;
use std::ops::Range;
use toml_edit::TableLike;

/// The keys of `[growth]`.
pub(super) const GROWTH_KEYS: &[&str] = &["velocity", "divide_above", "rule"];

/// Every rule by its case-file name.
const RULES: [DivisionRule; 3] = [
    DivisionRule::Midpoint,
    DivisionRule::LongestAxis,
    DivisionRule::ShortestWall,
];

impl Reader {
    pub(super) fn growth(
        &mut self,
        root: &dyn TableLike,
        table: &dyn TableLike,
        header: Option<Range<usize>>,
        scope: &Scope,
    ) -> Option<Problem> {
        let span_of = |key: &str| table.get_key_value(key).and_then(|(_, i)| i.span());
        let method = self.method(table, header.clone());
        if let Some(m) = method.filter(|m| !matches!(m, Method::Fv | Method::FvMimetic)) {
            self.error(
                span_of("method"),
                "problem.method",
                format!(
                    "a growing tissue carries the morphogen's amount per cell: method \"{}\" has no cell unknowns to carry it",
                    m.name()
                ),
                Some("use method = \"fv\" (two-point flux) or \"fv-mimetic\" (consistent on the polygons division makes)".into()),
            );
        }
        let conductivity = self.coefficient(table, "conductivity", scope);
        if conductivity.as_ref().is_some_and(Coefficient::uses_time) {
            self.error(
                span_of("conductivity"),
                "problem.conductivity",
                "the conductivity is evaluated at each cell's centroid without t: it may not depend on t",
                Some("the source and the boundary values may depend on t".into()),
            );
        }
        let decay = match self.entry(table, "problem", "decay") {
            None => Some(0.0),
            Some(e) => match self.number(&e) {
                Some(v) if v.is_finite() && v >= 0.0 => Some(v),
                Some(v) => {
                    self.error(
                        e.span(),
                        "problem.decay",
                        format!("the decay rate λ must be finite and ≥ 0, found {v}"),
                        Some("decay = 0 for none".into()),
                    );
                    None
                }
                None => None,
            },
        };
        let source = match self.entry(table, "problem", "source") {
            Some(_) => self.expression_at(table, "problem", "source", scope),
            None => scope.parse("0").ok(),
        };
        if source.as_ref().is_some_and(|f| f.regions().is_some()) {
            self.error(
                span_of("source"),
                "problem.source",
                "values per region are not carried through divisions: give one expression",
                Some("if(…) selects by position".into()),
            );
        }
        let initial = match self.entry(table, "problem", "initial") {
            Some(_) => self.expression_at(table, "problem", "initial", scope),
            None => {
                self.error(
                    header,
                    "problem.initial",
                    "missing: the morphogen's concentration c(x, y) at t₀",
                    Some("e.g. initial = \"exp(-((x - 0.5)^2 + (y - 0.5)^2) / 0.02)\"".into()),
                );
                None
            }
        };
        let boundary = self.boundary(root, scope, Conditions::Transient);
        let growth = self.growth_table(root, scope);
        let time = self.time(root);
        if let Some(time) = &time {
            let time_table = root.get("time").and_then(toml_edit::Item::as_table_like);
            let span = |key: &str| {
                time_table
                    .and_then(|t| t.get_key_value(key))
                    .and_then(|(k, _)| k.span())
            };
            if time.theta != 1.0 {
                let key = if time_table.is_some_and(|t| t.get("scheme").is_some()) {
                    "scheme"
                } else {
                    "theta"
                };
                self.error(
                    span(key),
                    &format!("time.{key}"),
                    "a growing tissue steps by backward Euler (θ = 1): the mesh changes between the levels a θ-scheme would combine",
                    Some(format!("remove time.{key}")),
                );
            }
            if time.adaptive.is_some() {
                self.error(
                    span("adaptive"),
                    "time.adaptive",
                    "a growing tissue takes constant steps: the motion and the divisions happen once a step",
                    Some("remove time.adaptive".into()),
                );
            }
        }
        let (velocity, divide_above, rule) = growth?;
        let method = method.filter(|m| matches!(m, Method::Fv | Method::FvMimetic))?;
        Some(Problem::Growth(GrowthSpec {
            method,
            conductivity: conductivity?,
            decay: decay?,
            source: source.filter(|f| f.regions().is_none())?,
            initial: initial?,
            boundary,
            velocity,
            divide_above,
            rule,
            time: time.filter(|t| t.theta == 1.0 && t.adaptive.is_none())?,
        }))
    }

    /// `[growth]`: velocity, divide_above and rule.
    #[allow(clippy::type_complexity)]
    fn growth_table(
        &mut self,
        root: &dyn TableLike,
        scope: &Scope,
    ) -> Option<(
        Vec<crate::frontend::case::expr::Expression>,
        f64,
        Option<DivisionRule>,
    )> {
        let Some((table, entry)) = self.subtable(root, "", "growth") else {
            if root.get("growth").is_none() {
                self.error(
                    None,
                    "growth",
                    "no [growth] table: a growing tissue needs its velocity and division threshold",
                    Some("add [growth] with `velocity = [\"0.1*x\", \"0.1*y\"]` and `divide_above = 0.02`".into()),
                );
            }
            return None;
        };
        let header = entry.span();
        self.check_keys(table, "growth", GROWTH_KEYS);
        let velocity = match self.entry(table, "growth", "velocity") {
            Some(e) => self.expression_list(&e, scope),
            None => {
                self.error(
                    header.clone(),
                    "growth.velocity",
                    "missing: the growth velocity v(x, t), one expression per coordinate",
                    Some(
                        "e.g. velocity = [\"0.1*x\", \"0.1*y\"] (uniform growth at rate 0.1)"
                            .into(),
                    ),
                );
                None
            }
        };
        let divide_above = match self.entry(table, "growth", "divide_above") {
            None => {
                self.error(
                    header,
                    "growth.divide_above",
                    "missing: the cell measure (length or area) above which a cell divides",
                    Some("e.g. divide_above = 0.02".into()),
                );
                None
            }
            Some(e) => match self.number(&e) {
                Some(v) if v.is_finite() && v > 0.0 => Some(v),
                Some(v) => {
                    self.error(
                        e.span(),
                        "growth.divide_above",
                        format!("the division threshold must be a positive, finite measure, found {v}"),
                        Some("give the length (1D) or area (2D) above which a cell divides, e.g. divide_above = 0.02".into()),
                    );
                    None
                }
                None => None,
            },
        };
        let rule = match table.get("rule") {
            None => Some(None),
            Some(_) => self
                .choice_in(
                    table,
                    "growth",
                    "rule",
                    &RULES,
                    DivisionRule::name,
                    "division rule",
                    None,
                    None,
                )
                .map(Some),
        };
        Some((velocity?, divide_above?, rule?))
    }
}
