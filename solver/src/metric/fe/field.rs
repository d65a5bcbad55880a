//! The discrete field inside a top cell, for norms of the error: quadrature
//! points of the cell with the values and gradients of the nodal shape
//! functions there.
//!
//! Each cell gets the representation its method uses: P1 (linear) on a
//! simplex, the isoparametric Q1 map on a quadrilateral or hexahedron that
//! fills its space, and on every other cell (virtual-element polygons and
//! polyhedra, non-simplicial cells of a surface) the continuous piecewise-
//! linear field on its fan of simplices: apex the vertex average of the
//! cell (and of each face in 3D), whose value is the average of the
//! vertex values there, so that linear fields are reproduced exactly.
//!
//! Cell-centred fields (a value and a reconstructed gradient per cell) are
//! integrated with the same points: the Q1 cell's rule where the cell is a
//! quadrilateral or hexahedron filling its space, the fan's elsewhere.
//!
//! The rules ([`super::rules`]) come in two degrees: 7 for the square of
//! a field's error, 5 for the square of its gradient's; that module says
//! why and what was measured.

pub(crate) use super::rules::Degree;
use super::rules::{q1_rule, simplex_rule};
use super::{simplex_gradients, Point, Topology};

/// One quadrature point of a cell: its weight (physical measure), its
/// position, and the nodal shape functions of the cell's sorted vertex
/// list there (values and gradients, tangent to the cell).
#[derive(Clone, Debug)]
pub(crate) struct FieldPoint {
    pub(crate) weight: f64,
    pub(crate) x: Point,
    pub(crate) values: Vec<f64>,
    pub(crate) gradients: Vec<Point>,
}

/// A simplex of the rule: its corners, and each corner as weights over the
/// cell's vertices (a vertex of the cell, or an average of several).
struct Piece {
    corners: Vec<Point>,
    mix: Vec<Vec<(usize, f64)>>,
}

/// Quadrature points of top cell `c` with its nodal shape functions; an
/// empty list for a degenerate cell (the metric refuses those first).
pub(crate) fn nodal_rule(top: &Topology, c: usize, degree: Degree) -> Vec<FieldPoint> {
    let vertices = top.complex.cell_vertices(top.n, c);
    if top.is_simplex(c) {
        let piece = Piece {
            corners: top.points(c),
            mix: (0..vertices.len()).map(|i| vec![(i, 1.0)]).collect(),
        };
        return piece_points(top, &piece, vertices.len(), degree);
    }
    if top.n == top.d {
        if let Some(order) = top.element_order(c) {
            return q1_points(top, c, &order, degree);
        }
    }
    fan(top, c)
        .iter()
        .flat_map(|piece| piece_points(top, piece, vertices.len(), degree))
        .collect()
}

/// Quadrature points and weights of top cell `c` for a field of its own
/// (cell-centred methods): the Q1 rule of a quadrilateral or hexahedron
/// that fills its space, the cell's own rule when it is a simplex, and the
/// points of its fan of simplices otherwise.
pub(crate) fn cell_rule(top: &Topology, c: usize, degree: Degree) -> Vec<(f64, Point)> {
    if !top.is_simplex(c) && top.n == top.d {
        if let Some(order) = top.element_order(c) {
            let points: Vec<(f64, Point)> = q1_map(top, c, &order, degree)
                .map(|(weight, x, _)| (weight, x))
                .collect();
            // A map that folds over (a non-convex quadrilateral: the
            // Jacobian changes sign) or degenerates at a point leaves the
            // cell to its fan.
            let positive = points.iter().all(|p| p.0 > 0.0);
            let negative = points.iter().all(|p| p.0 < 0.0);
            if points.len() == q1_rule(top.n, degree).len() && (positive || negative) {
                return points.into_iter().map(|(w, x)| (w.abs(), x)).collect();
            }
        }
    }
    let pieces = if top.is_simplex(c) {
        vec![Piece {
            corners: top.points(c),
            mix: Vec::new(),
        }]
    } else {
        fan(top, c)
    };
    let n = top.n;
    let mut out = Vec::new();
    for piece in &pieces {
        let Some((measure, _)) = simplex_gradients(&piece.corners, top.d) else {
            continue;
        };
        for (lambda, w) in simplex_rule(n, degree) {
            out.push((measure * w, combine(&piece.corners, lambda)));
        }
    }
    out
}

