//! Harmonic k-forms from cohomology generators: an integer cocycle c per
//! class of H^k(K) (absolute: no boundary condition), made harmonic by one
//! Poisson solve, h = c − d α with
//!
//! ```text
//!     d_{k−1}ᵀ ⋆_k d_{k−1} α = d_{k−1}ᵀ ⋆_k c,
//! ```
//!
//! so that d h = d c = 0 (exactly: c is an integer cocycle and d d = 0 in
//! integers) and dᵀ ⋆ h = 0 up to the solve's rounding. h has the periods
//! of c (it differs by an exact form), and is the unique harmonic form of
//! its class. This needs no eigensolver and is exact to rounding, unlike
//! the kernel of the pencil of [`super::HodgeLaplacian`].
//!
//! The generators, by degree:
//!
//! - k = 0: the indicator of each connected component (h = c).
//! - k = 1 on a 2-complex (surfaces, planar domains): the tree–cotree
//!   construction. A spanning forest T of the edges; a spanning forest C
//!   of the dual graph on the remaining edges, whose nodes are the faces
//!   and one node "outside" joined through every boundary edge (rooted
//!   there, since an absolute cocycle has no condition on the boundary);
//!   the edges in neither are the generators, β₁ of them on an orientable
//!   surface (E − V − F + 2 = 2g on a closed connected one, E − V − F + 1
//!   = 1 − χ on a connected one with boundary). The cocycle of generator g is 1 on g, 0 on T and on the
//!   other generators, and on the cotree edges what makes d c = 0 face by
//!   face, peeled from the leaves of C to its roots; values are integers.
//! - k = n: per connected closed orientable component (its top cells, with
//!   the complex's coherent orientation, form a cycle z), the indicator of
//!   one of its cells, of period 1 on z; its harmonic form is
//!   h = ⋆_n⁻¹ z / ⟨z, ⋆_n⁻¹ z⟩, the normalised volume form (co-closed:
//!   dᵀ ⋆ h ∝ ∂z = 0). On a component with boundary H^n is zero.
//!
//! Relative classes, Hᵏ(K, ∂K) ([`Forms::harmonic_basis_with`] and
//! [`Boundary::Essential`]), every degree: for k = 1 on a surface or
//! planar 2-complex the same tree–cotree with the boundary's vertices as
//! one ground node of the tree and the boundary's edges held at 0; for
//! every other (k, n) the integer reduction of the relative coboundaries
//! (`relative.rs`). Their harmonic forms h = z − dα (α a relative
//! (k−1)-cochain, 0 on the boundary) vanish on the boundary and are
//! co-closed at the interior (k−1)-cells; for k = n that makes ⋆h
//! constant over each component with boundary (a multiple of the volume
//! form: h_σ = |σ|/|K| on the diagonal star).
//!
//! - Every other degree (k = 1 and 2 on 3-complexes, k = 1 on 2-complexes
//!   that are not surfaces): integer column reduction of the coboundary
//!   matrices (see `reduction.rs`): the cocycles V_j of the k-cells left
//!   unpaired by the reductions of δ^{k−1} and δᵏ, closed exactly in
//!   integers (checked), independent modulo exact forms, β_k of them.
//!   For k ≥ 2 the exact part's potential α on the (k−1)-cells is held at
//!   0 off a set of cells whose columns of d_{k−1} are a basis of its
//!   image (found by the same reduction), which makes the solve definite.
//!
//! ```
//! use hasse_complex::{dual::DualKind, generate::torus};
//! use hasse_solver::physics::forms::{Forms, Star};
//! let k = torus(2.0, 0.7, 16, 8).unwrap();
//! let basis = Forms::new(&k, Star::Diagonal(DualKind::Barycentric)).harmonic_basis(1).unwrap();
//! // Two classes (β₁ = 2), each harmonic to rounding.
//! assert_eq!((basis.forms.len(), basis.betti), (2, 2));
//! assert!(basis.closed.iter().chain(&basis.coclosed).all(|r| *r < 1e-12));
//! ```

