//! The study as one plain-text table: a row per method and level, a
//! least-squares row per method, the orders next to their errors.

use super::{Norm, Refinement, StudyResult};
use std::fmt;

fn resolution(r: &[usize]) -> String {
    r.iter().map(usize::to_string).collect::<Vec<_>>().join("×")
}

fn order(p: Option<f64>) -> String {
    // A slope that rounds to zero prints as 0.00, not -0.00.
    match p.map(|p| format!("{p:.2}")) {
        None => "-".to_string(),
        Some(s) if s == "-0.00" => "0.00".to_string(),
        Some(s) => s,
    }
}

impl fmt::Display for StudyResult {
    /// ```
    /// use hasse_solver::study::{Refinement, StudyResult, StudyRow};
    /// let row = |level: usize, h: f64, l2: f64| StudyRow {
    ///     method: "fd".into(), level, resolution: vec![8 << level, 8 << level], h, cells: 64 << (2 * level),
    ///     unknowns: 64 << (2 * level), l2, max: 2.0 * l2, gradient_l2: None, flux: Some(10.0 * l2.sqrt()),
    ///     mesh_seconds: 0.001, solve_seconds: 0.01,
    /// };
    /// let result = StudyResult {
    ///     case: "demo.toml".into(), title: None, refinement: Refinement::Uniform, levels: 2,
    ///     methods: vec!["fd".into()], rows: vec![row(0, 0.2, 4e-2), row(1, 0.1, 1e-2)],
    /// };
    /// let table = result.to_string();
    /// assert!(table.contains("fd         1  16×16"));
    /// assert!(table.contains("least squares"));
    /// assert!(table.contains("2.00")); // L² order
    /// assert!(table.contains("1.00")); // flux order
    /// ```
    fn fmt(&self, out: &mut fmt::Formatter<'_>) -> fmt::Result {
        // Built whole, then written line by line without trailing blanks
        // (columns a method lacks would otherwise leave them).
        let mut text = String::new();
        self.write_table(&mut text)?;
        for line in text.lines() {
            writeln!(out, "{}", line.trim_end())?;
        }
        Ok(())
    }
}

impl StudyResult {
    fn write_table(&self, f: &mut String) -> fmt::Result {
        use std::fmt::Write;
        match &self.title {
            Some(t) => writeln!(f, "case     {} ({t})", self.case)?,
            None => writeln!(f, "case     {}", self.case)?,
        }
        let size = match self.refinement {
            Refinement::Uniform | Refinement::Split => "h = largest top-cell diameter",
            Refinement::Time => "Δt = time step (one mesh)",
        };
        writeln!(
            f,
            "study    {} level{}, {} refinement; resolution = {}; {size}; p = observed order (from the previous level; least squares over all levels); errors as the run reports them (diffusion: L² and H¹ by quadrature of each method's field, max at the unknowns' points; heat, darcy, coupled: at the unknowns' points; k-forms: the star norm of the cochain, max per cell measure)",
            self.levels,
            if self.levels == 1 { "" } else { "s" },
            self.refinement.name(),
            self.refinement.resolution_name()
        )?;
        let norms: Vec<Norm> = Norm::ALL
            .into_iter()
            .filter(|&n| self.rows.iter().any(|r| r.error(n).is_some()))
            .collect();
        let method_width = self
            .methods
            .iter()
            .map(|m| m.len())
            .chain([6])
            .max()
            .unwrap_or(6);
        let resolution_width = self
            .rows
            .iter()
            .map(|r| resolution(&r.resolution).chars().count())
            .chain([10])
            .max()
            .unwrap_or(10);
        let norm_title = |n: Norm| match n {
            Norm::L2 => "L² error",
            Norm::Max => "max error",
            Norm::GradientL2 => "H¹ error",
            Norm::Flux => "flux error",
        };
        write!(
            f,
            "\n{:<mw$} {:>5}  {:<rw$} {:>10} {:>9}",
            "method",
            "level",
            "resolution",
            self.refinement.size_name(),
            "unknowns",
            mw = method_width,
            rw = resolution_width
        )?;
        for &n in &norms {
            write!(f, "  {:>11} {:>5}", norm_title(n), "p")?;
        }
        writeln!(f, "  {:>9}", "seconds")?;
        for method in &self.methods {
            let orders: Vec<_> = norms.iter().map(|&n| self.orders(method, n)).collect();
            for row in self.method_rows(method) {
                write!(
                    f,
                    "{:<mw$} {:>5}  {:<rw$} {:>10.4e} {:>9}",
                    method,
                    row.level,
                    resolution(&row.resolution),
                    row.h,
                    row.unknowns,
                    mw = method_width,
                    rw = resolution_width
                )?;
                for (&n, o) in norms.iter().zip(&orders) {
                    match row.error(n) {
                        Some(e) => {
                            let p = if row.level == 0 {
                                "-".to_string()
                            } else {
                                order(o.pairwise.get(row.level - 1).copied().flatten())
                            };
                            write!(f, "  {e:>11.4e} {p:>5}")?;
                        }
                        None => write!(f, "  {:>11} {:>5}", "", "")?,
                    }
                }
                writeln!(f, "  {:>9.3}", row.solve_seconds)?;
            }
            if self.levels >= 2 {
                let label = format!("{method} least squares");
                write!(
                    f,
                    "{:<w$}",
                    label,
                    w = method_width + 6 + 2 + resolution_width + 11 + 10
                )?;
                for o in &orders {
                    let p = if self.method_rows(method).all(|r| r.error(o.norm).is_some()) {
                        order(o.least_squares)
                    } else {
                        String::new()
                    };
                    write!(f, "  {:>11} {p:>5}", "")?;
                }
                writeln!(f)?;
            }
        }
        Ok(())
    }
}

