//! The harness every paper case runs on: a [`Case`] declares its settings (grids, CFL
//! numbers, …), the scene of each and what a run shows; [`run`] makes the runs one after the
//! other (with progress, stage timings and the pipeline recorded by [`Harness::execute`]) and
//! assembles the [`Report`] from the case's [`Verdict`]. The helpers here are what the cases'
//! verdicts share: drift checks, the speed/accuracy series, ratios of successive errors and
//! figures with their CSV series.

use super::plot::Scale;
use super::{Check, Options, Report, Run, Series, execute_built, plot, save_series, slug};
use efsi_core::{Scene, Simulation};
use std::path::{Path, PathBuf};

/// A paper case: its settings, the scene and measurement of one run, and its verdict over the
/// runs. The default [`Case::run`] builds [`Case::scene`], runs it through
/// [`Harness::execute`] into the folder [`Case::folder`] and hands the finished simulation to
/// [`Case::measure`]; a case that steps in-process or may be refused overrides it.
pub trait Case: Sized {
    /// Name, as `--case` takes it; also the case's output folder.
    const NAME: &'static str;
    /// What distinguishes one run (a grid size, a CFL number, …).
    type Setting;
    /// What one run shows beyond its [`Run`] record.
    type Measured;

    /// The case's fixed data for `opts` (references, quick or full mode) and its runs in
    /// report order, each a label ("32 cells", "35 CPR", …) and a setting.
    fn plan(opts: &Options) -> Plan<Self>;

    /// The run's folder under the case's (the label as a [`slug`]).
    fn folder(&self, label: &str, _s: &Self::Setting) -> String {
        slug(label)
    }

    /// The scene of a setting, and the path it is read relative to.
    fn scene(&self, _s: &Self::Setting) -> Result<(Scene, PathBuf), String> {
        Err(format!("{}: no scene per setting", Self::NAME))
    }

    /// What the finished run shows; may set the run's error and metrics.
    fn measure(
        &self,
        _s: &Self::Setting,
        _sim: &Simulation,
        _run: &mut Run,
    ) -> Result<Self::Measured, String> {
        Err(format!("{}: no measurement of a run", Self::NAME))
    }

    /// Make one run: its record (`None` if it never ran) and what it shows.
    fn run(&self, h: &mut Harness, label: &str, s: &Self::Setting) -> RunResult<Self::Measured> {
        let (scene, path) = self.scene(s)?;
        let (sim, mut run) = h.execute(scene, &path, &self.folder(label, s), label)?;
        let m = self.measure(s, &sim, &mut run)?;
        Ok((Some(run), m))
    }

    /// Make the runs of the plan, in order (one after the other unless overridden). A run
    /// that fails is recorded in [`Done::failed`] and the others still run.
    fn runs(
        &self,
        h: &mut Harness,
        plan: Vec<(String, Self::Setting)>,
    ) -> Result<Done<Self>, String> {
        let mut done = Done {
            runs: Vec::new(),
            measured: Vec::new(),
            failed: Vec::new(),
        };
        for (label, s) in plan {
            match self.run(h, &label, &s) {
                Ok((run, m)) => {
                    done.runs.extend(run);
                    done.measured.push((s, m));
                }
                Err(e) => done.failed.push((label, e)),
            }
        }
        Ok(done)
    }

    /// The verdict over the runs: checks, and the report's words. Notes, plots and the
    /// pipeline go into `h`; runs' errors and metrics may be set here.
    fn conclude(&self, h: &mut Harness, done: &mut Done<Self>) -> Result<Verdict, String>;
}

/// A case's data and its runs, each a label and a setting (see [`Case::plan`]).
pub type Plan<C> = Result<(C, Vec<(String, <C as Case>::Setting)>), String>;

/// One run's outcome: its record (`None` if it never ran) and what it shows.
pub type RunResult<M> = Result<(Option<Run>, M), String>;

/// The runs of a case: the records of those that ran, and every setting with what it showed.
pub struct Done<C: Case> {
    /// The records, in order (one per setting that ran).
    pub runs: Vec<Run>,
    /// Each setting and what its run showed, in order (the failed runs' settings left out).
    pub measured: Vec<(C::Setting, C::Measured)>,
    /// The runs that failed: label and error. Each becomes a failed check of the report.
    pub failed: Vec<(String, String)>,
}

/// The failed check of a run that did not complete: it names the run and its error.
pub fn failed_run(label: &str, error: &str) -> Check {
    Check {
        what: format!("run {label} completes"),
        value: format!("failed: {error}"),
        target: "completes".into(),
        pass: false,
    }
}

/// A case's judgement and the words of its report.
pub struct Verdict {
    /// Title.
    pub title: String,
    /// The reference compared with, and its source.
    pub reference: String,
    /// The error metric of [`Run::error`], in words.
    pub error_metric: String,
    /// The targets.
    pub checks: Vec<Check>,
    /// The setting recommended for the speed/accuracy trade, and why.
    pub recommendation: String,
}