use super::{Boundary, Forms, FormsError};
use crate::la::direct::{DirectSolver, Factorization};
use crate::la::fixed::FixedSplit;
use crate::operator::Canonical;
use hasse_complex::Complex;
use sprs::CsMat;
use std::collections::VecDeque;

/// A basis of the harmonic k-forms with the cocycles it came from.
#[derive(Clone, Debug, PartialEq)]
pub struct HarmonicBasis {
    /// The degree k.
    pub degree: usize,
    /// The integer cocycles, one per cohomology class (as f64 values).
    pub generators: Vec<Vec<f64>>,
    /// Their harmonic representatives h = c − dα, in the same order.
    pub forms: Vec<Vec<f64>>,
    /// β_k over Q, from the ranks of ∂ (the relative β_k(K, ∂K) for
    /// essential conditions): `forms.len()` must equal it.
    pub betti: usize,
    /// ‖d h‖_∞ / ‖h‖_∞ per form (0 for k = n).
    pub closed: Vec<f64>,
    /// ‖dᵀ ⋆ h‖_∞ / ‖⋆ h‖_∞ per form (0 for k = 0).
    pub coclosed: Vec<f64>,
}

/// The exact part d α of a cochain and its potential α
/// ([`Forms::exact_part`]).
#[derive(Clone, Debug, PartialEq)]
pub struct ExactPart {
    /// α on the (k−1)-cells.
    pub potential: Vec<f64>,
    /// d α on the k-cells.
    pub exact: Vec<f64>,
}

fn max_abs(v: &[f64]) -> f64 {
    v.iter().fold(0.0, |m, x| m.max(x.abs()))
}

/// y = A x for an integer matrix (CSR).
pub(crate) fn multiply(a: &CsMat<i8>, x: &[f64]) -> Vec<f64> {
    let a = if a.is_csr() { a.clone() } else { a.to_csr() };
    a.outer_iterator()
        .map(|row| row.iter().map(|(j, &s)| f64::from(s) * x[j]).sum())
        .collect()
}

/// y = Aᵀ x for an integer matrix.
pub(crate) fn multiply_transpose(a: &CsMat<i8>, x: &[f64]) -> Vec<f64> {
    let mut y = vec![0.0; a.cols()];
    // sprs yields (row, column) whatever the storage.
    for (v, (i, j)) in a.iter() {
        y[j] += f64::from(*v) * x[i];
    }
    y
}

/// A spanning forest of the 1-skeleton as (tree edges mask, one root per
/// component).
fn spanning_forest(complex: &Complex) -> (Vec<bool>, Vec<usize>) {
    grounded_forest(complex, None)
}

/// A spanning forest of the 1-skeleton. With `wall` (the boundary
/// subcomplex's vertices and edges), the wall's vertices are one ground
/// node: the search starts from all of them at once and never uses a wall
/// edge, so every interior vertex hangs on the ground or, in a component
/// without boundary, on a root; the roots are returned (wall vertices are
/// not).
fn grounded_forest(complex: &Complex, wall: Option<(&[bool], &[bool])>) -> (Vec<bool>, Vec<usize>) {
    let vertices = complex.cell_count(0);
    let edges = complex.cell_count(1);
    let mut around = vec![Vec::new(); vertices];
    for e in 0..edges {
        if wall.is_some_and(|(_, on_wall)| on_wall[e]) {
            continue;
        }
        let ends = complex.cell_vertices(1, e);
        if let [a, b] = ends {
            around[*a].push((e, *b));
            around[*b].push((e, *a));
        }
    }
    let mut seen = vec![false; vertices];
    let mut tree = vec![false; edges];
    let mut roots = Vec::new();
    let mut queue = VecDeque::new();
    if let Some((ground, _)) = wall {
        for v in (0..vertices).filter(|&v| ground[v]) {
            seen[v] = true;
            queue.push_back(v);
        }
    }
    let mut next = 0;
    loop {
        while let Some(v) = queue.pop_front() {
            for &(e, w) in &around[v] {
                if !seen[w] {
                    seen[w] = true;
                    tree[e] = true;
                    queue.push_back(w);
                }
            }
        }
        while next < vertices && seen[next] {
            next += 1;
        }
        if next == vertices {
            break;
        }
        roots.push(next);
        seen[next] = true;
        queue.push_back(next);
    }
    (tree, roots)
}

