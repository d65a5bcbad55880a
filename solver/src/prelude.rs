//! The names most programs need, in one `use`.
//!
//! ```
//! use hasse_solver::prelude::*;
//!
//! // A 2-complex, its exact ∂ and δ, and the circumcentric DEC Laplacian
//! // on 0-forms: Δ₀ = δ⁰ᵀ ⋆₁ δ⁰, assembled in the canonical form Aᵀ Ω A.
//! let axis = generate::uniform_axis(4, 0.0, 1.0).unwrap();
//! let k = generate::kuhn(&[axis.clone(), axis]).unwrap(); // 32 right triangles
//! assert_eq!(k.betti_numbers(), vec![1, 0, 0]);
//! let forms = Forms::new(&k, Star::Diagonal(DualKind::Circumcentric));
//! let laplacian = Canonical::new(forms.d(0).unwrap(), forms.star(1).unwrap()).unwrap();
//! // Constants are its kernel on a closed-boundary (Neumann) complex.
//! assert!(laplacian.apply(&vec![1.0; 25]).iter().all(|v| v.abs() < 1e-12));
//! ```
//!
//! What it brings in:
//!
//! - the complex: [`Complex`], [`generate`] (meshes), [`DualKind`],
//!   [`Field`] (homology coefficients);
//! - the canonical form: [`Canonical`], [`BlockMetric`], [`IntoIncidence`],
//!   and the methods' metrics [`fd`], [`fe`], [`fv`], [`dec`];
//! - solving: [`DirectSolver`], [`Factor`], [`Factorization`],
//!   [`Multigrid`];
//! - problems: [`Diffusion`], [`Heat`], [`Conductivity`],
//!   [`BoundaryKind`], [`Method`];
//! - k-forms: [`Forms`], [`Star`], [`HodgeLaplacian`], [`Boundary`],
//!   [`HarmonicBasis`], [`Decomposition`], [`de_rham`], [`WhitneyField`];
//! - the two matrix crates hasse's types are made of, [`sprs`] (the
//!   integer incidence matrices) and [`faer`] (assembled operators,
//!   factorisations).

pub use crate::la::direct::{DirectSolver, Factor, Factorization};
pub use crate::metric::{dec, fd, fe, fv, Method};
pub use crate::multigrid::Multigrid;
pub use crate::operator::{BlockMetric, Canonical, IntoIncidence};
pub use crate::physics::diffusion::Diffusion;
pub use crate::physics::forms::whitney_map::{de_rham, Field as WhitneyField};
pub use crate::physics::forms::{
    Boundary, Decomposition, Forms, HarmonicBasis, HodgeLaplacian, Star,
};
pub use crate::physics::heat::Heat;
pub use crate::physics::{BoundaryKind, Conductivity};
pub use hasse_complex::{generate, Complex, DualKind, Field};
pub use {faer, sprs};
