use super::*;

const MIN: &str = r#"Scene(
        name: "t",
        domain: (x: (0.0, 1.0), y: (0.0, 1.0)),
        grid: (nx: 8, ny: 8),
        time: (end: 1.0),
        fluid: (density: 1.0, viscosity: 0.01),
        boundaries: (x_min: NoSlip, x_max: NoSlip, y_min: NoSlip, y_max: MovingWall(speed: 1.0)),
    )"#;

fn load(s: &str) -> Result<Scene, SceneError> {
    Scene::from_str_at(s, Path::new("scene.ron"))
}

#[test]
fn minimal_scene_loads_with_defaults() {
    let s = load(MIN).unwrap();
    assert_eq!(s.time.cfl, 0.4);
    assert!(s.physics.advection);
    assert_eq!(s.numerics.preset, Preset::Default);
    assert_eq!(s.numerics.sections().count(), 0);
}

#[test]
fn implicit_some_and_round_trip() {
    let s = load(&MIN.replace("end: 1.0", "end: 1.0, steady: 1e-6")).unwrap();
    assert_eq!(s.time.steady, Some(1e-6));
    let again = load(&s.to_ron()).unwrap();
    assert_eq!(again.time.steady, Some(1e-6));
}

#[test]
fn unknown_field_names_line_and_column() {
    let e = load(&MIN.replace("density: 1.0,", "density: 1.0, colour: 3,")).unwrap_err();
    let msg = e.to_string();
    assert!(msg.starts_with("scene.ron:6:"), "{msg}");
    assert!(msg.contains("colour"), "{msg}");
}

#[test]
fn sin2_ramp_matches_seed_eq26() {
    // Seed Eq. 26 on a 2-long lid: 0.5 sin²(πx/0.6) on [0, 0.3].
    let p = WallProfile::Sin2Ramp { width: 0.3 };
    let x: f64 = 0.1;
    assert!((p.factor(x, 2.0) - (std::f64::consts::PI * x / 0.6).sin().powi(2)).abs() < 1e-15);
    assert_eq!(p.factor(1.0, 2.0), 1.0);
    assert!(
        (p.factor(1.9, 2.0) - (std::f64::consts::PI * (1.9f64 - 2.0) / 0.6).sin().powi(2)).abs()
            < 1e-15
    );
}
