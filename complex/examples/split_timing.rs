//! Times SPLIT on an n × n quad grid (default n = 1000, i.e. 10⁶ cells):
//! every cell is cut by the vertical line through its centre, first with
//! one plane per grid column (x = (i + ½)/n), then with one plane per cell
//! built from its computed centroid. Run in release:
//!
//! A second argument m (default 50) adds the same experiment on an m × m × m
//! hexahedral grid.
//!
//! ```text
//! cargo run --release -p hasse-complex --example split_timing -- 1000 50
//! HASSE_SPLIT_PROFILE=1 cargo run --release -p hasse-complex --example split_timing
//! ```
//!
//! With `HASSE_SPLIT_PROFILE` set, each SPLIT pass prints its phases
//! (classification, edges, faces, matrix assembly, ζ) on stderr. Besides
//! wall time the example prints the process CPU time (Linux, from
//! /proc/self/stat) spent in each SPLIT: on a shared machine that is the
//! number to compare, and with `RAYON_NUM_THREADS=1` it is the
//! single-core cost.

use hasse_complex::generate::{box3, rectangle};
use hasse_complex::split::{split_cells, Hyperplane, SplitOptions};
use std::time::Instant;

/// User + system CPU seconds of this process so far (None off Linux).
fn cpu_seconds() -> Option<f64> {
    let stat = std::fs::read_to_string("/proc/self/stat").ok()?;
    // Fields after the parenthesised command name; utime and stime are the
    // 14th and 15th fields of the whole line, in clock ticks (100 per second).
    let rest = stat.rsplit_once(')')?.1;
    let fields: Vec<&str> = rest.split_whitespace().collect();
    let utime: f64 = fields.get(11)?.parse().ok()?;
    let stime: f64 = fields.get(12)?.parse().ok()?;
    Some((utime + stime) / 100.0)
}

fn cpu_since(start: Option<f64>) -> String {
    match (start, cpu_seconds()) {
        (Some(a), Some(b)) => format!("{:.2} s CPU", b - a),
        _ => "CPU time unavailable".into(),
    }
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let n: usize = match std::env::args().nth(1) {
        Some(arg) => arg.parse()?,
        None => 1000,
    };
    let start = Instant::now();
    let grid = rectangle(n, n, [0.0, 1.0], [0.0, 1.0])?;
    println!(
        "grid {n}×{n}: {:?} cells built in {:.3} s",
        grid.cell_counts(),
        start.elapsed().as_secs_f64()
    );

    let columns: Vec<Hyperplane> = (0..n)
        .map(|i| Hyperplane::axis(2, 0, (i as f64 + 0.5) / n as f64))
        .collect::<Result<_, _>>()?;
    let cuts: Vec<(usize, Hyperplane)> = (0..grid.cell_count(2))
        .map(|c| (c, columns[c % n].clone()))
        .collect();
    let start = Instant::now();
    let cpu = cpu_seconds();
    let (fine, r) = split_cells(&grid, &cuts, SplitOptions::default())?;
    let elapsed = start.elapsed().as_secs_f64();
    println!(
        "SPLIT by column planes: {:?} cells in {elapsed:.3} s wall, {} (ζ_2 nnz {})",
        fine.cell_counts(),
        cpu_since(cpu),
        r.zeta(2).nnz()
    );
    drop(fine);

    let centroids = grid.centroid(2).to_vec();
    let cuts: Vec<(usize, Hyperplane)> = (0..grid.cell_count(2))
        .map(|c| Hyperplane::through(&centroids[2 * c..2 * c + 2], &[1.0, 0.0]).map(|h| (c, h)))
        .collect::<Result<_, _>>()?;
    let start = Instant::now();
    let cpu = cpu_seconds();
    let (fine, _) = split_cells(&grid, &cuts, SplitOptions::default())?;
    let elapsed = start.elapsed().as_secs_f64();
    println!(
        "SPLIT by one plane per cell (through its centroid): {:?} cells in {elapsed:.3} s wall, {}",
        fine.cell_counts(),
        cpu_since(cpu)
    );
    drop(fine);

    let m: usize = match std::env::args().nth(2) {
        Some(arg) => arg.parse()?,
        None => 50,
    };
    let start = Instant::now();
    let cube = box3(m, m, m, [0.0, 1.0], [0.0, 1.0], [0.0, 1.0])?;
    println!(
        "box {m}³: {:?} cells built in {:.3} s",
        cube.cell_counts(),
        start.elapsed().as_secs_f64()
    );
    let columns: Vec<Hyperplane> = (0..m)
        .map(|i| Hyperplane::axis(3, 0, (i as f64 + 0.5) / m as f64))
        .collect::<Result<_, _>>()?;
    let cuts: Vec<(usize, Hyperplane)> = (0..cube.cell_count(3))
        .map(|c| (c, columns[c % m].clone()))
        .collect();
    let start = Instant::now();
    let cpu = cpu_seconds();
    let (fine, _) = split_cells(&cube, &cuts, SplitOptions::default())?;
    println!(
        "SPLIT of every hex by its column plane: {:?} cells in {:.3} s wall, {}",
        fine.cell_counts(),
        start.elapsed().as_secs_f64(),
        cpu_since(cpu)
    );
    Ok(())
}
