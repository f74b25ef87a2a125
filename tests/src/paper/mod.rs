//! The paper's cases (seed §5) as runnable benchmarks: each case runs its scene at several
//! resolutions, measures its error against a reference, checks the targets and
//! produces plots and CSV series. `cargo xtask bench-paper` runs them all and writes
//! `REPORT.md` and `summary.json`; the integration tests run the `--quick` versions and assert
//! their checks.

pub mod bodies;
pub mod case;
pub mod couette;
pub mod couette_mr;
pub mod disk_cavity;
pub mod extruded_cavity;
pub mod falling_drop;
pub mod lid_driven_cube;
pub mod oscillating_disk;
pub mod plot;
pub mod shear_rectangle;
pub mod soft_sphere_cube;
pub mod soft_wall;
pub mod sphere;
pub mod sphere_3d;
pub mod sphere_oblique;
pub mod stability;
pub mod vof_transport_3d;

use efsi_core::{EfsiError, Scene, Simulation};
use efsi_run::SceneOverrides;
use efsi_run::run::{Progress, run};
use serde::Serialize;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// How a bench-paper run is asked for.
#[derive(Clone, Debug)]
pub struct Options {
    /// The reduced version (what the test suite runs).
    pub quick: bool,
    /// The output folder.
    pub out: PathBuf,
    /// Show a progress bar per run.
    pub progress: bool,
    /// Settings applied to every run's scene after the case has made it (`--set KEY=VALUE`):
    /// the cases with another setting, e.g. `numerics.elastic.coupling=Coupled`. The report
    /// names them; a setting a case's scene cannot take fails that case's runs.
    pub overrides: Vec<efsi_core::Override>,
}

impl Options {
    /// `scene` with [`Options::overrides`] applied.
    pub fn adjust(&self, mut scene: Scene) -> Result<Scene, String> {
        scene.apply(&self.overrides).map_err(|e| e.to_string())?;
        Ok(scene)
    }
}

/// One resolution (or setting) of a case: its cost and its figures.
#[derive(Clone, Debug, Serialize)]
pub struct Run {
    /// What distinguishes the run ("35 CPR", "N = 64", "CFL 0.2").
    pub label: String,
    /// Cells of the grid.
    pub cells: usize,
    /// Time steps taken.
    pub steps: u64,
    /// Wall time (s).
    pub wall_seconds: f64,
    /// The case's error metric against its reference (see [`Report::error_metric`]).
    pub error: Option<f64>,
    /// Other figures of the run, by name.
    pub metrics: Vec<(String, f64)>,
    /// Wall time per stage: name, seconds, ns per cell-step, solver iterations per step.
    pub stages: Vec<(String, f64, f64, f64)>,
    /// Where its outputs are.
    pub dir: PathBuf,
}

impl Run {
    /// The record of a finished simulation: its cells, `steps`, wall time and per-stage
    /// timings (no error or metrics yet).
    pub fn of(sim: &Simulation, label: &str, dir: &Path, steps: u64, wall_seconds: f64) -> Run {
        let cells = sim.grid.nx * sim.grid.ny * sim.grid.nz;
        let n = steps.max(1) as f64;
        let timings = sim.pipeline().timings();
        let stages = timings.iter().map(|t| {
            let per_cell = 1e9 * t.seconds / (n * cells as f64);
            (
                t.name.to_string(),
                t.seconds,
                per_cell,
                t.iterations as f64 / n,
            )
        });
        Run {
            label: label.to_string(),
            cells,
            steps,
            wall_seconds,
            error: None,
            metrics: Vec::new(),
            stages: stages.collect(),
            dir: dir.to_path_buf(),
        }
    }

    /// A named metric.
    pub fn metric(&self, name: &str) -> Option<f64> {
        self.metrics
            .iter()
            .find(|(n, _)| n == name)
            .map(|(_, v)| *v)
    }
}

/// A target of the issue, checked on a run.
#[derive(Clone, Debug, Serialize)]
pub struct Check {
    /// What is checked.
    pub what: String,
    /// The measured value, formatted.
    pub value: String,
    /// The target, formatted ("≤ 0.005", "∈ [0.5, 1]").
    pub target: String,
    /// Whether it is met.
    pub pass: bool,
}

impl Check {
    /// `value ≤ limit`.
    pub fn at_most(what: impl Into<String>, value: f64, limit: f64, fmt: &str) -> Check {
        Check {
            what: what.into(),
            value: format_num(value, fmt),
            target: format!("≤ {}", format_num(limit, fmt)),
            pass: value <= limit,
        }
    }

    /// `value ≥ limit`.
    pub fn at_least(what: impl Into<String>, value: f64, limit: f64, fmt: &str) -> Check {
        Check {
            what: what.into(),
            value: format_num(value, fmt),
            target: format!("≥ {}", format_num(limit, fmt)),
            pass: value >= limit,
        }
    }

