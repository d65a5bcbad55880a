//! Quadrature rules for norms of the error: on simplices (collapsed
//! Gauss–Jacobi products) and on the reference square and cube of Q1 cells.
//!
//! The error e = u_h − u of a second-order method is, on a cell of size h,
//! a quadratic polynomial of size O(h²) plus O(h³) terms, so e² is a quartic
//! plus higher terms: a rule exact to degree 5 integrates it with a relative
//! error O(h²), far below the digits of a convergence table. Each rule here
//! is exact to degree 5 or more with as few points as such a rule needs,
//! because every point costs an evaluation of the exact solution and its
//! gradient (a handful of parsed expressions with sin/exp, about 1 µs): the
//! point count, not the arithmetic, is the cost of the error norms.

use nalgebra::{DMatrix, SymmetricEigen};
use std::sync::OnceLock;

/// One point of a reference rule: coordinates and weight.
pub(super) type RulePoint = ([f64; 4], f64);

/// Gauss–Jacobi rule with `q` points on [0, 1] for the weight (1 − u)^α:
/// (point, weight) pairs, exact for polynomials of degree 2q − 1 times the
/// weight. Nodes and weights come from the eigenvalues of the Jacobi
/// matrix of the recurrence (Golub and Welsch, Math. Comp. 23, 1969),
/// computed on [−1, 1] for (1 − x)^α and mapped to [0, 1].
fn gauss_jacobi(q: usize, alpha: f64) -> Vec<(f64, f64)> {
    // Recurrence coefficients of the orthonormal Jacobi polynomials with
    // β = 0: a_k on the diagonal, b_k (k ≥ 1) beside it.
    let diagonal = |k: usize| -> f64 {
        let s = 2.0 * k as f64 + alpha;
        if k == 0 {
            -alpha / (alpha + 2.0)
        } else {
            -alpha * alpha / (s * (s + 2.0))
        }
    };
    let off = |k: usize| -> f64 {
        let (k, s) = (k as f64, 2.0 * k as f64 + alpha);
        (4.0 * k * (k + alpha) * k * (k + alpha) / (s * s * (s + 1.0) * (s - 1.0))).sqrt()
    };
    let mut jacobi = DMatrix::<f64>::zeros(q, q);
    for k in 0..q {
        jacobi[(k, k)] = diagonal(k);
        if k + 1 < q {
            jacobi[(k, k + 1)] = off(k + 1);
            jacobi[(k + 1, k)] = off(k + 1);
        }
    }
    let eigen = SymmetricEigen::new(jacobi);
    // ∫_{−1}^{1} (1 − x)^α dx = 2^{α+1} / (α + 1); the map to [0, 1] scales
    // the weight by 2^{−α} and dx by 1/2.
    let mass = 2f64.powf(alpha + 1.0) / (alpha + 1.0);
    let scale = 0.5f64.powf(alpha + 1.0);
    let mut rule: Vec<(f64, f64)> = (0..q)
        .map(|i| {
            let x = eigen.eigenvalues[i];
            let first = eigen.eigenvectors[(0, i)];
            (0.5 * (1.0 + x), scale * mass * first * first)
        })
        .collect();
    rule.sort_by(|a, b| a.0.total_cmp(&b.0));
    rule
}

/// Gauss–Legendre on [0, 1], 4 points: exact to degree 7.
pub(super) fn gauss4() -> &'static [(f64, f64); 4] {
    static RULE: OnceLock<[(f64, f64); 4]> = OnceLock::new();
    RULE.get_or_init(|| {
        let (a, b) = (0.339_981_043_584_856_3, 0.861_136_311_594_052_6);
        let (wa, wb) = (0.652_145_154_862_546_1, 0.347_854_845_137_453_9);
        [
            (0.5 * (1.0 - b), 0.5 * wb),
            (0.5 * (1.0 - a), 0.5 * wa),
            (0.5 * (1.0 + a), 0.5 * wa),
            (0.5 * (1.0 + b), 0.5 * wb),
        ]
    })
}

/// Barycentric coordinates (λ₀ … λ_n) and weights (summing to 1) on the
/// n-simplex, n = 1, 2, 3: Gauss (4 points, degree 7) on segments, the
/// collapsed product of 4-point Gauss rules on triangles (16 points,
/// degree 6), and on tetrahedra the collapsed product of 3-point
/// Gauss–Jacobi rules whose weights (1 − u)² and (1 − v) absorb the
/// Duffy map's Jacobian (27 points, degree 5; the 4-point Gauss product
/// reached the same degree with 64).
pub(super) fn simplex_rule(n: usize) -> &'static [RulePoint] {
    static RULES: [OnceLock<Vec<RulePoint>>; 3] =
        [OnceLock::new(), OnceLock::new(), OnceLock::new()];
    RULES[n.clamp(1, 3) - 1].get_or_init(|| {
        let g = gauss4();
        let mut rule = Vec::new();
        match n {
            1 => {
                for &(u, wu) in g {
                    rule.push(([1.0 - u, u, 0.0, 0.0], wu));
                }
            }
            2 => {
                for &(u, wu) in g {
                    for &(v, wv) in g {
                        let (l1, l2) = (u, (1.0 - u) * v);
                        rule.push(([1.0 - l1 - l2, l1, l2, 0.0], 2.0 * wu * wv * (1.0 - u)));
                    }
                }
            }
            _ => {
                let (gu, gv, gs) = (
                    gauss_jacobi(3, 2.0),
                    gauss_jacobi(3, 1.0),
                    gauss_jacobi(3, 0.0),
                );
                for &(u, wu) in &gu {
                    for &(v, wv) in &gv {
                        for &(s, ws) in &gs {
                            let l1 = u;
                            let l2 = (1.0 - u) * v;
                            let l3 = (1.0 - u) * (1.0 - v) * s;
                            rule.push(([1.0 - l1 - l2 - l3, l1, l2, l3], 6.0 * wu * wv * ws));
                        }
                    }
                }
            }
        }
        rule
    })
}

