//! Fill-reducing orderings of a symmetric sparsity pattern.
//!
//! faer's sparse Cholesky orders by approximate minimum degree (AMD) unless
//! it is handed a permutation. AMD is a greedy, local rule; on the graphs of
//! three-dimensional meshes it leaves much more fill than nested dissection,
//! which splits the graph by small vertex separators and numbers the
//! separators last, so the factor's fill stays inside the separator blocks.
//! METIS (`METIS_NodeND`, built from source by the `metis-sys` crate)
//! computes that ordering ([`Ordering::NestedDissection`]), returned as a
//! faer [`Perm`] ready for `SymmetricOrdering::Custom`.
//!
//! [`Ordering::Geometric`] is nested dissection from the unknowns'
//! positions instead: each part is cut at the median of its longest axis,
//! and the vertices on one side of the cut that touch the other side are
//! the separator. It needs no graph partitioner, costs a few passes over the
//! graph, and on mesh graphs its separators are as small as the mesh is
//! thin across the cut (one grid line or plane on structured grids).
//!
//! The permutation follows faer's (and METIS's) convention: `forward[k]` is
//! the original index of the k-th pivot and `inverse[i]` the position of
//! original index i, so the factorised matrix is A(forward, forward).

use faer::perm::Perm;
use faer::sparse::SymbolicSparseColMatRef;
use metis_sys as metis;
use std::sync::atomic::AtomicU32;
use std::sync::atomic::Ordering::Relaxed;

/// The fill-reducing ordering of a symmetric (LLᵀ, LDLᵀ, LBLᵀ) analysis.
/// LU ignores it: faer orders LU's columns by COLAMD.
///
/// ```
/// use faer::sparse::{SparseColMat, Triplet};
/// use hasse_solver::la::direct::{DirectSolver, Factorization};
/// use hasse_solver::la::ordering::Ordering;
/// // The seven-point Laplacian on a 12³ grid.
/// let m = 12;
/// let id = |i: usize, j: usize, k: usize| i + m * (j + m * k);
/// let mut t = Vec::new();
/// for k in 0..m { for j in 0..m { for i in 0..m {
///     t.push(Triplet::new(id(i, j, k), id(i, j, k), 6.0));
///     for (a, b) in [(i + 1, j), (i, j + 1)].into_iter().filter(|&(a, b)| a < m && b < m) {
///         t.push(Triplet::new(id(a, b, k), id(i, j, k), -1.0));
///         t.push(Triplet::new(id(i, j, k), id(a, b, k), -1.0));
///     }
///     if k + 1 < m {
///         t.push(Triplet::new(id(i, j, k + 1), id(i, j, k), -1.0));
///         t.push(Triplet::new(id(i, j, k), id(i, j, k + 1), -1.0));
///     }
/// }}}
/// let n = m * m * m;
/// let a = SparseColMat::<usize, f64>::try_new_from_triplets(n, n, &t).unwrap();
/// let nd = DirectSolver::analyze_with(a.as_ref(), Factorization::Llt, Ordering::NestedDissection).unwrap();
/// let x = nd.factorize(a.as_ref()).unwrap().solve(&vec![1.0; n]).unwrap();
/// assert_eq!(nd.ordering(), Some(Ordering::NestedDissection));
/// assert!(x.iter().all(|v| v.is_finite() && *v > 0.0));
/// ```
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Ordering {
    /// For LLᵀ with the unknowns' positions (which
    /// [`crate::physics::diffusion`] gives): geometric nested dissection.
    /// Without them: AMD, or METIS nested dissection for LLᵀ systems on
    /// which AMD fills at least 300 factor entries per unknown (3D meshes
    /// from a few 10⁴ unknowns), keeping whichever factor is smaller. LDLᵀ
    /// and LBLᵀ: AMD, whose pivot order [`crate::physics::darcy`] relies on.
    ///
    /// The threshold is measured, not derived: on the 2D and Delaunay
    /// graphs measured AMD fills at most 68 entries per unknown and METIS's
    /// own time outweighs its smaller factor; on 3D grids from 40³ AMD fills
    /// 414 or more and nested dissection halves the factorisation time.
    ///
    /// Why the positions win, measured on whole `Diffusion::solve` runs
    /// (`HASSE_BENCH_ORDERING=amd|nd|geometric cargo bench --bench
    /// multigrid -- CASE PHASE`, release, 2 cores; seconds for the
    /// analysis (ordering included) and the numeric factorisation):
    ///
    /// | case | AMD | METIS ND | geometric |
    /// |---|---|---|---|
    /// | 2D 1000² five-point FV (`2d-1000 solve`) | 0.58 + 1.00 | — | 0.42 + 1.19 |
    /// | 2D 1000² nine-point Q1 (`2d-1000 q1-solve`) | 0.66 + 2.03 | — | 0.52 + 1.09 |
    /// | Delaunay P1, 5·10⁵ (`delaunay-1m solve`) | 0.77 + 0.57 | — | 0.27 + 0.63 |
    /// | 3D 60³ seven-point FV (`3d-60 solve`) | — | 1.44 + 2.42 | 0.23 + 2.89 |
    /// | 3D 60³ Q1 (`3d-60 q1-solve`) | — | 2.22 + 4.54 | 0.36 + 4.86 |
    ///
    /// The table predates the diagonal cuts of the geometric ordering. With
    /// them, two runs on
    /// a slower day gave 0.87 + 1.14 and 0.88 + 1.29 s on the five-point
    /// grid (factor 44.4 M entries instead of 68.4 M), against plain
    /// faer's AMD analysis and factorisation of 2.68 and 3.08 s in
    /// between, and 0.39 + 2.37 and 0.37 + 1.84 s on the seven-point one.
    ///
    /// Factorisation work Σ c_j²
    /// ([`SolveReport::factor_flops`](crate::la::direct::SolveReport::factor_flops)) against
    /// AMD: 0.53× on the five-point grid, 0.35× on the nine-point one; on
    /// 3D grids 0.51× METIS's (seven-point) and 1.0× (Q1). The analysis
    /// costs a third to a tenth of AMD's or METIS's, which is what the
    /// whole solve saves where the factor is no smaller.
    #[default]
    Automatic,
    /// faer's approximate minimum degree.
    Amd,
    /// METIS nested dissection of the matrix graph. Fails for graphs beyond
    /// METIS's 32-bit indices ([`OrderingError::TooLarge`]).
    NestedDissection,
    /// Nested dissection from the unknowns' positions: each part is cut at
    /// the median of its widest axis or, where that gives a smaller
    /// separator, of its widest diagonal. Needs the positions, which the
    /// physics layer passes for nodal and cell-centred unknowns
    /// ([`OrderingError::NoPoints`] otherwise).
    Geometric,
}

