//! Q1 elements on quadrilaterals and hexahedra: the Gauss-rule stiffness,
//! its constant-Jacobian form on parallelograms and parallelepipeds, the
//! per-thread memo of a cell's local incidence, and the Q1 load.

use super::*;

/// What the local incidence of a Q1 cell fixes (its tensor order and
/// A_c⁺), kept from the last cell looked up: neighbouring cells of a
/// structured grid have the same local incidence, and comparing it is
/// cheaper than finding the order again and looking A_c⁺ up by key.
#[derive(Default)]
pub(super) struct Q1Memo {
    /// Vertex count and each edge's (tail, head) in the sorted vertex
    /// list, for the last cell whose order was found.
    ends: Option<(usize, [[u8; 2]; 12])>,
    order: Option<TensorOrder>,
    /// A_c⁺ with its rows in tensor order (`pinv[l][e]`), valid when
    /// `pinv_valid`, for the local incidence in `ends`.
    pinv: [[f64; 12]; 8],
    pinv_valid: bool,
    /// S_ab = (A_c⁺)ᵀ R_ab A_c⁺ of [`affine_block`] for every axis pair,
    /// E × E each, valid for the same local incidence when `affine_valid`.
    affine: Vec<f64>,
    affine_valid: bool,
    /// Scratch for the A_c⁺ cache's key.
    key: Vec<usize>,
}

impl Q1Memo {
    /// The tensor order of a cell with `m` vertices, n-dimensional, whose
    /// edges have the local `ends` (unused entries zero).
    pub(super) fn order(
        &mut self,
        m: usize,
        n: usize,
        ends: &[[u8; 2]; 12],
        edges: usize,
    ) -> Option<TensorOrder> {
        if self.ends == Some((m, *ends)) {
            return self.order;
        }
        self.order = tensor_order_of(m, n, ends, edges);
        self.ends = Some((m, *ends));
        self.pinv_valid = false;
        self.affine_valid = false;
        self.order
    }

    /// Make A_c⁺ (and with `affine` the S_ab) those of a Q1 cell with N
    /// corners, E edges and tensor order `order`, unless they already are.
    fn refresh<const N: usize, const E: usize>(
        &mut self,
        order: &TensorOrder,
        c: usize,
        affine: bool,
    ) -> Result<(), MetricError> {
        if !(self.pinv_valid && self.ends == Some((N, order.ends))) {
            let key = &mut self.key;
            key.clear();
            key.push(N);
            for &[t, h] in &order.ends[..E] {
                key.extend([usize::from(t), usize::from(h)]);
            }
            let pinv = pseudo_inverse_of_key(key, c, "Q1")?;
            for (row, &o) in self.pinv.iter_mut().zip(order.iter()) {
                for (e, entry) in row.iter_mut().take(E).enumerate() {
                    *entry = pinv[(o, e)];
                }
            }
            self.ends = Some((N, order.ends));
            self.order = Some(*order);
            self.pinv_valid = true;
            self.affine_valid = false;
        }
        if affine && !self.affine_valid {
            let n = N.trailing_zeros() as usize;
            let reference = q1_reference(n);
            let p = self.tensor_pinv::<N, E>();
            self.affine.clear();
            self.affine.resize(axis_pairs(n).len() * E * E, 0.0);
            for (&(a, b), sum) in axis_pairs(n)
                .iter()
                .zip(self.affine.chunks_exact_mut(E * E))
            {
                let mut r = [[0.0; N]; N];
                for (l, row) in r.iter_mut().enumerate() {
                    for (j, entry) in row.iter_mut().enumerate() {
                        *entry = reference.products[a][b][l][j];
                        if a != b {
                            *entry += reference.products[b][a][l][j];
                        }
                    }
                }
                congruence::<N, E>(&r, &p, sum);
            }
            self.affine_valid = true;
        }
        Ok(())
    }

    /// A_c⁺ in tensor order (N × E), as [`Q1Memo::refresh`] left it.
    fn tensor_pinv<const N: usize, const E: usize>(&self) -> [[f64; E]; N] {
        let mut p = [[0.0; E]; N];
        for (row, memo_row) in p.iter_mut().zip(&self.pinv) {
            row.copy_from_slice(&memo_row[..E]);
        }
        p
    }
}

