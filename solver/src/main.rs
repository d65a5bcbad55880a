//! The `hasse` command line.

mod args;

use args::{Cli, Command, RefineArg};
use clap::Parser;
use hasse_solver::frontend::case::{Case, CaseError};
use hasse_solver::frontend::{info, mesh_spec, output, run};
use hasse_solver::refine as refinement;
use std::io::IsTerminal;
use std::path::{Path, PathBuf};
use std::process::ExitCode;

/// Exit code for bad input (case file, mesh file, parameters).
const EXIT_BAD_INPUT: u8 = 2;
/// Exit code for a failed or untrustworthy solve.
const EXIT_SOLVE_FAILED: u8 = 1;

fn load_timed(path: &Path, timing: bool) -> Result<hasse_complex::Complex, mesh_spec::MeshError> {
    let started = std::time::Instant::now();
    let complex = load(path)?;
    if timing {
        println!(
            "timing     mesh built in {:.3} s",
            started.elapsed().as_secs_f64()
        );
    }
    Ok(complex)
}

fn load(path: &Path) -> Result<hasse_complex::Complex, mesh_spec::MeshError> {
    let mut complex = match mesh_spec::read_mesh_file(path) {
        Some(read) => read?,
        None => return mesh_spec::read_case_mesh(path)?.build(path),
    };
    // As a case file's mesh would have it.
    mesh_spec::tag_boundary(&mut complex);
    Ok(complex)
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    match cli.command {
        Command::Run {
            case,
            output,
            set,
            quiet,
            verbose,
        } => run_case(&case, output.as_deref(), &set, quiet, verbose),
        Command::Check { case, set } => check_case(&case, &set),
        Command::Refine {
            case,
            steps,
            strategy,
            theta,
            output,
            mut set,
            quiet,
            verbose,
        } => {
            // The options are overrides of the [refine] table, checked with it.
            if let Some(n) = steps {
                set.push(format!("refine.steps={n}"));
            }
            if let Some(s) = strategy {
                set.push(format!("refine.strategy=\"{s}\""));
            }
            if let Some(t) = theta {
                set.push(format!("refine.theta={t:?}"));
            }
            let case_path = case;
            // Errors and warnings of the case are reported once, by run_case.
            let no_refine = Case::read(&case_path, &set).is_ok_and(|case| case.refine.is_none());
            if no_refine {
                eprintln!(
                    "error: {}: no [refine] table: add one (strategy, steps) or pass --steps N",
                    case_path.display()
                );
                return ExitCode::from(EXIT_BAD_INPUT);
            }
            run_case(&case_path, output.as_deref(), &set, quiet, verbose)
        }
        Command::Converge {
            case,
            levels,
            refine,
            methods,
            output,
            expect,
            set,
            quiet,
        } => converge(
            &case,
            levels as usize,
            refine,
            &methods,
            output,
            expect.as_deref(),
            &set,
            quiet,
        ),
        Command::Export { mesh, lar, json } => export(&mesh, lar.as_deref(), json.as_deref()),
        Command::Info {
            mesh,
            betti,
            timing,
        } => match load_timed(&mesh, timing) {
            Ok(complex) => {
                let started = std::time::Instant::now();
                let report = info::report(&complex, &mesh.display().to_string(), betti);
                print!("{report}");
                if timing {
                    println!(
                        "timing     report {:.3} s; peak memory {}",
                        started.elapsed().as_secs_f64(),
                        info::peak_memory().unwrap_or_else(|| "unknown".into())
                    );
                }
                ExitCode::SUCCESS
            }
            Err(e) => {
                eprintln!("error: {e}");
                ExitCode::from(EXIT_BAD_INPUT)
            }
        },
    }
}

