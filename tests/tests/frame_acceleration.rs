//! The frame acceleration (`FrameAcceleration::set_frame_acceleration`, the FMU's base-acceleration
//! input): a constant one is exactly a change of gravity, it travels with snapshots and
//! checkpoints, and it is refused where it could not act.

use efsi_run::checkpoint::{self, Checkpoint, OutputState};
use efsi_stages::body_force::FrameAcceleration;
use efsi_tests::{run_until, sim};

/// A heavy viscous disk (no law: VOF, body force, viscous, projection stages) falling in a box.
fn disk(gravity: f64) -> String {
    format!(
        r#"Scene(
    name: "falling_disk",
    domain: (x: (0.0, 1.0), y: (0.0, 2.0)),
    grid: (nx: 12, ny: 24),
    time: (end: 0.2, cfl: 0.4),
    fluid: (density: 1.0, viscosity: 0.01),
    gravity: (0.0, {gravity:?}),
    solid: (shape: Disk(center: (0.5, 1.4), radius: 0.2), density: 10.0),
    boundaries: (x_min: NoSlip, x_max: NoSlip, y_min: NoSlip, y_max: NoSlip),
)"#
    )
}

#[test]
fn constant_frame_acceleration_is_gravity_minus_it_bit_for_bit() {
    let mut shaken = sim(&disk(-1.0));
    shaken.set_frame_acceleration((0.0, 0.5)).unwrap();
    let mut heavier = sim(&disk(-1.5));
    let mut still = sim(&disk(-1.0));
    for s in [&mut shaken, &mut heavier, &mut still] {
        run_until(s, 0.2, |_, _| ());
    }
    assert_eq!(shaken.state.step, heavier.state.step);
    assert_eq!(shaken.state.u.data(), heavier.state.u.data());
    assert_eq!(shaken.state.v.data(), heavier.state.v.data());
    assert_eq!(shaken.state.phi, heavier.state.phi);
    assert_ne!(shaken.state.v.data(), still.state.v.data());
}

#[test]
fn frame_acceleration_travels_with_snapshots_and_checkpoints() {
    let mut s = sim(&disk(-1.0));
    s.set_frame_acceleration((0.25, -3.0)).unwrap();
    let snap = s.snapshot();
    s.set_frame_acceleration((0.0, 0.0)).unwrap();
    s.restore(&snap).unwrap();
    assert_eq!(s.state.frame_acceleration, (0.25, -3.0));
    let bytes = checkpoint::encode(&Checkpoint {
        efsi_version: "test".into(),
        scene_path: "<test>".into(),
        scene_ron: s.scene.to_ron(),
        overrides: s.scene.overrides.clone(),
        law: None,
        outputs: OutputState::default(),
        snapshot: snap,
    });
    let file = checkpoint::decode(&bytes, "test").unwrap();
    let fresh = sim(&disk(-1.0));
    let back = file.record.into_snapshot(fresh.snapshot(), "test").unwrap();
    assert_eq!(back.state.frame_acceleration, (0.25, -3.0));
    let names: Vec<_> = back.state.scalars().into_iter().map(|(n, _)| n).collect();
    assert_eq!(names, ["frame_acceleration_x", "frame_acceleration_y"]);
}

#[test]
fn frame_acceleration_is_refused_where_it_cannot_act() {
    let no_gravity = sim(&disk(0.0).replace("cfl: 0.4)", "cfl: 0.4, dt_max: 0.01)"));
    let mut s = no_gravity;
    let e = s
        .set_frame_acceleration((0.0, 1.0))
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("frame_acceleration") && e.contains("gravity"),
        "{e}"
    );
    let mut s = sim(&disk(-1.0));
    let e = s
        .set_frame_acceleration((f64::NAN, 0.0))
        .unwrap_err()
        .to_string();
    assert!(e.contains("finite"), "{e}");
    let axi = disk(-1.0)
        .replace(
            "name: \"falling_disk\",",
            "name: \"axi\", geometry: Axisymmetric,",
        )
        .replace("center: (0.5, 1.4)", "center: (0.0, 1.4)")
        .replace("x_min: NoSlip", "x_min: Axis");
    let mut s = sim(&axi);
    let e = s
        .set_frame_acceleration((1.0, 0.0))
        .unwrap_err()
        .to_string();
    assert!(e.contains("along z"), "{e}");
    s.set_frame_acceleration((0.0, 2.0)).unwrap();
    assert_eq!(s.state.frame_acceleration, (0.0, 2.0));
}
