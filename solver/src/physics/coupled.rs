//! Two scalar fields coupled both ways: the linearised two-species
//! reaction–diffusion system
//!
//! ```text
//!     −∇·(D₁ ∇u) + a u − b v = f
//!     −∇·(D₂ ∇v) − b u + c v = g
//! ```
//!
//! with a, b, c functions of position. Each diffusion operator is a
//! canonical operator Aᵀ Ω A of its own method (FE, DEC, FV, FD: the
//! [`Diffusion`] problem of the field, with its boundary conditions), and
//! the reaction and coupling terms are lumped masses W (vertex volumes for
//! nodal fields, cell volumes for cell-centred ones), so the system is the
//! symmetric block matrix
//!
//! ```text
//!     [ K₁ + aW    −bW   ] [u]   [f]
//!     [  −bW     K₂ + cW ] [v] = [g]
//! ```
//!
//! assembled by [`BlockSystem`]. It is symmetric positive definite when
//! a > 0, c > 0 and ac > b² everywhere (the 2×2 reaction matrix is then
//! positive definite at every unknown); stronger coupling may still be
//! definite thanks to diffusion, or may not, in which case LLᵀ reports its
//! failure and LBLᵀ or LU solve it. Both fields must live on the same cells
//! (both nodal or both cell-centred) for the pointwise coupling.
//!
//! Dirichlet values of nodal fields are eliminated before the blocks are
//! placed: the canonical operator of a field keeps Ω and drops the fixed
//! columns of A (A_free), the known values move to the right-hand side,
//! so the blocks keep their canonical form and the system stays SPD.
//! [`CoupledSystem::update`] puts new coefficient values into the same
//! pattern, and the symbolic factorisation is reused.

use crate::la::direct::{Factorization, SolveError};
use crate::metric::mass::lumped_vertex_volumes;
use crate::metric::Location;
use crate::operator::block::{Block, BlockError, BlockSystem, Symmetry};
use crate::operator::{Canonical, CanonicalError};
use crate::physics::diffusion::{Diffusion, DiffusionError};
use crate::physics::ScalarFn;
use faer::sparse::{SparseColMat, SymbolicSparseColMat};
use hasse_complex::Complex;
use sprs::TriMat;

/// One of the two fields: a name and its diffusion problem (method, D,
/// source, boundary conditions).
#[derive(Clone)]
pub struct CoupledField {
    pub name: String,
    pub diffusion: Diffusion,
}

impl CoupledField {
    pub fn new(name: &str, diffusion: Diffusion) -> Self {
        Self {
            name: name.to_string(),
            diffusion,
        }
    }

    /// The cochain degree of the unknowns: 0 (nodal) or n (cell-centred).
    pub fn degree(&self, complex: &Complex) -> Result<usize, CoupledError> {
        match self.diffusion.location() {
            Location::Nodal => Ok(0),
            Location::CellCentred => Ok(complex.dim()),
            Location::Hybrid => Err(self.hybrid()),
        }
    }

    fn hybrid(&self) -> CoupledError {
        CoupledError::Unsupported {
            name: self.name.clone(),
            method: self.diffusion.method.name(),
        }
    }
}

/// The reaction coefficients a, c and the coupling coefficient b.
#[derive(Clone)]
pub struct Reaction {
    pub a: ScalarFn,
    pub b: ScalarFn,
    pub c: ScalarFn,
}

/// The coupled problem.
///
/// ```
/// use hasse_complex::generate::rectangle;
/// use hasse_solver::physics::coupled::{Coupled, CoupledField, Reaction};
/// use hasse_solver::physics::diffusion::Diffusion;
/// use hasse_solver::physics::BoundaryKind;
/// use hasse_solver::physics::Conductivity;
/// use hasse_solver::metric::Method;
/// use std::sync::Arc;
/// // Constant fields solve the reaction part alone: with u = 1, v = 2,
/// // f = a − 2b and g = −b + 2c.
/// let mesh = rectangle(4, 4, [0.0, 1.0], [0.0, 1.0]).unwrap();
/// let field = |value: f64, source: f64| {
///     Diffusion::new(Method::Fe, Conductivity::Scalar(Arc::new(|_| 1.0)), Arc::new(move |_| source))
///         .with_boundary("boundary", BoundaryKind::Dirichlet(Arc::new(move |_| value)))
/// };
/// let reaction = Reaction { a: Arc::new(|_| 3.0), b: Arc::new(|_| 1.0), c: Arc::new(|_| 2.0) };
/// let problem = Coupled::new(
///     CoupledField::new("u", field(1.0, 1.0)),
///     CoupledField::new("v", field(2.0, 3.0)),
///     reaction,
/// );
/// let solution = problem.solve(&mesh).unwrap();
/// assert!(solution.field("v").unwrap().iter().all(|&v| (v - 2.0).abs() < 1e-12));
/// ```
#[derive(Clone)]
pub struct Coupled {
    pub fields: [CoupledField; 2],
    pub reaction: Reaction,
    /// Direct factorisation (default LLᵀ).
    pub factorization: Factorization,
}

