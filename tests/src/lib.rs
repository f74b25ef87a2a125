//! Shared helpers for the workspace integration tests: building simulations from scene text,
//! stepping them without outputs, and locating the reference data the repository carries in
//! `tests/references/`.

use efsi_core::{Advance, EfsiError, Flow, Scene, Simulation, StagePlugin, StepInfo};
use std::path::{Path, PathBuf};

/// Parse scene text (panics with the loader's message if it is invalid).
pub fn scene(text: &str) -> Scene {
    Scene::from_str_at(text, Path::new("<test>")).unwrap_or_else(|e| panic!("{e}"))
}

/// A simulation of `text` with all built-in stages.
pub fn sim(text: &str) -> Simulation {
    sim_with(text, &efsi_stages::builtin()).unwrap_or_else(|e| panic!("{e}"))
}

/// A simulation of `text` with the given stage plugins.
pub fn sim_with(text: &str, plugins: &[&dyn StagePlugin]) -> Result<Simulation, EfsiError> {
    efsi_run::simulation(scene(text), Path::new("<test>"), plugins)
}

/// Step `sim` until time `t` (landing on it, [`Simulation::advance_to`]), calling `each` with
/// the simulation and Δt after every step.
pub fn run_until(sim: &mut Simulation, t: f64, mut each: impl FnMut(&Simulation, f64)) {
    let mut hook = |sim: &mut Simulation, step: &StepInfo| {
        each(sim, step.dt);
        Ok(Flow::Continue)
    };
    let control = Advance {
        on_step: Some(&mut hook),
        ..Advance::default()
    };
    sim.advance_to(t, control).unwrap_or_else(|e| panic!("{e}"));
}

/// Step until steady (the scene's `time.steady`) or `t_max`; returns the time reached.
pub fn run_to_steady(sim: &mut Simulation, t_max: f64) -> f64 {
    while sim.state.t < t_max && !sim.is_steady() {
        let dt = sim.next_dt(t_max).unwrap_or_else(|e| panic!("{e}"));
        sim.step(dt).unwrap_or_else(|e| panic!("{e}"));
    }
    sim.state.t
}

/// The folder of the reference data the repository carries (`tests/references/`).
pub fn references_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("references")
}

/// The workspace root (the folder of the top-level `Cargo.toml`).
pub fn workspace_root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .parent()
        .expect("the tests crate sits in the workspace")
        .to_path_buf()
}

/// A file of the reference data, `rel` relative to [`references_dir`]. Panics if it is missing
/// or if `rel` resolves to a file outside the repository (a test must never depend on data a
/// clone of the repository does not carry).
pub fn reference(rel: &str) -> PathBuf {
    try_reference(rel).unwrap_or_else(|e| panic!("{e}"))
}

/// [`reference()`] with the failure as an error.
pub fn try_reference(rel: &str) -> Result<PathBuf, String> {
    let p = references_dir().join(rel);
    let canonical = p
        .canonicalize()
        .map_err(|e| format!("reference data {}: {e}", p.display()))?;
    let root = workspace_root()
        .canonicalize()
        .map_err(|e| format!("workspace root: {e}"))?;
    if !canonical.starts_with(&root) {
        return Err(format!(
            "reference data {} resolves to {}, outside the repository {}",
            p.display(),
            canonical.display(),
            root.display()
        ));
    }
    Ok(canonical)
}

/// Read a CSV with a header (lines starting with `#` skipped) into column-major numbers.
pub fn read_csv(path: &Path) -> (Vec<String>, Vec<Vec<f64>>) {
    try_read_csv(path).unwrap_or_else(|e| panic!("{e}"))
}

/// [`read_csv`] with the failure as an error naming the file (a cell that is not a number
/// reads as NaN).
pub fn try_read_csv(path: &Path) -> Result<(Vec<String>, Vec<Vec<f64>>), String> {
    let text = std::fs::read_to_string(path).map_err(|e| format!("{}: {e}", path.display()))?;
    let mut lines = text
        .lines()
        .filter(|l| !l.starts_with('#') && !l.trim().is_empty());
    let header: Vec<String> = lines
        .next()
        .ok_or_else(|| format!("{}: no header", path.display()))?
        .split(',')
        .map(|s| s.trim().to_string())
        .collect();
    let mut cols = vec![Vec::new(); header.len()];
    for l in lines {
        for (k, v) in l.split(',').enumerate().take(header.len()) {
            cols[k].push(v.trim().parse::<f64>().unwrap_or(f64::NAN));
        }
    }
    Ok((header, cols))
}

