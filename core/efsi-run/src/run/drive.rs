//! The step loop of a run: advancing the simulation to each output time, the outputs and
//! checkpoints after every step, and what a stop request, a failed step or a failed output
//! leaves behind (a checkpoint, the last good state, `run.json`'s `"Failed"`).

use super::outputs::checkpoints::save_checkpoint;
use super::room::Room;
use super::{Outputs, Progress, RunOptions, RunOutcome, StopReason};
use crate::checkpoint::{self, LawIdentity};
use efsi_core::error::EfsiError;
use efsi_core::simulation::Simulation;
use efsi_core::{Advance, AdvanceError, Advanced, Flow, Rollback, StepInfo, StepStart, due};
use std::time::Instant;

/// Keep room on disk for the run's last checkpoint and `run.json` ([`super::room`]), sized by
/// the checkpoint of the current state (counted, no snapshot made) and the `run.json` written.
pub(super) fn make_room(
    sim: &Simulation,
    law: &Option<LawIdentity>,
    out: &mut Outputs,
) -> Result<(), EfsiError> {
    let bytes = checkpoint::encoded_len_of(sim, law, &out.state());
    let record = std::fs::metadata(out.dir.join("run.json")).map_or(0, |m| m.len());
    let needed = Room::needed(bytes as u64, record);
    let room = Room::keep(&out.dir, needed).map_err(|e| {
        EfsiError::io(
            out.dir.join("checkpoint").join("room"),
            std::io::Error::new(
                e.kind(),
                format!("cannot keep {needed} bytes for the run's last checkpoint: {e}"),
            ),
        )
    })?;
    out.room = Some(room);
    Ok(())
}

/// The step loop shared by [`run_with`](super::run_with) and [`resume`](super::resume).
pub(super) fn drive(
    sim: &mut Simulation,
    out: &mut Outputs,
    law: &Option<LawIdentity>,
    options: &RunOptions,
    progress: &mut dyn FnMut(&Progress),
    start: Instant,
    resumed_from: Option<(u64, f64, String)>,
) -> Result<RunOutcome, EfsiError> {
    let end = sim.scene.time.end;
    let first_step = sim.state.step;
    let mut stop = StopReason::EndTime;
    let mut last_good = options.save_last_good.then(StepStart::default);
    let mut latest = None;
    while !due(sim.state.t, end) {
        let until = next_stop(out, sim.state.t, end);
        let advanced = {
            let mut each = after_step(out, progress, start, end);
            let control = Advance {
                stop: options.stop.as_deref(),
                rollback: match &mut last_good {
                    Some(_) => Rollback::Step(&mut last_good),
                    None => Rollback::None,
                },
                on_step: Some(&mut each),
                ..Advance::default()
            };
            sim.advance_to(until, control)
        };
        let error = match advanced {
            Ok(Advanced::Reached) => continue,
            Ok(Advanced::Halted) => {
                stop = StopReason::Steady;
                break;
            }
            Ok(Advanced::Stopped { signal }) => {
                // The run ends here: the room kept for this checkpoint is free.
                out.release_room();
                match save_checkpoint(sim, law, out.state(), sim.snapshot(), &out.dir) {
                    Ok(c) => {
                        latest = Some(c);
                        stop = StopReason::Interrupted { signal };
                        break;
                    }
                    Err(error) => error,
                }
            }
            // The simulation is back at the start of the failed step: the last good state.
            Err(AdvanceError::Failed { error, good: true }) => {
                out.release_room();
                let good = sim.snapshot();
                save_failure(sim, out, law, good, error)
            }
            // An output or a checkpoint could not be written after a good step: save the state
            // at the start of that step, whose outputs a resume writes again.
            Err(AdvanceError::Hook(error)) => {
                save_before_failed_output(sim, out, law, last_good.as_ref(), error)
            }
            Err(e) => e.into(),
        };
        return Err(failed(sim, out, start, first_step, error));
    }
    let outcome = RunOutcome {
        steps: sim.state.step,
        t: sim.state.t,
        wall_seconds: start.elapsed().as_secs_f64(),
        stop,
        out_dir: out.dir.clone(),
        steps_this_run: sim.state.step - first_step,
        resumed_from,
        checkpoint: latest.or_else(|| out.latest_checkpoint().cloned()),
        warnings: out.warnings().to_vec(),
    };
    out.release_room();
    out.write_summary(sim, &outcome)?;
    Ok(outcome)
}