/// `hasse export`: the mesh of MESH written as LAR and/or hasse JSON.
fn export(mesh: &Path, lar: Option<&Path>, json: Option<&Path>) -> ExitCode {
    if let Some(out) = lar.filter(|out| !hasse_complex::lar_json::is_lar_path(out)) {
        eprintln!(
            "error: --lar {}: the name must end in .lar.json, which is how hasse recognises a LAR file when it reads one",
            out.display()
        );
        return ExitCode::from(EXIT_BAD_INPUT);
    }
    let complex = match load(mesh) {
        Ok(complex) => complex,
        Err(e) => {
            eprintln!("error: {e}");
            return ExitCode::from(EXIT_BAD_INPUT);
        }
    };
    let files = [
        (lar, hasse_complex::lar_json::to_lar_json(&complex), "LAR"),
        (json, hasse_complex::json::to_json(&complex), "hasse JSON"),
    ];
    for (out, text, kind) in files {
        let Some(out) = out else { continue };
        if let Err(e) = output::write_text_file(out, &text) {
            eprintln!("error: writing {}: {e}", out.display());
            return ExitCode::from(EXIT_SOLVE_FAILED);
        }
        println!(
            "wrote      {} ({kind}, cells per dimension {:?})",
            out.display(),
            complex.cell_counts()
        );
    }
    ExitCode::SUCCESS
}

fn read_case(path: &Path, set: &[String]) -> Result<Case, ExitCode> {
    let case = Case::read(path, set).map_err(|e| {
        match e {
            CaseError::Invalid(diagnostics) => eprintln!("{diagnostics}"),
            other => eprintln!("error: {other}"),
        }
        ExitCode::from(EXIT_BAD_INPUT)
    })?;
    for warning in &case.warnings {
        eprintln!("warning: {warning}");
    }
    Ok(case)
}

fn check_case(path: &Path, set: &[String]) -> ExitCode {
    let case = match Case::read(path, set) {
        Ok(case) => case,
        Err(CaseError::Invalid(diagnostics)) => {
            eprintln!("{diagnostics}");
            eprintln!(
                "{}: {} problem{} found",
                path.display(),
                diagnostics.len(),
                if diagnostics.len() == 1 { "" } else { "s" }
            );
            return ExitCode::from(EXIT_BAD_INPUT);
        }
        Err(other) => {
            eprintln!("error: {other}");
            return ExitCode::from(EXIT_BAD_INPUT);
        }
    };
    for warning in &case.warnings {
        eprintln!("warning: {warning}");
    }
    // Where `hasse run` would write (without -o): refused here as there.
    if case.output.write {
        let stem = case.output.directory.join(&case.output.name);
        if let Err(code) = check_output_place(path, &stem) {
            eprintln!("{}: 1 problem found", path.display());
            return code;
        }
    }
    match case.build_mesh() {
        Ok(complex) => {
            // The data where the solve evaluates them: coefficients and
            // sources that are not finite or not positive are refused here.
            if let Err(e) = run::check_data(&case, &complex) {
                eprintln!("error: {e}");
                eprintln!("{}: 1 problem found", path.display());
                return ExitCode::from(EXIT_BAD_INPUT);
            }
            println!(
                "{}: ok ({}, mesh cells per dimension {:?})",
                path.display(),
                describe_problem(&case),
                complex.cell_counts()
            );
            ExitCode::SUCCESS
        }
        Err(diagnostics) => {
            eprintln!("{diagnostics}");
            ExitCode::from(EXIT_BAD_INPUT)
        }
    }
}

