//! The problem specifications of a case: one struct per `problem.kind`,
//! their coefficients, boundary conditions and time stepping, as read from
//! the file and before any mesh exists.

use super::expr::Expression;
use super::{CohomologySpec, DecompositionSpec, ElasticitySpec, HodgeSpec, MaterialSpec};
use crate::metric::Method;
use std::ops::Range;
use std::path::PathBuf;

/// A diffusion coefficient: scalar or a full symmetric tensor, each entry
/// an expression.
///
/// ```
/// use hasse_solver::frontend::case::{Case, Coefficient, Problem};
/// let text = r#"
/// [mesh]
/// generator = "rectangle"
/// n = [2, 2]
/// [problem]
/// method = "fe"
/// conductivity = [["1 + x", 0.5], [0.5, 2]]
/// "#;
/// let case = Case::from_text("k.toml", text, &[]).unwrap();
/// let Some(Coefficient::Tensor(rows)) = case.problem.coefficient() else { panic!() };
/// assert_eq!(rows[0][0].eval(&[1.0, 0.0], 0.0), 2.0);
/// assert_eq!(rows[1][0].text(), "0.5");
/// // Without the key, K = 1.
/// let case = Case::from_text("k.toml", &text.replace("conductivity", "# "), &[]).unwrap();
/// let Some(Coefficient::Scalar(k)) = case.problem.coefficient() else { panic!() };
/// assert_eq!(k.eval(&[0.3, 0.7], 0.0), 1.0);
/// ```
///
/// Given per region, a scalar coefficient is one expression per region
/// ([`Expression::regions`]); when some region is a tensor
/// (`{ layer = [[1, 0], [0, "10 + y"]], default = 1 }`, a scalar region s
/// standing for s·I) it is a `Tensor` whose entries are each given per
/// region, all with the same regions in the same order (an off-diagonal
/// entry that is 0 in every region stays the constant 0).
/// [`Coefficient::by_region`] gives the coefficient of each region.
#[derive(Clone, Debug)]
pub enum Coefficient {
    /// K = λ(x) I.
    Scalar(Expression),
    /// Rows of the tensor (d × d, d the embedding dimension).
    Tensor(Vec<Vec<Expression>>),
}

impl Coefficient {
    /// Whether any entry names the time `t`.
    ///
    /// ```
    /// use hasse_solver::frontend::case::{Case, Coefficient};
    /// let text = "[mesh]\ngenerator = \"rectangle\"\nn = [2, 2]\n[problem]\nmethod = \"fe\"\nconductivity = [[\"1 + t\", 0], [0, 1]]\n";
    /// let case = Case::from_text("k.toml", text, &[]).unwrap();
    /// assert!(case.problem.coefficient().unwrap().uses_time());
    /// ```
    pub fn uses_time(&self) -> bool {
        match self {
            Coefficient::Scalar(e) => e.uses_time(),
            Coefficient::Tensor(rows) => rows.iter().flatten().any(Expression::uses_time),
        }
    }

    /// An expression given per region whose regions are the coefficient's
    /// (what the mesh's tags must cover); `None` for one coefficient
    /// everywhere.
    pub fn regional_expression(&self) -> Option<&Expression> {
        match self {
            Coefficient::Scalar(e) => e.regions().map(|_| e),
            Coefficient::Tensor(rows) => rows.iter().flatten().find(|e| e.regions().is_some()),
        }
    }

