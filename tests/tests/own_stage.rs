//! A user's own stage with its own `numerics` options, defined entirely in this file: adding a
//! stage and an option touches no file of efsi (the plugin contract of `efsi_core::schedule`
//! and `efsi_core::scene::options`). The stage damps the velocity implicitly,
//! `u ← u / (1 + rate·Δt)`, at a rate its section sets.

use efsi_core::scene::options::check_iterations;
use efsi_core::scene::{Options, OptionsDecl, StageOptions};
use efsi_core::schedule::VELOCITY;
use efsi_core::{
    BoundarySet, FieldId, Grid, Phase, Scene, Stage, StageError, StagePlugin, StageStats, State,
    StepContext,
};
use efsi_run::SceneOverrides;
use serde::{Deserialize, Serialize};
use std::path::Path;

/// `numerics.damping`. Read through [`ReadDamping`], which counts the reads.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(from = "ReadDamping")]
struct DampingOptions {
    rate: f64,
    substeps: usize,
}

/// `numerics.damping` as the scene writes it.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct ReadDamping {
    /// The damping rate (1/s, default 1).
    #[serde(default = "one")]
    rate: f64,
    /// Sub-steps per step (default 1): a second field, to show ranges checked by name.
    #[serde(default = "one_step")]
    substeps: usize,
}

thread_local! {
    /// How many times this thread read a `numerics.damping` section.
    static READS: std::cell::Cell<usize> = const { std::cell::Cell::new(0) };
}

impl From<ReadDamping> for DampingOptions {
    fn from(r: ReadDamping) -> Self {
        READS.with(|n| n.set(n.get() + 1));
        DampingOptions {
            rate: r.rate,
            substeps: r.substeps,
        }
    }
}

fn one() -> f64 {
    1.0
}
fn one_step() -> usize {
    1
}

impl Default for DampingOptions {
    fn default() -> Self {
        DampingOptions {
            rate: one(),
            substeps: one_step(),
        }
    }
}

impl StageOptions for DampingOptions {
    const SECTION: &'static str = "damping";

    fn validate(&self, _scene: &Scene) -> Result<(), (&'static str, String)> {
        if !(self.rate.is_finite() && self.rate >= 0.0) {
            return Err(("rate", format!("must be finite and ≥ 0, got {}", self.rate)));
        }
        check_iterations("substeps", self.substeps)
    }
}

struct Damping;

impl StagePlugin for Damping {
    fn name(&self) -> &'static str {
        "damping"
    }
    fn phase(&self) -> Phase {
        Phase::BodyForce
    }
    fn reads(&self) -> &'static [FieldId] {
        &VELOCITY
    }
    fn writes(&self) -> &'static [FieldId] {
        &VELOCITY
    }
    fn needed(&self, _scene: &Scene, _options: &Options) -> bool {
        true
    }
    fn options(&self) -> Option<OptionsDecl> {
        Some(OptionsDecl::of::<DampingOptions>())
    }
    fn build(
        &self,
        _scene: &Scene,
        options: &Options,
        _grid: &Grid,
        _bc: &BoundarySet,
        _shared: &mut efsi_core::Resources,
    ) -> Result<Box<dyn Stage>, String> {
        let o: &DampingOptions = options.section()?;
        Ok(Box::new(DampingStage(o.clone())))
    }
}

struct DampingStage(DampingOptions);

impl Stage for DampingStage {
    fn run(&mut self, ctx: &StepContext, state: &mut State) -> Result<StageStats, StageError> {
        let h = ctx.dt / self.0.substeps as f64;
        for _ in 0..self.0.substeps {
            let f = 1.0 / (1.0 + self.0.rate * h);
            state.u.data_mut().iter_mut().for_each(|u| *u *= f);
            state.v.data_mut().iter_mut().for_each(|v| *v *= f);
        }
        Ok(StageStats::default())
    }
}

