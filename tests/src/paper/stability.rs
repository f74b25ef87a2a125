//! Stability at the extremes: the sphere-impact scene, reduced, over shear modulus ×
//! density ratio × CFL number, and with solids only four and five cells across. Every run must either
//! finish stable or be refused before it starts with a message naming the limit and the
//! setting to change — no third outcome. The map is made of the axisymmetric sphere
//! ([`Stability`], `--case stability`) and of the three-dimensional one on a quarter box
//! ([`Stability3d`], `--case stability_3d`, issue 41 case 5).
//!
//! # The runs
//! `cases/sphere_impact.ron` at 8 cells per radius (6 in quick mode), the sphere released
//! `GAP` above the substrate at its scene's 1.22 m/s so that it falls, hits and leaves the
//! wall within `END`; the fluid's density is the solid's divided by the ratio (the solid keeps
//! its 1106 kg/m³, the fluid its viscosity). The "4 cells across" and "5 cells across" runs
//! shrink the sphere to a diameter of 4 and 5 cells on the same grid. Expected to be refused:
//! the solid 4 cells across (below [`MIN_CELLS_ACROSS`]), a `time.fixed_dt` above the
//! elastic-wave limit, and a `numerics.elastic.wave_courant` above its allowed maximum.
//!
//! The three-dimensional map is the same over `cases/sphere_impact_3d.ron` (the Symmetry planes
//! x = 0 and z = 0 through the sphere's axis, y vertical) at [`CPR_3D`] cells per radius
//! ([`QUICK_CPR_3D`] in quick mode), each side of the scene's box rounded to whole cubic cells
//! (7 × 14 × 7 cells at 3 cells per radius, 9 × 19 × 9 at 4): the same settings, the same
//! criteria, the small solids 4 and 5 cells across their diameter (the width of
//! [`MIN_CELLS_ACROSS`] is `6V/S` in three dimensions); the sphere is released 1.25 cells
//! above the substrate (8 mm at 3 cells per radius, 6 mm at 4: the axisymmetric map's 4 mm
//! is less than a cell there, and the sphere would start pressed on the wall).
//!
//! The map's runs are `Split`; `Coupled` (Δt·c/h ≤ 25) and `Auto` (≤ 200) run at G = 1e7,
//! 1e9, 1e11 Pa × CFL 0.1, 0.5, 0.9, ratio 1e3 (quick: G = 1e9, CFL 0.9), their rebounds
//! reported.
//!
//! # What "stable" means here
//! With `E = KE + PE + EE` (kinetic, gravitational potential of the whole domain — fluid
//! included, so buoyancy is in it — and strain energy; walls at rest do no work) and the
//! energy budget `E_b = KE(0) + max_t (PE(0) − PE(t))` (what the initial motion and gravity
//! can release):
//! - the run reaches its end time with every field finite (the NaN guard stops it otherwise);
//! - the solid volume drifts by at most `VOLUME`;
//! - the motion never gains energy: `KE + PE ≤ KE(0) + PE(0) + MECH_GAIN·E_b` throughout;
//! - nothing is gained over the run: `E ≤ E(0) + TOTAL_END·E_b` at the end.
//!
//! The peak of `E − E(0)` during the contact is reported, not judged: while the solid is
//! pressed on the wall the strain-energy probe over-reads: much of the strain energy then sits
//! in the wall row's slivers of solid (φ ≈ 0.1–0.2) that the air film's squeeze flow has
//! strained. In stiff or small solids, whose Hertz compression stays below a cell, the reading
//! rises above `E(0)` by a budget or so whatever the resolution; it is zero for the seed's
//! sphere at 35 and 50 cells per radius and returns to nothing after the rebound, while the
//! mechanical energy — what a pumping instability shows first — shows no gain.

//!
//! # Where the runs are made
//! Through an efsi sweep (`python -m efsi sweep --runs …`, the Python package's Dask sweep)
//! when the Python of `EFSI_PYTHON` (else `python3`) has the efsi package and Dask's
//! distributed scheduler: each setting is a run of `cases/sphere_impact.ron` with overrides,
//! a task on a LocalCluster of one worker per core or on the Dask scheduler at
//! `EFSI_SWEEP_SCHEDULER`, and its probe rows come back as files judged here. Otherwise, or
//! with `EFSI_SWEEP=serial`, one after the other in this process. The map is the same either
//! way (the same scenes, the same steps); the sweep's report has no per-stage timings and names
//! a refused setting's override.

