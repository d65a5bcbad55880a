//! Coefficients K (conductivity, permeability): one expression, a
//! symmetric tensor written in rows, or either per region.

use super::*;

impl Reader {
    /// A scalar or tensor coefficient under `problem.<key>` (default 1).
    pub(super) fn coefficient(
        &mut self,
        table: &dyn TableLike,
        key: &str,
        scope: &Scope,
    ) -> Option<Coefficient> {
        self.coefficient_in(table, "problem", key, scope)
    }

    /// A scalar or tensor coefficient `<prefix>.<key>` (default 1), or one
    /// per region ([`Reader::regional_coefficient`]).
    pub(super) fn coefficient_in(
        &mut self,
        table: &dyn TableLike,
        prefix: &str,
        key: &str,
        scope: &Scope,
    ) -> Option<Coefficient> {
        let Some(entry) = self.entry(table, prefix, key) else {
            return scope.parse("1").ok().map(Coefficient::Scalar);
        };
        if let Some(regions) = entry.item.as_table_like() {
            let tensor_region = regions
                .iter()
                .any(|(_, item)| matches!(item.as_value(), Some(Value::Array(_))));
            if tensor_region {
                return self.regional_coefficient(&entry, regions, scope);
            }
        }
        let Some(Value::Array(rows)) = entry.item.as_value() else {
            return self
                .expression_or_regions(&entry, scope)
                .map(Coefficient::Scalar);
        };
        self.tensor_rows(rows, &entry.name, entry.span(), scope)
            .map(Coefficient::Tensor)
    }

    /// The rows of a tensor written `[[kxx, kxy], [kxy, kyy]]` at `name`,
    /// square with 1 to 3 rows, symmetric where the entries are constant.
    fn tensor_rows(
        &mut self,
        rows: &toml_edit::Array,
        name: &str,
        span: Option<Range<usize>>,
        scope: &Scope,
    ) -> Option<Vec<Vec<Expression>>> {
        let size = rows.len();
        if !(1..=3).contains(&size) {
            self.error(
                span,
                name,
                format!("a tensor has 1 to 3 rows, found {size}"),
                None,
            );
            return None;
        }
        let mut tensor = Vec::with_capacity(size);
        let mut ok = true;
        for (i, row) in rows.iter().enumerate() {
            let row_name = format!("{name}[{i}]");
            let Value::Array(cols) = row else {
                self.error(
                    row.span(),
                    &row_name,
                    "expected a row (an array)",
                    Some("write the tensor as [[kxx, kxy], [kxy, kyy]]".into()),
                );
                ok = false;
                continue;
            };
            if cols.len() != size {
                self.error(
                    row.span(),
                    &row_name,
                    format!(
                        "row has {} entries; the tensor is {size}×{size}",
                        cols.len()
                    ),
                    None,
                );
                ok = false;
                continue;
            }
            let mut parsed = Vec::with_capacity(size);
            for (j, v) in cols.iter().enumerate() {
                let item = Item::Value(v.clone());
                match self.expression_of(&item, &format!("{row_name}[{j}]"), v.span(), scope) {
                    Some(e) => parsed.push(e),
                    None => ok = false,
                }
            }
            tensor.push(parsed);
        }
        if !ok {
            return None;
        }
        // Symmetry can be checked textually for constant entries here; entries
        // that vary are checked where they are evaluated.
        for (i, row) in tensor.iter().enumerate() {
            for (j, a) in row.iter().enumerate().take(i) {
                let b = &tensor[j][i];
                if a.is_constant() && b.is_constant() && a.eval(&[], 0.0) != b.eval(&[], 0.0) {
                    self.error(span, name, format!("the tensor is not symmetric: entry [{i}][{j}] = {} but [{j}][{i}] = {}", a.text(), b.text()), Some("a diffusion or permeability tensor is symmetric positive definite".into()));
                    return None;
                }
            }
        }
        Some(tensor)
    }

