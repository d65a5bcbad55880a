//! The command line's commands and arguments (clap), read by `main.rs`.

use clap::{Parser, Subcommand};
use std::path::PathBuf;

/// hasse: one canonical form δΩ∂ = AᵀΩA for FD, FE, FV and DEC on any cell complex.
#[derive(Parser)]
#[command(
    version,
    about,
    long_about = None,
    after_help = "Case files: every key is documented in cases/README.md, with the shipped \
                  cases (cases/first-case.toml is the walk-through of README.md); the output \
                  layout is in cases/OUTPUT.md. `hasse COMMAND --help` explains a command \
                  with examples."
)]
pub(crate) struct Cli {
    #[command(subcommand)]
    pub(crate) command: Command,
}

#[derive(Subcommand)]
pub(crate) enum Command {
    /// Solve a case file and write its results (HDF5 + XDMF).
    ///
    /// Prints a summary: mesh, unknowns, method, solver, residual, errors
    /// against the exact solution when the case gives one, and timings.
    /// Exit code 0 on success, 1 when the solve fails, 2 for bad input.
    ///
    /// Examples:
    ///   hasse run cases/poisson-square.toml
    ///   hasse run cases/poisson-square.toml --set problem.method=fv --set mesh.n=\[64,64\] -o out/fv
    #[command(verbatim_doc_comment)]
    Run {
        /// The case file (.toml).
        case: PathBuf,
        /// Output stem: writes OUT.h5, OUT.xdmf, and OUT.edges.xdmf /
        /// OUT.faces.xdmf for edge / face fields (default: `[output]` of the
        /// case, else the case file's name in the current directory).
        #[arg(short, long, value_name = "OUT")]
        output: Option<PathBuf>,
        /// Override a case key, e.g. --set problem.method=fv (repeatable).
        #[arg(long = "set", value_name = "KEY=VALUE")]
        set: Vec<String>,
        /// Print only errors.
        #[arg(short, long, conflicts_with = "verbose")]
        quiet: bool,
        /// Print each phase as it starts.
        #[arg(short, long)]
        verbose: bool,
    },
    /// Solve a case, refine its mesh by SPLIT and solve again, step by step.
    ///
    /// Each step refines (uniform: every cell by axis-aligned planes through
    /// its centroid; adaptive: the cells holding the fraction θ of the error
    /// indicator; divide-longest-axis / divide-shortest-wall: tissue
    /// division rules), moves the solution to the refined mesh through the
    /// chain map, and re-solves by multigrid-CG from the moved solution,
    /// the earlier meshes being the coarse levels (the table shows the
    /// estimator, the errors, the iterations and where CG started).
    /// Options override the case's `[refine]` table. Output: every level,
    /// OUT.xdmf as a series (level k at time k) and OUT.level-K.xdmf each
    /// level alone (see cases/OUTPUT.md).
    ///
    /// Example: hasse refine cases/l-shape-adaptive.toml --steps 4
    #[command(verbatim_doc_comment)]
    Refine {
        /// The case file (.toml).
        case: PathBuf,
        /// Number of refinement steps.
        #[arg(long)]
        steps: Option<usize>,
        /// uniform | adaptive | divide-longest-axis | divide-shortest-wall.
        #[arg(long)]
        strategy: Option<String>,
        /// Dörfler fraction for the adaptive strategy (0 < θ ≤ 1).
        #[arg(long)]
        theta: Option<f64>,
        /// Output stem (as for `run`).
        #[arg(short, long, value_name = "OUT")]
        output: Option<PathBuf>,
        /// Override a case key, as for `run`.
        #[arg(long = "set", value_name = "KEY=VALUE")]
        set: Vec<String>,
        /// Print only errors.
        #[arg(short, long, conflicts_with = "verbose")]
        quiet: bool,
        /// Print each phase as it starts.
        #[arg(short, long)]
        verbose: bool,
    },
    /// Check a case file without solving: report every problem at once.
    ///
    /// Reports unknown or misspelt keys (with a suggestion), wrong types,
    /// missing files, expressions that do not parse or use unknown names,
    /// boundary tags that the mesh does not have, and coefficients,
    /// sources and materials that are not finite or not positive where the
    /// solve would evaluate them, each with file, line and column (or the
    /// --set text). Exit code 0 when the case is valid, 2 otherwise.
    ///
    /// Example: hasse check cases/l-shape.toml
    Check {
        /// The case file (.toml).
        case: PathBuf,
        /// Override a case key, as for `run`.
        #[arg(long = "set", value_name = "KEY=VALUE")]
        set: Vec<String>,
    },
    /// Report on a mesh: cell counts per dimension, Euler characteristic,
    /// Betti numbers, boundary regions (tags) and cell quality.
    ///
    /// MESH may be a case file (.toml, its `[mesh]` table is used), a Gmsh
    /// file (.msh, version 4), a LAR file (.lar.json: the LAR paper's `V`,
    /// `EV`, `FV`, `CV`) or a hasse complex file (.json).
    ///
    /// Example: hasse info cases/torus.toml
    Info {
        /// Case file, Gmsh .msh v4 file, LAR .lar.json or hasse .json complex.
        mesh: PathBuf,
        /// Compute Betti numbers even for large meshes.
        #[arg(long)]
        betti: bool,
        /// Also print the time taken to build the complex and its geometry,
        /// and the peak memory of the process.
        #[arg(long)]
        timing: bool,
    },
    /// Write a mesh in another format: the LAR paper's representation
    /// (--lar, a JSON object with the vertices `V` and the cells `EV`,
    /// `FV`, `CV` as vertex lists; tags are not part of it) or hasse's
    /// exact JSON complex (--json, with tags and orientations).
    ///
    /// MESH is read as by `info`: a case file (.toml, its `[mesh]` table),
    /// a Gmsh file (.msh), a LAR file (.lar.json) or a hasse complex
    /// (.json). Each file is written under a temporary name and renamed
    /// into place. Exit code 0 on success, 1 when a file cannot be
    /// written, 2 for bad input.
    ///
    /// Examples:
    ///   hasse export cases/l-shape.toml --lar l-shape.lar.json
    ///   hasse export cases/lar-fig2a.lar.json --json fig2a.json
    #[command(verbatim_doc_comment)]
    #[command(group(clap::ArgGroup::new("format").required(true).multiple(true).args(["lar", "json"])))]
    Export {
        /// Case file, Gmsh .msh v4 file, LAR .lar.json or hasse .json complex.
        mesh: PathBuf,
        /// Write the LAR representation here (the name must end in .lar.json).
        #[arg(long, value_name = "OUT.lar.json")]
        lar: Option<PathBuf>,
        /// Write the hasse JSON complex here.
        #[arg(long, value_name = "OUT.json")]
        json: Option<PathBuf>,
    },
    /// Convergence study: solve CASE on N successively refined meshes (or
    /// time steps) and report the errors against its exact solution and
    /// the observed orders of convergence.
    ///
    /// Cases: diffusion (kind = "diffusion"), heat, darcy and coupled. For
    /// each method and level: the resolution, the mesh size h (largest
    /// top-cell diameter; Δt in a time study), unknowns, and the errors the
    /// case's run reports. Diffusion: the L² and H¹ (seminorm, energy)
    /// error by quadrature of the field each method represents (P1/Q1
    /// shape functions, or cell values with their reconstructed gradient;
    /// the H¹ error needs `exact.gradient`), the max error at the unknowns'
    /// points, the face-flux error where the method defines one. Heat: L²
    /// and max at the unknowns' points at the last step. Darcy: pressure at
    /// the cell points, and the flux error with `exact.gradient`. Coupled:
    /// one row per [[field]] with `exact`, named FIELD (METHOD). `hasse run`
    /// also prints the sampled figures (L² at the unknowns' points,
    /// gradient at the centroids), which superconverge on grids. Orders:
    /// between consecutive levels, and the least-squares slope of log e
    /// against log h (log Δt) over all levels.
    ///
    /// Refinement `uniform` re-generates the case's mesh with 2^k times its
    /// mesh.n on level k (voronoi: 4^k times the sites; sphere: k more
    /// subdivisions); a mesh read from a file has no mesh.n: use `split`.
    /// `split` starts from the case's mesh (generated or a file) and splits
    /// every cell of the previous level through its centroid by the axis
    /// planes (quads → 4 quads, triangles → polygons), halving h; the
    /// resolution column is the number of cells. `time` (heat only) keeps
    /// the mesh and halves Δt, doubling the steps to the same end time; the
    /// resolution column is the number of steps.
    ///
    /// A spatial study of a heat case keeps the case's Δt, whose time
    /// error is the same on every level: the spatial order shows only while
    /// the spatial error dominates it (use a small time.dt). A time study
    /// likewise needs a mesh whose spatial error is below the time error.
    ///
    /// Prints the table, writes DIR/convergence.csv, .json, .png and .svg
    /// (log–log error against h or Δt, reference slopes 1 and 2).
    /// Exit code 0 on success, 1 when a solve fails or an --expect order is
    /// missed, 2 for bad input.
    ///
    /// Examples:
    ///   hasse converge cases/poisson-square.toml --levels 4 --methods fd,fe,fv,fv-mimetic
    ///   hasse converge cases/distorted-quads.toml --levels 5 --methods fv,fv-mimetic,fe -o out/dq
    ///   hasse converge cases/box-3d.toml --levels 3 --set mesh.n=\[8,8,8\] --expect 2
    ///   hasse converge cases/poisson-square.toml --levels 4 --methods dec,fe --set mesh.cells=simplex
    ///   hasse converge cases/l-shape.toml --refine split --levels 3 --methods fe
    ///   hasse converge cases/heat-square.toml --refine time --levels 3 --set mesh.n=\[64,64\] --set time.scheme=backward-euler
    ///   hasse converge cases/darcy-layered.toml --levels 3 --set mesh.n=\[8,8\]
    // Verbatim: the examples are one per line.
    #[command(verbatim_doc_comment)]
    Converge {
        /// The case file (.toml); it needs an exact solution (`[exact]`, or
        /// `exact` in a coupled case's [[field]]).
        case: PathBuf,
        /// Number of levels: the case's own mesh (and Δt), then N − 1
        /// refinements.
        #[arg(long, value_name = "N", value_parser = clap::value_parser!(u32).range(1..=16))]
        levels: u32,
        /// How each level is refined: uniform (re-generate at 2× mesh.n),
        /// split (split every cell; any mesh, files too), time (halve Δt).
        #[arg(long, value_enum, default_value_t = RefineArg::Uniform)]
        refine: RefineArg,
        /// Methods side by side on the same meshes (default: the case's own):
        /// fd, fe, fv, fv-mimetic, dec, dec-barycentric (diffusion and heat
        /// cases; a darcy or coupled case studies its own methods).
        #[arg(long, value_delimiter = ',', value_name = "METHOD,...")]
        methods: Vec<String>,
        /// Output directory (default: converge-STEM, STEM the case
        /// file's name without its extension).
        #[arg(short, long, value_name = "DIR")]
        output: Option<PathBuf>,
        /// Fail (exit code 1) when the least-squares L² order of any method
        /// is below ORDER − TOL (TOL defaults to 0.15), e.g. --expect 2 or
        /// --expect 1:0.3.
        #[arg(long, value_name = "ORDER[:TOL]")]
        expect: Option<String>,
        /// Override a case key before refining, as for `run` (repeatable).
        #[arg(long = "set", value_name = "KEY=VALUE")]
        set: Vec<String>,
        /// Print only errors and missed expectations (no progress, no table).
        #[arg(short, long)]
        quiet: bool,
    },
}

/// Values of `hasse converge --refine`.
#[derive(Clone, Copy, Debug, clap::ValueEnum)]
pub(crate) enum RefineArg {
    /// Re-generate the mesh at 2^k times the case's resolution.
    Uniform,
    /// Split every cell of the previous level through its centroid.
    Split,
    /// Halve the time step of a transient case, same mesh.
    Time,
}