/// [`q1_block`] of a quadrilateral (n = 2) or hexahedron (n = 3).
pub(super) fn q1_cell(
    top: &Topology,
    c: usize,
    order: &TensorOrder,
    k: &Tensor,
    memo: &mut Q1Memo,
    out: &mut [f64],
    load: Option<(LoadFn, &mut [f64])>,
) -> Result<(), MetricError> {
    match top.n {
        2 => q1_block::<4, 4>(top, c, order, k, memo, out, load),
        _ => q1_block::<8, 12>(top, c, order, k, memo, out, load),
    }
}

/// Ω_c of a Q1 cell with N = 2ⁿ corners and E edges (n = 2: 4, 4; n = 3:
/// 8, 12) into `out` (E × E), over its sorted edges (left in the scratch
/// by the element lookup that found the tensor order), in fixed arrays,
/// with A_c's pattern taken from the tensor order (no second walk of the
/// edges): for a parallelogram or parallelepiped from its one Jacobian
/// ([`affine_block`]), for any other cell K_c from the 2ⁿ Gauss points
/// and then (A_c⁺)ᵀ K_c A_c⁺ as in [`edge_block`] ([`gauss_block`]).
/// Either way Ω_c is exactly symmetric. With `load` = (f, shares), the
/// cell's load shares are written too, from the same map (as
/// [`q1_load`]).
pub(super) fn q1_block<const N: usize, const E: usize>(
    top: &Topology,
    c: usize,
    order: &TensorOrder,
    k: &Tensor,
    memo: &mut Q1Memo,
    out: &mut [f64],
    load: Option<(LoadFn, &mut [f64])>,
) -> Result<(), MetricError> {
    let n = N.trailing_zeros() as usize;
    debug_assert_eq!((order.len(), n << (n - 1), out.len()), (N, E, E * E));
    let x = tensor_points(top, c, order);
    let geometry = q1_geometry::<N>(&x, c)?;
    if let Some((f, shares)) = load {
        q1_shares(top, c, order, &x, &geometry.weights(), f, shares)?;
    }
    match &geometry {
        Q1Geometry::Affine { det, inverse } => {
            memo.refresh::<N, E>(order, c, true)?;
            affine_block::<N, E>(inverse, det.abs(), k, memo, out);
        }
        Q1Geometry::General(map) => {
            memo.refresh::<N, E>(order, c, false)?;
            gauss_block::<N, E>(map, k, memo, out);
        }
    }
    if out.iter().any(|v| !v.is_finite()) {
        return Err(MetricError::UnsupportedCell {
            method: "Q1",
            needs: "a non-degenerate cell (finite local stiffness)",
            cell: c,
        });
    }
    Ok(())
}

/// The error of a Q1 cell whose isoparametric map folds or collapses.
pub(super) fn q1_inverted(cell: usize) -> MetricError {
    MetricError::UnsupportedCell {
        method: "Q1",
        needs: "a quadrilateral or hexahedron whose isoparametric map keeps one orientation (convex, not inverted)",
        cell,
    }
}

/// The map of a Q1 cell at its Gauss points: one constant Jacobian for a
/// parallelogram or parallelepiped ([`affine_jacobian`]), else the full
/// isoparametric map.
pub(super) enum Q1Geometry<const N: usize> {
    Affine { det: f64, inverse: [[f64; 3]; 3] },
    General(Q1Map<N>),
}

impl<const N: usize> Q1Geometry<N> {
    /// |det J| at each Gauss point.
    fn weights(&self) -> [f64; N] {
        match self {
            Self::Affine { det, .. } => [det.abs(); N],
            Self::General(map) => map.weights,
        }
    }
}

