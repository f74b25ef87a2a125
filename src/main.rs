//! The `efsi` command: run, resume, check and inspect full-Eulerian FSI scenes.
//!
//! Exit codes: 0 success, 1 I/O failure (e.g. an output folder that cannot be created, reported
//! before the first step), 2 bad input (scene, settings, a checkpoint that cannot be resumed —
//! changed scene or law, corrupt file), 3 a run that failed numerically (non-convergence,
//! non-finite values, collapsing step; the last good state is saved as VTK and checkpoint),
//! 130 stopped by SIGINT and 143 by SIGTERM (128 + signal number, the shell convention).
//!
//! **Signals.** SIGXFSZ is ignored: a write past a file-size limit (`ulimit -f`) fails with
//! EFBIG, and the run stops as on a full disk (exit code 1, a checkpoint to resume from,
//! `run.json` saying why). During `run` and `resume`, SIGINT (Ctrl-C) or SIGTERM ends the run at the end of
//! the current step: it writes a checkpoint (`DIR/checkpoint/latest.efsick`), leaves the VTK
//! files, `fields.pvd` and `probes.csv` complete and `run.json` saying `Interrupted`, and exits
//! with 130 / 143; `efsi resume DIR` continues it. A second signal while stopping exits at once.

/// `println!` that ignores a closed standard output (`efsi run … | head` must not panic).
macro_rules! out {
    ($($t:tt)*) => {{
        use std::io::Write as _;
        let _ = writeln!(std::io::stdout(), $($t)*);
    }};
}

mod plot;

use clap::{Parser, Subcommand};
use efsi_core::{EfsiError, Override, Scene, Simulation};
use efsi_laws_host::Listed;
use efsi_run::SceneOutput;
use efsi_run::SceneOverrides as _;
use efsi_run::run::{Progress, RunOptions, RunOutcome, StopReason, resume, run_with};
use indicatif::{ProgressBar, ProgressStyle};
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, AtomicUsize};

#[derive(Parser)]
#[command(
    name = "efsi",
    version,
    about = "Full-Eulerian fluid–structure interaction on a fixed grid"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

/// Changes to the scene file's settings, shared by `run` and `check`.
#[derive(clap::Args)]
struct SceneOverrides {
    /// Set a scene setting by its path, e.g. `grid.nx=128`, `solid.law.parameters.G=1e6`,
    /// `solid.shape.radius=0.02`, `output.probes[2].at=(0.5,0.5)` (VALUE is RON; a string setting
    /// takes it unquoted). A setting absent from the file is added. Repeatable, applied in order.
    #[arg(long = "set", value_name = "PATH=VALUE", value_parser = Override::parse)]
    set: Vec<Override>,
    /// Multiply every grid dimension by F (rounded), keeping the domain: the speed/accuracy
    /// knob. Applied after the --set options.
    #[arg(long, value_name = "F")]
    refine: Option<f64>,
}

impl SceneOverrides {
    fn list(self) -> Vec<Override> {
        let mut list = self.set;
        list.extend(self.refine.map(Override::Refine));
        list
    }
}