/// Where a system's unknowns sit, for the geometric ordering: `dimension`
/// coordinates per unknown, unknown after unknown (vertices for nodal
/// unknowns, a point inside each cell for cell-centred ones).
#[derive(Clone, Copy, Debug)]
pub struct UnknownPoints<'a> {
    /// `dimension` coordinates per unknown, unknown after unknown.
    pub coordinates: &'a [f64],
    /// Coordinates per point (the embedding dimension).
    pub dimension: usize,
}

impl std::fmt::Display for Ordering {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Ordering::Automatic => "automatic",
            Ordering::Amd => "AMD",
            Ordering::NestedDissection => "nested dissection (METIS)",
            Ordering::Geometric => "geometric nested dissection",
        })
    }
}

/// AMD fill, in factor entries per unknown, from which
/// [`Ordering::Automatic`] tries nested dissection for an LLᵀ analysis.
///
/// The rule, by measurement rather than by size: analyze with AMD (cheap);
/// if the factor stores at least this many entries per unknown, analyze
/// again with METIS nested dissection and keep whichever factor is smaller.
/// LDLᵀ and LBLᵀ keep AMD unless asked: unpivoted LDLᵀ and LBLᵀ pivoting
/// within supernodes are only as stable as their pivot order allows, and
/// [`crate::physics::darcy`] relies on the order it gets.
///
/// Measured with `cargo bench --bench multigrid -- CASE amd|nd` (release,
/// the 5-/7-point Laplacian and P1 on a jittered Delaunay mesh, 2 cores
/// shared with other work; analysis + numeric factorisation in seconds,
/// two runs each; entries = values stored for L):
///
/// | case | n | AMD s | ND s | AMD entries/n | ND entries/n |
/// |---|---|---|---|---|---|
/// | 2D 100² | 10⁴ | 0.011 | 0.033 | 21 | 20 |
/// | 2D 300² | 9·10⁴ | 0.14–0.17 | 0.45 | 42 | 33 |
/// | 2D 1000² | 10⁶ | 2.4–2.8 | 6.8–7.4 | 55 | 42 |
/// | Delaunay P1 | 5·10⁵ | 1.7–2.4 | 3.4–4.3 | 68 | 47 |
/// | 3D 20³ | 8·10³ | 0.04 | 0.06–0.07 | 143 | 91 |
/// | 3D 40³ | 6.4·10⁴ | 0.87–1.38 | 0.86–0.96 | 414 | 281 |
/// | 3D 60³ | 2.2·10⁵ | 10.9–18.8 | 5.5–9.2 | 912 | 498 |
///
/// (The spread is other work on the machine; the entries are exact.) The
/// automatic rule adds AMD's analysis (0.7 s at 60³) to nested
/// dissection's. In 2D the factorisation is cheap and METIS's own time
/// (4 s of the 6.8 s at 1000²) outweighs the smaller factor, so size alone
/// would be the wrong rule; AMD's fill per unknown separates the 2D-like
/// graphs (≤ 68) from the 3D ones that gain (≥ 414), and the threshold
/// sits between 143 (3D 20³, where ND's analysis costs more than it
/// saves) and 414.
pub const ND_MIN_FILL_PER_UNKNOWN: usize = 300;

/// Largest adjacency (sum of vertex degrees) METIS can index: the vendored
/// METIS uses 32-bit `idx_t`.
pub(crate) const METIS_MAX_ENTRIES: usize = i32::MAX as usize;

/// Why an ordering could not be computed.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum OrderingError {
    /// The pattern is not square, so it is not the graph of a symmetric
    /// matrix.
    #[error("the pattern is {rows}×{cols}; a symmetric ordering needs a square pattern")]
    NotSquare {
        /// Rows of the pattern.
        rows: usize,
        /// Columns of the pattern.
        cols: usize,
    },
    /// The graph is too large for METIS's 32-bit indices; AMD has no such
    /// limit.
    #[error("the matrix graph has {vertices} vertices and {entries} adjacency entries; METIS indexes with 32-bit integers and takes at most {limit} of each. Use the AMD ordering for systems this large")]
    TooLarge {
        /// Vertices of the graph (unknowns).
        vertices: usize,
        /// Adjacency entries (twice the edges) counted when the limit was
        /// passed; 0 when the vertices alone pass it.
        entries: usize,
        /// The largest count METIS takes, 2³¹ − 1.
        limit: usize,
    },
    /// METIS returned an error code or a permutation that is not one (which
    /// of them).
    #[error("METIS nested dissection failed: {0}")]
    Metis(&'static str),
    /// The positions of the geometric ordering are not one point per
    /// unknown.
    #[error("{found} coordinates given for {unknowns} unknowns in R^{dimension}; coordinate dissection needs one point per unknown")]
    PointCount {
        /// Coordinates given.
        found: usize,
        /// Unknowns of the pattern.
        unknowns: usize,
        /// Coordinates per point.
        dimension: usize,
    },
    /// A position of the geometric ordering is NaN or infinite.
    #[error("coordinate {index} of the unknowns' points is {value}; coordinate dissection needs finite positions")]
    NonFinitePoint {
        /// Index of the coordinate in the flat list (point × dimension +
        /// axis).
        index: usize,
        /// The coordinate.
        value: f64,
    },
    /// [`Ordering::Geometric`] was asked for a system whose unknowns have
    /// no positions (e.g. the face unknowns of the hybrid mimetic method).
    #[error("the geometric ordering needs the unknowns' positions, and this solve has none; use the \"auto\", \"amd\" or \"nested-dissection\" ordering")]
    NoPoints,
}

/// The adjacency graph of a symmetric pattern in METIS's CSR form: the
/// neighbours of vertex v are `adjncy[xadj[v]..xadj[v + 1]]`, sorted, without
/// v itself and without repeats.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Adjacency {
    /// Offsets, length n + 1.
    pub xadj: Vec<i32>,
    /// Neighbour lists, concatenated.
    pub adjncy: Vec<i32>,
}