    /// A coefficient per region where some region is a tensor:
    /// `{ layer = [[1, 0], [0, "10 + y"]], default = 1 }`. A scalar region
    /// s stands for s·I. The result is a [`Coefficient::Tensor`] whose
    /// entries are each given per region (the same regions, in the order
    /// written), except off-diagonal entries that are the constant 0 in
    /// every region, which stay one constant so that methods that see only
    /// a diagonal tensor (the two-point flux, DEC's diagonal star) can tell.
    fn regional_coefficient(
        &mut self,
        entry: &Entry,
        regions: &dyn TableLike,
        scope: &Scope,
    ) -> Option<Coefficient> {
        // Each region's value: a scalar or the rows of a tensor.
        let mut pieces: Vec<(String, Coefficient)> = Vec::new();
        let mut ok = true;
        for (region, item) in regions.iter() {
            let name = format!("{}.{region}", entry.name);
            let span = item.span().or_else(|| entry.span());
            self.collector.record(&name, span.clone());
            let value = match item.as_value() {
                Some(Value::Array(rows)) => self
                    .tensor_rows(rows, &name, span, scope)
                    .map(Coefficient::Tensor),
                _ => self
                    .expression_of(item, &name, span, scope)
                    .map(Coefficient::Scalar),
            };
            match value {
                Some(v) => pieces.push((region.to_string(), v)),
                None => ok = false,
            }
        }
        if !ok {
            return None;
        }
        let mut sizes = pieces.iter().filter_map(|(name, v)| match v {
            Coefficient::Tensor(rows) => Some((name, rows.len())),
            Coefficient::Scalar(_) => None,
        });
        let (first, size) = sizes.next()?;
        if let Some((other, other_size)) = sizes.find(|&(_, s)| s != size) {
            self.error(
                entry.span(),
                &entry.name,
                format!("region `{first}` gives a {size}×{size} tensor but `{other}` a {other_size}×{other_size} one"),
                Some("every tensor region has the mesh's dimension; a scalar region s stands for s·I".into()),
            );
            return None;
        }
        if pieces.iter().all(|(name, _)| name == "default") {
            self.error(
                entry.span(),
                &entry.name,
                "a table of values per region names no region".to_string(),
                Some("write `{ region = value, …, default = value }` with tags of top cells as regions, or give one value".into()),
            );
            return None;
        }
        let zero = scope.parse("0").ok()?;
        // Entry (i, j) of each region.
        let entry_of = |v: &Coefficient, i: usize, j: usize| match v {
            Coefficient::Tensor(rows) => rows[i][j].clone(),
            Coefficient::Scalar(s) if i == j => s.clone(),
            Coefficient::Scalar(_) => zero.clone(),
        };
        let mut tensor = Vec::with_capacity(size);
        for i in 0..size {
            let mut row = Vec::with_capacity(size);
            for j in 0..size {
                let all_zero = i != j
                    && pieces.iter().all(|(_, v)| {
                        let e = entry_of(v, i, j);
                        e.is_constant() && e.eval(&[], 0.0) == 0.0
                    });
                if all_zero {
                    row.push(zero.clone());
                    continue;
                }
                let mut listed = Vec::new();
                let mut default = None;
                for (name, v) in &pieces {
                    let e = entry_of(v, i, j);
                    if name == "default" {
                        default = Some(e);
                    } else {
                        listed.push((name.clone(), e));
                    }
                }
                // The text names the entry's value in each region: equal
                // texts are equal entries (DEC's diagonal-star test reads it).
                let parts: Vec<String> = listed
                    .iter()
                    .map(|(n, e)| format!("{n} = \"{}\"", e.text()))
                    .chain(
                        default
                            .iter()
                            .map(|e| format!("default = \"{}\"", e.text())),
                    )
                    .collect();
                let text = format!("{{ {} }}", parts.join(", "));
                row.push(Expression::per_region(
                    &text,
                    Regions {
                        pieces: listed,
                        default,
                    },
                ));
            }
            tensor.push(row);
        }
        Some(Coefficient::Tensor(tensor))
    }
}