/// The boundary subcomplex's vertices and edges as masks.
fn wall_masks(complex: &Complex) -> (Vec<bool>, Vec<bool>) {
    let wall = complex.boundary_subcomplex();
    (
        (0..complex.cell_count(0))
            .map(|v| wall.contains(0, v))
            .collect(),
        (0..complex.cell_count(1))
            .map(|e| wall.contains(1, e))
            .collect(),
    )
}

/// The integer cocycles of a basis of H^k(K), every degree (see the module
/// docs for how, by degree).
pub fn cocycle_generators(complex: &Complex, k: usize) -> Result<Vec<Vec<f64>>, FormsError> {
    let n = complex.dim();
    if k > n {
        return Err(FormsError::Degree { degree: k, dim: n });
    }
    if k == 0 {
        let (tree, roots) = spanning_forest(complex);
        let mut component = vec![usize::MAX; complex.cell_count(0)];
        // Flood each root's tree.
        let mut around = vec![Vec::new(); complex.cell_count(0)];
        for (e, _) in tree.iter().enumerate().filter(|(_, t)| **t) {
            let ends = complex.cell_vertices(1, e);
            around[ends[0]].push(ends[1]);
            around[ends[1]].push(ends[0]);
        }
        for (i, &root) in roots.iter().enumerate() {
            let mut stack = vec![root];
            component[root] = i;
            while let Some(v) = stack.pop() {
                for &w in &around[v] {
                    if component[w] == usize::MAX {
                        component[w] = i;
                        stack.push(w);
                    }
                }
            }
        }
        return Ok((0..roots.len())
            .map(|i| {
                component
                    .iter()
                    .map(|&c| f64::from(u8::from(c == i)))
                    .collect()
            })
            .collect());
    }
    if k == n {
        return Ok(top_cycles(complex)
            .into_iter()
            .map(|z| {
                let first = z.iter().position(|&s| s != 0).unwrap_or(0);
                (0..z.len())
                    .map(|c| f64::from(u8::from(c == first)))
                    .collect()
            })
            .collect());
    }
    if k == 1 && n == 2 && is_surface(complex) {
        return tree_cotree(complex, false);
    }
    super::reduction::cocycles(complex, k)
}

/// Whether every edge of a 2-complex bounds one or two faces (what the
/// tree–cotree's dual graph needs).
fn is_surface(complex: &Complex) -> bool {
    let cofaces = complex.boundary(2);
    (0..complex.cell_count(1)).all(|e| {
        let count = cofaces.outer_view(e).map_or(0, |r| r.nnz());
        (1..=2).contains(&count)
    })
}

/// The top-cell cycles z (∂_n z = 0) of the closed orientable components:
/// ±1 on the component's cells (the complex orients them coherently, so
/// all +1), 0 elsewhere.
pub(super) fn top_cycles(complex: &Complex) -> Vec<Vec<i8>> {
    let n = complex.dim();
    let cells = complex.cell_count(n);
    let top = complex.boundary(n);
    let by_cell = complex.boundary_csc(n);
    let mut component = vec![usize::MAX; cells];
    let mut cycles = Vec::new();
    for start in 0..cells {
        if component[start] != usize::MAX {
            continue;
        }
        let id = cycles.len();
        let mut members = vec![start];
        component[start] = id;
        let mut stack = vec![start];
        while let Some(c) = stack.pop() {
            let Some(faces) = by_cell.outer_view(c) else {
                continue;
            };
            for &f in faces.indices() {
                if let Some(row) = top.outer_view(f) {
                    for &other in row.indices() {
                        if component[other] == usize::MAX {
                            component[other] = id;
                            members.push(other);
                            stack.push(other);
                        }
                    }
                }
            }
        }
        let mut z = vec![0i8; cells];
        for &c in &members {
            z[c] = 1;
        }
        // A cycle exactly when every face's signs cancel (integers).
        let boundary = multiply(top, &z.iter().map(|&s| f64::from(s)).collect::<Vec<_>>());
        cycles.push((z, boundary.iter().all(|&b| b == 0.0)));
    }
    cycles
        .into_iter()
        .filter_map(|(z, closed)| closed.then_some(z))
        .collect()
}