#[derive(Subcommand)]
enum Command {
    /// Run a scene: VTK fields, probes, profiles and run.json in the output folder.
    Run {
        /// The scene file (RON).
        scene: PathBuf,
        #[command(flatten)]
        overrides: SceneOverrides,
        /// Output folder (default: the scene's output.folder, else out/{scene name}/).
        #[arg(long)]
        out: Option<PathBuf>,
        /// Print the assembled stage pipeline and exit without running.
        #[arg(long)]
        print_schedule: bool,
        /// No progress bar.
        #[arg(long, short)]
        quiet: bool,
        /// Write a checkpoint to OUT/checkpoint/latest.efsick every T of simulated time (the
        /// latest only; checkpoints never change Δt). One is also written on SIGINT/SIGTERM and
        /// when a step fails.
        #[arg(long, value_name = "T")]
        checkpoint_every: Option<f64>,
        /// Worker threads of the parallel stages (default: $RAYON_NUM_THREADS, else all cores; at
        /// most 4 per core).
        #[arg(long)]
        threads: Option<usize>,
        /// Replace the outputs of an earlier run in the output folder (run.json, probes.csv,
        /// fields.pvd, VTK files, profiles, its checkpoint); without it such a folder is refused.
        #[arg(long)]
        overwrite: bool,
    },
    /// Continue a run from the latest checkpoint in its output folder, appending to its outputs.
    ///
    /// The scene is read again from the file the run started with, with the run's --set and
    /// --refine applied again; a changed scene or law library is refused (exit code 2) with the list of what differs — except `time.end`,
    /// which may be moved past the checkpoint to continue a run beyond its end.
    Resume {
        /// The run's output folder.
        dir: PathBuf,
        /// Checkpoint interval (default: the interrupted run's).
        #[arg(long, value_name = "T")]
        checkpoint_every: Option<f64>,
        /// No progress bar.
        #[arg(long, short)]
        quiet: bool,
    },
    /// Validate a scene (syntax, ranges, the pipeline it needs) without running it.
    Check {
        /// The scene file (RON).
        scene: PathBuf,
        #[command(flatten)]
        overrides: SceneOverrides,
    },
    /// Describe a run's VTK files: format, axes, units and every array (location, components
    /// in file order, meaning, unit), and its plane slices, from the `vtk` section of
    /// DIR/run.json.
    DescribeOutput {
        /// The run's output folder.
        dir: PathBuf,
    },
    /// Plot a run without ParaView: PNGs of the probe time series and of a field.
    ///
    /// Writes OUT/probes.png (every probes.csv column against time) and
    /// OUT/FIELD_tTIME.png (a cell field at an output time, colour-mapped, with the solid's
    /// φ = ½ contour over it when the run has a solid); of a three-dimensional run, the plane
    /// --slice names (OUT/FIELD_tTIME_z0.5.png).
    Plot {
        /// The run's output folder.
        dir: PathBuf,
        /// The field (a VTK array: velocity, pressure, solid_fraction, B, stress, …; default
        /// solid_fraction with a solid, else pressure).
        #[arg(long)]
        field: Option<String>,
        /// The component of a vector or tensor field (default: a vector's magnitude, a
        /// tensor's XX component).
        #[arg(long)]
        component: Option<usize>,
        /// The output time to plot (the nearest written; default the last).
        #[arg(long, value_name = "T")]
        time: Option<f64>,
        /// The plane of a three-dimensional run to draw, `x=V`, `y=V` or `z=V` (its cell
        /// values interpolated to the plane as `output.slices` are); required for a 3-D run.
        #[arg(long, value_name = "AXIS=V", value_parser = plot::SliceAt::parse)]
        slice: Option<plot::SliceAt>,
        /// Where the PNGs go (default DIR/plots).
        #[arg(long)]
        out: Option<PathBuf>,
    },
    /// List the constitutive laws, with their parameters, units, defaults and ranges.
    ///
    /// Shows the law libraries given, or without any, every law found on the law search path
    /// ($EFSI_LAW_PATH, next to efsi, the build's target folders).
    ///
    /// With --check, runs the tangent check (the one every law passes when loaded: the tangent
    /// against central differences of the stress at 26 deformed states, default parameters) on
    /// each library given, or on every law found if none is; exit code 2 if a law fails it.
    Laws {
        /// Law libraries to describe (e.g. one built from plugins/law-template); none: every
        /// law on the search path.
        paths: Vec<PathBuf>,
        /// Run the tangent check on the libraries instead of describing them.
        #[arg(long)]
        check: bool,
    },
    /// Run a scene over a grid of settings as Dask tasks: `efsi sweep SCENE --grid PATH=V1,V2 …
    /// [--scheduler ADDRESS] [--out FILE]`.
    ///
    /// Runs `python -m efsi sweep` of the efsi Python package (the interpreter: $EFSI_PYTHON,
    /// else python3), which prints the table and writes it as CSV or Parquet; `--help` there
    /// lists the options. Without --scheduler the runs go to a LocalCluster on this machine.
    #[command(disable_help_flag = true)]
    Sweep {
        /// The scene file and the sweep's options, passed on.
        #[arg(trailing_var_arg = true, allow_hyphen_values = true, num_args = 0..)]
        args: Vec<std::ffi::OsString>,
    },
}

fn load(path: &Path, overrides: &[Override]) -> Result<Simulation, EfsiError> {
    let scene = Scene::load_with(path, overrides)?;
    efsi_run::simulation(scene, path, &efsi_stages::builtin())
}

