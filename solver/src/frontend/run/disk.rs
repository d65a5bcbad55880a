//! The size of a run's output, estimated before solving, against the free
//! space where it goes: a long transient run that fills the disk fails at
//! its end and loses its work, so it is refused up front, as a mesh too
//! large for the memory is.

use crate::frontend::case::{Case, Problem};
use crate::frontend::mesh_spec::human_bytes;
use hasse_complex::Complex;
use std::path::Path;

/// A lower bound on the bytes a run writes: the mesh (vertices, the top
/// cells' characteristic matrix and XDMF topology, which every layout
/// writes uncompressed; `[output] complex = "full"` adds more, compressed)
/// and 8 bytes per
/// value of every field of every saved level, twice for a transient run
/// with a partial output (the partial output and the final file exist side
/// by side before the partial one is removed).
///
/// ```
/// use hasse_solver::frontend::case::Case;
/// use hasse_solver::frontend::run::OutputEstimate;
/// let text = "[mesh]\ngenerator = \"rectangle\"\nn = [10, 10]\n[problem]\nmethod = \"fv\"\n";
/// let case = Case::from_text("e.toml", text, &[]).unwrap();
/// let estimate = OutputEstimate::of(&case, &case.build_mesh().unwrap());
/// assert_eq!(estimate.levels, 1);
/// // More than the 100 cell values of u alone, less than a megabyte.
/// assert!(estimate.bytes > 800.0 && estimate.bytes < 1e6);
/// ```
#[derive(Clone, Debug, PartialEq)]
pub struct OutputEstimate {
    /// Saved levels.
    pub levels: usize,
    /// Bytes, at least.
    pub bytes: f64,
}

impl OutputEstimate {
    /// The estimate for `case` on `complex`.
    pub fn of(case: &Case, complex: &Complex) -> OutputEstimate {
        let n = complex.dim();
        let d = complex.embedding_dim() as f64;
        let count = |p: usize| complex.cell_count(p) as f64;
        let mut mesh = count(0) * 24.0;
        if n > 0 {
            let vertex_lists = complex.lar().characteristic(n).map_or(0, |m| m.nnz()) as f64;
            // M_n (indices and indptr) and its XDMF topology.
            mesh += 2.0 * vertex_lists * 8.0 + (count(n) + 1.0) * 8.0;
        }
        let unknowns = match case.method().map(|m| m.location()) {
            Some(crate::metric::Location::Nodal) => count(0),
            _ => count(n),
        };
        let (levels, per_level, copies) = match &case.problem {
            Problem::Heat(h) => {
                let levels = h.time.steps / h.time.save_every.max(1) + 2;
                let fields = if case.exact.is_some() { 3.0 } else { 1.0 };
                (
                    levels,
                    fields * unknowns,
                    if case.output.partial { 2.0 } else { 1.0 },
                )
            }
            // u (and u_exact, error), the fluxes on faces, the
            // conductivity and gradient per cell.
            _ => (
                1,
                3.0 * unknowns + 2.0 * count(n.saturating_sub(1)) + (1.0 + d) * count(n),
                1.0,
            ),
        };
        OutputEstimate {
            levels,
            bytes: copies * (mesh + levels as f64 * per_level * 8.0),
        }
    }

    /// Refuse, with the numbers, an estimate above the free space of the
    /// directory `stem` writes into: `HASSE_DISK_LIMIT` (bytes) if set,
    /// else what `df` reports; no check where neither is known.
    pub fn check(&self, stem: &Path) -> Result<(), String> {
        let dir = match stem.parent() {
            Some(p) if !p.as_os_str().is_empty() => p,
            _ => Path::new("."),
        };
        let Some((free, source)) = free_space(dir) else {
            return Ok(());
        };
        if self.bytes <= free as f64 {
            return Ok(());
        }
        Err(format!(
            "the output would take at least {} ({} saved levels), but {} has {} free ({source})",
            human_bytes(self.bytes),
            self.levels,
            dir.display(),
            human_bytes(free as f64)
        ))
    }
}

/// Free bytes where `dir` (or its nearest existing ancestor) lives.
fn free_space(dir: &Path) -> Option<(u64, &'static str)> {
    if let Some(limit) = std::env::var("HASSE_DISK_LIMIT")
        .ok()
        .and_then(|v| v.trim().parse::<u64>().ok())
    {
        return Some((limit, "HASSE_DISK_LIMIT"));
    }
    let existing = dir.ancestors().find(|p| p.exists())?;
    let out = std::process::Command::new("df")
        .args(["-P", "-B1"])
        .arg(existing)
        .output()
        .ok()?;
    let text = String::from_utf8(out.stdout).ok()?;
    // POSIX format: a header, then filesystem, blocks, used, available, …
    let available = text
        .lines()
        .nth(1)?
        .split_whitespace()
        .nth(3)?
        .parse()
        .ok()?;
    Some((available, "df"))
}
