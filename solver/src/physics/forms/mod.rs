//! Discrete differential forms on a cell complex: for every degree k the
//! exterior derivative d_k = δᵏ (exact integers), a Hodge star ⋆_k, the
//! codifferential, and the Hodge Laplacian Δ_k (see [`laplacian`]).
//!
//! | object | what | how |
//! |---|---|---|
//! | [`Forms::d`] | d_k: k-cochains → (k+1)-cochains | δᵏ = ∂_{k+1}ᵀ, i8 |
//! | [`Forms::star`] | ⋆_k, an Ω over the k-cells | [`Star`]: circumcentric or barycentric diagonal \|⋆σ\|/\|σ\|, or the Whitney mass M_k |
//! | [`Forms::codifferential`] | δ_k = ⋆_{k−1}⁻¹ d_{k−1}ᵀ ⋆_k (diagonal stars) | canonical coupling d_{k−1}ᵀ ⋆_k, scaled by 1/⋆_{k−1} |
//! | [`Forms::hodge_laplacian`] | Δ_k as the pencil (K, M) | [`laplacian::HodgeLaplacian`] |
//! | [`Forms::harmonic_basis`] | harmonic k-forms, one per cohomology class | integer cocycles ([`cohomology`]) made harmonic by one Poisson solve |
//! | [`Forms::harmonic_basis_with`] | the same for Hᵏ(K, ∂K) (essential conditions) | relative integer cocycles ([`relative`]), α = 0 on the boundary |
//! | [`Forms::poisson`] | Δ_k u = f, both parts of the Laplacian, natural or essential conditions | K u = M f on the pencil above, one Lagrange multiplier per harmonic form ([`poisson`]) |
//! | [`Forms::decompose`] | ω = dα + δβ + h for k-cochains, any degree and dimension | a Poisson solve for dα; ⋆⁻¹ eliminated or a mixed saddle-point block system for δβ ([`decomposition`]) |
//! | [`whitney_map::de_rham`], [`whitney_map::interpolate`] | fields ↔ cochains | quadrature over k-cells; Whitney forms |
//!
//! Every matrix is a canonical operator Aᵀ Ω B with A, B exact incidence
//! matrices (d or a selection of cells) and Ω a star; nothing here is
//! assembled by other means.
//!
//! ```
//! use hasse_complex::{dual::DualKind, generate::sphere};
//! use hasse_solver::physics::forms::{Forms, Star};
//! let k = sphere(1.0, 1).unwrap();
//! let forms = Forms::new(&k, Star::Diagonal(DualKind::Circumcentric));
//! // d∘d = 0 exactly, in integers.
//! let dd = &*forms.d(1).unwrap() * &*forms.d(0).unwrap();
//! assert!(dd.data().iter().all(|&x| x == 0));
//! // Σ ⋆₀ is the area of the (polyhedral) sphere, a bit below 4π.
//! let area: f64 = forms.star(0).unwrap().diagonal_weights().unwrap().iter().sum();
//! assert!(area < 4.0 * std::f64::consts::PI && area > 11.5);
//! ```

pub mod cohomology;
pub mod decomposition;
pub mod laplacian;
pub mod poisson;
mod reduction;
pub mod relative;
pub mod whitney_map;

pub use cohomology::{cocycle_generators, ExactPart, HarmonicBasis};
pub use decomposition::Decomposition;
pub use laplacian::{Boundary, FormModes, HodgeLaplacian};
pub use poisson::FormPoisson;
pub use relative::relative_cocycle_generators;

use crate::la::direct::SolveError;
use crate::la::eigen::EigenError;
use crate::metric::{whitney, MetricError};
use crate::operator::block::BlockError;
use crate::operator::{BlockMetric, Canonical, CanonicalError};
use faer::sparse::{SparseColMat, Triplet};
use hasse_complex::{Complex, ComplexError, DualKind};
use sprs::CsMat;
use std::sync::Arc;

/// Which Hodge star the forms get.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Star {
    /// The diagonal DEC star |⋆σ|/|σ| of the given dual.
    Diagonal(DualKind),
    /// The Whitney (Galerkin) mass ∫ W_σ · W_τ, simplices only.
    Whitney,
    /// Diagonal stars given by the user, one value per k-cell for every
    /// degree ([`Forms::with_stars`]): a metric hasse cannot compute (an
    /// anisotropic or curved one, another code's dual).
    Supplied,
}