    /// `lo ≤ value ≤ hi`.
    pub fn within(what: impl Into<String>, value: f64, lo: f64, hi: f64, fmt: &str) -> Check {
        Check {
            what: what.into(),
            value: format_num(value, fmt),
            target: format!("∈ [{}, {}]", format_num(lo, fmt), format_num(hi, fmt)),
            pass: (lo..=hi).contains(&value),
        }
    }
}

/// Format a number as `fmt` says: `e` (3 significant digits, scientific), `%` (a fraction as a
/// percentage), otherwise a fixed number of decimals given by the digit (`"4"`).
pub fn format_num(x: f64, fmt: &str) -> String {
    match fmt {
        "e" => format!("{x:.3e}"),
        "%" => format!("{:.2} %", 100.0 * x),
        d => format!("{x:.*}", d.parse().unwrap_or(4)),
    }
}

/// A case's report section.
#[derive(Clone, Debug, Serialize)]
pub struct Report {
    /// Case name (`sphere_impact`, …).
    pub name: String,
    /// Title.
    pub title: String,
    /// The reference compared with, and its source.
    pub reference: String,
    /// The error metric of [`Run::error`], in words.
    pub error_metric: String,
    /// The runs.
    pub runs: Vec<Run>,
    /// The targets.
    pub checks: Vec<Check>,
    /// Plots: caption and file name (relative to the report).
    pub plots: Vec<(String, String)>,
    /// Findings in words.
    pub notes: Vec<String>,
    /// The stage pipeline the case's scene assembled.
    pub schedule: Vec<String>,
    /// The setting recommended for the speed/accuracy trade, and why.
    pub recommendation: String,
}

impl Report {
    /// Whether every check passes.
    pub fn passed(&self) -> bool {
        self.checks.iter().all(|c| c.pass)
    }
}

/// A case as `--case` names it, and how to run it (see [`case::Case`]).
pub struct Entry {
    /// Name, as `--case` takes it.
    pub name: &'static str,
    /// Runs the case.
    pub run: fn(&Options) -> Result<Report, String>,
}

/// The entry of case `C`.
const fn entry<C: case::Case>() -> Entry {
    Entry {
        name: C::NAME,
        run: case::run::<C>,
    }
}

/// Every case, in report order.
pub const CASES: &[Entry] = &[
    entry::<sphere::SphereImpact>(),
    entry::<sphere_3d::SphereImpact3d>(),
    entry::<sphere_oblique::SphereOblique3d>(),
    entry::<soft_wall::SoftWall>(),
    entry::<disk_cavity::DiskCavity>(),
    entry::<soft_sphere_cube::SoftSphereCube>(),
    entry::<bodies::TwoSoftDisks>(),
    entry::<bodies::ContactMap>(),
    entry::<bodies::SpheresOnAxis>(),
    entry::<bodies::TwentyDisks>(),
    entry::<bodies::DisksInCavity>(),
    entry::<oscillating_disk::OscillatingDisk>(),
    entry::<shear_rectangle::ShearRectangle>(),
    entry::<couette::Couette>(),
    entry::<couette_mr::CouetteMr>(),
    entry::<lid_driven_cube::LidDrivenCube>(),
    entry::<extruded_cavity::ExtrudedCavity>(),
    entry::<falling_drop::FallingDrop>(),
    entry::<vof_transport_3d::VofTransport3d>(),
    entry::<stability::Stability>(),
    entry::<stability::Stability3d>(),
];

/// The workspace's `cases/` folder.
pub fn cases_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../cases")
}

/// Load a scene of `cases/`.
pub fn load_case(file: &str) -> Result<(Scene, PathBuf), String> {
    let path = cases_dir().join(file);
    let scene = Scene::load(&path).map_err(|e| e.to_string())?;
    Ok((scene, path))
}

/// Run `sim` with all outputs into `dir` (a progress bar if `opts` asks for one); returns the
/// finished simulation and its [`Run`] record (no error or metrics yet). The simulation is
/// built by the caller, so it can tell a scene refused before the run from a run that failed.
pub fn execute_built(
    mut sim: Simulation,
    dir: &Path,
    label: &str,
    opts: &Options,
) -> Result<(Simulation, Run), EfsiError> {
    let bar = if opts.progress {
        let b = indicatif::ProgressBar::new(1000);
        b.set_style(
            indicatif::ProgressStyle::with_template(
                "{prefix:>28} [{bar:30}] t = {msg} ({elapsed})",
            )
            .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
        );
        b.set_prefix(format!("{} {label}", sim.scene.name));
        b
    } else {
        indicatif::ProgressBar::hidden()
    };
    let end = sim.scene.time.end;
    let outcome = run(&mut sim, dir, &mut |p: &Progress| {
        bar.set_position((1000.0 * p.t / end) as u64);
        bar.set_message(format!("{:.4e}", p.t));
    })?;
    bar.finish_and_clear();
    let run = Run::of(&sim, label, dir, outcome.steps, outcome.wall_seconds);
    Ok((sim, run))
}

/// The columns of a run's `probes.csv`, by name.
pub fn probes(dir: &Path) -> Result<Probes, String> {
    let (header, cols) = crate::try_read_csv(&dir.join("probes.csv"))?;
    Ok(Probes { header, cols })
}