use super::case::{Case, Done, Harness, Plan, Verdict, stage_names};
use super::plot::{self, Panel, Tone};
use super::sphere_3d::Geometry;
use super::{Check, Options, Run, execute_built, load_case, probes};
use efsi_core::Scene;
use efsi_run::{ProbeSpec, SceneOutput};
use efsi_stages::elastic::MIN_CELLS_ACROSS;
use efsi_stages::elastic::{
    DEFAULT_AUTO_COUPLED_WAVE_COURANT, DEFAULT_COUPLED_WAVE_COURANT, ElasticCoupling,
    ElasticOptions, MAX_WAVE_COURANT,
};
use efsi_stages::solid::{SceneSolid, Shape};
use std::path::PathBuf;

/// Shear moduli (Pa).
const G_VALUES: [f64; 5] = [1e3, 1e5, 1.8e5, 1e7, 1e9];
/// Density ratios solid/fluid.
const RATIOS: [f64; 4] = [1.0, 10.0, 1e3, 1e4];
/// CFL numbers.
const CFLS: [f64; 3] = [0.1, 0.5, 0.9];
/// Shear moduli (Pa) of the coupled step's runs.
const COUPLED_G: [f64; 3] = [1e7, 1e9, 1e11];
/// Widths of the small solids, in cells: one below [`MIN_CELLS_ACROSS`] (refused), one at it.
const ACROSS: [f64; 2] = [4.0, 5.0];
/// Cells per radius of the 3-D map (quick version: [`QUICK_CPR_3D`]).
pub const CPR_3D: f64 = 4.0;
/// Cells per radius of the 3-D map's quick version.
pub const QUICK_CPR_3D: f64 = 3.0;
/// Gap between the sphere and the substrate at release (m).
const GAP: f64 = 0.004;
/// The 3-D map's least gap at release, in cells: the sphere clear of the substrate's row of
/// cells. At 3 and 4 cells per radius [`GAP`] is less than a cell and the sphere would start
/// in the wall's row, already pressed on it.
const GAP_CELLS_3D: f64 = 1.25;
/// End time (s): impact at ≈ 3 ms, rebound by ≈ 12 ms for the seed's stiffness.
const END: f64 = 0.016;
/// Largest relative drift of the solid volume.
const VOLUME: f64 = 1e-9;
/// Largest gain of kinetic + potential energy, as a fraction of the budget.
const MECH_GAIN: f64 = 0.01;
/// Largest excess of the total energy over its start at the end, as a fraction of the budget.
const TOTAL_END: f64 = 0.01;

/// One run of the map.
#[derive(Clone, Copy, Debug)]
pub struct Setting {
    g: f64,
    ratio: f64,
    cfl: f64,
    /// A sphere this many cells across instead of the scene's.
    across: Option<f64>,
    fixed_dt: Option<f64>,
    wave_courant: Option<f64>,
    /// `numerics.elastic.coupling` (the map's runs: `Split`).
    coupling: ElasticCoupling,
}

impl Setting {
    fn new(g: f64, ratio: f64, cfl: f64) -> Setting {
        Setting {
            g,
            ratio,
            cfl,
            across: None,
            fixed_dt: None,
            wave_courant: None,
            coupling: ElasticCoupling::Split,
        }
    }

    fn label(&self) -> String {
        let mut s = format!("G {:e}, ratio {:e}, CFL {}", self.g, self.ratio, self.cfl);
        if let Some(n) = self.across {
            s += &format!(", {n} cells across");
        }
        if let Some(dt) = self.fixed_dt {
            s += &format!(", fixed dt {dt:.0e}");
        }
        if let Some(w) = self.wave_courant {
            s += &format!(", wave_courant {w}");
        }
        if self.coupling != ElasticCoupling::Split {
            s += &format!(", {:?}", self.coupling);
        }
        s
    }
}

/// The energy and volume figures of a finished run.
#[derive(Clone, Copy, Debug, Default)]
pub struct Figures {
    /// max (KE + PE) − (KE + PE)(0), over the budget.
    mech_gain: f64,
    /// max E − E(0), over the budget.
    total_peak: f64,
    /// E(end) − E(0), over the budget.
    total_end: f64,
    /// Largest relative drift of the solid volume.
    volume: f64,
    /// Reached the end time.
    finished: bool,
    /// The solid's vertical velocity at the end (m/s; the rebound once it has left the wall).
    rebound: f64,
}

impl Figures {
    /// Why the run is not stable, if it is not.
    fn verdict(&self) -> Option<String> {
        let mut why = Vec::new();
        if !self.finished {
            why.push("did not reach its end".to_string());
        }
        if self.volume.is_nan() || self.volume > VOLUME {
            why.push(format!("volume drift {:.1e}", self.volume));
        }
        if self.mech_gain.is_nan() || self.mech_gain > MECH_GAIN {
            why.push(format!("KE+PE gained {:.3} E_b", self.mech_gain));
        }
        if self.total_peak.is_nan() {
            why.push("E is not a number".to_string());
        }
        if self.total_end.is_nan() || self.total_end > TOTAL_END {
            why.push(format!("E ended {:.3} E_b above E(0)", self.total_end));
        }
        (!why.is_empty()).then(|| why.join("; "))
    }
}

