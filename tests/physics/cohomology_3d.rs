//! Cohomology generators and harmonic forms of degrees 1 and 2 on
//! 3-complexes (issue 34), from the integer reduction of the coboundary.
//!
//! Independent facts checked:
//! - Counts: the generators of Hᵏ number β_k of the shape's topology: the
//!   3-torus (1, 3, 3, 1), the box with a cavity (a sphere shell up to
//!   homotopy: 1, 0, 1, 0), the box with a tunnel through it (a solid
//!   torus up to homotopy: 1, 1, 0, 0); and the same as the Betti
//!   numbers the complex crate computes from the ranks of ∂ (homology, a
//!   separate reduction).
//! - Each generator is closed exactly: δz = 0 in integer arithmetic.
//! - Independence modulo exact forms: rank [δ^{k−1} | z₁ … z_β] −
//!   rank δ^{k−1} = β_k, ranks over Q exact (the complex crate's rank).
//! - Harmonic forms are closed and co-closed, measured from d and ⋆ here.
//! - Flat 3-torus: the harmonic 1-forms are the constant forms
//!   a dx + b dy + c dz (constant fields are curl- and divergence-free) and the
//!   harmonic 2-forms the constant fluxes a dy∧dz + b dz∧dx + c dx∧dy.
//!   A harmonic form has its cocycle's integer periods (it differs by an
//!   exact form), so h = Σ n_a dx_a / L_a with integers n_a, and the period
//!   matrix of a basis of H¹(T³; Z) has determinant ±1. The ⋆-inner
//!   product of two constant 1-forms is the integral of F · G over the box:
//!   V Σ_a c_a c'_a (the diagonal star on a uniform box grid is exact for
//!   them: edge e along a carries c_a h_a with weight |⋆e|/|e| =
//!   h_b h_c / h_a, and there are n₀n₁n₂ edges along each axis).

use crate::forms_dec::{max_abs, residuals};
use approx::assert_abs_diff_eq;
use hasse_complex::dual::DualKind;
use hasse_complex::generate::{hollow_box, torus_flat_box, uniform_axis};
use hasse_complex::homology::rank;
use hasse_complex::{Complex, Field as Numbers, TopCells, Vertices};
use hasse_solver::physics::forms::whitney_map::{cell_vectors, de_rham, Field};
use hasse_solver::physics::forms::{cocycle_generators, Forms, FormsError, Star};
use sprs::TriMat;
use std::error::Error;

type Result<T = ()> = std::result::Result<T, Box<dyn Error>>;

const CIRCUMCENTRIC: Star = Star::Diagonal(DualKind::Circumcentric);
const BARYCENTRIC: Star = Star::Diagonal(DualKind::Barycentric);

/// Closed and co-closed to this, relative to the form's largest value:
/// h = c − dα is closed exactly (c an integer cocycle, d d = 0 in
/// integers, so only the rounding of d(dα) over a face's few terms,
/// ≈ 1e-16 relative), and co-closed up to the direct solve's backward
/// error, refined once (measured ≤ 2.5e-14 on every mesh here and on the
/// 8³ torus, for both degrees). 1e-12 leaves a factor 40 of margin without
/// hiding an O(h) or solver-tolerance error, which would be ≥ 1e-8.
const ROUNDING: f64 = 1e-12;