fn main() -> ExitCode {
    // Past a file-size limit a write fails with EFBIG instead of the signal killing the
    // process: the run then stops as on a full disk, with its checkpoint and run.json.
    // SAFETY: setting a signal's disposition to SIG_IGN before any thread starts.
    #[cfg(unix)]
    unsafe {
        libc::signal(libc::SIGXFSZ, libc::SIG_IGN);
    }
    let cli = Cli::parse();
    match cli.command {
        Command::Check { scene, overrides } => exit(check_scene(&scene, &overrides.list())),
        Command::Run {
            scene,
            overrides,
            out,
            print_schedule,
            quiet,
            checkpoint_every,
            threads,
            overwrite,
        } => {
            let overrides = overrides.list();
            on_workers(threads, || {
                run_scene(
                    &scene,
                    &overrides,
                    out,
                    print_schedule,
                    quiet,
                    checkpoint_every,
                    overwrite,
                )
            })
        }
        Command::Resume {
            dir,
            checkpoint_every,
            quiet,
        } => on_workers(None, || resume_run(&dir, quiet, checkpoint_every)),
        Command::Plot {
            dir,
            field,
            component,
            time,
            slice,
            out,
        } => {
            let request = plot::FieldRequest {
                field,
                component,
                time,
                slice,
            };
            plot_run(&dir, out, &request)
        }
        Command::DescribeOutput { dir } => {
            print_lines(describe_output(&dir).map(|text| vec![text]))
        }
        Command::Laws {
            paths,
            check: false,
        } => list_laws(&paths),
        Command::Laws { paths, check: true } => check_laws(&paths),
        Command::Sweep { args } => sweep(&args),
    }
}

/// The exit code of a command's `result`, its error said: 0, 128 + the signal that stopped a
/// run, or the error's code.
fn exit(result: Result<Option<usize>, EfsiError>) -> ExitCode {
    match result {
        Ok(None) => ExitCode::SUCCESS,
        Ok(Some(signal)) => ExitCode::from((128 + signal.min(127)) as u8),
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::from(e.exit_code() as u8)
        }
    }
}

/// `efsi check`: the scene loaded and its pipeline built, described in one line.
fn check_scene(scene: &Path, overrides: &[Override]) -> Result<Option<usize>, EfsiError> {
    let sim = load(scene, overrides)?;
    let g = &sim.grid;
    out!(
        "{}: ok — {} {} cells, stages: {}",
        scene.display(),
        match g.geometry {
            efsi_core::Geometry::Planar => "planar",
            efsi_core::Geometry::Axisymmetric => "axisymmetric",
            efsi_core::Geometry::Cartesian3D => "three-dimensional",
        },
        if g.is_3d() {
            format!("{}×{}×{}", g.nx, g.ny, g.nz)
        } else {
            format!("{}×{}", g.nx, g.ny)
        },
        sim.pipeline().stage_names().join(" → ")
    );
    Ok(None)
}

/// Run `work` (a run or a resume) on a pool of the worker threads asked for (`threads`, else
/// $RAYON_NUM_THREADS, else all cores) and return its exit code ([`exit`]): the run loop runs on
/// a worker of the pool, so the stages' parallel loops start from inside it (cheaper than
/// injecting each from outside, and allocation-free). Exit code 1 if the pool cannot be had.
fn on_workers(
    threads: Option<usize>,
    work: impl FnOnce() -> Result<Option<usize>, EfsiError> + Send,
) -> ExitCode {
    let threads = match efsi_run::setup::worker_threads(threads, "--threads") {
        Ok(n) => n,
        Err(e) => return exit(Err(e)),
    };
    let mut pool = rayon::ThreadPoolBuilder::new();
    if let Some(n) = threads {
        pool = pool.num_threads(n);
    }
    match pool.build() {
        Ok(pool) => exit(pool.install(work)),
        Err(e) => {
            eprintln!("error: cannot start the worker threads: {e}");
            ExitCode::from(1)
        }
    }
}

/// `efsi plot`: the plots `request` asks for of the run in `dir`, into `out` (default
/// `dir/plots`), each file written named.
fn plot_run(dir: &Path, out: Option<PathBuf>, request: &plot::FieldRequest) -> ExitCode {
    let out = out.unwrap_or_else(|| dir.join("plots"));
    print_lines(plot::plot(dir, &out, request).map(|files| {
        files
            .iter()
            .map(|f| format!("wrote {}", f.display()))
            .collect()
    }))
}

/// Print the lines of a command that reads a run's files, or its error (exit code 2).
fn print_lines(result: Result<Vec<String>, String>) -> ExitCode {
    match result {
        Ok(lines) => {
            for l in lines {
                out!("{l}");
            }
            ExitCode::SUCCESS
        }
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::from(2)
        }
    }
}

