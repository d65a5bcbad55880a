//! Growth: cell counts and sizes derived by hand, mass balance and the
//! topology of every divided complex.

use super::*;
use crate::physics::heat::{HeatBoundary, TimeFn};
use crate::physics::Conductivity;
use approx::assert_relative_eq;
use hasse_complex::generate::{box3, interval, rectangle, voronoi};
use std::sync::Arc;

/// Tests stop at the first error, reported by the test harness.
type TestResult = Result<(), Box<dyn std::error::Error>>;

fn heat(method: Method, dt: f64) -> Heat {
    Heat::new(method, Conductivity::Scalar(Arc::new(|_| 1.0)), dt)
}

/// v = g x in every coordinate (uniform exponential growth).
fn expanding(d: usize, g: f64) -> Vec<SpaceTimeFn> {
    (0..d)
        .map(|k| -> SpaceTimeFn { Arc::new(move |x: &[f64], _| g * x[k]) })
        .collect()
}

/// ∂_{p−1} ∂_p = 0 entry by entry (integers), for every p.
fn boundary_of_boundary_vanishes(k: &Complex) -> bool {
    (2..=k.dim()).all(|p| {
        let dd = &**k.boundary(p - 1) * &**k.boundary(p);
        dd.data().iter().all(|&x| x == 0)
    })
}

/// The signed measure of every top cell computed from its boundary chain
/// alone (1D: head − tail; 2D: the shoelace sum over the edges of ∂c, each
/// edge tail → head as ∂_1 orients it): positive for every cell exactly
/// when the orientation is the ambient one.
fn signed_measures(k: &Complex) -> Vec<f64> {
    let n = k.dim();
    let x = |v: usize| k.vertices().point(v).to_vec();
    let edge = |e: usize| {
        // A missing column gives a zero measure, which the tests refuse.
        let Some(col) = k.boundary_csc(1).outer_view(e) else {
            return (0, 0);
        };
        let (mut tail, mut head) = (0, 0);
        for (v, &s) in col.iter() {
            if s < 0 {
                tail = v;
            } else {
                head = v;
            }
        }
        (tail, head)
    };
    (0..k.cell_count(n))
        .map(|c| match n {
            1 => {
                let (t, h) = edge(c);
                x(h)[0] - x(t)[0]
            }
            _ => {
                let Some(col) = k.boundary_csc(2).outer_view(c) else {
                    return 0.0;
                };
                col.iter()
                    .map(|(e, &s)| {
                        let (t, h) = edge(e);
                        let (a, b) = (x(t), x(h));
                        f64::from(s) * 0.5 * (a[0] * b[1] - a[1] * b[0])
                    })
                    .sum()
            }
        })
        .collect()
}

#[test]
fn a_filament_divides_at_the_hand_counted_steps() -> TestResult {
    // N = 4 cells of length 0.25 on [0, 1], v = 0.5 x, Δt = 0.1: forward
    // Euler stretches every cell by 1 + gΔt = 1.05 a step. With the
    // threshold 0.3: 0.25·1.05³ = 0.289406 < 0.3 < 0.25·1.05⁴ = 0.303877,
    // so the 4 cells halve at step 4 (lengths 0.151938…); they pass 0.3
    // again when 1.05^k > 0.3/0.151938 = 1.97446, i.e. k = 14 (1.05¹³ =
    // 1.8856, 1.05¹⁴ = 1.9799): at step 18. So 4 cells for steps 1–3, 8
    // for 4–17, 16 for 18–20.
    let growth = Growth::new(
        heat(Method::Fv, 0.1),
        expanding(1, 0.5),
        0.3,
        DivisionRule::Midpoint,
    );
    let mut counts = Vec::new();
    let mut checks = Vec::new();
    let mut lengths = Vec::new();
    let steps = growth.run(&interval(4, 0.0, 1.0)?, &|_| 1.0, 20, &mut |t, _| {
        counts.push(t.complex.cell_count(1));
        lengths = t.complex.measure(1).to_vec();
        checks.push((
            t.complex.euler_characteristic(),
            signed_measures(&t.complex).iter().all(|&l| l > 0.0),
        ));
    })?;
    let mut expected = vec![4; 4];
    expected.extend(vec![8; 14]);
    expected.extend(vec![16; 3]);
    assert_eq!(counts, expected);
    // A filament stays one segment: χ = 1, every edge positive.
    assert!(checks.iter().all(|&c| c == (1, true)));
    assert_eq!(steps[3].divided, 4);
    assert_eq!(steps[17].divided, 8);
    // Total length 1.05²⁰ = 2.653297705144422: x_k = x₀(1.05)^k at each
    // vertex up to one rounding a step (20 steps: ~20 ulp).
    assert_relative_eq!(steps[19].size, 1.05f64.powi(20), max_relative = 1e-14);
    // The equal halves of equal cells: all 16 lengths are 1.05²⁰/16.
    assert_eq!(lengths.len(), 16);
    for l in lengths {
        assert_relative_eq!(l, 1.05f64.powi(20) / 16.0, max_relative = 1e-13);
    }
    Ok(())
}