/// What became of a setting.
#[derive(Clone, Debug)]
pub enum Outcome {
    /// Finished stable, with its figures.
    Stable(Figures),
    /// Refused before the run, with the message.
    Refused(String),
    /// Anything else: the error or the broken criteria.
    Failed(String),
}

impl Outcome {
    fn tone(&self) -> Tone {
        match self {
            Outcome::Stable(_) => Tone::Good,
            Outcome::Refused(_) => Tone::Refused,
            Outcome::Failed(_) => Tone::Bad,
        }
    }
}

/// The scene file of the map in `geometry`.
fn file_of(geometry: Geometry) -> &'static str {
    match geometry {
        Geometry::Axisymmetric => "sphere_impact.ron",
        Geometry::ThreeD => "sphere_impact_3d.ron",
    }
}

/// The scene of a setting at `cpr` cells per radius: `cases/sphere_impact.ron` (axisymmetric),
/// or `cases/sphere_impact_3d.ron` (3-D quarter box) with each side of its box rounded to
/// whole cubic cells.
fn scene_for(st: &Setting, cpr: f64, geometry: Geometry) -> Result<(Scene, PathBuf), String> {
    let (mut scene, path) = load_case(file_of(geometry))?;
    let (lx, ly) = (
        scene.domain.x.1 - scene.domain.x.0,
        scene.domain.y.1 - scene.domain.y.0,
    );
    let mut solid = super::sphere::solid_of(&scene)?;
    let radius = match (geometry, solid.shape) {
        (Geometry::Axisymmetric, Shape::Disk { radius, .. })
        | (Geometry::ThreeD, Shape::Sphere { radius, .. }) => radius,
        _ => return Err(format!("{}: the solid is not a sphere", file_of(geometry))),
    };
    let h = radius / cpr;
    let r = st.across.map_or(radius, |n| 0.5 * n * h);
    solid.shape = match geometry {
        Geometry::Axisymmetric => Shape::Disk {
            center: (0.0, r + GAP),
            radius: r,
        },
        Geometry::ThreeD => Shape::Sphere {
            center: (0.0, r + GAP.max(GAP_CELLS_3D * h), 0.0),
            radius: r,
        },
    };
    let law = solid.law.as_mut().ok_or("the solid has no law")?;
    law.parameters.insert("G".into(), st.g);
    scene.fluid.density = solid.density / st.ratio;
    scene.set_solid(&solid);
    scene.grid.nx = (lx / h).round() as usize;
    scene.grid.ny = (ly / h).round() as usize;
    if geometry == Geometry::ThreeD {
        let z = scene.domain.z.ok_or("the 3-D scene has no z extent")?;
        let nz = ((z.1 - z.0) / h).round() as usize;
        scene.domain.x = (0.0, scene.grid.nx as f64 * h);
        scene.domain.y = (0.0, scene.grid.ny as f64 * h);
        scene.domain.z = Some((0.0, nz as f64 * h));
        scene.grid.nz = Some(nz);
    }
    scene.time.end = END;
    scene.time.cfl = st.cfl;
    scene.time.fixed_dt = st.fixed_dt;
    scene.numerics.set(&ElasticOptions {
        wave_courant: st.wave_courant.unwrap_or(MAX_WAVE_COURANT),
        coupling: st.coupling,
        ..ElasticOptions::default()
    });
    scene.update_output(|o| {
        // No VTK; probes every step: an interval would cap Δt (the run lands on every probe time).
        (o.vtk_every, o.probe_every) = (None, None);
        o.probes = vec![
            ProbeSpec::SolidVolume,
            ProbeSpec::SolidCentroid,
            ProbeSpec::SolidVelocity,
            ProbeSpec::KineticEnergy,
            ProbeSpec::PotentialEnergy,
            ProbeSpec::ElasticEnergy,
        ];
    })?;
    Ok((scene, path))
}

