//! Reliability of a run: snapshots and checkpoints continue a run bit for bit, a resumed run
//! appends to the same outputs without duplicating or losing rows, unreadable checkpoints are
//! refused, and a step that blows up stops the run (exit code 3, naming the stage, field and
//! cell) after saving the last good state as VTK and as a checkpoint.

use efsi_core::{EfsiError, Scene, Simulation};
use efsi_run::SceneOverrides;
use efsi_run::checkpoint::{self, CheckpointFile};
use efsi_run::run::{RunOptions, RunOutcome, StopReason, resume, run_with};
use efsi_tests::run_until;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::sync::atomic::{AtomicUsize, Ordering};

/// A lid-driven cavity with every kind of output and steadiness tracking on.
const CAVITY: &str = r#"Scene(
    name: "cavity",
    domain: (x: (0.0, 1.0), y: (0.0, 1.0)),
    grid: (nx: 16, ny: 16),
    time: (end: 1.0, cfl: 0.5, steady: 1e-12),
    fluid: (density: 1.0, viscosity: 0.01),
    boundaries: (x_min: NoSlip, x_max: NoSlip, y_min: NoSlip, y_max: MovingWall(speed: 1.0)),
    output: (
        vtk_every: 0.25,
        probe_every: 0.05,
        probes: [Point(name: "u_c", field: "u", at: (0.5, 0.5)), KineticEnergy, MaxDivergence],
        profiles: [Line(name: "u", from: (0.5, 0.0), to: (0.5, 1.0), points: 17, fields: ["u", "p"], at: [0.5])],
    ),
)
"#;

/// A hyperelastic disk thrown sideways and falling in a box: advection, body force, viscous,
/// elastic, projection, B update and VOF stages all run.
const DISK: &str = r#"Scene(
    name: "disk",
    domain: (x: (0.0, 1.0), y: (0.0, 1.0)),
    grid: (nx: 16, ny: 16),
    time: (end: 0.15, cfl: 0.4, dt_max: 0.005),
    fluid: (density: 1.0, viscosity: 0.01),
    gravity: (0.0, -9.81),
    solid: (shape: Disk(center: (0.5, 0.6), radius: 0.2), density: 2.0, velocity: (0.5, 0.0),
            law: (name: "neo_hookean", parameters: {"G": 100.0})),
    boundaries: (x_min: NoSlip, x_max: NoSlip, y_min: NoSlip, y_max: NoSlip),
    output: (
        vtk_every: 0.05,
        probe_every: 0.01,
        probes: [KineticEnergy, SolidVolume, SolidCentroid, SolidVelocity],
        profiles: [Line(name: "v", from: (0.5, 0.0), to: (0.5, 1.0), points: 17, fields: ["v", "solid_fraction"])],
    ),
)
"#;

/// A lid-driven cube on a coarse grid: the three velocity components, profiles and VTK in 3-D.
const CUBE: &str = r#"Scene(
    name: "cube",
    geometry: Cartesian3D,
    domain: (x: (0.0, 1.0), y: (0.0, 1.0), z: (0.0, 1.0)),
    grid: (nx: 8, ny: 8, nz: 8),
    time: (end: 0.3, cfl: 0.5),
    fluid: (density: 1.0, viscosity: 0.01),
    boundaries: (x_min: NoSlip, x_max: NoSlip, y_min: NoSlip, y_max: MovingWall(speed: 1.0),
                 z_min: NoSlip, z_max: NoSlip),
    output: (
        vtk_every: 0.1,
        probe_every: 0.02,
        probes: [Point(name: "w_c", field: "w", at: (0.5, 0.5, 0.25)), KineticEnergy, MaxDivergence],
        profiles: [Line(name: "u", from: (0.5, 0.0, 0.5), to: (0.5, 1.0, 0.5), points: 9, fields: ["u", "w"])],
    ),
)
"#;

