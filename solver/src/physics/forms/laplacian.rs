//! The Hodge Laplacian Δ_k = d_{k−1} δ_k + δ_{k+1} d_k as a symmetric
//! pencil K x = λ M x, and its eigenpairs.
//!
//! **Diagonal stars** (DEC): M = ⋆_k and
//!
//! ```text
//!     K = d_kᵀ ⋆_{k+1} d_k + B ⋆_{k−1}⁻¹ Bᵀ,     B = ⋆_k d_{k−1},
//! ```
//!
//! the first term the canonical operator (A = d_k, Ω = ⋆_{k+1}), B the
//! canonical coupling block Iᵀ ⋆_k d_{k−1}. The second term is the Schur
//! complement of the mixed form below with its diagonal σ block ⋆_{k−1}
//! eliminated, exact because that block is diagonal: the product is formed
//! column by column of B, one rank-one term per (k−1)-cell.
//!
//! **Mixed form** (FEEC, any star, needed when ⋆_{k−1} is not diagonal):
//! σ = δ_k u is kept as an unknown on the (k−1)-cells,
//!
//! ```text
//!     [ −M_{k−1}    d_{k−1}ᵀ M_k     ] [σ]       [0  0  ] [σ]
//!     [ M_k d_{k−1}  d_kᵀ M_{k+1} d_k ] [u] = λ  [0  M_k] [u],
//! ```
//!
//! (the first row negated so the block matrix is symmetric), a
//! [`BlockSystem`] of canonical blocks. Its eigenvectors satisfy the first
//! row, σ = M_{k−1}⁻¹ d_{k−1}ᵀ M_k u, so the eigensolver works on that
//! subspace: every Krylov vector is projected onto it (one LLᵀ of
//! M_{k−1}), where the Rayleigh quotient is uᵀ(d M d + M d M⁻¹ dᵀ M)u ≥ 0
//! and the mass uᵀ M_k u > 0. K is indefinite, so the shift is put just
//! above 0 and K − σM factored by LBLᵀ.
//!
//! **Boundary conditions**: `Natural` (absolute) keeps every cell, the
//! dual cells truncated at the boundary; `Essential` (relative) holds the
//! k- and (k−1)-cochains at zero on the boundary subcomplex (zero
//! tangential trace). The kernel is then H^k(K) (absolute) or H^k(K, ∂K)
//! (relative), of dimension β_k or the relative Betti number.

use super::{from_triplets, Forms, FormsError};
use crate::la::direct::{DirectSolver, Factor, Factorization};
use crate::la::eigen::{self, multiply, Options};
use crate::la::fixed::FixedSplit;
use crate::operator::block::{Block, BlockSystem, Symmetry};
use crate::operator::{BlockMetric, Canonical};
use faer::sparse::{SparseColMat, SparseColMatRef, Triplet};
use hasse_complex::homology::rank;
use hasse_complex::{Complex, Field};
use sprs::CsMat;

/// The boundary condition of Δ_k on a complex with boundary.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Boundary {
    /// Absolute (natural) conditions: no cochain is constrained.
    Natural,
    /// Relative (essential) conditions: cochains vanish on the boundary.
    Essential,
}

impl Boundary {
    /// The name case files use (`problem.boundary`).
    pub fn name(&self) -> &'static str {
        match self {
            Boundary::Natural => "natural",
            Boundary::Essential => "essential",
        }
    }
}

/// Δ_k assembled: the pencil (K, M) on the free k-cells, and for the
/// mixed form the σ unknowns on the free (k−1)-cells before them.
///
/// ```
/// use hasse_complex::{dual::DualKind, generate::sphere};
/// use hasse_solver::physics::forms::{Boundary, Forms, Star};
/// let k = sphere(1.0, 2).unwrap();
/// let laplacian = Forms::new(&k, Star::Diagonal(DualKind::Circumcentric))
///     .hodge_laplacian(0, Boundary::Natural)
///     .unwrap();
/// let modes = laplacian.modes(4, &laplacian.default_options()).unwrap();
/// // Constants are the kernel (β₀ = 1); l = 1 gives 2 (three times) on the unit sphere.
/// assert_eq!(modes.kernel, 1);
/// assert!(modes.eigenvalues[..3].iter().all(|l| (l - 2.0).abs() < 0.05));
/// ```
pub struct HodgeLaplacian {
    degree: usize,
    boundary: Boundary,
    /// k-cells: boundary ones fixed for essential conditions.
    cells: FixedSplit,
    /// Unknowns of σ (mixed form) before the k-cells; 0 for the diagonal form.
    sigma: usize,
    stiffness: SparseColMat<usize, f64>,
    mass: SparseColMat<usize, f64>,
    /// Mixed form: M_{k−1} (LLᵀ) and the block d_{k−1}ᵀ M_k, for the
    /// projection σ = M_{k−1}⁻¹ d_{k−1}ᵀ M_k u.
    constraint: Option<(Factor, SparseColMat<usize, f64>)>,
    betti: usize,
    scale: f64,
}