/// The energy and volume figures from a run's probes (as far as it got).
fn figures(dir: &std::path::Path) -> Result<Figures, String> {
    let p = probes(dir)?;
    let t = p.col("t")?;
    let (ke, pe, ee) = (
        p.col("kinetic_energy")?,
        p.col("potential_energy")?,
        p.col("elastic_energy")?,
    );
    let vol = p.col("solid_volume")?;
    if t.is_empty() {
        return Err("no probe rows".into());
    }
    let mech0 = ke[0] + pe[0];
    let e0 = mech0 + ee[0];
    let budget = ke[0] + pe.iter().map(|x| pe[0] - x).fold(0.0, f64::max);
    let n = t.len();
    let nan_max = |it: &mut dyn Iterator<Item = f64>| {
        it.fold(f64::NEG_INFINITY, |m, x| {
            if x.is_nan() || m.is_nan() {
                f64::NAN
            } else {
                m.max(x)
            }
        })
    };
    Ok(Figures {
        mech_gain: nan_max(&mut (0..n).map(|k| (ke[k] + pe[k] - mech0) / budget)),
        total_peak: nan_max(&mut (0..n).map(|k| (ke[k] + pe[k] + ee[k] - e0) / budget)),
        total_end: (ke[n - 1] + pe[n - 1] + ee[n - 1] - e0) / budget,
        volume: nan_max(&mut vol.iter().map(|v| ((v - vol[0]) / vol[0]).abs())),
        finished: t[n - 1] >= END * (1.0 - 1e-9),
        rebound: p.col("solid_v")?[n - 1],
    })
}

/// Run one setting.
fn attempt(
    st: &Setting,
    (cpr, geometry): (f64, Geometry),
    dir: &std::path::Path,
    opts: &Options,
) -> (Outcome, Option<Run>) {
    let label = st.label();
    let (scene, path) =
        match scene_for(st, cpr, geometry).and_then(|(s, p)| Ok((opts.adjust(s)?, p))) {
            Ok(s) => s,
            Err(e) => return (Outcome::Failed(format!("scene: {e}")), None),
        };
    let sim = match efsi_run::simulation(scene, &path, &efsi_stages::builtin()) {
        Ok(sim) => sim,
        Err(e) => return (Outcome::Refused(e.to_string()), None),
    };
    let rdir = dir.join(super::slug(&label));
    match execute_built(sim, &rdir, &label, opts) {
        Ok((_, run)) => judge(run, &rdir),
        Err(e) => (Outcome::Failed(format!("the run failed: {e}")), None),
    }
}

/// Judge a finished run from its probes in `rdir`: its figures become its metrics and error.
fn judge(mut run: Run, rdir: &std::path::Path) -> (Outcome, Option<Run>) {
    match figures(rdir) {
        Ok(f) => {
            run.metrics = vec![
                ("mech_gain".into(), f.mech_gain),
                ("total_peak".into(), f.total_peak),
                ("total_end".into(), f.total_end),
                ("volume_drift".into(), f.volume),
            ];
            run.error = Some(f.mech_gain.max(0.0));
            let outcome = match f.verdict() {
                None => Outcome::Stable(f),
                Some(why) => Outcome::Failed(why),
            };
            (outcome, Some(run))
        }
        Err(e) => (Outcome::Failed(format!("probes: {e}")), Some(run)),
    }
}

/// The Python that runs the map as an efsi sweep (`EFSI_PYTHON`, else `python3`), if it has
/// the efsi package and Dask's distributed scheduler and `EFSI_SWEEP` is not `serial`; `None`:
/// the runs are made one after the other in this process.
fn sweep_python() -> Option<std::ffi::OsString> {
    if std::env::var("EFSI_SWEEP").is_ok_and(|v| v == "serial") {
        return None;
    }
    let python = std::env::var_os("EFSI_PYTHON").unwrap_or_else(|| "python3".into());
    let usable = std::process::Command::new(&python)
        .args(["-c", "import efsi, distributed"])
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::null())
        .status()
        .is_ok_and(|s| s.success());
    usable.then_some(python)
}

/// The overrides of the scene file ([`file_of`]) that make the scene of [`scene_for`], as JSON
/// (a number, or RON text).
fn overrides_for(
    st: &Setting,
    (cpr, geometry): (f64, Geometry),
) -> Result<serde_json::Value, String> {
    let (scene, _) = scene_for(st, cpr, geometry)?;
    let solid = super::sphere::solid_of(&scene)?;
    let shape = match solid.shape {
        Shape::Disk { center, radius } => format!(
            "Disk(center: ({:?}, {:?}), radius: {radius:?})",
            center.0, center.1
        ),
        Shape::Sphere { center, radius } => format!(
            "Sphere(center: ({:?}, {:?}, {:?}), radius: {radius:?})",
            center.0, center.1, center.2
        ),
        _ => return Err("the solid is not a sphere".into()),
    };
    let mut o = serde_json::Map::new();
    let mut put = |k: &str, v: serde_json::Value| {
        o.insert(k.to_string(), v);
    };
    put("solid.shape", shape.into());
    put("solid.law.parameters.G", st.g.into());
    put("fluid.density", scene.fluid.density.into());
    put("grid.nx", scene.grid.nx.into());
    put("grid.ny", scene.grid.ny.into());
    if let (Some(nz), Some(z)) = (scene.grid.nz, scene.domain.z) {
        let range = |(a, b): (f64, f64)| format!("({a:?}, {b:?})");
        put("grid.nz", nz.into());
        put("domain.x", range(scene.domain.x).into());
        put("domain.y", range(scene.domain.y).into());
        put("domain.z", range(z).into());
    }
    put("time.end", END.into());
    put("time.cfl", st.cfl.into());
    if let Some(dt) = st.fixed_dt {
        put("time.fixed_dt", dt.into());
    }
    if let Some(w) = st.wave_courant {
        put("numerics.elastic.wave_courant", w.into());
    }
    let coupling = format!("{:?}", st.coupling);
    if st.coupling != ElasticCoupling::Split {
        put("numerics.elastic.coupling", coupling.into());
    }
    put("output.vtk_every", "None".into());
    put("output.probe_every", "None".into());
    put(
        "output.probes",
        "[SolidVolume, SolidCentroid, SolidVelocity, KineticEnergy, PotentialEnergy, ElasticEnergy]"
            .into(),
    );
    Ok(serde_json::Value::Object(o))
}