/// [`Q1Geometry`] of the cell with corners `x` (tensor order).
pub(super) fn q1_geometry<const N: usize>(
    x: &[Point; N],
    cell: usize,
) -> Result<Q1Geometry<N>, MetricError> {
    match affine_jacobian::<N>(x) {
        Some(jacobian) => {
            let (det, inverse) = determinant_and_inverse(&jacobian, N.trailing_zeros() as usize);
            if det == 0.0 || !det.is_finite() {
                return Err(q1_inverted(cell));
            }
            Ok(Q1Geometry::Affine { det, inverse })
        }
        None => Ok(Q1Geometry::General(q1_map::<N>(x, cell)?)),
    }
}

/// The constant Jacobian of the map from [−1, 1]ⁿ onto a Q1 cell with
/// corners `x` (tensor order) when the cell is a parallelogram or
/// parallelepiped: every corner is corner 0 plus the edges along its set
/// axes, to within 16 ulp of the largest coordinate. Coordinates
/// carry that rounding already, so the Jacobian's differences do too and
/// the Gauss rule could not resolve a bilinear part that small. `None`
/// for any other cell. J is taken at the centre, from all corners, as the
/// Gauss rule's mean Jacobian.
pub(super) fn affine_jacobian<const N: usize>(x: &[Point; N]) -> Option<[[f64; 3]; 3]> {
    let n = N.trailing_zeros() as usize;
    let mut size = 0.0f64;
    for p in x {
        for &xi in &p[..n] {
            size = size.max(xi.abs());
        }
    }
    let tolerance = 16.0 * f64::EPSILON * size;
    for (l, p) in x.iter().enumerate().skip(3) {
        if l.count_ones() < 2 {
            continue;
        }
        for i in 0..n {
            let along: f64 = (0..n)
                .filter(|&a| (l >> a) & 1 == 1)
                .map(|a| x[1 << a][i] - x[0][i])
                .sum();
            if (p[i] - x[0][i] - along).abs() > tolerance {
                return None;
            }
        }
    }
    let mut jacobian = [[0.0; 3]; 3];
    let scale = 1.0 / N as f64;
    for (l, p) in x.iter().enumerate() {
        for a in 0..n {
            let s = scale * corner_sign(l, a);
            for (row, &pi) in jacobian.iter_mut().zip(&p[..n]) {
                row[a] += s * pi;
            }
        }
    }
    Some(jacobian)
}

/// Ω_c of an affine Q1 cell: with the constant J the Gauss rule gives
/// K_c = Σ_ab C_ab R_ab, C = |det J| J⁻¹ k J⁻ᵀ and R_ab the reference
/// products of the a- and b-derivatives of the shape functions (weight 1
/// per Gauss point), so Ω_c = Σ_{a≤b} C_ab S_ab with S_ab = (A_c⁺)ᵀ R_ab
/// A_c⁺ (R_ab + R_ba off the diagonal), kept in the memo for the cell's
/// local incidence. Every S_ab is exactly symmetric, so Ω_c is.
pub(super) fn affine_block<const N: usize, const E: usize>(
    inverse: &[[f64; 3]; 3],
    weight: f64,
    k: &Tensor,
    memo: &Q1Memo,
    out: &mut [f64],
) {
    let n = N.trailing_zeros() as usize;
    // J⁻¹ k, then C's entries on and above the diagonal, in pair order.
    let mut inverse_k = [[0.0; 3]; 3];
    for (row, inv) in inverse_k.iter_mut().zip(inverse) {
        for (j, entry) in row.iter_mut().enumerate().take(n) {
            *entry = (0..n).map(|i| inv[i] * k[i][j]).sum();
        }
    }
    let mut coefficients = [0.0; 6];
    for (coefficient, &(a, b)) in coefficients.iter_mut().zip(axis_pairs(n)) {
        *coefficient = weight * (0..n).map(|j| inverse_k[a][j] * inverse[b][j]).sum::<f64>();
    }
    out.fill(0.0);
    for (coefficient, sum) in coefficients.iter().zip(memo.affine.chunks_exact(E * E)) {
        for (o, s) in out.iter_mut().zip(sum) {
            *o += coefficient * s;
        }
    }
}