/// What a case's runs share: the options, the output folder, and the report's plots, notes and
/// pipeline as they are gathered.
pub struct Harness<'a> {
    /// How the bench was asked for.
    pub opts: &'a Options,
    /// The case's output folder (`<out>/<name>`).
    pub dir: PathBuf,
    /// Plots: caption and file name relative to the report.
    pub plots: Vec<(String, String)>,
    /// Findings in words.
    pub notes: Vec<String>,
    /// The stage pipeline (by default the last run's).
    pub schedule: Vec<String>,
}

impl Harness<'_> {
    /// Run `scene` (from `path`) into `<dir>/<folder>` with the label `label`, recording its
    /// pipeline as the report's.
    pub fn execute(
        &mut self,
        scene: Scene,
        path: &Path,
        folder: &str,
        label: &str,
    ) -> Result<(Simulation, Run), String> {
        let scene = self.opts.adjust(scene)?;
        let sim = efsi_run::simulation(scene, path, &efsi_stages::builtin())
            .map_err(|e| e.to_string())?;
        let (sim, run) = execute_built(sim, &self.dir.join(folder), label, self.opts)
            .map_err(|e| e.to_string())?;
        self.schedule = stage_names(&sim);
        Ok((sim, run))
    }

    /// Draw a figure into the case's folder: `<file>.png` and the CSV of its series
    /// `<file>.csv` beside it. The plot is recorded in [`Harness::plots`]; what could not be
    /// written becomes a note, so the report says what is missing.
    pub fn figure(
        &mut self,
        file: &str,
        (title, x, y): (&str, &str, &str),
        series: &[Series],
        scale: Scale,
    ) {
        let dir = &self.dir;
        if let Err(e) = save_series(&dir.join(format!("{file}.csv")), x, y, series) {
            self.notes.push(format!("{file}.csv not written: {e}"));
        }
        let case = dir
            .file_name()
            .map_or(String::new(), |c| c.to_string_lossy().into_owned());
        match plot::lines(&dir.join(format!("{file}.png")), title, x, y, series, scale) {
            Ok(()) => self
                .plots
                .push((title.to_string(), format!("{case}/{file}.png"))),
            Err(e) => self.notes.push(format!("plot {file} not drawn: {e}")),
        }
    }
}

/// Run case `C` as `opts` asks and assemble its report.
pub fn run<C: Case>(opts: &Options) -> Result<Report, String> {
    let (case, plan) = C::plan(opts)?;
    // The case's folder is the bench's own: cleared first, so a run into the same `--out` starts
    // afresh (efsi refuses to write over an earlier run's outputs, which failed every setting of
    // the stability map on a second `bench-paper` into one folder).
    let dir = opts.out.join(C::NAME);
    if dir.exists() {
        std::fs::remove_dir_all(&dir).map_err(|e| format!("{}: {e}", dir.display()))?;
    }
    let mut h = Harness {
        opts,
        dir,
        plots: Vec::new(),
        notes: Vec::new(),
        schedule: Vec::new(),
    };
    let mut done = case.runs(&mut h, plan)?;
    let failed: Vec<Check> = done.failed.iter().map(|(l, e)| failed_run(l, e)).collect();
    let mut v = match case.conclude(&mut h, &mut done) {
        Ok(v) => v,
        // The verdict may need the failed runs: the report still says what did run and why
        // it could not conclude.
        Err(e) if !failed.is_empty() => Verdict {
            title: C::NAME.into(),
            reference: String::new(),
            error_metric: String::new(),
            checks: vec![failed_run("verdict", &e)],
            recommendation: "none: runs failed".into(),
        },
        Err(e) => return Err(e),
    };
    v.checks.extend(failed);
    Ok(Report {
        name: C::NAME.into(),
        title: v.title,
        reference: v.reference,
        error_metric: v.error_metric,
        runs: done.runs,
        checks: v.checks,
        plots: h.plots,
        notes: h.notes,
        schedule: h.schedule,
        recommendation: v.recommendation,
    })
}

/// The names of a simulation's stages, in order.
pub fn stage_names(sim: &Simulation) -> Vec<String> {
    sim.pipeline()
        .stage_names()
        .iter()
        .map(|s| s.to_string())
        .collect()
}

/// The largest relative change of a conserved quantity's history from its first value.
pub fn drift(history: &[f64]) -> f64 {
    history
        .iter()
        .map(|v| ((v - history[0]) / history[0]).abs())
        .fold(0.0, f64::max)
}

/// The check that a conserved quantity (volume, area) drifts by at most 1e-10, the largest of
/// `drifts`.
pub fn drift_check(what: &str, drifts: impl IntoIterator<Item = f64>) -> Check {
    Check::at_most(what, drifts.into_iter().fold(0.0, f64::max), 1e-10, "e")
}