/// Eigenpairs of Δ_k.
#[derive(Clone, Debug, PartialEq)]
pub struct FormModes {
    /// The nonzero eigenvalues found, ascending.
    pub eigenvalues: Vec<f64>,
    /// Their eigenvectors as k-cochains on every k-cell (zero on the
    /// boundary for essential conditions), ⋆_k-orthonormal.
    pub fields: Vec<Vec<f64>>,
    /// The harmonic k-cochains found (eigenvalue 0 to rounding).
    pub harmonic: Vec<Vec<f64>>,
    /// The dimension of the kernel found: `harmonic.len()`.
    pub kernel: usize,
    /// Relative residuals of the nonzero pairs.
    pub residuals: Vec<f64>,
}

impl HodgeLaplacian {
    /// The k-cells and (k ≥ 1) the (k−1)-cells, split into free and held
    /// by the boundary condition.
    pub(super) fn splits(
        forms: &Forms<'_>,
        k: usize,
        boundary: Boundary,
    ) -> Result<(FixedSplit, Option<FixedSplit>), FormsError> {
        forms.check(k)?;
        let complex = forms.complex();
        let split = |p: usize| match boundary {
            Boundary::Natural => FixedSplit::from_mask((0..complex.cell_count(p)).map(|_| false)),
            Boundary::Essential => {
                let wall = complex.boundary_subcomplex();
                FixedSplit::from_mask((0..complex.cell_count(p)).map(|i| wall.contains(p, i)))
            }
        };
        Ok((split(k), (k > 0).then(|| split(k - 1))))
    }

    /// The diagonal form: K = d_kᵀ ⋆_{k+1} d_k + B ⋆_{k−1}⁻¹ Bᵀ, M = ⋆_k.
    pub(super) fn diagonal(
        forms: &Forms<'_>,
        k: usize,
        boundary: Boundary,
    ) -> Result<Self, FormsError> {
        let (cells, lower) = Self::splits(forms, k, boundary)?;
        let complex = forms.complex();
        let n = complex.dim();
        let free = cells.free().len();
        let star_k = forms.positive_diagonal(k, Some(cells.free()), "the mass M = ⋆_k")?;
        let mass = Canonical::new(cells.selection(), BlockMetric::diagonal(&star_k))?.assemble();
        let mut entries: Vec<Triplet<usize, usize, f64>> = Vec::new();
        if k < n {
            let star = forms.star(k + 1)?;
            let curl = Canonical::new(cells.restrict_columns(&*forms.d(k)?), star)?.assemble();
            push_entries(&mut entries, curl.as_ref());
        }
        if let Some(lower) = &lower {
            let inverse = forms.positive_diagonal(k - 1, Some(lower.free()), "⋆_{k−1}⁻¹ in Δ_k")?;
            // B = Eᵀ ⋆_k (d_{k−1} E'): free k-cells × free (k−1)-cells.
            let b = Canonical::coupling(
                cells.selection(),
                BlockMetric::diagonal(&star_k),
                lower.restrict_columns(&*forms.d(k - 1)?),
            )?
            .assemble();
            for (j, &cell) in lower.free().iter().enumerate() {
                let range = b.col_range(j);
                let rows = &b.row_idx()[range.clone()];
                let values = &b.val()[range];
                let w = 1.0 / inverse[cell];
                for (&r, &x) in rows.iter().zip(values) {
                    for (&s, &y) in rows.iter().zip(values) {
                        entries.push(Triplet::new(r, s, w * x * y));
                    }
                }
            }
        }
        let stiffness = from_triplets(free, free, &entries)?;
        Self::finish(forms, k, boundary, cells, 0, stiffness, mass, None)
    }

