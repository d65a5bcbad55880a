//! L² and H¹-seminorm errors by quadrature on each top cell, of the field
//! each method represents: the P1/Q1 (or fan) interpolant of nodal values
//! ([`fe::field`]), and for cell values the linear field u_c + g_c·(x − x_c)
//! of the cell value and its reconstructed gradient at the cell point.

use super::*;
use fe::field::{cell_rule, nodal_rule, Degree};

/// ∫ (u_h − u), ∫ (u_h − u)², ∫ |∇u_h − ∇u|² and the measure, summed over
/// the cells.
#[derive(Clone, Copy, Default)]
struct Sums {
    difference: f64,
    square: f64,
    gradient: f64,
    measure: f64,
}

impl Sums {
    /// One point of the field's rule, with weight `w` and error `e`.
    fn add_value(&mut self, w: f64, e: f64) {
        self.difference += w * e;
        self.square += w * e * e;
        self.measure += w;
    }
}

impl std::ops::Add for Sums {
    type Output = Sums;
    fn add(self, o: Sums) -> Sums {
        Sums {
            difference: self.difference + o.difference,
            square: self.square + o.square,
            gradient: self.gradient + o.gradient,
            measure: self.measure + o.measure,
        }
    }
}

/// (L², gradient L²) of u_h − u by quadrature, with `cell_gradients` the
/// reconstructed gradient of a field that is not nodal (unused for nodal
/// fields, which carry their own); the gradient figure is NaN
/// without `exact_gradient`. `remove_mean`: measure u_h − u − mean (a pure
/// Neumann solution is defined up to a constant). `None` for a complex
/// without edges.
pub(super) fn quadrature_errors(
    complex: &Complex,
    solution: &Solution,
    cell_gradients: &[[f64; 3]],
    exact: &ScalarFn,
    exact_gradient: Option<&VectorFn>,
    remove_mean: bool,
) -> Option<(f64, f64)> {
    let top = fe::Topology::new(complex, "error norms").ok()?;
    let n = complex.dim();
    let d = complex.embedding_dim();
    let field = solution.field(complex);
    let centre = post::cell_centres(complex, solution);
    let gradient_error = |x: &[f64], g: &[f64; 3]| -> f64 {
        exact_gradient.map_or(0.0, |grad| {
            let e = grad(x);
            (0..d).map(|a| (g[a] - e[a]).powi(2)).sum()
        })
    };
    // The field's error at a degree-7 rule, the gradient's at a degree-5
    // one (`fe::rules` says why each suffices): the exact gradient is three
    // expressions, and its points are most of the cost.
    let sums = (0..complex.cell_count(n))
        .into_par_iter()
        .map(|c| {
            let mut s = Sums::default();
            match solution.location {
                Location::Nodal => {
                    let ids = complex.cell_vertices(n, c);
                    for p in nodal_rule(&top, c, Degree::Septic) {
                        let uh: f64 = ids.iter().zip(&p.values).map(|(&v, s)| s * field[v]).sum();
                        s.add_value(p.weight, uh - exact(&p.x[..d]));
                    }
                    if exact_gradient.is_some() {
                        for p in nodal_rule(&top, c, Degree::Quintic) {
                            let mut g = [0.0; 3];
                            for (&v, sg) in ids.iter().zip(&p.gradients) {
                                for a in 0..3 {
                                    g[a] += sg[a] * field[v];
                                }
                            }
                            s.gradient += p.weight * gradient_error(&p.x[..d], &g);
                        }
                    }
                }
                _ => {
                    let g = &cell_gradients[c];
                    let xc = &centre[c * d..(c + 1) * d];
                    for (w, x) in cell_rule(&top, c, Degree::Septic) {
                        let uh = field[c] + (0..d).map(|a| g[a] * (x[a] - xc[a])).sum::<f64>();
                        s.add_value(w, uh - exact(&x[..d]));
                    }
                    if exact_gradient.is_some() {
                        for (w, x) in cell_rule(&top, c, Degree::Quintic) {
                            s.gradient += w * gradient_error(&x[..d], g);
                        }
                    }
                }
            }
            s
        })
        .reduce(Sums::default, |a, b| a + b);
    // ∫ (e − m)² = ∫ e² − m ∫ e with m = ∫ e / |Ω|.
    let square = if remove_mean && sums.measure > 0.0 {
        sums.square - sums.difference * sums.difference / sums.measure
    } else {
        sums.square
    };
    let gradient = if exact_gradient.is_some() {
        sums.gradient.sqrt()
    } else {
        f64::NAN
    };
    Some((square.max(0.0).sqrt(), gradient))
}