/// A box of `n` × `n` × `layers` unit cubes with the cubes whose (i, j)
/// lie in `hole` × `hole` removed through every layer: a tunnel along z,
/// so the solid is a thickened circle, β = (1, 1, 0, 0).
pub(crate) fn tunnel_box(n: usize, layers: usize, hole: std::ops::Range<usize>) -> Result<Complex> {
    let index = |i: usize, j: usize, k: usize| i + (n + 1) * (j + (n + 1) * k);
    let mut coords = Vec::new();
    for k in 0..=layers {
        for j in 0..=n {
            for i in 0..=n {
                coords.extend([i as f64, j as f64, k as f64]);
            }
        }
    }
    let mut cubes: Vec<[usize; 8]> = Vec::new();
    for k in 0..layers {
        for j in 0..n {
            for i in 0..n {
                if hole.contains(&i) && hole.contains(&j) {
                    continue;
                }
                // Tensor order, x fastest.
                cubes.push([
                    index(i, j, k),
                    index(i + 1, j, k),
                    index(i, j + 1, k),
                    index(i + 1, j + 1, k),
                    index(i, j, k + 1),
                    index(i + 1, j, k + 1),
                    index(i, j + 1, k + 1),
                    index(i + 1, j + 1, k + 1),
                ]);
            }
        }
    }
    // Vertices strictly inside the hole belong to no cube: renumber the
    // used ones so that none is isolated.
    let mut renumber = vec![usize::MAX; coords.len() / 3];
    let mut kept = Vec::new();
    for cube in &mut cubes {
        for v in cube.iter_mut() {
            if renumber[*v] == usize::MAX {
                renumber[*v] = kept.len();
                kept.push(*v);
            }
            *v = renumber[*v];
        }
    }
    let coords = kept
        .iter()
        .flat_map(|&v| coords[3 * v..3 * v + 3].to_vec())
        .collect();
    Ok(Complex::build(
        Vertices::new(3, coords)?,
        TopCells::cuboids(cubes),
    )?)
}

/// δᵏ z in integer arithmetic (the cochain's values are integers).
fn integer_coboundary(complex: &Complex, k: usize, z: &[f64]) -> Vec<i64> {
    if k == complex.dim() {
        return Vec::new();
    }
    let d = complex.coboundary(k);
    d.outer_iterator()
        .map(|row| row.iter().map(|(j, &s)| i64::from(s) * z[j] as i64).sum())
        .collect()
}

/// rank over Q of δ^{k−1} with the generators appended as columns, minus
/// rank δ^{k−1}: the number of generators independent modulo exact forms.
fn rank_modulo_exact(complex: &Complex, k: usize, generators: &[Vec<f64>]) -> usize {
    let cells = complex.cell_count(k);
    let lower_cols = if k == 0 { 0 } else { complex.cell_count(k - 1) };
    let mut both = TriMat::new((cells, lower_cols + generators.len()));
    let mut lower = TriMat::new((cells, lower_cols));
    if k > 0 {
        for (&s, (i, j)) in complex.coboundary(k - 1).iter() {
            both.add_triplet(i, j, s);
            lower.add_triplet(i, j, s);
        }
    }
    for (g, z) in generators.iter().enumerate() {
        for (i, &v) in z.iter().enumerate() {
            if v != 0.0 {
                // Entries fit i8: asserted by the caller.
                both.add_triplet(i, lower_cols + g, v as i8);
            }
        }
    }
    rank(&both.to_csc(), Numbers::Rationals) - rank(&lower.to_csc(), Numbers::Rationals)
}

/// Every degree on the three shapes: β_k generators (known topology and
/// the complex's own Betti numbers), each closed exactly, independent
/// modulo exact forms.
#[test]
fn generators_of_every_degree_count_betti() -> Result {
    let torus_cubes = torus_flat_box([3, 3, 4], [[0.0, 3.0], [0.0, 3.0], [0.0, 4.0]], false)?;
    let torus_tets = torus_flat_box([3, 3, 3], [[0.0, 1.0], [0.0, 1.0], [0.0, 1.0]], true)?;
    let shapes = [
        ("3-torus of cubes", torus_cubes, [1, 3, 3, 1]),
        ("3-torus of tetrahedra", torus_tets, [1, 3, 3, 1]),
        ("box with a cavity", hollow_box(4, [1, 3])?, [1, 0, 1, 0]),
        ("box with a tunnel", tunnel_box(3, 1, 1..2)?, [1, 1, 0, 0]),
        ("longer tunnel", tunnel_box(4, 2, 1..3)?, [1, 1, 0, 0]),
    ];
    for (name, complex, betti) in &shapes {
        assert_eq!(complex.betti_numbers(), betti.to_vec(), "{name}");
        for (k, &b) in betti.iter().enumerate() {
            let generators = cocycle_generators(complex, k)?;
            assert_eq!(generators.len(), b, "{name}, degree {k}");
            for z in &generators {
                assert!(z.iter().all(|v| v.fract() == 0.0 && v.abs() <= 127.0));
                assert!(
                    integer_coboundary(complex, k, z).iter().all(|&x| x == 0),
                    "{name}, degree {k}: not closed"
                );
            }
            assert_eq!(
                rank_modulo_exact(complex, k, &generators),
                b,
                "{name}, degree {k}"
            );
        }
    }
    Ok(())
}