/// A drop (a solid without a law) falling in a quarter box with two symmetry planes: the VOF
/// stage and the solid probes in 3-D.
const DROP: &str = r#"Scene(
    name: "drop",
    geometry: Cartesian3D,
    domain: (x: (0.0, 1.0), y: (0.0, 2.0), z: (0.0, 1.0)),
    grid: (nx: 6, ny: 12, nz: 6),
    time: (end: 0.25, fixed_dt: 0.0078125),
    fluid: (density: 1e-3, viscosity: 2e-4),
    numerics: (projection: (tolerance: 1e-8)),
    gravity: (0.0, -1.0, 0.0),
    solid: (shape: Sphere(center: (0.0, 1.5, 0.0), radius: 0.4), density: 1.0, viscosity: 1e-2),
    boundaries: (x_min: Symmetry, x_max: NoSlip, y_min: NoSlip, y_max: NoSlip,
                 z_min: Symmetry, z_max: NoSlip),
    output: (
        vtk_every: 0.125,
        probe_every: 0.03125,
        probes: [SolidVolume, SolidCentroid, SolidVelocity, MaxDivergence],
    ),
)
"#;

/// A neo-Hookean sphere thrown at the floor of a quarter box with two symmetry planes: the
/// elastic stages in 3-D (B̃ of six components, the implicit elastic step), the solid's initial
/// velocity and the contact probes.
const SPHERE: &str = r#"Scene(
    name: "sphere",
    geometry: Cartesian3D,
    domain: (x: (0.0, 1.0), y: (0.0, 1.5), z: (0.0, 1.0)),
    grid: (nx: 6, ny: 9, nz: 6),
    time: (end: 0.15, cfl: 0.4, dt_max: 0.005),
    fluid: (density: 1.0, viscosity: 0.01),
    gravity: (0.0, -9.81, 0.0),
    solid: (shape: Sphere(center: (0.0, 0.55, 0.0), radius: 0.4), density: 2.0,
            velocity: (0.0, -2.0, 0.0),
            law: (name: "neo_hookean", parameters: {"G": 50.0})),
    boundaries: (x_min: Symmetry, x_max: NoSlip, y_min: NoSlip, y_max: NoSlip,
                 z_min: Symmetry, z_max: NoSlip),
    output: (
        vtk_every: 0.05,
        probe_every: 0.01,
        probes: [SolidVolume, SolidCentroid, SolidVelocity, KineticEnergy,
                 ContactForce(wall: YMin), SolidPieces],
    ),
)
"#;

