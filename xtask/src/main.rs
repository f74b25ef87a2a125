//! Project automation.
//!
//! - `cargo xtask test`: everything CI runs — formatting, clippy and rustdoc (warnings are
//!   errors), the Rust test suite, and the Python tests (VTK files read back by the official `vtk` wheel,
//!   the FMUs, the `efsi` Python package built by maturin and installed there, sweeps on a local
//!   Dask cluster) in a virtual environment under `target/venv` that it creates on first use.
//! - `cargo xtask run SCENE [ARGS…]`: build the whole workspace in release (the `efsi` binary
//!   and the law plugin libraries it loads) and run `efsi run SCENE ARGS…`.
//! - `cargo xtask ghia DIR RE`: max |deviation| of a finished cavity run's last centreline
//!   profiles (`DIR/profiles/u_x0.5_t*.csv`, `v_y0.5_t*.csv`) from Ghia et al. (1982); refuses a
//!   run whose Reynolds number (`ρ U L / μ` of the scene in `DIR/run.json`) is not `RE`, and names
//!   the Reynolds numbers the reference has when it has no column for `RE`.
//! - `cargo xtask bench [--quick] [--roofline] [--cases LIST] [--threads N] [--repeat R]
//!   [--out DIR] [--binary PATH] [--write-docs]`: the
//!   Re = 1000 lid-driven cavity and the axisymmetric falling drop (cases `cavity<N>`,
//!   `drop<N>`, suffix `-ic` for the IC(0) pressure preconditioner, `-vmg` for the block
//!   multigrid viscous one) and the sphere impact at 35 cells per radius (case `sphere`, the
//!   whole run of `cases/sphere_impact.ron`; `-ej` for the Jacobi-preconditioned elastic step;
//!   default `cavity128,cavity256,drop128,drop256,sphere`), each on one thread and on N
//!   (default all), for ns
//!   per cell-step in total and per stage, solver iterations per step and the drop's fall;
//!   medians of R runs (the 1- and N-thread runs alternate; the speed-up of each pair is
//!   printed as a range and kept in the JSON), written to `DIR/bench.json` (default
//!   `target/bench`). A benchmark, not a test: timings are never asserted. With `--roofline`
//!   it also measures the machine's triad bandwidth and prints, per case and stage, the bytes
//!   per cell-step of a compulsory-traffic model, the achieved bandwidth and its fraction of the
//!   limit ([`roofline`]). `--binary PATH` times that build of `efsi` instead of building this
//!   one (a baseline for before/after figures). `--write-docs` copies `bench.json` to
//!   `docs/bench/bench.json` and renders `docs/benchmarks.md` again.
//! - `cargo xtask bench-paper [--quick] [--case NAME]… [--out DIR] [--set PATH=VALUE]…
//!   [--write-docs]`: build the workspace in release and run the paper's cases
//!   (`tests/src/paper/`), writing `DIR/REPORT.md` and `DIR/summary.json` (default
//!   `target/bench-paper`); `--write-docs` merges the run's cases into `docs/bench/paper.json`
//!   (each replaces its namesake, with the command, commit and machine that measured it) and
//!   renders `docs/benchmarks.md` again.
//! - `cargo xtask docs [--check | --merge SUMMARY_JSON]`: render the generated section of
//!   `docs/benchmarks.md` from `docs/bench/*.json` ([`xtask::bench_page`]), only check that it
//!   is in sync, or first merge the cases of a `bench-paper` run's `summary.json` into
//!   `docs/bench/paper.json` (as `--write-docs` does).
//! - `cargo xtask fmu [SCENE [--parameter PATH[=UNIT]] [--input NAME[=UNIT]]
//!   [--output PROBE[=UNIT]] [--range NAME=MIN..MAX]…]`: build the FMU library and the shipped
//!   laws (profile `fmu-release`: release code, stripped) and package the scene as
//!   `target/fmu/<name>.fmu` (FMI 2.0 Co-Simulation) and `target/fmu/<name>_fmi3.fmu` (FMI 3.0),
//!   with their documentation and licence; without a scene, the sphere impact.

mod bench;
mod csv;
mod docs;
mod fmu;
mod ghia;
mod roofline;
mod test;
mod zip;