/// The axis pairs (a, b), a ≤ b, of n dimensions, in the order of the
/// memo's S_ab.
pub(super) fn axis_pairs(n: usize) -> &'static [(usize, usize)] {
    match n {
        2 => &[(0, 0), (0, 1), (1, 1)],
        _ => &[(0, 0), (0, 1), (0, 2), (1, 1), (1, 2), (2, 2)],
    }
}

/// Ω_c of any Q1 cell from its isoparametric map: K_c from the 2ⁿ Gauss
/// points, then (A_c⁺)ᵀ K_c A_c⁺, both formed on and above the diagonal
/// and mirrored.
pub(super) fn gauss_block<const N: usize, const E: usize>(
    map: &Q1Map<N>,
    k: &Tensor,
    memo: &Q1Memo,
    out: &mut [f64],
) {
    let n = N.trailing_zeros() as usize;
    // K_c in tensor order.
    let mut kc = [[0.0; N]; N];
    for (&weight, gradients) in map.weights[..N].iter().zip(&map.gradients) {
        let mut flux = [[0.0; 3]; N];
        for (f, g) in flux.iter_mut().zip(gradients) {
            for (i, fi) in f.iter_mut().enumerate().take(n) {
                *fi = weight * (0..n).map(|j| k[i][j] * g[j]).sum::<f64>();
            }
        }
        for l in 0..N {
            for j in l..N {
                kc[l][j] += (0..n).map(|i| gradients[l][i] * flux[j][i]).sum::<f64>();
            }
        }
    }
    let upper = kc;
    for (l, row) in kc.iter_mut().enumerate() {
        for (j, entry) in row.iter_mut().enumerate().take(l) {
            *entry = upper[j][l];
        }
    }
    let p = memo.tensor_pinv::<N, E>();
    congruence::<N, E>(&kc, &p, out);
}

/// Pᵀ K P (E × E, row-major, into `out`) of a symmetric N × N matrix K,
/// formed on and above the diagonal and mirrored.
pub(super) fn congruence<const N: usize, const E: usize>(
    kc: &[[f64; N]; N],
    p: &[[f64; E]; N],
    out: &mut [f64],
) {
    // K P (N × E), then Pᵀ (K P) on and above the diagonal.
    let mut half = [[0.0; E]; N];
    for (h, kl) in half.iter_mut().zip(kc) {
        for (a, pa) in kl.iter().zip(p) {
            for (he, pe) in h.iter_mut().zip(pa) {
                *he += a * pe;
            }
        }
    }
    for e in 0..E {
        for f in e..E {
            let value: f64 = (0..N).map(|l| p[l][e] * half[l][f]).sum();
            out[e * E + f] = value;
            out[f * E + e] = value;
        }
    }
}

/// Sign (±1) of corner `l` along local axis `a`.
pub(super) fn corner_sign(l: usize, a: usize) -> f64 {
    if (l >> a) & 1 == 1 {
        1.0
    } else {
        -1.0
    }
}

/// Q1 shape functions and their reference gradients at ξ ∈ [−1, 1]^n.
pub(super) fn q1_shape(xi: &[f64], n: usize) -> (Vec<f64>, Vec<[f64; 3]>) {
    let m = 1 << n;
    let scale = 1.0 / m as f64;
    let factor = |l: usize, b: usize| 1.0 + corner_sign(l, b) * xi[b];
    let values = (0..m)
        .map(|l| scale * (0..n).map(|b| factor(l, b)).product::<f64>())
        .collect();
    let gradients = (0..m)
        .map(|l| {
            let mut g = [0.0; 3];
            for (a, ga) in g.iter_mut().enumerate().take(n) {
                *ga = scale
                    * corner_sign(l, a)
                    * (0..n)
                        .filter(|&b| b != a)
                        .map(|b| factor(l, b))
                        .product::<f64>();
            }
            g
        })
        .collect();
    (values, gradients)
}

/// The isoparametric map of a Q1 cell with N = 2ⁿ corners at its N Gauss
/// points: |det J| (the reference weight is 1) and the physical shape
/// gradients, both in tensor order. Fixed arrays of the cell's own size:
/// every cell of a Q1 mesh needs one.
pub(super) struct Q1Map<const N: usize> {
    weights: [f64; N],
    gradients: [[Point; N]; N],
}

