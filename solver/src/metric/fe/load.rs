//! The load ∫ f φ_v: simplex quadrature and each element's rule.

use super::*;

/// Barycentric quadrature on the n-simplex, (coordinates, weight / |c|)
/// with the coordinates in the first n + 1 entries: the P1 rules of
/// [`load`](super::load()), the same for every cell, so built once per dimension.
pub(super) fn simplex_rule(n: usize) -> &'static [([f64; 4], f64)] {
    type Rule = Vec<([f64; 4], f64)>;
    static RULES: [std::sync::OnceLock<Rule>; 4] = [
        std::sync::OnceLock::new(),
        std::sync::OnceLock::new(),
        std::sync::OnceLock::new(),
        std::sync::OnceLock::new(),
    ];
    RULES[n.min(3)].get_or_init(|| match n {
        1 => {
            let s = 3f64.sqrt() / 6.0;
            vec![
                ([0.5 + s, 0.5 - s, 0.0, 0.0], 0.5),
                ([0.5 - s, 0.5 + s, 0.0, 0.0], 0.5),
            ]
        }
        2 => vec![
            ([0.5, 0.5, 0.0, 0.0], 1.0 / 3.0),
            ([0.0, 0.5, 0.5, 0.0], 1.0 / 3.0),
            ([0.5, 0.0, 0.5, 0.0], 1.0 / 3.0),
        ],
        _ => {
            let root5 = 5f64.sqrt();
            let (a, b) = ((5.0 + 3.0 * root5) / 20.0, (5.0 - root5) / 20.0);
            (0..4)
                .map(|k| {
                    let mut beta = [b; 4];
                    beta[k] = a;
                    (beta, 0.25)
                })
                .collect()
        }
    })
}

pub(super) fn evaluate(
    f: &(dyn Fn(&[f64]) -> f64 + Sync),
    x: &Point,
    d: usize,
    cell: usize,
) -> Result<f64, MetricError> {
    let value = f(&x[..d]);
    if value.is_finite() {
        Ok(value)
    } else {
        Err(MetricError::NonFiniteSource {
            cell,
            point: x[..d].to_vec(),
            value,
        })
    }
}

/// Cell `c`'s load shares ∫_c f φ_v, written over `out` in the order of
/// the cell's vertex list.
pub(super) fn cell_load(
    top: &Topology,
    c: usize,
    f: &(dyn Fn(&[f64]) -> f64 + Sync),
    out: &mut [f64],
) -> Result<(), MetricError> {
    element_load(top, c, &top.element(c, Route::ByShape)?, f, out)
}

/// A source f as the loads take it.
pub(super) type LoadFn<'f> = &'f (dyn Fn(&[f64]) -> f64 + Sync);

/// [`cell_load`] of cell `c` with its element already found.
pub(super) fn element_load(
    top: &Topology,
    c: usize,
    element: &Element,
    f: LoadFn,
    out: &mut [f64],
) -> Result<(), MetricError> {
    let (n, d) = (top.n, top.d);
    out.fill(0.0);
    match element {
        Element::P1 => {
            let x = top.points(c);
            let (measure, _) = simplex_gradients(&x, d).ok_or(MetricError::UnsupportedCell {
                method: "P1",
                needs: "a simplex of positive measure",
                cell: c,
            })?;
            for (beta, w) in simplex_rule(n) {
                let mut p = [0.0; 3];
                for (xi, bi) in x.iter().zip(beta) {
                    for a in 0..3 {
                        p[a] += bi * xi[a];
                    }
                }
                let value = w * measure * evaluate(f, &p, d, c)?;
                for (o, bi) in out.iter_mut().zip(beta) {
                    *o += value * bi;
                }
            }
        }
        Element::Q1(order) if n == 2 => q1_load::<4>(top, c, order, f, out)?,
        Element::Q1(order) => q1_load::<8>(top, c, order, f, out)?,
        Element::Vem => {
            let measure = top.complex.measure(n)[c];
            let mut p = [0.0; 3];
            p[..d].copy_from_slice(top.complex.centroid_of(n, c));
            let share = measure * evaluate(f, &p, d, c)? / out.len() as f64;
            out.fill(share);
        }
    }
    Ok(())
}