/// The harmonic forms of degrees 1 and 2 on the three shapes, with each
/// star the mesh allows: closed and co-closed to rounding, and ⋆-Gram
/// matrix positive definite (independent forms).
#[test]
fn harmonic_forms_of_degrees_one_and_two_are_harmonic() -> Result {
    let torus_cubes = torus_flat_box([3, 4, 5], [[0.0, 3.0], [0.0, 2.0], [0.0, 1.0]], false)?;
    let torus_tets = torus_flat_box([3, 3, 4], [[0.0, 1.0], [0.0, 1.0], [0.0, 2.0]], true)?;
    let cavity = hollow_box(5, [2, 3])?;
    let tunnel = tunnel_box(4, 2, 1..3)?;
    let cases: [(&str, &Complex, Star, [usize; 2]); 5] = [
        (
            "3-torus, cubes, barycentric",
            &torus_cubes,
            BARYCENTRIC,
            [3, 3],
        ),
        (
            "3-torus, tetrahedra, barycentric",
            &torus_tets,
            BARYCENTRIC,
            [3, 3],
        ),
        (
            "3-torus, tetrahedra, Whitney",
            &torus_tets,
            Star::Whitney,
            [3, 3],
        ),
        ("cavity, barycentric", &cavity, BARYCENTRIC, [0, 1]),
        ("tunnel, barycentric", &tunnel, BARYCENTRIC, [1, 0]),
    ];
    for (name, complex, star, counts) in cases {
        let forms = Forms::new(complex, star);
        for (k, count) in [(1, counts[0]), (2, counts[1])] {
            let basis = forms.harmonic_basis(k)?;
            assert_eq!(
                (basis.forms.len(), basis.betti),
                (count, count),
                "{name} {k}"
            );
            for h in &basis.forms {
                let (closed, coclosed) = residuals(&forms, k, h)?;
                assert!(closed < ROUNDING, "{name} {k}: closed to {closed:e}");
                assert!(coclosed < ROUNDING, "{name} {k}: co-closed to {coclosed:e}");
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
    Ok(())
}

/// The coefficients c of `target` ≈ Σ c_i basis_i (least squares) and the
/// largest residual.
fn fit(basis: &[Vec<f64>], target: &[f64]) -> (Vec<f64>, f64) {
    let m = basis.len();
    let gram = nalgebra::DMatrix::from_fn(m, m, |i, j| {
        basis[i].iter().zip(&basis[j]).map(|(a, b)| a * b).sum()
    });
    let rhs = nalgebra::DVector::from_fn(m, |i, _| {
        basis[i].iter().zip(target).map(|(a, b)| a * b).sum()
    });
    let c = gram
        .lu()
        .solve(&rhs)
        .unwrap_or_else(|| nalgebra::DVector::from_element(m, f64::NAN));
    let residual: Vec<f64> = (0..target.len())
        .map(|e| target[e] - (0..m).map(|i| c[i] * basis[i][e]).sum::<f64>())
        .collect();
    (c.iter().copied().collect(), max_abs(&residual))
}

/// The 3×3 determinant.
fn det3(m: &[[f64; 3]; 3]) -> f64 {
    m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1])
        - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0])
        + m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0])
}

