//! Krylov solvers for symmetric positive definite systems: conjugate
//! gradients with a Jacobi (diagonal) preconditioner.
//!
//! Used where an initial guess matters (re-solving on a refined mesh from
//! the transferred coarse solution) and where a factorisation would be too
//! big. Convergence is measured by the relative residual ‖b − Mx‖₂ / ‖b‖₂,
//! the same figure the direct solvers report.
//!
//! ```
//! use faer::sparse::{SparseColMat, Triplet};
//! use hasse_solver::iterative::{conjugate_gradient, CgOptions};
//! // tridiag(−1, 2, −1) x = (1, 0, 1) has x = (1, 1, 1).
//! let t = [(0, 0, 2.0), (1, 1, 2.0), (2, 2, 2.0), (0, 1, -1.0), (1, 0, -1.0), (1, 2, -1.0), (2, 1, -1.0)];
//! let triplets: Vec<_> = t.iter().map(|&(i, j, v)| Triplet::new(i, j, v)).collect();
//! let m = SparseColMat::<usize, f64>::try_new_from_triplets(3, 3, &triplets).unwrap();
//! let (x, report) = conjugate_gradient(&m, &[1.0, 0.0, 1.0], None, &CgOptions::default()).unwrap();
//! assert!(x.iter().all(|v| (v - 1.0).abs() < 1e-10));
//! assert!(report.iterations <= 3);
//! ```

use faer::sparse::SparseColMat;

/// Stopping rule of [`conjugate_gradient`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CgOptions {
    /// Stop when ‖b − Mx‖₂ ≤ tolerance · ‖b‖₂.
    pub tolerance: f64,
    /// Give up (with [`CgError::NotConverged`]) after this many iterations.
    pub max_iterations: usize,
}

impl Default for CgOptions {
    fn default() -> Self {
        Self {
            tolerance: 1e-10,
            max_iterations: 10_000,
        }
    }
}

/// How an iterative solve went.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CgReport {
    pub iterations: usize,
    /// ‖b − Mx‖₂ / ‖b‖₂ at the returned x (recomputed, not the recurrence's).
    pub relative_residual: f64,
    /// The relative residual of the initial guess.
    pub initial_residual: f64,
    pub seconds: f64,
}

/// Why an iterative solve failed.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum CgError {
    #[error("conjugate gradients: matrix is {rows}×{cols}, right-hand side has {rhs} entries, initial guess {guess}")]
    Size {
        rows: usize,
        cols: usize,
        rhs: usize,
        guess: usize,
    },
    #[error("conjugate gradients: diagonal entry {index} is {value}, not positive: the matrix is not symmetric positive definite")]
    NotPositive { index: usize, value: f64 },
    #[error("conjugate gradients: direction {iteration} has pᵀMp = {curvature:e} ≤ 0: the matrix is not positive definite")]
    Breakdown { iteration: usize, curvature: f64 },
    #[error("conjugate gradients did not converge: relative residual {relative_residual:e} after {iterations} iterations (tolerance {tolerance:e}); raise the iteration limit or use a direct solver")]
    NotConverged {
        iterations: usize,
        relative_residual: f64,
        tolerance: f64,
    },
}

fn multiply(m: &SparseColMat<usize, f64>, x: &[f64], y: &mut [f64]) {
    y.iter_mut().for_each(|v| *v = 0.0);
    for (j, &xj) in x.iter().enumerate() {
        if xj == 0.0 {
            continue;
        }
        let range = m.col_range(j);
        for (&i, &v) in m.row_idx()[range.clone()].iter().zip(&m.val()[range]) {
            y[i] += v * xj;
        }
    }
}

fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

/// Solve M x = b (M symmetric positive definite, both triangles stored)
/// by Jacobi-preconditioned conjugate gradients from `initial` (zero if
/// `None`).
pub fn conjugate_gradient(
    matrix: &SparseColMat<usize, f64>,
    rhs: &[f64],
    initial: Option<&[f64]>,
    options: &CgOptions,
) -> Result<(Vec<f64>, CgReport), CgError> {
    let started = std::time::Instant::now();
    let n = rhs.len();
    if matrix.nrows() != n || matrix.ncols() != n || initial.is_some_and(|x| x.len() != n) {
        return Err(CgError::Size {
            rows: matrix.nrows(),
            cols: matrix.ncols(),
            rhs: n,
            guess: initial.map_or(n, <[f64]>::len),
        });
    }
    let mut inverse_diagonal = vec![0.0; n];
    for (j, inverse) in inverse_diagonal.iter_mut().enumerate() {
        let range = matrix.col_range(j);
        let diagonal: f64 = matrix.row_idx()[range.clone()]
            .iter()
            .zip(&matrix.val()[range])
            .filter(|(&i, _)| i == j)
            .map(|(_, &v)| v)
            .sum();
        // NaN fails too.
        if diagonal.is_nan() || diagonal <= 0.0 {
            return Err(CgError::NotPositive {
                index: j,
                value: diagonal,
            });
        }
        *inverse = 1.0 / diagonal;
    }
    let norm_b = dot(rhs, rhs).sqrt();
    let mut x = initial.map_or_else(|| vec![0.0; n], <[f64]>::to_vec);
    if norm_b == 0.0 {
        let report = CgReport {
            iterations: 0,
            relative_residual: 0.0,
            initial_residual: 0.0,
            seconds: started.elapsed().as_secs_f64(),
        };
        return Ok((vec![0.0; n], report));
    }
    let mut product = vec![0.0; n];
    multiply(matrix, &x, &mut product);
    let mut r: Vec<f64> = rhs.iter().zip(&product).map(|(b, mx)| b - mx).collect();
    let initial_residual = dot(&r, &r).sqrt() / norm_b;
    let mut z: Vec<f64> = r
        .iter()
        .zip(&inverse_diagonal)
        .map(|(a, d)| a * d)
        .collect();
    let mut p = z.clone();
    let mut rz = dot(&r, &z);
    let mut iterations = 0;
    let mut residual = initial_residual;
    while residual > options.tolerance {
        if iterations == options.max_iterations {
            return Err(CgError::NotConverged {
                iterations,
                relative_residual: residual,
                tolerance: options.tolerance,
            });
        }
        multiply(matrix, &p, &mut product);
        let curvature = dot(&p, &product);
        if curvature.is_nan() || curvature <= 0.0 {
            return Err(CgError::Breakdown {
                iteration: iterations,
                curvature,
            });
        }
        let alpha = rz / curvature;
        for i in 0..n {
            x[i] += alpha * p[i];
            r[i] -= alpha * product[i];
        }
        for i in 0..n {
            z[i] = r[i] * inverse_diagonal[i];
        }
        let rz_next = dot(&r, &z);
        let beta = rz_next / rz;
        rz = rz_next;
        for i in 0..n {
            p[i] = z[i] + beta * p[i];
        }
        iterations += 1;
        residual = dot(&r, &r).sqrt() / norm_b;
    }
    // The recurrence drifts from the true residual; report the true one.
    multiply(matrix, &x, &mut product);
    let true_residual = rhs
        .iter()
        .zip(&product)
        .map(|(b, mx)| (b - mx) * (b - mx))
        .sum::<f64>()
        .sqrt()
        / norm_b;
    let report = CgReport {
        iterations,
        relative_residual: true_residual,
        initial_residual,
        seconds: started.elapsed().as_secs_f64(),
    };
    Ok((x, report))
}

