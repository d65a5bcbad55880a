//! The de Rham map R_k (fields → k-cochains, by quadrature over the
//! k-cells) and the Whitney map W_k (k-cochains → fields, by the Whitney
//! forms of the top simplices). The Whitney mass of every degree, the
//! inner product of these forms, is [`crate::metric::whitney`].
//!
//! # Proxies: which field a k-form is
//!
//! | k | [`ProxyKind`] | R_k of a field | W_k at a point |
//! |---|---|---|---|
//! | 0 | `Function` | f at each vertex | Σ_v c_v λ_v (P1) |
//! | 1 | `Tangent` | ∫_e F · t ds along each edge | Σ_e c_e (λ_a ∇λ_b − λ_b ∇λ_a) |
//! | 2 = n − 1, n = 3 | `Flux` | ∫_f F · n dA through each face | Σ_f c_f 2(λ_a ∇λ_b×∇λ_c − λ_b ∇λ_a×∇λ_c + λ_c ∇λ_a×∇λ_b) |
//! | n (≥ 2) | `Density` | ∫_T ρ dV over each top cell | c_T / \|T\| |
//!
//! On a 1-complex, k = 1 is the tangential line integral (a 1-form), not a
//! density. On surfaces in R³ the gradients ∇λ are those of the simplex's
//! own tangent plane, so Whitney vectors are tangent to the cell.
//!
//! # Orientation
//!
//! The complex orients a k-simplex below the top dimension by its sorted
//! vertex list [s₀ < s₁ < …]: ∂[s₀ … s_k] = Σ (−1)^i [… ŝ_i …]. So an edge
//! [a, b] (a < b) runs from a to b (δ⁰ gives −1 at a, +1 at b, and R₀ then
//! d₀ is φ_b − φ_a), and a face [a, b, c] of a 3-complex has the normal
//! (x_b − x_a) × (x_c − x_a), the right-hand rule of its ∂. Top cells carry
//! the complex's own orientation ([`Complex::top_orientation`]), and a
//! density's cochain is ∫_T ρ taken with it as positive: the top cochain
//! of ρ = 1 is the measure. With these conventions d ∘ R = R ∘ d (Stokes) to
//! quadrature accuracy, and R_k ∘ W_k = identity on each simplex.
//!
//! # Accuracy
//!
//! The quadrature is the collapsed (Duffy) product of 4-point
//! Gauss–Legendre rules on the k-simplex: exact for polynomials of degree
//! 8 − k along the cell (7 on edges, 6 on triangles, 5 on tetrahedra), so
//! R_k of a polynomial field of degree ≤ 5 is exact to rounding. W_k is
//! exact on the Whitney forms: W_k R_k reproduces constant vector fields on
//! every simplex (k = 1 and the flux, see [`interpolate`]), linear
//! functions for k = 0 and constant densities for k = n. [`probe`] finds
//! the simplex that holds a point and evaluates the form there.
//!
//! ```
//! use hasse_complex::generate::{kuhn, uniform_axis};
//! use hasse_solver::physics::forms::whitney_map::{cell_vectors, de_rham, Field};
//! let x = uniform_axis(3, 0.0, 1.0).unwrap();
//! let k = kuhn(&[x.clone(), x]).unwrap();
//! // The constant field (2, −1): R₁ then W₁ gives it back in every triangle.
//! let field = |_: &[f64]| [2.0, -1.0, 0.0];
//! let cochain = de_rham(&k, 1, Field::Vector(&field)).unwrap();
//! for v in cell_vectors(&k, 1, &cochain).unwrap() {
//!     assert!((v[0] - 2.0).abs() < 1e-13 && (v[1] + 1.0).abs() < 1e-13);
//! }
//! ```

use super::FormsError;
use hasse_complex::Complex;
use nalgebra::{DMatrix, DVector, Vector3};

