//! A user's own stage with its own field and that field's outputs, defined entirely in this
//! file: adding a field, its VTK array and its probe touches no file of efsi (the contract of
//! `efsi_core::schedule`: `FieldId::Stage`, `StateResource`, `StagePlugin::outputs`). The
//! stage keeps the age of the fluid, `∂a/∂t = 1` in every cell, in a field of its own; the
//! run writes it as the VTK array `age`, samples it in a point probe and a line profile, adds
//! the probe quantity `mean_age`, carries the field through checkpoints, and refuses outputs
//! that no scheduled stage provides, naming the ones there are.

use efsi_core::scene::Options;
use efsi_core::{
    BoundarySet, Field, FieldId, Grid, OutputDecl, OutputKind, Phase, Scene, Simulation, Stage,
    StageError, StagePlugin, StageStats, State, StateResource, StepContext,
};
use efsi_run::SceneOverrides;
use efsi_run::output::read::{read_pvd, read_vtr};
use efsi_run::run::{RunOptions, StopReason, resume, run_with};
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::sync::atomic::{AtomicUsize, Ordering};

/// The field the stage owns.
const AGE: FieldId = FieldId::Stage("age");

/// The stage's data in the state: the age at the cell centres.
#[derive(Clone, Debug)]
struct Age(Field);

impl StateResource for Age {
    fn arrays(&self) -> Vec<(String, &Field)> {
        vec![("age".into(), &self.0)]
    }
    fn arrays_mut(&mut self) -> Vec<(String, &mut Field)> {
        vec![("age".into(), &mut self.0)]
    }
    fn clone_box(&self) -> Box<dyn StateResource> {
        Box::new(self.clone())
    }
    fn copy_from(&mut self, other: &dyn StateResource) -> bool {
        match (other as &dyn std::any::Any).downcast_ref::<Age>() {
            Some(o) if o.0.data().len() == self.0.data().len() => {
                self.0.copy_from(&o.0);
                true
            }
            _ => false,
        }
    }
}

/// The mean age over the cells.
fn mean_age(grid: &Grid, state: &State) -> f64 {
    let Some(Age(a)) = state.resources.get::<Age>() else {
        return f64::NAN;
    };
    let cells = (0..grid.ny as isize).flat_map(|j| (0..grid.nx as isize).map(move |i| (i, j)));
    cells.map(|c| a[c]).sum::<f64>() / (grid.nx * grid.ny) as f64
}

const OUTPUTS: &[OutputDecl] = &[
    OutputDecl {
        name: "age",
        meaning: "time since the start of the run",
        unit: "s",
        kind: OutputKind::Field(|state| state.resources.get::<Age>().map(|a| &a.0)),
    },
    OutputDecl {
        name: "mean_age",
        meaning: "the cells' mean age",
        unit: "s",
        kind: OutputKind::Quantity(mean_age),
    },
];

/// The plugin, by name, after the stages named (a second one shows that two stages cannot
/// declare one output).
struct Aging(&'static str, &'static [&'static str]);

impl StagePlugin for Aging {
    fn name(&self) -> &'static str {
        self.0
    }
    fn after(&self) -> &'static [&'static str] {
        self.1
    }
    fn phase(&self) -> Phase {
        Phase::Interface
    }
    fn reads(&self) -> &'static [FieldId] {
        &[AGE]
    }
    fn writes(&self) -> &'static [FieldId] {
        &[AGE]
    }
    fn needed(&self, _scene: &Scene, _options: &Options) -> bool {
        true
    }
    fn outputs(&self) -> &'static [OutputDecl] {
        OUTPUTS
    }
    fn build(
        &self,
        _scene: &Scene,
        _options: &Options,
        _grid: &Grid,
        _bc: &BoundarySet,
        _shared: &mut efsi_core::Resources,
    ) -> Result<Box<dyn Stage>, String> {
        Ok(Box::new(AgingStage))
    }
}

struct AgingStage;

impl Stage for AgingStage {
    fn init_state(&self, grid: &Grid, state: &mut State) {
        state.resources.insert(Age(Field::zeros(grid)));
    }
    fn run(&mut self, ctx: &StepContext, state: &mut State) -> Result<StageStats, StageError> {
        let a = state
            .resources
            .get_mut::<Age>()
            .expect("added by init_state");
        // Ghosts included: a point probe near a side interpolates with them.
        a.0.data_mut().iter_mut().for_each(|x| *x += ctx.dt);
        Ok(StageStats::default())
    }
}

