//! How each level of a study is made: the overrides of a uniform
//! (generator) or time refinement, and the SPLIT refinement of the
//! previous level's complex.

use super::StudyError;
use crate::frontend::case::TimeSpec;
use crate::frontend::mesh_spec::MeshSpec;
use hasse_complex::Complex;

/// The `--set` overrides that make level `level` of a uniform refinement
/// of `mesh`, and the resolution they give.
pub(super) fn uniform_overrides(
    case: &str,
    mesh: &MeshSpec,
    level: usize,
) -> Result<(Vec<String>, Vec<usize>), StudyError> {
    let refuse = |message: String| StudyError::Refinement {
        case: case.to_string(),
        message,
    };
    let generator = match (&mesh.generator, &mesh.file) {
        (Some(g), _) => g.as_str(),
        (None, Some(file)) => {
            return Err(refuse(format!(
                "the mesh is read from `{}`: --refine uniform re-generates a mesh at a finer `mesh.n`, and a mesh file has none; use --refine split, which refines any mesh by splitting each cell through its centroid",
                file.display()
            )))
        }
        (None, None) => return Err(refuse("the case has no mesh generator".into())),
    };
    let scale = |n: usize, factor: usize| -> Result<usize, StudyError> {
        factor
            .checked_pow(level as u32)
            .and_then(|f| n.checked_mul(f))
            .ok_or_else(|| refuse(format!("level {level}: the resolution overflows")))
    };
    let list = |v: &[usize]| {
        format!(
            "[{}]",
            v.iter()
                .map(usize::to_string)
                .collect::<Vec<_>>()
                .join(", ")
        )
    };
    if generator == "sphere" {
        let s = mesh.subdivisions.unwrap_or(2) as usize + level;
        return Ok((vec![format!("mesh.subdivisions={s}")], vec![s]));
    }
    let n = mesh.n.as_ref().ok_or_else(|| {
        refuse("mesh.n is missing: uniform refinement multiplies the case's n".into())
    })?;
    // A voronoi or delaunay n counts points in the plane: 4× the points
    // halve h.
    let factor = if matches!(generator, "voronoi" | "delaunay") {
        4
    } else {
        2
    };
    let refined = n
        .iter()
        .map(|&c| scale(c, factor))
        .collect::<Result<Vec<_>, _>>()?;
    let mut overrides = vec![format!("mesh.n={}", list(&refined))];
    if generator == "hollow-box" {
        if let Some([a, b]) = mesh.cavity {
            overrides.push(format!("mesh.cavity=[{}, {}]", scale(a, 2)?, scale(b, 2)?));
        }
    }
    if let Some(grading) = &mesh.grading {
        let refined: Vec<String> = grading
            .iter()
            .map(|r| format!("{:?}", r.powf(0.5f64.powi(level as i32))))
            .collect();
        overrides.push(format!("mesh.grading=[{}]", refined.join(", ")));
    }
    Ok((overrides, refined))
}

/// Level `level` of a time refinement of a case stepping `time`: the
/// override of Δt (Δt/2ᵏ) and that of the steps (2ᵏ times as many, so the
/// end time stays), and that step count. A case that gives `time.end`
/// derives the steps from Δt and refuses `time.steps` beside it, so the
/// caller applies the second override only where the first leaves the
/// count short.
pub(super) fn time_overrides(
    case: &str,
    time: &TimeSpec,
    level: usize,
) -> Result<(String, String, usize), StudyError> {
    let steps = u32::try_from(level)
        .ok()
        .and_then(|k| 1usize.checked_shl(k))
        .and_then(|f| time.steps.checked_mul(f));
    let Some(steps) = steps else {
        return Err(StudyError::Refinement {
            case: case.to_string(),
            message: format!("level {level}: the number of time steps overflows"),
        });
    };
    // Halving is exact in binary: 2ᵏ steps of Δt/2ᵏ end where the case does.
    let dt = time.dt * 0.5f64.powi(level as i32);
    Ok((
        format!("time.dt={dt:?}"),
        format!("time.steps={steps}"),
        steps,
    ))
}

/// Refuse a complex that SPLIT cannot refine (cells must fill R² or R³)
/// before any level is solved.
pub(super) fn check_splittable(case: &str, complex: &Complex) -> Result<(), StudyError> {
    let (n, d) = (complex.dim(), complex.embedding_dim());
    if n == d && (2..=3).contains(&n) {
        return Ok(());
    }
    Err(StudyError::Refinement {
        case: case.to_string(),
        message: format!(
            "--refine split cuts cells that fill the plane or space; this mesh has {n}-cells in R^{d} (use --refine uniform for a generated surface)"
        ),
    })
}
