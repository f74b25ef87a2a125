//! The run loop and its outputs: `(schedule, writer)` pairs kept apart from the model
//! (STYLE.md §5). Δt is shortened to land exactly on every output time.
//!
//! A run writes into its output folder:
//! - `fields/<name>_<step>.vtr` and `fields.pvd` (VTK XML for ParaView; the collection is
//!   rewritten after each file, so it is valid at every moment of the run);
//! - `probes.csv`: header `t,<columns…>`, one row per sample, flushed row by row;
//! - `profiles/<name>_t<time>.csv`: the coordinate along the line `s`, `x`, `y`, then the fields;
//! - `run.json`: the scene as read, efsi version, steps, wall time, wall time per stage.

use crate::error::EfsiError;
use crate::field::Field;
use crate::grid::Grid;
use crate::output::vtk::{CellArray, PvdCollection, write_vtr};
use crate::probes;
use crate::scene::{ProbeSpec, ProfileSpec};
use crate::simulation::Simulation;
use crate::state::State;
use std::fs::{self, File};
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};
use std::time::Instant;

/// What the progress display is told after each step.
#[derive(Clone, Copy, Debug)]
pub struct Progress {
    /// Simulated time.
    pub t: f64,
    /// End time.
    pub end: f64,
    /// Steps done.
    pub step: u64,
    /// Last Δt.
    pub dt: f64,
    /// Wall seconds since the start.
    pub wall: f64,
}

/// Why a run stopped.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
pub enum StopReason {
    /// Reached `time.end`.
    EndTime,
    /// The flow became steady (`time.steady`).
    Steady,
}

/// Summary of a finished run.
#[derive(Clone, Debug)]
pub struct RunOutcome {
    /// Steps taken.
    pub steps: u64,
    /// Final time.
    pub t: f64,
    /// Wall time (s).
    pub wall_seconds: f64,
    /// Why it stopped.
    pub stop: StopReason,
    /// The output folder.
    pub out_dir: PathBuf,
}

/// Format a time for file names: shortest decimal, e.g. `0.5`, `30`, `2.8`.
pub fn time_label(t: f64) -> String {
    let s = format!("{:.6}", t);
    let s = s.trim_end_matches('0').trim_end_matches('.');
    s.to_string()
}

fn due(t: f64, event: f64) -> bool {
    t >= event - 1e-9 * event.abs().max(1e-12)
}

/// The writers of one run.
pub struct Outputs {
    dir: PathBuf,
    vtk_every: Option<f64>,
    vtk_count: u64,
    pvd: PvdCollection,
    probe_every: Option<f64>,
    probe_count: u64,
    probes: Vec<ProbeSpec>,
    probe_file: BufWriter<File>,
    row: Vec<f64>,
    profiles: Vec<(ProfileSpec, Vec<f64>)>,
    end: f64,
}

impl Outputs {
    /// Create the output folder and open the writers (fails before any step if it cannot).
    pub fn new(sim: &Simulation, dir: &Path) -> Result<Outputs, EfsiError> {
        let o = &sim.scene.output;
        for d in [dir.to_path_buf(), dir.join("fields"), dir.join("profiles")] {
            fs::create_dir_all(&d).map_err(|e| EfsiError::io(&d, e))?;
        }
        let path = dir.join("probes.csv");
        let file = File::create(&path).map_err(|e| EfsiError::io(&path, e))?;
        let mut probe_file = BufWriter::new(file);
        let mut header = vec!["t".to_string()];
        for p in &o.probes {
            header.extend(probes::columns(p));
        }
        writeln!(probe_file, "{}", header.join(",")).map_err(|e| EfsiError::io(&path, e))?;
        let profiles = o
            .profiles
            .iter()
            .map(|p| {
                let ProfileSpec::Line { at, .. } = p;
                let mut times = at.clone();
                times.sort_by(f64::total_cmp);
                (p.clone(), times)
            })
            .collect();
        Ok(Outputs {
            dir: dir.to_path_buf(),
            vtk_every: o.vtk_every,
            vtk_count: 0,
            pvd: PvdCollection::new(dir.join("fields.pvd")),
            probe_every: o.probe_every,
            probe_count: 0,
            probes: o.probes.clone(),
            probe_file,
            row: Vec::new(),
            profiles,
            end: sim.scene.time.end,
        })
    }

    /// The next time an output is due after `t` (or the end).
    pub fn next_event(&self, t: f64) -> f64 {
        let mut next = self.end;
        if let Some(e) = self.vtk_every {
            next = next.min(self.vtk_count as f64 * e);
        }
        if let Some(e) = self.probe_every {
            next = next.min(self.probe_count as f64 * e);
        }
        for (_, times) in &self.profiles {
            if let Some(&tt) = times.first() {
                next = next.min(tt);
            }
        }
        next.max(t)
    }

