//! `[[output.probe]]`: the solution at points and along lines, as the
//! method represents it ([`crate::physics::probe`]), printed, stored in
//! the run report and written as `<stem>.probes.csv`. The DEC kinds probe
//! the k-forms they write by their Whitney maps
//! ([`crate::physics::forms::whitney_map::value_in_cell`]).

use super::{RunError, RunResult};
use crate::frontend::case::{Case, Problem};
use crate::frontend::output::Cochain;
use crate::metric::Location;
use crate::physics::diffusion::gradient_of;
use crate::physics::forms::whitney_map::{value_in_cell, Proxy, ProxyKind};
use crate::physics::probe::{value_at, PointLocator};
use hasse_complex::Complex;
use serde_json::{json, Value};

/// Every probe's values in one field: probe by probe, point by point
/// (NaN where a point is outside; the mesh check refuses that before).
pub(super) fn probe_values(
    case: &Case,
    complex: &Complex,
    location: Location,
    values: &[f64],
    cell_points: Option<&[f64]>,
) -> Vec<Vec<f64>> {
    if case.output.probes.is_empty() {
        return Vec::new();
    }
    let Ok(locator) = PointLocator::new(complex) else {
        return case
            .output
            .probes
            .iter()
            .map(|p| vec![f64::NAN; p.points.len()])
            .collect();
    };
    let gradient =
        (location != Location::Nodal).then(|| gradient_of(complex, location, values, cell_points));
    case.output
        .probes
        .iter()
        .map(|probe| {
            probe
                .points
                .iter()
                .map(|x| match locator.locate(x) {
                    Some(c) => value_at(complex, location, values, gradient.as_deref(), c, x),
                    None => f64::NAN,
                })
                .collect()
        })
        .collect()
}

/// The degree of the forms a DEC kind writes and its probes evaluate
/// (`None` for the kinds whose probes are scalar solutions).
pub(crate) fn form_degree(problem: &Problem) -> Option<usize> {
    match problem {
        Problem::Maxwell(_) => Some(1),
        Problem::Decomposition(spec) => Some(spec.degree),
        Problem::FormDiffusion(spec) => Some(spec.degree),
        Problem::Hodge(spec) => Some(spec.degree),
        Problem::Cohomology(spec) => Some(spec.degree),
        _ => None,
    }
}

/// The report columns of a k-form field: its name for a function or a
/// density, `NAME_x`, `NAME_y`(, `NAME_z`) for a vector proxy.
fn form_columns(name: &str, vector: bool, d: usize) -> Vec<String> {
    if vector {
        ["x", "y", "z"][..d]
            .iter()
            .map(|a| format!("{name}_{a}"))
            .collect()
    } else {
        vec![name.to_string()]
    }
}

