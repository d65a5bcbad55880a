//! `[[output.quantity]]` and `[[output.probe]]` tables.

use super::*;
use crate::frontend::case::{ProbeSpec, QuantityKind, QuantitySpec};

pub(super) const QUANTITY_KEYS: &[&str] = &["type", "tag", "region", "field", "name"];
pub(super) const PROBE_KEYS: &[&str] = &["at", "from", "to", "points", "name"];
/// The most points a line probe may have (each is located in the mesh).
const MOST_POINTS: i64 = 100_000;

impl Reader {
    /// The quantities under `[output]`, each checked for its keys (the
    /// tags and regions are checked against the mesh when it is built).
    pub(super) fn quantities(&mut self, output: &dyn TableLike) -> Vec<QuantitySpec> {
        let Some(entry) = self.entry(output, "output", "quantity") else {
            return Vec::new();
        };
        let Some(array) = entry.item.as_array_of_tables() else {
            self.type_error(&entry, "[[output.quantity]] tables");
            return Vec::new();
        };
        let mut out = Vec::new();
        for (i, table) in array.iter().enumerate() {
            let prefix = format!("output.quantity[{i}]");
            self.check_keys(table, &prefix, QUANTITY_KEYS);
            let header = table.span();
            let Some(kind_text) = self.string_at(table, &prefix, "type") else {
                if self.entry(table, &prefix, "type").is_none() {
                    self.error(
                        header,
                        &join(&prefix, "type"),
                        "missing: what the quantity computes",
                        Some("type = \"flux\" (with tag), \"integral\", \"mean\", \"min\" or \"max\" (with an optional region)".into()),
                    );
                }
                continue;
            };
            let Some(kind) = QuantityKind::ALL
                .iter()
                .find(|(_, n)| *n == kind_text)
                .map(|(k, _)| *k)
            else {
                let span = self.entry(table, &prefix, "type").and_then(|e| e.span());
                let names: Vec<String> = QuantityKind::ALL
                    .iter()
                    .map(|(_, n)| n.to_string())
                    .collect();
                let help = match closest(&kind_text, &names) {
                    Some(s) => format!("did you mean \"{s}\"? the types are {}", names.join(", ")),
                    None => format!("the types are {}", names.join(", ")),
                };
                self.error(
                    span,
                    &join(&prefix, "type"),
                    format!("unknown quantity type \"{kind_text}\""),
                    Some(help),
                );
                continue;
            };
            let tag = self.string_at(table, &prefix, "tag");
            let region = self.string_at(table, &prefix, "region");
            if let Some(field) = self.string_at(table, &prefix, "field") {
                if field != "u" {
                    let span = self.entry(table, &prefix, "field").and_then(|e| e.span());
                    self.error(
                        span,
                        &join(&prefix, "field"),
                        format!("no field \"{field}\" to compute quantities of"),
                        Some("quantities are of the solution, field = \"u\" (the default)".into()),
                    );
                    continue;
                }
            }
            match (kind, &tag, &region) {
                (QuantityKind::Flux, None, _) => {
                    self.error(
                        header,
                        &join(&prefix, "tag"),
                        "missing: the tag of (n−1)-cells the flux goes through",
                        Some("e.g. tag = \"xmin\"; `hasse info` lists the mesh's tags".into()),
                    );
                    continue;
                }
                (QuantityKind::Flux, Some(_), Some(_)) => {
                    let span = self.entry(table, &prefix, "region").and_then(|e| e.span());
                    self.error(
                        span,
                        &join(&prefix, "region"),
                        "a flux goes through a tag of (n−1)-cells, not over a region",
                        Some("remove `region`".into()),
                    );
                    continue;
                }
                (QuantityKind::Flux, Some(_), None) => {}
                (_, Some(_), _) => {
                    let span = self.entry(table, &prefix, "tag").and_then(|e| e.span());
                    self.error(span, &join(&prefix, "tag"), format!("a {kind_text} is over a region of top cells, not through a tag"), Some("write region = \"…\" (a tag of top cells), or leave it out for the whole domain".into()));
                    continue;
                }
                _ => {}
            }
            let name = self
                .string_at(table, &prefix, "name")
                .unwrap_or_else(|| match kind {
                    QuantityKind::Flux => format!("flux through {}", tag.as_deref().unwrap_or("")),
                    _ => match &region {
                        Some(r) => format!("{kind_text} of u in {r}"),
                        None => format!("{kind_text} of u"),
                    },
                });
            out.push(QuantitySpec {
                name,
                kind,
                tag,
                region,
                key: prefix,
            });
        }
        out
    }
}