#[cfg(test)]
mod tests {
    use super::*;
    use faer::sparse::Triplet;

    /// The 1D Dirichlet Laplacian tridiag(−1, 2, −1) of size n.
    fn laplacian(n: usize) -> SparseColMat<usize, f64> {
        let mut t = Vec::new();
        for i in 0..n {
            t.push(Triplet::new(i, i, 2.0));
            if i + 1 < n {
                t.push(Triplet::new(i, i + 1, -1.0));
                t.push(Triplet::new(i + 1, i, -1.0));
            }
        }
        SparseColMat::try_new_from_triplets(n, n, &t).unwrap()
    }

    #[test]
    fn exact_in_n_steps_in_exact_arithmetic() {
        // x_i = i(n+1−i)/2 solves tridiag(−1,2,−1) x = 1 (a discrete parabola).
        let n = 50;
        let m = laplacian(n);
        let (x, report) =
            conjugate_gradient(&m, &vec![1.0; n], None, &CgOptions::default()).unwrap();
        for (i, v) in x.iter().enumerate() {
            let k = (i + 1) as f64;
            let exact = k * (n as f64 + 1.0 - k) / 2.0;
            assert!((v - exact).abs() <= 1e-8 * exact, "{i}: {v} vs {exact}");
        }
        // CG on an n×n SPD system with distinct eigenvalues ends within n
        // steps up to rounding; the parabola needs about n/2 (symmetry).
        assert!(report.iterations <= n, "{}", report.iterations);
        assert!(report.relative_residual <= 1e-10);
    }

    #[test]
    fn a_good_initial_guess_saves_iterations() {
        // The guess is off by one eigenvector of tridiag(−1, 2, −1) (the
        // Jacobi scaling is the constant 1/2, so also of the preconditioned
        // operator): CG removes a single eigencomponent in one step, while
        // from zero it needs about n/2 = 100 (b = 1 excites the even modes).
        let n = 200;
        let m = laplacian(n);
        let b = vec![1.0; n];
        let (_, cold) = conjugate_gradient(&m, &b, None, &CgOptions::default()).unwrap();
        // The exact solution is the discrete parabola x_i = k(n+1−k)/2, k = i+1.
        let exact: Vec<f64> = (1..=n).map(|k| (k * (n + 1 - k)) as f64 / 2.0).collect();
        // The highest mode (λ ≈ 4): a step along the lowest one (λ ≈ 2.4e-4)
        // would multiply the rounding noise of the residual by 1/λ.
        let mode = |i: usize| (std::f64::consts::PI * (n * (i + 1)) as f64 / (n + 1) as f64).sin();
        let guess: Vec<f64> = exact
            .iter()
            .enumerate()
            .map(|(i, v)| v + 10.0 * mode(i))
            .collect();
        let (x, warm) = conjugate_gradient(&m, &b, Some(&guess), &CgOptions::default()).unwrap();
        assert!(cold.initial_residual == 1.0 && warm.initial_residual > 1e-4);
        assert_eq!(warm.iterations, 1);
        assert!(cold.iterations >= 90, "{}", cold.iterations);
        for (a, e) in x.iter().zip(&exact) {
            assert!((a - e).abs() <= 1e-8 * e.abs().max(1.0));
        }
    }

    #[test]
    fn indefinite_and_unconverged_systems_are_reported() {
        let t = [Triplet::new(0, 0, 1.0), Triplet::new(1, 1, -1.0)];
        let m = SparseColMat::try_new_from_triplets(2, 2, &t).unwrap();
        assert!(matches!(
            conjugate_gradient(&m, &[1.0, 1.0], None, &CgOptions::default()),
            Err(CgError::NotPositive { index: 1, .. })
        ));
        let options = CgOptions {
            tolerance: 1e-12,
            max_iterations: 3,
        };
        assert!(matches!(
            conjugate_gradient(&laplacian(100), &vec![1.0; 100], None, &options),
            Err(CgError::NotConverged { iterations: 3, .. })
        ));
    }
}