#[test]
fn without_sources_decay_or_flux_the_mass_stays_through_motions_and_divisions() -> TestResult {
    // λ = 0, f = 0, no boundary condition (no flux): every step's
    // equations sum to M^{n+1} = Mⁿ, and motion and division carry
    // amounts exactly; so M stays M⁰ = ∫c⁰ to rounding.
    let c0 = |x: &[f64]| 1.0 + x[0] + 2.0 * x[1];
    for (method, rule) in [
        (Method::FvMimetic, DivisionRule::LongestAxis),
        (Method::Fv, DivisionRule::ShortestWall),
    ] {
        let growth = Growth::new(heat(method, 0.05), expanding(2, 0.5), 0.03, rule);
        let mesh = voronoi(30, [0.0, 1.0], [0.0, 1.0], 7, 5)?;
        let mut masses = Vec::new();
        let steps = growth.run(&mesh, &c0, 8, &mut |t, _| masses.push(t.mass()))?;
        assert!(steps.iter().any(|s| s.divided > 0), "{method:?}");
        for m in &masses {
            assert_relative_eq!(*m, masses[0], max_relative = 1e-13);
        }
        for s in &steps {
            assert_relative_eq!(s.mass_carried, s.mass_before, max_relative = 1e-14);
            assert!(
                s.relative < 1e-13,
                "{method:?} step {}: {}",
                s.number,
                s.relative
            );
        }
    }
    Ok(())
}

#[test]
fn uniform_decay_divides_the_mass_by_one_plus_lambda_dt_each_step() -> TestResult {
    // c uniform, v = g x: every cell stretches by the same factor and
    // halves into equal pieces, so c stays uniform after motion and
    // division; K c = 0 for uniform c (no flux), and backward Euler gives
    // c^{n+1}(1 + λΔt) = cⁿ in every cell: M^{n+1} = Mⁿ/(1 + λΔt). With
    // λ = 2, Δt = 0.1: Mᵏ = 1/1.2ᵏ from M⁰ = 1 (c = 1 on [0, 1]).
    let growth = Growth::new(
        heat(Method::Fv, 0.1),
        expanding(1, 1.0),
        0.3,
        DivisionRule::Midpoint,
    )
    .with_decay(2.0);
    let steps = growth.run(&interval(5, 0.0, 1.0)?, &|_| 1.0, 12, &mut |_, _| {})?;
    assert!(steps.iter().any(|s| s.divided > 0));
    for s in &steps {
        assert_relative_eq!(
            s.mass,
            1.2f64.powi(-(s.number as i32)),
            max_relative = 1e-13
        );
        assert!(s.relative < 1e-13);
    }
    Ok(())
}

#[test]
fn every_divided_tissue_stays_a_coherently_oriented_disc() -> TestResult {
    // After every motion and division: ∂∂ = 0 exactly, every top cell's
    // boundary chain encloses a positive area, and χ = 1 (a disc).
    for rule in [DivisionRule::LongestAxis, DivisionRule::ShortestWall] {
        let growth = Growth::new(heat(Method::FvMimetic, 0.05), expanding(2, 1.0), 0.04, rule);
        let mesh = voronoi(25, [0.0, 1.0], [0.0, 1.0], 3, 5)?;
        let mut seen = 0;
        growth.run(&mesh, &|_| 1.0, 6, &mut |t, _| {
            assert!(boundary_of_boundary_vanishes(&t.complex));
            assert!(signed_measures(&t.complex).iter().all(|&a| a > 0.0));
            assert_eq!(t.complex.euler_characteristic(), 1);
            seen += 1;
        })?;
        assert_eq!(seen, 7);
    }
    Ok(())
}

