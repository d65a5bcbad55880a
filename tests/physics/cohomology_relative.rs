//! Relative (essential) cohomology Hᵏ(K, ∂K) and its harmonic forms, every
//! degree on 2- and 3-complexes (issue 34).
//!
//! Independent facts checked:
//! - Counts: Lefschetz duality on an orientable n-manifold with boundary,
//!   β_k(K, ∂K) = β_{n−k}(K), with the absolute Betti numbers known from
//!   each shape's topology: square and box (contractible: 1, 0, …),
//!   annulus and square ring (a circle: 1, 1, 0), box with a cavity (a
//!   sphere shell: 1, 0, 1, 0), box with a tunnel (a circle: 1, 1, 0, 0).
//!   On a complex without boundary (the flat 3-torus, 1, 3, 3, 1) the
//!   relative classes are the absolute ones. The same numbers also equal
//!   `relative_betti_numbers` (ranks over Q of the restricted
//!   coboundaries, a separate computation from the reduction).
//! - Each generator is an integer cochain, closed exactly (δz = 0 in
//!   integer arithmetic with the full δ, so also across the boundary) and
//!   exactly 0 on every cell of ∂K.
//! - Independence modulo relative exact forms: rank [δ^{k−1}_rel | z₁ … z_β]
//!   − rank δ^{k−1}_rel = β_k(K, ∂K), the restricted matrices built here
//!   from the boundary subcomplex, ranks over Q exact.
//! - Harmonic forms vanish on ∂K exactly, are closed and co-closed at the
//!   interior (k−1)-cells (i.e. ⋆-orthogonal to every relative exact form
//!   d α, α a (k−1)-cochain zero on ∂K), measured from d and ⋆ here, and
//!   independent (⋆-Gram matrix positive definite).
//! - Top degree: the relative class of a box is the period on the
//!   fundamental relative cycle (all cells); its harmonic form has ⋆h
//!   constant, i.e. h_σ = ±|σ|/V (period ±1), and ‖h‖²_⋆ = 1/V.
//! - The square annulus (k = 1): the relative reduction's harmonic form is
//!   the old tree–cotree path's (± one class).
//! - dim ker Δ_k with essential conditions = β_k(K, ∂K) on 3D meshes.

use crate::cohomology_3d::tunnel_box;
use crate::forms_dec::max_abs;
use approx::assert_abs_diff_eq;
use hasse_complex::dual::DualKind;
use hasse_complex::generate::{
    annulus, graded_axis, grid, hollow_box, kuhn, rectangle, torus_flat_box, uniform_axis,
};
use hasse_complex::homology::rank;
use hasse_complex::{Complex, Field as Numbers, TopCells, Vertices};
use hasse_solver::physics::forms::laplacian::relative_betti_numbers;
use hasse_solver::physics::forms::{relative_cocycle_generators, Boundary, Forms, Star};
use sprs::{CsMat, TriMat};
use std::error::Error;

type Result<T = ()> = std::result::Result<T, Box<dyn Error>>;

const BARYCENTRIC: Star = Star::Diagonal(DualKind::Barycentric);

/// Closed and co-closed to this, relative to the form's largest value:
/// h = z − dα is closed exactly up to the rounding of d(dα) over a cell's
/// few terms (≈ 1e-16), and co-closed up to the direct solve's backward
/// error after one refinement step (measured ≤ 1.6e-14 over every mesh,
/// star and degree here: printed by `relative_harmonic_forms_of_every_degree`).
/// 1e-12 leaves a wide margin without hiding a discretisation or solver
/// tolerance error, which would be ≥ 1e-8.
const ROUNDING: f64 = 1e-12;

/// The ring of eight unit squares around a square hole, [0, 3]² minus
/// (1, 2)², from LAR cells: an annulus with straight sides, β = (1, 1, 0).
fn square_ring() -> Result<Complex> {
    let mut coords = Vec::new();
    for j in 0..4 {
        for i in 0..4 {
            coords.extend([i as f64, j as f64]);
        }
    }
    let mut squares = Vec::new();
    for j in 0..3 {
        for i in 0..3 {
            if (i, j) != (1, 1) {
                let v = i + 4 * j;
                squares.push(vec![v, v + 1, v + 4, v + 5]);
            }
        }
    }
    Ok(Complex::build(
        Vertices::new(2, coords)?,
        TopCells::cuboids(squares),
    )?)
}

/// Per p-cell, whether it lies on ∂K.
fn wall(complex: &Complex, p: usize) -> Vec<bool> {
    let wall = complex.boundary_subcomplex();
    (0..complex.cell_count(p))
        .map(|i| wall.contains(p, i))
        .collect()
}