use std::path::{Path, PathBuf};
use std::process::{Command, ExitCode};

/// The workspace's root folder.
fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .parent()
        .expect("workspace root")
        .to_path_buf()
}

/// The `cargo` that runs xtask (`$CARGO`), else `cargo` on the path.
fn cargo() -> Command {
    Command::new(std::env::var("CARGO").unwrap_or_else(|_| "cargo".into()))
}

/// Run a command in the workspace root; Err names it if it fails.
fn run(mut cmd: Command, what: &str) -> Result<(), String> {
    eprintln!("==> {what}");
    let status = cmd
        .current_dir(root())
        .status()
        .map_err(|e| format!("{what}: cannot start: {e}"))?;
    if status.success() {
        Ok(())
    } else {
        Err(format!("{what}: failed ({status})"))
    }
}

/// `cargo xtask run SCENE [ARGS…]`: build the workspace (release) and run `efsi run SCENE ARGS…`.
fn run_scene(args: &[String]) -> Result<(), String> {
    if args.is_empty() {
        return Err("usage: cargo xtask run SCENE [efsi run options]".into());
    }
    let mut c = cargo();
    c.args(["build", "--quiet", "--release", "--workspace"]);
    run(c, "build efsi and the law plugins (release)")?;
    let mut c = Command::new(root().join("target/release/efsi"));
    c.arg("run").args(args);
    let status = c.status().map_err(|e| format!("cannot start efsi: {e}"))?;
    if status.success() {
        Ok(())
    } else {
        std::process::exit(status.code().unwrap_or(1))
    }
}

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let result = match args.first().map(String::as_str) {
        Some("test") => test::test(),
        Some("bench") => bench::bench(&args[1..]),
        Some("ghia") => ghia::ghia(&args[1..]),
        Some("run") => run_scene(&args[1..]),
        Some("bench-paper") => bench_paper(&args[1..]),
        Some("fmu") => fmu::fmu(&args[1..]).map(|_| ()),
        Some("docs") => docs::docs(&args[1..]),
        _ => Err(
            "usage: cargo xtask <run SCENE | test | fmu [SCENE [--parameter PATH[=UNIT]] [--input NAME[=UNIT]] [--output PROBE[=UNIT]] [--range NAME=MIN..MAX]…] | bench [--quick] [--roofline] [--cases LIST] \
             [--threads N] [--repeat R] [--out DIR] [--binary PATH] [--write-docs] | bench-paper [--quick] [--case NAME]… \
             [--out DIR] [--set PATH=VALUE]… [--write-docs] | docs [--check] | ghia DIR RE>"
                .into(),
        ),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("xtask: {e}");
            ExitCode::FAILURE
        }
    }
}

/// `cargo xtask bench-paper [--quick] [--case NAME…] [--out DIR] [--set PATH=VALUE]…
/// [--write-docs]`: build the workspace (release, so the law libraries exist) and run the
/// paper's cases (`tests/src/paper/`). Exits with the runner's status (1 if a check failed);
/// with `--write-docs`, the cases of a run that finished (their checks passed or not) replace
/// their namesakes in the page's snapshot.
fn bench_paper(args: &[String]) -> Result<(), String> {
    let write_docs = args.iter().any(|a| a == "--write-docs");
    let args: Vec<&String> = args.iter().filter(|a| *a != "--write-docs").collect();
    let mut c = cargo();
    c.args(["build", "--quiet", "--release", "--workspace"]);
    run(c, "build efsi, the law plugins and bench-paper (release)")?;
    let mut c = Command::new(root().join("target/release/bench-paper"));
    c.args(&args).current_dir(root());
    let status = c
        .status()
        .map_err(|e| format!("cannot start bench-paper: {e}"))?;
    // 0: every check passed; 1: the run finished and some check failed.
    let finished = matches!(status.code(), Some(0 | 1));
    if write_docs && finished {
        let out = args
            .windows(2)
            .find(|w| *w[0] == "--out")
            .map_or_else(|| root().join("target/bench-paper"), |w| root().join(w[1]));
        docs::merge_paper_snapshot(&out.join("summary.json"))?;
    }
    if status.success() {
        Ok(())
    } else {
        std::process::exit(status.code().unwrap_or(1))
    }
}
