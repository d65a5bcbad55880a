//! Running a gradient case: the cell field sampled at the centroids and
//! its normal gradient Ω δ f on the faces ([`crate::physics::gradient`]).

use super::*;

/// Read a metric file: `row column value` per line, `#` comments.
fn read_metric_file(
    case: &Case,
    path: &PathBuf,
    faces: usize,
) -> Result<Vec<(usize, usize, f64)>, RunError> {
    const KEY: &str = "problem.metric.file";
    let text = std::fs::read_to_string(path).map_err(|e| {
        RunError::input_at(
            case,
            KEY,
            format!("cannot read the metric file {}: {e}", path.display()),
            Some("metric file paths are relative to the case file's directory".into()),
        )
    })?;
    let mut entries = Vec::new();
    for (number, line) in text.lines().enumerate() {
        let line = line.split('#').next().unwrap_or("").trim();
        if line.is_empty() {
            continue;
        }
        let bad = |what: String| {
            RunError::input_at(
                case,
                KEY,
                format!("{}:{}: {what}", path.display(), number + 1),
                Some("each line of a metric file is `row column value` (face ids from 0); `#` starts a comment".into()),
            )
        };
        let parts: Vec<&str> = line.split_whitespace().collect();
        if parts.len() != 3 {
            return Err(bad(format!(
                "expected `row column value`, found {} fields",
                parts.len()
            )));
        }
        let index = |s: &str| -> Result<usize, RunError> {
            let i: usize = s
                .parse()
                .map_err(|_| bad(format!("`{s}` is not a face index")))?;
            if i >= faces {
                return Err(bad(format!(
                    "face {i} does not exist (the mesh has {faces} faces, numbered from 0)"
                )));
            }
            Ok(i)
        };
        let value: f64 = parts[2]
            .parse()
            .map_err(|_| bad(format!("`{}` is not a number", parts[2])))?;
        if !value.is_finite() {
            return Err(bad(format!("value {value} is not finite")));
        }
        entries.push((index(parts[0])?, index(parts[1])?, value));
    }
    Ok(entries)
}

/// g = −Ω ∂_nᵀ f: for an interior face F between cells c₁ (F oriented
/// outward of c₁) and c₂, (∂_nᵀ f)_F = f(c₁) − f(c₂), so −∂_nᵀ f is the
/// jump of f along F's normal and g approximates ∇f·n_F once Ω carries
/// 1/distance. Boundary faces (one cell) get no row: g = 0 there.
/// The field evaluated at the centroids, without the gradient.
pub(super) fn check(case: &Case, spec: &GradientSpec, complex: &Complex) -> Result<(), RunError> {
    sampled(case, spec, complex).map(|_| ())
}

/// The field at every top-cell centroid, each value finite.
fn sampled(case: &Case, spec: &GradientSpec, complex: &Complex) -> Result<Vec<f64>, RunError> {
    let n = complex.dim();
    if n == 0 {
        return Err(RunError::input_at(
            case,
            "mesh",
            "a gradient problem needs a mesh of dimension ≥ 1",
            None,
        ));
    }
    let points = field_points(complex, n);
    let f: Vec<f64> = points.iter().map(|x| spec.field.eval(x, 0.0)).collect();
    if let Some(c) = f.iter().position(|v| !v.is_finite()) {
        return Err(RunError::input_at(
            case,
            "problem.field",
            format!(
                "the field is not finite ({}) at {} (centroid of top cell {c})",
                crate::physics::non_finite_text(f[c]),
                crate::physics::point_text(&points[c])
            ),
            Some(FINITE_HELP.into()),
        ));
    }
    Ok(f)
}

pub(super) fn solve(
    case: &Case,
    spec: &GradientSpec,
    complex: &Complex,
    phase: &mut dyn FnMut(&str),
) -> Result<RunResult, RunError> {
    phase("sampling and applying Ω δ");
    let started = Instant::now();
    let n = complex.dim();
    let f = sampled(case, spec, complex)?;
    let faces = complex.cell_count(n - 1);
    let metric = match &spec.metric {
        GradientMetric::Diagonal(sigma) => FaceMetric::Diagonal(*sigma),
        GradientMetric::TwoPoint => FaceMetric::TwoPoint,
        GradientMetric::File { path, scale } => FaceMetric::Entries(
            read_metric_file(case, path, faces)?
                .into_iter()
                .map(|(row, column, value)| (row, column, scale * value))
                .collect(),
        ),
    };
    let NormalGradient { jump, gradient: g } = normal_gradient(complex, &f, &metric)
        .map_err(|e| RunError::input_at(case, "problem.metric", e.to_string(), None).because(e))?;
    let seconds = started.elapsed().as_secs_f64();
    Ok(RunResult {
        problem: "gradient".into(),
        method: None,
        unknowns: 0,
        fields: vec![
            Cochain::new("f", n, f).with_description("the field sampled at cell centroids"),
            Cochain::new("jump", n - 1, jump).with_description(
                "−∂ᵀ f: the jump of f across each interior face along its normal",
            ),
            Cochain::new("normal_gradient", n - 1, g)
                .with_description("Ω (−∂ᵀ f): the normal gradient as a face cochain"),
        ],
        errors: None,
        flux_error: None,
        relative_residual: None,
        factorization: None,
        ordering: None,
        timings: vec![("sample + Ω δ".into(), seconds)],
        warnings: Vec::new(),
        pure_neumann: false,
        series: Vec::new(),
        notes: Vec::new(),
        report: serde_json::Map::new(),
    })
}