    /// The coefficient of each region, each one expression (or tensor of
    /// expressions) for the whole region; `None` for a coefficient that is
    /// not given per region.
    ///
    /// ```
    /// use hasse_solver::frontend::case::{Case, Coefficient};
    /// let text = r#"
    /// [mesh]
    /// generator = "rectangle"
    /// n = [2, 2]
    /// [regions]
    /// layer = "y > 0.5"
    /// [problem]
    /// method = "fe"
    /// conductivity = { layer = [[1, 0], [0, "10 + y"]], default = 3 }
    /// "#;
    /// let case = Case::from_text("k.toml", text, &[]).unwrap();
    /// let regions = case.problem.coefficient().unwrap().by_region().unwrap();
    /// let Coefficient::Tensor(layer) = &regions.pieces()[0].1 else { panic!() };
    /// assert_eq!(layer[1][1].eval(&[0.0, 1.0], 0.0), 11.0);
    /// assert_eq!(layer[0][1].eval(&[0.0, 1.0], 0.0), 0.0);
    /// // The scalar default 3 is 3·I.
    /// let Some(Coefficient::Tensor(default)) = regions.default() else { panic!() };
    /// assert_eq!((default[0][0].eval(&[], 0.0), default[1][0].eval(&[], 0.0)), (3.0, 0.0));
    /// ```
    pub fn by_region(&self) -> Option<crate::physics::regions::Regional<Coefficient>> {
        use crate::physics::regions::Regional;
        match self {
            Coefficient::Scalar(e) => {
                let regions = e.regions()?;
                Some(Regional::new(
                    regions
                        .pieces
                        .iter()
                        .map(|(name, piece)| (name.clone(), Coefficient::Scalar(piece.clone())))
                        .collect(),
                    regions.default.clone().map(Coefficient::Scalar),
                ))
            }
            Coefficient::Tensor(rows) => {
                let regions = self.regional_expression()?.regions()?;
                // Entry (i, j) in piece k (the default for k = #regions):
                // the entry's own piece, or the entry itself where it is
                // one expression for all regions.
                let piece = |k: usize| -> Option<Coefficient> {
                    let mut tensor = Vec::with_capacity(rows.len());
                    for row in rows {
                        let mut out = Vec::with_capacity(row.len());
                        for e in row {
                            out.push(match e.regions() {
                                None => e.clone(),
                                Some(r) => match r.pieces.get(k) {
                                    Some((_, piece)) => piece.clone(),
                                    None => r.default.clone()?,
                                },
                            });
                        }
                        tensor.push(out);
                    }
                    Some(Coefficient::Tensor(tensor))
                };
                let pieces = regions
                    .pieces
                    .iter()
                    .enumerate()
                    .map(|(k, (name, _))| Some((name.clone(), piece(k)?)))
                    .collect::<Option<Vec<_>>>()?;
                let default = match &regions.default {
                    Some(_) => Some(piece(regions.pieces.len())?),
                    None => None,
                };
                Some(Regional::new(pieces, default))
            }
        }
    }
}

/// A boundary condition of the case: one `[[boundary]]` table.
///
/// ```
/// use hasse_solver::frontend::case::{BoundaryKindSpec, Case};
/// let text = r#"
/// [mesh]
/// generator = "rectangle"
/// n = [2, 2]
/// [problem]
/// method = "fe"
/// [[boundary]]
/// tag = "boundary"
/// type = "dirichlet"
/// value = 0
/// [[boundary]]
/// tag = "xmax"
/// type = "robin"
/// alpha = 2
/// value = "y"
/// "#;
/// let case = Case::from_text("bc.toml", text, &[]).unwrap();
/// let boundary = case.problem.boundary();
/// assert_eq!((boundary[0].tag.as_str(), boundary[1].tag.as_str()), ("boundary", "xmax"));
/// let BoundaryKindSpec::Robin { alpha, value } = &boundary[1].kind else { panic!() };
/// assert_eq!((alpha.eval(&[1.0, 0.5], 0.0), value.eval(&[1.0, 0.5], 0.0)), (2.0, 0.5));
/// ```
#[derive(Clone, Debug)]
pub struct BoundarySpec {
    /// Tag of (n−1)-cells in the mesh (`tag`).
    pub tag: String,
    /// The condition (`type`, `value`, `alpha`).
    pub kind: BoundaryKindSpec,
    /// Where the `tag` key is, for messages about the mesh.
    pub(crate) tag_span: Option<Range<usize>>,
    pub(crate) key: String,
}

