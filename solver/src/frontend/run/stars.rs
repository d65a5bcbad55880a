//! The forms of a DEC case: the star its `method` names, and for
//! `method = "supplied"` the diagonal stars read from `problem.stars`
//! (one file per degree: one value per k-cell in hasse's cell order,
//! whitespace-separated, `#` starting a comment); and cochains read from
//! files of the same format (`problem.cochain`).

use super::RunError;
use crate::frontend::case::{Case, HodgeMethod};
use crate::physics::forms::Forms;
use hasse_complex::Complex;
use std::path::PathBuf;

const KEY: &str = "problem.stars";

/// The stars of `files` (degree k from the k-th file), each checked for
/// its count against the complex and for finite values; empty when
/// `files` is (the method computes its stars).
pub(super) fn read_stars(
    case: &Case,
    files: &[PathBuf],
    complex: &Complex,
) -> Result<Vec<Vec<f64>>, RunError> {
    if files.is_empty() {
        return Ok(Vec::new());
    }
    let n = complex.dim();
    if files.len() != n + 1 {
        return Err(RunError::input_at(
            case,
            KEY,
            format!(
                "{} star files for a {n}-dimensional mesh, which needs {} (degrees 0 to {n})",
                files.len(),
                n + 1
            ),
            Some("give one file per degree, ⋆₀ first".into()),
        ));
    }
    files
        .iter()
        .enumerate()
        .map(|(k, path)| {
            let what = format!("⋆_{k}");
            let help = format!(
                "file {} of problem.stars is degree {k}; `hasse info` prints the cell counts",
                k + 1
            );
            read_cochain(case, path, KEY, &what, &help, k, complex.cell_count(k))
        })
        .collect()
}

/// One value per k-cell from the file `path` (written at `key`), `what`
/// naming them in messages: numbers separated by whitespace, `#` starting
/// a comment; the count must be `cells`.
pub(super) fn read_cochain(
    case: &Case,
    path: &PathBuf,
    key: &str,
    what: &str,
    help: &str,
    k: usize,
    cells: usize,
) -> Result<Vec<f64>, RunError> {
    let shown = path.display();
    let text = std::fs::read_to_string(path)
        .map_err(|e| RunError::input_at(case, key, format!("cannot read {shown}: {e}"), None))?;
    let mut values = Vec::with_capacity(cells);
    for (number, line) in text.lines().enumerate() {
        let line = line.split('#').next().unwrap_or("");
        for word in line.split_whitespace() {
            let value: f64 = word.parse().map_err(|_| {
                RunError::input_at(
                    case,
                    key,
                    format!("{shown}:{}: `{word}` is not a number", number + 1),
                    Some("the file holds numbers only, `#` starts a comment".into()),
                )
            })?;
            if !value.is_finite() {
                return Err(RunError::input_at(
                    case,
                    key,
                    format!("{shown}:{}: {what} value {value} is not finite", number + 1),
                    None,
                ));
            }
            values.push(value);
        }
    }
    if values.len() != cells {
        return Err(RunError::input_at(
            case,
            key,
            format!(
                "{shown} holds {} values, but {what} needs one per {k}-cell: the mesh has {cells}",
                values.len()
            ),
            Some(help.to_string()),
        ));
    }
    Ok(values)
}

/// The forms of `method` on `complex`, with `stars` (from
/// [`read_stars`]) for the supplied method.
pub(super) fn forms_of<'a>(
    case: &Case,
    method: HodgeMethod,
    complex: &'a Complex,
    stars: &'a [Vec<f64>],
) -> Result<Forms<'a>, RunError> {
    match method {
        HodgeMethod::Supplied => Forms::with_stars(complex, stars)
            .map_err(|e| RunError::input_at(case, KEY, e.to_string(), None).because(e)),
        other => Ok(Forms::new(complex, other.star())),
    }
}