/// Flat 3-torus of cubes (barycentric = circumcentric star) and of Kuhn
/// tetrahedra (Whitney star): the harmonic 1-forms span exactly the
/// constant forms R₁(e_x), R₁(e_y), R₁(e_z) (on an edge along a: h_a), with
/// integer periods n_a = c_a L_a forming a unimodular matrix, and the
/// ⋆-Gram matrix is V Σ_a c_a c'_a (the integral of the constant fields'
/// product).
#[test]
fn flat_three_torus_harmonic_one_forms_are_dx_dy_dz() -> Result {
    let lengths = [3.0, 2.0, 1.5];
    let extent = lengths.map(|l| [0.0, l]);
    for (simplices, star) in [(false, BARYCENTRIC), (true, Star::Whitney)] {
        let k = torus_flat_box([3, 4, 3], extent, simplices)?;
        let forms = Forms::new(&k, star);
        let basis = forms.harmonic_basis(1)?;
        assert_eq!(basis.forms.len(), 3);
        let axes: Vec<Vec<f64>> = (0..3)
            .map(|a| {
                de_rham(
                    &k,
                    1,
                    Field::Vector(&move |_| {
                        let mut f = [0.0; 3];
                        f[a] = 1.0;
                        f
                    }),
                )
            })
            .collect::<std::result::Result<_, _>>()?;
        let mut periods = [[0.0; 3]; 3];
        let mut coefficients = Vec::new();
        for (row, h) in basis.forms.iter().enumerate() {
            let (c, residual) = fit(&axes, h);
            assert!(residual < ROUNDING * max_abs(h), "{residual:e}");
            for a in 0..3 {
                let n = c[a] * lengths[a];
                assert_abs_diff_eq!(n, n.round(), epsilon = 1e-12);
                periods[row][a] = n.round();
            }
            coefficients.push(c);
        }
        assert_abs_diff_eq!(det3(&periods).abs(), 1.0);
        let volume: f64 = lengths.iter().product();
        for i in 0..3 {
            for j in 0..3 {
                let exact: f64 = volume
                    * (0..3)
                        .map(|a| coefficients[i][a] * coefficients[j][a])
                        .sum::<f64>();
                let inner = forms.inner(1, &basis.forms[i], &basis.forms[j])?;
                assert_abs_diff_eq!(inner, exact, epsilon = 1e-12 * volume);
            }
        }
    }
    Ok(())
}

/// Flat 3-torus of Kuhn tetrahedra (Whitney and barycentric stars): the
/// harmonic 2-forms span exactly the constant fluxes R₂(e_x), R₂(e_y),
/// R₂(e_z) (dy∧dz, dz∧dx, dx∧dy), with integer periods n_a = c_a A_a
/// (A_a the area of the torus's cross-section normal to a) of
/// determinant ±1.
#[test]
fn flat_three_torus_harmonic_two_forms_are_constant_fluxes() -> Result {
    let lengths = [3.0, 2.0, 1.5];
    let extent = lengths.map(|l| [0.0, l]);
    let k = torus_flat_box([3, 4, 3], extent, true)?;
    let fluxes: Vec<Vec<f64>> = (0..3)
        .map(|a| {
            de_rham(
                &k,
                2,
                Field::Vector(&move |_| {
                    let mut f = [0.0; 3];
                    f[a] = 1.0;
                    f
                }),
            )
        })
        .collect::<std::result::Result<_, _>>()?;
    let sections = [
        lengths[1] * lengths[2],
        lengths[2] * lengths[0],
        lengths[0] * lengths[1],
    ];
    for star in [Star::Whitney, BARYCENTRIC] {
        let basis = Forms::new(&k, star).harmonic_basis(2)?;
        assert_eq!(basis.forms.len(), 3);
        let mut periods = [[0.0; 3]; 3];
        for (row, h) in basis.forms.iter().enumerate() {
            let (c, residual) = fit(&fluxes, h);
            assert!(residual < ROUNDING * max_abs(h), "{residual:e}");
            for a in 0..3 {
                let n = c[a] * sections[a];
                assert_abs_diff_eq!(n, n.round(), epsilon = 1e-12);
                periods[row][a] = n.round();
            }
        }
        assert_abs_diff_eq!(det3(&periods).abs(), 1.0);
    }
    Ok(())
}

