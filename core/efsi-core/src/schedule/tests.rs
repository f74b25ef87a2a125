use super::Resources;

/// The first maker of a type's value runs, later ones do not; a failed maker keeps
/// nothing, so the next stage to ask makes it again (and reports its own error).
#[test]
fn resources_make_each_value_once_and_keep_no_failure() {
    let mut r = Resources::default();
    let mut calls = 0;
    let e = r
        .get_or_try_insert_with::<u32, String>(|| {
            calls += 1;
            Err("no law".into())
        })
        .unwrap_err();
    assert_eq!(e, "no law");
    assert!(r.get::<u32>().is_none());
    for want in [7, 7] {
        let got = *r
            .get_or_try_insert_with::<u32, String>(|| {
                calls += 1;
                Ok(7)
            })
            .unwrap();
        assert_eq!(got, want);
    }
    assert_eq!(calls, 2, "made once after the failure, then taken");
    // One value per type: another type is made separately.
    assert_eq!(
        r.get_or_try_insert_with::<&str, ()>(|| Ok("law")),
        Ok(&"law")
    );
    assert_eq!(r.get::<u32>(), Some(&7));
}

mod sub_steps {
    use super::super::{
        FieldId, Phase, Pipeline, Resources, Stage, StageError, StagePlugin, StageStats,
        StepContext, SubStep,
    };
    use crate::bc::BoundarySet;
    use crate::grid::Grid;
    use crate::scene::{Options, Scene};
    use crate::state::State;
    use std::path::Path;

    const SCENE: &str = r#"Scene(
        name: "t",
        domain: (x: (0.0, 1.0), y: (0.0, 1.0)),
        grid: (nx: 4, ny: 4),
        time: (end: 1.0),
        fluid: (density: 1.0, viscosity: 0.01),
        boundaries: (x_min: NoSlip, x_max: NoSlip, y_min: NoSlip, y_max: NoSlip),
    )"#;

    /// Two sub-steps: the first adds 1 to every u, the second doubles it if the first said so
    /// (what one sub-step decides for the next stays in the stage), else sets it to 5; the
    /// second projects.
    struct TwoSteps;
    struct TwoStepsStage {
        double: bool,
    }

    const SUBS: [SubStep; 2] = [
        SubStep {
            name: "add",
            writes: &[FieldId::VelocityX],
            projects: false,
        },
        SubStep {
            name: "double",
            writes: &[FieldId::VelocityX],
            projects: true,
        },
    ];

    impl StagePlugin for TwoSteps {
        fn name(&self) -> &'static str {
            "two"
        }
        fn phase(&self) -> Phase {
            Phase::Elastic
        }
        fn reads(&self) -> &'static [FieldId] {
            &[FieldId::VelocityX]
        }
        fn writes(&self) -> &'static [FieldId] {
            &[FieldId::VelocityX]
        }
        fn sub_steps(&self) -> &'static [SubStep] {
            &SUBS
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
            _: &mut Resources,
        ) -> Result<Box<dyn Stage>, String> {
            Ok(Box::new(TwoStepsStage { double: false }))
        }
    }

    impl Stage for TwoStepsStage {
        fn run(&mut self, _: &StepContext, _: &mut State) -> Result<StageStats, StageError> {
            unreachable!("a stage with sub-steps is run by them")
        }
        fn run_sub(
            &mut self,
            k: usize,
            _: &StepContext,
            state: &mut State,
        ) -> Result<StageStats, StageError> {
            if k == 0 {
                state.u.data_mut().iter_mut().for_each(|u| *u += 1.0);
                self.double = true;
            } else if self.double {
                state.u.data_mut().iter_mut().for_each(|u| *u *= 2.0);
            } else {
                state.u.data_mut().iter_mut().for_each(|u| *u = 5.0);
            }
            Ok(StageStats::default())
        }
    }

    /// A stage named as the other's second sub-step, never needed with it.
    struct Double;
    impl StagePlugin for Double {
        fn name(&self) -> &'static str {
            "double"
        }
        fn phase(&self) -> Phase {
            Phase::Projection
        }
        fn reads(&self) -> &'static [FieldId] {
            &[]
        }
        fn writes(&self) -> &'static [FieldId] {
            &[]
        }
        fn needed(&self, _: &Scene, _: &Options) -> bool {
            false
        }
        fn build(
            &self,
            _: &Scene,
            _: &Options,
            _: &Grid,
            _: &BoundarySet,
            _: &mut Resources,
        ) -> Result<Box<dyn Stage>, String> {
            Err("never built".into())
        }
    }

    fn build(plugins: &[&dyn StagePlugin]) -> (Pipeline, Grid, BoundarySet, State) {
        let mut scene = Scene::from_str_at(SCENE, Path::new("t.ron")).unwrap();
        let options = scene.check_options(Path::new("t.ron"), plugins).unwrap();
        let s = &scene;
        let grid = Grid::new(s.geometry, s.grid.nx, s.grid.ny, s.domain.x, s.domain.y);
        let bc = BoundarySet::new(&s.boundaries, &grid);
        let p = Pipeline::build(s, &options, &grid, &bc, plugins).unwrap_or_else(|e| panic!("{e}"));
        let state = State::new(&grid, 1.0, 0.01, p.fields());
        (p, grid, bc, state)
    }

    #[test]
    fn sub_steps_run_in_order_and_are_timed_and_named_in_place_of_their_stage() {
        let (mut p, grid, bc, mut state) = build(&[&TwoSteps, &Double]);
        assert_eq!(p.stage_names(), ["add", "double"]);
        let ctx = StepContext {
            grid: &grid,
            bc: &bc,
            t: 0.0,
            dt: 0.1,
            step: 0,
            start_velocity: None,
        };
        p.run_step(&ctx, &mut state).unwrap();
        p.run_step(&ctx, &mut state).unwrap();
        // ((0 + 1)·2 + 1)·2 = 6 on an interior face (the walls' ghosts are refreshed).
        assert_eq!(state.u[(2, 2)], 6.0);
        let t = p.timings();
        let names: Vec<_> = t.iter().map(|s| (s.name, s.calls)).collect();
        assert_eq!(names, [("add", 2), ("double", 2)]);
        let printed = p.to_string();
        assert!(printed.contains(" 1. two "), "{printed}");
        assert!(printed.contains("a. add"), "{printed}");
        assert!(printed.contains("b. double"), "{printed}");
        // One snapshot entry for the stage.
        let saved = p.save_stages();
        assert_eq!(saved, [("two".to_string(), Vec::<f64>::new())]);
    }

    #[test]
    fn a_snapshot_of_the_sub_steps_as_stages_restores_unless_one_holds_data() {
        let (mut p, ..) = build(&[&TwoSteps]);
        let old = |a: Vec<f64>| vec![("add".to_string(), a), ("double".to_string(), vec![])];
        p.restore_stages(&old(vec![])).unwrap();
        let e = p.restore_stages(&old(vec![1.0])).unwrap_err();
        assert!(e.message.contains("[add, double]"), "{}", e.message);
        let e = p
            .restore_stages(&[("add".to_string(), vec![])])
            .unwrap_err();
        assert!(
            e.message.contains("this pipeline has [two]"),
            "{}",
            e.message
        );
    }

    #[test]
    fn the_initial_projection_runs_the_projecting_sub_step_alone() {
        let (mut p, grid, bc, mut state) = build(&[&TwoSteps]);
        state.u.data_mut().iter_mut().for_each(|u| *u = 1.0);
        p.initialize(&grid, &bc, &mut state).unwrap();
        // `double` ran alone: `add` never said to double, so it set u to 5.
        assert_eq!(state.u[(2, 2)], 5.0);
        assert_eq!(
            p.timings()[1].calls,
            0,
            "the initial projection is not timed"
        );
    }
}