#[test]
fn a_source_decay_and_a_held_boundary_balance_to_rounding() -> TestResult {
    // f = 1 and v = (g x, g y): the tissue (area 1 at t = 0) is scaled by
    // 1 + gΔt = 1.05 in each direction a step, so ∫f at step k is its
    // area 1.05^{2k}; the balance M^{n+1} − Mⁿ = Δt(∫f − λM − outflow)
    // holds to rounding with c = 0 held on the boundary.
    let h = heat(Method::FvMimetic, 0.1)
        .with_source(TimeFn::Steady(Arc::new(|_| 1.0)))
        .with_boundary(
            "boundary",
            HeatBoundary::Dirichlet(TimeFn::Steady(Arc::new(|_| 0.0))),
        );
    let growth = Growth::new(h, expanding(2, 0.5), 0.05, DivisionRule::LongestAxis).with_decay(0.5);
    let mesh = voronoi(30, [0.0, 1.0], [0.0, 1.0], 7, 5)?;
    let steps = growth.run(&mesh, &|_| 0.0, 6, &mut |_, _| {})?;
    for s in &steps {
        assert_relative_eq!(
            s.sources,
            1.05f64.powi(2 * s.number as i32),
            max_relative = 1e-12
        );
        assert!(s.outflow > 0.0);
        assert!(s.relative < 1e-12, "step {}: {}", s.number, s.relative);
    }
    Ok(())
}

#[test]
fn a_long_rectangle_divides_across_by_either_rule() -> TestResult {
    // One 2 × 1 cell, no motion, threshold 1.5: both rules cut it by
    // x = 1 (the longest axis is x; the shortest wall through (1, ½) is
    // the vertical one, length 1) into two unit squares, each with half
    // the amount 2·c = 2·3.
    for rule in [DivisionRule::LongestAxis, DivisionRule::ShortestWall] {
        let still: Vec<SpaceTimeFn> = vec![Arc::new(|_, _| 0.0), Arc::new(|_, _| 0.0)];
        let growth = Growth::new(heat(Method::Fv, 1.0), still, 1.5, rule);
        let mut tissue = growth.start(&rectangle(1, 1, [0.0, 2.0], [0.0, 1.0])?, &|_| 3.0)?;
        let step = growth.step(&mut tissue)?;
        assert_eq!((step.divided, step.cells), (1, 2));
        assert_eq!(tissue.complex.measure(2), &[1.0, 1.0]);
        // Two cells at c = 3 stay at 3 (no flux between equal values).
        for c in tissue.concentration() {
            assert_relative_eq!(c, 3.0, max_relative = 1e-14);
        }
    }
    Ok(())
}

#[test]
fn growth_refuses_what_it_cannot_grow() -> TestResult {
    let line = interval(2, 0.0, 1.0)?;
    let g = |method, velocity: Vec<SpaceTimeFn>, threshold, rule| {
        Growth::new(heat(method, 0.1), velocity, threshold, rule)
    };
    let one = expanding(1, 1.0);
    assert!(matches!(
        g(Method::Fv, expanding(2, 1.0), 0.3, DivisionRule::Midpoint).check(&line),
        Err(GrowthError::Velocity {
            expected: 1,
            found: 2
        })
    ));
    assert!(matches!(
        g(Method::Fv, one.clone(), 0.0, DivisionRule::Midpoint).check(&line),
        Err(GrowthError::Threshold(_))
    ));
    assert!(matches!(
        g(Method::Fv, one.clone(), 0.3, DivisionRule::LongestAxis).check(&line),
        Err(GrowthError::Rule { dim: 1, .. })
    ));
    assert!(matches!(
        g(Method::Fe, one.clone(), 0.3, DivisionRule::Midpoint).check(&line),
        Err(GrowthError::Method("fe"))
    ));
    let cube = box3(1, 1, 1, [0.0, 1.0], [0.0, 1.0], [0.0, 1.0])?;
    assert!(matches!(
        g(
            Method::Fv,
            expanding(3, 1.0),
            0.3,
            DivisionRule::LongestAxis
        )
        .check(&cube),
        Err(GrowthError::Dimension {
            dim: 3,
            embedding: 3
        })
    ));
    // A velocity that squeezes a cell past flat in one step is refused.
    let crush: Vec<SpaceTimeFn> = vec![Arc::new(|x: &[f64], _| -20.0 * x[0])];
    let growth = g(Method::Fv, crush, 10.0, DivisionRule::Midpoint);
    let mut tissue = growth.start(&line, &|_| 1.0)?;
    assert!(matches!(
        growth.step(&mut tissue),
        Err(GrowthError::Inverted { .. })
    ));
    Ok(())
}
