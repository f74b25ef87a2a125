//! Three-dimensional fluid runs end to end (issue 40): a planar flow extruded along a periodic z
//! reproduces the planar run, and the lid-driven cube keeps the mirror symmetry of its set-up.
//! The cube against Albensoeder & Kuhlmann (2005) at 32³–96³ is `cargo xtask bench-paper`'s.

use efsi_core::{Scene, Simulation};
use efsi_run::probes::{sample, sample3};
use efsi_tests::run_to_steady;
use std::path::Path;

/// A simulation of the scene `text` with the built-in stages.
fn simulation(text: &str) -> Simulation {
    let path = Path::new("three_d.ron");
    let scene = Scene::from_str_at(text, path).unwrap_or_else(|e| panic!("{e}"));
    efsi_run::simulation(scene, path, &efsi_stages::builtin()).unwrap_or_else(|e| panic!("{e}"))
}

/// The Re = 100 lid-driven cavity at `n`² cells in `geometry` (the lid along +x at y = 1), with
/// the third axis' domain, cells and sides as written (empty in two dimensions).
fn cavity(geometry: &str, n: usize, domain_z: &str, grid_z: &str, sides_z: &str) -> String {
    format!(
        "Scene(name: \"cavity\", geometry: {geometry},
            domain: (x: (0.0, 1.0), y: (0.0, 1.0){domain_z}),
            grid: (nx: {n}, ny: {n}{grid_z}),
            time: (end: 1.0, cfl: 0.5),
            fluid: (density: 1.0, viscosity: 0.01),
            numerics: (projection: (tolerance: 1e-10)),
            boundaries: (x_min: NoSlip, x_max: NoSlip, y_min: NoSlip,
                         y_max: MovingWall(speed: 1.0){sides_z}))"
    )
}

#[test]
fn a_planar_cavity_extruded_along_a_periodic_z_reproduces_the_planar_run() {
    let n = 16;
    let mut planar = simulation(&cavity("Planar", n, "", "", ""));
    let mut extruded = simulation(&cavity(
        "Cartesian3D",
        n,
        ", z: (0.0, 0.25)",
        ", nz: 4",
        ", z_min: Periodic, z_max: Periodic",
    ));
    let t = 0.5;
    run_to_steady(&mut planar, t);
    run_to_steady(&mut extruded, t);
    let (mut du, mut w) = (0.0f64, 0.0f64);
    for k in 0..=16 {
        let s = k as f64 / 16.0;
        for z in [0.03125, 0.1, 0.21875] {
            for (f, at) in [("u", (0.5, s)), ("v", (s, 0.5))] {
                let d = sample3(&extruded.grid, &extruded.state, f, [at.0, at.1, z])
                    - sample(&planar.grid, &planar.state, f, at);
                du = du.max(d.abs());
            }
            w = w.max(sample3(&extruded.grid, &extruded.state, "w", [0.5, s, z]).abs());
        }
    }
    eprintln!(
        "extruded vs planar cavity, {n}² × 4, t = {t}: max |Δu|, |Δv| = {du:.3e}, max |w| = {w:.3e}"
    );
    assert!(
        du <= 1e-9,
        "the extruded run departs from the planar one by {du:e}"
    );
    assert!(w <= 1e-10, "w = {w:e} in a flow without z motion");
}