fn combine(corners: &[Point], lambda: &[f64; 4]) -> Point {
    let mut x = [0.0; 3];
    for (corner, l) in corners.iter().zip(lambda) {
        for (xi, ci) in x.iter_mut().zip(corner) {
            *xi += l * ci;
        }
    }
    x
}

/// The rule's points on one simplex piece, with the shape functions of the
/// cell's `m` vertices: the piece's barycentric functions spread over the
/// vertices through `piece.mix`.
fn piece_points(top: &Topology, piece: &Piece, m: usize, degree: Degree) -> Vec<FieldPoint> {
    let Some((measure, lambda_gradients)) = simplex_gradients(&piece.corners, top.d) else {
        return Vec::new();
    };
    let mut gradients = vec![[0.0; 3]; m];
    for (corner, g) in piece.mix.iter().zip(&lambda_gradients) {
        for &(i, share) in corner {
            for a in 0..3 {
                gradients[i][a] += share * g[a];
            }
        }
    }
    simplex_rule(top.n, degree)
        .iter()
        .map(|(lambda, w)| {
            let mut values = vec![0.0; m];
            for (corner, l) in piece.mix.iter().zip(lambda) {
                for &(i, share) in corner {
                    values[i] += share * l;
                }
            }
            FieldPoint {
                weight: measure * w,
                x: combine(&piece.corners, lambda),
                values,
                gradients: gradients.clone(),
            }
        })
        .collect()
}

/// The fan of a non-simplicial cell: in 2D one triangle (apex, edge) per
/// edge; in 3D one tetrahedron (apex, face apex, edge) per edge of each
/// face. Apexes are vertex averages.
fn fan(top: &Topology, c: usize) -> Vec<Piece> {
    let vertices = top.complex.cell_vertices(top.n, c);
    let local = |v: usize| vertices.iter().position(|&w| w == v);
    let average = |ids: &[usize]| -> (Point, Vec<(usize, f64)>) {
        let mut x = [0.0; 3];
        let share = 1.0 / ids.len() as f64;
        let mut mix = Vec::with_capacity(ids.len());
        for &v in ids {
            let p = top.point(v);
            for a in 0..3 {
                x[a] += share * p[a];
            }
            if let Some(i) = local(v) {
                mix.push((i, share));
            }
        }
        (x, mix)
    };
    let (apex, apex_mix) = average(vertices);
    let edge_piece = |e: usize, extra: &[(Point, Vec<(usize, f64)>)]| -> Option<Piece> {
        let (a, b) = top.ends(e);
        let (ia, ib) = (local(a)?, local(b)?);
        let mut corners = vec![apex];
        let mut mix = vec![apex_mix.clone()];
        for (x, m) in extra {
            corners.push(*x);
            mix.push(m.clone());
        }
        corners.extend([top.point(a), top.point(b)]);
        mix.extend([vec![(ia, 1.0)], vec![(ib, 1.0)]]);
        Some(Piece { corners, mix })
    };
    match top.n {
        2 => top
            .facets_of(2, c)
            .0
            .iter()
            .filter_map(|&e| edge_piece(e, &[]))
            .collect(),
        3 => {
            let mut pieces = Vec::new();
            for &f in top.facets_of(3, c).0 {
                let face = average(top.complex.cell_vertices(2, f));
                for &e in top.facets_of(2, f).0 {
                    pieces.extend(edge_piece(e, std::slice::from_ref(&face)));
                }
            }
            pieces
        }
        // Segments are simplices; nothing else has dimension 1.
        _ => Vec::new(),
    }
}