    /// The mixed (FEEC) block form, for any star; k = 0 has no σ block and
    /// is K = d₀ᵀ M₁ d₀, M = M₀.
    pub(super) fn mixed(
        forms: &Forms<'_>,
        k: usize,
        boundary: Boundary,
    ) -> Result<Self, FormsError> {
        let (cells, lower) = Self::splits(forms, k, boundary)?;
        let complex = forms.complex();
        let n = complex.dim();
        let free = cells.free().len();
        let star_k = forms.star(k)?;
        let curl = (k < n)
            .then(|| -> Result<Canonical, FormsError> {
                let d = cells.restrict_columns(&*forms.d(k)?);
                Ok(Canonical::new(d, forms.star(k + 1)?)?)
            })
            .transpose()?;
        let mass_k = Canonical::new(cells.selection(), star_k.clone())?;
        let Some(lower) = lower else {
            let stiffness = match &curl {
                Some(curl) => curl.assemble(),
                None => from_triplets(free, free, &[])?,
            };
            return Self::finish(
                forms,
                k,
                boundary,
                cells,
                0,
                stiffness,
                mass_k.assemble(),
                None,
            );
        };
        let sigma = lower.free().len();
        let star_lower = forms.star(k - 1)?;
        let mass_lower = Canonical::new(lower.selection(), star_lower.clone())?;
        let negated = Canonical::new(
            lower.selection(),
            BlockMetric::stacked(&[(-1.0, &star_lower)]),
        )?;
        // d_{k−1}ᵀ M_k: (k−1)-cells × k-cells, the σ–u block.
        let coupling = Canonical::coupling(
            lower.restrict_columns(&*forms.d(k - 1)?),
            star_k,
            cells.selection(),
        )?;
        let coupling_matrix = coupling.assemble();
        let mut blocks = vec![
            (0, 0, Block::Canonical(negated)),
            (0, 1, Block::Canonical(coupling)),
        ];
        if let Some(curl) = curl {
            blocks.push((1, 1, Block::Canonical(curl)));
        }
        let stiffness = BlockSystem::new(&[sigma, free], Symmetry::Symmetric, blocks)?.matrix();
        let mass = BlockSystem::new(
            &[sigma, free],
            Symmetry::Symmetric,
            vec![(1, 1, Block::Canonical(mass_k))],
        )?
        .matrix();
        let gram = mass_lower.assemble();
        let factor = if sigma == 0 {
            None
        } else {
            let factor = DirectSolver::analyze(gram.as_ref(), Factorization::Llt)?
                .factorize(gram.as_ref())?;
            Some((factor, coupling_matrix))
        };
        Self::finish(forms, k, boundary, cells, sigma, stiffness, mass, factor)
    }

    /// The mixed block form for any star, also a diagonal one (the
    /// diagonal form is this with σ eliminated); for k = 0 the same as the
    /// diagonal form.
    pub fn mixed_form(forms: &Forms<'_>, k: usize, boundary: Boundary) -> Result<Self, FormsError> {
        Self::mixed(forms, k, boundary)
    }

    #[allow(clippy::too_many_arguments)]
    fn finish(
        forms: &Forms<'_>,
        k: usize,
        boundary: Boundary,
        cells: FixedSplit,
        sigma: usize,
        stiffness: SparseColMat<usize, f64>,
        mass: SparseColMat<usize, f64>,
        constraint: Option<(Factor, SparseColMat<usize, f64>)>,
    ) -> Result<Self, FormsError> {
        let complex = forms.complex();
        let betti = match boundary {
            Boundary::Natural => complex.betti_numbers().get(k).copied().unwrap_or(0),
            Boundary::Essential => relative_betti_numbers(complex)[k],
        };
        let scale = complex.mesh_size().max(f64::MIN_POSITIVE);
        Ok(Self {
            degree: k,
            boundary,
            cells,
            sigma,
            stiffness,
            mass,
            constraint,
            betti,
            scale,
        })
    }

    /// The degree k.
    pub fn degree(&self) -> usize {
        self.degree
    }

    /// The boundary condition.
    pub fn boundary(&self) -> Boundary {
        self.boundary
    }

    /// Whether this is the mixed block form (σ unknowns first).
    pub fn is_mixed(&self) -> bool {
        self.constraint.is_some()
    }

    /// The free k-cells (all of them for natural conditions).
    pub fn free_cells(&self) -> &[usize] {
        self.cells.free()
    }

