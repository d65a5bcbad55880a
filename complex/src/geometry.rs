//! Geometry of every cell: measures, centroids, normals, circumcentres.

/// Lazily computed geometric quantities of a complex.
#[derive(Clone, Debug, Default)]
pub(crate) struct GeometryCache {}