/// A field to integrate over the k-cells.
#[derive(Clone, Copy)]
pub enum Field<'a> {
    /// A function of the point (k = 0 values, k = n densities); the point
    /// has the embedding dimension's coordinates.
    Scalar(&'a dyn Fn(&[f64]) -> f64),
    /// A vector field (k = 1 tangential, k = 2 in 3D flux), three
    /// components whatever the embedding (the unused ones are ignored
    /// where they are orthogonal to the cells).
    Vector(&'a dyn Fn(&[f64]) -> [f64; 3]),
}

/// What a k-form is as a field on this complex (see the module table).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ProxyKind {
    /// k = 0: a function, by its vertex values.
    Function,
    /// k = 1: a vector field, by its line integrals along the edges.
    Tangent,
    /// k = 2 on a 3-complex: a vector field, by its fluxes through the faces.
    Flux,
    /// k = n ≥ 2: a density, by its integrals over the top cells.
    Density,
}

impl ProxyKind {
    /// The proxy of k-forms on `complex`, or why there is none here.
    pub fn of(complex: &Complex, k: usize) -> Result<Self, FormsError> {
        let n = complex.dim();
        match k {
            _ if k > n => Err(FormsError::Degree { degree: k, dim: n }),
            0 => Ok(ProxyKind::Function),
            1 => Ok(ProxyKind::Tangent),
            _ if k == n => Ok(ProxyKind::Density),
            2 if n == 3 && complex.embedding_dim() == 3 => Ok(ProxyKind::Flux),
            _ => Err(FormsError::Field(format!(
                "{k}-forms on a {n}-complex embedded in R^{} have no vector or scalar proxy here",
                complex.embedding_dim()
            ))),
        }
    }

    /// Whether the proxy is a vector field.
    pub fn is_vector(&self) -> bool {
        matches!(self, ProxyKind::Tangent | ProxyKind::Flux)
    }
}

/// The value of a Whitney form at a point: a number or a vector.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Proxy {
    /// A function or a density.
    Scalar(f64),
    /// A vector (padded to three components).
    Vector([f64; 3]),
}

/// A quadrature rule on the reference k-simplex: barycentric points
/// (k + 1 coordinates) and weights summing to 1.
fn simplex_rule(k: usize) -> Vec<(Vec<f64>, f64)> {
    // 4-point Gauss–Legendre on [0, 1].
    const XI: [f64; 4] = [
        -0.861_136_311_594_052_6,
        -0.339_981_043_584_856_3,
        0.339_981_043_584_856_3,
        0.861_136_311_594_052_6,
    ];
    const W: [f64; 4] = [
        0.347_854_845_137_453_9,
        0.652_145_154_862_546_1,
        0.652_145_154_862_546_1,
        0.347_854_845_137_453_9,
    ];
    let nodes: Vec<(f64, f64)> = XI
        .iter()
        .zip(W)
        .map(|(&x, w)| ((1.0 + x) / 2.0, w / 2.0))
        .collect();
    let factorial: f64 = (1..=k).map(|i| i as f64).product();
    let mut rule = Vec::new();
    let count = nodes.len().pow(k as u32);
    for index in 0..count {
        // The collapsed coordinates u_1 … u_k of this product point.
        let mut rest = index;
        let mut lambda = vec![0.0; k + 1];
        let mut weight = factorial;
        let mut remaining = 1.0;
        for i in 0..k {
            let (u, w) = nodes[rest % nodes.len()];
            rest /= nodes.len();
            lambda[i + 1] = u * remaining;
            // Jacobian of the Duffy map: Π (1 − u_i)^{k−1−i}.
            weight *= w * (1.0 - u).powi((k - 1 - i) as i32);
            remaining *= 1.0 - u;
        }
        lambda[0] = remaining;
        rule.push((lambda, weight));
    }
    rule
}

fn padded(x: &[f64]) -> [f64; 3] {
    let mut p = [0.0; 3];
    for (slot, v) in p.iter_mut().zip(x) {
        *slot = *v;
    }
    p
}