impl Adjacency {
    /// The graph of the pattern of A + Aᵀ without the diagonal: an entry
    /// stored in either triangle (or both) is one edge, so a matrix stored
    /// whole and one stored as a single triangle give the same graph.
    ///
    /// ```
    /// use faer::sparse::{SparseColMat, Triplet};
    /// use hasse_solver::la::ordering::Adjacency;
    /// // Lower triangle of tridiag(−1, 2, −1), n = 3.
    /// let t = [(0, 0, 2.0), (1, 0, -1.0), (1, 1, 2.0), (2, 1, -1.0), (2, 2, 2.0)];
    /// let t: Vec<_> = t.iter().map(|&(i, j, v)| Triplet::new(i, j, v)).collect();
    /// let a = SparseColMat::<usize, f64>::try_new_from_triplets(3, 3, &t).unwrap();
    /// let g = Adjacency::of_pattern(a.symbolic()).unwrap();
    /// assert_eq!(g.xadj, [0, 1, 3, 4]);
    /// assert_eq!(g.adjncy, [1, 0, 2, 1]);
    /// ```
    pub fn of_pattern(pattern: SymbolicSparseColMatRef<'_, usize>) -> Result<Self, OrderingError> {
        let (rows, cols) = (pattern.nrows(), pattern.ncols());
        if rows != cols {
            return Err(OrderingError::NotSquare { rows, cols });
        }
        let n = cols;
        let too_large = |entries| OrderingError::TooLarge {
            vertices: n,
            entries,
            limit: METIS_MAX_ENTRIES,
        };
        if n > METIS_MAX_ENTRIES {
            return Err(too_large(0));
        }
        let row_idx = pattern.row_idx();
        // Every stored off-diagonal entry (i, j) is written under i and
        // under j; a symmetric matrix stored whole writes each edge twice per
        // vertex, removed by the sort-and-dedup below. Offsets are counted
        // in usize so the 32-bit check sees the true size.
        let mut start = vec![0usize; n + 1];
        for j in 0..n {
            for &i in &row_idx[pattern.col_range(j)] {
                if i != j {
                    start[i + 1] += 1;
                    start[j + 1] += 1;
                }
            }
        }
        for v in 0..n {
            start[v + 1] += start[v];
        }
        let mut next = start.clone();
        let mut adjncy = vec![0i32; start[n]];
        for j in 0..n {
            for &i in &row_idx[pattern.col_range(j)] {
                if i != j {
                    // i, j < n ≤ i32::MAX (checked above).
                    adjncy[next[i]] = j as i32;
                    next[i] += 1;
                    adjncy[next[j]] = i as i32;
                    next[j] += 1;
                }
            }
        }
        let mut xadj = Vec::with_capacity(n + 1);
        xadj.push(0i32);
        let mut write = 0usize;
        for v in 0..n {
            let list = &mut adjncy[start[v]..start[v + 1]];
            list.sort_unstable();
            let mut last = -1i32;
            for k in start[v]..start[v + 1] {
                let u = adjncy[k];
                if u != last {
                    adjncy[write] = u;
                    write += 1;
                    last = u;
                }
            }
            xadj.push(i32::try_from(write).map_err(|_| too_large(write))?);
        }
        adjncy.truncate(write);
        Ok(Self { xadj, adjncy })
    }

    /// Number of vertices.
    pub fn vertices(&self) -> usize {
        self.xadj.len().saturating_sub(1)
    }
}

/// The METIS nested-dissection ordering of a symmetric pattern (either
/// triangle or both may be stored; the diagonal is ignored).
///
/// Vertices without neighbours and several connected components are
/// allowed; a pattern with no off-diagonal entry (n = 0 and n = 1 included)
/// needs no ordering and gets the identity. METIS is seeded with a fixed
/// value, so the ordering is the same on every run.
///
/// ```
/// use faer::sparse::{SparseColMat, Triplet};
/// use hasse_solver::la::ordering::nested_dissection;
/// // The five-point Laplacian's pattern on a 20×20 grid.
/// let m = 20;
/// let mut t = Vec::new();
/// for j in 0..m * m {
///     t.push(Triplet::new(j, j, 4.0));
///     if j % m + 1 < m { t.push(Triplet::new(j + 1, j, -1.0)); }
///     if j + m < m * m { t.push(Triplet::new(j + m, j, -1.0)); }
/// }
/// let a = SparseColMat::<usize, f64>::try_new_from_triplets(m * m, m * m, &t).unwrap();
/// let perm = nested_dissection(a.symbolic()).unwrap();
/// let (forward, inverse) = perm.arrays();
/// assert!((0..m * m).all(|k| inverse[forward[k]] == k));
/// ```
pub fn nested_dissection(
    pattern: SymbolicSparseColMatRef<'_, usize>,
) -> Result<Perm<usize>, OrderingError> {
    let mut graph = Adjacency::of_pattern(pattern)?;
    let n = graph.vertices();
    if graph.adjncy.is_empty() {
        // METIS has nothing to separate (and older releases mishandle a
        // graph without edges): every order gives a diagonal factor.
        let identity: Box<[usize]> = (0..n).collect();
        return Ok(Perm::new_checked(identity.clone(), identity, n));
    }
    let mut options = [0 as metis::idx_t; metis::METIS_NOPTIONS as usize];
    let mut nvtxs = graph.xadj.len() as metis::idx_t - 1;
    let mut perm = vec![0 as metis::idx_t; n];
    let mut iperm = vec![0 as metis::idx_t; n];
    // SAFETY: `options` has METIS_NOPTIONS entries; xadj has nvtxs + 1
    // nondecreasing offsets into adjncy, every neighbour lies in 0..nvtxs
    // and differs from its vertex (Adjacency::of_pattern), perm and iperm
    // have nvtxs entries, and vwgt may be null. METIS keeps no pointer past
    // the call.
    let status = unsafe {
        metis::METIS_SetDefaultOptions(options.as_mut_ptr());
        options[metis::moptions_et_METIS_OPTION_NUMBERING as usize] = 0;
        metis::METIS_NodeND(
            &mut nvtxs,
            graph.xadj.as_mut_ptr(),
            graph.adjncy.as_mut_ptr(),
            std::ptr::null_mut(),
            options.as_mut_ptr(),
            perm.as_mut_ptr(),
            iperm.as_mut_ptr(),
        )
    };
    match status {
        metis::rstatus_et_METIS_OK => {}
        metis::rstatus_et_METIS_ERROR_INPUT => return Err(OrderingError::Metis("invalid input")),
        metis::rstatus_et_METIS_ERROR_MEMORY => return Err(OrderingError::Metis("out of memory")),
        _ => return Err(OrderingError::Metis("unspecified error")),
    }
    // METIS's perm[k] is the original vertex in position k (faer's
    // forward). Both arrays are checked rather than trusted, so a bad
    // result is an error here and not a panic in faer.
    let forward: Box<[usize]> = perm.iter().map(|&v| v as usize).collect();
    let inverse: Box<[usize]> = iperm.iter().map(|&v| v as usize).collect();
    let consistent = forward.iter().enumerate().all(|(k, &v)| {
        v < n && inverse[v] == k // inverse[forward[k]] = k for all k ⇒ bijection
    });
    if !consistent {
        return Err(OrderingError::Metis("returned an invalid permutation"));
    }
    Ok(Perm::new_checked(forward, inverse, n))
}

