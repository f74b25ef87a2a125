//! Setting a simulation up for a run: the checks a driver makes before and after
//! [`Simulation::new`] — the machine's memory, the scene's `output` section — and the energy
//! guard ([`crate::guard`]) added to its steps.

use crate::output::spec::SceneOutput;
use efsi_core::error::EfsiError;
use efsi_core::grid::GHOST;
use efsi_core::scene::bodies::SceneBodies;
use efsi_core::scene::{Options, Scene};
use efsi_core::{Simulation, StagePlugin};
use std::path::Path;

/// How a driver (the CLI, the FMU, the Python binding) builds its simulation: a scene beyond
/// the machine's memory refused before anything is allocated, then [`Simulation::new`], then
/// the scene's `output` section checked ([`crate::output::spec::check`]) and kept with its
/// settings in force, and the energy guard added ([`crate::guard::EnergyGuard`]).
pub fn simulation(
    scene: Scene,
    path: &Path,
    plugins: &[&dyn StagePlugin],
) -> Result<Simulation, EfsiError> {
    simulation_with(scene, None, path, plugins)
}

/// [`simulation`] for a scene checked already ([`Scene::check_options`], which returned
/// `options`), or checked here if `options` is `None`: its sections are read once either way.
pub(crate) fn simulation_with(
    mut scene: Scene,
    options: Option<Options>,
    path: &Path,
    plugins: &[&dyn StagePlugin],
) -> Result<Simulation, EfsiError> {
    // Before anything is allocated; a scene whose ranges are wrong is refused by the
    // simulation, naming the setting.
    if scene.validate().is_ok() {
        check_memory(&scene).map_err(|message| EfsiError::Config {
            path: path.to_path_buf(),
            field: "grid".into(),
            message,
        })?;
    }
    let mut sim = match options {
        Some(options) => Simulation::with_options(scene, options, path, plugins)?,
        None => {
            scene
                .validate()
                .map_err(|(field, message)| EfsiError::Config {
                    path: path.to_path_buf(),
                    field,
                    message,
                })?;
            let options = scene.check_options(path, plugins)?;
            Simulation::with_options(scene, options, path, plugins)?
        }
    };
    let spec = crate::output::spec::check(&sim.scene, path, sim.pipeline())?;
    sim.scene.set_output(&spec);
    sim.add_check(Box::new(crate::guard::EnergyGuard::default()));
    first_step(&sim, path)?;
    Ok(sim)
}

/// A scene whose own limits set a first step below its smallest allowed step (`time.dt_min`,
/// by default 1e-12·`time.end`) is refused before it runs, naming `time.dt_min` and the limit:
/// that is a conflict between its settings, not an unstable run (nothing has moved yet).
fn first_step(sim: &Simulation, path: &Path) -> Result<(), EfsiError> {
    let t = &sim.scene.time;
    let (dt, cause) = sim.step_limit(t.end);
    let dt_min = t.dt_min_or_default();
    if sim.state.step != 0 || dt.is_nan() || dt >= dt_min || dt <= 0.0 {
        return Ok(());
    }
    use efsi_core::scene::num;
    let floor = match t.dt_min {
        Some(_) => format!("time.dt_min = {}", num(dt_min)),
        None => format!(
            "time.dt_min's default 1e-12·time.end = {} (time.end = {})",
            num(dt_min),
            num(t.end)
        ),
    };
    Err(EfsiError::Config {
        path: path.to_path_buf(),
        field: "time.dt_min".into(),
        message: format!(
            "the first step, Δt = {}, set by {cause}, is below {floor}: every step would be \
             refused before anything moves; set time.dt_min lower, or change the setting that \
             limits Δt",
            num(dt)
        ),
    })
}

/// Memory a run needs per grid cell, ghost layers included (bytes): the fields, the stages'
/// work arrays and the solvers' hierarchies, from the peak resident size of runs on large grids
/// (fluid only, and with an elastic solid).
pub const BYTES_PER_CELL: (f64, f64) = (790.0, 2800.0);