/// Make the runs of `settings` as one efsi sweep (`python -m efsi sweep --runs … --save-probes
/// …`: Dask tasks on a LocalCluster of one worker per core, or on the scheduler at
/// `EFSI_SWEEP_SCHEDULER`), then judge each from its probe rows as [`attempt`] does. Returns
/// what [`attempt`] returns, per setting in order (no per-stage timings: the runs were made
/// elsewhere).
fn through_sweep(
    python: &std::ffi::OsStr,
    settings: &[Setting],
    at: (f64, Geometry),
    dir: &std::path::Path,
) -> Result<Vec<(Outcome, Option<Run>)>, String> {
    let (_, scene_path) = load_case(file_of(at.1))?;
    let sweep = dir.join("sweep");
    let _ = std::fs::remove_dir_all(&sweep);
    std::fs::create_dir_all(&sweep).map_err(|e| format!("{}: {e}", sweep.display()))?;
    let list = settings
        .iter()
        .map(|st| overrides_for(st, at))
        .collect::<Result<Vec<_>, _>>()?;
    let runs_file = sweep.join("runs.json");
    std::fs::write(&runs_file, serde_json::Value::Array(list).to_string())
        .map_err(|e| format!("{}: {e}", runs_file.display()))?;
    let table_file = sweep.join("table.json");
    let mut c = std::process::Command::new(python);
    c.args(["-m", "efsi", "sweep"])
        .arg(&scene_path)
        .arg("--runs")
        .arg(&runs_file)
        .arg("--save-probes")
        .arg(sweep.join("probes"))
        .arg("--out")
        .arg(&table_file)
        .arg("-q")
        .stdout(std::process::Stdio::null());
    if let Some(a) = std::env::var_os("EFSI_SWEEP_SCHEDULER") {
        c.arg("--scheduler").arg(a);
    }
    let status = c
        .status()
        .map_err(|e| format!("cannot start {}: {e}", python.to_string_lossy()))?;
    if !status.success() {
        return Err(format!("efsi sweep of the stability map failed ({status})"));
    }
    let text = std::fs::read_to_string(&table_file)
        .map_err(|e| format!("{}: {e}", table_file.display()))?;
    let rows: Vec<serde_json::Value> = serde_json::from_str(&text).map_err(|e| e.to_string())?;
    if rows.len() != settings.len() {
        return Err(format!(
            "{}: {} rows for {} settings",
            table_file.display(),
            rows.len(),
            settings.len()
        ));
    }
    Ok(settings
        .iter()
        .zip(&rows)
        .map(|(st, row)| {
            let outcome = row["outcome"].as_str().unwrap_or("failed: no outcome");
            if let Some(m) = outcome.strip_prefix("refused: ") {
                return (Outcome::Refused(m.to_string()), None);
            }
            if outcome != "ok" {
                let m = outcome.split_once(": ").map_or(outcome, |(_, m)| m);
                return (Outcome::Failed(format!("the run failed: {m}")), None);
            }
            let rdir = std::path::PathBuf::from(row["probes_dir"].as_str().unwrap_or_default());
            let n = |k: &str| row[k].as_u64().unwrap_or(0) as usize;
            let run = Run {
                label: st.label(),
                cells: n("grid.nx")
                    * n("grid.ny")
                    * row["grid.nz"].as_u64().map_or(1, |z| z as usize),
                steps: row["steps"].as_u64().unwrap_or(0),
                wall_seconds: row["wall_time"].as_f64().unwrap_or(f64::NAN),
                error: None,
                metrics: Vec::new(),
                stages: Vec::new(),
                dir: rdir.clone(),
            };
            judge(run, &rdir)
        })
        .collect())
}

