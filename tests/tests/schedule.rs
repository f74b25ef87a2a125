//! The scheduler: pipelines assembled from the scene with only the stages it needs, fields
//! allocated only when declared, and declarations checked at build time.

use efsi_core::scene::Options;
use efsi_core::schedule::{FieldId, Phase, ScheduleError, Stage, StagePlugin};
use efsi_core::{BoundarySet, EfsiError, Grid, Scene};
use efsi_tests::{sim, sim_with};

fn cavity(extra: &str) -> String {
    format!(
        r#"Scene(
        name: "cavity",
        domain: (x: (0.0, 1.0), y: (0.0, 1.0)),
        grid: (nx: 8, ny: 8),
        time: (end: 1.0, dt_max: 0.01),
        fluid: (density: 1.0, viscosity: 0.01),
        boundaries: (x_min: NoSlip, x_max: NoSlip, y_min: NoSlip, y_max: MovingWall(speed: 1.0)),
        {extra}
    )"#
    )
}

#[test]
fn cavity_schedules_exactly_advection_predictor_viscous_projection() {
    let s = sim(&cavity(""));
    assert_eq!(
        s.pipeline().stage_names(),
        ["advection", "pressure_predictor", "viscous", "projection"]
    );
    assert!(s.state.phi.is_none(), "no solid: no solid-fraction storage");
    assert!(!s.pipeline().fields().contains(&FieldId::SolidFraction));
    let printed = s.pipeline().to_string();
    assert!(
        printed.contains("advection")
            && printed.contains("projection")
            && !printed.contains("body_force")
    );
}

#[test]
fn stokes_scene_omits_advection_and_gravity_adds_body_force() {
    let s = sim(&cavity("physics: (advection: false),"));
    assert_eq!(
        s.pipeline().stage_names(),
        ["pressure_predictor", "viscous", "projection"]
    );
    let s = sim(&cavity("gravity: (0.0, -9.81),"));
    assert_eq!(
        s.pipeline().stage_names(),
        [
            "advection",
            "body_force",
            "pressure_predictor",
            "viscous",
            "projection"
        ]
    );
    // The seed's non-incremental projection has no predictor.
    let s = sim(&cavity("numerics: (projection: (incremental: false)),"));
    assert_eq!(
        s.pipeline().stage_names(),
        ["advection", "viscous", "projection"]
    );
}

struct Dummy {
    name: &'static str,
    reads: &'static [FieldId],
    writes: &'static [FieldId],
    after: &'static [&'static str],
    /// A limit on Δt and its lift ([`LimitStage`]); none: a stage that does nothing.
    limit: Option<(f64, Option<(f64, f64)>)>,
}
struct Noop;
impl Stage for Noop {
    fn run(
        &mut self,
        _: &efsi_core::StepContext,
        _: &mut efsi_core::State,
    ) -> Result<efsi_core::StageStats, efsi_core::StageError> {
        Ok(Default::default())
    }
}
impl StagePlugin for Dummy {
    fn name(&self) -> &'static str {
        self.name
    }
    fn phase(&self) -> Phase {
        Phase::Interface
    }
    fn reads(&self) -> &'static [FieldId] {
        self.reads
    }
    fn writes(&self) -> &'static [FieldId] {
        self.writes
    }
    fn after(&self) -> &'static [&'static str] {
        self.after
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
        Ok(match self.limit {
            Some((dt, lift)) => Box::new(LimitStage(dt, lift)),
            None => Box::new(Noop),
        })
    }
}

#[test]
fn reading_an_unprovided_field_is_refused_at_build() {
    let reader = Dummy {
        name: "reader",
        reads: &[FieldId::SolidFraction],
        writes: &[],
        after: &[],
        limit: None,
    };
    match sim_with(&cavity(""), &[&reader]) {
        Err(EfsiError::Schedule(ScheduleError::MissingField { stage, field })) => {
            assert_eq!((stage.as_str(), field), ("reader", "solid_fraction"));
        }
        other => panic!("expected MissingField, got {:?}", other.err()),
    }
}

#[test]
fn unordered_writers_of_one_field_are_ambiguous_and_after_resolves_it() {
    let a = Dummy {
        name: "a",
        reads: &[],
        writes: &[FieldId::SolidFraction],
        after: &[],
        limit: None,
    };
    let b = Dummy {
        name: "b",
        reads: &[FieldId::SolidFraction],
        writes: &[],
        after: &[],
        limit: None,
    };
    let err = sim_with(&cavity(""), &[&a, &b]).err().expect("ambiguous");
    assert!(
        err.to_string()
            .contains("neither is declared after the other"),
        "{err}"
    );
    let b2 = Dummy {
        name: "b",
        reads: &[FieldId::SolidFraction],
        writes: &[],
        after: &["a"],
        limit: None,
    };
    let s = sim_with(&cavity(""), &[&b2, &a]).unwrap();
    assert_eq!(
        s.pipeline().stage_names(),
        ["a", "b"],
        "order is data, not registration order"
    );
    assert!(s.state.phi.is_some(), "a declared field is allocated");
}

/// A stage with a fixed limit on Δt that it lifts to `lifted` where the others allow at least
/// `gain` times its own (`(dt, Some((gain, lifted)))`).
struct LimitStage(f64, Option<(f64, f64)>);
impl Stage for LimitStage {
    fn run(
        &mut self,
        _: &efsi_core::StepContext,
        _: &mut efsi_core::State,
    ) -> Result<efsi_core::StageStats, efsi_core::StageError> {
        Ok(Default::default())
    }
    fn max_dt(&self, _: &Grid, _: &efsi_core::State, _: f64) -> Option<f64> {
        Some(self.0)
    }
    fn lift_dt(
        &self,
        _: &Grid,
        _: &efsi_core::State,
        own: f64,
        others: Option<f64>,
    ) -> Option<f64> {
        let (gain, lifted) = self.1?;
        others.is_none_or(|o| o >= gain * own).then_some(lifted)
    }
}
/// The limiting stage may lift its limit (`Stage::lift_dt`, the elastic stage's `Auto`
/// coupling): only where the next smallest limit leaves room for the gain it asks, and never
/// above that next limit; a stage that is not the smallest is not asked.
#[test]
fn the_limiting_stage_may_lift_its_limit_up_to_the_next_one() {
    let cases = [
        // (liftable stage's dt, its lift (gain, lifted), other stage's dt) → (name, Δt)
        (0.1, (1.5, 0.5), 1.0, ("liftable", 0.5)),
        (0.1, (1.5, 0.5), 0.12, ("liftable", 0.1)),
        (0.1, (1.5, 5.0), 1.0, ("other", 1.0)),
        (0.1, (1.5, 0.5), 0.05, ("other", 0.05)),
    ];
    for (dt, lift, other, expected) in cases {
        let a = Dummy {
            name: "liftable",
            reads: &[],
            writes: &[],
            after: &[],
            limit: Some((dt, Some(lift))),
        };
        let b = Dummy {
            name: "other",
            reads: &[],
            writes: &[],
            after: &[],
            limit: Some((other, None)),
        };
        // A fluid at rest: the built-in stages set no limit.
        let s = sim_with(
            &cavity("").replace("MovingWall(speed: 1.0)", "NoSlip"),
            &[&a, &b],
        )
        .unwrap();
        let got = s.pipeline().limiting_stage(&s.grid, &s.state, 0.5);
        assert_eq!(got, Some(expected), "{dt} lifting {lift:?} beside {other}");
    }
}
