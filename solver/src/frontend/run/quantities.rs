//! The global balance of a diffusion run and its quantities of interest
//! (`[[output.quantity]]`), from the method's own discrete fluxes
//! ([`Diffusion::boundary_outflow`]) and its representation of u.

use crate::frontend::case::{Case, QuantityKind, QuantitySpec};
use crate::metric::Location;
use crate::physics::diffusion::{Diffusion, DiffusionError, Solution};
use hasse_complex::Complex;
use serde_json::{json, Value};

/// What the summary prints and the report stores.
pub(super) struct Quantities {
    /// Summary lines (label, text).
    pub notes: Vec<(String, String)>,
    /// `balance` and `quantities` of the run report.
    pub report: serde_json::Map<String, Value>,
    /// What the summary's warnings add (fluxes that left vertices out).
    pub warnings: Vec<String>,
}

/// The balance Σ outflow = ∫f and every quantity of the case, from the
/// solution's `outflow` ([`Diffusion::boundary_outflow`]).
pub(super) fn diffusion_quantities(
    case: &Case,
    problem: &Diffusion,
    complex: &Complex,
    solution: &Solution,
    outflow: &[f64],
) -> Result<Quantities, DiffusionError> {
    let sources = problem.source_total(complex)?;
    let total: f64 = outflow.iter().sum();
    let scale = outflow
        .iter()
        .map(|q| q.abs())
        .sum::<f64>()
        .max(sources.abs());
    let imbalance = total - sources;
    let relative = if scale > 0.0 {
        imbalance.abs() / scale
    } else {
        0.0
    };
    let mut notes = vec![(
        "balance".to_string(),
        format!(
            "outflow {total:.6e} − sources {sources:.6e} = {imbalance:.2e}, {relative:.1e} of the boundary and source terms (the method's own fluxes)"
        ),
    )];
    let mut report = serde_json::Map::new();
    report.insert(
        "balance".into(),
        json!({ "outflow": total, "sources": sources, "imbalance": imbalance, "relative": relative }),
    );
    let fluxes = flux_values(case, problem, complex, solution, outflow)?;
    let warnings = fluxes.warnings(case, complex);
    let mut entries = Vec::new();
    for (i, q) in case.output.quantities.iter().enumerate() {
        let value = match q.kind {
            QuantityKind::Flux => fluxes.values[i],
            kind => region_statistic(kind, q, complex, solution.field(complex), solution.location),
        };
        notes.push(("quantity".into(), format!("{} = {value:e}", q.name)));
        let mut entry = quantity_json(q, value);
        if !fluxes.left_out[i].is_empty() {
            if let Value::Object(map) = &mut entry {
                map.insert("left_out_vertices".into(), json!(fluxes.left_out[i]));
            }
        }
        entries.push(entry);
    }
    if !entries.is_empty() {
        report.insert("quantities".into(), Value::Array(entries));
    }
    Ok(Quantities {
        notes,
        report,
        warnings,
    })
}

/// The value of every `type = "flux"` quantity (NaN for the others): the
/// outflow through the faces of its tag that bound the domain plus the
/// flux along their orientation through the inner ones, the method's own
/// ([`Diffusion::flux_across`]), and the vertices a nodal method left out.
pub(super) struct LevelFluxes {
    pub values: Vec<f64>,
    pub left_out: Vec<Vec<usize>>,
}

impl LevelFluxes {
    /// A warning for every flux whose tag ends inside the domain, where a
    /// nodal method leaves the end vertices out.
    pub fn warnings(&self, case: &Case, complex: &Complex) -> Vec<String> {
        let mut warnings = Vec::new();
        for (q, left_out) in case.output.quantities.iter().zip(&self.left_out) {
            let Some(&v) = left_out.first() else {
                continue;
            };
            let (count, more) = match left_out.len() {
                1 => ("its end vertex".to_string(), ""),
                k => (format!("its {k} end vertices"), ", …"),
            };
            warnings.push(format!(
                "{}: the faces of `{}` end inside the domain; the flux near {count} (at {:?}{more}) is not counted, an O(h) part of it",
                q.name,
                q.tag.as_deref().unwrap_or_default(),
                complex.vertices().point(v),
            ));
        }
        warnings
    }
}

/// [`LevelFluxes`] of a solution whose boundary outflow is `outflow`.
pub(super) fn flux_values(
    case: &Case,
    problem: &Diffusion,
    complex: &Complex,
    solution: &Solution,
    outflow: &[f64],
) -> Result<LevelFluxes, DiffusionError> {
    let count = case.output.quantities.len();
    let mut fluxes = LevelFluxes {
        values: vec![f64::NAN; count],
        left_out: vec![Vec::new(); count],
    };
    for (i, q) in case.output.quantities.iter().enumerate() {
        if q.kind != QuantityKind::Flux {
            continue;
        }
        let tag = q.tag.as_deref().and_then(|t| complex.tag(t));
        let faces = tag.map_or(&[][..], |t| &t.cells[..]);
        let across = problem.flux_across(complex, solution, outflow, faces)?;
        fluxes.values[i] = across.flux.iter().sum();
        fluxes.left_out[i] = across.left_out;
    }
    Ok(fluxes)
}

/// The quantities of a heat run at one saved level, one value per
/// quantity; fluxes from `fluxes` (computed when the case asks for one).
pub(super) fn level_values(
    case: &Case,
    complex: &Complex,
    field: &[f64],
    location: Location,
    fluxes: Option<&LevelFluxes>,
) -> Vec<f64> {
    case.output
        .quantities
        .iter()
        .enumerate()
        .map(|(i, q)| match (q.kind, fluxes) {
            (QuantityKind::Flux, Some(f)) => f.values[i],
            (QuantityKind::Flux, None) => f64::NAN,
            (kind, _) => region_statistic(kind, q, complex, field, location),
        })
        .collect()
}