fn describe_problem(case: &Case) -> String {
    use hasse_solver::frontend::case::Problem;
    match &case.problem {
        Problem::Diffusion(d) => format!("diffusion, method {}", d.method.name()),
        Problem::Gradient(_) => "gradient".to_string(),
        Problem::Heat(h) => match h.time.adaptive {
            None => format!(
                "heat, method {}, {} steps of dt = {}",
                h.method.name(),
                h.time.steps,
                h.time.dt
            ),
            Some(tolerance) => format!(
                "heat, method {}, adaptive steps from dt = {} to t = {} (tolerance {tolerance:e})",
                h.method.name(),
                h.time.dt,
                h.time.start + h.time.steps as f64 * h.time.dt
            ),
        },
        Problem::Darcy(d) => format!("darcy, flux mass {:?}", d.mass),
        Problem::Maxwell(m) => format!("maxwell, {} modes, dual {:?}", m.modes, m.dual),
        Problem::Hodge(h) => format!(
            "hodge-laplacian, degree {}, {} modes, {}, {} boundary",
            h.degree,
            h.modes,
            h.method.name(),
            h.boundary.name()
        ),
        Problem::Cohomology(c) => format!(
            "cohomology, degree {}, {}, {} boundary",
            c.degree,
            c.method.name(),
            c.boundary.name()
        ),
        Problem::Decomposition(d) => {
            format!(
                "hodge-decomposition of a {}-cochain, {}",
                d.degree,
                d.method.name()
            )
        }
        Problem::FormDiffusion(d) => format!(
            "diffusion of {}-forms (Δ_k u = f), {}, {} boundary",
            d.degree,
            d.method.name(),
            d.boundary.name()
        ),
        Problem::Elasticity(e) => format!("elasticity, P1/Q1, {:?}", e.plane),
        Problem::Transport(t) => match &t.time {
            Some(time) if t.method == hasse_solver::metric::Method::Fe => format!(
                "transport, method fe, {}, θ = {}, {} steps of dt = {}",
                t.stabilisation.name(),
                time.theta,
                time.steps,
                time.dt
            ),
            Some(time) => format!(
                "transport, method fv, {} scheme, {} steps of dt = {}",
                t.scheme.name(),
                time.steps,
                time.dt
            ),
            None if t.method == hasse_solver::metric::Method::Fe => {
                format!("transport, method fe, {}, steady", t.stabilisation.name())
            }
            None => "transport, method fv, upwind, steady".to_string(),
        },
        Problem::Growth(g) => format!(
            "growth, {}, {} steps of dt = {}, divide above {}",
            g.method.name(),
            g.time.steps,
            g.time.dt,
            g.divide_above
        ),
        Problem::Coupled(c) => format!(
            "coupled fields {} ({}) and {} ({})",
            c.fields[0].name,
            c.fields[0].diffusion.method.name(),
            c.fields[1].name,
            c.fields[1].diffusion.method.name()
        ),
    }
}

/// Progress on stderr: a spinner on a terminal, plain lines with -v
/// otherwise, nothing with -q.
struct Progress {
    spinner: Option<indicatif::ProgressBar>,
    verbose: bool,
    started: std::time::Instant,
}

impl Progress {
    fn new(quiet: bool, verbose: bool) -> Self {
        let spinner = (!quiet && std::io::stderr().is_terminal()).then(|| {
            let bar = indicatif::ProgressBar::new_spinner();
            bar.enable_steady_tick(std::time::Duration::from_millis(120));
            bar
        });
        Self {
            spinner,
            verbose: verbose && !quiet,
            started: std::time::Instant::now(),
        }
    }

    fn phase(&self, name: &str) {
        if let Some(bar) = &self.spinner {
            bar.set_message(name.to_string());
        } else if self.verbose {
            eprintln!("[{:8.3} s] {name}", self.started.elapsed().as_secs_f64());
        }
    }

    fn finish(&self) {
        if let Some(bar) = &self.spinner {
            bar.finish_and_clear();
        }
    }
}

