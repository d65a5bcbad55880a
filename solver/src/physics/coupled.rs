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
//! Every block is a canonical operator. Dirichlet values of nodal fields
//! are eliminated before the blocks are placed ([`FixedSplit`]): the
//! operator of a field keeps Ω and drops the fixed columns of A (A E, E the
//! selection of the free unknowns), the known values move to the
//! right-hand side, so the system stays SPD. The reaction blocks are
//! Eᵀ (aW) E and the coupling block E₁ᵀ (−bW) E₂, lumped masses over the
//! unknowns restricted to each field's free ones.
//! [`CoupledSystem::update`] puts new coefficient values into the same
//! pattern, and the symbolic factorisation is reused.

use crate::la::direct::{Factorization, SolveError};
use crate::la::fixed::FixedSplit;
use crate::metric::mass::lumped_vertex_volumes;
use crate::metric::Location;
use crate::operator::block::{Block, BlockError, BlockSystem, Symmetry};
use crate::operator::{BlockMetric, Canonical, CanonicalError};
use crate::physics::diffusion::{Diffusion, DiffusionError};
use crate::physics::regions::{RegionError, Regional};
use crate::physics::ScalarFn;
use hasse_complex::Complex;
use std::sync::Arc;

/// One of the two fields: a name and its diffusion problem (method, D,
/// source, boundary conditions).
///
/// ```
/// use hasse_complex::generate::rectangle;
/// use hasse_solver::metric::Method;
/// use hasse_solver::physics::coupled::{CoupledError, CoupledField};
/// use hasse_solver::physics::diffusion::Diffusion;
/// use hasse_solver::physics::Conductivity;
/// use std::sync::Arc;
/// let mesh = rectangle(2, 2, [0.0, 1.0], [0.0, 1.0]).unwrap();
/// let field = |method| {
///     CoupledField::new("u", Diffusion::new(method, Conductivity::Scalar(Arc::new(|_| 1.0)), Arc::new(|_| 0.0)))
/// };
/// assert_eq!(field(Method::Fe).degree(&mesh).unwrap(), 0); // on vertices
/// assert_eq!(field(Method::Fv).degree(&mesh).unwrap(), 2); // on squares
/// // Cell and face unknowns have no pointwise partner in the other field.
/// let hybrid = field(Method::FvMimetic).degree(&mesh);
/// assert!(matches!(hybrid, Err(CoupledError::Unsupported { method: "fv-mimetic", .. })));
/// ```
#[derive(Clone)]
pub struct CoupledField {
    /// The field's name, by which the solution gives it back
    /// ([`CoupledSolution::field`]) and output files store it.
    pub name: String,
    /// −∇·(D ∇·) = source with the field's method and boundary
    /// conditions; the reaction terms come from [`Reaction`].
    pub diffusion: Diffusion,
}

