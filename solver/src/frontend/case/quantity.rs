//! Quantities of interest (`[[output.quantity]]`): numbers a run computes
//! from its solution and prints, stores in its report and, for heat,
//! records at every saved level.
//!
//! ```
//! use hasse_solver::frontend::case::{Case, QuantityKind};
//! let text = r#"
//! [mesh]
//! generator = "rectangle"
//! n = [4, 4]
//! [problem]
//! method = "fv"
//! [[output.quantity]]
//! type = "flux"
//! tag = "xmin"
//! [[output.quantity]]
//! type = "mean"
//! "#;
//! let case = Case::from_text("q.toml", text, &[]).unwrap();
//! let q = &case.output.quantities;
//! assert_eq!(q[0].kind, QuantityKind::Flux);
//! assert_eq!(q[0].name, "flux through xmin");
//! assert_eq!(q[1].name, "mean of u");
//! ```

/// What a quantity computes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum QuantityKind {
    /// The flux −K∇u·n out of the domain through a boundary tag, or across
    /// an interior tag of (n−1)-cells along the cells' orientation.
    Flux,
    /// ∫ u over a region (or the whole domain).
    Integral,
    /// ∫ u / |region|.
    Mean,
    /// The smallest value of u's representation in the region.
    Min,
    /// The largest value.
    Max,
}

impl QuantityKind {
    /// Every kind, with its case-file spelling.
    pub const ALL: [(QuantityKind, &'static str); 5] = [
        (QuantityKind::Flux, "flux"),
        (QuantityKind::Integral, "integral"),
        (QuantityKind::Mean, "mean"),
        (QuantityKind::Min, "min"),
        (QuantityKind::Max, "max"),
    ];

    /// The case-file spelling.
    pub fn name(self) -> &'static str {
        Self::ALL
            .iter()
            .find(|(k, _)| *k == self)
            .map_or("flux", |(_, n)| n)
    }
}

/// One `[[output.quantity]]` table.
#[derive(Clone, Debug, PartialEq)]
pub struct QuantitySpec {
    /// The label of the summary and the report (`name`, or made from the
    /// type and the tag or region).
    pub name: String,
    /// What it computes (`type`).
    pub kind: QuantityKind,
    /// The tag of (n−1)-cells of a flux.
    pub tag: Option<String>,
    /// The region (tag of top cells) of an integral, mean, min or max;
    /// `None` for the whole domain.
    pub region: Option<String>,
    /// Its key in messages, `output.quantity[i]`.
    pub key: String,
}

/// One `[[output.probe]]` table: a point (`at`) or the points of a line
/// (`from`, `to`, `points`), where the solution is interpolated the way
/// the method represents it.
///
/// ```
/// use hasse_solver::frontend::case::Case;
/// let text = r#"
/// [mesh]
/// generator = "rectangle"
/// n = [4, 4]
/// [problem]
/// method = "fe"
/// [[output.probe]]
/// at = [0.5, 0.25]
/// [[output.probe]]
/// name = "diagonal"
/// from = [0, 0]
/// to = [1, 1]
/// points = 3
/// "#;
/// let probes = Case::from_text("p.toml", text, &[]).unwrap().output.probes;
/// assert_eq!(probes[0].name, "probe-0");
/// assert_eq!(probes[0].points, vec![vec![0.5, 0.25]]);
/// assert_eq!(probes[1].points, vec![vec![0.0, 0.0], vec![0.5, 0.5], vec![1.0, 1.0]]);
/// ```
#[derive(Clone, Debug, PartialEq)]
pub struct ProbeSpec {
    /// The label in the summary and the CSV (`name`, or `probe-<i>`).
    pub name: String,
    /// The points: one for `at`, `points` evenly spaced from `from` to
    /// `to` (both included) for a line.
    pub points: Vec<Vec<f64>>,
    /// Its key in messages, `output.probe[i]`.
    pub key: String,
}