fn run_case(
    path: &Path,
    output: Option<&Path>,
    set: &[String],
    quiet: bool,
    verbose: bool,
) -> ExitCode {
    let case = match read_case(path, set) {
        Ok(case) => case,
        Err(code) => return code,
    };
    let stem = output
        .map(Path::to_path_buf)
        .unwrap_or_else(|| case.output.directory.join(&case.output.name));
    if case.output.write || output.is_some() {
        if let Err(code) = prepare_output(path, &stem) {
            return code;
        }
    }
    let progress = Progress::new(quiet, verbose);
    progress.phase("building the mesh");
    let mesh_started = std::time::Instant::now();
    let complex = match case.build_mesh() {
        Ok(complex) => complex,
        Err(diagnostics) => {
            progress.finish();
            eprintln!("{diagnostics}");
            return ExitCode::from(EXIT_BAD_INPUT);
        }
    };
    let mesh_seconds = mesh_started.elapsed().as_secs_f64();
    let writing = case.output.write || output.is_some();
    if writing {
        if let Err(message) = run::OutputEstimate::of(&case, &complex).check(&stem) {
            progress.finish();
            eprintln!("error: {}: {message}\n    help: free some space, write elsewhere (-o DIR/NAME), save fewer levels (time.save_every) or fewer fields ([output] fields)", path.display());
            return ExitCode::from(EXIT_BAD_INPUT);
        }
    }
    // A transient run writes each saved level as it completes to a partial
    // output, so that an interrupted or failed run keeps them.
    let mut stream = (writing && case.output.partial).then(|| run::LevelStream::new(&case, &stem));
    // With a [refine] table the case is solved, refined and re-solved; the
    // output holds every level, each on its own mesh.
    // A growing tissue changes its mesh at every step: the output holds
    // every saved level, each on its own mesh.
    let mut grown = None;
    let (refined, study, result) = match &case.refine {
        None if matches!(
            case.problem,
            hasse_solver::frontend::case::Problem::Growth(_)
        ) =>
        {
            match run::growth::grow_case(&case, &complex, &mut |name| progress.phase(name)) {
                Ok(growth) => {
                    let result = Ok(growth.result.clone());
                    let last = growth.complex.clone();
                    grown = Some(growth);
                    (Some(last), None, result)
                }
                Err(e) => (None, None, Err(e)),
            }
        }
        None => {
            let result = run::solve_streaming(&case, &complex, stream.as_mut(), &mut |name| {
                progress.phase(name)
            });
            (None, None, result)
        }
        Some(spec) => {
            match run::refine::refine_case(&case, &complex, spec, &mut |name| progress.phase(name))
            {
                Ok(study) => (
                    Some(study.complex),
                    Some((study.steps, study.levels)),
                    Ok(study.result),
                ),
                Err(e) => (None, None, Err(e)),
            }
        }
    };
    let complex = refined.as_ref().unwrap_or(&complex);
    // What an error leaves: the completed levels of a transient run, or nothing.
    let left_behind = |stream: Option<&run::LevelStream>| {
        if let Some(e) = stream.and_then(run::LevelStream::stopped) {
            eprintln!("warning: the partial output stopped early: {e}");
        }
        match stream.and_then(run::LevelStream::readable) {
            Some(readable) => eprintln!("{readable}"),
            None => eprintln!("no output written"),
        }
    };
    let mut result = match result {
        Ok(result) => result,
        Err(e) => {
            progress.finish();
            eprintln!("error: {e}");
            left_behind(stream.as_ref());
            return ExitCode::from(if e.is_input() {
                EXIT_BAD_INPUT
            } else {
                EXIT_SOLVE_FAILED
            });
        }
    };
    result.timings.insert(0, ("mesh".into(), mesh_seconds));
    result
        .warnings
        .extend(run::unwritten_fields(&case, &result));
    let writing_started = std::time::Instant::now();
    let written = if writing {
        progress.phase("writing output");
        if let Some(e) = stream.as_ref().and_then(run::LevelStream::stopped) {
            result
                .warnings
                .push(format!("the partial output stopped early: {e}"));
        }
        let readable = stream.as_ref().and_then(run::LevelStream::readable);
        let written = match (&study, stream.take()) {
            // A refinement writes every level, each on its own mesh.
            (Some((steps, levels)), _) => {
                let mut report = result.report_json(complex);
                report["refinement"] = refinement::steps_json(steps);
                // The partial output of an earlier transient run under
                // this stem is stale once this output is in place.
                run::write_levels(&case, levels, report, &stem).and_then(|files| {
                    hasse_solver::frontend::output::remove_partial(&stem)?;
                    Ok(files)
                })
            }
            (None, _) if grown.is_some() => match &grown {
                Some(growth) => {
                    run::growth::write_series(&case, growth, result.report_json(complex), &stem)
                        .and_then(|files| {
                            hasse_solver::frontend::output::remove_partial(&stem)?;
                            Ok(files)
                        })
                }
                None => run::write_output(&case, complex, &result, &stem),
            },
            (None, Some(stream)) => stream.finish(complex, &mut result),
            (None, None) => run::write_output(&case, complex, &result, &stem),
        };
        // The CSV tables (transient quantities, probes) beside the output.
        let written = written.and_then(|files| {
            Ok((
                files,
                run::write_tables(&stem, &result.report_json(complex))?,
            ))
        });
        match written {
            Ok(files) => {
                // The summary's figure only: the report inside the file
                // was complete before its own writing was.
                let seconds = writing_started.elapsed().as_secs_f64();
                result.timings.push(("output".into(), seconds));
                Some(files)
            }
            Err(e) => {
                progress.finish();
                eprintln!("error: writing output: {e}");
                eprintln!("{}", readable.unwrap_or_else(|| "no output written".into()));
                return ExitCode::from(EXIT_SOLVE_FAILED);
            }
        }
    } else {
        None
    };
    progress.finish();
    if !quiet {
        println!("case       {}", path.display());
        if let Some(title) = &case.title {
            println!("title      {title}");
        }
        println!(
            "mesh       {} (cells per dimension {:?})",
            complex_kind(complex),
            complex.cell_counts()
        );
        if let Some((steps, _)) = &study {
            println!("refinement {}", refinement::TABLE_HEADER);
            for step in steps {
                println!("           {step}");
            }
            println!("solvers    {}", refinement::solvers_line(steps));
            println!(
                "columns    iters: CG iterations; start r: relative residual of the solution moved from the previous mesh, where CG starts"
            );
            println!("finest     re-solved with the case's own solver for the output:");
        }
        print!("{result}");
        if let Some((files, csv)) = written {
            let mut names = vec![files.hdf5.display().to_string()];
            names.push(files.xdmf.display().to_string());
            names.extend(files.extra_xdmf.iter().map(|p| p.display().to_string()));
            names.extend(csv.iter().map(|p| p.display().to_string()));
            println!("output     {}", names.join(", "));
            if let Some(levels) = files.levels_line() {
                println!("levels     {levels}");
            }
        }
    } else {
        for w in &result.warnings {
            eprintln!("warning: {w}");
        }
    }
    ExitCode::SUCCESS
}

