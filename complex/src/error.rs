//! Typed errors for everything that can go wrong when a complex is built
//! from user input. Every variant names the offending cell or vertex so a
//! front end can point the user at it.

/// Why a complex could not be built or a query could not be answered.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ComplexError {
    #[error("the vertex coordinates are empty: a complex needs at least one vertex")]
    NoVertices,
    #[error("no top cells were given: a complex needs at least one cell")]
    NoCells,
    #[error("embedding dimension {0} is not supported (1, 2 or 3)")]
    UnsupportedEmbedding(usize),
    #[error("{len} coordinate values cannot be split into points of dimension {dim}")]
    CoordinateShape { len: usize, dim: usize },
    #[error(
        "vertex {vertex} has a non-finite coordinate {value} on axis {axis}; fix the mesh input"
    )]
    NonFiniteCoordinate {
        vertex: usize,
        axis: usize,
        value: f64,
    },
    #[error("top cell {cell} refers to vertex {vertex}, but only {vertex_count} vertices exist (indices start at 0)")]
    VertexOutOfRange {
        cell: usize,
        vertex: usize,
        vertex_count: usize,
    },
    #[error("top cell {cell} lists vertex {vertex} more than once")]
    RepeatedVertex { cell: usize, vertex: usize },
    #[error("top cell {cell} is a {shape} with {found} vertices; a {shape} needs {expected}")]
    WrongVertexCount {
        cell: usize,
        shape: &'static str,
        expected: String,
        found: usize,
    },
    #[error("top cell {cell} is a {found}-cell but the complex is {expected}-dimensional; all top cells must have the same dimension")]
    MixedDimension {
        cell: usize,
        expected: usize,
        found: usize,
    },
    #[error("top cells are {cell_dim}-dimensional, which does not fit in R^{embedding_dim}")]
    DimensionTooHigh {
        cell_dim: usize,
        embedding_dim: usize,
    },
    #[error("{dim}-cell {cell} (vertices {vertices:?}) has zero {dim}-measure: its vertices span fewer than {dim} dimensions")]
    DegenerateCell {
        dim: usize,
        cell: usize,
        vertices: Vec<usize>,
    },
    #[error("the complex is not orientable: top cell {cell} cannot be oriented consistently with its neighbours across {face_dim}-cell {face}")]
    NonOrientable {
        cell: usize,
        face: usize,
        face_dim: usize,
    },
    #[error("cell dimension {p} is out of range: this complex has cells of dimension 0..={dim}")]
    DimensionOutOfRange { p: usize, dim: usize },
    /// An incidence operator asked for at a degree where it does not exist.
    #[error("{operator} exists for {valid} on this {dim}-complex, not for p = {p}")]
    DegreeOutOfRange {
        /// The operator's name, "∂_p" or "δ^p".
        operator: &'static str,
        p: usize,
        dim: usize,
        /// The valid degrees, e.g. "1 ≤ p ≤ 2".
        valid: String,
    },
    #[error("characteristic matrix M_{p} has {found} columns but there are {expected} vertices")]
    CharacteristicShape {
        p: usize,
        expected: usize,
        found: usize,
    },
    #[error("{0}")]
    Invalid(String),
}

/// Shorthand used throughout the crate.
pub type Result<T, E = ComplexError> = std::result::Result<T, E>;

/// Why an Euler make or kill operator, a SPLIT or a field transfer was
/// refused. Each variant names the offending cell, plane or array.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum SplitError {
    #[error("cell dimension {p} is out of range for this operation: expected 1..={dim}")]
    DimensionOutOfRange { p: usize, dim: usize },
    #[error("{p}-cell {cell} does not exist (there are {count})")]
    CellOutOfRange { p: usize, cell: usize, count: usize },
    #[error("{p}-cell {cell}: {reason}")]
    BadFacetSelection {
        p: usize,
        cell: usize,
        reason: String,
    },
    #[error("the hyperplane normal {0:?} is zero or not finite")]
    BadNormal(Vec<f64>),
    #[error("the hyperplane offset {0} is not finite")]
    BadOffset(f64),
    #[error("the hyperplane has {found} normal components but the complex lives in R^{expected}")]
    PlaneDimension { expected: usize, found: usize },
    #[error("the snap tolerance {0} must be finite and in [0, 0.25)")]
    BadTolerance(f64),
    #[error("SPLIT needs a complex that fills its space (n = d = 2 or 3); this one has n = {dim} in R^{embedding}")]
    Unsupported { dim: usize, embedding: usize },
    #[error("{dim}-cell {cell} is cut ambiguously by the plane (its vertices on one side are not contiguous within the snap tolerance); use a smaller tolerance or move the plane")]
    AmbiguousCut { dim: usize, cell: usize },
    #[error("{what} has {found} values but there are {expected} {p}-cells")]
    LengthMismatch {
        what: &'static str,
        p: usize,
        expected: usize,
        found: usize,
    },
    #[error("chain maps cannot be composed: the first refines to {first:?} cells, the second starts from {second:?}")]
    Incompatible {
        first: Vec<usize>,
        second: Vec<usize>,
    },
    #[error("{0}")]
    Invalid(String),
    #[error(transparent)]
    Complex(#[from] ComplexError),
    #[error("{what} is {found:?} but the operator expects {expected:?}")]
    Shape {
        what: String,
        expected: (usize, usize),
        found: (usize, usize),
    },
    #[error("{p}-cell {cell} cannot be merged with itself")]
    SameCell { p: usize, cell: usize },
    #[error("{p}-cells {a} and {b} share the {count} facets {shared:?}; a kill merges two cells across exactly one", count = shared.len())]
    NotAdjacent {
        p: usize,
        a: usize,
        b: usize,
        shared: Vec<usize>,
    },
    #[error("the facet {facet} between {p}-cells {a} and {b} also bounds {p}-cell {other}, so it cannot be removed")]
    FacetHasOtherCofaces {
        p: usize,
        facet: usize,
        a: usize,
        b: usize,
        other: usize,
    },
    #[error("merging {p}-cells {a} and {b} would not give a cell: {reason}")]
    NotACell {
        p: usize,
        a: usize,
        b: usize,
        reason: String,
    },
}