/// Run options with a stop flag that SIGINT and SIGTERM set to their number. A second signal
/// while the first is being handled exits at once (128 + signal).
fn options(checkpoint_every: Option<f64>, overwrite: bool) -> Result<RunOptions, EfsiError> {
    if let Some(t) = checkpoint_every
        && !(t.is_finite() && t > 0.0)
    {
        return Err(EfsiError::Config {
            path: PathBuf::from("--checkpoint-every"),
            field: "checkpoint_every".into(),
            message: format!("must be a positive time, got {t}"),
        });
    }
    let stop = Arc::new(AtomicUsize::new(0));
    let armed = Arc::new(AtomicBool::new(false));
    for sig in [signal_hook::consts::SIGINT, signal_hook::consts::SIGTERM] {
        let registered =
            signal_hook::flag::register_conditional_shutdown(sig, 128 + sig, armed.clone())
                .and_then(|_| signal_hook::flag::register(sig, armed.clone()))
                .and_then(|_| signal_hook::flag::register_usize(sig, stop.clone(), sig as usize));
        if let Err(e) = registered {
            return Err(EfsiError::io(format!("signal handler for signal {sig}"), e));
        }
    }
    Ok(RunOptions {
        checkpoint_every,
        stop: Some(stop),
        save_last_good: true,
        overwrite,
    })
}

fn progress_bar(quiet: bool) -> ProgressBar {
    let bar = if quiet {
        ProgressBar::hidden()
    } else {
        ProgressBar::new(1000)
    };
    bar.set_style(
        ProgressStyle::with_template(
            "{bar:30} {percent:>3}% {msg} [{elapsed_precise} elapsed, ~{eta} left]",
        )
        .unwrap_or_else(|_| ProgressStyle::default_bar()),
    );
    bar
}

fn draw(bar: &ProgressBar, last_draw: &mut f64, p: &Progress) {
    if p.wall - *last_draw > 0.1 || p.t >= p.end {
        *last_draw = p.wall;
        bar.set_position((1000.0 * p.t / p.end).round() as u64);
        bar.set_message(format!(
            "t = {:.4e} / {:.4e}  step {}  Δt = {:.3e}",
            p.t, p.end, p.step, p.dt
        ));
    }
}

fn resume_run(
    dir: &Path,
    quiet: bool,
    checkpoint_every: Option<f64>,
) -> Result<Option<usize>, EfsiError> {
    let opts = options(checkpoint_every, false)?;
    let bar = progress_bar(quiet);
    let mut last_draw = 0.0;
    let mut progress = |p: &Progress| draw(&bar, &mut last_draw, p);
    let result = resume(dir, &efsi_stages::builtin(), &opts, &mut progress);
    bar.finish_and_clear();
    let (sim, outcome) = result?;
    Ok(report(&sim, &outcome, dir))
}

fn run_scene(
    path: &Path,
    overrides: &[Override],
    out: Option<PathBuf>,
    print_schedule: bool,
    quiet: bool,
    checkpoint_every: Option<f64>,
    overwrite: bool,
) -> Result<Option<usize>, EfsiError> {
    let mut sim = load(path, overrides)?;
    if print_schedule {
        out!("{}", sim.pipeline());
        return Ok(None);
    }
    let dir = out
        .or_else(|| sim.scene.output_spec().ok().and_then(|o| o.folder))
        .unwrap_or_else(|| Path::new("out").join(&sim.scene.name));
    let opts = options(checkpoint_every, overwrite)?;
    let bar = progress_bar(quiet);
    let mut last_draw = 0.0;
    let mut progress = |p: &Progress| draw(&bar, &mut last_draw, p);
    let outcome = run_with(&mut sim, &dir, &opts, &mut progress);
    bar.finish_and_clear();
    let outcome = outcome?;
    Ok(report(&sim, &outcome, &dir))
}

