//! Quadrature rules for norms of the error: on simplices (collapsed
//! Gauss–Jacobi products) and on the reference square and cube of Q1 cells
//! (Gauss products).
//!
//! The error e = u_h − u of a second-order method is, on a cell of size h,
//! a quadratic polynomial of size O(h²) plus O(h³) terms, so e² is a quartic
//! plus higher terms, and a rule exact to degree p integrates it with a
//! relative error O(h^(p−3)). The gradient's error ∇e is O(h) with a
//! leading part of degree one, so |∇e|² is a quadratic plus higher terms,
//! integrated with a relative error O(h^(p−1)).
//!
//! Convergence tables print five significant digits, from meshes as coarse
//! as 8³. Measured on the 3D box case at 8³ (fv and Q1 fe) against 6 × 6 × 6
//! Gauss: degree-5 rules for the field missed by 2–4·10⁻⁵ (the last printed
//! digit), 4 × 4 × 4 Gauss (degree 7) agreed to seven digits; for the
//! gradient, 2 × 2 × 2 Gauss missed by 2·10⁻⁴ and 3 × 3 × 3 agreed to seven
//! digits. Hence [`Degree::Septic`] for the field and [`Degree::Quintic`]
//! for the gradient.
//!
//! Each rule has as few points as its degree needs in product form,
//! because every point costs evaluations of the exact solution or its
//! gradient (parsed expressions with sin and exp, a few hundred ns each):
//! the point count, not the arithmetic, is the cost of the error norms.

use nalgebra::{DMatrix, SymmetricEigen};
use std::sync::OnceLock;

/// One point of a reference rule: coordinates and weight.
pub(super) type RulePoint = ([f64; 4], f64);

/// The polynomial degree a rule integrates exactly (per axis for the Q1
/// products, in total on simplices).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Degree {
    /// Degree 5: 3 Gauss points per axis. For the square of a gradient's
    /// error.
    Quintic,
    /// Degree 7: 4 Gauss points per axis. For the square of a field's
    /// error.
    Septic,
}

impl Degree {
    fn index(self) -> usize {
        match self {
            Degree::Quintic => 0,
            Degree::Septic => 1,
        }
    }

    /// Points per axis of the product rules: 2q − 1 is the degree.
    fn points(self) -> usize {
        match self {
            Degree::Quintic => 3,
            Degree::Septic => 4,
        }
    }
}

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

/// Barycentric coordinates (λ₀ … λ_n) and weights (summing to 1) on the
/// n-simplex, n = 1, 2, 3: the collapsed (Duffy) product of Gauss–Jacobi
/// rules, whose weights (1 − t)^(n−1−axis) absorb the map's Jacobian, so
/// that q points per axis are exact to degree 2q − 1: 3ⁿ points for
/// [`Degree::Quintic`], 4ⁿ for [`Degree::Septic`].
pub(super) fn simplex_rule(n: usize, degree: Degree) -> &'static [RulePoint] {
    static RULES: [[OnceLock<Vec<RulePoint>>; 3]; 2] = [
        [OnceLock::new(), OnceLock::new(), OnceLock::new()],
        [OnceLock::new(), OnceLock::new(), OnceLock::new()],
    ];
    let n = n.clamp(1, 3);
    RULES[degree.index()][n - 1].get_or_init(|| {
        let axes: Vec<Vec<(f64, f64)>> = (0..n)
            .map(|axis| gauss_jacobi(degree.points(), (n - 1 - axis) as f64))
            .collect();
        let factorial: f64 = (1..=n).map(|k| k as f64).product();
        let total: usize = axes.iter().map(Vec::len).product();
        (0..total)
            .map(|index| {
                let mut rest = index;
                let mut lambda = [0.0; 4];
                let mut weight = factorial;
                // λ_{k+1} = t_k Π_{j<k} (1 − t_j), λ₀ what is left.
                let mut left = 1.0;
                for (axis, points) in axes.iter().enumerate() {
                    let (t, w) = points[rest % points.len()];
                    rest /= points.len();
                    lambda[axis + 1] = left * t;
                    weight *= w;
                    left *= 1.0 - t;
                }
                lambda[0] = left;
                (lambda, weight)
            })
            .collect()
    })
}