/// The isoparametric map of a Q1 cell at the points of its reference rule:
/// for each point its physical weight (signed: the Jacobian's determinant
/// times the reference weight), position and the map's data there
/// (shape functions in tensor order, their reference gradients, the inverse
/// Jacobian). A degenerate map (zero or non-finite Jacobian) ends the list
/// early; [`q1_points`] and [`cell_rule`] then give no points for the cell,
/// which the metric refuses first.
fn q1_map<'a>(
    top: &'a Topology,
    c: usize,
    order: &'a [usize],
    degree: Degree,
) -> impl Iterator<Item = (f64, Point, Q1Point)> + 'a {
    let n = top.n;
    let vertices = top.complex.cell_vertices(n, c);
    let corners: Vec<Point> = order.iter().map(|&o| top.point(vertices[o])).collect();
    q1_rule(n, degree).iter().map_while(move |(xi, weight)| {
        let (shape, reference) = super::q1::q1_shape(&xi[..n], n);
        let mut jacobian = [[0.0; 3]; 3];
        let mut x = [0.0; 3];
        for ((corner, r), s) in corners.iter().zip(&reference).zip(&shape) {
            for i in 0..n {
                x[i] += s * corner[i];
                for a in 0..n {
                    jacobian[i][a] += corner[i] * r[a];
                }
            }
        }
        let (det, inverse) = super::q1::determinant_and_inverse(&jacobian, n);
        (det.is_finite() && det != 0.0).then(|| {
            let data = Q1Point {
                shape,
                reference,
                inverse,
            };
            (weight * det, x, data)
        })
    })
}

/// The isoparametric data at one point of a Q1 cell's rule.
struct Q1Point {
    shape: Vec<f64>,
    reference: Vec<[f64; 3]>,
    inverse: [[f64; 3]; 3],
}