/// The tree–cotree cocycles of H¹ of a 2-complex, or with `relative` of
/// H¹(K, ∂K): then the wall's vertices are one ground node of the tree,
/// wall edges are neither tree, cotree nor generators (their value is 0),
/// and the cotree has no outside node (every face has its equation; the
/// root's holds because the others do and the wall edges are 0).
fn tree_cotree(complex: &Complex, relative: bool) -> Result<Vec<Vec<f64>>, FormsError> {
    let edges = complex.cell_count(1);
    let faces = complex.cell_count(2);
    let (ground, on_wall) = if relative {
        wall_masks(complex)
    } else {
        (Vec::new(), vec![false; edges])
    };
    let (tree, _) = if relative {
        grounded_forest(complex, Some((&ground, &on_wall)))
    } else {
        spanning_forest(complex)
    };
    let cofaces = complex.boundary(2);
    let by_face = complex.boundary_csc(2);
    let outside = faces;
    // The dual node on the far side of edge e from node u.
    let across = |e: usize, u: usize| -> Result<usize, FormsError> {
        let row = cofaces
            .outer_view(e)
            .map(|r| r.indices().to_vec())
            .unwrap_or_default();
        match row.as_slice() {
            [f] if u == outside => Ok(*f),
            [_] => Ok(outside),
            [f, g] => Ok(if *f == u { *g } else { *f }),
            _ => Err(FormsError::Cohomology(format!(
                "edge {e} bounds {} faces; tree–cotree needs a surface (one or two faces per edge)",
                row.len()
            ))),
        }
    };
    let boundary_edges: Vec<usize> = (0..edges)
        .filter(|&e| !relative && cofaces.outer_view(e).map_or(0, |r| r.nnz()) == 1)
        .collect();
    let mut seen = vec![false; faces + 1];
    let mut cotree = vec![false; edges];
    let mut parent = vec![usize::MAX; faces];
    let mut order = Vec::with_capacity(faces);
    let mut visit =
        |start: usize, seen: &mut [bool], cotree: &mut [bool]| -> Result<(), FormsError> {
            seen[start] = true;
            let mut queue = VecDeque::from([start]);
            while let Some(u) = queue.pop_front() {
                let around: Vec<usize> = if u == outside {
                    boundary_edges.clone()
                } else {
                    order.push(u);
                    by_face
                        .outer_view(u)
                        .map(|c| c.indices().to_vec())
                        .unwrap_or_default()
                };
                for e in around {
                    if tree[e] || cotree[e] || on_wall[e] {
                        continue;
                    }
                    let v = across(e, u)?;
                    if !seen[v] {
                        seen[v] = true;
                        cotree[e] = true;
                        if v != outside {
                            parent[v] = e;
                        }
                        queue.push_back(v);
                    }
                }
            }
            Ok(())
        };
    if !boundary_edges.is_empty() {
        visit(outside, &mut seen, &mut cotree)?;
    }
    for f in 0..faces {
        if !seen[f] {
            visit(f, &mut seen, &mut cotree)?;
        }
    }
    let generators: Vec<usize> = (0..edges)
        .filter(|&e| !tree[e] && !cotree[e] && !on_wall[e])
        .collect();
    let d1 = complex.coboundary(1);
    generators
        .iter()
        .map(|&g| {
            let mut c = vec![0.0; edges];
            c[g] = 1.0;
            for &f in order.iter().rev() {
                let p = parent[f];
                if p == usize::MAX {
                    continue;
                }
                let Some(column) = by_face.outer_view(f) else {
                    continue;
                };
                let mut sum = 0.0;
                let mut own = 0.0;
                for (e, &s) in column.iter() {
                    if e == p {
                        own = f64::from(s);
                    } else {
                        sum += f64::from(s) * c[e];
                    }
                }
                c[p] = -sum / own;
            }
            if multiply(d1, &c).iter().any(|&v| v != 0.0) {
                return Err(FormsError::Cohomology(
                    "the tree–cotree cochain is not closed: the surface is not orientable (its top cells cannot be oriented coherently)".into(),
                ));
            }
            Ok(c)
        })
        .collect()
}