    /// Write whatever is due at the simulation's current time (everything, if `last`).
    pub fn emit(&mut self, sim: &Simulation, last: bool) -> Result<(), EfsiError> {
        let t = sim.state.t;
        let probe_due = match self.probe_every {
            Some(e) => due(t, self.probe_count as f64 * e),
            None => true,
        };
        if probe_due || last {
            self.row.clear();
            self.row.push(t);
            for p in &self.probes {
                probes::evaluate(p, &sim.grid, &sim.state, &mut self.row);
            }
            let line: Vec<String> = self.row.iter().map(|v| format!("{v:.17e}")).collect();
            let path = self.dir.join("probes.csv");
            writeln!(self.probe_file, "{}", line.join(",")).map_err(|e| EfsiError::io(&path, e))?;
            self.probe_file
                .flush()
                .map_err(|e| EfsiError::io(&path, e))?;
            if let Some(e) = self.probe_every {
                while due(t, self.probe_count as f64 * e) {
                    self.probe_count += 1;
                }
            }
        }
        let vtk_due = self
            .vtk_every
            .is_some_and(|e| due(t, self.vtk_count as f64 * e));
        if vtk_due || (last && self.vtk_every.is_some()) {
            self.write_fields(&sim.grid, &sim.state, &sim.scene.name)?;
            if let Some(e) = self.vtk_every {
                while due(t, self.vtk_count as f64 * e) {
                    self.vtk_count += 1;
                }
            }
        }
        for k in 0..self.profiles.len() {
            let is_due = self.profiles[k].1.first().is_some_and(|&tt| due(t, tt));
            let at_end = last && self.profiles[k].1.is_empty();
            if is_due || at_end {
                self.write_profile(k, sim)?;
                while self.profiles[k].1.first().is_some_and(|&tt| due(t, tt)) {
                    self.profiles[k].1.remove(0);
                }
            }
        }
        Ok(())
    }

    fn write_fields(&mut self, grid: &Grid, state: &State, name: &str) -> Result<(), EfsiError> {
        let (nx, ny) = (grid.nx, grid.ny);
        let n = nx * ny;
        let mut vel = vec![0.0; 3 * n];
        let mut div = vec![0.0; n];
        let mut scalars: Vec<(&str, Vec<f64>)> = vec![
            ("pressure", Vec::with_capacity(n)),
            ("density", Vec::with_capacity(n)),
            ("viscosity", Vec::with_capacity(n)),
        ];
        if state.phi.is_some() {
            scalars.push(("solid_fraction", Vec::with_capacity(n)));
        }
        // Axisymmetric output is the r–z slice in the X–Z plane (u_z goes to the Z component).
        let vy = if grid.is_axisymmetric() { 2 } else { 1 };
        for j in 0..ny as isize {
            for i in 0..nx as isize {
                let k = j as usize * nx + i as usize;
                let (a, b) = crate::ops::centre_velocity(&state.u, &state.v, i, j);
                vel[3 * k] = a;
                vel[3 * k + vy] = b;
                div[k] = crate::ops::div(grid, &state.u, &state.v, i, j);
                scalars[0].1.push(state.p[(i, j)]);
                scalars[1].1.push(state.rho[(i, j)]);
                scalars[2].1.push(state.mu[(i, j)]);
                if let Some(phi) = &state.phi {
                    scalars[3].1.push(phi[(i, j)]);
                }
            }
        }
        // B̃ = φ^{1/2} B and the elastic stress as VTK symmetric tensors.
        let (mut btilde, mut stress) = (Vec::new(), Vec::new());
        if let (Some(d), Some(phi)) = (&state.deformation, &state.phi) {
            btilde = vtk_tensor(grid, &d.b, Some(phi));
            stress = vtk_tensor(grid, &d.stress, None);
        }
        let mut arrays = vec![
            CellArray {
                name: "velocity",
                components: 3,
                values: &vel,
            },
            CellArray {
                name: "divergence",
                components: 1,
                values: &div,
            },
        ];
        if !btilde.is_empty() {
            arrays.push(CellArray {
                name: "B",
                components: 6,
                values: &btilde,
            });
            arrays.push(CellArray {
                name: "stress",
                components: 6,
                values: &stress,
            });
        }
        for (nm, v) in &scalars {
            arrays.push(CellArray {
                name: nm,
                components: 1,
                values: v,
            });
        }
        let file = format!("{name}_{:06}.vtr", state.step);
        let path = self.dir.join("fields").join(&file);
        write_vtr(&path, grid, state.t, &arrays).map_err(|e| EfsiError::io(&path, e))?;
        let rel = format!("fields/{file}");
        self.pvd
            .add(state.t, &rel)
            .map_err(|e| EfsiError::io(self.dir.join("fields.pvd"), e))?;
        Ok(())
    }