impl Star {
    /// Whether ⋆_k is diagonal (so ⋆⁻¹ is too).
    pub fn is_diagonal(&self) -> bool {
        matches!(self, Star::Diagonal(_) | Star::Supplied)
    }
}

/// Why a form operator could not be built or solved.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum FormsError {
    /// The degree is above the dimension of the complex.
    #[error(
        "degree {degree} is out of range: the complex has dimension {dim}, so 0 ≤ degree ≤ {dim}"
    )]
    Degree {
        /// The degree asked for.
        degree: usize,
        /// The dimension of the complex.
        dim: usize,
    },
    /// A diagonal star is zero, negative or not finite where the operator
    /// divides by it or needs it positive.
    #[error("the Hodge star ⋆_{k} of {k}-cell {cell} is {value:e}, but {what} needs it > 0 (a non-well-centred or degenerate mesh for the circumcentric dual: use the barycentric dual or the Whitney star)")]
    NonPositiveStar {
        /// The degree of the star.
        k: usize,
        /// The cell.
        cell: usize,
        /// Its value.
        value: f64,
        /// The operator it would spoil.
        what: &'static str,
    },
    /// The operator needs the diagonal star (e.g. the codifferential as a
    /// sparse matrix).
    #[error("{0} needs a diagonal Hodge star")]
    NeedsDiagonal(&'static str),
    /// A field or cochain does not fit the degree (a vector field for a
    /// function, a cochain of the wrong length, a degree without proxy).
    #[error("{0}")]
    Field(String),
    /// A cell the operation needs to be a simplex is not one.
    #[error("{dim}-cell {cell} has {vertices} vertices, but Whitney forms and the quadrature of the de Rham map need simplices here")]
    NotSimplex {
        /// Its dimension.
        dim: usize,
        /// The cell.
        cell: usize,
        /// Its vertex count.
        vertices: usize,
    },
    /// Cohomology generators of this degree are not computed, or the
    /// complex does not allow them (non-manifold, non-orientable).
    #[error("{0}")]
    Cohomology(String),
    /// The complex could not give a dual or a star.
    #[error(transparent)]
    Complex(#[from] ComplexError),
    /// The Whitney star refused the mesh.
    #[error(transparent)]
    Metric(#[from] MetricError),
    /// A and Ω do not fit together.
    #[error(transparent)]
    Canonical(#[from] CanonicalError),
    /// The block system could not be built.
    #[error(transparent)]
    Block(#[from] BlockError),
    /// A factorisation failed.
    #[error(transparent)]
    Solve(#[from] SolveError),
    /// The eigensolver failed.
    #[error(transparent)]
    Eigen(#[from] EigenError),
    /// A matrix built here did not fit its own shape (a bug).
    #[error("internal: {0}")]
    Internal(String),
}

/// The k-forms of one complex with one choice of star.
#[derive(Clone, Copy, Debug)]
pub struct Forms<'a> {
    complex: &'a Complex,
    star: Star,
    /// ⋆_k per degree for [`Star::Supplied`] (empty otherwise).
    supplied: &'a [Vec<f64>],
}

impl<'a> Forms<'a> {
    /// Forms on `complex` with the star `star` ([`Star::Supplied`] needs
    /// [`Forms::with_stars`], which gives the values).
    pub fn new(complex: &'a Complex, star: Star) -> Self {
        Self {
            complex,
            star,
            supplied: &[],
        }
    }

    /// Forms on `complex` with the diagonal stars `stars[k]` (one value per
    /// k-cell, k = 0 … n), checked for their lengths and finite values;
    /// where an operator divides by a star or needs it as a mass it is
    /// checked > 0 there, as the computed stars are.
    ///
    /// ```
    /// use hasse_complex::generate::rectangle;
    /// use hasse_solver::physics::forms::{Boundary, Forms};
    /// # fn main() -> Result<(), Box<dyn std::error::Error>> {
    /// // One square cell as the square [0, 2] × [0, 1] would measure it:
    /// // ⋆₀ = quarter areas ½, ⋆₁ = 1/4 on the x-edges (dual ½ over
    /// // length 2) and 1 on the y-edges (dual 1 over length 1), ⋆₂ = ½.
    /// let k = rectangle(1, 1, [0.0, 1.0], [0.0, 1.0])?;
    /// let x_edges: Vec<bool> = (0..4).map(|e| {
    ///     let v = k.cell_vertices(1, e);
    ///     let (a, b) = (k.vertices().point(v[0]), k.vertices().point(v[1]));
    ///     a[1] == b[1]
    /// }).collect();
    /// let stars = vec![
    ///     vec![0.5; 4],
    ///     x_edges.iter().map(|&x| if x { 0.25 } else { 1.0 }).collect(),
    ///     vec![0.5],
    /// ];
    /// let forms = Forms::with_stars(&k, &stars)?;
    /// let area: f64 = forms.star(0)?.diagonal_weights().unwrap().iter().sum();
    /// assert_eq!(area, 2.0);
    /// // Δ₀ with natural conditions: the constants are the kernel.
    /// assert_eq!(forms.hodge_laplacian(0, Boundary::Natural)?.betti(), 1);
    /// # Ok(())
    /// # }
    /// ```
    pub fn with_stars(complex: &'a Complex, stars: &'a [Vec<f64>]) -> Result<Self, FormsError> {
        let n = complex.dim();
        if stars.len() != n + 1 {
            return Err(FormsError::Field(format!(
                "a {n}-dimensional complex needs {} supplied stars (degrees 0 to {n}), got {}",
                n + 1,
                stars.len()
            )));
        }
        for (k, star) in stars.iter().enumerate() {
            let cells = complex.cell_count(k);
            if star.len() != cells {
                return Err(FormsError::Field(format!(
                    "the supplied star ⋆_{k} has {} values, but the complex has {cells} {k}-cells",
                    star.len()
                )));
            }
            if let Some(cell) = star.iter().position(|v| !v.is_finite()) {
                return Err(FormsError::Field(format!(
                    "the supplied star ⋆_{k} is {} on {k}-cell {cell}",
                    star[cell]
                )));
            }
        }
        Ok(Self {
            complex,
            star: Star::Supplied,
            supplied: stars,
        })
    }

    /// The diagonal ⋆_k of a diagonal star.
    fn diagonal_star(&self, k: usize) -> Result<Option<Vec<f64>>, FormsError> {
        Ok(match self.star {
            Star::Diagonal(dual) => Some(self.complex.hodge_star(dual, k)?),
            Star::Supplied => Some(
                self.supplied
                    .get(k)
                    .ok_or_else(|| {
                        FormsError::Field(format!(
                            "no supplied star of degree {k}: build the forms with Forms::with_stars"
                        ))
                    })?
                    .clone(),
            ),
            Star::Whitney => None,
        })
    }

    /// The complex.
    pub fn complex(&self) -> &'a Complex {
        self.complex
    }

    /// The star kind.
    pub fn star_kind(&self) -> Star {
        self.star
    }

    fn check(&self, k: usize) -> Result<(), FormsError> {
        let dim = self.complex.dim();
        if k > dim {
            return Err(FormsError::Degree { degree: k, dim });
        }
        Ok(())
    }

    /// d_k = δᵏ = ∂_{k+1}ᵀ ((k+1)-cells × k-cells), exact integers; for
    /// k = n the empty 0 × |K_n| matrix.
    /// Shared with the complex (no copy) for k < n.
    pub fn d(&self, k: usize) -> Result<Arc<CsMat<i8>>, FormsError> {
        self.check(k)?;
        if k == self.complex.dim() {
            let cols = self.complex.cell_count(k);
            return Ok(Arc::new(CsMat::new(
                (0, cols),
                vec![0],
                Vec::new(),
                Vec::new(),
            )));
        }
        Ok(Arc::clone(self.complex.coboundary(k)))
    }

    /// ⋆_k as a metric over the k-cells: diagonal for [`Star::Diagonal`],
    /// one dense block per top simplex for [`Star::Whitney`].
    pub fn star(&self, k: usize) -> Result<BlockMetric, FormsError> {
        self.check(k)?;
        Ok(match self.diagonal_star(k)? {
            Some(weights) => BlockMetric::from_weights(weights),
            None => whitney::whitney_mass(self.complex, k)?,
        })
    }

    /// The diagonal ⋆_k, checked > 0 on the listed cells (all when `None`).
    pub(crate) fn positive_diagonal(
        &self,
        k: usize,
        cells: Option<&[usize]>,
        what: &'static str,
    ) -> Result<Vec<f64>, FormsError> {
        let Some(star) = self.diagonal_star(k)? else {
            return Err(FormsError::NeedsDiagonal(what));
        };
        let bad = |&c: &usize| !(star[c].is_finite() && star[c] > 0.0);
        let found = match cells {
            Some(cells) => cells.iter().copied().find(bad),
            None => (0..star.len()).find(bad),
        };
        if let Some(cell) = found {
            return Err(FormsError::NonPositiveStar {
                k,
                cell,
                value: star[cell],
                what,
            });
        }
        Ok(star)
    }

    /// The codifferential δ_k = ⋆_{k−1}⁻¹ d_{k−1}ᵀ ⋆_k ((k−1)-cells ×
    /// k-cells), k ≥ 1, for a diagonal star: the canonical coupling block
    /// d_{k−1}ᵀ ⋆_k I (A = d_{k−1}, Ω = ⋆_k, B = I) with its rows divided by
    /// ⋆_{k−1}. It is the adjoint of d_{k−1} in the star inner products:
    /// ⟨δ_k a, b⟩_{⋆_{k−1}} = ⟨a, d_{k−1} b⟩_{⋆_k}.
    ///
    /// ```
    /// use hasse_complex::{dual::DualKind, generate::rectangle};
    /// use hasse_solver::physics::forms::{Forms, Star};
    /// let k = rectangle(3, 2, [0.0, 3.0], [0.0, 1.0]).unwrap();
    /// let forms = Forms::new(&k, Star::Diagonal(DualKind::Barycentric));
    /// // δ₁ of the constant field along x (a 1-cochain: edge length along x):
    /// // divergence-free inside, so δ₁ vanishes at interior vertices.
    /// let delta = forms.codifferential(1).unwrap().to_dense();
    /// assert_eq!((delta.nrows(), delta.ncols()), (12, 17));
    /// ```
    pub fn codifferential(&self, k: usize) -> Result<SparseColMat<usize, f64>, FormsError> {
        self.check(k)?;
        if k == 0 {
            return Err(FormsError::Degree {
                degree: 0,
                dim: self.complex.dim(),
            });
        }
        let lower = self.positive_diagonal(k - 1, None, "the codifferential ⋆⁻¹ dᵀ ⋆")?;
        let star = self.star(k)?;
        let cells = self.complex.cell_count(k);
        let coupling = Canonical::coupling(
            self.complex.coboundary(k - 1),
            star,
            CsMat::<i8>::eye(cells),
        )?
        .assemble();
        scale_rows(
            &coupling,
            &lower.iter().map(|s| 1.0 / s).collect::<Vec<_>>(),
        )
    }

    /// Δ_k as the pencil (K, M) with the boundary condition `boundary`:
    /// the diagonal form for a diagonal star, the mixed (FEEC) block form
    /// otherwise (see [`laplacian`]).
    pub fn hodge_laplacian(
        &self,
        k: usize,
        boundary: Boundary,
    ) -> Result<HodgeLaplacian, FormsError> {
        if self.star.is_diagonal() {
            HodgeLaplacian::diagonal(self, k, boundary)
        } else {
            HodgeLaplacian::mixed(self, k, boundary)
        }
    }
}

/// diag(s) A.
fn scale_rows(
    a: &SparseColMat<usize, f64>,
    s: &[f64],
) -> Result<SparseColMat<usize, f64>, FormsError> {
    let mut entries = Vec::with_capacity(a.compute_nnz());
    for j in 0..a.ncols() {
        let range = a.col_range(j);
        for (&i, &v) in a.row_idx()[range.clone()].iter().zip(&a.val()[range]) {
            entries.push(Triplet::new(i, j, s[i] * v));
        }
    }
    from_triplets(a.nrows(), a.ncols(), &entries)
}

/// A sparse matrix from triplets whose indices are in range by
/// construction.
pub(crate) fn from_triplets(
    rows: usize,
    cols: usize,
    entries: &[Triplet<usize, usize, f64>],
) -> Result<SparseColMat<usize, f64>, FormsError> {
    SparseColMat::try_new_from_triplets(rows, cols, entries)
        .map_err(|e| FormsError::Internal(format!("a {rows}×{cols} matrix: {e:?}")))
}