/// Flat 3-torus of cubes: each harmonic 2-form is a constant flux, so on
/// every face normal to axis a it has the same magnitude |c_a| h_b h_c
/// (the face's area), and its vector proxy per cube (least-squares
/// constant field of the six fluxes) is the same vector (±c_a per axis)
/// in every cube, with |v_a| = |h_f| / |f|.
#[test]
fn flat_three_torus_of_cubes_two_forms_are_constant_fluxes() -> Result {
    let lengths = [3.0, 2.0, 1.5];
    let n = [3, 4, 3];
    let k = torus_flat_box(n, lengths.map(|l| [0.0, l]), false)?;
    let h: Vec<f64> = (0..3).map(|a| lengths[a] / n[a] as f64).collect();
    let basis = Forms::new(&k, BARYCENTRIC).harmonic_basis(2)?;
    assert_eq!(basis.forms.len(), 3);
    for form in &basis.forms {
        let vectors = cell_vectors(&k, 2, form)?;
        let first = vectors[0];
        for v in &vectors {
            for a in 0..3 {
                assert_abs_diff_eq!(v[a], first[a], epsilon = 1e-12 * max_abs(form));
            }
        }
        for (f, value) in form.iter().enumerate() {
            let points = k.cell_points(2, f);
            // The normal axis: the coordinate all four corners share.
            let a = (0..3)
                .find(|&a| points.iter().all(|p| (p[a] - points[0][a]).abs() < 1e-12))
                .ok_or("a face is not axis-aligned")?;
            let area = h[(a + 1) % 3] * h[(a + 2) % 3];
            assert_abs_diff_eq!(value.abs(), first[a].abs() * area, epsilon = 1e-12);
        }
    }
    Ok(())
}

/// The flux proxy on cubes against Stokes: the 2-cochain δ¹ R₁(A) of the
/// linear potential A = ½ F × x holds the fluxes of curl A = F through
/// each face (R₁ exact for linear fields), and the least-squares vector of
/// every cube of a (non-periodic) box grid is F.
#[test]
fn flux_proxy_on_cubes_is_the_constant_field() -> Result {
    let f = [0.3, -1.2, 2.0];
    let axis = uniform_axis(3, 0.0, 1.5)?;
    let k = hasse_complex::generate::grid(&[axis.clone(), uniform_axis(2, 0.0, 1.0)?, axis])?;
    let potential = move |x: &[f64]| {
        [
            0.5 * (f[1] * x[2] - f[2] * x[1]),
            0.5 * (f[2] * x[0] - f[0] * x[2]),
            0.5 * (f[0] * x[1] - f[1] * x[0]),
        ]
    };
    let a = de_rham(&k, 1, Field::Vector(&potential))?;
    let flux: Vec<f64> = k
        .coboundary(1)
        .outer_iterator()
        .map(|row| row.iter().map(|(e, &s)| f64::from(s) * a[e]).sum())
        .collect();
    for v in cell_vectors(&k, 2, &flux)? {
        for c in 0..3 {
            assert_abs_diff_eq!(v[c], f[c], epsilon = 1e-13);
        }
    }
    Ok(())
}

/// The circumcentric star of degree 2 on Kuhn tetrahedra: the six
/// tetrahedra of a cube share its circumcentre (they all have the cube's
/// main diagonal as a diameter of their circumsphere), so the dual edge of
/// a face inside a cube has length 0 and ⋆₂ = 0 there. The harmonic
/// 1-forms are still computed (⋆₁ > 0: measured), the 2-forms refused with
/// the typed error naming the star.
#[test]
fn circumcentric_kuhn_torus_refuses_degree_two() -> Result {
    let k = torus_flat_box([3, 3, 3], [[0.0, 1.0]; 3], true)?;
    let forms = Forms::new(&k, CIRCUMCENTRIC);
    let basis = forms.harmonic_basis(1)?;
    assert_eq!(basis.forms.len(), 3);
    for h in &basis.forms {
        let (closed, coclosed) = residuals(&forms, 1, h)?;
        assert!(closed.max(coclosed) < ROUNDING, "{closed:e} {coclosed:e}");
    }
    match forms.harmonic_basis(2) {
        Err(FormsError::NonPositiveStar { k: 2, .. }) => Ok(()),
        other => Err(format!("expected a non-positive ⋆₂, got {other:?}").into()),
    }
}