/// R_k: the k-cochain of `field` (see the module table for which field
/// each degree takes). Every k-cell of degree ≥ 2 must be a simplex; on a
/// flat torus each cell is integrated unwrapped, so the field is evaluated
/// at points that may lie one period outside the box (give a periodic
/// field).
///
/// ```
/// use hasse_complex::generate::{kuhn, uniform_axis};
/// use hasse_solver::physics::forms::whitney_map::{de_rham, Field};
/// let x = uniform_axis(2, 0.0, 1.0).unwrap();
/// let k = kuhn(&[x.clone(), x]).unwrap();
/// // Stokes: d R₀(φ) = R₁(∇φ) for φ = x² y.
/// let phi = |p: &[f64]| p[0] * p[0] * p[1];
/// let grad = |p: &[f64]| [2.0 * p[0] * p[1], p[0] * p[0], 0.0];
/// let r0 = de_rham(&k, 0, Field::Scalar(&phi)).unwrap();
/// let r1 = de_rham(&k, 1, Field::Vector(&grad)).unwrap();
/// let d0 = k.coboundary(0);
/// for (e, row) in d0.outer_iterator().enumerate() {
///     let d: f64 = row.iter().map(|(v, &s)| f64::from(s) * r0[v]).sum();
///     assert!((d - r1[e]).abs() < 1e-14);
/// }
/// ```
pub fn de_rham(complex: &Complex, k: usize, field: Field<'_>) -> Result<Vec<f64>, FormsError> {
    let kind = ProxyKind::of(complex, k)?;
    let d = complex.embedding_dim();
    let wrong = |wants: &str| -> Result<Vec<f64>, FormsError> {
        Err(FormsError::Field(format!(
            "the de Rham map of degree {k} on this {}-complex integrates {wants}",
            complex.dim()
        )))
    };
    let rule = simplex_rule(k);
    let count = complex.cell_count(k);
    match (kind, field) {
        (ProxyKind::Function, Field::Scalar(f)) => {
            Ok((0..count).map(|v| f(complex.vertices().point(v))).collect())
        }
        (ProxyKind::Density, Field::Scalar(f)) => (0..count)
            .map(|c| {
                let points = simplex_points(complex, k, c)?;
                let measure = complex.measure(k)[c];
                Ok(measure
                    * rule
                        .iter()
                        .map(|(lambda, w)| w * f(&at(&points, lambda)[..d]))
                        .sum::<f64>())
            })
            .collect(),
        (ProxyKind::Tangent | ProxyKind::Flux, Field::Vector(f)) => (0..count)
            .map(|c| {
                let points = simplex_points(complex, k, c)?;
                // t = x_b − x_a along an edge; for a face the normal of
                // its orientation with length 2|f|, so that the integral
                // is Σ w F·N / 2.
                let (direction, scale) = if kind == ProxyKind::Tangent {
                    (points[1] - points[0], 1.0)
                } else {
                    ((points[1] - points[0]).cross(&(points[2] - points[0])), 0.5)
                };
                Ok(scale
                    * rule
                        .iter()
                        .map(|(lambda, w)| {
                            let x = at(&points, lambda);
                            w * Vector3::from(f(&x[..d])).dot(&direction)
                        })
                        .sum::<f64>())
            })
            .collect(),
        (ProxyKind::Function | ProxyKind::Density, Field::Vector(_)) => {
            wrong("a function (Field::Scalar)")
        }
        (ProxyKind::Tangent | ProxyKind::Flux, Field::Scalar(_)) => {
            wrong("a vector field (Field::Vector)")
        }
    }
}

/// The point Σ λ_i x_i, padded to three coordinates.
fn at(points: &[Vector3<f64>], lambda: &[f64]) -> [f64; 3] {
    let x: Vector3<f64> = points
        .iter()
        .zip(lambda)
        .map(|(p, l)| p * *l)
        .fold(Vector3::zeros(), |a, b| a + b);
    [x[0], x[1], x[2]]
}

/// The unwrapped points of k-cell `c`, which must be a simplex.
fn simplex_points(complex: &Complex, k: usize, c: usize) -> Result<Vec<Vector3<f64>>, FormsError> {
    let points = complex.cell_points(k, c);
    if points.len() != k + 1 {
        return Err(FormsError::NotSimplex {
            dim: k,
            cell: c,
            vertices: points.len(),
        });
    }
    Ok(points.into_iter().map(Vector3::from).collect())
}

/// The barycentric coordinates of a top simplex as affine functions: the
/// unwrapped vertices and the tangent gradients ∇λ_i.
struct Barycentric {
    points: Vec<Vector3<f64>>,
    gradients: Vec<Vector3<f64>>,
}