/// The reference rule's points of a Q1 cell with its isoparametric shape
/// functions, in the cell's sorted vertex order.
fn q1_points(top: &Topology, c: usize, order: &[usize], degree: Degree) -> Vec<FieldPoint> {
    let n = top.n;
    let m = 1usize << n;
    let total = q1_rule(n, degree).len();
    let points: Vec<FieldPoint> = q1_map(top, c, order, degree)
        .map(|(weight, x, data)| {
            let mut values = vec![0.0; m];
            let mut gradients = vec![[0.0; 3]; m];
            for (l, &o) in order.iter().enumerate() {
                values[o] = data.shape[l];
                for (i, gradient) in gradients[o].iter_mut().enumerate().take(n) {
                    *gradient = (0..n)
                        .map(|a| data.inverse[a][i] * data.reference[l][a])
                        .sum();
                }
            }
            FieldPoint {
                weight: weight.abs(),
                x,
                values,
                gradients,
            }
        })
        .collect();
    // All points or none: a map degenerate at one point is no element.
    if points.len() == total {
        points
    } else {
        Vec::new()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;
    use hasse_complex::generate::{box3, perturb, rectangle, voronoi};
    use hasse_complex::{Complex, TopCells, Vertices};

    /// ∫ over the mesh of a polynomial, through the nodal rules.
    fn integrate(k: &Complex, f: impl Fn(&Point) -> f64) -> f64 {
        let top = Topology::new(k, "test").unwrap();
        (0..k.cell_count(k.dim()))
            .flat_map(|c| nodal_rule(&top, c, Degree::Quintic))
            .map(|p| p.weight * f(&p.x))
            .sum()
    }

    #[test]
    fn rules_integrate_polynomials_exactly() {
        // ∫_[0,1]² x⁴ y² = 1/5 · 1/3 on Q1 cells (distorted by nothing)
        // and on the Kuhn triangles of the same square.
        let f = |x: &Point| x[0].powi(4) * x[1].powi(2);
        let quads = rectangle(3, 2, [0.0, 1.0], [0.0, 1.0]).unwrap();
        assert_relative_eq!(integrate(&quads, f), 1.0 / 15.0, max_relative = 1e-13);
        // A single triangle (0,0), (1,0), (0,1): ∫ x² y² = 2!2!/6! = 1/180.
        let v = Vertices::from_points(&[[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]]).unwrap();
        let t = Complex::build(v, TopCells::simplices([[0, 1, 2]])).unwrap();
        let g = |x: &Point| x[0].powi(2) * x[1].powi(2);
        assert_relative_eq!(integrate(&t, g), 1.0 / 180.0, max_relative = 1e-13);
    }

    #[test]
    fn cell_rule_integrates_quintics_on_boxes_and_measures_every_cell() {
        // ∫ over [0,1]×[0,2]×[0,1] of x²y²z = (1/3)(8/3)(1/2) = 4/9 (degree
        // 2 per axis: the 3 × 3 × 3 Gauss product is exact for it).
        let boxes = box3(2, 3, 2, [0.0, 1.0], [0.0, 2.0], [0.0, 1.0]).unwrap();
        let top = Topology::new(&boxes, "test").unwrap();
        let mut integral = 0.0;
        for c in 0..boxes.cell_count(3) {
            let rule = cell_rule(&top, c, Degree::Quintic);
            assert_eq!(rule.len(), 27);
            integral += rule
                .iter()
                .map(|(w, x)| w * x[0].powi(2) * x[1].powi(2) * x[2])
                .sum::<f64>();
        }
        assert_relative_eq!(integral, 4.0 / 9.0, max_relative = 1e-13);
        // On randomly perturbed quadrilaterals (Q1 maps that are not affine)
        // and on Voronoi polygons (fans), the weights of each cell add up to
        // its measure, computed by the complex from its own geometry.
        let perturbed =
            perturb(&rectangle(6, 5, [0.0, 1.0], [0.0, 1.0]).unwrap(), 0.3, 11).unwrap();
        for k in [
            perturbed,
            voronoi(30, [0.0, 1.0], [0.0, 1.0], 7, 0).unwrap(),
        ] {
            let top = Topology::new(&k, "test").unwrap();
            for c in 0..k.cell_count(2) {
                let area: f64 = cell_rule(&top, c, Degree::Quintic)
                    .iter()
                    .map(|(w, _)| w)
                    .sum();
                assert_relative_eq!(area, k.measure(2)[c], max_relative = 1e-12);
            }
        }
    }

    #[test]
    fn shape_functions_reproduce_linear_fields_on_every_cell_kind() {
        // On Voronoi polygons (fans) and on quads (Q1), the field with
        // vertex values a + b·x is a + b·x at every point, with gradient b.
        let linear = |x: &Point| 0.3 + 2.0 * x[0] - 1.5 * x[1];
        for k in [
            voronoi(30, [0.0, 1.0], [0.0, 1.0], 7, 0).unwrap(),
            rectangle(2, 3, [0.0, 1.0], [0.0, 2.0]).unwrap(),
        ] {
            let top = Topology::new(&k, "test").unwrap();
            let mut area = 0.0;
            for c in 0..k.cell_count(2) {
                let ids = k.cell_vertices(2, c);
                for p in nodal_rule(&top, c, Degree::Quintic) {
                    let u: f64 = ids
                        .iter()
                        .zip(&p.values)
                        .map(|(&v, s)| s * linear(&top.point(v)))
                        .sum();
                    assert_relative_eq!(u, linear(&p.x), epsilon = 1e-12);
                    for (a, want) in [2.0, -1.5].iter().enumerate() {
                        let g: f64 = ids
                            .iter()
                            .zip(&p.gradients)
                            .map(|(&v, s)| s[a] * linear(&top.point(v)))
                            .sum();
                        assert_relative_eq!(g, *want, epsilon = 1e-11);
                    }
                    area += p.weight;
                }
            }
            let total: f64 = k.measure(2).iter().sum();
            assert_relative_eq!(area, total, max_relative = 1e-13);
        }
    }
}
