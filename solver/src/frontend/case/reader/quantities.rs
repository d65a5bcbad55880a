//! `[[output.quantity]]` tables.

use super::*;
use crate::frontend::case::{QuantityKind, QuantitySpec};

pub(super) const QUANTITY_KEYS: &[&str] = &["type", "tag", "region", "field", "name"];

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