/// Time series read from `probes.csv`.
pub struct Probes {
    header: Vec<String>,
    cols: Vec<Vec<f64>>,
}

impl Probes {
    /// The columns' names, in file order.
    pub fn header(&self) -> &[String] {
        &self.header
    }

    /// A column (panics-free: an unknown name gives an error).
    pub fn col(&self, name: &str) -> Result<&[f64], String> {
        self.header
            .iter()
            .position(|h| h == name)
            .map(|k| self.cols[k].as_slice())
            .ok_or_else(|| format!("probes.csv has no column `{name}`"))
    }
}

/// The command that runs `reports` as `opts` asks (`--case` for each when not all ran).
fn command(opts: &Options, reports: &[Report]) -> String {
    let mut c = String::from("cargo xtask bench-paper");
    if opts.quick {
        c.push_str(" --quick");
    }
    if reports.len() < CASES.len() {
        for r in reports {
            let _ = write!(c, " --case {}", r.name);
        }
    }
    for o in &opts.overrides {
        let _ = write!(c, " --set {o}");
    }
    c
}

/// Write `summary.json` for `reports` into `opts.out`, with the command, the date, the commit
/// and the machine, and `REPORT.md` rendered from it (`xtask::bench_page::paper_report`, which
/// also renders the figures of `docs/benchmarks.md`).
pub fn write_report(opts: &Options, reports: &[Report], wall: f64) -> Result<(), String> {
    let summary = serde_json::json!({
        "command": command(opts, reports),
        "provenance": xtask::provenance::provenance(&crate::workspace_root()),
        "mode": if opts.quick { "quick" } else { "full" },
        "wall_seconds": wall,
        "cases": reports,
        "passed": reports.iter().all(Report::passed),
    });
    let md = xtask::bench_page::paper_report(&summary);
    save(&opts.out.join("REPORT.md"), md.as_bytes())?;
    let text = serde_json::to_string_pretty(&summary).map_err(|e| e.to_string())?;
    save(&opts.out.join("summary.json"), text.as_bytes())
}

/// A label as a folder name: letters, digits, `.` and `-` kept, runs of anything else `_`.
pub fn slug(label: &str) -> String {
    let mut out = String::new();
    for c in label.chars() {
        if c.is_ascii_alphanumeric() || c == '.' || c == '-' {
            out.push(c);
        } else if !out.ends_with('_') {
            out.push('_');
        }
    }
    out.trim_matches('_').to_string()
}

/// Write a file atomically.
pub fn save(path: &Path, bytes: &[u8]) -> Result<(), String> {
    efsi_run::output::atomic::write_bytes_atomically(path, bytes).map_err(|e| e.to_string())
}

/// Write named series `(label, points)` sharing an x column name as CSV: `series,x,y` rows.
pub fn save_series(
    path: &Path,
    x: &str,
    y: &str,
    series: &[(String, Vec<(f64, f64)>)],
) -> Result<(), String> {
    let mut s = format!("series,{x},{y}\n");
    for (label, pts) in series {
        for (a, b) in pts {
            let _ = writeln!(s, "{label},{a:e},{b:e}");
        }
    }
    save(path, s.as_bytes())
}

/// Run the named cases (all if `names` is empty) and write the report.
pub fn bench(opts: &Options, names: &[String]) -> Result<Vec<Report>, String> {
    for n in names {
        if !CASES.iter().any(|c| c.name == n) {
            return Err(format!(
                "unknown case `{n}`; the cases are {}",
                CASES.iter().map(|c| c.name).collect::<Vec<_>>().join(", ")
            ));
        }
    }
    std::fs::create_dir_all(&opts.out).map_err(|e| format!("{}: {e}", opts.out.display()))?;
    let start = std::time::Instant::now();
    let mut reports = Vec::new();
    for case in CASES {
        if !names.is_empty() && !names.iter().any(|n| n == case.name) {
            continue;
        }
        let t0 = std::time::Instant::now();
        // A case that cannot complete is a failed check of the report, not the bench's end.
        let report = (case.run)(opts).unwrap_or_else(|e| failed_case(case.name, &e));
        eprintln!(
            "{}: {}/{} checks passed ({:.0} s)",
            case.name,
            report.checks.iter().filter(|c| c.pass).count(),
            report.checks.len(),
            t0.elapsed().as_secs_f64()
        );
        reports.push(report);
    }
    write_report(opts, &reports, start.elapsed().as_secs_f64())?;
    Ok(reports)
}

/// The report of a case that could not complete: one failed check naming its error.
fn failed_case(name: &str, error: &str) -> Report {
    Report {
        name: name.into(),
        title: name.into(),
        reference: String::new(),
        error_metric: String::new(),
        runs: Vec::new(),
        checks: vec![case::failed_run(name, error)],
        plots: Vec::new(),
        notes: Vec::new(),
        schedule: Vec::new(),
        recommendation: "none: the case failed".into(),
    }
}

/// A named series of (x, y) points of a plot.
pub type Series = (String, Vec<(f64, f64)>);
