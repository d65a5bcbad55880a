//! # hasse-complex
//!
//! Cell complexes in LAR form (cells listed by their vertices, CSR
//! characteristic matrices M_p), their exact signed boundary matrices ∂_p,
//! the Hasse matrix, homology, geometry, dual complexes and mesh
//! generators. No physics lives here: the solver crate builds the canonical
//! operators Aᵀ Ω A on top of this topology.
//!
//! ```
//! use hasse_complex::{Complex, TopCells, Vertices};
//! let v = Vertices::from_points(&[[0.0], [0.5], [1.0]]).unwrap();
//! let k = Complex::build(v, TopCells::simplices([[0, 1], [1, 2]])).unwrap();
//! assert_eq!(k.betti_numbers(), vec![1, 0]);
//! ```

pub mod cells;
pub mod coarsen;
pub mod complex;
mod convex_order;
pub mod dual;
pub mod error;
pub mod euler;
mod fingerprint;
mod frame;
pub mod generate;
pub mod geometry;
pub mod gmsh;
pub mod hasse_transform;
pub mod homology;
pub mod json;
pub mod kill;
pub mod lar;
pub mod lar_json;
mod nonconvex;
mod period;
pub mod product;
pub mod refine;
pub mod relations;
pub mod split;
pub mod tags;

pub use cells::{Shape, TopCells, Vertices};
pub use complex::{Complex, Subcomplex};
pub use dual::DualKind;
pub use error::{ComplexError, Result, SplitError};
pub use homology::Field;
pub use lar::Lar;
pub use tags::{CellTag, Tags};
