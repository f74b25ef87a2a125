//! `run.json`, the run's record: its identity (`run_id`, also in its checkpoints), the effective
//! scene and overrides, how it stands or stopped, its steps, wall time and wall time per stage,
//! and the process's peak resident memory.

use super::{Outputs, RunOutcome};
use crate::checkpoint;
use efsi_core::error::EfsiError;
use efsi_core::simulation::Simulation;
use std::path::Path;

/// A new run's identity: a hash of the clock, the process and the folder.
pub(super) fn new_run_id(dir: &Path) -> String {
    let nanos = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map_or(0, |d| d.as_nanos());
    let mut bytes = nanos.to_le_bytes().to_vec();
    bytes.extend_from_slice(&std::process::id().to_le_bytes());
    let dir = std::path::absolute(dir).unwrap_or_else(|_| dir.to_path_buf());
    bytes.extend_from_slice(dir.as_os_str().as_encoded_bytes());
    format!("{:016x}", checkpoint::content_hash(&bytes))
}

/// The run identity recorded in `dir/run.json`, or why there is none (the file cannot be read
/// — absent, not a regular file, longer than a record can be — or names no run).
pub(super) fn recorded_run_id(dir: &Path) -> Result<String, String> {
    let path = dir.join("run.json");
    let text =
        crate::output::read::read_regular_text(&path, crate::output::read::MAX_RUN_JSON_BYTES)
            .map_err(|e| format!("{} cannot be read ({e})", path.display()))?;
    let json: serde_json::Value = serde_json::from_str(&text)
        .map_err(|e| format!("{} is not a run record ({e})", path.display()))?;
    json.get("run_id")
        .and_then(|v| v.as_str())
        .map(str::to_string)
        .ok_or_else(|| format!("{} names no run", path.display()))
}

/// The process's peak resident memory so far, in bytes (`VmHWM` of `/proc/self/status`; `None`
/// where the system has no such file, e.g. outside Linux).
pub(crate) fn peak_rss_bytes() -> Option<u64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let kb = status
        .lines()
        .find_map(|l| l.strip_prefix("VmHWM:"))?
        .trim()
        .strip_suffix("kB")?
        .trim()
        .parse::<u64>()
        .ok()?;
    Some(kb * 1024)
}

impl Outputs {
    /// Write `run.json` for a finished or stopped run.
    pub fn write_summary(&self, sim: &Simulation, outcome: &RunOutcome) -> Result<(), EfsiError> {
        self.write_run_json(
            sim,
            serde_json::to_value(outcome.stop).unwrap_or_default(),
            outcome.steps_this_run,
            outcome.resumed_from.as_ref().map(|r| r.0),
            outcome.wall_seconds,
        )
    }

    /// Write `run.json` with `stop` saying how the run stands (`"Running"` while it runs, the
    /// [`StopReason`](super::StopReason) at its end, `{"Failed": {"error": …}}` after a failed
    /// step or output).
    pub(super) fn write_run_json(
        &self,
        sim: &Simulation,
        stop: serde_json::Value,
        steps_this_run: u64,
        resumed_from_step: Option<u64>,
        wall_seconds: f64,
    ) -> Result<(), EfsiError> {
        let timings = sim.pipeline().timings();
        let cells = sim.grid.cells() as f64;
        let steps = steps_this_run.max(1) as f64;
        let mut scene = serde_json::to_value(&sim.scene).unwrap_or_default();
        // The stages' numerics sections are RON text in the scene: recorded as JSON values.
        for (name, json) in sim.scene.numerics.sections_json() {
            scene["numerics"][name] = json.clone();
        }
        scene["output"] = crate::output::spec::json(&sim.scene);
        scene["solid"] = efsi_core::scene::solid::checked_json(sim.options());
        let projection_tolerance = scene["numerics"]["projection"]["tolerance"].clone();
        let json = serde_json::json!({
            "run_id": self.run_id,
            "efsi_version": env!("CARGO_PKG_VERSION"),
            "scene": scene,
            "scene_path": sim.scene_path.display().to_string(),
            "overrides": sim.scene.overrides.iter().map(|o| o.to_string()).collect::<Vec<_>>(),
            "stop": stop,
            "warnings": self.warnings,
            "vtk": crate::output::fields::summary(&sim.grid, &sim.state, &self.vtk, &self.slices, sim.pipeline().outputs()),
            "t_end": sim.state.t,
            "steps": sim.state.step,
            "steps_this_run": steps_this_run,
            "resumed_from_step": resumed_from_step,
            "cells": sim.grid.cells(),
            "wall_seconds": wall_seconds,
            "ns_per_cell_step": wall_seconds * 1e9 / (cells * steps),
            "peak_rss_bytes": peak_rss_bytes(),
            "projection_tolerance": projection_tolerance,
            "final_rate_of_change": if sim.rate_of_change().is_finite() { serde_json::json!(sim.rate_of_change()) } else { serde_json::Value::Null },
            "stages": timings.iter().map(|s| serde_json::json!({
                "name": s.name,
                "seconds": s.seconds,
                "ns_per_cell_step": s.seconds * 1e9 / (cells * steps),
                "solver_iterations": s.iterations,
                "solver_iterations_per_step": s.iterations as f64 / steps,
            })).collect::<Vec<_>>(),
        });
        let path = self.dir.join("run.json");
        let text = serde_json::to_string_pretty(&json).unwrap_or_default();
        crate::output::atomic::write_bytes_atomically(&path, text.as_bytes())
            .map_err(|e| EfsiError::io(&path, e))
    }
}