/// Print the outcome and the timing table; the signal that stopped the run, if one did.
fn report(sim: &Simulation, outcome: &RunOutcome, dir: &Path) -> Option<usize> {
    let cells = sim.grid.cells() as f64;
    let steps = outcome.steps_this_run.max(1) as f64;
    if let Some((step, t, version)) = &outcome.resumed_from {
        let other = if version != env!("CARGO_PKG_VERSION") {
            format!(" (written by efsi {version})")
        } else {
            String::new()
        };
        out!("resumed from the checkpoint at step {step}, t = {t:.6e}{other}");
    }
    out!(
        "{}: {:?} at t = {:.6e} after {} steps in {:.2} s ({:.0} ns per cell-step); outputs in {}",
        sim.scene.name,
        outcome.stop,
        outcome.t,
        outcome.steps,
        outcome.wall_seconds,
        outcome.wall_seconds * 1e9 / (cells * steps),
        dir.display()
    );
    if sim.rate_of_change().is_finite() {
        out!("final max|uⁿ⁺¹ − uⁿ|/Δt = {:.3e}", sim.rate_of_change());
    }
    for w in &outcome.warnings {
        eprintln!("warning: {w}");
    }
    out!(
        "{:<18} {:>10} {:>16} {:>14}",
        "stage",
        "seconds",
        "ns/cell-step",
        "iters/step"
    );
    for s in sim.pipeline().timings() {
        out!(
            "{:<18} {:>10.3} {:>16.1} {:>14.1}",
            s.name,
            s.seconds,
            s.seconds * 1e9 / (cells * steps),
            s.iterations as f64 / steps
        );
    }
    match outcome.stop {
        StopReason::Interrupted { signal } => {
            let ck = outcome
                .checkpoint
                .as_ref()
                .map_or_else(|| "-".to_string(), |p| p.display().to_string());
            eprintln!(
                "stopped by signal {signal} after step {} (t = {:.6e}); checkpoint {ck}; continue with `efsi resume {}`",
                outcome.steps,
                outcome.t,
                dir.display()
            );
            Some(signal)
        }
        _ => None,
    }
}

/// `efsi describe-output DIR`: the `vtk` section of `DIR/run.json` as text.
fn describe_output(dir: &Path) -> Result<String, String> {
    let path = dir.join("run.json");
    let text = efsi_run::output::read::read_regular_text(
        &path,
        efsi_run::output::read::MAX_RUN_JSON_BYTES,
    )
    .map_err(|e| format!("{}: {e}", path.display()))?;
    let json: serde_json::Value =
        serde_json::from_str(&text).map_err(|e| format!("{}: {e}", path.display()))?;
    let vtk = json.get("vtk").ok_or_else(|| {
        format!(
            "{}: no `vtk` section (written by an older efsi?)",
            path.display()
        )
    })?;
    let s = |v: &serde_json::Value| v.as_str().map_or_else(|| v.to_string(), str::to_string);
    let mut out = format!(
        "VTK files of {}: {} arrays, compression {}, point data {}\n",
        dir.display(),
        s(&vtk["precision"]),
        s(&vtk["compression"]),
        vtk["point_data"]
    );
    if let Some(notes) = vtk["field_data"].as_object() {
        for (k, v) in notes {
            out.push_str(&format!("{k}: {}\n", s(v)));
        }
    }
    for a in vtk["arrays"].as_array().into_iter().flatten() {
        let components: Vec<String> = a["components"]
            .as_array()
            .into_iter()
            .flatten()
            .map(s)
            .collect();
        out.push_str(&format!(
            "\n{} ({}; {}) [{}]\n  {}\n",
            s(&a["name"]),
            s(&a["location"]),
            components.join(", "),
            s(&a["unit"]),
            s(&a["meaning"])
        ));
    }
    out.push_str(&describe_slices(vtk));
    Ok(out.trim_end().to_string())
}

/// The plane slices `run.json`'s `vtk` section lists (none in a run without them), as text.
fn describe_slices(vtk: &serde_json::Value) -> String {
    let Some(slices) = vtk["slices"].as_array().filter(|s| !s.is_empty()) else {
        return String::new();
    };
    let s = |v: &serde_json::Value| v.as_str().map_or_else(|| v.to_string(), str::to_string);
    let mut out =
        "\nplane slices (VTK files of the plane, flat along its normal; the arrays above \
                   interpolated linearly between the two cell layers around it):\n"
            .to_string();
    for slice in slices {
        let when = match slice["every"].as_f64() {
            Some(every) => format!("every {every}"),
            None => "at the start and the end".into(),
        };
        let arrays: Vec<String> = slice["arrays"]
            .as_array()
            .into_iter()
            .flatten()
            .map(s)
            .collect();
        out.push_str(&format!(
            "  {}: the plane {} = {}, {when}, {}: {}\n",
            s(&slice["name"]),
            s(&slice["normal"]),
            s(&slice["at"]),
            s(&slice["collection"]),
            arrays.join(", ")
        ));
    }
    out
}