fn plugins() -> Vec<&'static dyn StagePlugin> {
    let mut p = efsi_stages::builtin();
    p.push(&Aging("aging", &[]));
    p
}

/// A uniform flow through a periodic box, 1/8 s in steps of 1/64 s (exact in binary).
fn scene_text(output: &str) -> String {
    format!(
        r#"Scene(
    name: "own_field",
    domain: (x: (0.0, 1.0), y: (0.0, 1.0)),
    grid: (nx: 8, ny: 6),
    time: (end: 0.125, fixed_dt: 0.015625),
    fluid: (density: 1.0, viscosity: 0.01),
    initial_velocity: Uniform((1.0, 0.5)),
    boundaries: (x_min: Periodic, x_max: Periodic, y_min: Periodic, y_max: Periodic),
    output: ({output}),
)"#
    )
}

fn scene(output: &str) -> Scene {
    Scene::from_str_at(&scene_text(output), Path::new("own_field.ron"))
        .unwrap_or_else(|e| panic!("{e}"))
}

fn tmp(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("efsi_own_field_{name}_{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    d
}

const OUTPUT: &str = r#"vtk_every: 0.0625, vtk: (fields: ["velocity", "age"]),
        probes: [Quantity("mean_age"), KineticEnergy, Point(name: "age_c", field: "age", at: (0.3, 0.4))],
        profiles: [Line(name: "a", from: (0.0, 0.5), to: (1.0, 0.5), points: 5, fields: ["u", "age"])]"#;

#[test]
fn a_stage_of_ones_own_writes_its_field_to_vtk_and_probes() {
    let dir = tmp("run");
    let mut sim =
        efsi_run::simulation(scene(OUTPUT), Path::new("own_field.ron"), &plugins()).unwrap();
    assert!(sim.pipeline().fields().contains(&AGE));
    let out = run_with(&mut sim, &dir, &RunOptions::default(), &mut |_| {}).unwrap();
    assert_eq!(out.steps, 8);
    // probes.csv: the column named after the quantity, the age equal to the time in every row.
    let csv = std::fs::read_to_string(dir.join("probes.csv")).unwrap();
    let mut lines = csv.lines();
    assert_eq!(lines.next(), Some("t,mean_age,kinetic_energy,age_c"));
    let rows: Vec<Vec<f64>> = lines
        .map(|l| l.split(',').map(|x| x.parse().unwrap()).collect())
        .collect();
    assert_eq!(rows.len(), 9);
    for r in &rows {
        assert_eq!(r[1], r[0], "mean age at t = {}", r[0]);
        assert_eq!(r[3], r[0], "sampled age at t = {}", r[0]);
    }
    // The profile at the end samples it along the line.
    let profiles: Vec<_> = std::fs::read_dir(dir.join("profiles")).unwrap().collect();
    assert_eq!(profiles.len(), 1);
    let text = std::fs::read_to_string(profiles[0].as_ref().unwrap().path()).unwrap();
    let mut lines = text.lines();
    assert_eq!(lines.next(), Some("s,x,y,u,age"));
    for l in lines {
        let age: f64 = l.rsplit(',').next().unwrap().parse().unwrap();
        assert_eq!(age, 0.125, "{l}");
    }
    // The VTK files: the array asked for, one component, the age in every cell.
    let files = read_pvd(&dir.join("fields.pvd")).unwrap();
    assert_eq!(files.len(), 3);
    for (t, file) in files {
        let data = read_vtr(&dir.join(file)).unwrap();
        let names: Vec<&str> = data.cells.iter().map(|a| a.name.as_str()).collect();
        assert_eq!(names, ["velocity", "age"]);
        let age = data.cell("age").unwrap();
        assert_eq!((age.components, age.values.len()), (1, 48));
        assert!(age.values.iter().all(|&a| a == t), "age at t = {t}");
    }
    // run.json documents the array like the shipped ones.
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("run.json")).unwrap()).unwrap();
    let arrays = &json["vtk"]["arrays"];
    assert_eq!(arrays[1]["name"], "age");
    assert_eq!(arrays[1]["components"], serde_json::json!(["age"]));
    assert_eq!(arrays[1]["unit"], "s");
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn the_field_survives_a_checkpoint_and_a_resume() {
    let dir = tmp("resume");
    std::fs::create_dir_all(&dir).unwrap();
    // A resume reads the scene again from its file.
    let path = dir.join("own_field.ron");
    std::fs::write(&path, scene_text(OUTPUT)).unwrap();
    let load = || efsi_run::simulation(Scene::load(&path).unwrap(), &path, &plugins()).unwrap();
    let mut a = load();
    assert!(a.state.arrays().iter().any(|(n, _)| n == "age"));
    run_with(&mut a, &dir.join("a"), &RunOptions::default(), &mut |_| {}).unwrap();
    let mut b = load();
    let flag = Arc::new(AtomicUsize::new(0));
    let opts = RunOptions {
        stop: Some(flag.clone()),
        ..RunOptions::default()
    };
    let first = run_with(&mut b, &dir.join("b"), &opts, &mut |p| {
        if p.step == 3 {
            flag.store(2, Ordering::SeqCst);
        }
    })
    .unwrap();
    assert_eq!(first.stop, StopReason::Interrupted { signal: 2 });
    drop(b);
    let (b, _) = resume(
        &dir.join("b"),
        &plugins(),
        &RunOptions::default(),
        &mut |_| {},
    )
    .unwrap_or_else(|e| panic!("{e}"));
    let age = |s: &Simulation| s.state.resources.get::<Age>().unwrap().0.data().to_vec();
    assert_eq!(age(&a), age(&b));
    assert_eq!(age(&b)[0], 0.125);
    for f in ["probes.csv", "fields.pvd"] {
        assert_eq!(
            std::fs::read_to_string(dir.join("a").join(f)).unwrap(),
            std::fs::read_to_string(dir.join("b").join(f)).unwrap(),
            "{f}"
        );
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn outputs_no_scheduled_stage_provides_are_refused_naming_the_ones_there_are() {
    let refused = |output: &str, plugins: &[&dyn StagePlugin]| match efsi_run::simulation(
        scene(output),
        Path::new("own_field.ron"),
        plugins,
    ) {
        Ok(_) => panic!("{output}: accepted"),
        Err(e) => e.to_string(),
    };
    // Without the stage, its array and its quantity are unknown.
    let m = refused("vtk: (fields: [\"age\"])", &efsi_stages::builtin());
    assert!(
        m.contains("output.vtk.fields[0]")
            && m.contains("unknown field `age`")
            && m.contains(r#"["velocity", "pressure", "density", "viscosity", "divergence", "solid_fraction"]"#),
        "{m}"
    );
    let m = refused("probes: [Quantity(\"mean_age\")]", &efsi_stages::builtin());
    assert!(
        m.contains("output.probes[0]") && m.contains("unknown quantity `mean_age`"),
        "{m}"
    );
    // Two stages cannot both declare one output.
    let mut twice = plugins();
    twice.push(&Aging("aging_too", &["aging"]));
    let m = refused("", &twice);
    assert!(
        m.contains("stages `aging` and `aging_too` both declare the output `age`"),
        "{m}"
    );
    // With it, a misspelt one is named with the ones its stages provide.
    let m = refused("vtk: (fields: [\"velocity\", \"ages\"])", &plugins());
    assert!(
        m.contains("output.vtk.fields[1]")
            && m.contains("unknown field `ages`")
            && m.contains("\"age\"]"),
        "{m}"
    );
    let m = refused("probes: [Quantity(\"mean\")]", &plugins());
    assert!(
        m.contains("unknown quantity `mean`") && m.contains(r#"["mean_age"]"#),
        "{m}"
    );
    let m = refused(
        r#"profiles: [Line(name: "a", from: (0.0, 0.5), to: (1.0, 0.5), points: 5, fields: ["agee"])]"#,
        &plugins(),
    );
    assert!(
        m.contains("output.profiles[0].fields")
            && m.contains("unknown field `agee`")
            && m.contains(r#""solid_fraction", "age"]"#),
        "{m}"
    );
}