/// Kind and data of a boundary condition (the meaning of each is that of
/// [`BoundaryKind`](crate::physics::BoundaryKind)).
///
/// ```
/// use hasse_solver::frontend::case::{BoundaryKindSpec, Case};
/// let text = r#"
/// [mesh]
/// generator = "rectangle"
/// n = [2, 2]
/// [problem]
/// method = "fv"
/// [[boundary]]
/// tag = "ymin"
/// type = "neumann"
/// value = "-x"
/// "#;
/// let case = Case::from_text("bc.toml", text, &[]).unwrap();
/// let BoundaryKindSpec::Neumann(g) = &case.problem.boundary()[0].kind else { panic!() };
/// assert_eq!(g.eval(&[0.25, 0.0], 0.0), -0.25);
/// ```
#[derive(Clone, Debug)]
pub enum BoundaryKindSpec {
    /// `type = "dirichlet"`: u = `value` (Darcy: `type = "pressure"`).
    Dirichlet(Expression),
    /// `type = "neumann"`: K∇u·n = `value`, n outward (Darcy:
    /// `type = "flux"`, the outward normal velocity).
    Neumann(Expression),
    /// `type = "robin"`: K∇u·n + α u = `value`.
    Robin {
        /// `alpha`: α > 0, constant in time.
        alpha: Expression,
        /// `value`: g.
        value: Expression,
    },
}

/// The metric of a gradient problem (the face-to-face Ω of the thesis's
/// Ch. 6), `[problem.metric]`.
///
/// ```
/// use hasse_solver::frontend::case::{Case, GradientMetric, Problem};
/// let text = r#"
/// [mesh]
/// generator = "rectangle"
/// n = [2, 2]
/// [problem]
/// kind = "gradient"
/// field = "x"
/// metric = { type = "diagonal", value = 2 }
/// "#;
/// let case = Case::from_text("g.toml", text, &[]).unwrap();
/// let Problem::Gradient(spec) = &case.problem else { panic!() };
/// assert_eq!(spec.metric, GradientMetric::Diagonal(2.0));
/// ```
#[derive(Clone, Debug, PartialEq)]
pub enum GradientMetric {
    /// `type = "diagonal"`: Ω = σ I with σ = `value`.
    Diagonal(f64),
    /// `type = "file"`: Ω read from a file of `row column value` triplets
    /// (face ids of the mesh, 0-based), times `scale`.
    File {
        /// The file, relative to the case file's directory.
        path: PathBuf,
        /// The factor applied to every value (default 1).
        scale: f64,
    },
    /// `type = "two-point"`: σ_F = 1 / d_F, d_F the distance between the
    /// centroids on either side of F.
    TwoPoint,
}

/// −∇·(K∇u) = f with boundary conditions (`kind = "diffusion"`, the
/// default).
///
/// ```
/// use hasse_solver::frontend::case::{Case, Problem};
/// use hasse_solver::metric::Method;
/// let text = r#"
/// [mesh]
/// generator = "rectangle"
/// n = [2, 2]
/// cells = "simplex"
/// [problem]
/// method = "fv"
/// source = "2 * x"
/// cell_points = "circumcentres"
/// "#;
/// let case = Case::from_text("d.toml", text, &[]).unwrap();
/// let Problem::Diffusion(spec) = &case.problem else { panic!() };
/// assert_eq!(spec.method, Method::Fv);
/// assert_eq!(spec.source.eval(&[0.5], 0.0), 1.0);
/// assert!(spec.circumcentres && spec.boundary.is_empty());
/// ```
#[derive(Clone, Debug)]
pub struct DiffusionSpec {
    /// `problem.method`.
    pub method: Method,
    /// K (`problem.conductivity`, default 1).
    pub conductivity: Coefficient,
    /// f (`problem.source`, default 0).
    pub source: Expression,
    /// The `[[boundary]]` tables, in order; untagged faces are insulated.
    pub boundary: Vec<BoundarySpec>,
    /// Two-point flux with unknowns at circumcentres instead of centroids
    /// (`problem.cell_points = "circumcentres"`).
    pub circumcentres: bool,
    /// The largest relative imbalance of pure-Neumann data that is
    /// projected away (`problem.neumann_tolerance`, default 1e-2;
    /// `problem.neumann = "project"` makes it infinite).
    pub neumann_tolerance: f64,
    /// r(u, x) of −∇·(k∇u) + r = f (`problem.reaction`); with it, or with
    /// a conductivity that uses `u`, the problem is nonlinear.
    pub reaction: Option<Expression>,
}

