//! The `efsi` command: run, check and inspect full-Eulerian FSI scenes.
//!
//! Exit codes: 0 success, 1 I/O failure, 2 bad input (scene, settings), 3 a run that failed
//! numerically (non-convergence, non-finite values, collapsing step).

use clap::{Parser, Subcommand};
use efsi_core::run::{Progress, run};
use efsi_core::{EfsiError, Scene, Simulation};
use indicatif::{ProgressBar, ProgressStyle};
use std::path::{Path, PathBuf};
use std::process::ExitCode;

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

#[derive(Subcommand)]
enum Command {
    /// Run a scene: VTK fields, probes, profiles and run.json in the output folder.
    Run {
        /// The scene file (RON).
        scene: PathBuf,
        /// Output folder (default: the scene's output.folder, else out/<scene name>/).
        #[arg(long)]
        out: Option<PathBuf>,
        /// Print the assembled stage pipeline and exit without running.
        #[arg(long)]
        print_schedule: bool,
        /// No progress bar.
        #[arg(long, short)]
        quiet: bool,
        /// Worker threads of the parallel stages (default: $RAYON_NUM_THREADS, else all cores).
        #[arg(long)]
        threads: Option<usize>,
    },
    /// Validate a scene (syntax, ranges, the pipeline it needs) without running it.
    Check {
        /// The scene file (RON).
        scene: PathBuf,
    },
    /// List the constitutive laws, with their parameters, units, defaults and ranges.
    ///
    /// Shows the shipped laws found on the law search path ($EFSI_LAW_PATH, next to efsi, the
    /// build's target folders) and every law library given.
    Laws {
        /// Law libraries to describe as well (e.g. one built from plugins/law-template).
        paths: Vec<PathBuf>,
    },
}

fn load(path: &Path) -> Result<Simulation, EfsiError> {
    let scene = Scene::load(path)?;
    Simulation::new(scene, path, &efsi_stages::builtin())
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Check { scene } => load(&scene).map(|sim| {
            println!(
                "{}: ok — {} {}×{} cells, stages: {}",
                scene.display(),
                match sim.grid.geometry {
                    efsi_core::Geometry::Planar => "planar",
                    efsi_core::Geometry::Axisymmetric => "axisymmetric",
                },
                sim.grid.nx,
                sim.grid.ny,
                sim.pipeline().stage_names().join(" → ")
            );
        }),
        Command::Run {
            scene,
            out,
            print_schedule,
            quiet,
            threads,
        } => {
            // The run loop runs on a worker of the pool, so the stages' parallel loops start
            // from inside it (cheaper than injecting each from outside, and allocation-free).
            let mut pool = rayon::ThreadPoolBuilder::new();
            if let Some(n) = threads {
                pool = pool.num_threads(n.max(1));
            }
            match pool.build() {
                Ok(pool) => pool.install(|| run_scene(&scene, out, print_schedule, quiet)),
                Err(e) => {
                    eprintln!("error: cannot start the worker threads: {e}");
                    return ExitCode::from(1);
                }
            }
        }
        Command::Laws { paths } => return list_laws(&paths),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::from(e.exit_code() as u8)
        }
    }
}

fn run_scene(
    path: &Path,
    out: Option<PathBuf>,
    print_schedule: bool,
    quiet: bool,
) -> Result<(), EfsiError> {
    let mut sim = load(path)?;
    if print_schedule {
        println!("{}", sim.pipeline());
        return Ok(());
    }
    let dir = out
        .or_else(|| sim.scene.output.folder.clone())
        .unwrap_or_else(|| Path::new("out").join(&sim.scene.name));
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
    let mut last_draw = 0.0;
    let mut progress = |p: &Progress| {
        if p.wall - last_draw > 0.1 || p.t >= p.end {
            last_draw = p.wall;
            bar.set_position((1000.0 * p.t / p.end).round() as u64);
            bar.set_message(format!(
                "t = {:.4e} / {:.4e}  step {}  Δt = {:.3e}",
                p.t, p.end, p.step, p.dt
            ));
        }
    };
    let outcome = run(&mut sim, &dir, &mut progress);
    bar.finish_and_clear();
    let outcome = outcome?;
    let cells = sim.grid.cells() as f64;
    let steps = outcome.steps.max(1) as f64;
    println!(
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
        println!("final max|uⁿ⁺¹ − uⁿ|/Δt = {:.3e}", sim.rate_of_change());
    }
    println!(
        "{:<16} {:>10} {:>16} {:>14}",
        "stage", "seconds", "ns/cell-step", "iters/step"
    );
    for s in sim.pipeline().timings() {
        println!(
            "{:<16} {:>10.3} {:>16.1} {:>14.1}",
            s.name,
            s.seconds,
            s.seconds * 1e9 / (cells * steps),
            s.iterations as f64 / steps
        );
    }
    Ok(())
}

/// `efsi laws`: describes every law found; exit code 2 if any library could not be read.
fn list_laws(paths: &[PathBuf]) -> ExitCode {
    let laws = efsi_core::law::list_laws(paths);
    if laws.is_empty() {
        println!(
            "no laws found; searched: {}",
            efsi_core::law::loader::search_dirs()
                .iter()
                .map(|d| d.display().to_string())
                .collect::<Vec<_>>()
                .join(", ")
        );
    }
    let mut failed = false;
    for law in laws {
        match law {
            Ok(info) => print!("{info}"),
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