/// Parts of at most this many vertices are not cut further: their own
/// order adds little fill, and smaller leaves only lengthen the recursion
/// (measured on 2D 1000² grids: leaves of 8 to 64 give the same factor
/// within 4 %, leaves of 256 give 25 % more).
const DISSECTION_LEAF: usize = 32;

/// Values closer to a part's median than this fraction of the part's width
/// count as on the median (far below any grid spacing, far above rounding).
const MEDIAN_TOLERANCE: f64 = 1e-9;

/// Parts larger than this try both kinds of direction (axes and, in the
/// plane, diagonals); smaller ones keep their parent's kind.
const TRIAL_PART: usize = 50_000;

/// Parts larger than this cut their two halves in parallel.
const PARALLEL_PART: usize = 20_000;

/// Nested dissection from positions: `points` holds `dimension`
/// coordinates per vertex of the pattern's graph (vertex v at
/// `points[v * dimension..(v + 1) * dimension]`).
///
/// A part is cut at the median of its widest coordinate: the vertices below
/// the median go left, the others right, and the right vertices with a left
/// neighbour are the separator, numbered after both sides, whose own parts
/// are ordered the same way first. Ties at the median go right (values
/// within 10⁻⁹ of the part's width count as ties, so that rounding in
/// centroids does not split a grid line), so on a grid the separator is
/// one grid line (2D) or plane (3D). The part's widest diagonal is tried
/// too (x ± y in the plane, x ± y ± z in space), and the
/// cut with the smaller separator is kept, the diagonal on a tie; parts of
/// at most 50 000 vertices try only the kind (axis or diagonal) their
/// parent was cut along. The five- and seven-point stencils step the
/// diagonals by ±1, so a diagonal line or plane separates them, with
/// 1/√2 or 1/√3 of the points per length or area of an axis-aligned one:
/// dissection along diagonals does half the work or less. On the nine-
/// and 27-point stencils a diagonal separator is two or three layers
/// thick, and the axes win. Parts of at most 32 vertices keep their
/// order.
///
/// Factorisation work Σ c_j² (supernodal, faer's default relaxation)
/// against AMD and METIS:
///
/// | pattern | geometric | axes only | AMD | METIS |
/// |---|---|---|---|---|
/// | five-point 1000² | 9.8·10⁹ | 1.96·10¹⁰ | 1.84·10¹⁰ | 1.42·10¹⁰ |
/// | nine-point 500² | 2.42·10⁹ | 2.42·10⁹ | 2.72·10⁹ | 2.42·10⁹ |
/// | seven-point 60³ | 1.12·10¹¹ | 2.85·10¹¹ | — | 2.21·10¹¹ |
/// | 27-point 40³ | 2.59·10¹⁰ | 2.59·10¹⁰ | — | 2.61·10¹⁰ |
///
/// The ordering takes 1/10 to 1/25 of METIS's time (see
/// [`crate::la::ordering::Ordering::Automatic`]); trying the diagonals costs
/// about 0.1 s at 10⁶ unknowns. The result depends only on the pattern and
/// the points.
///
/// ```
/// use faer::sparse::{SparseColMat, Triplet};
/// use hasse_solver::la::ordering::coordinate_dissection;
/// // The five-point pattern of a 9×9 grid, vertex i + 9 j at (i, j).
/// let m = 9;
/// let mut t = Vec::new();
/// let mut points = Vec::new();
/// for j in 0..m * m {
///     t.push(Triplet::new(j, j, 4.0));
///     if j % m + 1 < m { t.push(Triplet::new(j + 1, j, -1.0)); }
///     if j + m < m * m { t.push(Triplet::new(j + m, j, -1.0)); }
///     points.extend([(j % m) as f64, (j / m) as f64]);
/// }
/// let a = SparseColMat::<usize, f64>::try_new_from_triplets(m * m, m * m, &t).unwrap();
/// let perm = coordinate_dissection(a.symbolic(), &points, 2).unwrap();
/// // The diagonal x + y = 8 separates with as few points (9) as the line
/// // x = 4; ties go to the diagonal, numbered last.
/// let (forward, _) = perm.arrays();
/// assert!(forward[m * m - m..].iter().all(|&v| v % m + v / m == 8));
/// ```
pub fn coordinate_dissection(
    pattern: SymbolicSparseColMatRef<'_, usize>,
    points: &[f64],
    dimension: usize,
) -> Result<Perm<usize>, OrderingError> {
    dissect_with_leaf(pattern, points, dimension, DISSECTION_LEAF)
}

fn dissect_with_leaf(
    pattern: SymbolicSparseColMatRef<'_, usize>,
    points: &[f64],
    dimension: usize,
    leaf: usize,
) -> Result<Perm<usize>, OrderingError> {
    let n = pattern.ncols();
    if dimension == 0 || points.len() != n * dimension {
        return Err(OrderingError::PointCount {
            found: points.len(),
            unknowns: n,
            dimension,
        });
    }
    if let Some((index, &value)) = points.iter().enumerate().find(|(_, x)| !x.is_finite()) {
        return Err(OrderingError::NonFinitePoint { index, value });
    }
    let graph = Adjacency::of_pattern(pattern)?;
    let parts = Dissection {
        points,
        dimension,
        graph: &graph,
        side: (0..n).map(|_| AtomicU32::new(0)).collect(),
        cuts: AtomicU32::new(0),
        leaf: leaf.max(1),
    };
    // n ≤ i32::MAX (Adjacency::of_pattern checked it).
    let mut order: Vec<u32> = (0..n as u32).collect();
    parts.order(&mut order, None);
    let forward: Box<[usize]> = order.iter().map(|&v| v as usize).collect();
    let mut inverse = vec![0usize; n].into_boxed_slice();
    for (k, &v) in forward.iter().enumerate() {
        inverse[v] = k;
    }
    Ok(Perm::new_checked(forward, inverse, n))
}

/// The shared state of one coordinate dissection.
struct Dissection<'a> {
    points: &'a [f64],
    dimension: usize,
    graph: &'a Adjacency,
    /// `side[v]` = the number of the cut that put v on its left side.
    /// Parts being cut at the same time hold disjoint vertices, so a
    /// relaxed atomic is enough; a cut reads only marks it wrote itself.
    side: Vec<AtomicU32>,
    cuts: AtomicU32,
    leaf: usize,
}

