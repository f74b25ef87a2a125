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

const CUBE: &str = r#"Scene(
        name: "cube",
        geometry: Cartesian3D,
        domain: (x: (0.0, 1.0), y: (0.0, 2.0), z: (-1.0, 1.0)),
        grid: (nx: 4, ny: 8, nz: 6),
        time: (end: 1.0),
        fluid: (density: 1.0, viscosity: 0.01),
        gravity: (0.0, 0.0, -9.81),
        boundaries: (x_min: NoSlip, x_max: NoSlip, y_min: NoSlip, y_max: MovingWall(speed: 1.0),
                     z_min: Symmetry, z_max: NoSlip),
    )"#;

/// The field a refused scene names, and its message.
fn refused(text: &str) -> (String, String) {
    match load(text).unwrap_err() {
        SceneError::Invalid { field, message, .. } => (field, message),
        e => panic!("not a validation error: {e}"),
    }
}

#[test]
fn a_cartesian_3d_scene_reads_its_third_axis_and_round_trips() {
    let s = load(CUBE).unwrap();
    assert_eq!(s.domain.z, Some((-1.0, 1.0)));
    assert_eq!(s.grid.n(), [4, 8, 6]);
    assert_eq!(s.boundaries.get(Side::ZMin), &Boundary::Symmetry);
    assert_eq!(s.boundaries.get(Side::ZMax), &Boundary::NoSlip);
    assert_eq!(s.gravity.xyz(), [0.0, 0.0, -9.81]);
    let g = s.build_grid();
    assert_eq!(
        (g.n(), g.dims(), g.h()),
        ([4, 8, 6], 3, [0.25, 0.25, 1.0 / 3.0])
    );
    let again = load(&s.to_ron()).unwrap();
    assert_eq!(
        (again.domain, again.grid, again.boundaries, again.gravity),
        (s.domain, s.grid, s.boundaries, s.gravity)
    );
}

#[test]
fn axisymmetric_spellings_still_name_x_and_y() {
    let s = load(
        r#"Scene(name: "a", geometry: Axisymmetric,
            domain: (r: (0.0, 1.0), z: (0.0, 2.0)), grid: (nr: 4, nz: 8),
            time: (end: 1.0), fluid: (density: 1.0, viscosity: 0.01),
            boundaries: (r_min: Axis, r_max: NoSlip, z_min: NoSlip, z_max: MovingWall(speed: 1.0)))"#,
    )
    .unwrap();
    assert_eq!((s.domain.y, s.domain.z), ((0.0, 2.0), None));
    assert_eq!((s.grid.ny, s.grid.nz), (8, None));
    assert_eq!(s.boundaries.y_min, Boundary::NoSlip);
    assert!(matches!(s.boundaries.y_max, Boundary::MovingWall { .. }));
    assert_eq!(s.boundaries.z_min, None);
    // What is written back is the canonical spelling, and reads the same.
    let again = load(&s.to_ron()).unwrap();
    assert_eq!((again.domain.y, again.grid.ny), ((0.0, 2.0), 8));
}

#[test]
fn a_planar_scene_with_a_third_axis_is_refused_by_name() {
    let (f, m) = refused(&MIN.replace(
        "y_max: MovingWall(speed: 1.0)",
        "y_max: NoSlip, z_min: NoSlip",
    ));
    assert_eq!(f, "boundaries.z_min");
    assert!(m.contains("Cartesian3D"), "{m}");
    let (f, _) = refused(&MIN.replace("ny: 8", "ny: 8, nz: 4"));
    assert_eq!(f, "grid.nz");
    let (f, _) = refused(&MIN.replace("y: (0.0, 1.0))", "y: (0.0, 1.0), z: (0.0, 1.0))"));
    assert_eq!(f, "domain.z");
    let (f, m) = refused(&MIN.replace("time:", "gravity: (0.0, -1.0, 0.0), time:"));
    assert_eq!(f, "gravity");
    assert!(m.contains("three components"), "{m}");
}

#[test]
fn a_cartesian_3d_scene_without_its_third_axis_or_with_r_z_spellings_is_refused_by_name() {
    let (f, m) = refused(&CUBE.replace(", nz: 6", ""));
    assert_eq!(f, "grid.nz");
    assert!(m.contains("missing"), "{m}");
    let (f, _) = refused(&CUBE.replace(", z_max: NoSlip", ""));
    assert_eq!(f, "boundaries.z_max");
    let (f, m) = refused(&CUBE.replace("(x: (0.0, 1.0)", "(r: (0.0, 1.0)"));
    assert_eq!(f, "domain.x");
    assert!(m.contains("`r`"), "{m}");
    // `z` alone is the third axis: y is then missing.
    let (f, m) = refused(&CUBE.replace("y: (0.0, 2.0), ", ""));
    assert_eq!(f, "domain.y");
    assert!(m.contains("third"), "{m}");
    let (f, m) = refused(&CUBE.replace("(0.0, 0.0, -9.81)", "(0.0, -9.81)"));
    assert_eq!(f, "gravity");
    assert!(m.contains("three components"), "{m}");
    let (f, _) = refused(&CUBE.replace("z_min: Symmetry", "z_min: Periodic"));
    assert_eq!(f, "boundaries.z_min");
    let (f, _) = refused(&CUBE.replace("nz: 6", "nz: 1"));
    assert_eq!(f, "grid.nz");
}

#[test]
fn symmetry_is_a_boundary_of_planar_scenes_too() {
    let s = load(&MIN.replace("x_min: NoSlip", "x_min: Symmetry")).unwrap();
    assert_eq!(s.boundaries.x_min, Boundary::Symmetry);
}

#[test]
fn sides_know_their_axis_and_partner() {
    assert_eq!(Side::of(2), &Side::ALL);
    assert_eq!(Side::of(3).len(), 6);
    for s in Side::ALL3 {
        assert_eq!(Side::normal_to(s.axis(), s.is_upper()), s);
        assert_eq!(s.opposite().opposite(), s);
        assert_eq!(s.opposite().axis(), s.axis());
    }
    assert_eq!(Side::ZMin.opposite(), Side::ZMax);
    assert_eq!(Side::ZMax.field_name(), "z_max");
}