/// The report entry and the summary lines of heat quantities over the
/// saved levels.
pub(super) fn heat_quantities(case: &Case, times: &[f64], values: &[Vec<f64>]) -> Quantities {
    let mut notes = Vec::new();
    let mut entries = Vec::new();
    for (i, q) in case.output.quantities.iter().enumerate() {
        let series: Vec<f64> = values.iter().map(|level| level[i]).collect();
        if let (Some(&t), Some(&last)) = (times.last(), series.last()) {
            notes.push((
                "quantity".to_string(),
                format!(
                    "{} = {last:.9e} at t = {t} (every saved level in the report and the CSV)",
                    q.name
                ),
            ));
        }
        let mut entry = quantity_json(q, series.last().copied().unwrap_or(f64::NAN));
        entry["times"] = json!(times);
        entry["values"] = Value::Array(
            series
                .iter()
                .map(|v| if v.is_finite() { json!(v) } else { Value::Null })
                .collect(),
        );
        entries.push(entry);
    }
    let mut report = serde_json::Map::new();
    if !entries.is_empty() {
        report.insert("quantities".into(), Value::Array(entries));
    }
    Quantities {
        notes,
        report,
        warnings: Vec::new(),
    }
}

/// The CSV time history of a report's quantities (`t` and one column per
/// quantity), or `None` when they have no history (steady runs).
pub fn quantities_csv(report: &Value) -> Option<String> {
    let quantities = report.get("quantities")?.as_array()?;
    let times = quantities.first()?.get("times")?.as_array()?;
    let mut text = String::from("t");
    for q in quantities {
        let name = q["name"].as_str().unwrap_or("quantity").replace('"', "'");
        text.push_str(&format!(",\"{name}\""));
    }
    text.push('\n');
    for (k, t) in times.iter().enumerate() {
        text.push_str(&format!("{}", t.as_f64().unwrap_or(f64::NAN)));
        for q in quantities {
            let v = q["values"][k].as_f64().unwrap_or(f64::NAN);
            text.push_str(&format!(",{v:e}"));
        }
        text.push('\n');
    }
    Some(text)
}

/// Write the CSV time history of a report's quantities to
/// `<stem>.quantities.csv` (atomically), when they have one.
pub fn write_quantities_csv(
    stem: &std::path::Path,
    report: &Value,
) -> Result<Option<std::path::PathBuf>, crate::frontend::output::OutputError> {
    quantities_csv(report)
        .map(|text| super::probes::write_beside(stem, "quantities.csv", &text))
        .transpose()
}

fn quantity_json(q: &QuantitySpec, value: f64) -> Value {
    let mut entry = serde_json::Map::new();
    entry.insert("name".into(), json!(q.name));
    entry.insert("type".into(), json!(q.kind.name()));
    if let Some(tag) = &q.tag {
        entry.insert("tag".into(), json!(tag));
    }
    if let Some(region) = &q.region {
        entry.insert("region".into(), json!(region));
    }
    // JSON has no NaN: a value that is not finite is stored as null.
    entry.insert(
        "value".into(),
        if value.is_finite() {
            json!(value)
        } else {
            Value::Null
        },
    );
    Value::Object(entry)
}

/// ∫u, its mean, min or max over the region's top cells (all of them
/// without a region): cell values times measures for cell-centred and
/// hybrid methods; for nodal ones the mean of the cell's vertex values
/// times its measure (exact for P1 simplices and Q1 parallelograms) and
/// the extremes over the vertices, where P1 and Q1 fields take them.
pub(super) fn region_statistic(
    kind: QuantityKind,
    q: &QuantitySpec,
    complex: &Complex,
    field: &[f64],
    location: Location,
) -> f64 {
    let n = complex.dim();
    let cells: Vec<usize> = match q.region.as_deref().and_then(|r| complex.tag(r)) {
        Some(tag) => tag.cells.clone(),
        None => (0..complex.cell_count(n)).collect(),
    };
    let measure = complex.measure(n);
    let (integral, volume, values): (f64, f64, Vec<f64>) = match location {
        Location::Nodal => {
            let mut seen = vec![false; complex.cell_count(0)];
            let mut values = Vec::new();
            let mut integral = 0.0;
            for &c in &cells {
                let vertices = complex.cell_vertices(n, c);
                let mean = vertices.iter().map(|&v| field[v]).sum::<f64>() / vertices.len() as f64;
                integral += mean * measure[c];
                for &v in vertices {
                    if !std::mem::replace(&mut seen[v], true) {
                        values.push(field[v]);
                    }
                }
            }
            let volume = cells.iter().map(|&c| measure[c]).sum();
            (integral, volume, values)
        }
        _ => (
            cells.iter().map(|&c| field[c] * measure[c]).sum(),
            cells.iter().map(|&c| measure[c]).sum(),
            cells.iter().map(|&c| field[c]).collect(),
        ),
    };
    match kind {
        QuantityKind::Integral => integral,
        QuantityKind::Mean => integral / volume,
        QuantityKind::Min => values.iter().copied().fold(f64::INFINITY, f64::min),
        QuantityKind::Max => values.iter().copied().fold(f64::NEG_INFINITY, f64::max),
        QuantityKind::Flux => f64::NAN,
    }
}
