//! Maxwell resonant cavity: the electric field on 1-cochains with perfectly
//! conducting walls, the generalised eigenproblem K e = ω² M e.
//!
//! Both operators are canonical forms over the interior edges (tangential
//! E = 0 on the walls eliminates every boundary edge):
//!
//! ```text
//!     K = δ₁ᵀ ⋆₂ δ₁     (curl-curl; δ₁ = ∂₂ᵀ, ⋆₂ = |⋆f| / |f|, in 2D 1/|f|)
//!     M = Eᵀ ⋆₁ E       (E selects the interior edges; ⋆₁ = |⋆e| / |e|,
//!                        or the Whitney/Nédélec mass on simplices)
//! ```
//!
//! K vanishes on discrete gradients δ₀φ of the interior-vertex functions φ
//! (δ₁δ₀ = 0), an exact null space of dimension = number of interior
//! vertices, far larger than the handful of physical modes wanted. It is
//! deflated rather than computed: every Krylov vector is M-orthogonally
//! projected off range(G), G = δ₀ restricted to interior edges and
//! vertices, with one LLᵀ of the small Gram matrix Gᵀ M G (itself the
//! canonical form (δ₀)ᵀ ⋆₁ δ₀ with Dirichlet walls). That LLᵀ succeeding
//! is the check that the gradients are independent, i.e. that the null
//! space has exactly that dimension. The physical modes then come from
//! [`crate::la::eigen::smallest`] with a negative shift (K − σM positive
//! definite, faer LLᵀ).
//!
//! ```
//! use hasse_complex::{dual::DualKind, generate::rectangle};
//! use hasse_solver::physics::maxwell::{Cavity, Mass};
//! use std::f64::consts::PI;
//! let k = rectangle(8, 8, [0.0, PI], [0.0, PI]).unwrap();
//! let cavity = Cavity::new(&k, DualKind::Barycentric, Mass::Hodge).unwrap();
//! let modes = cavity.modes(3, &cavity.default_options()).unwrap();
//! // Exact ω² on [0, π]²: m² + n² = 1, 1, 2; the grid gives (4/h²) Σ sin²(m h/2).
//! let h = PI / 8.0;
//! let discrete = |m: f64| 4.0 / (h * h) * (m * h / 2.0).sin().powi(2);
//! for (got, want) in modes.eigenvalues.iter().zip([discrete(1.0), discrete(1.0), 2.0 * discrete(1.0)]) {
//!     assert!((got - want).abs() < 1e-8);
//! }
//! assert_eq!(cavity.gradient_count(), 49);
//! ```

use crate::la::direct::{DirectSolver, Factor, Factorization, SolveError};
use crate::la::eigen::{self, multiply, EigenError, Options};
use crate::la::fixed::FixedSplit;
use crate::metric::{dec, isotropic, MetricError};
use crate::operator::{BlockMetric, Canonical, CanonicalError};
use faer::sparse::{SparseColMat, SparseColMatRef};
use hasse_complex::{Complex, ComplexError, DualKind};
use sprs::CsMat;