/// The case: the map over G × ratio × CFL, the small solids, the settings to be refused and
/// the coupled step's runs, on the axisymmetric sphere at 6 (quick) or 8 cells per radius
/// ([`Stability`]), or on the 3-D sphere's quarter box ([`Stability3d`]) at
/// [`QUICK_CPR_3D`] or [`CPR_3D`].
pub struct Map<const THREE_D: bool> {
    quick: bool,
    cpr: f64,
    gs: &'static [f64],
    ratios: &'static [f64],
    cfls: &'static [f64],
    small_ratios: &'static [f64],
}

/// The map of the axisymmetric sphere (`--case stability`).
pub type Stability = Map<false>;
/// The map of the 3-D sphere on a quarter box (`--case stability_3d`).
pub type Stability3d = Map<true>;

impl<const THREE_D: bool> Map<THREE_D> {
    /// The scene's geometry.
    const GEOMETRY: Geometry = if THREE_D {
        Geometry::ThreeD
    } else {
        Geometry::Axisymmetric
    };

    /// The map's settings, the small solids, the refusals, then the coupled step's runs.
    fn settings(&self) -> Vec<Setting> {
        let mut out = Vec::new();
        for &cfl in self.cfls {
            for &ratio in self.ratios {
                out.extend(self.gs.iter().map(|&g| Setting::new(g, ratio, cfl)));
            }
        }
        for across in ACROSS {
            for &ratio in self.small_ratios {
                let small = |&g: &f64| Setting {
                    across: Some(across),
                    ..Setting::new(g, ratio, 0.5)
                };
                out.extend(self.gs.iter().map(small));
            }
        }
        // Beyond a limit: to be refused.
        out.push(Setting {
            fixed_dt: Some(1e-4),
            ..Setting::new(1e9, 1e3, 0.5)
        });
        out.push(Setting {
            wave_courant: Some(2.5 * MAX_WAVE_COURANT),
            ..Setting::new(1e7, 1e3, 0.5)
        });
        // The coupled elastic step (issue 16): stiff solids at the flow's step.
        let (coupled_g, coupled_cfl): (&[f64], &[f64]) = if self.quick {
            (&COUPLED_G[1..2], &[0.9])
        } else {
            (&COUPLED_G, &CFLS)
        };
        for coupling in [ElasticCoupling::Coupled, ElasticCoupling::Auto] {
            for &cfl in coupled_cfl {
                for &g in coupled_g {
                    out.push(Setting {
                        coupling,
                        ..Setting::new(g, 1e3, cfl)
                    });
                }
            }
        }
        out
    }
}

impl<const THREE_D: bool> Case for Map<THREE_D> {
    const NAME: &'static str = if THREE_D { "stability_3d" } else { "stability" };
    type Setting = Setting;
    type Measured = Outcome;

    fn plan(opts: &Options) -> Plan<Self> {
        let cpr = match (THREE_D, opts.quick) {
            (false, true) => 6.0,
            (false, false) => 8.0,
            (true, true) => QUICK_CPR_3D,
            (true, false) => CPR_3D,
        };
        let (gs, ratios, cfls): (&[f64], &[f64], &[f64]) = if opts.quick {
            (&[1e3, 1e9], &[1.0, 1e4], &[0.1, 0.9])
        } else {
            (&G_VALUES, &RATIOS, &CFLS)
        };
        let small_ratios: &[f64] = if opts.quick { &[1e3] } else { &RATIOS };
        let case = Map {
            quick: opts.quick,
            cpr,
            gs,
            ratios,
            cfls,
            small_ratios,
        };
        let plan = case.settings().into_iter().map(|st| (st.label(), st));
        Ok((case, plan.collect()))
    }

    /// Through an efsi sweep if there is a Python for it, else one after the other here.
    fn runs(&self, h: &mut Harness, plan: Vec<(String, Setting)>) -> Result<Done<Self>, String> {
        let settings: Vec<Setting> = plan.into_iter().map(|(_, st)| st).collect();
        let attempts = match sweep_python() {
            Some(python) => through_sweep(&python, &settings, (self.cpr, Self::GEOMETRY), &h.dir)?,
            None => settings
                .iter()
                .map(|st| attempt(st, (self.cpr, Self::GEOMETRY), &h.dir, h.opts))
                .collect(),
        };
        let mut runs = Vec::new();
        let measured = settings.into_iter().zip(attempts);
        let measured = measured.map(|(st, (outcome, run))| {
            runs.extend(run);
            (st, outcome)
        });
        Ok(Done {
            measured: measured.collect(),
            runs,
            failed: Vec::new(),
        })
    }

