//! `--set KEY=VALUE` overrides, applied to the case text before it is
//! read.

use super::*;

/// The text with `key.path=value` overrides applied, and each overridden
/// key as diagnostics name it (`boundary.0.value` is `boundary[0].value`)
/// with its assignment. Values are TOML (`n=[64,64]`,
/// `problem.method="fv"`); a value that is not valid TOML is taken as a
/// string, so `problem.method=fv` works too.
pub(in crate::frontend::case) fn apply_overrides(
    file: &str,
    text: &str,
    overrides: &[String],
) -> Result<(String, Vec<(String, String)>), Diagnostics> {
    if overrides.is_empty() {
        return Ok((text.to_string(), Vec::new()));
    }
    let mut keys = Vec::new();
    let mut collector = Collector::new(file, text);
    let mut doc: toml_edit::DocumentMut = match text.parse() {
        Ok(doc) => doc,
        // The syntax error is reported with its position by the reader.
        Err(_) => return Ok((text.to_string(), Vec::new())),
    };
    for assignment in overrides {
        let Some((path, raw)) = assignment.split_once('=') else {
            collector.error(
                None,
                "",
                format!("--set {assignment}: expected KEY=VALUE"),
                Some("e.g. --set problem.method=fv or --set mesh.n=[64,64]".into()),
            );
            continue;
        };
        let value: Value = raw
            .trim()
            .parse()
            .unwrap_or_else(|_| Value::from(raw.trim()));
        let segments: Vec<&str> = path.trim().split('.').collect();
        if segments.iter().all(|s| !s.is_empty()) && set_path(doc.as_table_mut(), &segments, value)
        {
            keys.push((diagnostic_key(&segments), assignment.trim().to_string()));
        } else {
            collector.error(
                None,
                path.trim(),
                format!(
                    "--set {assignment}: `{}` does not name a value in this case file",
                    path.trim()
                ),
                Some("use dotted keys such as problem.method, mesh.n or boundary.0.value".into()),
            );
        }
    }
    if collector.diagnostics.is_empty() {
        Ok((doc.to_string(), keys))
    } else {
        Err(Diagnostics(collector.diagnostics))
    }
}

/// Set the value at a dotted path, creating tables on the way; a numeric
/// segment indexes an array of tables (`boundary.0.value`).
fn set_path(table: &mut dyn TableLike, segments: &[&str], value: Value) -> bool {
    let Some((head, rest)) = segments.split_first() else {
        return false;
    };
    if rest.is_empty() {
        table.insert(head, Item::Value(value));
        return true;
    }
    if table.get(head).is_none() {
        table.insert(head, Item::Table(toml_edit::Table::new()));
    }
    match table.get_mut(head) {
        Some(Item::ArrayOfTables(array)) => {
            let (Some(index), Some(rest)) = (rest[0].parse::<usize>().ok(), rest.get(1..)) else {
                return false;
            };
            match array.get_mut(index) {
                Some(t) if !rest.is_empty() => set_path(t, rest, value),
                _ => false,
            }
        }
        Some(item) => match item.as_table_like_mut() {
            Some(t) => set_path(t, rest, value),
            None => false,
        },
        None => false,
    }
}

/// A `--set` path as diagnostics write keys: numeric segments index the
/// array before them (`boundary.0.value` → `boundary[0].value`).
fn diagnostic_key(segments: &[&str]) -> String {
    let mut key = String::new();
    for segment in segments {
        if segment.parse::<usize>().is_ok() && !key.is_empty() {
            key.push_str(&format!("[{segment}]"));
        } else {
            if !key.is_empty() {
                key.push('.');
            }
            key.push_str(segment);
        }
    }
    key
}
