//! `[[output.probe]]`: the solution at points and along lines, as the
//! method represents it ([`crate::physics::probe`]), printed, stored in
//! the run report and written as `<stem>.probes.csv`.

use crate::frontend::case::Case;
use crate::metric::Location;
use crate::physics::diffusion::gradient_of;
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
/// `t` column for transient runs (one row per time, probe and point).
pub fn probes_csv(report: &Value) -> Option<String> {
    let probes = report.get("probes")?.as_array()?;
    let transient = probes.first()?.get("times").is_some();
    let d = probes.first()?["points"][0].as_array()?.len();
    let axes = ["x", "y", "z"];
    let mut text = String::new();
    if transient {
        text.push_str("t,");
    }
    text.push_str("probe,point,");
    text.push_str(&axes[..d].join(","));
    text.push_str(",u\n");
    let row =
        |text: &mut String, t: Option<f64>, name: &str, k: usize, point: &Value, u: &Value| {
            if let Some(t) = t {
                text.push_str(&format!("{t},"));
            }
            text.push_str(&format!("\"{}\",{k}", name.replace('"', "'")));
            for a in 0..d {
                text.push_str(&format!(",{}", point[a].as_f64().unwrap_or(f64::NAN)));
            }
            text.push_str(&format!(",{:e}\n", u.as_f64().unwrap_or(f64::NAN)));
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