    fn write_profile(&mut self, k: usize, sim: &Simulation) -> Result<(), EfsiError> {
        let ProfileSpec::Line {
            name,
            from,
            to,
            points,
            fields,
            ..
        } = &self.profiles[k].0;
        let path = self
            .dir
            .join("profiles")
            .join(format!("{name}_t{}.csv", time_label(sim.state.t)));
        let len = (to.0 - from.0).hypot(to.1 - from.1);
        let mut text = format!("s,x,y,{}\n", fields.join(","));
        for q in 0..*points {
            let f = q as f64 / (*points - 1) as f64;
            let p = (from.0 + f * (to.0 - from.0), from.1 + f * (to.1 - from.1));
            text.push_str(&format!("{:.17e},{:.17e},{:.17e}", f * len, p.0, p.1));
            for fl in fields {
                text.push_str(&format!(
                    ",{:.17e}",
                    probes::sample(&sim.grid, &sim.state, fl, p)
                ));
            }
            text.push('\n');
        }
        crate::output::atomic::write_atomically(&path, |w| w.write_all(text.as_bytes()))
            .map_err(|e| EfsiError::io(&path, e))
    }

    /// Write `run.json`.
    pub fn write_summary(&self, sim: &Simulation, outcome: &RunOutcome) -> Result<(), EfsiError> {
        let timings = sim.pipeline().timings();
        let cells = sim.grid.cells() as f64;
        let steps = outcome.steps.max(1) as f64;
        let json = serde_json::json!({
            "efsi_version": env!("CARGO_PKG_VERSION"),
            "scene": serde_json::to_value(&sim.scene).unwrap_or_default(),
            "scene_path": sim.scene_path.display().to_string(),
            "stop": outcome.stop,
            "t_end": outcome.t,
            "steps": outcome.steps,
            "cells": sim.grid.cells(),
            "wall_seconds": outcome.wall_seconds,
            "ns_per_cell_step": outcome.wall_seconds * 1e9 / (cells * steps),
            "projection_tolerance": sim.scene.numerics.projection.tolerance,
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
        crate::output::atomic::write_atomically(&path, |w| w.write_all(text.as_bytes()))
            .map_err(|e| EfsiError::io(&path, e))
    }
}

/// Run `sim` to its end time (or steady state), writing outputs into `dir`.
pub fn run(
    sim: &mut Simulation,
    dir: &Path,
    progress: &mut dyn FnMut(&Progress),
) -> Result<RunOutcome, EfsiError> {
    let start = Instant::now();
    let mut out = Outputs::new(sim, dir)?;
    out.emit(sim, false)?;
    let end = sim.scene.time.end;
    let mut stop = StopReason::EndTime;
    while !due(sim.state.t, end) {
        let until = out.next_event(sim.state.t);
        let until = if due(sim.state.t, until) {
            end.min(out.next_event(sim.state.t + 1e-9 * end))
        } else {
            until
        };
        let dt = sim.next_dt(until)?;
        sim.step(dt)?;
        sim.snap_time(until);
        let finished = due(sim.state.t, end) || sim.is_steady();
        out.emit(sim, finished)?;
        progress(&Progress {
            t: sim.state.t,
            end,
            step: sim.state.step,
            dt,
            wall: start.elapsed().as_secs_f64(),
        });
        if sim.is_steady() {
            stop = StopReason::Steady;
            break;
        }
    }
    let outcome = RunOutcome {
        steps: sim.state.step,
        t: sim.state.t,
        wall_seconds: start.elapsed().as_secs_f64(),
        stop,
        out_dir: dir.to_path_buf(),
    };
    out.write_summary(sim, &outcome)?;
    Ok(outcome)
}

/// A staggered tensor (11, 22, 33 at centres, 12 at corners) at the cell centres as a VTK
/// symmetric tensor (XX, YY, ZZ, XY, YZ, XZ), weighted by `φ^{1/2}` if `phi` is given. Planar:
/// 1 = X, 2 = Y, 3 = Z. Axisymmetric (the r–z slice in the X–Z plane): r = X, z = Z, θ = Y.
fn vtk_tensor(grid: &Grid, t: &[Field; 4], phi: Option<&Field>) -> Vec<f64> {
    let (nx, ny) = (grid.nx, grid.ny);
    let mut out = vec![0.0; 6 * nx * ny];
    let (c11, c22, c33, c12) = if grid.is_axisymmetric() {
        (0, 2, 1, 5)
    } else {
        (0, 1, 2, 3)
    };
    for j in 0..ny as isize {
        for i in 0..nx as isize {
            let k = 6 * (j as usize * nx + i as usize);
            let w = phi.map_or(1.0, |p| p[(i, j)].clamp(0.0, 1.0).sqrt());
            let t12 =
                0.25 * (t[3][(i, j)] + t[3][(i + 1, j)] + t[3][(i, j + 1)] + t[3][(i + 1, j + 1)]);
            out[k + c11] = w * t[0][(i, j)];
            out[k + c22] = w * t[1][(i, j)];
            out[k + c33] = w * t[2][(i, j)];
            out[k + c12] = w * t12;
        }
    }
    out
}