impl Barycentric {
    fn new(complex: &Complex, c: usize) -> Result<Self, FormsError> {
        let n = complex.dim();
        let points = simplex_points(complex, n, c)?;
        let edges: Vec<Vector3<f64>> = points[1..].iter().map(|p| p - points[0]).collect();
        let gram = DMatrix::from_fn(n, n, |a, b| edges[a].dot(&edges[b]));
        let inverse = gram.try_inverse().ok_or_else(|| {
            FormsError::Field(format!(
                "top cell {c} is a degenerate simplex (zero volume)"
            ))
        })?;
        // ∇λ_a = Σ_b (G⁻¹)_ab E_b, a ≥ 1, in the simplex's own plane; the
        // λ sum to 1, so ∇λ₀ = −Σ ∇λ_a.
        let mut gradients = vec![Vector3::zeros(); n + 1];
        for a in 0..n {
            let g: Vector3<f64> = (0..n)
                .map(|b| edges[b] * inverse[(a, b)])
                .fold(Vector3::zeros(), |s, v| s + v);
            gradients[a + 1] = g;
            gradients[0] -= g;
        }
        Ok(Self { points, gradients })
    }

    /// λ(x) for a point of the cell (of its plane; outside, the affine
    /// extension).
    fn at(&self, x: &Vector3<f64>) -> Vec<f64> {
        let offset = x - self.points[0];
        let mut lambda: Vec<f64> = self.gradients.iter().map(|g| g.dot(&offset)).collect();
        lambda[0] = 1.0 - lambda[1..].iter().sum::<f64>();
        lambda
    }
}

/// The global k-cell of the local face `local` (increasing positions in
/// the top cell's sorted vertex list).
fn face(
    complex: &Complex,
    k: usize,
    vertices: &[usize],
    local: &[usize],
) -> Result<usize, FormsError> {
    let global: Vec<usize> = local.iter().map(|&i| vertices[i]).collect();
    complex.find_cell(k, &global).ok_or_else(|| {
        FormsError::Internal(format!("face {global:?} of a top cell is not a {k}-cell"))
    })
}

fn check_length(complex: &Complex, k: usize, cochain: &[f64]) -> Result<(), FormsError> {
    let cells = complex.cell_count(k);
    if cochain.len() != cells {
        return Err(FormsError::Field(format!(
            "a {k}-cochain needs one value per {k}-cell ({cells}), got {}",
            cochain.len()
        )));
    }
    Ok(())
}

/// W_k: the Whitney form of the k-cochain `cochain` at the point `x` of
/// top simplex `cell` (embedding coordinates; on a flat torus any image
/// of the point), as its proxy (module table).
///
/// The exact property: on each simplex the Whitney k-forms span the
/// polynomial forms P₁⁻Λᵏ, which contain the constant k-forms, and R_k W_k
/// is the identity on the cochains of the simplex. So for a constant
/// vector field F, W₁(R₁ F) = F at every point (and W₂(R₂ F) = F for the
/// flux in 3D): R₁ F is the cochain of the constant 1-form F·dx, which is
/// its own Whitney interpolant.
///
/// ```
/// use hasse_complex::generate::{kuhn, uniform_axis};
/// use hasse_solver::physics::forms::whitney_map::{interpolate, Proxy};
/// let x = uniform_axis(2, 0.0, 1.0).unwrap();
/// let k = kuhn(&[x.clone(), x]).unwrap();
/// // The Whitney form of one edge e: along e its tangential component is
/// // 1/|e|, so W · (x_b − x_a) = 1 at any point of e, here its midpoint.
/// let t = 0;
/// let (a, b) = (k.cell_vertices(2, t)[0], k.cell_vertices(2, t)[1]);
/// let e = k.find_cell(1, &[a, b]).unwrap();
/// let mut c = vec![0.0; k.cell_count(1)];
/// c[e] = 1.0;
/// let (p, q) = (k.vertices().point(a), k.vertices().point(b));
/// let mid = [(p[0] + q[0]) / 2.0, (p[1] + q[1]) / 2.0];
/// let Proxy::Vector(v) = interpolate(&k, 1, &c, t, &mid).unwrap() else { panic!() };
/// let along = v[0] * (q[0] - p[0]) + v[1] * (q[1] - p[1]);
/// assert!((along - 1.0).abs() < 1e-14);
/// ```
pub fn interpolate(
    complex: &Complex,
    k: usize,
    cochain: &[f64],
    cell: usize,
    x: &[f64],
) -> Result<Proxy, FormsError> {
    let kind = ProxyKind::of(complex, k)?;
    check_length(complex, k, cochain)?;
    let n = complex.dim();
    if cell >= complex.cell_count(n) {
        return Err(FormsError::Field(format!(
            "top cell {cell} does not exist (the complex has {})",
            complex.cell_count(n)
        )));
    }
    let local = Barycentric::new(complex, cell)?;
    let reference: [f64; 3] = local.points[0].into();
    let point = Vector3::from(complex.vertices().nearest(&padded(x), &reference));
    let lambda = local.at(&point);
    whitney_value(complex, kind, cochain, cell, &local, &lambda)
}