/// What the loop does after every step: the outputs due (a periodic checkpoint among them),
/// the progress; a steady flow ends the run.
fn after_step<'a>(
    out: &'a mut Outputs,
    progress: &'a mut dyn FnMut(&Progress),
    start: Instant,
    end: f64,
) -> impl FnMut(&mut Simulation, &StepInfo) -> Result<Flow, EfsiError> + 'a {
    move |sim: &mut Simulation, step: &StepInfo| {
        let finished = due(sim.state.t, end) || sim.is_steady();
        out.emit(sim, finished)?;
        progress(&Progress {
            t: sim.state.t,
            end,
            step: sim.state.step,
            dt: step.dt,
            wall: start.elapsed().as_secs_f64(),
        });
        Ok(if sim.is_steady() {
            Flow::Stop
        } else {
            Flow::Continue
        })
    }
}

/// The time the loop advances to next: the next output event after `t`, or after a sliver
/// past `t` when that event is already due (the outputs at `t` were written).
fn next_stop(out: &Outputs, t: f64, end: f64) -> f64 {
    let until = out.next_event(t);
    if due(t, until) {
        end.min(out.next_event(t + 1e-9 * end))
    } else {
        until
    }
}

/// An output or a checkpoint could not be written after a good step (a full disk or a
/// file-size limit, most likely): free the room kept for this moment, put the simulation back
/// to the start of that step, `good` ([`Simulation::rewind`]), and save it, whose outputs a
/// resume writes again. Returns the error to report: [`EfsiError::Saved`] when the checkpoint
/// was written, `error` itself otherwise.
fn save_before_failed_output(
    sim: &mut Simulation,
    out: &mut Outputs,
    law: &Option<LawIdentity>,
    good: Option<&StepStart>,
    error: EfsiError,
) -> EfsiError {
    out.release_room();
    let Some(good) = good else {
        return error;
    };
    if sim.rewind(good).is_err() {
        return error;
    }
    let good = sim.snapshot();
    let (step, t) = (good.step(), good.t());
    match save_checkpoint(sim, law, out.state_before_emit(), good, &out.dir) {
        Ok(checkpoint) => EfsiError::Saved {
            error: Box::new(error),
            step,
            t,
            vtk: None,
            checkpoint,
        },
        Err(_) => error,
    }
}

/// The run failed with `error`: record it in `run.json` (as far as that can still be written)
/// and return it.
fn failed(
    sim: &Simulation,
    out: &mut Outputs,
    start: Instant,
    first_step: u64,
    error: EfsiError,
) -> EfsiError {
    out.release_room();
    let stop = serde_json::json!({ "Failed": { "error": error.to_string(), "exit_code": error.exit_code() } });
    let _ = out.write_run_json(
        sim,
        stop,
        sim.state.step.saturating_sub(first_step),
        None,
        start.elapsed().as_secs_f64(),
    );
    error
}

/// A step failed with `error`: write the last good state `good` as VTK (when the scene writes
/// VTK) and as the checkpoint, and return the error with where they went. If saving fails too,
/// the original error is returned.
fn save_failure(
    sim: &Simulation,
    out: &mut Outputs,
    law: &Option<LawIdentity>,
    good: efsi_core::Snapshot,
    error: EfsiError,
) -> EfsiError {
    let (step, t) = (good.step(), good.t());
    let state = out.state();
    let vtk = match out.write_last_good(sim, &good.state) {
        Ok(p) => p,
        Err(_) => return error,
    };
    match save_checkpoint(sim, law, state, good, &out.dir) {
        Ok(checkpoint) => EfsiError::Saved {
            error: Box::new(error),
            step,
            t,
            vtk,
            checkpoint,
        },
        Err(_) => error,
    }
}