/// [`BYTES_PER_CELL`] of a three-dimensional grid: the two-dimensional figures × 3/2, as the
/// arrays that grow with the dimension do — one velocity component and its stage work arrays
/// more (3 against 2), six tensor components against four — while the cell scalars do not (so
/// the bound is on the safe side).
pub const BYTES_PER_CELL_3D: (f64, f64) = (1185.0, 4200.0);

/// Refuse a scene whose estimated memory (cells with ghost layers × [`BYTES_PER_CELL`]) exceeds
/// the memory the machine has available now (`MemAvailable` of `/proc/meminfo`; no check where
/// that cannot be read), before anything is allocated.
fn check_memory(scene: &Scene) -> Result<(), String> {
    let (nx, ny) = (scene.grid.nx, scene.grid.ny);
    let three = scene.geometry == efsi_core::Geometry::Cartesian3D;
    let planes = match scene.grid.nz {
        Some(nz) if three => (nz + 1 + 2 * GHOST) as f64,
        _ => 1.0,
    };
    let padded = ((nx + 1 + 2 * GHOST) * (ny + 1 + 2 * GHOST)) as f64 * planes;
    let bytes = if three {
        BYTES_PER_CELL_3D
    } else {
        BYTES_PER_CELL
    };
    let per_cell = if scene.has_bodies() { bytes.1 } else { bytes.0 };
    let need = padded * per_cell;
    let Some(available) = std::fs::read_to_string("/proc/meminfo").ok().and_then(|m| {
        m.lines()
            .find_map(|l| l.strip_prefix("MemAvailable:"))
            .and_then(|v| v.trim().trim_end_matches("kB").trim().parse::<f64>().ok())
            .map(|kb| kb * 1024.0)
    }) else {
        return Ok(());
    };
    if need <= available {
        return Ok(());
    }
    Err(format!(
        "the run needs about {:.1} GB ({padded:.3e} cells with ghost layers × ≈ {per_cell} B{}), \
         more than the {:.1} GB of memory available: use a coarser grid (e.g. --refine {:.2})",
        need / 1e9,
        if scene.has_bodies() {
            " with a solid"
        } else {
            ""
        },
        available / 1e9,
        {
            // The factor that brings the cell count under what is available.
            let r = available / need;
            if three { r.cbrt() } else { r.sqrt() }
        } * 0.9
    ))
}

/// Worker threads per core a run may ask for ([`worker_threads`]): the stages' parallel loops
/// gain nothing past one thread per core, and a few per core leave room for timing tests of
/// oversubscription; thousands would only exhaust the process's threads and memory.
pub const THREADS_PER_CORE: usize = 4;

/// The worker threads a run asked for — `requested` (a `--threads` option), else
/// `$RAYON_NUM_THREADS` — checked against [`THREADS_PER_CORE`] × this machine's cores; `None`:
/// the default (one per core). A requested 0 is one thread; `$RAYON_NUM_THREADS=0` the
/// default, as the thread pool reads it. The error names where the number came from, the number and the
/// limit.
pub fn worker_threads(requested: Option<usize>, option: &str) -> Result<Option<usize>, EfsiError> {
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    let limit = THREADS_PER_CORE * cores;
    let (n, from) = match requested {
        Some(n) => (n, option.to_string()),
        None => match std::env::var("RAYON_NUM_THREADS") {
            Ok(v) => match v.trim().parse::<usize>() {
                Ok(n) => (n, "$RAYON_NUM_THREADS".to_string()),
                Err(_) => {
                    return Err(EfsiError::Config {
                        path: "$RAYON_NUM_THREADS".into(),
                        field: "worker threads".into(),
                        message: format!("must be a whole number, got `{v}`"),
                    });
                }
            },
            Err(_) => return Ok(None),
        },
    };
    if n > limit {
        return Err(EfsiError::Config {
            path: from.into(),
            field: "worker threads".into(),
            message: format!(
                "{n} asked for, at most {limit} ({THREADS_PER_CORE} per core; this machine has {cores} cores)"
            ),
        });
    }
    Ok(match requested {
        // At least one.
        Some(n) => Some(n.max(1)),
        // 0 is the thread pool's own default: one per core.
        None => (n > 0).then_some(n),
    })
}