/// Linear interpolation of `(xs, ys)` (xs increasing) at `x`.
pub fn interp(xs: &[f64], ys: &[f64], x: f64) -> f64 {
    let k = xs.partition_point(|&a| a < x).clamp(1, xs.len() - 1);
    let w = (x - xs[k - 1]) / (xs[k] - xs[k - 1]);
    ys[k - 1] * (1.0 - w) + ys[k] * w
}

/// Observed orders of convergence between successive (h, error) pairs.
pub fn orders(h: &[f64], e: &[f64]) -> Vec<f64> {
    (1..h.len())
        .map(|k| (e[k - 1] / e[k]).ln() / (h[k - 1] / h[k]).ln())
        .collect()
}
pub mod paper;

/// Scenes shared by the parallel and allocation tests (large enough for the parallel paths).
pub mod scenes {
    /// The Re = 1000 lid-driven cavity at 128².
    pub const CAVITY: &str = r#"Scene(
    name: "cavity",
    domain: (x: (0.0, 1.0), y: (0.0, 1.0)),
    grid: (nx: 128, ny: 128),
    time: (end: 1.0, cfl: 0.4),
    fluid: (density: 1.0, viscosity: 1e-3),
    boundaries: (x_min: NoSlip, x_max: NoSlip, y_min: NoSlip, y_max: MovingWall(speed: 1.0)),
    )"#;

    /// The axisymmetric drop of density 1 in a fluid of density 1e-3 at 128², fixed Δt.
    pub const DROP: &str = r#"Scene(
    name: "drop",
    geometry: Axisymmetric,
    domain: (r: (0.0, 4.0), z: (0.0, 4.0)),
    grid: (nr: 128, nz: 128),
    time: (end: 1.0, fixed_dt: 0.00390625),
    fluid: (density: 1e-3, viscosity: 2e-4),
    gravity: (0.0, -1.0),
    solid: (shape: Disk(center: (0.0, 3.0), radius: 0.5), density: 1.0, viscosity: 1e-2),
    boundaries: (r_min: Axis, r_max: NoSlip, z_min: NoSlip, z_max: NoSlip),
    )"#;

    /// The sphere impact of `cases/sphere_impact.ron` (35 cells per radius, 82 × 164, the
    /// neo-Hookean plugin law) released 1.5 cells above the substrate: it touches down within a
    /// few steps, so the elastic stage's solve, its block multigrid and the contact all run.
    pub const SPHERE: &str = r#"Scene(
    name: "sphere",
    geometry: Axisymmetric,
    domain: (r: (0.0, 0.045), z: (0.0, 0.09)),
    grid: (nr: 82, nz: 164),
    time: (end: 0.06, cfl: 0.4),
    fluid: (density: 1.2, viscosity: 1.8e-5),
    gravity: (0.0, -9.81),
    solid: (
        shape: Disk(center: (0.0, 0.0200), radius: 0.0192),
        density: 1106.0,
        velocity: (0.0, -1.22),
        law: (name: "neo_hookean", parameters: {"G": 0.18e6}),
    ),
    boundaries: (r_min: Axis, r_max: NoSlip, z_min: NoSlip, z_max: NoSlip),
    )"#;

    /// Three soft disks of two materials, two of them within the contact's reach of each other and
    /// one of the floor, at 64²: every body's window, the contact's halos, pairs and frictionless
    /// projection.
    pub const DISKS: &str = r#"Scene(
    name: "disks",
    domain: (x: (0.0, 1.0), y: (0.0, 1.0)),
    grid: (nx: 64, ny: 64),
    time: (end: 1.0, cfl: 0.4),
    fluid: (density: 1.0, viscosity: 0.01),
    gravity: (0.0, -1.0),
    solids: [
        (name: "a", shape: Disk(center: (0.3, 0.125), radius: 0.12), density: 1.5, viscosity: 0.01,
         law: (name: "neo_hookean", parameters: {"G": 1.0})),
        (name: "b", shape: Disk(center: (0.55, 0.14), radius: 0.12), density: 2.0, viscosity: 0.01,
         law: (name: "neo_hookean", parameters: {"G": 4.0})),
        (name: "c", shape: Disk(center: (0.45, 0.6), radius: 0.1), density: 1.5, viscosity: 0.01,
         velocity: (0.0, -1.0), law: (name: "neo_hookean", parameters: {"G": 1.0})),
    ],
    boundaries: (x_min: NoSlip, x_max: NoSlip, y_min: NoSlip, y_max: NoSlip),
)"#;
}