impl DiffusionSpec {
    /// Whether the problem is solved by Newton's method: the conductivity
    /// uses the solution `u`, or there is a reaction term.
    ///
    /// ```
    /// use hasse_solver::frontend::case::{Case, Problem};
    /// let text = "[mesh]\ngenerator = \"rectangle\"\nn = [2, 2]\n[problem]\nmethod = \"fv\"\nconductivity = \"1 + u^2\"\n";
    /// let case = Case::from_text("n.toml", text, &[]).unwrap();
    /// let Problem::Diffusion(spec) = &case.problem else { panic!() };
    /// assert!(spec.is_nonlinear());
    /// ```
    pub fn is_nonlinear(&self) -> bool {
        self.reaction.is_some()
            || matches!(&self.conductivity, Coefficient::Scalar(k) if k.uses_solution())
    }
}

/// g = Ω δ f: a cell field's "normal gradient" as a face cochain
/// (`kind = "gradient"`; see [`GradientMetric`] for a case).
#[derive(Clone, Debug)]
pub struct GradientSpec {
    /// The field sampled at top-cell centroids (`problem.field`).
    pub field: Expression,
    /// Ω (`problem.metric`).
    pub metric: GradientMetric,
}

/// The time stepping of a transient problem (`[time]`; see [`HeatSpec`]
/// for a case).
#[derive(Clone, Debug, PartialEq)]
pub struct TimeSpec {
    /// Constant step Δt > 0.
    pub dt: f64,
    /// Number of steps taken from t₀.
    pub steps: usize,
    /// Start time t₀.
    pub start: f64,
    /// θ of the θ-scheme: 1 backward Euler, ½ Crank–Nicolson.
    pub theta: f64,
    /// Every how many steps a level is written (t₀ and the last always are).
    pub save_every: usize,
    /// `end`, when the case gives it instead of `steps` (a restarted run
    /// then stops at it).
    pub end: Option<f64>,
    /// `adaptive = { tolerance }`: adaptive step sizes from `dt` on, with
    /// this relative local error per step; the run ends at t₀ + steps·dt.
    pub adaptive: Option<f64>,
}

/// ∂u/∂t − ∇·(K∇u) = f(x, t) from u(x, t₀) = `initial` (`kind = "heat"`).
///
/// ```
/// use hasse_solver::frontend::case::{Case, Problem, TimeSpec};
/// let text = r#"
/// [mesh]
/// generator = "rectangle"
/// n = [2, 2]
/// [problem]
/// kind = "heat"
/// method = "fe"
/// source = "t"
/// initial = "x * y"
/// [time]
/// dt = 0.25
/// end = 1.0
/// scheme = "crank-nicolson"
/// "#;
/// let case = Case::from_text("h.toml", text, &[]).unwrap();
/// let Problem::Heat(spec) = &case.problem else { panic!() };
/// // `end` is turned into a whole number of steps.
/// let time = TimeSpec { dt: 0.25, steps: 4, start: 0.0, theta: 0.5, save_every: 1, end: Some(1.0), adaptive: None };
/// assert_eq!(spec.time, time);
/// assert!(spec.source.uses_time() && !spec.initial.uses_time());
/// ```
#[derive(Clone, Debug)]
pub struct HeatSpec {
    /// `problem.method`, nodal or cell-centred.
    pub method: Method,
    /// K (`problem.conductivity`, default 1), constant in time; a scalar
    /// k(u, x) makes the problem nonlinear.
    pub conductivity: Coefficient,
    /// r(u, x) (`problem.reaction`), which makes the problem nonlinear.
    pub reaction: Option<Expression>,
    /// f(x, t).
    pub source: Expression,
    /// u(x, t₀).
    pub initial: Expression,
    /// Values may depend on t; a Robin α may not.
    pub boundary: Vec<BoundarySpec>,
    /// `[time]`.
    pub time: TimeSpec,
    /// `initial = { from = "run.h5", level = … }`: u⁰ is a saved level of
    /// an earlier run on the same mesh, and t₀ its time.
    pub restart: Option<RestartSpec>,
}