impl Dissection<'_> {
    fn coordinate(&self, v: u32, axis: usize) -> f64 {
        self.points[v as usize * self.dimension + axis]
    }

    /// The value along `direction` of vertex v.
    fn key(&self, v: u32, direction: Direction) -> f64 {
        match direction {
            Direction::Axis(a) => self.coordinate(v, a),
            Direction::Diagonal(signs) => signs[..self.dimension]
                .iter()
                .enumerate()
                .map(|(a, &sign)| f64::from(sign) * self.coordinate(v, a))
                .sum(),
        }
    }

    /// The directions worth cutting `part` across, with the part's width
    /// along each: its widest axis and its widest diagonal (of
    /// [`diagonals_of`]), each the first of equally wide ones, or only
    /// those of `family`; none when every point of the part is at one
    /// position.
    fn directions(&self, part: &[u32], family: Option<Family>) -> Vec<(Direction, f64)> {
        let diagonals = diagonals_of(self.dimension);
        let axes = (family != Some(Family::Diagonals) || diagonals.is_empty())
            .then(|| self.widest(part, (0..self.dimension).map(Direction::Axis)));
        let diagonal = (family != Some(Family::Axes))
            .then(|| self.widest(part, diagonals.iter().map(|&s| Direction::Diagonal(s))));
        axes.flatten()
            .into_iter()
            .chain(diagonal.flatten())
            .collect()
    }

    /// The first of the widest `candidates` across `part` (extents in the
    /// units of the axes) with the width of its key; `None` when every one
    /// has width 0.
    fn widest(
        &self,
        part: &[u32],
        candidates: impl Iterator<Item = Direction>,
    ) -> Option<(Direction, f64)> {
        let mut best: Option<(Direction, f64, f64)> = None;
        for direction in candidates {
            let (lo, hi) = part
                .iter()
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &v| {
                    let x = self.key(v, direction);
                    (lo.min(x), hi.max(x))
                });
            let width = hi - lo;
            let scaled = width * direction.scale();
            if scaled > 0.0 && best.is_none_or(|(_, _, s)| scaled > s) {
                best = Some((direction, width, scaled));
            }
        }
        best.map(|(direction, width, _)| (direction, width))
    }

    /// Rearranges `part` into [left, right, separator] by the median along
    /// `direction`, across which the part is `width` wide; `None` (and
    /// `part` in some order) when no value lies below the largest.
    fn cut(&self, part: &mut [u32], direction: Direction, width: f64) -> Option<Cut> {
        let n = part.len();
        let x = |v: &u32| self.key(*v, direction);
        part.select_nth_unstable_by(n / 2, |a, b| x(a).total_cmp(&x(b)));
        let median = x(&part[n / 2]);
        // Points of one grid line differ by rounding (centroids, x ± y):
        // values within `near` of the median count as on it, else a line
        // is split point by point and its separator is two lines thick.
        let near = MEDIAN_TOLERANCE * width;
        // Below the median goes left; when the median is the smallest
        // value, at or below it.
        let mut left = partition(part, |v| x(v) < median - near);
        if left == 0 {
            left = partition(part, |v| x(v) <= median + near);
        }
        if left == 0 || left == n {
            return None;
        }
        let cut = self.cuts.fetch_add(1, Relaxed) + 1;
        for &v in &part[..left] {
            self.side[v as usize].store(cut, Relaxed);
        }
        let xadj = &self.graph.xadj;
        let touches_left = |v: u32| {
            let v = v as usize;
            self.graph.adjncy[xadj[v] as usize..xadj[v + 1] as usize]
                .iter()
                .any(|&w| self.side[w as usize].load(Relaxed) == cut)
        };
        // The separator to the end of the part.
        let mut end = n;
        let mut k = left;
        while k < end {
            if touches_left(part[k]) {
                end -= 1;
                part.swap(k, end);
            } else {
                k += 1;
            }
        }
        Some(Cut {
            direction,
            left,
            end,
            len: n,
        })
    }

    /// Rearranges `part` into [left, right, separator], each side ordered
    /// recursively, by the candidate cut with the smallest separator. Of
    /// equally small ones the later wins, a diagonal over an axis: on a
    /// five-point grid a square's diagonal separates as well as its middle
    /// line, and the triangles it leaves are cut by diagonals of half
    /// their legs, where a line along an axis would take 0.7 of them.
    fn order(&self, part: &mut [u32], family: Option<Family>) {
        let n = part.len();
        if n <= self.leaf {
            return;
        }
        let directions = self.directions(part, family);
        // Every candidate rearranges the part, so the best is in place only
        // when it was the last one tried; before that it is saved.
        let mut best: Option<(usize, Cut)> = None;
        let mut saved: Vec<u32> = Vec::new();
        for (k, &(direction, width)) in directions.iter().enumerate() {
            let Some(cut) = self.cut(part, direction, width) else {
                continue;
            };
            if best.is_none_or(|(_, b)| cut.separator() <= b.separator()) {
                best = Some((k, cut));
                if k + 1 < directions.len() {
                    saved.clear();
                    saved.extend_from_slice(part);
                }
            }
        }
        let Some((k, best)) = best else {
            return;
        };
        if k + 1 < directions.len() {
            part.copy_from_slice(&saved);
        }
        let (left_part, rest) = part.split_at_mut(best.left);
        let right_part = &mut rest[..best.end - best.left];
        let inherit = |side: &[u32]| (side.len() <= TRIAL_PART).then(|| best.direction.family());
        let (left_family, right_family) = (inherit(left_part), inherit(right_part));
        if n > PARALLEL_PART {
            rayon::join(
                || self.order(left_part, left_family),
                || self.order(right_part, right_family),
            );
        } else {
            self.order(left_part, left_family);
            self.order(right_part, right_family);
        }
    }
}

/// The diagonals a part is also cut across: of the unit square in the
/// plane (x ± y), of the unit cube in space (x ± y ± z). Each stencil step
/// along one axis moves them by ±1, so their level sets separate the
/// five- and seven-point graphs, with 1/√2 (lines) and 1/√3 (planes) of
/// the lattice points per length or area that an axis-aligned cut holds.
/// Face diagonals of the cube (x ± y) separate the seven-point graph too,
/// but with them the 40³ factor is 18 % larger than with the body
/// diagonals alone.
fn diagonals_of(dimension: usize) -> &'static [[i8; 3]] {
    match dimension {
        2 => &[[1, 1, 0], [1, -1, 0]],
        3 => &[[1, 1, 1], [1, 1, -1], [1, -1, 1], [1, -1, -1]],
        _ => &[],
    }
}

/// A direction a part is cut across: a coordinate axis, or a diagonal of
/// [`diagonals_of`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Direction {
    Axis(usize),
    /// Σ_a `signs[a]` x_a over the axes (zeros past the dimension).
    Diagonal([i8; 3]),
}

/// The kinds of [`Direction`]: a part of at most [`TRIAL_PART`] vertices
/// is cut across its parent's kind only.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Family {
    Axes,
    Diagonals,
}