impl Reader {
    /// The probes under `[output]` (their points are located in the mesh
    /// when it is built).
    pub(super) fn probes(&mut self, output: &dyn TableLike) -> Vec<ProbeSpec> {
        let Some(entry) = self.entry(output, "output", "probe") else {
            return Vec::new();
        };
        let Some(array) = entry.item.as_array_of_tables() else {
            self.type_error(&entry, "[[output.probe]] tables");
            return Vec::new();
        };
        let mut out = Vec::new();
        for (i, table) in array.iter().enumerate() {
            let prefix = format!("output.probe[{i}]");
            self.check_keys(table, &prefix, PROBE_KEYS);
            let header = table.span();
            let name = self
                .string_at(table, &prefix, "name")
                .unwrap_or_else(|| format!("probe-{i}"));
            let at = self.point_at(table, &prefix, "at");
            let from = self.point_at(table, &prefix, "from");
            let to = self.point_at(table, &prefix, "to");
            let count = match self.entry(table, &prefix, "points") {
                None => Some(101),
                Some(e) => match e.item.as_integer() {
                    Some(k) if (2..=MOST_POINTS).contains(&k) => Some(k as usize),
                    _ => {
                        self.error(e.span(), &e.name, format!("the number of points of a line, an integer from 2 to {MOST_POINTS}"), None);
                        None
                    }
                },
            };
            let written = |key: &str| table.get(key).is_some();
            let points = match (at, from, to) {
                (Some(Some(p)), None, None)
                    if !written("from") && !written("to") && !written("points") =>
                {
                    vec![p]
                }
                (None, Some(Some(a)), Some(Some(b))) if !written("at") => {
                    if a.len() != b.len() {
                        self.error(
                            header,
                            &prefix,
                            "`from` and `to` have different numbers of coordinates",
                            None,
                        );
                        continue;
                    }
                    let Some(k) = count else { continue };
                    (0..k)
                        .map(|j| {
                            let s = j as f64 / (k - 1) as f64;
                            a.iter().zip(&b).map(|(p, q)| p + s * (q - p)).collect()
                        })
                        .collect()
                }
                // A point that could not be read was reported already.
                (Some(None), _, _) | (_, Some(None), _) | (_, _, Some(None)) => continue,
                _ => {
                    self.error(
                        header,
                        &prefix,
                        "a probe is a point, `at = [x, y]`, or a line, `from = [x, y]`, `to = [x, y]` (and `points`, default 101)",
                        None,
                    );
                    continue;
                }
            };
            out.push(ProbeSpec {
                name,
                points,
                key: prefix,
            });
        }
        out
    }

    /// `<prefix>.<key>` as a point of 1 to 3 finite coordinates: `None`
    /// when not written, `Some(None)` when written wrongly (reported).
    fn point_at(
        &mut self,
        table: &dyn TableLike,
        prefix: &str,
        key: &str,
    ) -> Option<Option<Vec<f64>>> {
        let entry = self.entry(table, prefix, key)?;
        let coordinates: Option<Vec<f64>> = entry.item.as_array().and_then(|a| {
            a.iter()
                .map(|v| match v {
                    Value::Float(f) => Some(*f.value()),
                    Value::Integer(i) => Some(*i.value() as f64),
                    _ => None,
                })
                .collect()
        });
        match coordinates {
            Some(p) if (1..=3).contains(&p.len()) && p.iter().all(|x| x.is_finite()) => {
                Some(Some(p))
            }
            _ => {
                self.error(
                    entry.span(),
                    &entry.name,
                    "a point: an array of 1 to 3 finite numbers, e.g. [0.5, 0.25]",
                    None,
                );
                Some(None)
            }
        }
    }
}