/// Probe every k-form (every field of degree k) a DEC run wrote, at every
/// probe point, and add the summary lines and the report's `probes`
/// entry (`columns` names the values of each point's row) to `result`.
pub(super) fn attach_form_probes(
    case: &Case,
    complex: &Complex,
    k: usize,
    result: &mut RunResult,
) -> Result<(), RunError> {
    let probes = &case.output.probes;
    if probes.is_empty() {
        return Ok(());
    }
    let key = probes[0].key.as_str();
    let failed = |message: String| RunError::input_at(case, key, message, None);
    let locator = PointLocator::new(complex).map_err(|e| failed(e.to_string()))?;
    let vector = ProxyKind::of(complex, k)
        .map_err(|e| failed(e.to_string()))?
        .is_vector();
    let d = complex.embedding_dim();
    let forms: Vec<&Cochain> = result.fields.iter().filter(|f| f.dim == k).collect();
    let columns: Vec<String> = forms
        .iter()
        .flat_map(|f| form_columns(&f.name, vector, d))
        .collect();
    let mut entries = Vec::new();
    for probe in probes {
        let mut rows = Vec::with_capacity(probe.points.len());
        for x in &probe.points {
            let mut row = Vec::with_capacity(columns.len());
            let cell = locator.locate(x);
            for form in &forms {
                match cell {
                    None => row.extend(std::iter::repeat_n(f64::NAN, if vector { d } else { 1 })),
                    Some(c) => match value_in_cell(complex, k, &form.values, c, x).map_err(|e| {
                        failed(format!("probe `{}` of {}: {e}", probe.name, form.name))
                    })? {
                        Proxy::Scalar(v) => row.push(v),
                        Proxy::Vector(v) => row.extend_from_slice(&v[..d]),
                    },
                }
            }
            rows.push(row);
        }
        let text = match probe.points.as_slice() {
            [p] => {
                const SHOWN: usize = 3;
                let width = if vector { d } else { 1 };
                let mut parts: Vec<String> = forms
                    .iter()
                    .zip(rows[0].chunks(width))
                    .take(SHOWN)
                    .map(|(form, v)| match v {
                        [s] => format!("{} = {s:.6e}", form.name),
                        v => format!(
                            "{} = ({})",
                            form.name,
                            v.iter()
                                .map(|c| format!("{c:.6e}"))
                                .collect::<Vec<_>>()
                                .join(", ")
                        ),
                    })
                    .collect();
                if forms.len() > SHOWN {
                    parts.push(format!(
                        "… {} more in the report and the CSV",
                        forms.len() - SHOWN
                    ));
                }
                format!("{} at {p:?}: {}", probe.name, parts.join(", "))
            }
            points => format!(
                "{}: {} points from {:?} to {:?}, {} {k}-forms (values in the report and the CSV)",
                probe.name,
                points.len(),
                points[0],
                points[points.len() - 1],
                forms.len()
            ),
        };
        result.notes.push(("probe".to_string(), text));
        let values: Vec<Value> = rows
            .iter()
            .map(|row| Value::Array(row.iter().map(|&v| number(v)).collect()))
            .collect();
        entries.push(json!({
            "name": probe.name,
            "points": probe.points,
            "columns": columns,
            "values": values,
        }));
    }
    result.report.insert("probes".into(), Value::Array(entries));
    Ok(())
}

fn number(v: f64) -> Value {
    if v.is_finite() {
        json!(v)
    } else {
        Value::Null
    }
}

/// Summary lines and the report's `probes` entry of values at one or more
/// times (`times` empty for a steady run, which has one level).
pub(super) fn probe_report(
    case: &Case,
    times: &[f64],
    levels: &[Vec<Vec<f64>>],
) -> (Vec<(String, String)>, Option<Value>) {
    let probes = &case.output.probes;
    if probes.is_empty() || levels.is_empty() {
        return (Vec::new(), None);
    }
    let last = &levels[levels.len() - 1];
    let when = times
        .last()
        .map(|t| format!(" at t = {t}"))
        .unwrap_or_default();
    let mut notes = Vec::new();
    let mut entries = Vec::new();
    for (i, probe) in probes.iter().enumerate() {
        let text = match probe.points.as_slice() {
            [p] => format!("{} at {p:?}: u = {:e}{when}", probe.name, last[i][0]),
            points => format!(
                "{}: {} points from {:?} to {:?}{} (values in the report and the CSV)",
                probe.name,
                points.len(),
                points[0],
                points[points.len() - 1],
                if times.is_empty() {
                    String::new()
                } else {
                    " at every saved level".into()
                }
            ),
        };
        notes.push(("probe".to_string(), text));
        let values: Value = if times.is_empty() {
            Value::Array(last[i].iter().map(|&v| number(v)).collect())
        } else {
            Value::Array(
                levels
                    .iter()
                    .map(|level| Value::Array(level[i].iter().map(|&v| number(v)).collect()))
                    .collect(),
            )
        };
        let mut entry = json!({ "name": probe.name, "points": probe.points, "values": values });
        if !times.is_empty() {
            entry["times"] = json!(times);
        }
        entries.push(entry);
    }
    (notes, Some(Value::Array(entries)))
}

