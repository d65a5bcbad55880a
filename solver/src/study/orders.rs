//! Observed orders of convergence from errors e_k on meshes of size h_k.
//!
//! If e ≈ C hᵖ, then ln e = ln C + p ln h: the order is a slope in log–log
//! coordinates. Between two consecutive levels it is
//! p = ln(e_k / e_{k+1}) / ln(h_k / h_{k+1}); over all levels it is the
//! least-squares slope of ln e against ln h, which is less sensitive to one
//! noisy level (a pre-asymptotic coarse mesh, a random mesh that came out
//! slightly better or worse than its neighbours).

/// Why an order cannot be computed from the given sizes and errors.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum OrderError {
    /// `h` and `e` have different lengths.
    #[error("{h} mesh sizes but {e} errors")]
    LengthMismatch {
        /// Mesh sizes given.
        h: usize,
        /// Errors given.
        e: usize,
    },
    /// An order needs at least two levels.
    #[error("an order needs at least 2 levels, got {0}")]
    TooFewLevels(usize),
    /// A size or an error is zero, negative or not finite: it has no
    /// logarithm (an error of exactly 0 means the discrete space contains
    /// the solution, and there is no order to observe).
    #[error("level {level}: {what} = {value} is not a positive finite number")]
    NotPositive {
        /// The level.
        level: usize,
        /// `"h"` or `"error"`.
        what: &'static str,
        /// The value.
        value: f64,
    },
    /// Two levels with the same mesh size: the slope is undefined.
    #[error("levels {0} and {1} have the same mesh size")]
    SameSize(usize, usize),
}

fn logs(h: &[f64], e: &[f64]) -> Result<(Vec<f64>, Vec<f64>), OrderError> {
    if h.len() != e.len() {
        return Err(OrderError::LengthMismatch {
            h: h.len(),
            e: e.len(),
        });
    }
    if h.len() < 2 {
        return Err(OrderError::TooFewLevels(h.len()));
    }
    let log = |values: &[f64], what: &'static str| {
        values
            .iter()
            .enumerate()
            .map(|(level, &value)| {
                if value > 0.0 && value.is_finite() {
                    Ok(value.ln())
                } else {
                    Err(OrderError::NotPositive { level, what, value })
                }
            })
            .collect::<Result<Vec<f64>, OrderError>>()
    };
    Ok((log(h, "h")?, log(e, "error")?))
}

/// The observed order between each pair of consecutive levels:
/// p_k = ln(e_k / e_{k+1}) / ln(h_k / h_{k+1}), one fewer than the levels.
///
/// ```
/// use hasse_solver::study::pairwise_orders;
/// let h = [0.1, 0.05, 0.025];
/// let e = [4e-3, 1e-3, 5e-4];             // second order, then first
/// let p = pairwise_orders(&h, &e).unwrap();
/// assert!((p[0] - 2.0).abs() < 1e-12 && (p[1] - 1.0).abs() < 1e-12);
/// ```
pub fn pairwise_orders(h: &[f64], e: &[f64]) -> Result<Vec<f64>, OrderError> {
    let (lh, le) = logs(h, e)?;
    (0..lh.len() - 1)
        .map(|k| {
            let dh = lh[k] - lh[k + 1];
            if dh == 0.0 {
                return Err(OrderError::SameSize(k, k + 1));
            }
            Ok((le[k] - le[k + 1]) / dh)
        })
        .collect()
}

/// The least-squares slope p of ln e = ln C + p ln h over all levels.
///
/// ```
/// use hasse_solver::study::least_squares_order;
/// // Pairwise orders 2 and 1; the fit through all three points has slope 1.5.
/// let p = least_squares_order(&[1.0, 0.5, 0.25], &[1.0, 0.25, 0.125]).unwrap();
/// assert!((p - 1.5).abs() < 1e-12);
/// ```
pub fn least_squares_order(h: &[f64], e: &[f64]) -> Result<f64, OrderError> {
    let (lh, le) = logs(h, e)?;
    let n = lh.len() as f64;
    let mean_h = lh.iter().sum::<f64>() / n;
    let mean_e = le.iter().sum::<f64>() / n;
    let (mut sxy, mut sxx) = (0.0, 0.0);
    for (x, y) in lh.iter().zip(&le) {
        sxy += (x - mean_h) * (y - mean_e);
        sxx += (x - mean_h) * (x - mean_h);
    }
    if sxx == 0.0 {
        return Err(OrderError::SameSize(0, lh.len() - 1));
    }
    Ok(sxy / sxx)
}