fn number(x: Option<f64>) -> String {
    x.map_or_else(String::new, |v| format!("{v:e}"))
}

impl StudyResult {
    /// The rows as CSV: a header, then one line per method and level, with
    /// the pairwise order of each norm next to it (empty on level 0 and
    /// where undefined). The resolution is written `64x64` so that it
    /// stays one field.
    ///
    /// ```
    /// use hasse_solver::study::{Refinement, StudyResult, StudyRow};
    /// let row = |level: usize, h: f64, l2: f64| StudyRow {
    ///     method: "fe".into(), level, resolution: vec![4 << level], h, cells: 4 << level,
    ///     unknowns: 3 << level, l2, max: l2, gradient_l2: Some(l2.sqrt()), flux: None,
    ///     mesh_seconds: 0.0, solve_seconds: 0.0,
    /// };
    /// let result = StudyResult {
    ///     case: "demo.toml".into(), title: None, refinement: Refinement::Uniform, levels: 2,
    ///     methods: vec!["fe".into()], rows: vec![row(0, 0.25, 1e-2), row(1, 0.125, 2.5e-3)],
    /// };
    /// let csv = result.csv();
    /// let lines: Vec<&str> = csv.lines().collect();
    /// assert_eq!(lines.len(), 3);
    /// assert!(lines[0].starts_with("method,level,resolution,h,cells,unknowns,l2,l2_order"));
    /// assert!(lines[2].starts_with("fe,1,8,1.25e-1,8,6,2.5e-3,"));
    /// let l2_order: f64 = lines[2].split(',').nth(7).unwrap().parse().unwrap();
    /// assert!((l2_order - 2.0).abs() < 1e-12);
    /// ```
    pub fn csv(&self) -> String {
        // A time study's size column is its time step, not a mesh size.
        let size = match self.refinement {
            Refinement::Uniform | Refinement::Split => "h",
            Refinement::Time => "dt",
        };
        let mut out = format!("method,level,resolution,{size},cells,unknowns");
        for n in Norm::ALL {
            out.push_str(&format!(",{0},{0}_order", n.key()));
        }
        out.push_str(",mesh_seconds,solve_seconds\n");
        for method in &self.methods {
            let orders: Vec<_> = Norm::ALL.iter().map(|&n| self.orders(method, n)).collect();
            for row in self.method_rows(method) {
                let resolution: Vec<String> = row.resolution.iter().map(usize::to_string).collect();
                out.push_str(&format!(
                    "{},{},{},{:e},{},{}",
                    row.method,
                    row.level,
                    resolution.join("x"),
                    row.h,
                    row.cells,
                    row.unknowns
                ));
                for (n, o) in Norm::ALL.iter().zip(&orders) {
                    let p = row
                        .level
                        .checked_sub(1)
                        .and_then(|k| o.pairwise.get(k).copied().flatten());
                    out.push_str(&format!(",{},{}", number(row.error(*n)), number(p)));
                }
                out.push_str(&format!(
                    ",{:e},{:e}\n",
                    row.mesh_seconds, row.solve_seconds
                ));
            }
        }
        out
    }

    /// The study as JSON: the case, the refinement, every row, and per
    /// method and norm the pairwise and least-squares orders.
    pub fn json(&self) -> serde_json::Value {
        let methods: Vec<serde_json::Value> = self
            .methods
            .iter()
            .map(|m| {
                let orders: serde_json::Map<String, serde_json::Value> = self
                    .norms(m)
                    .into_iter()
                    .map(|n| {
                        let o = self.orders(m, n);
                        (
                            n.key().to_string(),
                            serde_json::json!({
                                "pairwise": o.pairwise,
                                "least_squares": o.least_squares,
                            }),
                        )
                    })
                    .collect();
                serde_json::json!({
                    "method": m,
                    "rows": self.method_rows(m).collect::<Vec<_>>(),
                    "orders": orders,
                })
            })
            .collect();
        serde_json::json!({
            "case": self.case,
            "title": self.title,
            "refinement": self.refinement,
            "levels": self.levels,
            "mesh_size": "largest diameter of a top cell",
            // The rows' `h`: the mesh size, or Δt in a time study.
            "size": self.refinement.size_name(),
            "methods": methods,
        })
    }
}
