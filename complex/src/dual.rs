//! The dual complex (circumcentric and barycentric) and its measures.

/// Lazily computed dual measures.
#[derive(Clone, Debug, Default)]
pub(crate) struct DualCache {}