#[test]
fn the_lid_driven_cube_is_mirror_symmetric_about_its_mid_plane() {
    let n = 12;
    let mut sim = simulation(&cavity(
        "Cartesian3D",
        n,
        ", z: (0.0, 1.0)",
        &format!(", nz: {n}"),
        ", z_min: NoSlip, z_max: NoSlip",
    ));
    run_to_steady(&mut sim, 0.5);
    let (g, s) = (&sim.grid, &sim.state);
    let (mut asym, mut scale, mut w_max) = (0.0f64, 0.0f64, 0.0f64);
    for i in 1..12 {
        for j in 1..12 {
            let (x, y) = (i as f64 / 12.0, j as f64 / 12.0);
            for z in [0.1, 0.25, 0.4] {
                for (f, sign) in [("u", 1.0), ("v", 1.0), ("w", -1.0)] {
                    let a = sample3(g, s, f, [x, y, z]);
                    let b = sample3(g, s, f, [x, y, 1.0 - z]);
                    asym = asym.max((a - sign * b).abs());
                    scale = scale.max(a.abs());
                }
                w_max = w_max.max(sample3(g, s, "w", [x, y, z]).abs());
            }
        }
    }
    let div = efsi_run::probes::max_divergence(g, s) * sim.state.dt_prev;
    eprintln!(
        "cube {n}³, t = 0.5: largest mirror asymmetry {asym:.3e} of velocities up to {scale:.3e}, \
         max |w| = {w_max:.3e}, max |∇·V|·Δt = {div:.3e}"
    );
    assert!(scale > 0.1, "the lid drives no flow: {scale}");
    assert!(w_max > 1e-3, "no flow across the planes: max |w| = {w_max}");
    assert!(asym <= 1e-10 * scale, "asymmetry {asym:e}");
    assert!(div <= 1e-9, "max |∇·V|·Δt = {div:e}");
}

/// The seed's sphere in three dimensions (`cases/sphere_impact_3d.ron`, the quarter domain) at
/// 10 cells per radius, released 4 mm above the substrate at the speed it strikes it with in
/// the full run (1.48 m/s), to 20 ms: the impact, the rebound and the sphere leaving the
/// substrate. At every 0.2 ms (the scene's probe interval, on which the steps land) the solid
/// is one piece: its largest connected piece holds at least 99.9 % of its volume and no second
/// piece holds more than 1e-3 of it. Where the surface is oblique to the grid along an edge
/// family (the diagonal x = z, whose normal lies half along the edges parallel to x and to
/// z), the edges joining the surface cells to the bulk take the closure of their midpoint
/// sections ("Edges in three dimensions" in the elastic stage's docs); a surface left without
/// shear to the bulk stays behind on the substrate as a ligament.
#[test]
fn the_sphere_in_three_dimensions_stays_one_piece_through_its_rebound() {
    use efsi_run::probes::solid_pieces;
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../cases/sphere_impact_3d.ron");
    let mut text = std::fs::read_to_string(&path).unwrap();
    for (from, to) in [
        (
            "grid: (nx: 82, ny: 164, nz: 82)",
            "grid: (nx: 23, ny: 47, nz: 23)",
        ),
        ("center: (0.0, 0.0573, 0.0)", "center: (0.0, 0.0232, 0.0)"),
        ("velocity: (0.0, -1.22, 0.0)", "velocity: (0.0, -1.48, 0.0)"),
    ] {
        assert!(text.contains(from), "the scene has no `{from}`");
        text = text.replace(from, to);
    }
    let mut scene = Scene::from_str_at(&text, &path).unwrap_or_else(|e| panic!("{e}"));
    scene.source_dir = path.parent().map(Path::to_path_buf);
    scene.output = Default::default();
    let mut sim = efsi_run::simulation(scene, &path, &efsi_stages::builtin())
        .unwrap_or_else(|e| panic!("{e}"));
    let (mut least, mut most, mut at) = (1.0f64, 0, 0.0);
    for k in 1..=100 {
        let t = 2e-4 * k as f64;
        efsi_tests::run_until(&mut sim, t, |_, _| {});
        let phi = sim.state.phi.as_ref().expect("a solid fraction");
        let p = solid_pieces(&sim.grid, phi);
        if p.largest < least {
            (least, at) = (p.largest, t);
        }
        most = most.max(p.count);
    }
    eprintln!(
        "largest piece at least {least:.6} of the volume (t = {at:.4} s), at most {most} pieces"
    );
    assert!(
        least >= 0.999,
        "the largest piece held only {least:.6} of the volume at t = {at:.4} s"
    );
    assert_eq!(
        most, 1,
        "the solid broke into {most} pieces above 1e-3 of its volume"
    );
}
