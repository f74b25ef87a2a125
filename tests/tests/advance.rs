//! `Simulation::advance_to`: landing on targets, refused targets, the stop flag, the step
//! budget, the per-step hook, and the rollback of a failed step.

use efsi_core::scene::Options;
use efsi_core::schedule::{FieldId, Phase, Stage, StagePlugin, VELOCITY};
use efsi_core::{
    Advance, AdvanceError, Advanced, BoundarySet, EfsiError, Flow, Grid, Rollback, Scene,
    Simulation, Snapshot, StageError, StageStats, State, StepContext, StepInfo, StepStart,
};
use efsi_tests::{sim, sim_with};
use std::sync::atomic::{AtomicUsize, Ordering};

const CAVITY: &str = r#"Scene(
    name: "cavity",
    domain: (x: (0.0, 1.0), y: (0.0, 1.0)),
    grid: (nx: 12, ny: 12),
    time: (end: 1.0, cfl: 0.4),
    fluid: (density: 1.0, viscosity: 0.01),
    boundaries: (x_min: NoSlip, x_max: NoSlip, y_min: NoSlip, y_max: MovingWall(speed: 1.0)),
)"#;

/// Every array of the state, bit for bit.
fn same_state(a: &State, b: &State) -> bool {
    let (x, y) = (a.arrays(), b.arrays());
    a.t.to_bits() == b.t.to_bits()
        && a.step == b.step
        && x.len() == y.len()
        && x.iter().zip(&y).all(|((n, f), (m, g))| {
            n == m
                && f.data()
                    .iter()
                    .zip(g.data())
                    .all(|(p, q)| p.to_bits() == q.to_bits())
        })
}

#[test]
fn lands_exactly_on_each_target_with_the_steps_of_the_plain_loop() {
    let mut a = sim(CAVITY);
    let mut b = sim(CAVITY);
    for k in 1..=5 {
        let target = 0.03 * k as f64;
        assert_eq!(
            a.advance_to(target, Advance::default()).unwrap(),
            Advanced::Reached
        );
        assert_eq!(a.state.t, target);
        // The loop every driver used to write by hand.
        while !efsi_core::due(b.state.t, target) {
            let dt = b.next_dt(target).unwrap();
            b.step(dt).unwrap();
            b.snap_time(target);
        }
        assert!(same_state(&a.state, &b.state), "target {target}");
    }
    // Already there: no step.
    let steps = a.state.step;
    a.advance_to(a.state.t, Advance::default()).unwrap();
    assert_eq!(a.state.step, steps);
}

#[test]
fn targets_not_finite_or_behind_are_refused_and_nothing_changes() {
    let mut s = sim(CAVITY);
    s.advance_to(0.05, Advance::default()).unwrap();
    let before = s.snapshot();
    for target in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY, 0.01] {
        let e = s.advance_to(target, Advance::default()).unwrap_err();
        let AdvanceError::Refused(e) = e else {
            panic!("{target}: {e}")
        };
        let text = e.to_string();
        assert!(text.contains("cannot advance to t ="), "{text}");
        assert!(
            text.contains(if target.is_finite() {
                "before the simulation's time"
            } else {
                "not a finite time"
            }),
            "{text}"
        );
        assert_eq!(e.exit_code(), 2);
        assert!(same_state(&s.state, &before.state));
    }
}

#[test]
fn the_stop_flag_ends_the_call_at_a_step_boundary() {
    let mut s = sim(CAVITY);
    let flag = AtomicUsize::new(0);
    // Raised by the hook after the second step: the call returns before the third.
    let mut hook = |_: &mut Simulation, step: &StepInfo| {
        if step.steps == 2 {
            flag.store(15, Ordering::SeqCst);
        }
        Ok(Flow::Continue)
    };
    let control = Advance {
        stop: Some(&flag),
        on_step: Some(&mut hook),
        ..Advance::default()
    };
    assert_eq!(
        s.advance_to(0.5, control).unwrap(),
        Advanced::Stopped { signal: 15 }
    );
    assert_eq!(s.state.step, 2);
    // Still raised: the next call takes no step.
    let control = Advance {
        stop: Some(&flag),
        ..Advance::default()
    };
    assert_eq!(
        s.advance_to(0.5, control).unwrap(),
        Advanced::Stopped { signal: 15 }
    );
    assert_eq!(s.state.step, 2);
}

#[test]
fn the_step_budget_is_a_clear_error_at_a_step_boundary() {
    let mut s = sim(CAVITY);
    let control = Advance {
        max_steps: Some(3),
        ..Advance::default()
    };
    let e = s.advance_to(0.9, control).unwrap_err();
    let AdvanceError::Failed {
        error: e @ EfsiError::StepBudget { .. },
        good: true,
    } = e
    else {
        panic!("{e}")
    };
    assert_eq!(s.state.step, 3);
    let text = e.to_string();
    assert!(
        text.contains("3 solver steps") && text.contains("short of the target t = 9.000000e-1"),
        "{text}"
    );
    assert_eq!(e.exit_code(), 3);
    // A budget that suffices changes nothing.
    let mut t = sim(CAVITY);
    let control = Advance {
        max_steps: Some(1000),
        ..Advance::default()
    };
    assert_eq!(t.advance_to(0.9, control).unwrap(), Advanced::Reached);
}