fn scratch(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("efsi-ckpt-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// Write `text` as `dir/scene.ron` and build its simulation.
fn load(dir: &Path, text: &str) -> Simulation {
    let path = dir.join("scene.ron");
    std::fs::write(&path, text).unwrap();
    let scene = Scene::load(&path).unwrap_or_else(|e| panic!("{e}"));
    efsi_run::simulation(scene, &path, &efsi_stages::builtin()).unwrap_or_else(|e| panic!("{e}"))
}

/// Run to the end in `dir/a` (with periodic checkpoints); run again in `dir/b`, stopped after
/// `stop_at` steps and resumed. Returns both simulations and outcomes.
fn run_twice(
    dir: &Path,
    text: &str,
    stop_at: u64,
) -> (
    (Simulation, RunOutcome),
    (Simulation, RunOutcome, RunOutcome),
) {
    let mut a = load(dir, text);
    let opts = RunOptions {
        checkpoint_every: Some(0.02),
        ..RunOptions::default()
    };
    let out_a = run_with(&mut a, &dir.join("a"), &opts, &mut |_| {}).unwrap();
    assert!(dir.join("a").join(checkpoint::LATEST).is_file());

    let mut b = load(dir, text);
    let flag = Arc::new(AtomicUsize::new(0));
    let opts = RunOptions {
        stop: Some(flag.clone()),
        ..RunOptions::default()
    };
    let first = run_with(&mut b, &dir.join("b"), &opts, &mut |p| {
        if p.step == stop_at {
            flag.store(2, Ordering::SeqCst);
        }
    })
    .unwrap();
    assert_eq!(first.stop, StopReason::Interrupted { signal: 2 });
    assert_eq!(first.steps, stop_at);
    drop(b);
    let (b, second) = resume(
        &dir.join("b"),
        &efsi_stages::builtin(),
        &RunOptions::default(),
        &mut |_| {},
    )
    .unwrap_or_else(|e| panic!("{e}"));
    ((a, out_a), (b, first, second))
}

/// Every array of both states, compared bit for bit (ghosts included).
fn assert_bit_identical(a: &Simulation, b: &Simulation) {
    assert_eq!(a.state.step, b.state.step);
    assert_eq!(a.state.t.to_bits(), b.state.t.to_bits());
    assert_eq!(a.state.dt_prev.to_bits(), b.state.dt_prev.to_bits());
    let (fa, fb) = (a.state.arrays(), b.state.arrays());
    assert_eq!(fa.len(), fb.len());
    for ((name, x), (_, y)) in fa.iter().zip(&fb) {
        let differ = x
            .data()
            .iter()
            .zip(y.data())
            .filter(|(p, q)| p.to_bits() != q.to_bits())
            .count();
        assert_eq!(differ, 0, "{name}: {differ} values differ");
    }
    assert_eq!(
        a.rate_of_change().to_bits(),
        b.rate_of_change().to_bits(),
        "rate of change"
    );
}

/// The files of an output folder (relative names, sorted) except run.json and the checkpoint.
fn outputs(dir: &Path) -> Vec<(String, Vec<u8>)> {
    let mut out = Vec::new();
    for sub in ["", "fields", "profiles"] {
        for e in std::fs::read_dir(dir.join(sub)).unwrap() {
            let p = e.unwrap().path();
            if p.is_file() && p.file_name().unwrap() != "run.json" {
                let rel = p.strip_prefix(dir).unwrap().display().to_string();
                out.push((rel, std::fs::read(&p).unwrap()));
            }
        }
    }
    out.sort();
    out
}

/// Two viscous disks thrown at each other (no law): the contact stage's repulsion acts across
/// the checkpoint, which carries its stored energy (its step limit) and the bodies' windows.
const TWO_DISKS: &str = r#"Scene(
    name: "two_disks",
    domain: (x: (0.0, 2.0), y: (0.0, 1.0)),
    grid: (nx: 32, ny: 16),
    time: (end: 0.3, cfl: 0.4),
    fluid: (density: 1.0, viscosity: 0.001),
    numerics: (projection: (tolerance: 1e-10)),
    solids: [
        (name: "left", shape: Disk(center: (0.7, 0.5), radius: 0.2), density: 20.0,
         viscosity: 20.0, velocity: (2.0, 0.0)),
        (name: "right", shape: Disk(center: (1.3, 0.5), radius: 0.2), density: 20.0,
         viscosity: 20.0, velocity: (-2.0, 0.0)),
    ],
    boundaries: (x_min: NoSlip, x_max: NoSlip, y_min: NoSlip, y_max: NoSlip),
    output: (
        vtk_every: 0.1,
        probe_every: 0.02,
        probes: [SolidCentroid, SolidVelocity, SolidOverlap, BodyContact],
    ),
)
"#;

fn check_resumed_run(name: &str, text: &str, stop_at: u64, steps: u64) {
    let dir = scratch(name);
    let ((a, out_a), (b, first, second)) = run_twice(&dir, text, stop_at);
    assert_eq!(out_a.steps, steps, "{name}: steps of the reference run");
    assert_eq!(second.steps, steps);
    assert_eq!(second.steps_this_run, steps - stop_at);
    assert_eq!(second.resumed_from.as_ref().unwrap().0, first.steps);
    assert_bit_identical(&a, &b);
    // The same files, byte for byte: VTK, the collection, probes (no duplicated or lost rows),
    // profiles.
    let (oa, ob) = (outputs(&dir.join("a")), outputs(&dir.join("b")));
    let names = |o: &[(String, Vec<u8>)]| o.iter().map(|(n, _)| n.clone()).collect::<Vec<_>>();
    assert_eq!(names(&oa), names(&ob), "{name}");
    for ((n, x), (_, y)) in oa.iter().zip(&ob) {
        assert!(x == y, "{name}: {n} differs between the runs");
    }
    let json = std::fs::read_to_string(dir.join("b/run.json")).unwrap();
    assert!(
        json.contains(&format!("\"resumed_from_step\": {stop_at}")),
        "{json}"
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn a_resumed_cavity_run_is_bit_identical_to_an_uninterrupted_one() {
    check_resumed_run("cavity", CAVITY, 23, 34);
}

#[test]
fn a_resumed_fluid_structure_run_is_bit_identical_to_an_uninterrupted_one() {
    check_resumed_run("disk", DISK, 17, 30);
}

#[test]
fn a_resumed_3d_cavity_run_is_bit_identical_to_an_uninterrupted_one() {
    check_resumed_run("cube", CUBE, 9, 15);
}

#[test]
fn a_resumed_3d_drop_run_is_bit_identical_to_an_uninterrupted_one() {
    check_resumed_run("drop", DROP, 13, 32);
}

#[test]
fn a_resumed_3d_elastic_run_is_bit_identical_to_an_uninterrupted_one() {
    check_resumed_run("sphere", SPHERE, 17, 30);
}

#[test]
fn a_resumed_run_of_bodies_in_contact_is_bit_identical_to_an_uninterrupted_one() {
    check_resumed_run("two_disks", TWO_DISKS, 30, 78);
    // The same disks elastic: each body's deformation is in the checkpoint, its fraction
    // published again by the VOF stage on restore.
    let soft = TWO_DISKS.replace(
        "viscosity: 20.0,",
        "viscosity: 0.02, law: (name: \"neo_hookean\", parameters: {\"G\": 50.0}),",
    );
    check_resumed_run("two_soft_disks", &soft, 30, 85);
}

#[test]
fn snapshot_and_restore_rewind_a_simulation_exactly() {
    let dir = scratch("snapshot");
    let mut s = load(&dir, DISK);
    run_until(&mut s, 0.03, |_, _| {});
    let snap = s.snapshot();
    // None of these stages keeps data beside the state (the VOF stage's previous velocity is
    // the state's between steps).
    let padded = s.state.u.data().len();
    assert_eq!(snap.stage_data("vof"), Some(&[][..]));
    assert_eq!(snap.stage_data("momentum"), Some(&[][..]));
    assert_eq!(snap.stage_data("body_force"), Some(&[][..]));
    assert_eq!(snap.stage_data("no_such_stage"), None);
    assert!(snap.size_bytes() > 30 * 8 * padded);
    run_until(&mut s, 0.06, |_, _| {});
    let ahead = s.snapshot();
    s.restore(&snap).unwrap();
    assert_eq!(s.state.t, 0.03);
    run_until(&mut s, 0.06, |_, _| {});
    let mut again = load(&dir, DISK);
    again.restore(&ahead).unwrap();
    assert_bit_identical(&s, &again);
    // Allocation-free refresh of an existing snapshot.
    let mut reused = snap.clone();
    s.snapshot_into(&mut reused);
    assert_eq!(reused.step(), s.state.step);
    // A snapshot of another scene does not fit, and the simulation is left untouched.
    let mut cavity = load(&dir, CAVITY);
    let before = cavity.snapshot();
    let e = cavity.restore(&snap).unwrap_err();
    assert_eq!(e.exit_code(), 2);
    assert!(
        e.to_string().starts_with("snapshot: it holds the fields ["),
        "{e}"
    );
    assert!(e.to_string().contains("phi"), "{e}");
    assert_eq!(cavity.state.step, before.step());
    std::fs::remove_dir_all(&dir).unwrap();
}

/// Write a checkpoint of a few steps of the cavity; returns its folder.
fn cavity_checkpoint(name: &str) -> PathBuf {
    let dir = scratch(name);
    let mut s = load(&dir, CAVITY);
    let flag = Arc::new(AtomicUsize::new(15));
    let opts = RunOptions {
        stop: Some(flag),
        ..RunOptions::default()
    };
    // Stopped before the first step: a checkpoint at step 0.
    let o = run_with(&mut s, &dir.join("out"), &opts, &mut |_| {}).unwrap();
    assert_eq!(o.stop, StopReason::Interrupted { signal: 15 });
    assert_eq!(o.steps, 0);
    dir
}

fn resume_err(dir: &Path) -> EfsiError {
    resume(
        &dir.join("out"),
        &efsi_stages::builtin(),
        &RunOptions::default(),
        &mut |_| {},
    )
    .err()
    .expect("refused")
}

#[test]
fn damaged_or_missing_checkpoints_are_refused_with_a_reason() {
    let dir = cavity_checkpoint("damaged");
    let path = dir.join("out").join(checkpoint::LATEST);
    let good = std::fs::read(&path).unwrap();
    let file = CheckpointFile::read(&path).unwrap();
    assert_eq!(file.record.step(), 0);
    assert_eq!(file.outputs.probe_count, 1);
    assert!(file.scene_ron.contains("cavity"));
    for (bytes, needle) in [
        (good[..good.len() - 5].to_vec(), "truncated"),
        (
            {
                let mut b = good.clone();
                let k = b.len() / 2;
                b[k] ^= 1;
                b
            },
            "checksum",
        ),
        (b"not a checkpoint at all, just text".to_vec(), "EFSICKPT"),
        (
            {
                let mut b = good.clone();
                b[8] = 9;
                b
            },
            "format version 9",
        ),
    ] {
        std::fs::write(&path, &bytes).unwrap();
        let e = resume_err(&dir);
        assert_eq!(e.exit_code(), 2, "{e}");
        let m = e.to_string();
        assert!(m.contains("latest.efsick") && m.contains(needle), "{m}");
    }
    std::fs::remove_file(&path).unwrap();
    let e = resume_err(&dir);
    assert_eq!(e.exit_code(), 2);
    assert!(
        e.to_string().contains("no checkpoint to resume from"),
        "{e}"
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

/// A checkpoint of the format before postcard (version 4), written by `efsi run` of that
/// format (commit 4e6fb80) for [`CAVITY`] with `--set grid.nx=8 --set grid.ny=8 --set
/// time.end=0.05 --set output.profiles[0].at=[0.05] --checkpoint-every 0.05`: refused by its
/// version, saying what to do, never misread.
#[test]
fn a_checkpoint_of_an_earlier_format_is_refused_naming_its_version() {
    let fixture = Path::new(env!("CARGO_MANIFEST_DIR")).join("fixtures/checkpoint-format-4.efsick");
    let old = std::fs::read(&fixture).unwrap();
    assert_eq!(&old[..12], b"EFSICKPT\x04\0\0\0");
    let expected = format!(
        "checkpoint format version 4 (written by an earlier efsi); this efsi reads version {} \
         only; finish that run with the efsi that wrote the checkpoint, or start it again",
        checkpoint::FORMAT_VERSION
    );
    let e = CheckpointFile::read(&fixture).unwrap_err();
    assert_eq!(e.to_string(), format!("{}: {expected}", fixture.display()));
    let dir = cavity_checkpoint("format-4");
    let path = dir.join("out").join(checkpoint::LATEST);
    std::fs::write(&path, &old).unwrap();
    let e = resume_err(&dir);
    assert_eq!(e.exit_code(), 2, "{e}");
    assert_eq!(e.to_string(), format!("{}: {expected}", path.display()));
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn a_changed_scene_is_refused_naming_what_differs() {
    let dir = cavity_checkpoint("changed");
    let scene = dir.join("scene.ron");
    std::fs::write(
        &scene,
        CAVITY
            .replace("viscosity: 0.01", "viscosity: 0.02")
            .replace("nx: 16", "nx: 17"),
    )
    .unwrap();
    let e = resume_err(&dir);
    assert_eq!(e.exit_code(), 2);
    let m = e.to_string();
    assert!(m.contains("cannot resume"), "{m}");
    assert!(m.contains("scene: fluid.viscosity: 0.01 → 0.02"), "{m}");
    assert!(m.contains("scene: grid.nx: 16 → 17"), "{m}");
    // Probes of the interrupted run are untouched by the refusal.
    let probes = std::fs::read_to_string(dir.join("out/probes.csv")).unwrap();
    assert_eq!(probes.lines().count(), 2, "{probes}");
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn lost_probe_rows_are_detected_on_resume() {
    let dir = cavity_checkpoint("lost");
    std::fs::write(
        dir.join("out/probes.csv"),
        "t,u_c,kinetic_energy,max_divergence\n",
    )
    .unwrap();
    let e = resume_err(&dir);
    assert_eq!(e.exit_code(), 2);
    assert!(e.to_string().contains("rows were lost"), "{e}");
    std::fs::remove_dir_all(&dir).unwrap();
}

/// A box whose gravity overflows in the first step: the pipeline's finite check stops the run.
const OVERFLOW: &str = r#"Scene(
    name: "overflow",
    domain: (x: (0.0, 1.0), y: (0.0, 1.0)),
    grid: (nx: 8, ny: 8),
    time: (end: 1e11, fixed_dt: 1e10),
    fluid: (density: 1.0, viscosity: 0.01),
    gravity: (0.0, -1e300),
    boundaries: (x_min: NoSlip, x_max: NoSlip, y_min: NoSlip, y_max: NoSlip),
    output: (vtk_every: 1e10, probe_every: 1e10, probes: [KineticEnergy]),
)
"#;

#[test]
fn a_non_finite_field_stops_the_run_and_saves_the_last_good_state() {
    let dir = scratch("overflow");
    let mut s = load(&dir, OVERFLOW);
    let out = dir.join("out");
    let e = run_with(&mut s, &out, &RunOptions::default(), &mut |_| {}).unwrap_err();
    assert_eq!(e.exit_code(), 3);
    let m = e.to_string();
    assert!(
        m.starts_with(
            "stage `body_force`: produced a non-finite `v` at cell (0, 1) in step 0 (t = 0.000000e0, Δt = 1.000e10)"
        ),
        "{m}"
    );
    let EfsiError::Saved {
        step,
        vtk,
        checkpoint: ck,
        ..
    } = &e
    else {
        panic!("{e:?}")
    };
    assert_eq!(*step, 0);
    assert!(
        vtk.as_ref()
            .is_some_and(|v| v.ends_with("fields/overflow_000000_last_good.vtr")),
        "{vtk:?}"
    );
    assert!(
        m.contains("last good state (step 0, t = 0.000000e0)"),
        "{m}"
    );
    let vtr = std::fs::read(vtk.as_ref().unwrap()).unwrap();
    assert!(vtr.starts_with(b"<?xml") && vtr.ends_with(b"</VTKFile>\n"));
    let pvd = std::fs::read_to_string(out.join("fields.pvd")).unwrap();
    assert!(
        pvd.contains(r#"file="fields/overflow_000000_last_good.vtr""#),
        "{pvd}"
    );
    // The checkpoint holds the start of the failed step: finite, at rest.
    let file = CheckpointFile::read(ck).unwrap();
    assert_eq!(file.record.step(), 0);
    let snap = file
        .record
        .into_snapshot(load(&dir, OVERFLOW).snapshot(), "test")
        .unwrap();
    for (name, f) in snap.state.arrays() {
        assert!(f.data().iter().all(|x| x.is_finite()), "{name}");
    }
    assert_eq!(snap.state.v.max_abs(efsi_core::Stagger::YFace, 8, 8), 0.0);
    std::fs::remove_dir_all(&dir).unwrap();
}

/// The room a run keeps for its last checkpoint is counted from the simulation without a
/// snapshot ([`checkpoint::encoded_len_of`]): exactly the bytes of the checkpoint written from a
/// snapshot, with every stage's history filled (the viscous warm start, the advection's
/// predictor, the elastic stages' data), in 2-D and 3-D.
#[test]
fn the_checkpoint_is_sized_exactly_without_a_snapshot() {
    let dir = scratch("sized");
    for (text, steps) in [(CAVITY, 3), (DISK, 3), (CUBE, 3), (DROP, 2), (SPHERE, 2)] {
        let mut s = load(&dir, text);
        for _ in 0..steps {
            let dt = s.next_dt(s.scene.time.end).unwrap();
            s.step(dt).unwrap();
        }
        let outputs = efsi_run::checkpoint::OutputState {
            probe_count: 7,
            run_id: "abc".into(),
            ..Default::default()
        };
        let c = efsi_run::Checkpoint {
            efsi_version: env!("CARGO_PKG_VERSION").into(),
            scene_path: std::path::absolute(&s.scene_path).unwrap(),
            scene_ron: s.scene.to_ron(),
            overrides: s.scene.overrides.clone(),
            law: None,
            outputs: outputs.clone(),
            snapshot: s.snapshot(),
        };
        let bytes = checkpoint::encode(&c).len();
        assert!(bytes > 8 * s.state.u.data().len(), "{bytes}");
        assert_eq!(checkpoint::encoded_len_of(&s, &None, &outputs), bytes);
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

/// The start of a step kept for a rollback ([`efsi_core::StepStart`]: the fields the stages
/// write, the part of each stage's data a step overwrites) puts a simulation back as a whole
/// snapshot does: after a step and its rewind, every array and every stage's data equal the
/// snapshot's bit for bit, and two more steps give the same state as from the snapshot — in
/// 2-D and 3-D, with one fluid, a drop (VOF) and elastic solids.
#[test]
fn a_kept_step_start_rewinds_a_step_as_a_snapshot_does() {
    let dir = scratch("rewind");
    for (text, steps) in [(CAVITY, 3), (DISK, 3), (CUBE, 3), (DROP, 2), (SPHERE, 2)] {
        let mut s = load(&dir, text);
        let mut fresh = load(&dir, text);
        let mut start = None;
        for _ in 0..steps {
            s.keep_step_start(&mut start);
            let dt = s.next_dt(s.scene.time.end).unwrap();
            s.step(dt).unwrap();
        }
        let before = s.snapshot();
        s.keep_step_start(&mut start);
        let dt = s.next_dt(s.scene.time.end).unwrap();
        s.step(dt).unwrap();
        s.rewind(start.as_ref().unwrap()).unwrap();
        let back = s.snapshot();
        let arrays = |x: &efsi_core::Snapshot| -> Vec<(String, Vec<u64>)> {
            (x.state.arrays().into_iter())
                .map(|(n, f)| (n, f.data().iter().map(|v| v.to_bits()).collect()))
                .collect()
        };
        let bits = |x: &efsi_core::Snapshot| -> Vec<(String, Vec<u64>)> {
            (x.stages.iter())
                .map(|(n, d)| (n.clone(), d.iter().map(|v| v.to_bits()).collect()))
                .collect()
        };
        assert_eq!((back.t(), back.step()), (before.t(), before.step()));
        assert!(arrays(&back) == arrays(&before), "{}: arrays", s.scene.name);
        assert!(bits(&back) == bits(&before), "{}: stage data", s.scene.name);
        fresh.restore(&before).unwrap();
        for _ in 0..2 {
            for sim in [&mut s, &mut fresh] {
                let dt = sim.next_dt(sim.scene.time.end).unwrap();
                sim.step(dt).unwrap();
            }
        }
        assert_bit_identical(&s, &fresh);
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

/// Measured figures for the report: checkpoint size and write/read time of a 128² cavity.
#[test]
fn checkpoint_of_a_128_cavity_is_small_and_quick() {
    let dir = scratch("size");
    let s = load(&dir, &CAVITY.replace("nx: 16, ny: 16", "nx: 128, ny: 128"));
    let c = efsi_run::Checkpoint {
        efsi_version: "test".into(),
        scene_path: dir.join("scene.ron"),
        scene_ron: s.scene.to_ron(),
        overrides: s.scene.overrides.clone(),
        law: None,
        outputs: Default::default(),
        snapshot: s.snapshot(),
    };
    let path = dir.join("c.efsick");
    let t0 = std::time::Instant::now();
    c.write(&path).unwrap();
    let write = t0.elapsed().as_secs_f64();
    let t0 = std::time::Instant::now();
    let back = CheckpointFile::read(&path).unwrap();
    let read = t0.elapsed().as_secs_f64();
    let bytes = std::fs::metadata(&path).unwrap().len();
    eprintln!(
        "128² cavity checkpoint: {bytes} bytes, write {:.2} ms, read {:.2} ms",
        write * 1e3,
        read * 1e3
    );
    // 5 padded arrays of 133² values, plus the scene.
    let arrays = 5 * 133 * 133 * 8;
    assert!(
        bytes as usize > arrays && (bytes as usize) < arrays + 8192,
        "{bytes}"
    );
    assert_eq!(back.record.step(), 0);
    std::fs::remove_dir_all(&dir).unwrap();
}

/// The energy guard's baseline is part of the checkpoint: a run pumping energy in (the sphere
/// with its elastic stress explicit at 1.2 × the explicit step's wave limit) stopped halfway to
/// the guard's verdict and resumed is stopped at the same step with the same figures as the
/// uninterrupted run (a baseline restarted at the resume would move or remove the verdict).
#[test]
fn the_energy_guard_judges_a_resumed_run_as_the_uninterrupted_one() {
    const PUMP: &str = r#"Scene(
    name: "explicit_sphere",
    geometry: Axisymmetric,
    domain: (r: (0.0, 0.045), z: (0.0, 0.09)),
    grid: (nr: 19, nz: 38),
    time: (end: 0.02, cfl: 0.4),
    numerics: (elastic: (implicit: false, wave_courant: 1.2)),
    fluid: (density: 1.2, viscosity: 1.8e-5),
    gravity: (0.0, -9.81),
    solid: (
        shape: Disk(center: (0.0, 0.0573), radius: 0.0192),
        density: 1106.0,
        velocity: (0.0, -1.22),
        law: (name: "neo_hookean", parameters: {"G": 1.8e5}),
    ),
    boundaries: (r_min: Axis, r_max: NoSlip, z_min: NoSlip, z_max: NoSlip),
    output: (probe_every: 0.0005, probes: [KineticEnergy, PotentialEnergy]),
)
"#;
    let dir = scratch("guard");
    let verdict = |e: EfsiError| match e {
        EfsiError::Saved { error, step, .. } => match *error {
            EfsiError::EnergyGrowth { .. } => (step, error.to_string()),
            other => panic!("not the energy guard: {other}"),
        },
        other => panic!("not a saved failure: {other}"),
    };
    let mut a = load(&dir, PUMP);
    let whole =
        verdict(run_with(&mut a, &dir.join("a"), &RunOptions::default(), &mut |_| {}).unwrap_err());
    assert!(whole.0 > 4, "the guard fires at step {}", whole.0);
    let stop_at = whole.0 / 2;
    let mut b = load(&dir, PUMP);
    let flag = Arc::new(AtomicUsize::new(0));
    let opts = RunOptions {
        stop: Some(flag.clone()),
        ..RunOptions::default()
    };
    let first = run_with(&mut b, &dir.join("b"), &opts, &mut |p| {
        if p.step == stop_at {
            flag.store(2, Ordering::SeqCst);
        }
    })
    .unwrap();
    assert_eq!(first.steps, stop_at);
    let resumed = resume(
        &dir.join("b"),
        &efsi_stages::builtin(),
        &RunOptions::default(),
        &mut |_| {},
    );
    let resumed = verdict(
        resumed
            .err()
            .expect("the resumed run must be stopped by the guard"),
    );
    assert_eq!(resumed, whole);
    std::fs::remove_dir_all(&dir).unwrap();
}

/// The elastic stages' data moved from the core's state into a stage-owned resource with its
/// checkpoint names and order unchanged (the format version stays): a checkpoint written
/// before the move is read as before. The names, in order: the shared fields, φ, the seven B
/// tensors' four components, then the scalars.
#[test]
fn the_elastic_stages_data_keeps_its_checkpoint_names() {
    let dir = scratch("names");
    let sim = load(&dir, DISK);
    let names: Vec<String> = sim.state.arrays().into_iter().map(|(n, _)| n).collect();
    let mut want: Vec<String> = ["u", "v", "p", "rho", "mu", "phi"].map(String::from).into();
    for part in [
        "b",
        "start",
        "advection",
        "advection_prev",
        "stretching",
        "explicit",
        "stress",
    ] {
        for c in ["11", "22", "33", "12"] {
            want.push(format!("B.{part}.{c}"));
        }
    }
    assert_eq!(names, want);
    let scalars: Vec<&str> = sim.state.scalars().into_iter().map(|(n, _)| n).collect();
    assert_eq!(
        scalars,
        [
            "frame_acceleration_x",
            "frame_acceleration_y",
            "elastic_energy"
        ]
    );
    std::fs::remove_dir_all(&dir).unwrap();
}