impl Direction {
    /// 1 over the length of the key's gradient: a key's width times this
    /// is the part's extent along the direction.
    fn scale(self) -> f64 {
        match self {
            Direction::Axis(_) => 1.0,
            Direction::Diagonal(signs) => {
                1.0 / signs.iter().map(|&x| f64::from(x * x)).sum::<f64>().sqrt()
            }
        }
    }

    fn family(self) -> Family {
        match self {
            Direction::Axis(_) => Family::Axes,
            Direction::Diagonal(_) => Family::Diagonals,
        }
    }
}

/// A part rearranged by [`Dissection::cut`]: `[..left]` the left side,
/// `[left..end]` the right side, `[end..len]` the separator.
#[derive(Clone, Copy)]
struct Cut {
    direction: Direction,
    left: usize,
    end: usize,
    len: usize,
}

impl Cut {
    fn separator(&self) -> usize {
        self.len - self.end
    }
}

/// Moves the entries where `keep` holds to the front (their order is not
/// kept) and returns how many there are.
fn partition(part: &mut [u32], keep: impl Fn(&u32) -> bool) -> usize {
    let mut front = 0;
    for k in 0..part.len() {
        if keep(&part[k]) {
            part.swap(k, front);
            front += 1;
        }
    }
    front
}

#[cfg(test)]
mod tests {
    use super::*;
    use faer::sparse::{SparseColMat, SymbolicSparseColMat, Triplet};

    /// A symbolic pattern from (row, col) pairs.
    fn pattern(n: usize, entries: &[(usize, usize)]) -> SymbolicSparseColMat<usize> {
        let mut cols: Vec<Vec<usize>> = vec![Vec::new(); n];
        for &(i, j) in entries {
            cols[j].push(i);
        }
        let mut col_ptr = vec![0];
        let mut row_idx = Vec::new();
        for mut c in cols {
            c.sort_unstable();
            c.dedup();
            row_idx.extend(c);
            col_ptr.push(row_idx.len());
        }
        SymbolicSparseColMat::new_checked(n, n, col_ptr, None, row_idx)
    }

    fn assert_bijection(perm: &Perm<usize>, n: usize) {
        let (forward, inverse) = perm.arrays();
        assert_eq!((forward.len(), inverse.len()), (n, n));
        let mut seen = vec![false; n];
        for (k, &v) in forward.iter().enumerate() {
            assert!(v < n && !seen[v], "{forward:?}");
            seen[v] = true;
            assert_eq!(inverse[v], k);
        }
    }

    #[test]
    fn whole_and_one_triangle_patterns_give_the_same_graph() {
        // A 4-cycle 0-1-2-3-0 with a diagonal.
        let edges = [(1, 0), (2, 1), (3, 2), (3, 0)];
        let mut lower: Vec<(usize, usize)> = edges.to_vec();
        lower.extend((0..4).map(|i| (i, i)));
        let mut whole = lower.clone();
        whole.extend(edges.iter().map(|&(i, j)| (j, i)));
        let upper: Vec<(usize, usize)> = lower.iter().map(|&(i, j)| (j, i)).collect();
        let expected = Adjacency {
            xadj: vec![0, 2, 4, 6, 8],
            adjncy: vec![1, 3, 0, 2, 1, 3, 0, 2],
        };
        for entries in [&lower, &whole, &upper] {
            let p = pattern(4, entries);
            assert_eq!(Adjacency::of_pattern(p.as_ref()).unwrap(), expected);
        }
    }

    #[test]
    fn nested_dissection_is_a_bijection_on_small_and_disconnected_graphs() {
        // n = 0, n = 1, a diagonal-only pattern: the identity.
        for n in [0, 1, 5] {
            let diagonal: Vec<(usize, usize)> = (0..n).map(|i| (i, i)).collect();
            let perm = nested_dissection(pattern(n, &diagonal).as_ref()).unwrap();
            assert_bijection(&perm, n);
            assert_eq!(perm.arrays().0, (0..n).collect::<Vec<_>>().as_slice());
        }
        // Two paths of 150 vertices (large enough for METIS to bisect
        // rather than hand the graph to minimum degree), three isolated
        // vertices between and after them, a triangle.
        let mut entries = Vec::new();
        let n = 150 + 2 + 150 + 1 + 3;
        for i in 0..n {
            entries.push((i, i));
        }
        for i in 0..149 {
            entries.push((i + 1, i));
            entries.push((152 + i + 1, 152 + i));
        }
        entries.extend([(304, 303), (305, 304), (305, 303)]);
        let perm = nested_dissection(pattern(n, &entries).as_ref()).unwrap();
        assert_bijection(&perm, n);
    }

    #[test]
    fn a_path_is_ordered_with_its_middle_last() {
        // Nested dissection numbers the top-level separator last; an end
        // of a path separates nothing, so the last pivot is interior.
        // (Minimum degree would end on whichever vertex remains, often an
        // end.)
        let n = 400;
        let mut entries: Vec<(usize, usize)> = (0..n).map(|i| (i, i)).collect();
        entries.extend((0..n - 1).map(|i| (i + 1, i)));
        let p = pattern(n, &entries);
        let perm = nested_dissection(p.as_ref()).unwrap();
        assert_bijection(&perm, n);
        let last = perm.arrays().0[n - 1];
        assert!(last > 0 && last < n - 1, "last pivot {last}");
    }

    /// The pattern and points of the (2r+1)-point grid operator on an
    /// m^d grid (r = 1: nearest neighbours), vertex index
    /// i + m j (+ m² k) at (i, j, k).
    fn grid(m: usize, d: usize) -> (SymbolicSparseColMat<usize>, Vec<f64>) {
        let n = m.pow(d as u32);
        let mut entries: Vec<(usize, usize)> = (0..n).map(|v| (v, v)).collect();
        let mut points = Vec::new();
        for v in 0..n {
            for a in 0..d {
                let stride = m.pow(a as u32);
                let x = (v / stride) % m;
                points.push(x as f64);
                if x + 1 < m {
                    entries.push((v + stride, v));
                    entries.push((v, v + stride));
                }
            }
        }
        (pattern(n, &entries), points)
    }

    #[test]
    fn a_path_is_cut_at_its_medians() {
        // Seven vertices at x = 0..6, cut down to single vertices: the
        // median x = 3 splits {0, 1, 2} | {3, …, 6} and 3 is the right
        // vertex touching the left, so it is numbered last; {0, 1, 2} cuts
        // at x = 1 (separator 1), {4, 5, 6} at x = 5 (separator 5).
        let n = 7;
        let mut entries: Vec<(usize, usize)> = (0..n).map(|i| (i, i)).collect();
        entries.extend((0..n - 1).map(|i| (i + 1, i)));
        let points: Vec<f64> = (0..n).map(|i| i as f64).collect();
        let perm = dissect_with_leaf(pattern(n, &entries).as_ref(), &points, 1, 1).unwrap();
        assert_bijection(&perm, n);
        assert_eq!(perm.arrays().0, [0, 2, 1, 4, 6, 5, 3]);
    }