/// [`Q1Map`] of the cell with corners `x` in tensor order (2 Gauss points
/// per axis, weight 1 each on [−1, 1]^n, N = 2ⁿ). The dimension is read
/// from N, so every loop below has a length known at compile time and is
/// unrolled: this runs for every cell of a Q1 mesh.
#[inline(always)]
pub(super) fn q1_map<const N: usize>(x: &[Point; N], cell: usize) -> Result<Q1Map<N>, MetricError> {
    let n = N.trailing_zeros() as usize;
    let bad = q1_inverted(cell);
    let mut map = Q1Map {
        weights: [0.0; N],
        gradients: [[[0.0; 3]; N]; N],
    };
    let reference = q1_reference(n);
    let mut orientation = 0.0;
    for q in 0..N {
        let shape_gradients = &reference.gradients[q];
        let mut jacobian = [[0.0; 3]; 3];
        for (xl, gl) in x.iter().zip(shape_gradients) {
            for (i, row) in jacobian.iter_mut().enumerate().take(n) {
                for (a, entry) in row.iter_mut().enumerate().take(n) {
                    *entry += xl[i] * gl[a];
                }
            }
        }
        let (det, inverse) = determinant_and_inverse(&jacobian, n);
        if det.is_nan() || det == 0.0 || det * orientation < 0.0 || !det.is_finite() {
            return Err(bad);
        }
        orientation = det.signum();
        map.weights[q] = det.abs();
        // ∇φ = J⁻ᵀ ∇̂φ.
        for (p, r) in map.gradients[q].iter_mut().zip(shape_gradients) {
            for (i, pi) in p.iter_mut().enumerate().take(n) {
                *pi = (0..n).map(|a| inverse[a][i] * r[a]).sum();
            }
        }
    }
    Ok(map)
}

/// Shape values (`values[q][l]`, corner l) and reference gradients at the
/// 2ⁿ Gauss points q of [−1, 1]^n, in arrays of the largest size (n = 3)
/// whose first 2ⁿ entries are used: the same for every cell, so computed
/// once per dimension, and fixed-size so that the per-cell loops over
/// them have known lengths.
pub(super) struct Q1Reference {
    values: [[f64; 8]; 8],
    gradients: [[Point; 8]; 8],
    /// R_ab of [`affine_block`]: `products[a][b][l][j]` = Σ_q ∂_a N̂_l(q)
    /// ∂_b N̂_j(q) over the Gauss points.
    products: [[[[f64; 8]; 8]; 3]; 3],
}

pub(super) fn q1_reference(n: usize) -> &'static Q1Reference {
    static REFERENCE: [std::sync::OnceLock<Q1Reference>; 4] = [
        std::sync::OnceLock::new(),
        std::sync::OnceLock::new(),
        std::sync::OnceLock::new(),
        std::sync::OnceLock::new(),
    ];
    REFERENCE[n.min(3)].get_or_init(|| {
        let g = 1.0 / 3f64.sqrt();
        let mut reference = Q1Reference {
            values: [[0.0; 8]; 8],
            gradients: [[[0.0; 3]; 8]; 8],
            products: [[[[0.0; 8]; 8]; 3]; 3],
        };
        let corners = 1usize << n;
        for q in 0..corners {
            let xi: Vec<f64> = (0..n).map(|a| g * corner_sign(q, a)).collect();
            let (values, gradients) = q1_shape(&xi, n);
            reference.values[q][..values.len()].copy_from_slice(&values);
            reference.gradients[q][..gradients.len()].copy_from_slice(&gradients);
            for a in 0..n {
                for b in 0..n {
                    for l in 0..corners {
                        for j in 0..corners {
                            reference.products[a][b][l][j] += gradients[l][a] * gradients[j][b];
                        }
                    }
                }
            }
        }
        reference
    })
}