    fn conclude(&self, h: &mut Harness, done: &mut Done<Self>) -> Result<Verdict, String> {
        let (cpr, gs, ratios, cfls, small_ratios) =
            (self.cpr, self.gs, self.ratios, self.cfls, self.small_ratios);
        let sphere = match Self::GEOMETRY {
            Geometry::Axisymmetric => "sphere",
            Geometry::ThreeD => "3-D sphere, quarter box",
        };
        let runs = &done.runs;
        let (coupled_results, results): (Vec<_>, Vec<_>) = done
            .measured
            .iter()
            .cloned()
            .partition(|(st, _)| st.coupling != ElasticCoupling::Split);
        // The map: one panel per CFL number, then the small solids.
        let cell = |o: &Outcome, steps: Option<u64>| -> (Tone, String) {
            let text = match o {
                Outcome::Stable(_) => steps.map_or(String::new(), |s| format!("{s} steps")),
                Outcome::Refused(_) => "refused".into(),
                Outcome::Failed(_) => "FAILED".into(),
            };
            (o.tone(), text)
        };
        let steps_of = |st: &Setting| runs.iter().find(|r| r.label == st.label()).map(|r| r.steps);
        let outcome_of = |pred: &dyn Fn(&Setting) -> bool| {
            results
                .iter()
                .find(|(s, _)| pred(s) && s.fixed_dt.is_none() && s.wave_courant.is_none())
                .map(|(s, o)| (*s, o.clone()))
        };
        let cols: Vec<String> = gs.iter().map(|g| format!("{g:e}")).collect();
        // One panel: G across, density ratio up, the settings `pick` selects.
        let panel = |title: String,
                     rows: &[f64],
                     pick: &dyn Fn(&Setting) -> bool|
         -> Result<Panel, String> {
            let mut cells = Vec::new();
            for &ratio in rows {
                for &g in gs {
                    let (s, o) = outcome_of(&|s: &Setting| pick(s) && s.g == g && s.ratio == ratio)
                        .ok_or("a map cell has no run")?;
                    cells.push(cell(&o, steps_of(&s)));
                }
            }
            Ok(Panel {
                title,
                cols: cols.clone(),
                rows: rows.iter().map(|r| format!("{r:.0e}")).collect(),
                cells,
            })
        };
        let mut panels = Vec::new();
        for &cfl in cfls {
            panels.push(panel(format!("{sphere}, CFL {cfl}"), ratios, &|s| {
                s.across.is_none() && s.cfl == cfl
            })?);
        }
        for across in ACROSS {
            panels.push(panel(
                format!("{across} cells across, CFL 0.5"),
                small_ratios,
                &|s| s.across == Some(across),
            )?);
        }
        match plot::map(
            &h.dir.join("stability_map.png"),
            "Stability map: green stable (text: time steps taken), amber refused, red failed",
            ("shear modulus G (Pa)", "ρs/ρf"),
            &panels,
        ) {
            Ok(()) => h.plots.push((
                format!("Stability map ({sphere} at reduced resolution)"),
                format!("{}/stability_map.png", Self::NAME),
            )),
            Err(e) => h.notes.push(format!("stability map not drawn: {e}")),
        }

        // The table behind the map, as a note per outcome kind, and the checks (over every
        // run, the coupled step's too).
        let all = &done.measured;
        let total = all.len();
        let stable = all
            .iter()
            .filter(|(_, o)| matches!(o, Outcome::Stable(_)))
            .count();
        let refused: Vec<_> = all
            .iter()
            .filter_map(|(s, o)| match o {
                Outcome::Refused(m) => Some((*s, m.clone())),
                _ => None,
            })
            .collect();
        let failed: Vec<_> = all
            .iter()
            .filter_map(|(s, o)| match o {
                Outcome::Failed(m) => Some(format!("{}: {m}", s.label())),
                _ => None,
            })
            .collect();
        for f in &failed {
            h.notes.push(format!("FAILED — {f}"));
        }
        // One line per kind of refusal (the message of its first setting).
        let mut kinds: Vec<(String, Vec<String>, String)> = Vec::new();
        for (s, m) in &refused {
            let kind = m.split(':').nth(1).unwrap_or(m).trim().to_string();
            match kinds.iter_mut().find(|(k, _, _)| *k == kind) {
                Some((_, labels, _)) => labels.push(s.label()),
                None => kinds.push((kind, vec![s.label()], m.clone())),
            }
        }
        for (_, labels, m) in &kinds {
            h.notes.push(format!(
                "refused ({} setting{}: {}): {m}",
                labels.len(),
                if labels.len() == 1 { "" } else { "s" },
                labels.join("; ")
            ));
        }
        let worst = |key: fn(&Figures) -> f64| {
            results
                .iter()
                .filter_map(|(s, o)| match o {
                    Outcome::Stable(f) => Some((key(f), s.label())),
                    _ => None,
                })
                .fold((f64::NEG_INFINITY, String::new()), |a, b| {
                    if b.0 > a.0 { b } else { a }
                })
        };
        let (mg, mg_at) = worst(|f| f.mech_gain);
        let (tp, tp_at) = worst(|f| f.total_peak);
        let (te, te_at) = worst(|f| f.total_end);
        let (vd, vd_at) = worst(|f| f.volume);
        h.notes.push(format!(
            "Largest among the stable runs: KE+PE gain {mg:.2e} E_b ({mg_at}); total-energy peak \
             {tp:.3} E_b ({tp_at}); total at the end {te:.2e} E_b ({te_at}); volume drift {vd:.1e} \
             ({vd_at})."
        ));
        if !coupled_results.is_empty() {
            let lines: Vec<String> = coupled_results
                .iter()
                .map(|(s, o)| {
                    let steps = steps_of(s).map_or(String::new(), |n| format!("{n} steps, "));
                    match o {
                        Outcome::Stable(f) => format!(
                            "{}: stable, {steps}KE+PE gain {:.1e} E_b, total at the end {:.2} E_b, \
                             leaves at {:.3} m/s",
                            s.label(),
                            f.mech_gain,
                            f.total_end,
                            f.rebound
                        ),
                        Outcome::Refused(m) => format!("{}: refused: {m}", s.label()),
                        Outcome::Failed(m) => format!("{}: FAILED ({steps}{m})", s.label()),
                    }
                })
                .collect();
            h.notes.push(format!(
                "The coupled elastic step (numerics.elastic.coupling: Coupled, Δt·c/h ≤ \
                 {DEFAULT_COUPLED_WAVE_COURANT}, and Auto, ≤ {DEFAULT_AUTO_COUPLED_WAVE_COURANT}), \
                 ratio 1e3: {}.",
                lines.join("; ")
            ));
        }
        if !THREE_D {
            h.notes.push(format!(
                "The split step's elastic-wave limit Δt·c/h ≤ {MAX_WAVE_COURANT} keeps G = 1e7 and \
                 1e9 stable at the cost of their step counts (without it, G = 1e9 gained 26 % of \
                 E_b)."
            ));
        }
        // The refusals' two settings and the small solids below the limit.
        let expected_refusals = done
            .measured
            .iter()
            .filter(|(s, _)| {
                s.fixed_dt.is_some()
                    || s.wave_courant.is_some()
                    || s.across.is_some_and(|n| n < MIN_CELLS_ACROSS)
            })
            .count();
        let mut checks = vec![
            Check::at_least(
                "runs finished stable or refused (no third outcome)",
                (stable + refused.len()) as f64,
                total as f64,
                "0",
            ),
            Check::at_most("runs failed", failed.len() as f64, 0.0, "0"),
            Check::at_least(
                "settings beyond a limit refused before the run",
                refused.len() as f64,
                expected_refusals as f64,
                "0",
            ),
        ];
        let names_setting = refused.iter().all(|(s, m)| {
            if s.across.is_some_and(|n| n < MIN_CELLS_ACROSS) {
                m.contains("solid.shape")
                    && m.contains("cells across")
                    && m.contains("refine the grid")
            } else if s.fixed_dt.is_some() {
                m.contains("time.fixed_dt")
                    && m.contains("wave_courant")
                    && m.contains("set time.fixed_dt ≤")
            } else {
                m.contains("numerics.elastic.wave_courant") && m.contains("must be in")
            }
        });
        checks.push(Check {
            what: "each refusal names the limit and the setting to change".into(),
            value: if names_setting { "yes" } else { "no" }.into(),
            target: "yes".into(),
            pass: names_setting && refused.len() == expected_refusals,
        });
        h.schedule = match scene_for(&Setting::new(1.8e5, 1e3, 0.5), cpr, Self::GEOMETRY).and_then(
            |(s, p)| {
                efsi_run::simulation(s, &p, &efsi_stages::builtin()).map_err(|e| e.to_string())
            },
        ) {
            Ok(sim) => stage_names(&sim),
            Err(_) => Vec::new(),
        };
        Ok(Verdict {
            title: format!(
                "Stability at the extremes: the {sphere} at {cpr} cells per radius over G × ρs/ρf \
                 × CFL, and solids 4 and 5 cells across"
            ),
            reference: "issue 8's criteria: finish with finite fields, solid volume kept, energy \
                        bounded by its start plus the work of gravity (walls at rest do no work) — \
                        or be refused before the run, naming the limit and the setting"
                .into(),
            error_metric: "KE+PE gain / energy budget".into(),
            checks,
            recommendation: format!(
                "keep numerics.elastic.wave_courant at its default {MAX_WAVE_COURANT}; a very stiff \
                 solid (G ≳ 1e7 Pa here) then runs at the elastic-wave step, not the flow's"
            ),
        })
    }
}