/// Where a restarted heat run takes its initial temperature.
#[derive(Clone, Debug, PartialEq)]
pub struct RestartSpec {
    /// The earlier run's HDF5 output, relative to the case file's
    /// directory.
    pub from: PathBuf,
    /// The saved level (`None`: the last one).
    pub level: Option<usize>,
}

/// Mixed Darcy: u = −K∇p, ∇·u = f, flux on faces and pressure on cells.
///
/// Boundary conditions reuse [`BoundarySpec`]: `type = "pressure"` is read
/// as [`BoundaryKindSpec::Dirichlet`] (p given), `type = "flux"` as
/// [`BoundaryKindSpec::Neumann`] with the value the outward normal velocity
/// u·n. Boundary faces in no tag are no-flow.
///
/// ```
/// use hasse_solver::frontend::case::{BoundaryKindSpec, Case, Problem};
/// use hasse_solver::metric::fv::FluxMass;
/// let text = r#"
/// [mesh]
/// generator = "rectangle"
/// n = [2, 2]
/// [problem]
/// kind = "darcy"
/// method = "mimetic"
/// permeability = 0.5
/// [[boundary]]
/// tag = "xmin"
/// type = "flux"
/// value = -1
/// [[boundary]]
/// tag = "xmax"
/// type = "pressure"
/// value = 0
/// "#;
/// let case = Case::from_text("darcy.toml", text, &[]).unwrap();
/// let Problem::Darcy(spec) = &case.problem else { panic!() };
/// assert_eq!(spec.mass, FluxMass::Mimetic);
/// assert!(matches!(spec.boundary[0].kind, BoundaryKindSpec::Neumann(_)));
/// assert!(matches!(spec.boundary[1].kind, BoundaryKindSpec::Dirichlet(_)));
/// ```
#[derive(Clone, Debug)]
pub struct DarcySpec {
    /// The flux mass M_u (`problem.method`: `mimetic`, `dec`,
    /// `dec-barycentric`).
    pub mass: crate::metric::fv::FluxMass,
    /// K (`problem.permeability`, default 1).
    pub permeability: Coefficient,
    /// f (`problem.source`, default 0), integrated per cell.
    pub source: Expression,
    /// Pressure and flux conditions, in order.
    pub boundary: Vec<BoundarySpec>,
}

/// Resonant modes of a cavity with perfectly conducting walls
/// (`kind = "maxwell"`).
///
/// ```
/// use hasse_complex::DualKind;
/// use hasse_solver::frontend::case::{Case, MaxwellSpec, Problem};
/// use hasse_solver::physics::maxwell::Mass;
/// let text = r#"
/// [mesh]
/// generator = "rectangle"
/// n = [4, 4]
/// [problem]
/// kind = "maxwell"
/// method = "dec-barycentric"
/// modes = 3
/// "#;
/// let case = Case::from_text("cavity.toml", text, &[]).unwrap();
/// let Problem::Maxwell(spec) = &case.problem else { panic!() };
/// assert_eq!(*spec, MaxwellSpec { dual: DualKind::Barycentric, mass: Mass::Hodge, modes: 3 });
/// ```
#[derive(Clone, Debug, PartialEq)]
pub struct MaxwellSpec {
    /// The dual whose Hodge stars ⋆₁, ⋆₂ are used (`problem.method`:
    /// `dec` circumcentric, `dec-barycentric`).
    pub dual: hasse_complex::DualKind,
    /// The mass of the 1-cochains (`problem.mass`, default `hodge`).
    pub mass: crate::physics::maxwell::Mass,
    /// How many of the smallest nonzero ω² to compute.
    pub modes: usize,
}