/// Refuse an output place that cannot take the output, before solving:
/// the stem, the files and the directory it names ([`output::check_place`]).
fn check_output_place(case_path: &Path, stem: &Path) -> Result<output::OutputPlace, ExitCode> {
    output::check_place(stem).map_err(|e| output_refused(case_path, stem, e))
}

fn output_refused(case_path: &Path, stem: &Path, e: output::OutputError) -> ExitCode {
    eprintln!(
        "error: {}: output {}: {e}\n    help: choose a writable place with -o DIR/NAME (run, refine) or [output] directory and name",
        case_path.display(),
        stem.display()
    );
    ExitCode::from(EXIT_BAD_INPUT)
}

/// Check the output place, create its directory if missing (saying so),
/// and probe that a file can be written there.
fn prepare_output(case_path: &Path, stem: &Path) -> Result<(), ExitCode> {
    let place = check_output_place(case_path, stem)?;
    output::check_writable(stem).map_err(|e| output_refused(case_path, stem, e))?;
    if let Some(first) = place.missing {
        let dir = stem.parent().unwrap_or(&first);
        eprintln!("note: created the output directory {}", dir.display());
    }
    Ok(())
}

fn complex_kind(complex: &hasse_complex::Complex) -> String {
    format!(
        "{}-dimensional in R^{}",
        complex.dim(),
        complex.embedding_dim()
    )
}

