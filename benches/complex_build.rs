//! Building complexes at scale: every boundary matrix ∂_p plus the primal
//! geometry (measures and centroids of every dimension, face normals).
//!
//! Baseline in the same run: the bare LAR product M_{n-1} M_nᵀ of the same
//! grid done by `sprs` (one sparse matrix product, no extraction, no
//! orientation, no geometry), so the printed ratio says how many "plain
//! sparse products" a complete complex costs.
//!
//! Run with `scripts/bench` (prints the headline table) or
//! `cargo bench --bench complex_build`. For a quick look at construction
//! alone (no geometry), set `COMPLEX_BUILD_QUICK=2d` or `=3d` (optionally
//! `COMPLEX_BUILD_REPEAT=k`): the binary then times `rectangle(1000, 1000)`
//! or `box3(100, 100, 100)` k times and prints the process's peak memory
//! (and, with `COMPLEX_BUILD_HASH` set, a hash of the whole construction,
//! to compare two builds of the crate).
//!
//! The generators build grids directly from index arithmetic; every other
//! mesh goes through the general LAR path (facet extraction, filtered
//! products, geometric signs). `COMPLEX_BUILD_GENERAL=1` makes the quick
//! mode build the same grid through that path instead (its top cells handed
//! to `Complex::build`, then tagged like the generator's): run it once with
//! and once without to compare the two paths' time and peak memory, each in
//! its own process, and with `COMPLEX_BUILD_HASH` their results bit for bit.

use criterion::{criterion_group, BenchmarkId, Criterion};
use hasse_complex::{generate, Complex, TopCells, Vertices};
use std::hint::black_box;
use std::time::{Duration, Instant};

#[path = "common/measure.rs"]
mod measure;

fn build_with_geometry(axes: &[Vec<f64>]) -> Complex {
    with_geometry(generate::grid(axes).expect("grid parameters are valid"))
}

/// Every measure and centroid and the face normals of `complex`.
fn with_geometry(complex: Complex) -> Complex {
    for p in 0..=complex.dim() {
        black_box(complex.measure(p));
        black_box(complex.centroid(p));
    }
    black_box(complex.normal());
    complex
}

fn bare_product(complex: &Complex) -> usize {
    let n = complex.dim();
    let upper = complex
        .lar()
        .characteristic(n)
        .expect("top level exists")
        .map(|&x| u32::from(x));
    let lower = complex
        .lar()
        .characteristic(n - 1)
        .expect("lower level exists")
        .map(|&x| u32::from(x));
    (&lower * &upper.transpose_view().to_csr()).nnz()
}

fn bench(c: &mut Criterion) {
    // Under `cargo test --all-targets` (no --bench flag) criterion runs each
    // benchmark once as a smoke test: use small grids there.
    let benching = std::env::args().any(|a| a == "--bench");
    let (n2, n3) = if benching { (1000, 100) } else { (20, 5) };
    let sizes: Vec<(String, Vec<Vec<f64>>)> = vec![
        (
            format!("2d-{n2}x{n2}"),
            vec![generate::uniform_axis(n2, 0.0, 1.0).expect("valid axis"); 2],
        ),
        (
            format!("3d-{n3}x{n3}x{n3}"),
            vec![generate::uniform_axis(n3, 0.0, 1.0).expect("valid axis"); 3],
        ),
    ];
    let mut group = c.benchmark_group("complex_build");
    group
        .sample_size(10)
        .measurement_time(Duration::from_secs(30))
        .warm_up_time(Duration::from_secs(1));
    for (name, axes) in &sizes {
        group.bench_with_input(
            BenchmarkId::new("complex+geometry", name.as_str()),
            axes,
            |b, axes| b.iter(|| build_with_geometry(axes)),
        );
        // The path of every mesh that is not a generator's grid.
        group.bench_with_input(
            BenchmarkId::new("general LAR path+geometry", name.as_str()),
            axes,
            |b, axes| {
                b.iter(|| {
                    let mut complex = general_grid(axes);
                    tag_sides(&mut complex, axes);
                    with_geometry(complex)
                })
            },
        );
        let complex = build_with_geometry(axes);
        group.bench_with_input(
            BenchmarkId::new("baseline:sprs M_(n-1) M_n^T", name.as_str()),
            &complex,
            |b, complex| b.iter(|| bare_product(complex)),
        );
    }
    group.finish();
}

/// FNV-1a over every ∂_p (pointers, indices, signs), the characteristic
/// matrices, the top orientation and the tags: equal hashes from two builds
/// of the crate mean the same complex.
fn construction_hash(complex: &Complex) -> u64 {
    let mut h = 0xcbf2_9ce4_8422_2325u64;
    let mut eat = |x: u64| {
        for b in x.to_le_bytes() {
            h = (h ^ u64::from(b)).wrapping_mul(0x0100_0000_01b3);
        }
    };
    for p in 1..=complex.dim() {
        let d = complex.boundary(p);
        d.indptr().raw_storage().iter().for_each(|&i| eat(i as u64));
        d.indices().iter().for_each(|&i| eat(i as u64));
        d.data().iter().for_each(|&s| eat(s as u64));
        let m = complex.lar().characteristic(p).expect("level exists");
        m.indices().iter().for_each(|&i| eat(i as u64));
    }
    complex
        .top_orientation()
        .iter()
        .for_each(|&s| eat(s as u64));
    for (name, tag) in complex.tags().iter() {
        name.bytes().for_each(|b| eat(u64::from(b)));
        tag.cells.iter().for_each(|&c| eat(c as u64));
    }
    h
}

