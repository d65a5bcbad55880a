//! What the benchmarks share: wall time, the process's peak memory and the
//! Poisson matrices built by hand (cell-centred and nodal Q1, the baselines
//! hasse's assembly is measured against). Include it with
//! `#[path = "common/measure.rs"] mod measure;`.

// Each benchmark uses its own subset.
#![allow(dead_code)]

use faer::sparse::{SparseColMat, Triplet};
use std::time::Instant;

/// Seconds since `t`.
pub fn seconds(t: Instant) -> f64 {
    t.elapsed().as_secs_f64()
}

/// Peak resident memory of this process so far (VmHWM), in GiB; NaN where
/// `/proc` is missing.
pub fn peak_memory_gib() -> f64 {
    std::fs::read_to_string("/proc/self/status")
        .ok()
        .and_then(|s| {
            s.lines().find(|l| l.starts_with("VmHWM:")).and_then(|l| {
                l.split_whitespace()
                    .nth(1)
                    .and_then(|v| v.parse::<f64>().ok())
            })
        })
        .map_or(f64::NAN, |kib| kib / (1024.0 * 1024.0))
}

/// (CPU seconds of all threads, minor page faults) of this process so far,
/// from `/proc/self/stat`; differences of two readings are steadier than
/// wall time on a loaded machine. CPU time has the kernel tick's
/// resolution (10 ms). NaN and 0 where `/proc` is missing.
pub fn cpu_and_faults() -> (f64, u64) {
    let stat = std::fs::read_to_string("/proc/self/stat").unwrap_or_default();
    // Fields after the parenthesised command name, which may hold spaces.
    let fields: Vec<&str> = stat
        .rsplit_once(')')
        .map_or(vec![], |(_, rest)| rest.split_whitespace().collect());
    let field = |k: usize| fields.get(k).and_then(|v| v.parse::<u64>().ok());
    // After ')': state is field 0, minflt 7, utime 11, stime 12.
    match (field(7), field(11), field(12)) {
        (Some(faults), Some(user), Some(system)) => ((user + system) as f64 / 100.0, faults),
        _ => (f64::NAN, 0),
    }
}

/// The cell-centred 5/7-point operator on an n^d unit grid with Dirichlet
/// ghosts, as the two-point flux gives it (λ = 1): |F|/h between cells,
/// 2|F|/h on boundary faces. Built without hasse.
pub fn plain_matrix(n: usize, d: usize) -> SparseColMat<usize, f64> {
    let h = 1.0 / n as f64;
    let face = h.powi(d as i32 - 1);
    let interior = face / h;
    let boundary = 2.0 * face / h;
    let cells = n.pow(d as u32);
    let stride: Vec<usize> = (0..d).map(|a| n.pow(a as u32)).collect();
    let mut triplets = Vec::with_capacity(cells * (2 * d + 1));
    for c in 0..cells {
        let mut diagonal = 0.0;
        for &step in &stride {
            let i = (c / step) % n;
            for (exists, other) in [(i > 0, c.wrapping_sub(step)), (i + 1 < n, c + step)] {
                if exists {
                    triplets.push(Triplet::new(c, other, -interior));
                    diagonal += interior;
                } else {
                    diagonal += boundary;
                }
            }
        }
        triplets.push(Triplet::new(c, c, diagonal));
    }
    SparseColMat::try_new_from_triplets(cells, cells, &triplets).expect("valid triplets")
}

/// The Q1 stiffness (λ = 1) of an n^d unit grid (d = 2, 3) with vertex
/// i + (n + 1) j (+ (n + 1)² k) at (i, j, k)/n, built without hasse from
/// the element matrix of a square or cube of side h, whose entry between
/// corners that differ in m coordinates is, in 2D, 2/3, −1/6, −1/3 for
/// m = 0, 1, 2 (independent of h), and in 3D h/3, 0, −h/12, −h/12 for
/// m = 0, 1, 2, 3 (∫∇φ_a·∇φ_b of the products of hat functions).
pub fn plain_q1_matrix(n: usize, d: usize) -> SparseColMat<usize, f64> {
    let h = 1.0 / n as f64;
    let entry: Vec<f64> = if d == 2 {
        vec![2.0 / 3.0, -1.0 / 6.0, -1.0 / 3.0]
    } else {
        vec![h / 3.0, 0.0, -h / 12.0, -h / 12.0]
    };
    let side = n + 1;
    let vertices = side.pow(d as u32);
    let corners = 1usize << d;
    let stride: Vec<usize> = (0..d).map(|a| side.pow(a as u32)).collect();
    let cells = n.pow(d as u32);
    let mut triplets = Vec::with_capacity(cells * corners * corners);
    for c in 0..cells {
        // The cell's lowest corner, then the others by bit pattern.
        let base: usize = (0..d)
            .map(|a| ((c / n.pow(a as u32)) % n) * stride[a])
            .sum();
        let corner = |l: usize| -> usize {
            base + (0..d)
                .filter(|a| l >> a & 1 == 1)
                .map(|a| stride[a])
                .sum::<usize>()
        };
        for a in 0..corners {
            for b in 0..corners {
                // Zeros too (3D edge neighbours): the pattern is the
                // cells' vertex cliques, as hasse's.
                let value = entry[(a ^ b).count_ones() as usize];
                triplets.push(Triplet::new(corner(a), corner(b), value));
            }
        }
    }
    SparseColMat::try_new_from_triplets(vertices, vertices, &triplets).expect("valid triplets")
}

/// Largest entry-wise difference of two matrices with the same pattern
/// (asserted).
pub fn max_difference(a: &SparseColMat<usize, f64>, b: &SparseColMat<usize, f64>) -> f64 {
    assert_eq!(a.symbolic().col_ptr(), b.symbolic().col_ptr(), "patterns");
    assert_eq!(a.symbolic().row_idx(), b.symbolic().row_idx(), "patterns");
    a.val()
        .iter()
        .zip(b.val())
        .map(|(x, y)| (x - y).abs())
        .fold(0.0, f64::max)
}
