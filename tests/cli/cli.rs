//! The `efsi` command end to end: bad input is refused with exit code 2 and a message naming
//! the file and line:column or the field; `check`, `--print-schedule` and `run` outputs.

mod common;

use common::{efsi, tmp};
use std::path::Path;

const GOOD: &str = r#"Scene(
    name: "tiny_cavity",
    domain: (x: (0.0, 1.0), y: (0.0, 1.0)),
    grid: (nx: 8, ny: 8),
    time: (end: 0.5),
    fluid: (density: 1.0, viscosity: 0.01),
    boundaries: (x_min: NoSlip, x_max: NoSlip, y_min: NoSlip, y_max: MovingWall(speed: 1.0)),
    output: (
        vtk_every: 0.25,
        probe_every: 0.1,
        probes: [Point(name: "u_c", field: "u", at: (0.5, 0.5)), KineticEnergy],
        profiles: [Line(name: "u_x0.5", from: (0.5, 0.0), to: (0.5, 1.0), points: 11, fields: ["u", "p"])],
    ),
)
"#;

fn write_scene(dir: &Path, text: &str) -> String {
    let p = dir.join("scene.ron");
    std::fs::write(&p, text).unwrap();
    p.display().to_string()
}

/// Run `efsi check` on a mutated scene: exit code 2 and every `needle` in the message.
fn refused(name: &str, text: &str, needles: &[&str]) {
    let d = tmp(name);
    let path = write_scene(&d, text);
    for args in [
        vec!["check", path.as_str()],
        vec!["run", path.as_str(), "-q"],
    ] {
        let out = efsi(&args);
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{name}: {args:?}: {err}");
        for n in needles {
            assert!(err.contains(n), "{name}: expected `{n}` in: {err}");
        }
        assert!(!err.contains("panicked"), "{err}");
    }
}

#[test]
fn malformed_ron_names_file_line_and_column() {
    refused(
        "malformed",
        &GOOD.replace("grid: (nx: 8, ny: 8),", "grid: (nx: 8 ny: 8),"),
        &["scene.ron:4:"],
    );
}

#[test]
fn unknown_field_is_named_with_its_position() {
    refused(
        "unknown",
        &GOOD.replace("viscosity: 0.01)", "viscosity: 0.01, temperature: 300.0)"),
        &["scene.ron:6:", "temperature", "expected"],
    );
}

#[test]
fn negative_viscosity_is_refused_by_name() {
    refused(
        "viscosity",
        &GOOD.replace("viscosity: 0.01", "viscosity: -0.01"),
        &["fluid.viscosity", "≥ 0", "-0.01"],
    );
}

#[test]
fn zero_cells_is_refused_by_name() {
    refused(
        "cells",
        &GOOD.replace("nx: 8,", "nx: 0,"),
        &["grid.nx", "at least 1"],
    );
}

#[test]
fn periodic_side_without_partner_is_refused() {
    refused(
        "periodic",
        &GOOD.replace("x_min: NoSlip", "x_min: Periodic"),
        &["boundaries.x_min", "partner", "boundaries.x_max"],
    );
}

#[test]
fn non_positive_end_time_is_refused() {
    for end in ["0.0", "-1.0"] {
        refused(
            "end",
            &GOOD.replace("end: 0.5", &format!("end: {end}")),
            &["time.end", "> 0"],
        );
    }
}

/// A lid-driven cube at Re = 100 on 16³ cells.
const CUBE: &str = r#"Scene(
    name: "lid_driven_cube",
    geometry: Cartesian3D,
    domain: (x: (0.0, 1.0), y: (0.0, 1.0), z: (0.0, 1.0)),
    grid: (nx: 16, ny: 16, nz: 16),
    time: (end: 1.0, cfl: 0.5),
    fluid: (density: 1.0, viscosity: 0.01),
    boundaries: (x_min: NoSlip, x_max: NoSlip, y_min: NoSlip, y_max: MovingWall(speed: 1.0),
                 z_min: NoSlip, z_max: NoSlip),
    output: (probes: [Point(name: "u_c", field: "u", at: (0.5, 0.5, 0.5)), KineticEnergy, MaxDivergence],
             profiles: [Line(name: "u_x", from: (0.5, 0.0, 0.5), to: (0.5, 1.0, 0.5), points: 17, fields: ["u", "w"])]),
)
"#;