/// δᵖ restricted to the interior p- and (p+1)-cells (renumbered in
/// index order), built here from the boundary subcomplex.
fn relative_delta(complex: &Complex, p: usize) -> CsMat<i8> {
    let number = |mask: &[bool]| {
        let mut next = 0;
        mask.iter()
            .map(|&w| {
                (!w).then(|| {
                    next += 1;
                    next - 1
                })
            })
            .collect::<Vec<_>>()
    };
    let columns = number(&wall(complex, p));
    let count = |m: &[Option<usize>]| m.iter().flatten().count();
    if p == complex.dim() {
        return TriMat::<i8>::new((0, count(&columns))).to_csc();
    }
    let rows = number(&wall(complex, p + 1));
    let mut m = TriMat::new((count(&rows), count(&columns)));
    for (&s, (i, j)) in complex.coboundary(p).iter() {
        if let (Some(r), Some(c)) = (rows[i], columns[j]) {
            m.add_triplet(r, c, s);
        }
    }
    m.to_csc()
}

/// rank [δ^{k−1}_rel | z₁ … z_β] − rank δ^{k−1}_rel over Q: how many of
/// the (relative) cochains are independent modulo relative exact forms.
fn rank_modulo_relative_exact(complex: &Complex, k: usize, cochains: &[Vec<f64>]) -> usize {
    let interior: Vec<usize> = wall(complex, k)
        .iter()
        .enumerate()
        .filter(|(_, w)| !**w)
        .map(|(i, _)| i)
        .collect();
    let lower = if k == 0 {
        TriMat::<i8>::new((interior.len(), 0)).to_csc()
    } else {
        relative_delta(complex, k - 1)
    };
    let mut both = TriMat::new((interior.len(), lower.cols() + cochains.len()));
    for (&s, (i, j)) in lower.iter() {
        both.add_triplet(i, j, s);
    }
    for (g, z) in cochains.iter().enumerate() {
        for (row, &cell) in interior.iter().enumerate() {
            if z[cell] != 0.0 {
                // Entries fit i8: asserted by the callers.
                both.add_triplet(row, lower.cols() + g, z[cell] as i8);
            }
        }
    }
    rank(&both.to_csc(), Numbers::Rationals) - rank(&lower, Numbers::Rationals)
}

/// δᵏ z in integer arithmetic, with the complex's full δᵏ.
fn integer_coboundary(complex: &Complex, k: usize, z: &[f64]) -> Vec<i64> {
    if k == complex.dim() {
        return Vec::new();
    }
    complex
        .coboundary(k)
        .outer_iterator()
        .map(|row| row.iter().map(|(j, &s)| i64::from(s) * z[j] as i64).sum())
        .collect()
}

/// The shapes with their absolute Betti numbers, known from topology.
fn shapes() -> Result<Vec<(&'static str, Complex, Vec<usize>)>> {
    let unit = uniform_axis(3, 0.0, 1.0)?;
    Ok(vec![
        (
            "square",
            rectangle(4, 3, [0.0, 1.0], [0.0, 1.0])?,
            vec![1, 0, 0],
        ),
        ("annulus", annulus(1.0, 2.0, 3, 12)?, vec![1, 1, 0]),
        ("square ring", square_ring()?, vec![1, 1, 0]),
        (
            "box",
            grid(&[unit.clone(), unit.clone(), unit.clone()])?,
            vec![1, 0, 0, 0],
        ),
        (
            "Kuhn box",
            kuhn(&[unit.clone(), unit.clone(), unit])?,
            vec![1, 0, 0, 0],
        ),
        (
            "box with a cavity",
            hollow_box(4, [1, 3])?,
            vec![1, 0, 1, 0],
        ),
        (
            "box with a tunnel",
            tunnel_box(3, 1, 1..2)?,
            vec![1, 1, 0, 0],
        ),
        ("longer tunnel", tunnel_box(4, 2, 1..3)?, vec![1, 1, 0, 0]),
    ])
}

