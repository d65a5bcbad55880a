//! `hasse info`: what a mesh is made of — cell counts, Euler
//! characteristic, Betti numbers, boundary regions and cell quality.

use hasse_complex::Complex;
use std::fmt::Write;

/// Above this many cells in total, Betti numbers are only computed on request
/// (the exact rank computation grows faster than linearly).
pub const BETTI_CELL_LIMIT: usize = 200_000;

/// A plain-text report of the complex, one fact per line.
pub fn report(complex: &Complex, source: &str, force_betti: bool) -> String {
    let mut out = String::new();
    let n = complex.dim();
    let counts = complex.cell_counts();
    let _ = writeln!(out, "mesh       {source}");
    let _ = writeln!(
        out,
        "dimension  {n}-complex in R^{}",
        complex.embedding_dim()
    );
    let cells: Vec<String> = counts
        .iter()
        .enumerate()
        .map(|(p, k)| format!("K{p} = {k}"))
        .collect();
    let _ = writeln!(out, "cells      {}", cells.join("   "));
    let _ = writeln!(out, "euler      χ = {}", complex.euler_characteristic());
    let total: usize = counts.iter().sum();
    if force_betti || total <= BETTI_CELL_LIMIT {
        let betti: Vec<String> = complex
            .betti_numbers()
            .iter()
            .map(usize::to_string)
            .collect();
        let _ = writeln!(out, "betti      β = ({}) over Q", betti.join(", "));
    } else {
        let _ = writeln!(
            out,
            "betti      skipped: {total} cells is above {BETTI_CELL_LIMIT}; pass --betti to compute"
        );
    }
    let boundary = complex.boundary_subcomplex();
    let faces = boundary.cells(n - 1).len();
    let _ = writeln!(
        out,
        "boundary   {faces} {}-cells{}",
        n - 1,
        if faces == 0 { " (closed)" } else { "" }
    );
    if complex.tags().is_empty() {
        let _ = writeln!(out, "tags       none");
    }
    for (name, tag) in complex.tags().iter() {
        let _ = writeln!(
            out,
            "tag        {name}: {} {}-cells",
            tag.cells.len(),
            tag.dim
        );
    }
    let measure = complex.measure(n);
    let (min, max) = measure
        .iter()
        .fold((f64::INFINITY, 0.0f64), |(lo, hi), &m| {
            (lo.min(m), hi.max(m))
        });
    let sum: f64 = measure.iter().sum();
    let unit = ["count", "length", "area", "volume"][n];
    let _ = writeln!(out, "measure    total {unit} {sum:.6e}");
    let _ = writeln!(
        out,
        "quality    top-cell {unit} min {min:.3e}, max {max:.3e} (ratio {:.3}); mesh size h = {:.3e}",
        if min > 0.0 { max / min } else { f64::INFINITY },
        complex.mesh_size()
    );
    out
}

/// Peak resident memory of this process (Linux `VmHWM`), e.g. "1.23 GiB".
pub fn peak_memory() -> Option<String> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with("VmHWM:"))?;
    let kib: f64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(format!("{:.2} GiB", kib / (1024.0 * 1024.0)))
}