#[test]
fn a_lid_driven_cube_and_an_elastic_ball_check_and_what_stays_planar_is_refused() {
    // Scene, grid and boundaries are read in three dimensions and the fluid stages run there.
    let d = tmp("cube_ok");
    let path = write_scene(&d, CUBE);
    let out = efsi(&["check", &path]);
    let said = String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success(), "{said}");
    assert!(
        said.contains("three-dimensional 16×16×16 cells")
            && said.contains("advection → pressure_predictor → viscous → projection"),
        "{said}"
    );
    // An elastic solid runs in three dimensions: the VOF stage and the implicit-momentum
    // stage's sub-steps (elastic, deformation) in the schedule, and its strain-energy probe.
    let ball = CUBE.replace(
        "    boundaries:",
        "    solid: (shape: Sphere(center: (0.5, 0.5, 0.5), radius: 0.2), density: 2.0,\n\
         \x20          law: (name: \"neo_hookean\", parameters: {\"G\": 10.0})),\n    boundaries:",
    );
    let d = tmp("cube_with_solid");
    let out = efsi(&["check", &write_scene(&d, &ball)]);
    let said = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "{said}{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(
        said.contains("three-dimensional 16×16×16 cells")
            && said.contains("advection → viscous → elastic → projection → deformation → vof"),
        "{said}"
    );
    let d = tmp("cube_with_solid_energy");
    let energy = ball.replace("KineticEnergy,", "KineticEnergy, ElasticEnergy,");
    assert!(energy.contains("ElasticEnergy"));
    let out = efsi(&["check", &write_scene(&d, &energy)]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    // The seven-point pressure matrix has no Dirichlet face: an Outflow side is refused by name.
    refused(
        "cube_with_outflow",
        &CUBE.replace("x_max: NoSlip", "x_max: Outflow"),
        &["boundaries.x_max", "Outflow is two-dimensional", "Symmetry"],
    );
    refused(
        "cube_with_outflow_top",
        &CUBE.replace("z_max: NoSlip", "z_max: Outflow"),
        &["boundaries.z_max", "Outflow is two-dimensional"],
    );
    // Mixing two- and three-dimensional keys is refused by name.
    refused(
        "cube_without_nz",
        &CUBE.replace(", nz: 16", ""),
        &["grid.nz", "missing"],
    );
    refused(
        "planar_with_z_min",
        &GOOD.replace(
            "MovingWall(speed: 1.0)",
            "MovingWall(speed: 1.0), z_min: NoSlip",
        ),
        &["boundaries.z_min", "Cartesian3D"],
    );
}