/// Every degree on every shape: β_{n−k}(K) generators (Lefschetz), equal
/// to the relative Betti numbers from ranks; integer, closed exactly, 0 on
/// ∂K exactly, independent modulo relative exact forms. On the flat
/// 3-torus (no boundary) the relative classes are the absolute ones.
#[test]
fn relative_generators_count_lefschetz_duals() -> Result {
    let mut all = shapes()?;
    all.push((
        "3-torus",
        torus_flat_box([3, 3, 3], [[0.0, 1.0]; 3], false)?,
        vec![1, 3, 3, 1],
    ));
    for (name, complex, betti) in &all {
        let n = complex.dim();
        assert_eq!(&complex.betti_numbers(), betti, "{name}");
        let closed_manifold = complex.boundary_subcomplex().cells(n - 1).is_empty();
        let expected: Vec<usize> = if closed_manifold {
            betti.clone()
        } else {
            (0..=n).map(|k| betti[n - k]).collect()
        };
        assert_eq!(relative_betti_numbers(complex), expected, "{name}");
        for (k, &count) in expected.iter().enumerate() {
            let generators = relative_cocycle_generators(complex, k)?;
            assert_eq!(generators.len(), count, "{name}, degree {k}");
            let on_wall = wall(complex, k);
            for z in &generators {
                assert!(
                    z.iter().all(|v| v.fract() == 0.0 && v.abs() <= 127.0),
                    "{name}, degree {k}: not small integers"
                );
                assert!(
                    integer_coboundary(complex, k, z).iter().all(|&x| x == 0),
                    "{name}, degree {k}: not closed"
                );
                assert!(
                    z.iter().zip(&on_wall).all(|(v, w)| !w || *v == 0.0),
                    "{name}, degree {k}: nonzero on the boundary"
                );
            }
            assert_eq!(
                rank_modulo_relative_exact(complex, k, &generators),
                count,
                "{name}, degree {k}"
            );
        }
    }
    Ok(())
}

/// ‖dh‖_∞/‖h‖_∞ and ‖d_{k−1}ᵀ⋆h‖_∞/‖⋆h‖_∞ at the interior (k−1)-cells.
fn relative_residuals(forms: &Forms<'_>, k: usize, h: &[f64]) -> Result<(f64, f64)> {
    let complex = forms.complex();
    let dh: Vec<f64> = forms
        .d(k)?
        .outer_iterator()
        .map(|row| row.iter().map(|(j, &s)| f64::from(s) * h[j]).sum())
        .collect();
    let closed = max_abs(&dh) / max_abs(h);
    if k == 0 {
        return Ok((closed, 0.0));
    }
    let weighted = forms.star(k)?.apply(h);
    let mut divergence = vec![0.0; complex.cell_count(k - 1)];
    for (row, w) in forms.d(k - 1)?.outer_iterator().zip(&weighted) {
        for (v, &s) in row.iter() {
            divergence[v] += f64::from(s) * w;
        }
    }
    let interior: Vec<f64> = divergence
        .iter()
        .zip(wall(complex, k - 1))
        .filter(|(_, w)| !w)
        .map(|(d, _)| *d)
        .collect();
    Ok((closed, max_abs(&interior) / max_abs(&weighted)))
}

/// The relative harmonic forms of every degree on every shape (barycentric
/// star; the Whitney star too on the Kuhn box): as many as the Lefschetz
/// dual Betti numbers, 0 on ∂K exactly, closed and co-closed at interior
/// cells to rounding, ⋆-Gram matrix positive definite.
#[test]
fn relative_harmonic_forms_of_every_degree() -> Result {
    let mut worst: f64 = 0.0;
    for (name, complex, betti) in &shapes()? {
        let n = complex.dim();
        let stars: &[Star] = if *name == "Kuhn box" {
            &[BARYCENTRIC, Star::Whitney]
        } else {
            &[BARYCENTRIC]
        };
        for &star in stars {
            let forms = Forms::new(complex, star);
            for k in 0..=n {
                let count = betti[n - k];
                let basis = forms.harmonic_basis_with(k, Boundary::Essential)?;
                assert_eq!(
                    (basis.forms.len(), basis.betti),
                    (count, count),
                    "{name} {star:?} {k}"
                );
                let on_wall = wall(complex, k);
                for h in &basis.forms {
                    assert!(h.iter().zip(&on_wall).all(|(v, w)| !w || *v == 0.0));
                    let (closed, coclosed) = relative_residuals(&forms, k, h)?;
                    assert!(closed < ROUNDING, "{name} {k}: closed to {closed:e}");
                    assert!(coclosed < ROUNDING, "{name} {k}: co-closed to {coclosed:e}");
                    worst = worst.max(closed).max(coclosed);
                }
                let gram = nalgebra::DMatrix::from_fn(count, count, |i, j| {
                    forms
                        .inner(k, &basis.forms[i], &basis.forms[j])
                        .unwrap_or(f64::NAN)
                });
                if count > 0 {
                    assert!(gram.clone().cholesky().is_some(), "{name} {k}: {gram}");
                }
            }
        }
    }
    eprintln!("worst relative residual (closed, co-closed): {worst:e}");
    Ok(())
}