/// A uniform flow through a periodic box: advection and projection keep it uniform, so only
/// the damping changes it.
fn scene(numerics: &str) -> Result<Scene, String> {
    let text = format!(
        r#"Scene(
    name: "own_stage",
    domain: (x: (0.0, 1.0), y: (0.0, 1.0)),
    grid: (nx: 8, ny: 8),
    time: (end: 1.0, fixed_dt: 0.01),
    fluid: (density: 1.0, viscosity: 0.0),
    initial_velocity: Uniform((1.0, 0.5)),
    numerics: {numerics},
    boundaries: (x_min: Periodic, x_max: Periodic, y_min: Periodic, y_max: Periodic),
)"#
    );
    Scene::from_str_at(&text, Path::new("own_stage.ron")).map_err(|e| e.to_string())
}

fn plugins() -> Vec<&'static dyn StagePlugin> {
    let mut p = efsi_stages::builtin();
    p.push(&Damping);
    p
}

#[test]
fn a_stage_of_ones_own_reads_its_own_section() {
    let mut sim = efsi_run::simulation(
        scene("(damping: (rate: 2.0, substeps: 2))").unwrap(),
        Path::new("own_stage.ron"),
        &plugins(),
    )
    .unwrap();
    assert!(sim.pipeline().stage_names().contains(&"damping"));
    for _ in 0..10 {
        sim.step(0.01).unwrap();
    }
    let expect = (1.0f64 + 2.0 * 0.005).powi(-20);
    let (u, v) = (sim.state.u[(3, 4)], sim.state.v[(3, 4)]);
    assert!((u - expect).abs() < 1e-13, "u = {u}, expected {expect}");
    assert!(
        (v - 0.5 * expect).abs() < 1e-13,
        "v = {v}, expected {}",
        0.5 * expect
    );
    // The settings in force are recorded with the scene, defaults and all.
    let recorded: Vec<&str> = sim.scene.numerics.sections().map(|(n, _)| n).collect();
    assert!(recorded.contains(&"damping"), "{recorded:?}");
}

#[test]
fn the_section_is_refused_without_its_stage_and_checked_by_field_with_it() {
    let refused = |numerics: &str, plugins: &[&dyn StagePlugin]| match efsi_run::simulation(
        scene(numerics).unwrap(),
        Path::new("own_stage.ron"),
        plugins,
    ) {
        Ok(_) => panic!("{numerics}: accepted"),
        Err(e) => e.to_string(),
    };
    let m = refused("(damping: (rate: 2.0))", &efsi_stages::builtin());
    assert!(
        m.contains("numerics.damping") && m.contains("no stage has a section `damping`"),
        "{m}"
    );
    let m = refused("(damping: (rate: -1.0))", &plugins());
    assert!(
        m.contains("numerics.damping.rate: must be finite and ≥ 0"),
        "{m}"
    );
    let m = refused("(damping: (substeps: 0))", &plugins());
    assert!(m.contains("numerics.damping.substeps: must be ≥ 1"), "{m}");
    let m = refused("(damping: (rate: 1.0, sub_steps: 2))", &plugins());
    assert!(
        m.contains("numerics.damping") && m.contains("sub_steps"),
        "{m}"
    );
    // An override of the new option is checked and named like any other.
    let mut s = scene("()").unwrap();
    s.set("numerics.damping.rate", -3.0).unwrap();
    let m = match efsi_run::simulation(s, Path::new("own_stage.ron"), &plugins()) {
        Ok(_) => panic!("accepted"),
        Err(e) => e.to_string(),
    };
    assert!(m.contains("set numerics.damping.rate=-3.0"), "{m}");
}

/// A section is read once per build: by the check, into its type, from which the stage is
/// built and the run steps — whatever the stages, the steps and the records read.
#[test]
fn the_section_is_read_once_per_build() {
    READS.with(|n| n.set(0));
    let mut sim = efsi_run::simulation(
        scene("(damping: (rate: 2.0, substeps: 2))").unwrap(),
        Path::new("own_stage.ron"),
        &plugins(),
    )
    .unwrap();
    for _ in 0..3 {
        sim.step(0.01).unwrap();
    }
    assert_eq!(READS.with(|n| n.get()), 1);
    assert_eq!(sim.options().section::<DampingOptions>().unwrap().rate, 2.0);
    // Not in the scene: its defaults, with nothing to read.
    READS.with(|n| n.set(0));
    efsi_run::simulation(scene("()").unwrap(), Path::new("own_stage.ron"), &plugins()).unwrap();
    assert_eq!(READS.with(|n| n.get()), 0);
}
