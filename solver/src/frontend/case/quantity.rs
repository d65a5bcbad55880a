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