/// The square annulus and the round one, k = 1: the relative reduction's
/// generator, made harmonic with the relative exact part, is the harmonic
/// form of the tree–cotree path (which `harmonic_basis_with` keeps on
/// surfaces) up to the sign of the class: one class (β₁(K, ∂K) = β₁(K) =
/// 1), one harmonic form per class. The generators differ by a relative
/// exact form (or its negative).
#[test]
fn square_annulus_matches_the_tree_cotree_path() -> Result {
    for (name, complex) in [
        ("square ring", square_ring()?),
        ("annulus", annulus(1.0, 2.0, 4, 16)?),
    ] {
        let forms = Forms::new(&complex, BARYCENTRIC);
        let old = forms.harmonic_basis_with(1, Boundary::Essential)?;
        let generators = relative_cocycle_generators(&complex, 1)?;
        assert_eq!((old.forms.len(), generators.len()), (1, 1), "{name}");
        let part = forms.exact_part_with(1, &generators, Boundary::Essential)?;
        let new: Vec<f64> = generators[0]
            .iter()
            .zip(&part[0].exact)
            .map(|(z, e)| z - e)
            .collect();
        let sign = forms.inner(1, &new, &old.forms[0])?.signum();
        let scale = max_abs(&old.forms[0]);
        for (a, b) in new.iter().zip(&old.forms[0]) {
            assert_abs_diff_eq!(sign * a, *b, epsilon = ROUNDING * scale);
        }
        // z_new ∓ z_old is relative exact: it adds nothing to the rank.
        let difference: Vec<f64> = generators[0]
            .iter()
            .zip(&old.generators[0])
            .map(|(a, b)| sign * a - b)
            .collect();
        assert_eq!(
            rank_modulo_relative_exact(&complex, 1, &[difference]),
            0,
            "{name}"
        );
    }
    Ok(())
}

/// The fundamental relative n-cycle of a connected orientable complex:
/// signs c_σ = ±1 with ∂c supported on ∂K, found by walking across
/// interior faces (the two cells of face f need s_fσ c_σ + s_fτ c_τ = 0),
/// then checked: ∂c vanishes on every interior face.
fn fundamental_relative_cycle(complex: &Complex) -> Result<Vec<f64>> {
    let n = complex.dim();
    let by_face = complex.boundary(n);
    let by_cell = complex.boundary_csc(n);
    let mut c = vec![0.0; complex.cell_count(n)];
    c[0] = 1.0;
    let mut stack = vec![0];
    while let Some(cell) = stack.pop() {
        let faces = by_cell.outer_view(cell).ok_or("no faces")?;
        for (f, &s) in faces.iter() {
            let row = by_face.outer_view(f).ok_or("no cofaces")?;
            for (other, &t) in row.iter() {
                if c[other] == 0.0 {
                    c[other] = -f64::from(s) * c[cell] / f64::from(t);
                    stack.push(other);
                }
            }
        }
    }
    let on_faces = wall(complex, n - 1);
    for (f, row) in by_face.outer_iterator().enumerate() {
        let sum: f64 = row.iter().map(|(cell, &s)| f64::from(s) * c[cell]).sum();
        assert!(on_faces[f] || sum == 0.0, "face {f}: ∂c = {sum}");
    }
    assert!(c.iter().all(|&x| x == 1.0 || x == -1.0));
    Ok(c)
}