/// `hasse converge`: a thin layer over [`hasse_solver::frontend::converge::Study`].
#[allow(clippy::too_many_arguments)]
fn converge(
    path: &Path,
    levels: usize,
    refine: RefineArg,
    methods: &[String],
    output: Option<PathBuf>,
    expect: Option<&str>,
    set: &[String],
    quiet: bool,
) -> ExitCode {
    use hasse_solver::frontend::converge::{Study, StudyError};
    use hasse_solver::frontend::output::study::{write_csv, write_json, write_plot};
    use hasse_solver::metric::Method;
    use hasse_solver::study::{Expectation, PlotFormat, PlotOptions, Refinement};
    let bad_input = |message: String| {
        eprintln!("error: {message}");
        ExitCode::from(EXIT_BAD_INPUT)
    };
    let methods = match methods
        .iter()
        .map(|m| m.parse::<Method>())
        .collect::<Result<Vec<_>, _>>()
    {
        Ok(methods) => methods,
        Err(e) => {
            let names: Vec<String> = Method::names().iter().map(|s| s.to_string()).collect();
            let help = match hasse_solver::frontend::case::expr::closest(&e.name, &names) {
                Some(name) => format!("\n    help: did you mean `{name}`?"),
                None => String::new(),
            };
            return bad_input(format!("--methods: {e}{help}"));
        }
    };
    let expect: Option<Expectation> = match expect.map(str::parse).transpose() {
        Ok(e) => e,
        Err(e) => return bad_input(format!("--expect {e}")),
    };
    if expect.is_some() && levels < 2 {
        return bad_input("--expect needs at least 2 levels to observe an order".into());
    }
    let refinement = match refine {
        RefineArg::Uniform => Refinement::Uniform,
        RefineArg::Split => Refinement::Split,
        RefineArg::Time => Refinement::Time,
    };
    let study = Study {
        levels,
        refinement,
        methods,
    };
    let result = study.run(path, set, &mut |level, rows| {
        if quiet {
            return;
        }
        let Some(first) = rows.first() else { return };
        let solves: Vec<String> = rows
            .iter()
            .map(|r| format!("{} {:.2} s", r.method, r.solve_seconds))
            .collect();
        let size = match refinement {
            Refinement::Uniform => format!("n = {:?}, h = {:.3e}", first.resolution, first.h),
            Refinement::Split => format!("h = {:.3e}", first.h),
            Refinement::Time => format!(
                "{} steps of Δt = {:.3e}",
                first.resolution.first().copied().unwrap_or(0),
                first.h
            ),
        };
        eprintln!(
            "level {level} of 0–{}: {size}, {} cells, mesh {:.2} s; {}",
            levels - 1,
            first.cells,
            first.mesh_seconds,
            solves.join(", ")
        );
    });
    let result = match result {
        Ok(result) => result,
        Err(StudyError::Invalid(diagnostics)) => {
            eprintln!("{diagnostics}");
            return ExitCode::from(EXIT_BAD_INPUT);
        }
        Err(e) => {
            eprintln!("error: {e}");
            eprintln!("no output written");
            return ExitCode::from(if e.is_input() {
                EXIT_BAD_INPUT
            } else {
                EXIT_SOLVE_FAILED
            });
        }
    };
    let directory = output.unwrap_or_else(|| {
        let stem = path
            .file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_else(|| "case".into());
        PathBuf::from(format!("converge-{stem}"))
    });
    if let Err(e) = std::fs::create_dir_all(&directory) {
        eprintln!("error: {}: {e}", directory.display());
        return ExitCode::from(EXIT_SOLVE_FAILED);
    }
    let file = |ext: &str| directory.join(format!("convergence.{ext}"));
    let plot = |ext, format| write_plot(&result, &file(ext), format, PlotOptions::default());
    let written = write_csv(&result, &file("csv"))
        .and_then(|()| write_json(&result, &file("json")))
        .and_then(|()| plot("png", PlotFormat::Png))
        .and_then(|()| plot("svg", PlotFormat::Svg));
    if let Err(e) = written {
        eprintln!("error: writing the study: {e}");
        return ExitCode::from(EXIT_SOLVE_FAILED);
    }
    if !quiet {
        print!("{result}");
        println!(
            "\nwritten  {}/convergence.{{csv,json,png,svg}}",
            directory.display()
        );
    }
    if let Some(expect) = expect {
        let missed = result.shortfalls(expect);
        let bound = expect.order - expect.tolerance;
        for m in &missed {
            match m.observed {
                Some(p) => eprintln!(
                    "expectation missed: {} least-squares L² order {p:.2} < {} − {} = {bound:.2}",
                    m.method, expect.order, expect.tolerance
                ),
                None => eprintln!(
                    "expectation missed: {} least-squares L² order cannot be computed (an error is zero or not finite)",
                    m.method
                ),
            }
        }
        if !missed.is_empty() {
            return ExitCode::from(EXIT_SOLVE_FAILED);
        }
        if !quiet {
            println!(
                "expect   least-squares L² order ≥ {} − {} for {}: met",
                expect.order,
                expect.tolerance,
                result.methods.join(", ")
            );
        }
    }
    ExitCode::SUCCESS
}