/// Points ξ ∈ [−1, 1]ⁿ (first n entries) and weights (summing to 2ⁿ) of
/// the reference rule of Q1 cells, n = 2, 3: the Gauss product with 3
/// ([`Degree::Quintic`]) or 4 ([`Degree::Septic`]) points per axis.
pub(super) fn q1_rule(n: usize, degree: Degree) -> &'static [RulePoint] {
    static RULES: [[OnceLock<Vec<RulePoint>>; 2]; 2] = [
        [OnceLock::new(), OnceLock::new()],
        [OnceLock::new(), OnceLock::new()],
    ];
    let dims = n.clamp(2, 3);
    RULES[degree.index()][dims - 2].get_or_init(|| {
        let points = gauss_jacobi(degree.points(), 0.0);
        let total = points.len().pow(dims as u32);
        (0..total)
            .map(|index| {
                let (mut xi, mut weight, mut rest) = ([0.0; 4], 1.0, index);
                for x in xi.iter_mut().take(dims) {
                    let (t, w) = points[rest % points.len()];
                    rest /= points.len();
                    *x = 2.0 * t - 1.0;
                    weight *= 2.0 * w;
                }
                (xi, weight)
            })
            .collect()
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
    fn simplex_rules_are_exact_to_their_degree() {
        // ∫ over the unit n-simplex of λ₁^a λ₂^b λ₃^c = a! b! c! n! / (a+b+c+n)!
        // relative to its volume 1/n! (the weights sum to 1).
        for n in 1..=3usize {
            for (degree, top) in [(Degree::Quintic, 5u32), (Degree::Septic, 7)] {
                let rule = simplex_rule(n, degree);
                assert_eq!(rule.len(), degree.points().pow(n as u32));
                let limit = |axis: usize, used: u32| if axis < n { top - used } else { 0 };
                for a in 0..=limit(0, 0) {
                    for b in 0..=limit(1, a) {
                        for c in 0..=limit(2, a + b) {
                            let got: f64 = rule
                                .iter()
                                .map(|(l, w)| {
                                    w * l[1].powi(a as i32)
                                        * l[2].powi(b as i32)
                                        * l[3].powi(c as i32)
                                })
                                .sum();
                            let want =
                                factorial(a) * factorial(b) * factorial(c) * factorial(n as u32)
                                    / factorial(a + b + c + n as u32);
                            assert_relative_eq!(got, want, max_relative = 1e-13);
                        }
                    }
                }
            }
        }
    }

    #[test]
    fn q1_rules_are_exact_to_their_degree_per_axis() {
        // ∫_{[−1,1]^n} Π x_a^{e_a} = Π 2/(e_a + 1) for even e_a, else 0.
        let moment = |e: &[u32]| -> f64 {
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
        for n in [2usize, 3] {
            for (degree, top) in [(Degree::Quintic, 5u32), (Degree::Septic, 7)] {
                let rule = q1_rule(n, degree);
                assert_eq!(rule.len(), degree.points().pow(n as u32));
                let quadrature = |e: &[u32]| -> f64 {
                    rule.iter()
                        .map(|(x, w)| w * (0..n).map(|a| x[a].powi(e[a] as i32)).product::<f64>())
                        .sum()
                };
                for a in 0..=top {
                    for b in 0..=top {
                        let e = [a, b, top - a.min(top)];
                        assert_relative_eq!(quadrature(&e[..n]), moment(&e[..n]), epsilon = 1e-14);
                    }
                }
                // One degree more on one axis is where each rule stops.
                let e = [top + 1, 0, 0];
                assert!((quadrature(&e[..n]) - moment(&e[..n])).abs() > 1e-4);
            }
        }
    }
}