/// det J and J⁻¹ of the leading n×n block (n ≤ 3), by cofactors; the
/// inverse is meaningless when det J = 0 (the caller refuses those cells).
pub(super) fn determinant_and_inverse(j: &[[f64; 3]; 3], n: usize) -> (f64, [[f64; 3]; 3]) {
    let mut inverse = [[0.0; 3]; 3];
    match n {
        1 => {
            inverse[0][0] = 1.0 / j[0][0];
            (j[0][0], inverse)
        }
        2 => {
            let det = j[0][0] * j[1][1] - j[0][1] * j[1][0];
            inverse[0][0] = j[1][1] / det;
            inverse[0][1] = -j[0][1] / det;
            inverse[1][0] = -j[1][0] / det;
            inverse[1][1] = j[0][0] / det;
            (det, inverse)
        }
        _ => {
            let cofactor = |r: usize, c: usize| {
                let (r1, r2) = ((r + 1) % 3, (r + 2) % 3);
                let (c1, c2) = ((c + 1) % 3, (c + 2) % 3);
                j[r1][c1] * j[r2][c2] - j[r1][c2] * j[r2][c1]
            };
            let det = (0..3).map(|c| j[0][c] * cofactor(0, c)).sum::<f64>();
            for (r, row) in inverse.iter_mut().enumerate() {
                for (c, entry) in row.iter_mut().enumerate() {
                    *entry = cofactor(c, r) / det;
                }
            }
            (det, inverse)
        }
    }
}

/// The N corners of cell `c` in tensor order.
pub(super) fn tensor_points<const N: usize>(
    top: &Topology,
    c: usize,
    order: &[usize],
) -> [Point; N] {
    let vertices = top.complex.cell_vertices(top.n, c);
    let mut points = [[0.0; 3]; N];
    for (p, &o) in points.iter_mut().zip(order) {
        *p = top.point(vertices[o]);
    }
    points
}

/// [`shape_gradients`] of a Q1 cell with N = 2ⁿ corners: each Gauss
/// point's |det J| and physical gradients, moved from tensor order to the
/// cell's sorted vertex order.
pub(super) fn q1_gradients<const N: usize>(
    top: &Topology,
    c: usize,
    order: &TensorOrder,
) -> Result<Vec<WeightedGradients>, MetricError> {
    let map = q1_map::<N>(&tensor_points(top, c, order), c)?;
    Ok(map
        .weights
        .iter()
        .zip(&map.gradients)
        .map(|(&weight, gradients)| {
            let mut sorted = vec![[0.0; 3]; N];
            for (&o, g) in order.iter().zip(gradients) {
                sorted[o] = *g;
            }
            (weight, sorted)
        })
        .collect())
}

/// [`cell_load`] of a Q1 cell with N = 2ⁿ corners, tensor Gauss rule.
pub(super) fn q1_load<const N: usize>(
    top: &Topology,
    c: usize,
    order: &TensorOrder,
    f: &(dyn Fn(&[f64]) -> f64 + Sync),
    out: &mut [f64],
) -> Result<(), MetricError> {
    let x = tensor_points(top, c, order);
    let weights = q1_geometry::<N>(&x, c)?.weights();
    q1_shares(top, c, order, &x, &weights, f, out)
}

/// The tensor Gauss rule of [`q1_load`] on corners `x` (tensor order) with
/// the map's weights |det J|, written over `out` (sorted vertex order).
pub(super) fn q1_shares<const N: usize>(
    top: &Topology,
    c: usize,
    order: &TensorOrder,
    x: &[Point; N],
    weights: &[f64; N],
    f: LoadFn,
    out: &mut [f64],
) -> Result<(), MetricError> {
    let (n, d) = (N.trailing_zeros() as usize, top.d);
    out.fill(0.0);
    let reference = q1_reference(n);
    for (values, &weight) in reference.values.iter().zip(weights) {
        let mut point = [0.0; 3];
        for (xl, &v) in x.iter().zip(values) {
            for i in 0..n {
                point[i] += v * xl[i];
            }
        }
        let value = weight * evaluate(f, &point, d, c)?;
        for (&o, v) in order.iter().zip(values) {
            out[o] += value * v;
        }
    }
    Ok(())
}