#[test]
fn the_hook_sees_every_step_and_can_halt() {
    let mut s = sim(CAVITY);
    let mut seen = Vec::new();
    let mut hook = |sim: &mut Simulation, step: &StepInfo| {
        seen.push((sim.state.step, step.dt, step.target));
        Ok(if sim.state.step == 4 {
            Flow::Stop
        } else {
            Flow::Continue
        })
    };
    let control = Advance {
        on_step: Some(&mut hook),
        ..Advance::default()
    };
    assert_eq!(s.advance_to(0.5, control).unwrap(), Advanced::Halted);
    assert_eq!(seen.len(), 4);
    assert!(
        seen.iter().enumerate().all(|(k, (step, dt, target))| {
            *step == k as u64 + 1 && *dt > 0.0 && *target == 0.5
        })
    );
    // A hook's error comes back as such.
    let mut failing =
        |_: &mut Simulation, _: &StepInfo| Err(EfsiError::io("x", std::io::Error::other("full")));
    let control = Advance {
        on_step: Some(&mut failing),
        ..Advance::default()
    };
    assert!(matches!(
        s.advance_to(0.5, control),
        Err(AdvanceError::Hook(EfsiError::Io { .. }))
    ));
}

/// A stage that scribbles over the velocity and fails in its step `fail_at`.
struct Saboteur {
    fail_at: u64,
}

struct SaboteurStage {
    fail_at: u64,
}

impl Stage for SaboteurStage {
    fn run(&mut self, ctx: &StepContext, state: &mut State) -> Result<StageStats, StageError> {
        if ctx.step == self.fail_at {
            state.u.fill(1e3);
            state.p.fill(f64::NAN);
            return Err(StageError {
                stage: "saboteur".into(),
                message: "failed on purpose".into(),
            });
        }
        Ok(StageStats::default())
    }
}

impl StagePlugin for Saboteur {
    fn name(&self) -> &'static str {
        "saboteur"
    }
    fn phase(&self) -> Phase {
        Phase::Interface
    }
    fn reads(&self) -> &'static [FieldId] {
        &VELOCITY
    }
    fn writes(&self) -> &'static [FieldId] {
        &[FieldId::VelocityX, FieldId::Pressure]
    }
    fn needed(&self, _: &Scene, _: &Options) -> bool {
        true
    }
    fn build(
        &self,
        _: &Scene,
        _: &Options,
        _: &Grid,
        _: &BoundarySet,
        _: &mut efsi_core::Resources,
    ) -> Result<Box<dyn Stage>, String> {
        Ok(Box::new(SaboteurStage {
            fail_at: self.fail_at,
        }))
    }
}

#[test]
fn a_failed_step_is_rolled_back_to_the_step_or_the_call_start() {
    let saboteur = Saboteur { fail_at: 5 };
    let mut plugins = efsi_stages::builtin();
    plugins.push(&saboteur);
    let build = || sim_with(CAVITY, &plugins).unwrap();

    // To the start of the failed step.
    let mut s = build();
    let mut reference = build();
    let mut slot: Option<StepStart> = None;
    let control = Advance {
        rollback: Rollback::Step(&mut slot),
        ..Advance::default()
    };
    let e = s.advance_to(0.5, control).unwrap_err();
    let AdvanceError::Failed { error, good: true } = e else {
        panic!("{e}")
    };
    assert!(error.to_string().contains("failed on purpose"), "{error}");
    assert_eq!(s.state.step, 5);
    for _ in 0..5 {
        let dt = reference.next_dt(0.5).unwrap();
        reference.step(dt).unwrap();
        reference.snap_time(0.5);
    }
    assert!(same_state(&s.state, &reference.state));

    // To the start of the call.
    let mut s = build();
    s.advance_to(0.02, Advance::default()).unwrap();
    let start = s.snapshot();
    let mut slot: Option<Snapshot> = None;
    let control = Advance {
        rollback: Rollback::Call(&mut slot),
        ..Advance::default()
    };
    let e = s.advance_to(1.0, control).unwrap_err();
    assert!(matches!(e, AdvanceError::Failed { good: true, .. }), "{e}");
    assert!(same_state(&s.state, &start.state));

    // Without a rollback the state is where the stage left it, and said so.
    let mut s = build();
    let e = s.advance_to(0.5, Advance::default()).unwrap_err();
    assert!(matches!(e, AdvanceError::Failed { good: false, .. }), "{e}");
    assert!(s.state.p.data().iter().all(|p| p.is_nan()));
}