mod geometry_support {
    use super::super::{
        FieldId, Phase, Pipeline, Resources, ScheduleError, Stage, StageError, StagePlugin,
        StageStats, StepContext,
    };
    use crate::bc::BoundarySet;
    use crate::grid::{Geometry, Grid};
    use crate::scene::{Options, Scene};
    use crate::state::State;
    use std::path::Path;

    const CUBE: &str = r#"Scene(
        name: "t",
        geometry: Cartesian3D,
        domain: (x: (0.0, 1.0), y: (0.0, 1.0), z: (0.0, 0.75)),
        grid: (nx: 4, ny: 4, nz: 3),
        time: (end: 1.0),
        fluid: (density: 1.0, viscosity: 0.01),
        boundaries: (x_min: NoSlip, x_max: NoSlip, y_min: NoSlip, y_max: NoSlip,
                     z_min: Periodic, z_max: Periodic),
    )"#;

    /// A stage that does nothing, with or without three-dimensional support.
    struct Plain(&'static str, bool);
    struct Nothing;

    impl StagePlugin for Plain {
        fn name(&self) -> &'static str {
            self.0
        }
        fn phase(&self) -> Phase {
            Phase::Elastic
        }
        fn reads(&self) -> &'static [FieldId] {
            &[]
        }
        fn writes(&self) -> &'static [FieldId] {
            &[]
        }
        fn supports(&self, geometry: Geometry) -> bool {
            self.1 || geometry != Geometry::Cartesian3D
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
            _: &mut Resources,
        ) -> Result<Box<dyn Stage>, String> {
            Ok(Box::new(Nothing))
        }
    }

    impl Stage for Nothing {
        fn run(&mut self, _: &StepContext, _: &mut State) -> Result<StageStats, StageError> {
            Ok(StageStats::default())
        }
    }

    fn build(text: &str, plugins: &[&dyn StagePlugin]) -> Result<Pipeline, ScheduleError> {
        let mut scene = Scene::from_str_at(text, Path::new("t.ron")).unwrap();
        let options = scene.check_options(Path::new("t.ron"), plugins).unwrap();
        let grid = scene.build_grid();
        let bc = BoundarySet::new(&scene.boundaries, &grid);
        Pipeline::build(&scene, &options, &grid, &bc, plugins)
    }

    #[test]
    fn a_three_dimensional_scene_is_refused_naming_every_stage_without_support() {
        let e = build(
            CUBE,
            &[
                &Plain("flat", false),
                &Plain("cube", true),
                &Plain("other", false),
            ],
        )
        .err()
        .expect("refused");
        assert!(matches!(
            &e,
            ScheduleError::Unsupported { stages, geometry: Geometry::Cartesian3D, cells: [4, 4, 3] }
                if stages == &["flat", "other"]
        ));
        assert_eq!(
            e.to_string(),
            "the Cartesian3D scene (4×4×3 cells) needs stages that do not support Cartesian3D \
             geometry: `flat`, `other`"
        );
        let p = build(CUBE, &[&Plain("cube", true)]).unwrap();
        assert_eq!(p.stage_names(), ["cube"]);
    }

    #[test]
    fn two_dimensional_scenes_run_every_stage_by_default() {
        let planar = CUBE
            .replace("geometry: Cartesian3D,", "")
            .replace(", z: (0.0, 0.75)", "")
            .replace(", nz: 3", "")
            .replace(
                ",\n                     z_min: Periodic, z_max: Periodic",
                "",
            );
        let p = build(&planar, &[&Plain("flat", false), &Plain("cube", true)]).unwrap();
        assert_eq!(p.stage_names(), ["cube", "flat"]);
    }
}
