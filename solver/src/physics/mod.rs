//! Physics: each problem is a block of canonical operators plus its data.

pub mod coupled;
pub mod darcy;
pub mod diffusion;
pub mod elasticity;
pub mod heat;
pub mod maxwell;