/// Why a coupled problem could not be assembled or solved.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum CoupledError {
    #[error("field '{name}': {source}")]
    Field {
        name: String,
        source: DiffusionError,
    },
    #[error("both fields are called '{name}'; give them different names")]
    SameName { name: String },
    #[error("field '{first}' is {first_location:?} and field '{second}' is {second_location:?}: the pointwise coupling needs both fields on the same cells (both nodal or both cell-centred methods)")]
    Locations {
        first: String,
        first_location: Location,
        second: String,
        second_location: Location,
    },
    #[error("field '{name}': the {method} method has cell and face unknowns; coupling needs nodal or cell-centred fields")]
    Unsupported { name: String, method: &'static str },
    #[error("coupling coefficient {what} is not finite at {location:?}")]
    NonFinite {
        what: &'static str,
        location: Vec<f64>,
    },
    #[error("{factorization} failed on the coupled system: {source} (the system is positive definite when a > 0, c > 0 and ac > b² everywhere; for stronger coupling use Factorization::Lblt or Factorization::Lu)")]
    Factorization {
        factorization: Factorization,
        source: SolveError,
    },
    #[error(transparent)]
    Block(#[from] BlockError),
    #[error(transparent)]
    Canonical(#[from] CanonicalError),
    #[error(transparent)]
    Solve(#[from] SolveError),
}

/// One field's share of the system.
#[derive(Clone, Debug)]
struct Part {
    /// Free unknowns, in order (their position is the block's index).
    free: Vec<usize>,
    /// Every unknown's prescribed value, if any.
    fixed: Vec<Option<f64>>,
    /// K restricted to the free unknowns, in canonical form.
    operator: Canonical,
    /// The field's right-hand side on its free unknowns, Dirichlet values
    /// of its own operator lifted.
    rhs: Vec<f64>,
}

/// The values of one assembly: both parts and the lumped reaction blocks.
struct Values {
    parts: [Part; 2],
    /// Diagonal of aW on field 0's free unknowns, of cW on field 1's.
    reaction: [Vec<f64>; 2],
    /// −bW at (free index in field 0, free index in field 1).
    coupling: Vec<(usize, usize, f64)>,
    /// Both fields' right-hand sides, coupling lifts included, stacked.
    rhs: Vec<f64>,
    location: Location,
}

/// The assembled block system, ready to solve and to take new values.
pub struct CoupledSystem {
    names: [String; 2],
    system: BlockSystem,
    parts: [Part; 2],
    rhs: Vec<f64>,
    location: Location,
}

/// Both fields on all their unknowns (Dirichlet values included).
#[derive(Clone, Debug)]
pub struct CoupledSolution {
    pub names: [String; 2],
    pub fields: [Vec<f64>; 2],
    /// Where both fields live.
    pub location: Location,
    /// Symbolic analyses made by the system so far (1 however often the
    /// values change).
    pub symbolic_analyses: usize,
}

impl CoupledSolution {
    /// The field called `name`.
    pub fn field(&self, name: &str) -> Option<&[f64]> {
        self.names
            .iter()
            .position(|n| n == name)
            .map(|i| self.fields[i].as_slice())
    }
}

/// A diagonal matrix with every entry stored, zeros included, so the
/// pattern does not depend on the values.
fn diagonal(values: &[f64]) -> SparseColMat<usize, f64> {
    let n = values.len();
    let symbolic =
        SymbolicSparseColMat::new_checked(n, n, (0..=n).collect(), None, (0..n).collect());
    SparseColMat::new(symbolic, values.to_vec())
}

/// A rows × cols matrix with one entry per column at most, from (row, col,
/// value) sorted by column, explicit zeros kept.
fn sparse(rows: usize, cols: usize, entries: &[(usize, usize, f64)]) -> SparseColMat<usize, f64> {
    let mut col_ptr = vec![0usize; cols + 1];
    for &(_, c, _) in entries {
        col_ptr[c + 1] += 1;
    }
    for c in 0..cols {
        col_ptr[c + 1] += col_ptr[c];
    }
    let row_idx = entries.iter().map(|e| e.0).collect();
    let values = entries.iter().map(|e| e.2).collect();
    SparseColMat::new(
        SymbolicSparseColMat::new_checked(rows, cols, col_ptr, None, row_idx),
        values,
    )
}

impl Coupled {
    /// The problem, solved by LLᵀ unless told otherwise.
    pub fn new(first: CoupledField, second: CoupledField, reaction: Reaction) -> Self {
        Self {
            fields: [first, second],
            reaction,
            factorization: Factorization::Llt,
        }
    }

    /// Assemble and solve once.
    pub fn solve(&self, complex: &Complex) -> Result<CoupledSolution, CoupledError> {
        self.assemble(complex)?.solve(self.factorization)
    }

    /// Assemble the block system (pattern and values).
    pub fn assemble(&self, complex: &Complex) -> Result<CoupledSystem, CoupledError> {
        let Values {
            parts,
            reaction,
            coupling,
            rhs,
            location,
        } = self.values(complex)?;
        let sizes = [parts[0].free.len(), parts[1].free.len()];
        let blocks: Vec<(usize, usize, Block)> = vec![
            (0, 0, parts[0].operator.clone().into()),
            (1, 1, parts[1].operator.clone().into()),
            (0, 0, diagonal(&reaction[0]).into()),
            (1, 1, diagonal(&reaction[1]).into()),
            (0, 1, sparse(sizes[0], sizes[1], &coupling).into()),
        ];
        let system = BlockSystem::new(&sizes, Symmetry::Symmetric, blocks)?;
        Ok(CoupledSystem {
            names: [self.fields[0].name.clone(), self.fields[1].name.clone()],
            system,
            parts,
            rhs,
            location,
        })
    }

    fn values(&self, complex: &Complex) -> Result<Values, CoupledError> {
        let [first, second] = &self.fields;
        if first.name == second.name {
            return Err(CoupledError::SameName {
                name: first.name.clone(),
            });
        }
        let locations = [first.diffusion.location(), second.diffusion.location()];
        for (field, location) in self.fields.iter().zip(locations) {
            if location == Location::Hybrid {
                return Err(field.hybrid());
            }
        }
        if locations[0] != locations[1] {
            return Err(CoupledError::Locations {
                first: first.name.clone(),
                first_location: locations[0],
                second: second.name.clone(),
                second_location: locations[1],
            });
        }
        let location = locations[0];
        let n = complex.dim();
        let (weights, points): (Vec<f64>, Vec<&[f64]>) = match location {
            Location::Nodal => (
                lumped_vertex_volumes(complex),
                (0..complex.cell_count(0))
                    .map(|v| complex.vertices().point(v))
                    .collect(),
            ),
            _ => (
                complex.measure(n).to_vec(),
                (0..complex.cell_count(n))
                    .map(|c| complex.centroid_of(n, c))
                    .collect(),
            ),
        };
        let coefficient = |f: &ScalarFn, what: &'static str| -> Result<Vec<f64>, CoupledError> {
            points
                .iter()
                .zip(&weights)
                .map(|(x, w)| {
                    let value = f(x);
                    if value.is_finite() {
                        Ok(value * w)
                    } else {
                        Err(CoupledError::NonFinite {
                            what,
                            location: x.to_vec(),
                        })
                    }
                })
                .collect()
        };
        let aw = coefficient(&self.reaction.a, "a")?;
        let bw = coefficient(&self.reaction.b, "b")?;
        let cw = coefficient(&self.reaction.c, "c")?;
        let parts = [part(first, complex)?, part(second, complex)?];

        let mut index = [
            vec![usize::MAX; weights.len()],
            vec![usize::MAX; weights.len()],
        ];
        for (p, idx) in parts.iter().zip(&mut index) {
            for (k, &u) in p.free.iter().enumerate() {
                idx[u] = k;
            }
        }
        let reaction = [
            parts[0].free.iter().map(|&u| aw[u]).collect(),
            parts[1].free.iter().map(|&u| cw[u]).collect(),
        ];
        let mut rhs0 = parts[0].rhs.clone();
        let mut rhs1 = parts[1].rhs.clone();
        let mut coupling = Vec::new();
        // The coupling −bW joins the same unknown of both fields; where one
        // side is fixed, its known value moves to the other's right-hand
        // side. Visiting the unknowns in order leaves the entries sorted by
        // column of the (0, 1) block, one per column, as `sparse` needs.
        for u in 0..weights.len() {
            match (parts[0].fixed[u], parts[1].fixed[u]) {
                (None, None) => coupling.push((index[0][u], index[1][u], -bw[u])),
                (None, Some(g)) => rhs0[index[0][u]] += bw[u] * g,
                (Some(g), None) => rhs1[index[1][u]] += bw[u] * g,
                (Some(_), Some(_)) => {}
            }
        }
        rhs0.extend(rhs1);
        Ok(Values {
            parts,
            reaction,
            coupling,
            rhs: rhs0,
            location,
        })
    }
}

/// Assemble one field's diffusion problem and restrict it to its free
/// unknowns.
fn part(field: &CoupledField, complex: &Complex) -> Result<Part, CoupledError> {
    let assembled = field
        .diffusion
        .assemble(complex)
        .map_err(|source| CoupledError::Field {
            name: field.name.clone(),
            source,
        })?;
    let fixed = assembled.fixed;
    let unknowns = fixed.len();
    let mut free_index = vec![usize::MAX; unknowns];
    let mut free = Vec::new();
    for (u, g) in fixed.iter().enumerate() {
        if g.is_none() {
            free_index[u] = free.len();
            free.push(u);
        }
    }
    let canonical = assembled.canonical;
    // b_free −= (Aᵀ Ω A g)_free with g the prescribed values (0 elsewhere).
    let known: Vec<f64> = fixed.iter().map(|g| g.unwrap_or(0.0)).collect();
    let lifted = canonical.apply(&known);
    let rhs = free.iter().map(|&u| assembled.rhs[u] - lifted[u]).collect();
    let a = canonical.incidence();
    let mut tri = TriMat::with_capacity((a.rows(), free.len()), a.nnz());
    for (&s, (r, u)) in a.iter() {
        if free_index[u] != usize::MAX {
            tri.add_triplet(r, free_index[u], s);
        }
    }
    let operator = Canonical::new(tri.to_csr(), canonical.metric().clone())?;
    Ok(Part {
        free,
        fixed,
        operator,
        rhs,
    })
}

impl CoupledSystem {
    /// The block system (its matrix, its count of symbolic analyses).
    pub fn block_system(&self) -> &BlockSystem {
        &self.system
    }

    /// The stacked right-hand side on the free unknowns of both fields.
    pub fn rhs(&self) -> &[f64] {
        &self.rhs
    }

    /// Put the values of `problem` on `complex` (new coefficients, sources
    /// or boundary values; the same mesh, methods and boundary tags) into
    /// the existing pattern; the next solve reuses the symbolic analysis.
    pub fn update(&mut self, complex: &Complex, problem: &Coupled) -> Result<(), CoupledError> {
        let Values {
            parts,
            reaction,
            coupling,
            rhs,
            location,
        } = problem.values(complex)?;
        let sizes = self.system.fields().to_vec();
        if location != self.location
            || parts[0].free != self.parts[0].free
            || parts[1].free != self.parts[1].free
        {
            // Other fixed unknowns or another location are another pattern.
            return Err(CoupledError::Block(BlockError::PatternChanged { block: 0 }));
        }
        self.system.set_block(0, parts[0].operator.clone())?;
        self.system.set_block(1, parts[1].operator.clone())?;
        self.system.set_block(2, diagonal(&reaction[0]))?;
        self.system.set_block(3, diagonal(&reaction[1]))?;
        self.system
            .set_block(4, sparse(sizes[0], sizes[1], &coupling))?;
        self.names = [
            problem.fields[0].name.clone(),
            problem.fields[1].name.clone(),
        ];
        self.parts = parts;
        self.rhs = rhs;
        Ok(())
    }

    /// Factorise the current values (reusing the symbolic analysis) and solve.
    pub fn solve(&mut self, factorization: Factorization) -> Result<CoupledSolution, CoupledError> {
        let factor = self.system.factorize(factorization).map_err(|e| match e {
            BlockError::Solve(source) => CoupledError::Factorization {
                factorization,
                source,
            },
            other => CoupledError::Block(other),
        })?;
        let x = factor.solve(&self.rhs)?;
        let offset = self.parts[0].free.len();
        let fields = [0, 1].map(|i| {
            let part = &self.parts[i];
            let mut values: Vec<f64> = part.fixed.iter().map(|g| g.unwrap_or(0.0)).collect();
            let start = if i == 0 { 0 } else { offset };
            for (k, &u) in part.free.iter().enumerate() {
                values[u] = x[start + k];
            }
            values
        });
        Ok(CoupledSolution {
            names: self.names.clone(),
            fields,
            location: self.location,
            symbolic_analyses: self.system.symbolic_analyses(),
        })
    }
}