fn whitney_value(
    complex: &Complex,
    kind: ProxyKind,
    cochain: &[f64],
    cell: usize,
    local: &Barycentric,
    lambda: &[f64],
) -> Result<Proxy, FormsError> {
    let n = complex.dim();
    let vertices = complex.cell_vertices(n, cell);
    let g = &local.gradients;
    Ok(match kind {
        ProxyKind::Function => Proxy::Scalar(
            vertices
                .iter()
                .zip(lambda)
                .map(|(&v, l)| cochain[v] * l)
                .sum(),
        ),
        ProxyKind::Density => Proxy::Scalar(cochain[cell] / complex.measure(n)[cell]),
        ProxyKind::Tangent => {
            let mut v = Vector3::zeros();
            for i in 0..=n {
                for j in i + 1..=n {
                    let c = cochain[face(complex, 1, vertices, &[i, j])?];
                    v += c * (lambda[i] * g[j] - lambda[j] * g[i]);
                }
            }
            Proxy::Vector(v.into())
        }
        ProxyKind::Flux => {
            let mut v = Vector3::zeros();
            for i in 0..=n {
                for j in i + 1..=n {
                    for l in j + 1..=n {
                        let c = cochain[face(complex, 2, vertices, &[i, j, l])?];
                        v += 2.0
                            * c
                            * (lambda[i] * g[j].cross(&g[l]) - lambda[j] * g[i].cross(&g[l])
                                + lambda[l] * g[i].cross(&g[j]));
                    }
                }
            }
            Proxy::Vector(v.into())
        }
    })
}

/// A probe of a k-cochain: its value at the point `x` of a mesh that
/// fills its space, in the top cell `locator` finds for it
/// ([`crate::physics::probe::PointLocator`]), by [`value_in_cell`]: on a
/// simplex the Whitney form, so for a 1-cochain its Whitney vector at `x`;
/// `None` outside the mesh.
///
/// ```
/// use hasse_complex::generate::{kuhn, uniform_axis};
/// use hasse_solver::physics::forms::whitney_map::{de_rham, probe, Field, Proxy};
/// use hasse_solver::physics::probe::PointLocator;
/// let x = uniform_axis(4, 0.0, 1.0).unwrap();
/// let k = kuhn(&[x.clone(), x]).unwrap();
/// let c = de_rham(&k, 1, Field::Vector(&|p| [-p[1], p[0], 0.0])).unwrap();
/// let locator = PointLocator::new(&k).unwrap();
/// // The rotation is a Whitney form: the probe gives it back exactly.
/// let Some(Proxy::Vector(v)) = probe(&k, &locator, 1, &c, &[0.3, 0.8]).unwrap() else { panic!() };
/// assert!((v[0] + 0.8).abs() < 1e-14 && (v[1] - 0.3).abs() < 1e-14);
/// assert_eq!(probe(&k, &locator, 1, &c, &[1.5, 0.5]).unwrap(), None);
/// ```
pub fn probe(
    complex: &Complex,
    locator: &crate::physics::probe::PointLocator<'_>,
    k: usize,
    cochain: &[f64],
    x: &[f64],
) -> Result<Option<Proxy>, FormsError> {
    match locator.locate(x) {
        Some(cell) => value_in_cell(complex, k, cochain, cell, x).map(Some),
        None => Ok(None),
    }
}

