//! Setting a simulation up for a run: the checks a driver makes before and after
//! [`Simulation::new`] — the machine's memory, the scene's `output` section — and the energy
//! guard ([`crate::guard`]) added to its steps.

use crate::output::spec::SceneOutput;
use efsi_core::error::EfsiError;
use efsi_core::grid::GHOST;
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
    Ok(sim)
}

/// Memory a run needs per grid cell, ghost layers included (bytes): the fields, the stages'
/// work arrays and the solvers' hierarchies, from the peak resident size of runs on large grids
/// (fluid only, and with an elastic solid).
pub const BYTES_PER_CELL: (f64, f64) = (790.0, 2800.0);

/// Refuse a scene whose estimated memory (cells with ghost layers × [`BYTES_PER_CELL`]) exceeds
/// the memory the machine has available now (`MemAvailable` of `/proc/meminfo`; no check where
/// that cannot be read), before anything is allocated.
fn check_memory(scene: &Scene) -> Result<(), String> {
    let (nx, ny) = (scene.grid.nx, scene.grid.ny);
    let padded = ((nx + 1 + 2 * GHOST) * (ny + 1 + 2 * GHOST)) as f64;
    let per_cell = if scene.solid.is_some() {
        BYTES_PER_CELL.1
    } else {
        BYTES_PER_CELL.0
    };
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
        if scene.solid.is_some() {
            " with a solid"
        } else {
            ""
        },
        available / 1e9,
        (available / need).sqrt() * 0.9
    ))
}