/// Points ξ ∈ [−1, 1]ⁿ (first n entries) and weights (summing to 2ⁿ) of
/// the reference rule of Q1 cells: the 4 × 4 Gauss product on the square
/// (degree 7 per axis), and on the cube the 14-point rule exact to total
/// degree 5 of Hammer and Stroud (Stroud, *Approximate Calculation of
/// Multiple Integrals*, 1971, C3: 5-1): six points (±r, 0, 0), … with
/// weight 320/361 and eight (±s, ±s, ±s) with weight 121/361,
/// r² = 19/30, s² = 19/33. The 4 × 4 × 4 product it replaces took 64
/// evaluations of the exact solution per hexahedron.
pub(super) fn q1_rule(n: usize) -> &'static [RulePoint] {
    static RULES: [OnceLock<Vec<RulePoint>>; 2] = [OnceLock::new(), OnceLock::new()];
    RULES[usize::from(n >= 3)].get_or_init(|| {
        let mut rule = Vec::new();
        if n >= 3 {
            let (r, s) = ((19.0f64 / 30.0).sqrt(), (19.0f64 / 33.0).sqrt());
            for axis in 0..3 {
                for sign in [-1.0, 1.0] {
                    let mut xi = [0.0; 4];
                    xi[axis] = sign * r;
                    rule.push((xi, 320.0 / 361.0));
                }
            }
            for corner in 0..8 {
                let mut xi = [0.0; 4];
                for (a, x) in xi.iter_mut().take(3).enumerate() {
                    *x = if corner >> a & 1 == 1 { s } else { -s };
                }
                rule.push((xi, 121.0 / 361.0));
            }
        } else {
            for &(u, wu) in gauss4() {
                for &(v, wv) in gauss4() {
                    rule.push(([2.0 * u - 1.0, 2.0 * v - 1.0, 0.0, 0.0], 4.0 * wu * wv));
                }
            }
        }
        rule
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    fn factorial(k: u32) -> f64 {
        (1..=k).map(f64::from).product()
    }

    #[test]
    fn gauss_jacobi_matches_closed_forms() {
        // Two-point Gauss–Legendre on [0, 1]: 1/2 ± 1/(2√3), weights 1/2.
        let legendre = gauss_jacobi(2, 0.0);
        let h = 0.5 / 3f64.sqrt();
        assert_relative_eq!(legendre[0].0, 0.5 - h, epsilon = 1e-15);
        assert_relative_eq!(legendre[1].0, 0.5 + h, epsilon = 1e-15);
        assert_relative_eq!(legendre[0].1, 0.5, epsilon = 1e-15);
        // Moments ∫₀¹ uᵏ (1 − u)^α du = k! α! / (k + α + 1)! for k ≤ 2q − 1.
        for alpha in [0u32, 1, 2] {
            let rule = gauss_jacobi(3, f64::from(alpha));
            for k in 0..=5u32 {
                let got: f64 = rule.iter().map(|(u, w)| w * u.powi(k as i32)).sum();
                let want = factorial(k) * factorial(alpha) / factorial(k + alpha + 1);
                assert_relative_eq!(got, want, max_relative = 1e-13);
            }
        }
    }

    #[test]
    fn tetrahedron_rule_is_exact_to_degree_five() {
        // ∫ over the unit simplex of λ₁^a λ₂^b λ₃^c = a! b! c! 3! / (a+b+c+3)!
        // relative to its volume 1/6 (the weights sum to 1).
        let rule = simplex_rule(3);
        assert_eq!(rule.len(), 27);
        for a in 0..=5u32 {
            for b in 0..=5 - a {
                for c in 0..=5 - a - b {
                    let got: f64 = rule
                        .iter()
                        .map(|(l, w)| {
                            w * l[1].powi(a as i32) * l[2].powi(b as i32) * l[3].powi(c as i32)
                        })
                        .sum();
                    let want =
                        factorial(a) * factorial(b) * factorial(c) * 6.0 / factorial(a + b + c + 3);
                    assert_relative_eq!(got, want, max_relative = 1e-13);
                }
            }
        }
    }

    #[test]
    fn cube_rule_is_exact_to_degree_five_and_not_six() {
        // ∫_{[−1,1]³} x^a y^b z^c = Π 2/(e + 1) for even exponents, 0 otherwise.
        let rule = q1_rule(3);
        assert_eq!(rule.len(), 14);
        let moment = |e: [u32; 3]| -> f64 {
            e.iter()
                .map(|&k| {
                    if k % 2 == 1 {
                        0.0
                    } else {
                        2.0 / f64::from(k + 1)
                    }
                })
                .product()
        };
        let quadrature = |e: [u32; 3]| -> f64 {
            rule.iter()
                .map(|(x, w)| w * (0..3).map(|a| x[a].powi(e[a] as i32)).product::<f64>())
                .sum()
        };
        for a in 0..=5u32 {
            for b in 0..=5 - a {
                for c in 0..=5 - a - b {
                    assert_relative_eq!(quadrature([a, b, c]), moment([a, b, c]), epsilon = 1e-14);
                }
            }
        }
        // Degree 6 is where it stops: x⁶ gives 2·(320/361)(19/30)³ +
        // 8·(121/361)(19/33)³ ≠ 8/7.
        assert!((quadrature([6, 0, 0]) - moment([6, 0, 0])).abs() > 1e-3);
    }
}