/// The value at `x` of a k-cochain in top cell `cell` of any shape: the
/// Whitney form ([`interpolate`]) on a simplex; on another cell, the
/// function of a 0-cochain interpolated by the cell's nodal shape
/// functions (Q1 on quadrilaterals and hexahedra, as
/// [`crate::physics::probe::value_at`] does for nodal fields), the density
/// c_T/|T| of an n-cochain, and for a vector proxy the cell's constant
/// least-squares vector of [`cell_vectors`] (exact for constant fields:
/// on a box, the mean of opposite edges or faces).
///
/// ```
/// use hasse_complex::generate::rectangle;
/// use hasse_solver::physics::forms::whitney_map::{de_rham, value_in_cell, Field, Proxy};
/// use hasse_solver::physics::probe::PointLocator;
/// let k = rectangle(4, 4, [0.0, 1.0], [0.0, 1.0]).unwrap();
/// let p = [0.3, 0.4];
/// let cell = PointLocator::new(&k).unwrap().locate(&p).unwrap();
/// // A constant field on squares comes back exactly.
/// let c = de_rham(&k, 1, Field::Vector(&|_| [0.5, -2.0, 0.0])).unwrap();
/// let Proxy::Vector(v) = value_in_cell(&k, 1, &c, cell, &p).unwrap() else { panic!() };
/// assert!((v[0] - 0.5).abs() < 1e-14 && (v[1] + 2.0).abs() < 1e-14);
/// // A bilinear function, by its vertex values, is reproduced by Q1.
/// let f = de_rham(&k, 0, Field::Scalar(&|x| 1.0 + x[0] * x[1])).unwrap();
/// let Proxy::Scalar(u) = value_in_cell(&k, 0, &f, cell, &p).unwrap() else { panic!() };
/// assert!((u - 1.12).abs() < 1e-14);
/// ```
pub fn value_in_cell(
    complex: &Complex,
    k: usize,
    cochain: &[f64],
    cell: usize,
    x: &[f64],
) -> Result<Proxy, FormsError> {
    let n = complex.dim();
    if cell < complex.cell_count(n) && complex.cell_vertices(n, cell).len() == n + 1 {
        return interpolate(complex, k, cochain, cell, x);
    }
    let kind = ProxyKind::of(complex, k)?;
    check_length(complex, k, cochain)?;
    if cell >= complex.cell_count(n) {
        return Err(FormsError::Field(format!(
            "top cell {cell} does not exist (the complex has {})",
            complex.cell_count(n)
        )));
    }
    Ok(match kind {
        ProxyKind::Function => Proxy::Scalar(crate::physics::probe::value_at(
            complex,
            crate::metric::Location::Nodal,
            cochain,
            None,
            cell,
            x,
        )),
        ProxyKind::Density => Proxy::Scalar(cochain[cell] / complex.measure(n)[cell]),
        ProxyKind::Tangent => Proxy::Vector(least_squares_vector(complex, cell, cochain)?),
        ProxyKind::Flux => Proxy::Vector(least_squares_flux(complex, cell, cochain)?),
    })
}

/// The vector proxy of a k-cochain (k = 1, or k = 2 on a 3-complex) per
/// top cell: on a simplex the Whitney form at its centroid; on another
/// cell the constant vector whose line integrals (k = 1) or fluxes
/// (k = 2) fit the cell's edge or face values best in least squares (the
/// minimum-norm solution, tangent to a flat cell), which, like the Whitney
/// form, is exact for constant fields, and on a rectangle or a box is the
/// lowest-order edge (Nédélec) or face (Raviart–Thomas) element's value at
/// the centre, the mean of opposite edges or faces.
pub fn cell_vectors(
    complex: &Complex,
    k: usize,
    cochain: &[f64],
) -> Result<Vec<[f64; 3]>, FormsError> {
    let kind = ProxyKind::of(complex, k)?;
    if !kind.is_vector() {
        return Err(FormsError::Field(format!(
            "{k}-forms on a {}-complex are not vector fields",
            complex.dim()
        )));
    }
    check_length(complex, k, cochain)?;
    let n = complex.dim();
    let centroid = vec![1.0 / (n + 1) as f64; n + 1];
    (0..complex.cell_count(n))
        .map(|c| {
            if complex.cell_vertices(n, c).len() == n + 1 {
                let local = Barycentric::new(complex, c)?;
                match whitney_value(complex, kind, cochain, c, &local, &centroid)? {
                    Proxy::Vector(v) => Ok(v),
                    Proxy::Scalar(_) => Err(FormsError::Internal("a scalar proxy".into())),
                }
            } else if kind == ProxyKind::Tangent {
                least_squares_vector(complex, c, cochain)
            } else {
                least_squares_flux(complex, c, cochain)
            }
        })
        .collect()
}