    /// K (for the mixed form, the whole symmetric block matrix).
    pub fn stiffness(&self) -> SparseColMatRef<'_, usize, f64> {
        self.stiffness.as_ref()
    }

    /// K as the owned matrix.
    pub(super) fn stiffness_matrix(&self) -> &SparseColMat<usize, f64> {
        &self.stiffness
    }

    /// M (for the mixed form, diag(0, M_k)).
    pub fn mass(&self) -> SparseColMatRef<'_, usize, f64> {
        self.mass.as_ref()
    }

    /// The dimension the kernel must have: β_k (natural) or the relative
    /// Betti number β_k(K, ∂K) (essential), from the ranks of the
    /// (restricted) coboundaries over Q.
    pub fn betti(&self) -> usize {
        self.betti
    }

    /// How many eigenpairs exist: the free k-cells.
    pub fn unknowns(&self) -> usize {
        self.cells.free().len()
    }

    /// Shift −(π/h)²/100 below the spectrum (LLᵀ) for the diagonal form;
    /// just above 0 for the mixed form, whose K is indefinite (LBLᵀ): the
    /// eigenvalues closest to it are still the smallest.
    pub fn default_options(&self) -> Options {
        let unit = (1.0 / self.scale).powi(2) * 1e-4;
        Options {
            shift: if self.is_mixed() { unit } else { -unit },
            ..Options::default()
        }
    }

    /// The kernel (as [`FormModes::harmonic`]) and the `count` smallest
    /// nonzero eigenvalues of Δ_k with their k-cochains. Asks for
    /// `count + β` pairs, so a kernel larger than β shows up in
    /// [`FormModes::kernel`].
    pub fn modes(&self, count: usize, options: &Options) -> Result<FormModes, FormsError> {
        let available = self.unknowns();
        if available == 0 {
            // Essential conditions on a complex whose k-cells all lie on
            // the boundary (e.g. a solid one cell thick): no relative
            // k-cochains, so the spectrum and the kernel are empty, as
            // β_k(K, ∂K) = 0 says.
            return Ok(FormModes {
                eigenvalues: Vec::new(),
                fields: Vec::new(),
                harmonic: Vec::new(),
                kernel: 0,
                residuals: Vec::new(),
            });
        }
        let wanted = (count + self.betti).min(available);
        let project = |z: &mut [f64]| -> Result<(), crate::la::direct::SolveError> {
            if let Some((factor, coupling)) = &self.constraint {
                // The σ–u block is d_{k−1}ᵀ M_k already.
                let rhs = multiply(coupling.as_ref(), &z[self.sigma..]);
                let sigma = factor.solve(&rhs)?;
                z[..self.sigma].copy_from_slice(&sigma);
            }
            Ok(())
        };
        let projection: Option<eigen::Projection<'_>> = self
            .constraint
            .as_ref()
            .map(|_| &project as eigen::Projection<'_>);
        let pairs = eigen::smallest(
            self.stiffness.as_ref(),
            self.mass.as_ref(),
            wanted,
            projection,
            available,
            options,
        )?;
        let lift = |z: &[f64]| self.cells.lift(&z[self.sigma..], &[]);
        let zeros = pairs.zeros;
        let harmonic = pairs.vectors[..zeros].iter().map(|z| lift(z)).collect();
        let mut eigenvalues = pairs.values[zeros..].to_vec();
        let mut fields: Vec<Vec<f64>> = pairs.vectors[zeros..].iter().map(|z| lift(z)).collect();
        let mut residuals = pairs.residuals[zeros..].to_vec();
        eigenvalues.truncate(count);
        fields.truncate(count);
        residuals.truncate(count);
        Ok(FormModes {
            eigenvalues,
            fields,
            harmonic,
            kernel: zeros,
            residuals,
        })
    }
}

fn push_entries(entries: &mut Vec<Triplet<usize, usize, f64>>, m: SparseColMatRef<'_, usize, f64>) {
    for j in 0..m.ncols() {
        let range = m.col_range(j);
        for (&i, &v) in m.row_idx()[range.clone()].iter().zip(&m.val()[range]) {
            entries.push(Triplet::new(i, j, v));
        }
    }
}

/// The relative Betti numbers β_k(K, ∂K) over Q, from the relative
/// cochain complex: cochains on the cells not in the boundary subcomplex,
/// d_k restricted to them, β_k = |free k-cells| − rank d_k − rank d_{k−1}.
/// On a complex without boundary they are the ordinary Betti numbers.
///
/// ```
/// use hasse_complex::generate::{annulus, rectangle};
/// use hasse_solver::physics::forms::laplacian::relative_betti_numbers;
/// // Lefschetz duality on orientable surfaces: β_k(K, ∂K) = β_{2−k}(K).
/// assert_eq!(relative_betti_numbers(&rectangle(3, 3, [0.0, 1.0], [0.0, 1.0]).unwrap()), vec![0, 0, 1]);
/// assert_eq!(relative_betti_numbers(&annulus(1.0, 2.0, 2, 8).unwrap()), vec![0, 1, 1]);
/// ```
pub fn relative_betti_numbers(complex: &Complex) -> Vec<usize> {
    let n = complex.dim();
    let wall = complex.boundary_subcomplex();
    let splits: Vec<FixedSplit> = (0..=n)
        .map(|p| FixedSplit::from_mask((0..complex.cell_count(p)).map(|i| wall.contains(p, i))))
        .collect();
    let ranks: Vec<usize> = (0..n)
        .map(|p| {
            let d: CsMat<i8> =
                splits[p + 1].restrict_rows(&splits[p].restrict_columns(complex.coboundary(p)));
            rank(&d, Field::Rationals)
        })
        .collect();
    (0..=n)
        .map(|p| {
            let above = ranks.get(p).copied().unwrap_or(0);
            let below = if p > 0 { ranks[p - 1] } else { 0 };
            splits[p].free().len() - above - below
        })
        .collect()
}
