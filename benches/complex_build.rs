//! Building complexes at scale: every boundary matrix ∂_p plus the primal
//! geometry (measures and centroids of every dimension, face normals).
//!
//! Baseline in the same run: the bare LAR product M_{n-1} M_nᵀ of the same
//! grid done by `sprs` (one sparse matrix product, no extraction, no
//! orientation, no geometry), so the printed ratio says how many "plain
//! sparse products" a complete complex costs.
//!
//! Run with `scripts/bench` (prints the headline table) or
//! `cargo bench --bench complex_build`.

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion};
use hasse_complex::{generate, Complex};
use std::hint::black_box;
use std::time::Duration;

fn build_with_geometry(axes: &[Vec<f64>]) -> Complex {
    let complex = generate::grid(axes).expect("grid parameters are valid");
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
    let sizes: Vec<(&str, Vec<Vec<f64>>)> = vec![
        (
            "2d-1000x1000",
            vec![generate::uniform_axis(1000, 0.0, 1.0).expect("valid axis"); 2],
        ),
        (
            "3d-100x100x100",
            vec![generate::uniform_axis(100, 0.0, 1.0).expect("valid axis"); 3],
        ),
    ];
    let mut group = c.benchmark_group("complex_build");
    group
        .sample_size(10)
        .measurement_time(Duration::from_secs(30))
        .warm_up_time(Duration::from_secs(1));
    for (name, axes) in &sizes {
        group.bench_with_input(
            BenchmarkId::new("complex+geometry", name),
            axes,
            |b, axes| b.iter(|| build_with_geometry(axes)),
        );
        let complex = build_with_geometry(axes);
        group.bench_with_input(
            BenchmarkId::new("baseline:sprs M_(n-1) M_n^T", name),
            &complex,
            |b, complex| b.iter(|| bare_product(complex)),
        );
    }
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