#[test]
fn missing_scene_file_is_reported() {
    let out = efsi(&["check", "/nonexistent/scene.ron"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("/nonexistent/scene.ron"));
}

#[test]
fn check_and_print_schedule() {
    let d = tmp("check");
    let path = write_scene(&d, GOOD);
    let out = efsi(&["check", &path]);
    assert!(out.status.success());
    assert!(
        String::from_utf8_lossy(&out.stdout)
            .contains("advection → pressure_predictor → viscous → projection")
    );
    let out = efsi(&["run", &path, "--print-schedule"]);
    let s = String::from_utf8_lossy(&out.stdout);
    let stages: Vec<&str> = s
        .lines()
        .filter(|l| l.contains("phase"))
        .map(|l| l.split_whitespace().nth(1).unwrap())
        .collect();
    assert_eq!(
        stages,
        ["advection", "pressure_predictor", "viscous", "projection"]
    );
    // Each stage names the type that implements it, and the section of its options.
    assert!(
        s.contains("(efsi_stages::viscous::Viscous)")
            && s.contains("(efsi_stages::projection::Projection)"),
        "{s}"
    );
    assert!(
        s.lines()
            .any(|l| l.contains(" viscous ") && l.contains("options numerics.viscous")),
        "{s}"
    );
}

#[test]
fn run_writes_fields_probes_profiles_and_summary() {
    let d = tmp("run");
    let path = write_scene(&d, GOOD);
    let out_dir = d.join("out");
    let out = efsi(&["run", &path, "--out", out_dir.to_str().unwrap(), "-q"]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    // VTK: t = 0, 0.25, 0.5 and their collection.
    let pvd = std::fs::read_to_string(out_dir.join("fields.pvd")).unwrap();
    assert_eq!(pvd.matches("<DataSet").count(), 3, "{pvd}");
    let vtrs = std::fs::read_dir(out_dir.join("fields")).unwrap().count();
    assert_eq!(vtrs, 3);
    // Probes: header and samples at t = 0, 0.1, …, 0.5.
    let probes = std::fs::read_to_string(out_dir.join("probes.csv")).unwrap();
    let mut lines = probes.lines();
    assert_eq!(lines.next().unwrap(), "t,u_c,kinetic_energy");
    let times: Vec<f64> = lines
        .map(|l| l.split(',').next().unwrap().parse().unwrap())
        .collect();
    assert_eq!(times.len(), 6, "{times:?}");
    for (k, t) in times.iter().enumerate() {
        assert!((t - 0.1 * k as f64).abs() < 1e-12, "{times:?}");
    }
    // Profile at the end, with the lid speed at the top.
    let prof = std::fs::read_to_string(out_dir.join("profiles/u_x0.5_t0.5.csv")).unwrap();
    let rows: Vec<&str> = prof.lines().collect();
    assert_eq!(rows[0], "s,x,y,u,p");
    assert_eq!(rows.len(), 12);
    let top_u: f64 = rows[11].split(',').nth(3).unwrap().parse().unwrap();
    assert!(
        (top_u - 1.0).abs() < 1e-12,
        "lid speed on the wall: {top_u}"
    );
    // Summary.
    let json = std::fs::read_to_string(out_dir.join("run.json")).unwrap();
    for key in [
        "\"efsi_version\"",
        "\"scene\"",
        "\"steps\"",
        "\"wall_seconds\"",
        "\"stages\"",
        "\"projection_tolerance\"",
    ] {
        assert!(json.contains(key), "{key} missing from run.json");
    }
    // The peak resident memory: at least the grid's fields, at most what a small run can take.
    if cfg!(target_os = "linux") {
        let j: serde_json::Value = serde_json::from_str(&json).unwrap();
        let rss = j["peak_rss_bytes"]
            .as_f64()
            .expect("peak_rss_bytes on Linux");
        assert!((1e6..1e9).contains(&rss), "peak_rss_bytes {rss}");
    }
}

/// A profile's `at` times are written when reached; when the run stops at a steady state before
/// some of them, the profile is written at the end instead, and the run says so on stderr and in
/// `run.json`.
#[test]
fn profile_past_a_steady_stop_is_written_at_the_end_and_reported() {
    for case in ["end", "steady"] {
        let d = tmp(&format!("late-profile-{case}"));
        let time = if case == "end" {
            "time: (end: 0.5)"
        } else {
            // Steady from the first step (the flow changes by far less than 1e9 per unit
            // time): the run stops at t = Δt.
            "time: (end: 5.0, steady: 1e9)"
        };
        let at = if case == "end" {
            "[0.5, 0.2]"
        } else {
            "[0.2, 0.7, 5.0]"
        };
        let text = GOOD.replace("time: (end: 0.5)", time).replace(
            "points: 11, fields: [\"u\", \"p\"])",
            &format!("points: 11, fields: [\"u\", \"p\"], at: {at})"),
        );
        let path = write_scene(&d, &text);
        let out_dir = d.join("out");
        let out = efsi(&["run", &path, "--out", out_dir.to_str().unwrap(), "-q"]);
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(out.status.success(), "{case}: {err}");
        let json: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(out_dir.join("run.json")).unwrap())
                .unwrap();
        let t_end = json["t_end"].as_f64().unwrap();
        let mut files: Vec<String> = std::fs::read_dir(out_dir.join("profiles"))
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        files.sort();
        let warnings = json["warnings"].as_array().unwrap();
        if case == "end" {
            assert_eq!(json["stop"], "EndTime");
            assert_eq!(files, ["u_x0.5_t0.2.csv", "u_x0.5_t0.5.csv"]);
            assert!(warnings.is_empty(), "{warnings:?}");
            assert!(!err.contains("warning"), "{err}");
            continue;
        }
        assert_eq!(json["stop"], "Steady");
        assert!(t_end < 0.2, "steady at {t_end}");
        let label = efsi_run::run::time_label(t_end);
        assert_eq!(files, [format!("u_x0.5_t{label}.csv")]);
        let rows = std::fs::read_to_string(out_dir.join(format!("profiles/u_x0.5_t{label}.csv")))
            .unwrap()
            .lines()
            .count();
        assert_eq!(rows, 12);
        assert_eq!(warnings.len(), 1, "{warnings:?}");
        let w = warnings[0].as_str().unwrap();
        let want = format!(
            "profile `u_x0.5`: the run ended at t = {label} before its time(s) 0.2, 0.7, 5; written at the end instead"
        );
        assert!(w.starts_with(&want), "{w}");
        assert!(err.contains(&format!("warning: {want}")), "{err}");
    }
}

/// `efsi describe-output DIR` prints run.json's description of the VTK files: axes, units and
/// each array with its components and unit; a folder without run.json is refused.
#[test]
fn describe_output_documents_every_array() {
    let d = tmp("describe");
    let path = write_scene(&d, GOOD);
    let out_dir = d.join("out");
    let o = efsi(&["run", &path, "--out", out_dir.to_str().unwrap(), "-q"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let o = efsi(&["describe-output", out_dir.to_str().unwrap()]);
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(o.status.success(), "{text}");
    for needle in [
        "Float64 arrays, compression None, point data false",
        "geometry: planar: X = x, Y = y",
        "units: the scene's units",
        "velocity (cell; u_x, u_y, 0) [m/s]",
        "pressure (cell; p) [Pa]",
        "divergence (cell; ∇·u) [1/s]",
    ] {
        assert!(text.contains(needle), "`{needle}` missing from:\n{text}");
    }
    // No solid: no solid_fraction, B or stress.
    assert!(
        !text.contains("\nsolid_fraction (") && !text.contains("\nB ("),
        "{text}"
    );
    let o = efsi(&["describe-output", d.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("run.json"));
}