/// The check that every run stopped at the scene's steady state (`time.steady`), not at its
/// end time: `steady` holds one flag per run.
pub fn steady_check(steady: impl IntoIterator<Item = bool>) -> Check {
    let (mut n, mut stopped) = (0usize, 0usize);
    for s in steady {
        n += 1;
        stopped += usize::from(s);
    }
    Check::at_least(
        format!("runs stopped at the steady state (time.steady), of {n}"),
        stopped as f64,
        n as f64,
        "0",
    )
}

/// The speed/accuracy series: (wall time, error) of each run of `runs` that has an error.
pub fn trade<'a>(label: &str, runs: impl IntoIterator<Item = &'a Run>) -> Series {
    (
        label.to_string(),
        runs.into_iter()
            .filter_map(|r| r.error.map(|e| (r.wall_seconds, e)))
            .collect(),
    )
}

/// The largest ratio of successive values (`< 1`: every value falls with refinement).
pub fn largest_ratio(values: impl IntoIterator<Item = f64>) -> f64 {
    let v: Vec<f64> = values.into_iter().collect();
    v.windows(2).map(|w| w[1] / w[0]).fold(0.0, f64::max)
}

/// A named series of `ys` against `xs`.
pub fn xy(label: &str, xs: &[f64], ys: &[f64]) -> Series {
    (
        label.to_string(),
        xs.iter().copied().zip(ys.iter().copied()).collect(),
    )
}

/// The largest deviation of the points (`xs`, `ys`) from a reference (`rx`, `ry`) interpolated
/// linearly at `xs`.
pub fn deviation(xs: &[f64], ys: &[f64], (rx, ry): (&[f64], &[f64])) -> f64 {
    let d = xs
        .iter()
        .zip(ys)
        .map(|(&x, &y)| (y - crate::interp(rx, ry, x)).abs());
    d.fold(0.0, f64::max)
}

/// The observed order p of three grids' successive differences `g = [g12, g23]` on spacings
/// `h = [h1, h2, h3]`: the root of (h1^p − h2^p)/(h2^p − h3^p) = g12/g23 in (0, 8], found by
/// bisection (the ratio grows with p); NaN if there is none there.
pub fn observed_order(h: [f64; 3], g: [f64; 2]) -> f64 {
    let f = |p: f64| (h[0].powf(p) - h[1].powf(p)) / (h[1].powf(p) - h[2].powf(p)) - g[0] / g[1];
    let (mut lo, mut hi) = (1e-6, 8.0);
    if !(f(lo) < 0.0 && f(hi) > 0.0) {
        return f64::NAN;
    }
    for _ in 0..100 {
        let mid = 0.5 * (lo + hi);
        if f(mid) < 0.0 {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    0.5 * (lo + hi)
}

/// A grid study of a case whose settings are grid sizes `n` (spacing `1/n`): each run's error
/// is `gap` from the finest run's figures, and the differences between successive grids,
/// `gap(finer, coarser)`, come back with their observed order ([`observed_order`]; NaN
/// unless there are three grids).
pub fn grid_study<C: Case<Setting = usize>>(
    done: &mut Done<C>,
    gap: impl Fn(&C::Measured, &C::Measured) -> f64,
) -> (Vec<f64>, f64) {
    if let Some((_, finest)) = done.measured.last() {
        for (r, (_, m)) in done.runs.iter_mut().zip(&done.measured) {
            r.error = Some(gap(m, finest));
        }
    }
    let measured: Vec<&C::Measured> = done.measured.iter().map(|(_, m)| m).collect();
    let diffs: Vec<f64> = measured.windows(2).map(|w| gap(w[1], w[0])).collect();
    let hs: Vec<f64> = done.measured.iter().map(|(n, _)| 1.0 / *n as f64).collect();
    let order = match (hs.as_slice(), diffs.as_slice()) {
        ([h1, h2, h3], [g1, g2]) => observed_order([*h1, *h2, *h3], [*g1, *g2]),
        _ => f64::NAN,
    };
    (diffs, order)
}

#[cfg(test)]
mod tests {
    use super::observed_order;

    /// The order of exact power-law differences is recovered, for unequal refinement ratios.
    #[test]
    fn observed_order_of_a_power_law() {
        for p in [0.8, 1.0, 2.0] {
            let h = [1.0 / 16.0, 1.0 / 20.0, 1.0 / 24.0];
            let e = |h: f64| 3.0 * h.powf(p);
            let g = [e(h[0]) - e(h[1]), e(h[1]) - e(h[2])];
            assert!((observed_order(h, g) - p).abs() < 1e-9, "p = {p}");
        }
        assert!(observed_order([0.1, 0.05, 0.025], [1.0, 2.0]).is_nan());
    }
}