impl Forms<'_> {
    /// ⟨a, b⟩ in the ⋆_k inner product, aᵀ ⋆_k b.
    pub fn inner(&self, k: usize, a: &[f64], b: &[f64]) -> Result<f64, FormsError> {
        let star = self.star(k)?;
        if a.len() != star.size() || b.len() != star.size() {
            return Err(FormsError::Field(format!(
                "{k}-cochains need {} values, got {} and {}",
                star.size(),
                a.len(),
                b.len()
            )));
        }
        Ok(star.apply(b).iter().zip(a).map(|(x, y)| x * y).sum())
    }

    /// The exact part of the k-cochain ω: d α with α the (k−1)-cochain of
    /// least ⋆-distance, solving d_{k−1}ᵀ ⋆_k d_{k−1} α = d_{k−1}ᵀ ⋆_k ω
    /// (the canonical operator A = d_{k−1}, Ω = ⋆_k). For k = 1 the kernel
    /// (constants per component) is removed by holding α = 0 at one vertex
    /// per component; for k ≥ 2 (the kernel: every closed (k−1)-cochain)
    /// by holding α = 0 off a set of (k−1)-cells whose columns of d_{k−1}
    /// are a basis of its image; k = 0 is refused. One [`ExactPart`] per
    /// cochain of `omegas` (one factorisation for all).
    pub fn exact_part(&self, k: usize, omegas: &[Vec<f64>]) -> Result<Vec<ExactPart>, FormsError> {
        self.exact_part_with(k, omegas, Boundary::Natural)
    }

    /// [`Forms::exact_part`] with a boundary condition: `Essential` holds α
    /// = 0 on the boundary's (k−1)-cells (the relative complex), so the
    /// exact part vanishes on the boundary's k-cells. For k = 1 it pins a
    /// vertex only in components without boundary; for k ≥ 2 it holds α = 0
    /// also off a set of interior (k−1)-cells whose columns of the
    /// restricted d_{k−1} are a basis of its image (the relative
    /// reduction), which makes the solve definite.
    pub fn exact_part_with(
        &self,
        k: usize,
        omegas: &[Vec<f64>],
        boundary: Boundary,
    ) -> Result<Vec<ExactPart>, FormsError> {
        self.check(k)?;
        let complex = self.complex;
        let pinned = match (k, boundary) {
            (0, _) => {
                return Err(FormsError::Cohomology(
                    "0-cochains have no exact part (there are no (−1)-cochains)".into(),
                ))
            }
            (1, Boundary::Natural) => {
                let mut pinned = vec![false; complex.cell_count(0)];
                spanning_forest(complex)
                    .1
                    .iter()
                    .for_each(|&r| pinned[r] = true);
                pinned
            }
            (1, Boundary::Essential) => {
                let (mut ground, on_wall) = wall_masks(complex);
                let roots = grounded_forest(complex, Some((&ground, &on_wall))).1;
                roots.iter().for_each(|&r| ground[r] = true);
                ground
            }
            // Degree ≥ 2: α lives on (k−1)-cells and d_{k−1} has a large
            // kernel (all closed (k−1)-forms); holding α = 0 off a set of
            // cells whose columns are a basis of im d_{k−1} removes it
            // without restricting the exact part.
            (_, Boundary::Natural) => super::reduction::exact_gauge(complex, k)?
                .into_iter()
                .map(|independent| !independent)
                .collect(),
            // The same in the relative complex: α is 0 on the boundary's
            // (k−1)-cells and off a basis of im δ^{k−1}_rel.
            (_, Boundary::Essential) => super::relative::relative_gauge(complex, k)?,
        };
        if k >= 2 && self.star.is_diagonal() {
            // A zero weight (a dual edge of length 0, e.g. inside a cube of
            // Kuhn tetrahedra with the circumcentric dual) leaves the gauged
            // operator singular: name the star rather than the solve. With
            // essential conditions only the interior k-cells' weights enter
            // (d α vanishes on the boundary's k-cells).
            let interior: Vec<usize>;
            let cells = match boundary {
                Boundary::Natural => None,
                Boundary::Essential => {
                    let wall = super::relative::wall_mask(complex, k);
                    interior = (0..wall.len()).filter(|&c| !wall[c]).collect();
                    Some(interior.as_slice())
                }
            };
            self.positive_diagonal(k, cells, "the harmonic projection dᵀ⋆d α = dᵀ⋆c")?;
        }
        let split = FixedSplit::from_mask(pinned);
        let lower = complex.coboundary(k - 1);
        let restricted = split.restrict_columns(lower);
        let star = self.star(k)?;
        let operator = Canonical::new(restricted.clone(), star.clone())?;
        let load = Canonical::coupling(restricted, star, CsMat::<i8>::eye(lower.rows()))?;
        let matrix = operator.assemble();
        let factor = if split.free().is_empty() {
            None
        } else {
            Some(
                DirectSolver::analyze(matrix.as_ref(), Factorization::Llt)?
                    .factorize(matrix.as_ref())?,
            )
        };
        omegas
            .iter()
            .map(|omega| {
                if omega.len() != lower.rows() {
                    return Err(FormsError::Field(format!(
                        "a {k}-cochain needs {} values, got {}",
                        lower.rows(),
                        omega.len()
                    )));
                }
                let mut free = match &factor {
                    Some(factor) => factor.solve(&load.apply(omega))?,
                    None => Vec::new(),
                };
                if let Some(factor) = &factor {
                    // One step of iterative refinement on the residual
                    // dᵀ⋆(ω − dα) of the free cells: the equations of the
                    // held cells are (exactly) combinations of these, so
                    // their residual is a sum of the free ones and grows
                    // with the mesh unless those are at rounding level.
                    let exact = multiply(lower, &split.lift(&free, &[]));
                    let rest: Vec<f64> = omega.iter().zip(&exact).map(|(w, e)| w - e).collect();
                    let correction = factor.solve(&load.apply(&rest))?;
                    free.iter_mut().zip(correction).for_each(|(a, c)| *a += c);
                }
                let alpha = split.lift(&free, &[]);
                let exact = multiply(lower, &alpha);
                Ok(ExactPart {
                    potential: alpha,
                    exact,
                })
            })
            .collect()
    }

    /// A basis of the harmonic k-forms (absolute conditions), one per
    /// cohomology generator ([`cocycle_generators`]), with the closedness
    /// and co-closedness residuals of each.
    pub fn harmonic_basis(&self, k: usize) -> Result<HarmonicBasis, FormsError> {
        self.harmonic_basis_with(k, Boundary::Natural)
    }

    /// [`Forms::harmonic_basis`] with a boundary condition: `Essential`
    /// (relative: the forms vanish on the boundary subcomplex's k-cells)
    /// for every degree, one per class of Hᵏ(K, ∂K): the relative
    /// tree–cotree cocycles for k = 1 on a surface or planar 2-complex,
    /// the relative integer reduction
    /// ([`super::relative_cocycle_generators`]) otherwise, each made
    /// harmonic by h = z − dα with α a relative (k−1)-cochain (0 on ∂K).
    /// The count must equal the relative Betti number β_k(K, ∂K) (from
    /// ranks over Q of the restricted coboundaries, a separate
    /// computation), and the co-closedness residual is measured at the
    /// interior (k−1)-cells, where the equations dᵀ⋆h = 0 hold.
    ///
    /// ```
    /// use hasse_complex::{dual::DualKind, generate::hollow_box};
    /// use hasse_solver::physics::forms::{Boundary, Forms, Star};
    /// // Box with a cavity: β(K, ∂K) = (0, 1, 0, 1), Lefschetz dual to β = (1, 0, 1, 0).
    /// let k = hollow_box(3, [1, 2])?;
    /// let forms = Forms::new(&k, Star::Diagonal(DualKind::Barycentric));
    /// for (degree, count) in [(0, 0), (1, 1), (2, 0), (3, 1)] {
    ///     let basis = forms.harmonic_basis_with(degree, Boundary::Essential)?;
    ///     assert_eq!((basis.forms.len(), basis.betti), (count, count));
    ///     assert!(basis.closed.iter().chain(&basis.coclosed).all(|r| *r < 1e-12));
    /// }
    /// # Ok::<(), Box<dyn std::error::Error>>(())
    /// ```
    pub fn harmonic_basis_with(
        &self,
        k: usize,
        boundary: Boundary,
    ) -> Result<HarmonicBasis, FormsError> {
        self.check(k)?;
        let complex = self.complex;
        let n = complex.dim();
        let relative = boundary == Boundary::Essential;
        let generators = if !relative {
            cocycle_generators(complex, k)?
        } else if k == 1 && n == 2 && is_surface(complex) {
            tree_cotree(complex, true)?
        } else {
            super::relative::relative_cocycle_generators(complex, k)?
        };
        let forms: Vec<Vec<f64>> = if k == 0 {
            // No (−1)-cochains: a closed 0-cochain is its own harmonic form.
            generators.clone()
        } else if k == n && !relative {
            // h = ⋆⁻¹ z / ⟨z, ⋆⁻¹ z⟩: ⋆_n is SPD (diagonal for every star
            // here, one block per cell), solved as the operator Iᵀ ⋆ I.
            let mass =
                Canonical::new(CsMat::<i8>::eye(complex.cell_count(n)), self.star(n)?)?.assemble();
            let factor = DirectSolver::analyze(mass.as_ref(), Factorization::Llt)?
                .factorize(mass.as_ref())?;
            top_cycles(complex)
                .iter()
                .map(|z| -> Result<Vec<f64>, FormsError> {
                    let z: Vec<f64> = z.iter().map(|&s| f64::from(s)).collect();
                    let h = factor.solve(&z)?;
                    let period: f64 = h.iter().zip(&z).map(|(a, b)| a * b).sum();
                    Ok(h.iter().map(|v| v / period).collect())
                })
                .collect::<Result<_, _>>()?
        } else {
            self.exact_part_with(k, &generators, boundary)?
                .into_iter()
                .zip(&generators)
                .map(|(part, c)| c.iter().zip(&part.exact).map(|(a, b)| a - b).collect())
                .collect()
        };
        let d = self.d(k)?;
        let star = self.star(k)?;
        // Only interior (k−1)-cells carry the co-closedness equation under
        // essential conditions.
        let lower_wall = if relative && k > 0 {
            super::relative::wall_mask(complex, k - 1)
        } else {
            Vec::new()
        };
        let mut closed = Vec::new();
        let mut coclosed = Vec::new();
        for h in &forms {
            let scale = max_abs(h).max(f64::MIN_POSITIVE);
            closed.push(max_abs(&multiply(&d, h)) / scale);
            coclosed.push(if k == 0 {
                0.0
            } else {
                let weighted = star.apply(h);
                let mut divergence = multiply_transpose(&*self.d(k - 1)?, &weighted);
                divergence
                    .iter_mut()
                    .zip(&lower_wall)
                    .filter(|(_, wall)| **wall)
                    .for_each(|(v, _)| *v = 0.0);
                max_abs(&divergence) / max_abs(&weighted).max(f64::MIN_POSITIVE)
            });
        }
        let betti = if relative {
            super::laplacian::relative_betti_numbers(complex)[k]
        } else {
            complex.betti_numbers().get(k).copied().unwrap_or(0)
        };
        Ok(HarmonicBasis {
            degree: k,
            generators,
            forms,
            betti,
            closed,
            coclosed,
        })
    }
}