    /// The pattern and points of the 3^d-point operator on an m^d grid
    /// (every vertex coupled to those at most one step away along each
    /// axis: nine-point in 2D, Q1's 27-point in 3D), vertex index
    /// i + m j (+ m² k) at (i, j, k).
    fn box_grid(m: usize, d: usize) -> (SymbolicSparseColMat<usize>, Vec<f64>) {
        let n = m.pow(d as u32);
        let coordinates =
            |v: usize| -> Vec<usize> { (0..d).map(|a| (v / m.pow(a as u32)) % m).collect() };
        let mut entries = Vec::new();
        let mut points = Vec::new();
        for v in 0..n {
            let x = coordinates(v);
            points.extend(x.iter().map(|&c| c as f64));
            for w in 0..n {
                if coordinates(w)
                    .iter()
                    .zip(&x)
                    .all(|(&a, &b)| a.abs_diff(b) <= 1)
                {
                    entries.push((w, v));
                }
            }
        }
        (pattern(n, &entries), points)
    }

    #[test]
    fn a_grid_is_cut_along_its_middle_plane_then_across_the_halves() {
        // 7³ grid, 27-point pattern: all axes are as wide, so the first
        // cut is x = 3 (the first axis) and the plane x = 3 (49 points) is
        // numbered last. A diagonal plane would not do: a 27-point step
        // moves x + y + z by up to 3, so its separator is three planes
        // thick (37 + 36 + 33 points). The right part x ∈ {4, 5, 6} is
        // then widest in y (y and z tie, y comes first): its separator,
        // the 3 × 7 vertices with y = 3, comes just before the plane.
        let m = 7;
        let (p, points) = box_grid(m, 3);
        let n = m * m * m;
        let perm = coordinate_dissection(p.as_ref(), &points, 3).unwrap();
        assert_bijection(&perm, n);
        let forward = perm.arrays().0;
        let (x, y) = (|v: usize| v % m, |v: usize| (v / m) % m);
        let plane = &forward[n - m * m..];
        assert!(plane.iter().all(|&v| x(v) == 3), "{plane:?}");
        let right_cut = &forward[n - m * m - 3 * m..n - m * m];
        assert!(
            right_cut.iter().all(|&v| x(v) >= 4 && y(v) == 3),
            "{right_cut:?}"
        );
    }

    #[test]
    fn a_seven_point_grid_is_cut_along_a_body_diagonal_plane() {
        // 7³ grid, seven-point pattern: a step moves x + y + z by ±1, so
        // the plane x + y + z = 9 through the centre separates, with the
        // C(11, 2) − 3 C(4, 2) = 37 solutions of x + y + z = 9 in [0, 6]³
        // (inclusion–exclusion on the coordinates above 6), against 49 on
        // the plane x = 3. The four body diagonals are as wide; the first,
        // x + y + z, is cut, at its median 9, and numbered last.
        let m = 7;
        let (p, points) = grid(m, 3);
        let n = m * m * m;
        let perm = coordinate_dissection(p.as_ref(), &points, 3).unwrap();
        assert_bijection(&perm, n);
        let sum = |v: usize| v % m + (v / m) % m + v / (m * m);
        let plane = &perm.arrays().0[n - 37..];
        assert!(plane.iter().all(|&v| sum(v) == 9), "{plane:?}");
        assert_eq!((0..n).filter(|&v| sum(v) == 9).count(), 37);
    }

    /// The lattice points of the diamond |x| + |y| ≤ r with their
    /// five-point pattern (neighbours one unit apart along an axis).
    fn five_point_diamond(r: i64) -> (SymbolicSparseColMat<usize>, Vec<f64>, Vec<(i64, i64)>) {
        let sites: Vec<(i64, i64)> = (-r..=r)
            .flat_map(|y| (-r..=r).map(move |x| (x, y)))
            .filter(|(x, y)| x.abs() + y.abs() <= r)
            .collect();
        let index = |p: (i64, i64)| sites.iter().position(|&q| q == p);
        let mut entries = Vec::new();
        for (v, &(x, y)) in sites.iter().enumerate() {
            entries.push((v, v));
            for step in [(x + 1, y), (x - 1, y), (x, y + 1), (x, y - 1)] {
                if let Some(w) = index(step) {
                    entries.push((w, v));
                }
            }
        }
        let points = sites
            .iter()
            .flat_map(|&(x, y)| [x as f64, y as f64])
            .collect();
        (pattern(sites.len(), &entries), points, sites)
    }

    #[test]
    fn a_diamond_of_the_five_point_grid_is_cut_along_its_diagonal() {
        // On the diamond |x| + |y| ≤ 6 (85 points) the median of x is 0 and
        // the grid line x = 0 separates with its 13 points; the median of
        // x + y is 0 too, and the 7 points (k, −k), |k| ≤ 3, separate: the
        // five-point stencil steps x + y by ±1, so the line x + y = 0 is
        // crossed by no edge from x + y < 0 to x + y > 0, and each of its
        // points has a neighbour at x + y = −1. The smaller separator is
        // numbered last.
        let (p, points, sites) = five_point_diamond(6);
        assert_eq!(sites.len(), 85);
        let perm = coordinate_dissection(p.as_ref(), &points, 2).unwrap();
        assert_bijection(&perm, 85);
        let last: Vec<(i64, i64)> = perm.arrays().0[85 - 7..]
            .iter()
            .map(|&v| sites[v])
            .collect();
        assert!(last.iter().all(|&(x, y)| x + y == 0), "{last:?}");
    }

    #[test]
    fn rounding_in_the_points_does_not_split_a_grid_line() {
        // A 5³ grid (27-point pattern, cut along the axes as in
        // `a_grid_is_cut_along_its_middle_plane_then_across_the_halves`)
        // whose middle plane x = 2 holds 12 points at 2 and 13 one
        // ulp above (as rounding leaves centroids): sorted by x, positions
        // 50..62 are the plane's 2s and the median, position 62, is the
        // first value above 2. Split at that value, the plane would lose 12
        // points to the left side; within the tolerance they are one plane,
        // the separator of 25 points numbered last.
        let m = 5;
        let (p, mut points) = box_grid(m, 3);
        let above = f64::from_bits(2.0f64.to_bits() + 1);
        let mut on_plane = 0;
        for v in 0..m * m * m {
            if v % m == 2 {
                if on_plane >= 12 {
                    points[3 * v] = above;
                }
                on_plane += 1;
            }
        }
        let perm = coordinate_dissection(p.as_ref(), &points, 3).unwrap();
        let last = &perm.arrays().0[m * m * m - m * m..];
        assert!(last.iter().all(|&v| v % m == 2), "{last:?}");
    }