/// One field of a coupled problem: its own diffusion operator and data,
/// one `[[field]]` table (see [`CoupledSpec`] for a case).
#[derive(Clone, Debug)]
pub struct CoupledFieldSpec {
    /// `name`, the field's name in the output and the summary.
    pub name: String,
    /// `method`, `conductivity`, `source` and its `[[field.boundary]]`
    /// tables.
    pub diffusion: DiffusionSpec,
    /// The exact field, when known.
    pub exact: Option<Expression>,
}

/// Two diffusion fields coupled by linear reaction terms:
/// −∇·(D₁∇u) + a u − b v = f, −∇·(D₂∇v) − b u + c v = g
/// (`kind = "coupled"`).
///
/// ```
/// use hasse_solver::frontend::case::{Case, Problem};
/// let text = r#"
/// [mesh]
/// generator = "rectangle"
/// n = [2, 2]
/// [problem]
/// kind = "coupled"
/// a = 2
/// b = 1
/// c = 2
/// [[field]]
/// name = "u"
/// method = "fe"
/// [[field]]
/// name = "v"
/// method = "fe"
/// source = 3
/// [[field.boundary]]
/// tag = "boundary"
/// type = "dirichlet"
/// value = 2
/// "#;
/// let case = Case::from_text("c.toml", text, &[]).unwrap();
/// let Problem::Coupled(spec) = &case.problem else { panic!() };
/// assert_eq!([spec.fields[0].name.as_str(), spec.fields[1].name.as_str()], ["u", "v"]);
/// // A `[[field.boundary]]` belongs to the `[[field]]` written before it.
/// assert_eq!((spec.fields[0].diffusion.boundary.len(), spec.fields[1].diffusion.boundary.len()), (0, 1));
/// assert_eq!(spec.b.eval(&[0.0, 0.0], 0.0), 1.0);
/// ```
#[derive(Clone, Debug)]
pub struct CoupledSpec {
    /// The two `[[field]]` tables, in order.
    pub fields: [CoupledFieldSpec; 2],
    /// a (`problem.a`), the first field's reaction rate.
    pub a: Expression,
    /// b (`problem.b`), the exchange between the fields.
    pub b: Expression,
    /// c (`problem.c`), the second field's reaction rate.
    pub c: Expression,
}

/// What the case solves: its `[problem]` table, by `kind`.
///
/// ```
/// use hasse_solver::frontend::case::Case;
/// let text = "[mesh]\ngenerator = \"rectangle\"\nn = [2, 2]\n[problem]\nmethod = \"fe\"\n";
/// let case = Case::from_text("p.toml", text, &[]).unwrap();
/// assert_eq!(case.problem.kind(), "diffusion"); // the default kind
/// assert_eq!(case.problem.coefficients()[0].0, "problem.conductivity");
/// let set = ["problem.kind=maxwell", "problem.method=dec-barycentric", "problem.modes=2"];
/// let case = Case::from_text("p.toml", text, &set.map(String::from)).unwrap();
/// assert_eq!(case.problem.kind(), "maxwell");
/// assert!(case.problem.coefficient().is_none());
/// ```
#[derive(Clone, Debug)]
pub enum Problem {
    /// `kind = "diffusion"`.
    Diffusion(DiffusionSpec),
    /// `kind = "diffusion"` with `degree` ≥ 1: Δ_k u = f for k-forms.
    FormDiffusion(super::FormDiffusionSpec),
    /// `kind = "gradient"`.
    Gradient(GradientSpec),
    /// `kind = "heat"`.
    Heat(HeatSpec),
    /// `kind = "darcy"`.
    Darcy(DarcySpec),
    /// `kind = "maxwell"`.
    Maxwell(MaxwellSpec),
    /// `kind = "hodge-laplacian"`.
    Hodge(HodgeSpec),
    /// `kind = "cohomology"`.
    Cohomology(CohomologySpec),
    /// `kind = "hodge-decomposition"`.
    Decomposition(DecompositionSpec),
    /// `kind = "elasticity"`.
    Elasticity(ElasticitySpec),
    /// `kind = "coupled"` (boxed: two diffusion specifications).
    Coupled(Box<CoupledSpec>),
    /// `kind = "transport"`.
    Transport(super::TransportSpec),
    /// `kind = "growth"`.
    Growth(super::GrowthSpec),
}