/// `generate::grid(axes)` through the general path, untagged: the top
/// cells (corners in tensor order, x fastest) handed to `Complex::build`.
fn general_grid(axes: &[Vec<f64>]) -> Complex {
    let d = axes.len();
    let counts: &[usize] = &axes.iter().map(Vec::len).collect::<Vec<_>>();
    let stride = |a: usize| counts[..a].iter().product::<usize>();
    let vertex_count: usize = counts.iter().product();
    let coords: Vec<f64> = (0..vertex_count)
        .flat_map(|v| (0..d).map(move |a| axes[a][(v / stride(a)) % counts[a]]))
        .collect();
    let origins =
        (0..vertex_count).filter(|&v| (0..d).all(|a| (v / stride(a)) % counts[a] + 1 < counts[a]));
    let corner = |l: usize| -> usize { (0..d).filter(|a| (l >> a) & 1 == 1).map(stride).sum() };
    // Fixed-size corner lists: no allocation per cell.
    let cells = match d {
        1 => TopCells::cuboids(origins.map(|o| [o, o + 1])),
        2 => TopCells::cuboids(origins.map(|o| std::array::from_fn::<_, 4, _>(|l| o + corner(l)))),
        _ => TopCells::cuboids(origins.map(|o| std::array::from_fn::<_, 8, _>(|l| o + corner(l)))),
    };
    let vertices = Vertices::new(d, coords).expect("finite coordinates");
    Complex::build(vertices, cells).expect("a valid grid")
}

/// The tags `generate::grid` sets, from the facets' vertex averages (for
/// [`general_grid`]; each call walks the boundary again, so the quick mode
/// times it apart from the build).
fn tag_sides(complex: &mut Complex, axes: &[Vec<f64>]) {
    // A facet on a side has its vertex average on that side's plane;
    // half the smallest spacing tells the planes apart.
    const SIDES: [&str; 6] = ["xmin", "xmax", "ymin", "ymax", "zmin", "zmax"];
    for (a, axis) in axes.iter().enumerate() {
        let half = axis
            .windows(2)
            .map(|w| w[1] - w[0])
            .fold(f64::INFINITY, f64::min)
            / 2.0;
        let ends = [axis[0], axis[axis.len() - 1]];
        for (side, end) in ends.into_iter().enumerate() {
            complex.tag_boundary_where(SIDES[2 * a + side], |c| (c[a] - end).abs() < half);
        }
    }
    complex.tag_boundary_where("boundary", |_| true);
}

/// Construction alone, repeated: one line per build, then the peak memory.
fn quick(which: &str, repeat: usize) {
    let unit = [0.0, 1.0];
    let general = std::env::var_os("COMPLEX_BUILD_GENERAL").is_some();
    let path = if general {
        "general path, untagged"
    } else {
        "generator"
    };
    let axes = match which {
        "3d" => vec![generate::uniform_axis(100, 0.0, 1.0).expect("valid axis"); 3],
        _ => vec![generate::uniform_axis(1000, 0.0, 1.0).expect("valid axis"); 2],
    };
    for _ in 0..repeat {
        let t = Instant::now();
        let mut complex = if general {
            general_grid(&axes)
        } else {
            match which {
                "3d" => generate::box3(100, 100, 100, unit, unit, unit),
                _ => generate::rectangle(1000, 1000, unit, unit),
            }
            .expect("grid parameters are valid")
        };
        let seconds = measure::seconds(t);
        println!(
            "{which} build ({path}) {seconds:.3} s  cells {:?}",
            complex.cell_counts()
        );
        if general {
            let t = Instant::now();
            tag_sides(&mut complex, &axes);
            println!("{which} tags set afterwards {:.3} s", measure::seconds(t));
        }
        if std::env::var_os("COMPLEX_BUILD_HASH").is_some() {
            println!(
                "{which} construction hash {:#018x}",
                construction_hash(&complex)
            );
        }
        drop(black_box(complex));
    }
    println!("peak memory {:.3} GiB", measure::peak_memory_gib());
}

criterion_group!(benches, bench);

fn main() {
    if let Ok(which) = std::env::var("COMPLEX_BUILD_QUICK") {
        let repeat = std::env::var("COMPLEX_BUILD_REPEAT")
            .ok()
            .and_then(|r| r.parse().ok())
            .unwrap_or(1);
        quick(&which, repeat);
        return;
    }
    benches();
    Criterion::default().configure_from_args().final_summary();
}