    #[test]
    fn a_grid_in_dissection_order_fills_less_than_its_band() {
        // In the natural order the factor of the five-point pattern of an
        // m × m grid fills its envelope: row i of L runs from its first
        // neighbour to the diagonal, i − 1 for the m − 1 rows of the first
        // grid row after vertex 0 and i − m for the n − m others, so L
        // holds n + (m − 1) + (n − m) m values. Nested dissection by grid
        // lines fills (31/8) n log₂ m to leading order (George 1973), 0.37
        // of the envelope at m = 63; the lower-order terms add a few per
        // cent at this size.
        use faer::sparse::linalg::cholesky::{
            factorize_symbolic_cholesky, CholeskySymbolicParams, SymmetricOrdering,
        };
        let m = 63;
        let n = m * m;
        let (p, points) = grid(m, 2);
        let lower_count = |order: SymmetricOrdering<'_, usize>| {
            let params = CholeskySymbolicParams {
                supernodal_flop_ratio_threshold:
                    faer::sparse::linalg::SupernodalThreshold::FORCE_SIMPLICIAL,
                ..Default::default()
            };
            factorize_symbolic_cholesky(p.as_ref(), faer::Side::Lower, order, params)
                .unwrap()
                .len_val()
        };
        let identity: Box<[usize]> = (0..n).collect();
        let natural = Perm::new_checked(identity.clone(), identity, n);
        let band = lower_count(SymmetricOrdering::Custom(natural.as_ref()));
        assert_eq!(band, n + (m - 1) + (n - m) * m);
        let perm = coordinate_dissection(p.as_ref(), &points, 2).unwrap();
        let dissected = lower_count(SymmetricOrdering::Custom(perm.as_ref()));
        let george = 31.0 / 8.0 * n as f64 * (m as f64).log2();
        assert!(
            2 * dissected < band && (dissected as f64) < 1.1 * george,
            "{dissected} against the band's {band} and George's {george}"
        );
    }

    #[test]
    fn coincident_points_and_leaf_sized_graphs_keep_their_order() {
        let (p, _) = grid(8, 2);
        let n = 64;
        let same = vec![0.5; 2 * n];
        let perm = coordinate_dissection(p.as_ref(), &same, 2).unwrap();
        assert_eq!(perm.arrays().0, (0..n).collect::<Vec<_>>().as_slice());
        // At most a leaf's worth of vertices: not cut at all.
        let (q, points) = grid(5, 2);
        let perm = coordinate_dissection(q.as_ref(), &points, 2).unwrap();
        assert_eq!(perm.arrays().0, (0..25).collect::<Vec<_>>().as_slice());
    }

    #[test]
    fn points_that_do_not_fit_are_refused() {
        let (p, points) = grid(4, 2);
        assert_eq!(
            coordinate_dissection(p.as_ref(), &points[1..], 2).unwrap_err(),
            OrderingError::PointCount {
                found: 31,
                unknowns: 16,
                dimension: 2
            }
        );
        let mut bad = points.clone();
        bad[7] = f64::NAN;
        assert!(matches!(
            coordinate_dissection(p.as_ref(), &bad, 2).unwrap_err(),
            OrderingError::NonFinitePoint { index: 7, .. }
        ));
        assert!(matches!(
            coordinate_dissection(p.as_ref(), &points, 0).unwrap_err(),
            OrderingError::PointCount { dimension: 0, .. }
        ));
    }

    #[test]
    fn non_square_patterns_are_refused() {
        let a = SparseColMat::<usize, f64>::try_new_from_triplets(2, 3, &[]).unwrap();
        assert_eq!(
            nested_dissection(a.symbolic()).unwrap_err(),
            OrderingError::NotSquare { rows: 2, cols: 3 }
        );
    }

    #[test]
    fn the_adjacency_of_a_lower_triangle_is_symmetric() {
        // Lower triangle of tridiag(−1, 2, −1), n = 3.
        let t = [
            (0, 0, 2.0),
            (1, 0, -1.0),
            (1, 1, 2.0),
            (2, 1, -1.0),
            (2, 2, 2.0),
        ];
        let t: Vec<_> = t.iter().map(|&(i, j, v)| Triplet::new(i, j, v)).collect();
        let a = SparseColMat::<usize, f64>::try_new_from_triplets(3, 3, &t).unwrap();
        let g = Adjacency::of_pattern(a.symbolic()).unwrap();
        assert_eq!(g.xadj, [0, 1, 3, 4]);
        assert_eq!(g.adjncy, [1, 0, 2, 1]);
    }

    #[test]
    fn nested_dissection_is_a_permutation_of_a_grid() {
        // The five-point Laplacian's pattern on a 20×20 grid.
        let m = 20;
        let mut t = Vec::new();
        for j in 0..m * m {
            t.push(Triplet::new(j, j, 4.0));
            if j % m + 1 < m {
                t.push(Triplet::new(j + 1, j, -1.0));
            }
            if j + m < m * m {
                t.push(Triplet::new(j + m, j, -1.0));
            }
        }
        let a = SparseColMat::<usize, f64>::try_new_from_triplets(m * m, m * m, &t).unwrap();
        let perm = nested_dissection(a.symbolic()).unwrap();
        let (forward, inverse) = perm.arrays();
        assert!((0..m * m).all(|k| inverse[forward[k]] == k));
    }

    #[test]
    fn coordinate_dissection_numbers_the_diagonal_separator_last() {
        // The five-point pattern of a 9×9 grid, vertex i + 9 j at (i, j).
        let m = 9;
        let mut t = Vec::new();
        let mut points = Vec::new();
        for j in 0..m * m {
            t.push(Triplet::new(j, j, 4.0));
            if j % m + 1 < m {
                t.push(Triplet::new(j + 1, j, -1.0));
            }
            if j + m < m * m {
                t.push(Triplet::new(j + m, j, -1.0));
            }
            points.extend([(j % m) as f64, (j / m) as f64]);
        }
        let a = SparseColMat::<usize, f64>::try_new_from_triplets(m * m, m * m, &t).unwrap();
        let perm = coordinate_dissection(a.symbolic(), &points, 2).unwrap();
        // The diagonal x + y = 8 separates with as few points (9) as the line
        // x = 4; ties go to the diagonal, numbered last.
        let (forward, _) = perm.arrays();
        assert!(forward[m * m - m..].iter().all(|&v| v % m + v / m == 8));
    }
}