/// The box with a tunnel: its one harmonic 1-form has period 1 (up to
/// sign) around the tunnel, as its integer cocycle, since they differ by
/// an exact form; the loop is the square of edges around the hole at
/// z = 0.
#[test]
fn tunnel_form_has_period_one_around_the_hole() -> Result {
    let k = tunnel_box(3, 1, 1..2)?;
    let basis = Forms::new(&k, BARYCENTRIC).harmonic_basis(1)?;
    assert_eq!(basis.forms.len(), 1);
    // The vertices (i, j, 0) around the hole's square, in order.
    let at = |x: f64, y: f64| {
        (0..k.cell_count(0))
            .find(|&v| k.vertices().point(v) == [x, y, 0.0])
            .ok_or("no such vertex")
    };
    let ring = [
        at(1.0, 1.0)?,
        at(2.0, 1.0)?,
        at(2.0, 2.0)?,
        at(1.0, 2.0)?,
        at(1.0, 1.0)?,
    ];
    let d0 = k.coboundary(0);
    for cochain in [&basis.generators[0], &basis.forms[0]] {
        let mut period = 0.0;
        for w in ring.windows(2) {
            let (from, to) = (w[0], w[1]);
            let e = k
                .find_cell(1, &[from.min(to), from.max(to)])
                .ok_or("no such edge")?;
            // Along the edge from its −1 end to its +1 end in δ⁰.
            let forward = d0
                .outer_view(e)
                .and_then(|row| row.get(to).copied())
                .ok_or("edge without ends")?
                > 0;
            period += if forward { cochain[e] } else { -cochain[e] };
        }
        assert_abs_diff_eq!(period.abs(), 1.0, epsilon = 1e-12);
    }
    Ok(())
}

/// A 2-complex that is not a surface: the ring of eight unit squares
/// around a square hole (an annulus, β₁ = 1) with a fin, one more square
/// standing on the interior edge x = 1, 0 ≤ y ≤ 1, which then bounds three
/// squares. The fin is a disk glued along an edge, so it changes no Betti
/// number: β = (1, 1, 0). The tree–cotree needs a surface; the reduction
/// gives the one generator, closed exactly and not exact.
#[test]
fn non_surface_two_complex_gets_its_generator() -> Result {
    // Vertices (i, j, 0), i, j ∈ 0..4, index i + 4 j, then the fin's top
    // edge (1, 0, 1) = 16 and (1, 1, 1) = 17.
    let mut coords = Vec::new();
    for j in 0..4 {
        for i in 0..4 {
            coords.extend([i as f64, j as f64, 0.0]);
        }
    }
    coords.extend([1.0, 0.0, 1.0, 1.0, 1.0, 1.0]);
    let mut squares = Vec::new();
    for j in 0..3 {
        for i in 0..3 {
            if (i, j) != (1, 1) {
                let v = i + 4 * j;
                squares.push(vec![v, v + 1, v + 4, v + 5]);
            }
        }
    }
    // Tensor order: (1,0,0), (1,1,0), (1,0,1), (1,1,1).
    squares.push(vec![1, 5, 16, 17]);
    let k = Complex::build(Vertices::new(3, coords)?, TopCells::cuboids(squares))?;
    let shared = k.find_cell(1, &[1, 5]).ok_or("no edge (1,0,0)–(1,1,0)")?;
    assert_eq!(k.boundary(2).outer_view(shared).map_or(0, |r| r.nnz()), 3);
    assert_eq!(k.betti_numbers(), vec![1, 1, 0]);
    let generators = cocycle_generators(&k, 1)?;
    assert_eq!(generators.len(), 1);
    assert!(integer_coboundary(&k, 1, &generators[0])
        .iter()
        .all(|&x| x == 0));
    assert_eq!(rank_modulo_exact(&k, 1, &generators), 1);
    Ok(())
}