impl Problem {
    /// The `problem.kind` that names this problem.
    pub fn kind(&self) -> &'static str {
        match self {
            Problem::Diffusion(_) | Problem::FormDiffusion(_) => "diffusion",
            Problem::Gradient(_) => "gradient",
            Problem::Heat(_) => "heat",
            Problem::Darcy(_) => "darcy",
            Problem::Maxwell(_) => "maxwell",
            Problem::Hodge(_) => "hodge-laplacian",
            Problem::Cohomology(_) => "cohomology",
            Problem::Decomposition(_) => "hodge-decomposition",
            Problem::Elasticity(_) => "elasticity",
            Problem::Coupled(_) => "coupled",
            Problem::Transport(_) => "transport",
            Problem::Growth(_) => "growth",
        }
    }

    /// The scalar boundary conditions (diffusion, heat, Darcy).
    pub fn boundary(&self) -> &[BoundarySpec] {
        match self {
            Problem::Diffusion(d) => &d.boundary,
            Problem::Heat(h) => &h.boundary,
            Problem::Darcy(d) => &d.boundary,
            Problem::Transport(t) => &t.boundary,
            Problem::Growth(g) => &g.boundary,
            Problem::Gradient(_)
            | Problem::Maxwell(_)
            | Problem::Hodge(_)
            | Problem::Cohomology(_)
            | Problem::Decomposition(_)
            | Problem::FormDiffusion(_)
            | Problem::Elasticity(_)
            | Problem::Coupled(_) => &[],
        }
    }

    /// (tag, where the tag is written, `boundary[i]`) of every boundary
    /// condition, whatever the kind.
    pub(super) fn boundary_tags(&self) -> Vec<(&str, Option<Range<usize>>, &str)> {
        match self {
            Problem::Elasticity(e) => e
                .boundary
                .iter()
                .map(|b| (b.tag.as_str(), b.tag_span.clone(), b.key.as_str()))
                .collect(),
            Problem::Coupled(c) => c
                .fields
                .iter()
                .flat_map(|f| &f.diffusion.boundary)
                .map(|b| (b.tag.as_str(), b.tag_span.clone(), b.key.as_str()))
                .collect(),
            other => other
                .boundary()
                .iter()
                .map(|b| (b.tag.as_str(), b.tag_span.clone(), b.key.as_str()))
                .collect(),
        }
    }

    /// The diffusion coefficient or permeability, if the problem has one.
    pub fn coefficient(&self) -> Option<&Coefficient> {
        match self {
            Problem::Diffusion(d) => Some(&d.conductivity),
            Problem::Heat(h) => Some(&h.conductivity),
            Problem::Darcy(d) => Some(&d.permeability),
            Problem::Transport(t) => t.conductivity.as_ref(),
            Problem::Growth(g) => Some(&g.conductivity),
            Problem::Gradient(_)
            | Problem::Maxwell(_)
            | Problem::Hodge(_)
            | Problem::Cohomology(_)
            | Problem::Decomposition(_)
            | Problem::FormDiffusion(_)
            | Problem::Elasticity(_)
            | Problem::Coupled(_) => None,
        }
    }

    /// Every coefficient K of the problem with its key: the conductivity
    /// or permeability, or each field's conductivity.
    pub fn coefficients(&self) -> Vec<(String, &Coefficient)> {
        match self {
            Problem::Diffusion(d) => vec![("problem.conductivity".into(), &d.conductivity)],
            Problem::Heat(h) => vec![("problem.conductivity".into(), &h.conductivity)],
            Problem::Darcy(d) => vec![("problem.permeability".into(), &d.permeability)],
            Problem::Transport(t) => t
                .conductivity
                .iter()
                .map(|k| ("problem.conductivity".into(), k))
                .collect(),
            Problem::Growth(g) => vec![("problem.conductivity".into(), &g.conductivity)],
            Problem::Coupled(c) => c
                .fields
                .iter()
                .enumerate()
                .map(|(i, f)| {
                    (
                        format!("field[{i}].conductivity"),
                        &f.diffusion.conductivity,
                    )
                })
                .collect(),
            Problem::Gradient(_)
            | Problem::Maxwell(_)
            | Problem::Hodge(_)
            | Problem::Cohomology(_)
            | Problem::Decomposition(_)
            | Problem::FormDiffusion(_)
            | Problem::Elasticity(_) => Vec::new(),
        }
    }

    /// Every datum given per region, with its key: what the mesh's tags
    /// must cover ([`Case::build_mesh`] checks them).
    pub fn regional_data(&self) -> Vec<(String, &Expression)> {
        fn diffusion<'a>(
            all: &mut Vec<(String, &'a Expression)>,
            prefix: &str,
            k: &'a Coefficient,
            f: &'a Expression,
        ) {
            if let Some(e) = k.regional_expression() {
                all.push((format!("{prefix}.conductivity"), e));
            }
            all.push((format!("{prefix}.source"), f));
        }
        let mut all: Vec<(String, &Expression)> = Vec::new();
        match self {
            Problem::Diffusion(d) => diffusion(&mut all, "problem", &d.conductivity, &d.source),
            Problem::Heat(h) => diffusion(&mut all, "problem", &h.conductivity, &h.source),
            Problem::Growth(g) => diffusion(&mut all, "problem", &g.conductivity, &g.source),
            Problem::Transport(t) => {
                if let Some(e) = t
                    .conductivity
                    .as_ref()
                    .and_then(Coefficient::regional_expression)
                {
                    all.push(("problem.conductivity".into(), e));
                }
                all.push(("problem.source".into(), &t.source));
            }
            Problem::Coupled(c) => {
                for (key, e) in [("a", &c.a), ("b", &c.b), ("c", &c.c)] {
                    all.push((format!("problem.{key}"), e));
                }
                for (i, f) in c.fields.iter().enumerate() {
                    let prefix = format!("field[{i}]");
                    diffusion(
                        &mut all,
                        &prefix,
                        &f.diffusion.conductivity,
                        &f.diffusion.source,
                    );
                }
            }
            Problem::Elasticity(e) => match &e.material {
                MaterialSpec::Lame { lambda, mu } => {
                    all.push(("problem.lambda".into(), lambda));
                    all.push(("problem.mu".into(), mu));
                }
                MaterialSpec::Young { young, poisson } => {
                    all.push(("problem.young".into(), young));
                    all.push(("problem.poisson".into(), poisson));
                }
            },
            Problem::Darcy(d) => {
                if let Some(e) = d.permeability.regional_expression() {
                    all.push(("problem.permeability".into(), e));
                }
                all.push(("problem.source".into(), &d.source));
            }
            Problem::Gradient(_)
            | Problem::Maxwell(_)
            | Problem::Hodge(_)
            | Problem::Cohomology(_)
            | Problem::Decomposition(_)
            | Problem::FormDiffusion(_) => {}
        }
        all.retain(|(_, e)| e.regions().is_some());
        all
    }
}