/// `efsi laws --check`: the tangent checks of each library in `paths` (every law found if
/// none) — on in-plane tensors, and for an ABI-v2 library on full 3-D tensors too; exit code 2
/// if a law fails one or cannot be checked.
fn check_laws(paths: &[PathBuf]) -> ExitCode {
    let mut libraries = paths.to_vec();
    let mut failed = false;
    if libraries.is_empty() {
        for law in efsi_laws_host::list_laws(&[]) {
            match law {
                Listed::Law(info) => libraries.push(info.path),
                Listed::Skipped(e) => eprintln!("warning: skipped {e}"),
                Listed::Failed(e) => {
                    eprintln!("error: {e}");
                    failed = true;
                }
            }
        }
    }
    if libraries.is_empty() && !failed {
        eprintln!("error: no laws found to check");
        return ExitCode::from(2);
    }
    for path in &libraries {
        match efsi_laws_host::check_library(path) {
            Ok(c) => {
                let full = match &c.full {
                    Some(check) => format!("full 3-D tensors: {check}"),
                    None => format!(
                        "full 3-D tensors: not checked — ABI v{} carries in-plane tensors only (refused in 3-D scenes)",
                        c.info.abi_version
                    ),
                };
                let embedding = c.embedding.as_ref().map_or(String::new(), |e| {
                    format!("\n  in-plane vs full evaluation of in-plane tensors: {e}")
                });
                let text = format!(
                    "{} ({}, ABI v{}): tangent check {} — in-plane tensors: {}\n  {full}{embedding}",
                    c.info.name,
                    path.display(),
                    c.info.abi_version,
                    if c.passed() { "passed" } else { "FAILED" },
                    c.in_plane
                );
                if c.passed() {
                    out!("{text}");
                } else {
                    eprintln!("error: {text}");
                    failed = true;
                }
            }
            Err(e) => {
                eprintln!("error: {e}");
                failed = true;
            }
        }
    }
    if failed {
        ExitCode::from(2)
    } else {
        ExitCode::SUCCESS
    }
}

/// `efsi sweep`: hand over to the Python package's `python -m efsi sweep` (exit code 2 if the
/// interpreter cannot be started).
fn sweep(args: &[std::ffi::OsString]) -> ExitCode {
    let python = std::env::var_os("EFSI_PYTHON").unwrap_or_else(|| "python3".into());
    let mut c = std::process::Command::new(&python);
    c.args(["-m", "efsi", "sweep"]).args(args);
    #[cfg(unix)]
    {
        use std::os::unix::process::CommandExt as _;
        let e = c.exec();
        eprintln!(
            "error: efsi sweep needs the efsi Python package: cannot start {} ({e}); set EFSI_PYTHON to the Python that has it (see docs/python.md)",
            Path::new(&python).display()
        );
        ExitCode::from(2)
    }
    #[cfg(not(unix))]
    match c.status() {
        Ok(s) => ExitCode::from(s.code().unwrap_or(1).clamp(0, 255) as u8),
        Err(e) => {
            eprintln!(
                "error: efsi sweep needs the efsi Python package: cannot start {} ({e}); set EFSI_PYTHON to the Python that has it (see docs/python.md)",
                Path::new(&python).display()
            );
            ExitCode::from(2)
        }
    }
}

/// `efsi laws [LIB…]`: describes the libraries given, or without any every law found on the
/// search path, where a file that cannot be trusted (truncated, corrupted, another ABI) is
/// skipped with a warning naming it and why; exit code 2 if a library given could not be read.
fn list_laws(paths: &[PathBuf]) -> ExitCode {
    let laws = if paths.is_empty() {
        efsi_laws_host::list_laws(&[])
    } else {
        paths
            .iter()
            .map(|p| efsi_laws_host::describe(p).map_or_else(Listed::Failed, Listed::Law))
            .collect()
    };
    if laws.is_empty() {
        out!(
            "no laws found; searched: {}",
            efsi_laws_host::loader::search_dirs()
                .iter()
                .map(|d| d.display().to_string())
                .collect::<Vec<_>>()
                .join(", ")
        );
    }
    let mut failed = false;
    for law in laws {
        match law {
            Listed::Law(info) => {
                use std::io::Write as _;
                let _ = write!(std::io::stdout(), "{info}");
            }
            Listed::Skipped(e) => eprintln!("warning: skipped {e}"),
            Listed::Failed(e) => {
                eprintln!("error: {e}");
                failed = true;
            }
        }
    }
    if failed {
        ExitCode::from(2)
    } else {
        ExitCode::SUCCESS
    }
}