/// The report's probes as CSV: `probe,point,x,y[,z],u`, with a leading
/// `t` column for transient runs (one row per time, probe and point); a
/// DEC run's form probes have the report's `columns` in place of `u`.
pub fn probes_csv(report: &Value) -> Option<String> {
    let probes = report.get("probes")?.as_array()?;
    let first = probes.first()?;
    let transient = first.get("times").is_some();
    let d = first["points"][0].as_array()?.len();
    let columns: Vec<&str> = match first.get("columns").and_then(Value::as_array) {
        Some(columns) => columns.iter().filter_map(Value::as_str).collect(),
        None => vec!["u"],
    };
    let axes = ["x", "y", "z"];
    let mut text = String::new();
    if transient {
        text.push_str("t,");
    }
    text.push_str("probe,point,");
    text.push_str(&axes[..d].join(","));
    text.push_str(&format!(",{}\n", columns.join(",")));
    // One value is a scalar solution's; an array is a form probe's row.
    let row =
        |text: &mut String, t: Option<f64>, name: &str, k: usize, point: &Value, u: &Value| {
            if let Some(t) = t {
                text.push_str(&format!("{t},"));
            }
            text.push_str(&format!("\"{}\",{k}", name.replace('"', "'")));
            for a in 0..d {
                text.push_str(&format!(",{}", point[a].as_f64().unwrap_or(f64::NAN)));
            }
            let values = match u.as_array() {
                Some(values) => values.clone(),
                None => vec![u.clone()],
            };
            for v in values {
                text.push_str(&format!(",{:e}", v.as_f64().unwrap_or(f64::NAN)));
            }
            text.push('\n');
        };
    for probe in probes {
        let name = probe["name"].as_str().unwrap_or("probe");
        let points = probe["points"].as_array()?;
        match probe.get("times").and_then(Value::as_array) {
            None => {
                for (k, point) in points.iter().enumerate() {
                    row(&mut text, None, name, k, point, &probe["values"][k]);
                }
            }
            Some(times) => {
                for (level, t) in times.iter().enumerate() {
                    for (k, point) in points.iter().enumerate() {
                        row(
                            &mut text,
                            t.as_f64(),
                            name,
                            k,
                            point,
                            &probe["values"][level][k],
                        );
                    }
                }
            }
        }
    }
    Some(text)
}

/// Write the probes of a report to `<stem>.probes.csv` (atomically), when
/// the case has probes.
pub fn write_probes_csv(
    stem: &std::path::Path,
    report: &Value,
) -> Result<Option<std::path::PathBuf>, crate::frontend::output::OutputError> {
    probes_csv(report)
        .map(|text| write_beside(stem, "probes.csv", &text))
        .transpose()
}

/// Write `text` to `<stem>.<suffix>`, atomically.
pub(super) fn write_beside(
    stem: &std::path::Path,
    suffix: &str,
    text: &str,
) -> Result<std::path::PathBuf, crate::frontend::output::OutputError> {
    use crate::frontend::output::atomic;
    let mut name = stem.file_name().unwrap_or_default().to_os_string();
    name.push(format!(".{suffix}"));
    let path = stem.with_file_name(name);
    atomic::write_atomically(&path, |temporary| atomic::write_text(temporary, text))?;
    Ok(path)
}

/// The CSV tables of a run beside its output: `<stem>.quantities.csv` (a
/// transient run's quantities, level by level) and `<stem>.probes.csv`,
/// each when the report has them; the paths written.
pub fn write_tables(
    stem: &std::path::Path,
    report: &Value,
) -> Result<Vec<std::path::PathBuf>, crate::frontend::output::OutputError> {
    let mut written: Vec<_> = super::write_quantities_csv(stem, report)?
        .into_iter()
        .collect();
    written.extend(write_probes_csv(stem, report)?);
    Ok(written)
}