/// Top degree on boxes (2D rectangle, 3D graded box of volume V = 3, the
/// unit box of cubes and of Kuhn tetrahedra): Hⁿ(K, ∂K) = Z, generated by any one
/// cell's indicator. The generator z is ±e_σ up to a relative coboundary
/// (rank check), with period ±1 on the fundamental relative cycle c (the
/// coherently signed sum of all top cells: its boundary lies on ∂K). Its
/// harmonic form is co-closed at interior faces, so c_σ ⋆h_σ = c_σ h_σ/|σ|
/// (the diagonal ⋆ₙ is 1/|σ|: the dual of a top cell is a point) is one
/// constant C, and the period ⟨h, c⟩ = C V gives C = ±1/V: h_σ = ±c_σ|σ|/V,
/// and ‖h‖²_⋆ = Σ |σ|²/V² · 1/|σ| = 1/V (the ⋆-normalised form is
/// ±c_σ|σ|/√V).
#[test]
fn top_degree_form_is_the_volume_density() -> Result {
    let cases = [
        ("rectangle", rectangle(3, 2, [0.0, 1.5], [0.0, 1.0])?, 1.5),
        (
            "graded box",
            grid(&[
                graded_axis(3, 0.0, 2.0, 1.5)?,
                graded_axis(2, 0.0, 1.0, 2.0)?,
                uniform_axis(3, 0.0, 1.5)?,
            ])?,
            3.0,
        ),
        (
            "unit box",
            grid(&[
                uniform_axis(2, 0.0, 1.0)?,
                uniform_axis(2, 0.0, 1.0)?,
                uniform_axis(2, 0.0, 1.0)?,
            ])?,
            1.0,
        ),
        (
            "unit box of Kuhn tetrahedra",
            kuhn(&[
                uniform_axis(2, 0.0, 1.0)?,
                uniform_axis(2, 0.0, 1.0)?,
                uniform_axis(2, 0.0, 1.0)?,
            ])?,
            1.0,
        ),
    ];
    for (name, complex, volume) in &cases {
        let n = complex.dim();
        let cells = complex.cell_count(n);
        let measures = complex.measure(n);
        assert_abs_diff_eq!(measures.iter().sum::<f64>(), *volume, epsilon = 1e-12);
        let c = fundamental_relative_cycle(complex)?;
        let generators = relative_cocycle_generators(complex, n)?;
        assert_eq!(generators.len(), 1, "{name}");
        let z = &generators[0];
        let period: f64 = z.iter().zip(&c).map(|(a, b)| a * b).sum();
        assert!(period == 1.0 || period == -1.0, "{name}: period {period}");
        // z − period · c₀ e₀ has period 0: a relative coboundary.
        let mut shifted = z.clone();
        shifted[0] -= period * c[0];
        assert_eq!(
            rank_modulo_relative_exact(complex, n, &[shifted]),
            0,
            "{name}: z is not ±e₀ up to a relative coboundary"
        );
        let forms = Forms::new(complex, BARYCENTRIC);
        let basis = forms.harmonic_basis_with(n, Boundary::Essential)?;
        assert_eq!(basis.forms.len(), 1);
        let h = &basis.forms[0];
        for cell in 0..cells {
            let density = period * c[cell] * measures[cell] / volume;
            assert_abs_diff_eq!(h[cell], density, epsilon = ROUNDING);
        }
        assert_abs_diff_eq!(forms.inner(n, h, h)?, 1.0 / volume, epsilon = ROUNDING);
    }
    Ok(())
}

/// dim ker Δ_k with essential conditions (the relative Hodge Laplacian,
/// diagonal star) = β_{n−k}(K) by Lefschetz duality, every degree, on the
/// 3D shapes: box (0, 0, 0, 1), cavity (0, 1, 0, 1), tunnel (0, 0, 1, 1);
/// the Whitney star (mixed form) on a Kuhn box too.
#[test]
fn relative_laplacian_kernels_in_three_dimensions() -> Result {
    let unit = uniform_axis(3, 0.0, 1.0)?;
    let shapes = [
        (
            "box",
            grid(&[unit.clone(), unit.clone(), unit])?,
            [1, 0, 0, 0],
        ),
        ("box with a cavity", hollow_box(4, [1, 3])?, [1, 0, 1, 0]),
        // One cell thick: every vertex and edge lies on ∂K, so Δ₀ and Δ₁
        // have no unknowns and an empty kernel.
        ("box with a tunnel", tunnel_box(3, 1, 1..2)?, [1, 1, 0, 0]),
        ("longer tunnel", tunnel_box(4, 2, 1..3)?, [1, 1, 0, 0]),
    ];
    for (name, complex, betti) in &shapes {
        let forms = Forms::new(complex, BARYCENTRIC);
        for k in 0..=3 {
            let laplacian = forms.hodge_laplacian(k, Boundary::Essential)?;
            let modes = laplacian.modes(2, &laplacian.default_options())?;
            assert_eq!(
                (modes.kernel, laplacian.betti()),
                (betti[3 - k], betti[3 - k]),
                "{name}, degree {k}"
            );
        }
    }
    let x = uniform_axis(2, 0.0, 1.0)?;
    let tets = kuhn(&[x.clone(), x.clone(), x])?;
    let forms = Forms::new(&tets, Star::Whitney);
    for (k, count) in [(0, 0), (1, 0), (2, 0), (3, 1)] {
        let laplacian = forms.hodge_laplacian(k, Boundary::Essential)?;
        let modes = laplacian.modes(2, &laplacian.default_options())?;
        assert_eq!(
            (modes.kernel, laplacian.betti()),
            (count, count),
            "Kuhn box {k}"
        );
    }
    Ok(())
}
