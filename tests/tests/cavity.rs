//! Lid-driven cavity against Ghia, Ghia & Shin (1982), from the shipped case files at reduced
//! resolution (the full-resolution comparison is `cargo xtask bench-paper`, and the figures
//! are in the foundation issue's closing note).

use efsi_core::{Scene, Simulation};
use efsi_run::SceneOverrides;
use efsi_run::probes::sample;
use efsi_tests::{interp, read_csv, reference, run_to_steady};
use std::path::Path;

/// Max |deviation| of u on x = 0.5 and v on y = 0.5 from Ghia's tables.
fn ghia_deviation(sim: &Simulation, re: u32) -> (f64, f64) {
    let (h, c) = read_csv(&reference(
        "ghia1982/ghia1982_u_vertical_centerline_x0.5.csv",
    ));
    let col = h.iter().position(|n| *n == format!("u_Re{re}")).unwrap();
    let yi = h.iter().position(|n| n == "y").unwrap();
    let du = c[yi]
        .iter()
        .zip(&c[col])
        .map(|(&y, &u)| (sample(&sim.grid, &sim.state, "u", (0.5, y)) - u).abs())
        .fold(0.0, f64::max);
    let (h, c) = read_csv(&reference(
        "ghia1982/ghia1982_v_horizontal_centerline_y0.5.csv",
    ));
    let col = h.iter().position(|n| *n == format!("v_Re{re}")).unwrap();
    let xi = h.iter().position(|n| n == "x").unwrap();
    let dv = c[xi]
        .iter()
        .zip(&c[col])
        .map(|(&x, &v)| (sample(&sim.grid, &sim.state, "v", (x, 0.5)) - v).abs())
        .fold(0.0, f64::max);
    (du, dv)
}

fn case(name: &str, n: usize) -> Simulation {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../cases")
        .join(name);
    let mut scene = Scene::load(&path).unwrap_or_else(|e| panic!("{e}"));
    scene.grid.nx = n;
    scene.grid.ny = n;
    efsi_run::simulation(scene, &path, &efsi_stages::builtin()).unwrap_or_else(|e| panic!("{e}"))
}

#[test]
fn cavity_re100_at_32_cells_matches_ghia() {
    let mut sim = case("lid_driven_cavity_re100.ron", 32);
    let end = sim.scene.time.end;
    let t = run_to_steady(&mut sim, end);
    let (du, dv) = ghia_deviation(&sim, 100);
    eprintln!(
        "Re = 100, 32²: steady at t = {t:.2}, max |u − Ghia| = {du:.4}, max |v − Ghia| = {dv:.4}"
    );
    assert!(sim.is_steady(), "not steady by t = {t}");
    assert!(du <= 0.02 && dv <= 0.02, "deviation u {du}, v {dv}");
}

#[test]
fn centreline_interpolation_helper_is_linear() {
    assert_eq!(interp(&[0.0, 1.0, 2.0], &[0.0, 10.0, 0.0], 1.5), 5.0);
}