/// Why a cavity could not be set up or solved.
///
/// ```
/// use hasse_complex::{dual::DualKind, generate::interval};
/// use hasse_solver::physics::maxwell::{Cavity, Mass, MaxwellError};
/// let line = interval(4, 0.0, 1.0).unwrap();
/// let err = Cavity::new(&line, DualKind::Barycentric, Mass::Hodge).err().unwrap();
/// assert_eq!(err, MaxwellError::Dimension { dim: 1 });
/// ```
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum MaxwellError {
    /// The complex is not 2- or 3-dimensional.
    #[error("a Maxwell cavity needs a 2- or 3-dimensional complex (curl lives on edges and faces); this one is {dim}-dimensional")]
    Dimension {
        /// Its dimension n.
        dim: usize,
    },
    /// A closed surface or a periodic complex: there is no wall to hold
    /// the tangential field at zero.
    #[error("the complex has no boundary: a cavity needs conducting walls (boundary (n−1)-cells)")]
    NoWall,
    /// The mesh is so coarse that every edge touches the wall.
    #[error("every edge lies on the wall, so no field is left (refine the mesh)")]
    NoInteriorEdges,
    /// A Hodge star that enters K or M is zero or negative (a
    /// circumcentric dual on a mesh that is not well centred).
    #[error("⋆{p} of {p}-cell {cell} is {value:e} ≤ 0: with a vanishing or negative star the {what} is not definite and spurious modes appear. Use the barycentric dual, a well-centred mesh{hint}")]
    NonPositiveStar {
        /// Degree of the star: 1 (the mass) or 2 (the curl-curl).
        p: usize,
        /// The p-cell.
        cell: usize,
        /// Its star, ≤ 0 or NaN.
        value: f64,
        /// The operator it would spoil, in words.
        what: &'static str,
        /// A further remedy for the message (the Whitney mass), or empty.
        hint: &'static str,
    },
    /// The LLᵀ of the gradient Gram matrix Gᵀ M G failed, so the null
    /// space of K cannot be deflated.
    #[error("the gradients of the interior vertices are not independent (Gᵀ M G is not positive definite): {0}")]
    DependentGradients(SolveError),
    /// The complex could not give a dual or a star.
    #[error(transparent)]
    Complex(#[from] ComplexError),
    /// The Whitney mass refused the mesh (cells that are not simplices).
    #[error(transparent)]
    Metric(#[from] MetricError),
    /// A and Ω of K or M do not fit together.
    #[error(transparent)]
    Canonical(#[from] CanonicalError),
    /// The eigensolver failed (shift, factorisation or convergence).
    #[error(transparent)]
    Eigen(#[from] EigenError),
}

/// Which mass matrix M the 1-cochains get.
///
/// ```
/// use hasse_complex::{dual::DualKind, generate::{kuhn, uniform_axis}};
/// use hasse_solver::physics::maxwell::{Cavity, Mass, MaxwellError};
/// use std::f64::consts::PI;
/// // Right triangles: the circumcentre of each lies on its diagonal, whose
/// // circumcentric dual edge then has length 0.
/// let x = uniform_axis(8, 0.0, PI).unwrap();
/// let k = kuhn(&[x.clone(), x]).unwrap();
/// let hodge = Cavity::new(&k, DualKind::Circumcentric, Mass::Hodge);
/// assert!(matches!(hodge, Err(MaxwellError::NonPositiveStar { p: 1, .. })));
/// // The Whitney mass needs no dual: lowest ω² on [0, π]² is 1.
/// let cavity = Cavity::new(&k, DualKind::Circumcentric, Mass::Whitney).unwrap();
/// let modes = cavity.modes(1, &cavity.default_options()).unwrap();
/// assert!((modes.eigenvalues[0] - 1.0).abs() < 0.05);
/// ```
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Mass {
    /// The diagonal DEC Hodge star ⋆₁ = |⋆e| / |e| of the chosen dual.
    Hodge,
    /// The Whitney (Galerkin) star ∫ W_e · W_f, simplices only: with it,
    /// in 2D, K and M are the lowest-order Nédélec (edge element) matrices.
    Whitney,
}

impl Mass {
    /// Every mass, in the order help texts list them.
    pub const ALL: [Mass; 2] = [Mass::Hodge, Mass::Whitney];

    /// The name case files use (`problem.mass`).
    ///
    /// ```
    /// use hasse_solver::physics::maxwell::Mass;
    /// assert_eq!(Mass::ALL.map(|m| m.name()), ["hodge", "whitney"]);
    /// ```
    pub fn name(&self) -> &'static str {
        match self {
            Mass::Hodge => "hodge",
            Mass::Whitney => "whitney",
        }
    }
}

/// The cavity operators on one complex, ready to give modes.
///
/// ```
/// use hasse_complex::{dual::DualKind, generate::box3};
/// use hasse_solver::physics::maxwell::{Cavity, Mass};
/// let k = box3(2, 2, 2, [0.0, 1.0], [0.0, 1.0], [0.0, 1.0]).unwrap();
/// let cavity = Cavity::new(&k, DualKind::Barycentric, Mass::Hodge).unwrap();
/// // 54 edges, 48 on the walls; one interior vertex.
/// assert_eq!((cavity.unknowns(), cavity.gradient_count()), (6, 1));
/// assert_eq!(cavity.physical_count(), 5);
/// ```
pub struct Cavity {
    /// Interior edges free, wall edges fixed at zero.
    edges: FixedSplit,
    /// Interior vertices free, wall vertices fixed at zero.
    vertices: FixedSplit,
    stiffness: SparseColMat<usize, f64>,
    mass: SparseColMat<usize, f64>,
    /// G = δ₀ on interior edges × interior vertices, as f64 for products.
    gradient: SparseColMat<usize, f64>,
    /// LLᵀ of Gᵀ M G (absent when there is no interior vertex).
    gram: Option<Factor>,
    diameter: f64,
    /// β_{n−1} of the cavity: the dimension of its static fields.
    static_count: usize,
}

/// Resonant modes, ascending in ω².
///
/// ```
/// use hasse_complex::{dual::DualKind, generate::box3};
/// use hasse_solver::physics::maxwell::{Cavity, Mass};
/// use std::f64::consts::PI;
/// let k = box3(4, 4, 4, [0.0, PI], [0.0, PI], [0.0, PI]).unwrap();
/// let cavity = Cavity::new(&k, DualKind::Barycentric, Mass::Hodge).unwrap();
/// let modes = cavity.modes(3, &cavity.default_options()).unwrap();
/// // The lowest cube mode ω² = 2 is threefold; on 4 cells per side it is 2 (4/h²) sin²(h/2).
/// let h = PI / 4.0;
/// let want = (8.0 / (h * h) * (h / 2.0).sin().powi(2)).sqrt();
/// assert!(modes.frequencies().iter().all(|w| (w - want).abs() < 1e-8));
/// ```
#[derive(Clone, Debug, PartialEq)]
pub struct Modes {
    /// ω² (for a unit wave speed), ascending.
    pub eigenvalues: Vec<f64>,
    /// E on the interior edges (see [`Cavity::extend`]), M-orthonormal.
    pub fields: Vec<Vec<f64>>,
    /// Relative residuals ‖Ke − ω²Me‖ / (‖Ke‖ + ω²‖Me‖).
    pub residuals: Vec<f64>,
    /// The static fields found (ω² = 0 to rounding, M-orthonormal), on the
    /// interior edges; [`Cavity::static_count`] says how many there are.
    pub static_fields: Vec<Vec<f64>>,
    /// Krylov basis size used.
    pub basis: usize,
    /// Solves with K − σM used.
    pub solves: usize,
    /// The shift σ used.
    pub shift: f64,
}

impl Modes {
    /// The angular frequencies ω = √(ω²).
    pub fn frequencies(&self) -> Vec<f64> {
        self.eigenvalues.iter().map(|l| l.max(0.0).sqrt()).collect()
    }
}

impl Cavity {
    /// Assemble K and M on the interior edges of `complex` with stars of the
    /// `dual` kind (barycentric for grids of quads/hexes, either for
    /// simplices) and the chosen mass, and factor the gradient Gram matrix.
    ///
    /// Errors: dimension other than 2 or 3; no wall; no interior edge; a
    /// star ≤ 0 where it enters K or M (e.g. the circumcentric ⋆₁ of the
    /// diagonals of a right-angled Kuhn triangulation is 0); a Whitney
    /// mass on cells that are not simplices.
    pub fn new(complex: &Complex, dual: DualKind, mass: Mass) -> Result<Self, MaxwellError> {
        let n = complex.dim();
        if !(2..=3).contains(&n) {
            return Err(MaxwellError::Dimension { dim: n });
        }
        let wall = complex.boundary_subcomplex();
        if wall.cells(n - 1).is_empty() {
            return Err(MaxwellError::NoWall);
        }
        // Tangential E vanishes on the walls: wall edges (and, for the
        // gradients, wall vertices) are fixed at zero.
        let wall = &wall;
        let on_wall = |p: usize| (0..complex.cell_count(p)).map(move |i| wall.contains(p, i));
        let edges = FixedSplit::from_mask(on_wall(1));
        let vertices = FixedSplit::from_mask(on_wall(0));
        if edges.free().is_empty() {
            return Err(MaxwellError::NoInteriorEdges);
        }

        // K = (δ₁ E)ᵀ ⋆₂ (δ₁ E): faces × interior edges.
        let curl = edges.restrict_columns(complex.coboundary(1));
        let star2 = complex.hodge_star(dual, 2)?;
        for (f, row) in curl.outer_iterator().enumerate() {
            // Faces made only of wall edges do not enter K.
            if row.nnz() > 0 && star2[f].partial_cmp(&0.0) != Some(std::cmp::Ordering::Greater) {
                return Err(MaxwellError::NonPositiveStar {
                    p: 2,
                    cell: f,
                    value: star2[f],
                    what: "curl-curl K on the gradient complement",
                    hint: "",
                });
            }
        }
        let stiffness = Canonical::new(curl, BlockMetric::diagonal(&star2))?.assemble();

        // M = Eᵀ Ω E over all edges, Ω = ⋆₁ or the Whitney star.
        let metric = match mass {
            Mass::Hodge => {
                let star1 = complex.hodge_star(dual, 1)?;
                if let Some(&e) = edges
                    .free()
                    .iter()
                    .find(|&&e| star1[e].is_nan() || star1[e] <= 0.0)
                {
                    return Err(MaxwellError::NonPositiveStar {
                        p: 1,
                        cell: e,
                        value: star1[e],
                        what: "mass M",
                        hint: " or the Whitney mass",
                    });
                }
                BlockMetric::diagonal(&star1)
            }
            Mass::Whitney => {
                let tops = complex.cell_count(n);
                dec::whitney_metric(complex, &vec![isotropic(1.0); tops])?
            }
        };
        let mass_matrix = Canonical::new(edges.selection(), metric.clone())?.assemble();

        // Gᵀ M G = (δ₀ restricted to interior vertices)ᵀ Ω (…): a wall edge
        // has both ends on the wall, so its rows of δ₀[:, interior] vanish
        // and the product only sees interior edges.
        let grad_all = vertices.restrict_columns(complex.coboundary(0));
        let gram = if vertices.free().is_empty() {
            None
        } else {
            let gram = Canonical::new(grad_all.clone(), metric)?.assemble();
            let factor = DirectSolver::analyze(gram.as_ref(), Factorization::Llt)
                .and_then(|s| s.factorize(gram.as_ref()))
                .map_err(MaxwellError::DependentGradients)?;
            Some(factor)
        };
        let gradient = to_faer(&edges.restrict_rows(&grad_all));

        let dim = complex.embedding_dim();
        let coords = complex.vertices().as_slice();
        let diameter = (0..dim)
            .map(|a| {
                let (lo, hi) = coords
                    .iter()
                    .skip(a)
                    .step_by(dim)
                    .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), &x| {
                        (l.min(x), h.max(x))
                    });
                (hi - lo).powi(2)
            })
            .sum::<f64>()
            .sqrt();
        // Static fields: curl-free, divergence-free fields with zero
        // tangential trace, the relative cohomology H¹(Ω, ∂Ω), which by
        // Lefschetz duality has the dimension of H_{n−1}(Ω): one per hole
        // of a 2D cavity, one per enclosed void of a 3D one. The mesh is
        // orientable and embedded, so Z₂ gives the rational Betti numbers.
        let betti = complex.betti_numbers_over(hasse_complex::Field::Z2);
        let static_count = betti.get(complex.dim() - 1).copied().unwrap_or(0);
        Ok(Self {
            edges,
            vertices,
            stiffness,
            mass: mass_matrix,
            gradient,
            gram,
            diameter,
            static_count,
        })
    }

    /// Number of unknowns: the interior edges.
    pub fn unknowns(&self) -> usize {
        self.edges.free().len()
    }

    /// Dimension of the gradient null space of K: the interior vertices.
    pub fn gradient_count(&self) -> usize {
        self.vertices.free().len()
    }

    /// The most physical modes there are: unknowns − gradients (the
    /// static fields included).
    pub fn physical_count(&self) -> usize {
        self.unknowns() - self.gradient_count()
    }

    /// The number of static fields (ω² = 0 after the gradients are
    /// removed): β_{n−1} of the cavity, its holes in 2D and enclosed voids
    /// in 3D.
    pub fn static_count(&self) -> usize {
        self.static_count
    }

    /// The interior edges, in unknown order.
    pub fn interior_edges(&self) -> &[usize] {
        self.edges.free()
    }

    /// The curl-curl matrix K on the interior edges.
    pub fn stiffness(&self) -> SparseColMatRef<'_, usize, f64> {
        self.stiffness.as_ref()
    }

    /// The mass matrix M on the interior edges.
    pub fn mass(&self) -> SparseColMatRef<'_, usize, f64> {
        self.mass.as_ref()
    }

    /// δ₀φ on the interior edges for φ on the interior vertices.
    pub fn gradient(&self, phi: &[f64]) -> Vec<f64> {
        multiply(self.gradient.as_ref(), phi)
    }

    /// Remove the gradient part of e: e − G (GᵀMG)⁻¹ GᵀM e, the
    /// M-orthogonal projection onto the complement of the null space.
    pub fn remove_gradients(&self, e: &mut [f64]) -> Result<(), SolveError> {
        let Some(gram) = &self.gram else {
            return Ok(());
        };
        let me = multiply(self.mass.as_ref(), e);
        let g = self.gradient.as_ref();
        let rhs: Vec<f64> = (0..g.ncols())
            .map(|j| {
                let range = g.col_range(j);
                g.row_idx()[range.clone()]
                    .iter()
                    .zip(&g.val()[range])
                    .map(|(&i, &v)| v * me[i])
                    .sum()
            })
            .collect();
        let phi = gram.solve(&rhs)?;
        for (x, y) in e.iter_mut().zip(self.gradient(&phi)) {
            *x -= y;
        }
        Ok(())
    }

    /// A field on the interior edges as a 1-cochain on every edge (zero
    /// tangential E on the walls).
    pub fn extend(&self, e: &[f64]) -> Vec<f64> {
        self.edges.lift(e, &[])
    }

    /// Default eigensolver settings with σ = −½ (π/D)², D the bounding-box
    /// diagonal: negative, so K − σM is positive definite, and of the
    /// order of the lowest cavity eigenvalue (≈ (π/D)² up to a small
    /// factor for convex cavities) so that the wanted modes dominate.
    pub fn default_options(&self) -> Options {
        Options {
            shift: -0.5 * (std::f64::consts::PI / self.diameter).powi(2),
            ..Options::default()
        }
    }

    /// The `count` smallest nonzero ω² and their fields, with the gradient
    /// null space deflated, after the static fields (ω² = 0, as many as
    /// [`static_count`](Self::static_count)). Errors: `count` = 0 or
    /// above [`physical_count`](Self::physical_count) less the static
    /// fields, non-convergence, and factorisation failures, as
    /// [`MaxwellError::Eigen`].
    pub fn modes(&self, count: usize, options: &Options) -> Result<Modes, MaxwellError> {
        let project = |v: &mut [f64]| self.remove_gradients(v);
        let pairs = eigen::smallest(
            self.stiffness.as_ref(),
            self.mass.as_ref(),
            count + self.static_count,
            Some(&project),
            self.physical_count(),
            options,
        )?;
        let zeros = pairs.zeros;
        let mut values = pairs.values;
        let mut fields = pairs.vectors;
        let mut residuals = pairs.residuals;
        let static_fields: Vec<Vec<f64>> = fields.drain(..zeros).collect();
        values.drain(..zeros);
        residuals.drain(..zeros);
        values.truncate(count);
        fields.truncate(count);
        residuals.truncate(count);
        Ok(Modes {
            eigenvalues: values,
            fields,
            residuals,
            static_fields,
            basis: pairs.basis,
            solves: pairs.solves,
            shift: options.shift,
        })
    }
}

fn to_faer(a: &CsMat<i8>) -> SparseColMat<usize, f64> {
    let entries: Vec<_> = a
        .iter()
        .map(|(&v, (i, j))| faer::sparse::Triplet::new(i, j, f64::from(v)))
        .collect();
    SparseColMat::try_new_from_triplets(a.rows(), a.cols(), &entries)
        .expect("indices come from a matrix of this size")
}