impl CoupledField {
    /// The field `name` with its diffusion problem.
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
///
/// ```
/// use hasse_complex::generate::rectangle;
/// use hasse_solver::metric::Method;
/// use hasse_solver::physics::coupled::{Coupled, CoupledField, Reaction};
/// use hasse_solver::physics::diffusion::Diffusion;
/// use hasse_solver::physics::Conductivity;
/// use std::sync::Arc;
/// // No boundary conditions (no flux anywhere) and constant sources: the
/// // fields are constants solving the reaction alone,
/// // 2u − v = 0, −u + 2v = 3, i.e. u = 1, v = 2.
/// let mesh = rectangle(4, 4, [0.0, 1.0], [0.0, 1.0]).unwrap();
/// let field = |name, source: f64| {
///     CoupledField::new(name, Diffusion::new(Method::Fv, Conductivity::Scalar(Arc::new(|_| 1.0)), Arc::new(move |_| source)))
/// };
/// let reaction = Reaction { a: Arc::new(|_| 2.0), b: Arc::new(|_| 1.0), c: Arc::new(|_| 2.0) };
/// let solution = Coupled::new(field("u", 0.0), field("v", 3.0), reaction).solve(&mesh).unwrap();
/// assert!(solution.field("u").unwrap().iter().all(|u| (u - 1.0).abs() < 1e-12));
/// assert!(solution.field("v").unwrap().iter().all(|v| (v - 2.0).abs() < 1e-12));
/// ```
#[derive(Clone)]
pub struct Reaction {
    /// a, the first field's own reaction rate (+a u in its equation).
    pub a: ScalarFn,
    /// b, the exchange: −b v in the first equation, −b u in the second.
    pub b: ScalarFn,
    /// c, the second field's own reaction rate (+c v in its equation).
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
    /// u and v, in the order of the block rows.
    pub fields: [CoupledField; 2],
    /// a, b and c.
    pub reaction: Reaction,
    /// Direct factorisation (default LLᵀ).
    pub factorization: Factorization,
    /// a, b or c per region of top cells, in place of the uniform ones
    /// ([`Coupled::with_reaction_by_region`]).
    pub reaction_by_region: Option<Arc<RegionalReaction>>,
}

/// Reaction coefficients given per region of top cells (tags): each that
/// is `Some` replaces the function of [`Reaction`]. On cell-centred fields
/// a cell's lumped mass takes its region's value at its centroid; on nodal
/// fields the vertex volume Σ_c |c|/#vertices(c) is summed cell by cell,
/// each share with its cell's region's value at the vertex, so a vertex on
/// a region boundary mixes the regions around it by volume.
#[derive(Clone, Default)]
pub struct RegionalReaction {
    /// a per region.
    pub a: Option<Regional<ScalarFn>>,
    /// b per region.
    pub b: Option<Regional<ScalarFn>>,
    /// c per region.
    pub c: Option<Regional<ScalarFn>>,
}

/// Why a coupled problem could not be assembled or solved.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum CoupledError {
    /// One field's own diffusion problem could not be assembled.
    #[error("field '{name}': {source}")]
    Field {
        /// The field.
        name: String,
        /// Why.
        source: DiffusionError,
    },
    /// The two fields have the same name, so the solution could not tell
    /// them apart.
    #[error("both fields are called '{name}'; give them different names")]
    SameName {
        /// The shared name.
        name: String,
    },
    /// One field is nodal and the other cell-centred: there is no
    /// pointwise coupling between vertices and cells.
    #[error("field '{first}' is {first_location:?} and field '{second}' is {second_location:?}: the pointwise coupling needs both fields on the same cells (both nodal or both cell-centred methods)")]
    Locations {
        /// The first field.
        first: String,
        /// Where its unknowns live.
        first_location: Location,
        /// The second field.
        second: String,
        /// Where its unknowns live.
        second_location: Location,
    },
    /// A field uses the hybrid mimetic method, whose face unknowns have
    /// no reaction term.
    #[error("field '{name}': the {method} method has cell and face unknowns; coupling needs nodal or cell-centred fields")]
    Unsupported {
        /// The field.
        name: String,
        /// Its method's name.
        method: &'static str,
    },
    /// a, b or c given per region does not fit the complex's tags.
    #[error("coupling coefficient {what}: {source}")]
    Region {
        /// `"a"`, `"b"` or `"c"`.
        what: &'static str,
        /// Why.
        source: RegionError,
    },
    /// a, b or c is NaN or ±∞ at an unknown.
    #[error("coupling coefficient {what} is not finite at {location:?}")]
    NonFinite {
        /// `"a"`, `"b"` or `"c"`.
        what: &'static str,
        /// The vertex or centroid where it was evaluated.
        location: Vec<f64>,
    },
    /// The factorisation failed, most likely because the coupling makes
    /// the system indefinite for LLᵀ.
    #[error("{factorization} failed on the coupled system: {source} (the system is positive definite when a > 0, c > 0 and ac > b² everywhere; for stronger coupling use Factorization::Lblt or Factorization::Lu)")]
    Factorization {
        /// The factorisation tried.
        factorization: Factorization,
        /// How it failed.
        source: SolveError,
    },
    /// The block system could not be built or updated; an update with
    /// other fixed unknowns or another location is
    /// [`BlockError::PatternChanged`].
    #[error(transparent)]
    Block(#[from] BlockError),
    /// A and Ω of a block do not fit together.
    #[error(transparent)]
    Canonical(#[from] CanonicalError),
    /// The solve with the factor failed.
    #[error(transparent)]
    Solve(#[from] SolveError),
}

/// One field's share of the system.
#[derive(Clone, Debug)]
struct Part {
    /// Free and fixed unknowns (the free ones' positions index the block).
    split: FixedSplit,
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
    /// Eᵀ (aW) E on field 0's free unknowns, Eᵀ (cW) E on field 1's.
    reaction: [Canonical; 2],
    /// E₀ᵀ (−bW) E₁.
    coupling: Canonical,
    /// Both fields' right-hand sides, coupling lifts included, stacked.
    rhs: Vec<f64>,
    location: Location,
}

/// The assembled block system, ready to solve and to take new values.
///
/// ```
/// use hasse_complex::generate::rectangle;
/// use hasse_solver::la::direct::Factorization;
/// use hasse_solver::metric::Method;
/// use hasse_solver::physics::coupled::{Coupled, CoupledField, Reaction};
/// use hasse_solver::physics::diffusion::Diffusion;
/// use hasse_solver::physics::Conductivity;
/// use std::sync::Arc;
/// let mesh = rectangle(4, 4, [0.0, 1.0], [0.0, 1.0]).unwrap();
/// let field = |name, source: f64| {
///     CoupledField::new(name, Diffusion::new(Method::Fe, Conductivity::Scalar(Arc::new(|_| 1.0)), Arc::new(move |_| source)))
/// };
/// let with_c = |c: f64| {
///     let reaction = Reaction { a: Arc::new(|_| 2.0), b: Arc::new(|_| 1.0), c: Arc::new(move |_| c) };
///     Coupled::new(field("u", 0.0), field("v", 3.0), reaction)
/// };
/// let mut system = with_c(2.0).assemble(&mesh).unwrap();
/// let first = system.solve(Factorization::Llt).unwrap();
/// assert!((first.field("v").unwrap()[0] - 2.0).abs() < 1e-12);
/// // c = 5: 2u − v = 0, −u + 5v = 3, so v = 2/3, on the same pattern.
/// system.update(&mesh, &with_c(5.0)).unwrap();
/// let second = system.solve(Factorization::Llt).unwrap();
/// assert!((second.field("v").unwrap()[0] - 2.0 / 3.0).abs() < 1e-12);
/// assert_eq!(second.symbolic_analyses, 1);
/// ```
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
    /// The fields' names, in the order of [`Coupled::fields`].
    pub names: [String; 2],
    /// Their values, in the same order, on every vertex (nodal) or top
    /// cell (cell-centred).
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

impl Coupled {
    /// The problem, solved by LLᵀ unless told otherwise.
    pub fn new(first: CoupledField, second: CoupledField, reaction: Reaction) -> Self {
        Self {
            fields: [first, second],
            reaction,
            factorization: Factorization::Llt,
            reaction_by_region: None,
        }
    }

    /// The same problem with reaction coefficients per region.
    pub fn with_reaction_by_region(mut self, reaction: RegionalReaction) -> Self {
        self.reaction_by_region = Some(Arc::new(reaction));
        self
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
        let sizes = [parts[0].split.free().len(), parts[1].split.free().len()];
        let [first_reaction, second_reaction] = reaction;
        let blocks: Vec<(usize, usize, Block)> = vec![
            (0, 0, parts[0].operator.clone().into()),
            (1, 1, parts[1].operator.clone().into()),
            (0, 0, first_reaction.into()),
            (1, 1, second_reaction.into()),
            (0, 1, coupling.into()),
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
        // A coefficient per region: its lumped mass share by share.
        let regional = |f: &Regional<ScalarFn>, what: &'static str| {
            let pieces = f
                .per_cell(complex)
                .map_err(|source| CoupledError::Region { what, source })?;
            let volume = complex.measure(n);
            let mut out = vec![0.0; weights.len()];
            for (c, f) in pieces.iter().enumerate() {
                let unknowns: &[usize] = match location {
                    Location::Nodal => complex.cell_vertices(n, c),
                    _ => std::slice::from_ref(&c),
                };
                let share = volume[c] / unknowns.len() as f64;
                for &u in unknowns {
                    let x = points[u];
                    let value = f(x);
                    if !value.is_finite() {
                        return Err(CoupledError::NonFinite {
                            what,
                            location: x.to_vec(),
                        });
                    }
                    out[u] += share * value;
                }
            }
            Ok(out)
        };
        let by_region = self.reaction_by_region.as_deref();
        let pick = |uniform: &ScalarFn,
                    per_region: Option<&Regional<ScalarFn>>,
                    what: &'static str| match per_region {
            Some(f) => regional(f, what),
            None => coefficient(uniform, what),
        };
        let aw = pick(&self.reaction.a, by_region.and_then(|r| r.a.as_ref()), "a")?;
        let bw = pick(&self.reaction.b, by_region.and_then(|r| r.b.as_ref()), "b")?;
        let cw = pick(&self.reaction.c, by_region.and_then(|r| r.c.as_ref()), "c")?;
        let parts = [part(first, complex)?, part(second, complex)?];

        let [first_selection, second_selection] = [0, 1].map(|i| parts[i].split.selection());
        let reaction = [
            Canonical::new(first_selection.clone(), BlockMetric::from_weights(aw))?,
            Canonical::new(second_selection.clone(), BlockMetric::from_weights(cw))?,
        ];
        let minus_bw: Vec<f64> = bw.iter().map(|v| -v).collect();
        let coupling = Canonical::coupling(
            first_selection,
            BlockMetric::from_weights(minus_bw),
            second_selection,
        )?;
        let mut rhs0 = parts[0].rhs.clone();
        let mut rhs1 = parts[1].rhs.clone();
        // The coupling −bW joins the same unknown of both fields; where one
        // side is fixed, its known value moves to the other's right-hand
        // side.
        let index = |p: usize, u: usize| parts[p].split.free_index(u);
        for u in 0..weights.len() {
            match (parts[0].fixed[u], parts[1].fixed[u]) {
                (None, Some(g)) => rhs0[index(0, u).unwrap_or(0)] += bw[u] * g,
                (Some(g), None) => rhs1[index(1, u).unwrap_or(0)] += bw[u] * g,
                _ => {}
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
    let split = FixedSplit::new(&fixed);
    let canonical = assembled.canonical;
    // b_free −= (Aᵀ Ω A g)_free with g the prescribed values (0 elsewhere).
    let known = split.lift(&[], &fixed);
    let lifted = canonical.apply(&known);
    let rhs = split
        .free()
        .iter()
        .map(|&u| assembled.rhs[u] - lifted[u])
        .collect();
    let operator = Canonical::new(
        split.restrict_columns(canonical.incidence()),
        canonical.metric().clone(),
    )?;
    Ok(Part {
        split,
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
        if location != self.location
            || parts[0].split != self.parts[0].split
            || parts[1].split != self.parts[1].split
        {
            // Other fixed unknowns or another location are another pattern.
            return Err(CoupledError::Block(BlockError::PatternChanged { block: 0 }));
        }
        self.system.set_block(0, parts[0].operator.clone())?;
        self.system.set_block(1, parts[1].operator.clone())?;
        let [first_reaction, second_reaction] = reaction;
        self.system.set_block(2, first_reaction)?;
        self.system.set_block(3, second_reaction)?;
        self.system.set_block(4, coupling)?;
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
        let offset = self.parts[0].split.free().len();
        let (first, second) = x.split_at(offset);
        let fields = [first, second].map(|x| x.to_vec());
        let fields = [0, 1].map(|i| self.parts[i].split.lift(&fields[i], &self.parts[i].fixed));
        Ok(CoupledSolution {
            names: self.names.clone(),
            fields,
            location: self.location,
            symbolic_analyses: self.system.symbolic_analyses(),
        })
    }
}