/// The edges of top cell `c`, through the boundary matrices.
fn cell_edges(complex: &Complex, c: usize) -> Vec<usize> {
    let mut cells = vec![c];
    for p in (2..=complex.dim()).rev() {
        let by_cell = complex.boundary_csc(p);
        let mut below: Vec<usize> = cells
            .iter()
            .filter_map(|&f| by_cell.outer_view(f))
            .flat_map(|col| col.indices().to_vec())
            .collect();
        below.sort_unstable();
        below.dedup();
        cells = below;
    }
    cells
}

fn least_squares_vector(
    complex: &Complex,
    c: usize,
    cochain: &[f64],
) -> Result<[f64; 3], FormsError> {
    let edges = cell_edges(complex, c);
    let tangents = DMatrix::from_fn(edges.len(), 3, |r, a| {
        let p = complex.cell_points(1, edges[r]);
        p[1][a] - p[0][a]
    });
    let values = DVector::from_iterator(edges.len(), edges.iter().map(|&e| cochain[e]));
    least_squares(c, tangents, values)
}

/// The minimum-norm least-squares F of rows · F = values, with a relative
/// rank cut that leaves out the normal of a flat cell.
fn least_squares(
    c: usize,
    rows: DMatrix<f64>,
    values: DVector<f64>,
) -> Result<[f64; 3], FormsError> {
    let scale = rows.norm().max(f64::MIN_POSITIVE);
    let svd = rows.svd(true, true);
    let v = svd
        .solve(&values, 1e-12 * scale)
        .map_err(|e| FormsError::Internal(format!("least squares on cell {c}: {e}")))?;
    Ok([v[0], v[1], v[2]])
}

/// The constant field whose fluxes through the faces of 3-cell `c` fit
/// its 2-cochain values best: the flux of F through a planar face is
/// F · N_f, N_f = ½ Σ_e s_e (x_tail − x₀) × (x_head − x₀) the face's vector
/// area, oriented by its boundary (s_e the sign of edge e in ∂f, tail and
/// head from δ⁰): the right-hand rule of ∂, as for triangles.
fn least_squares_flux(
    complex: &Complex,
    c: usize,
    cochain: &[f64],
) -> Result<[f64; 3], FormsError> {
    let faces: Vec<usize> = complex
        .boundary_csc(3)
        .outer_view(c)
        .map(|col| col.indices().to_vec())
        .unwrap_or_default();
    let by_face = complex.boundary_csc(2);
    let d0 = complex.coboundary(0);
    let mut areas = Vec::with_capacity(faces.len());
    for &f in &faces {
        // The face's own unwrapped frame: every edge measured in it.
        let ids = complex.cell_vertices(2, f);
        let points: Vec<Vector3<f64>> = complex
            .cell_points(2, f)
            .into_iter()
            .map(Vector3::from)
            .collect();
        let at = |v: usize| -> Result<Vector3<f64>, FormsError> {
            ids.iter()
                .position(|&w| w == v)
                .map(|i| points[i] - points[0])
                .ok_or_else(|| FormsError::Internal(format!("vertex {v} not on face {f}")))
        };
        let mut area = Vector3::zeros();
        if let Some(column) = by_face.outer_view(f) {
            for (e, &s) in column.iter() {
                let (mut tail, mut head) = (usize::MAX, usize::MAX);
                if let Some(row) = d0.outer_view(e) {
                    for (v, &sign) in row.iter() {
                        if sign < 0 {
                            tail = v;
                        } else {
                            head = v;
                        }
                    }
                }
                area += f64::from(s) * at(tail)?.cross(&at(head)?) / 2.0;
            }
        }
        areas.push(area);
    }
    let rows = DMatrix::from_fn(faces.len(), 3, |r, a| areas[r][a]);
    let values = DVector::from_iterator(faces.len(), faces.iter().map(|&f| cochain[f]));
    least_squares(c, rows, values)
}
