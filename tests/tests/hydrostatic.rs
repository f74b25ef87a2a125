//! Gravity in the seed's (non-incremental) scheme: the carrier fluid's hydrostatic pressure is
//! carried by the pressure, not by the body force (`efsi_stages::projection`, module
//! `hydrostatic`), so the viscous step never shears it at no-slip walls. A fluid at rest stays at
//! rest to the last bit (planar, axisymmetric, three-dimensional, in an accelerating frame, open
//! at the top) with the whole hydrostatic pressure in `p`; a soft disk released near the floor
//! settles and the flow comes to rest.

use efsi_core::{Field, Grid, Simulation, operators};
use efsi_stages::body_force::FrameAcceleration;
use efsi_tests::run_until;
use std::path::Path;

/// A simulation of `text`, its laws found as the shipped cases' are.
fn simulation(text: &str) -> Simulation {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../cases/hydrostatic.ron");
    let mut scene = efsi_core::Scene::from_str_at(text, &path).unwrap_or_else(|e| panic!("{e}"));
    scene.source_dir = path.parent().map(Path::to_path_buf);
    efsi_run::simulation(scene, &path, &efsi_stages::builtin()).unwrap_or_else(|e| panic!("{e}"))
}

/// The largest |velocity| on any face of the grid (ghosts included).
fn fastest(sim: &Simulation) -> f64 {
    let s = &sim.state;
    [Some(&s.u), Some(&s.v), s.w.as_ref()]
        .into_iter()
        .flatten()
        .flat_map(|f: &Field| f.data().iter())
        .fold(0.0f64, |m, x| m.max(x.abs()))
}

/// `p` at cell `(i, j)` (of the first layer in three dimensions).
fn at(p: &Field, i: isize, j: isize) -> f64 {
    p.data()[p.idx3([i, j, 0])]
}

/// The kinetic energy of the flow (per radian in axisymmetric geometry).
fn kinetic_energy(grid: &Grid, sim: &Simulation) -> f64 {
    operators::kinetic_energy(grid, &sim.state.velocity(), &sim.state.rho)
}

/// A tank of one fluid (density 2) at rest under gravity, the seed's scheme.
fn tank(geometry: &str, sides: &str, gravity: &str, extra: &str) -> String {
    format!(
        r#"Scene(
    name: "tank",
    geometry: {geometry},
    domain: (x: (0.0, 1.0), y: (0.0, 1.0){extra}),
    grid: (nx: 16, ny: 16{grid_z}),
    time: (end: 1.0, cfl: 0.4),
    fluid: (density: 2.0, viscosity: 0.01),
    gravity: {gravity},
    numerics: (projection: (incremental: false)),
    boundaries: ({sides}),
)"#,
        grid_z = if extra.is_empty() { "" } else { ", nz: 8" },
    )
}

/// A viscous fluid at rest under gravity with the seed's scheme stays at rest to the last bit,
/// step after step, and its pressure is the hydrostatic one: closed and open at the top, planar,
/// axisymmetric and three-dimensional, and in a frame accelerating sideways and up. (Before the
/// split, the viscous step sheared the body force's `gΔt` at the side walls and the energy guard
/// stopped the planar tank in its first step.)
#[test]
fn a_fluid_at_rest_under_gravity_stays_at_rest_in_the_seeds_scheme() {
    let closed = "x_min: NoSlip, x_max: NoSlip, y_min: NoSlip, y_max: NoSlip";
    let open = "x_min: NoSlip, x_max: NoSlip, y_min: NoSlip, y_max: Outflow";
    let axi = "x_min: Axis, x_max: NoSlip, y_min: NoSlip, y_max: NoSlip";
    let box3 =
        "x_min: NoSlip, x_max: NoSlip, y_min: NoSlip, y_max: NoSlip, z_min: NoSlip, z_max: NoSlip";
    let g2 = "(0.0, -9.81)";
    let cases = [
        ("closed", tank("Planar", closed, g2, ""), (0.0, 0.0)),
        ("open", tank("Planar", open, g2, ""), (0.0, 0.0)),
        (
            "axisymmetric",
            tank("Axisymmetric", axi, g2, ""),
            (0.0, 0.0),
        ),
        ("accelerating", tank("Planar", closed, g2, ""), (2.0, 3.0)),
        (
            "three-dimensional",
            tank("Cartesian3D", box3, "(1.0, -9.81, 2.0)", ", z: (0.0, 0.5)"),
            (0.0, 0.0),
        ),
    ];
    for (name, text, a) in cases {
        let mut s = simulation(&text);
        if a != (0.0, 0.0) {
            s.set_frame_acceleration(a).unwrap();
        }
        let mut steps = 0;
        let mut worst = 0.0f64;
        run_until(&mut s, 1.0, |s, _| {
            steps += 1;
            worst = worst.max(fastest(s));
        });
        assert!(steps >= 20, "{name}: {steps} steps");
        assert_eq!(worst, 0.0, "{name}: the fluid moved at {worst:e}");
        // The pressure is the hydrostatic one, ρ (g − a)·x up to a constant: between the
        // bottom and the top rows of cells, and (sideways gravity in the frame) across a row.
        let (g, p) = (&s.grid, &s.state.p);
        let e = [1.0 - a.0, -9.81 - a.1];
        let top = (g.ny - 1) as isize;
        let rise = at(p, 0, top) - at(p, 0, 0);
        let want = 2.0 * e[1] * (g.yc(top) - g.yc(0));
        assert!(
            (rise - want).abs() < 1e-12 * want.abs(),
            "{name}: p rises by {rise} from the bottom to the top row, hydrostatic {want}"
        );
        if name == "accelerating" {
            let last = (g.nx - 1) as isize;
            let across = at(p, last, 0) - at(p, 0, 0);
            let want = 2.0 * -a.0 * (g.xc(last) - g.xc(0));
            assert!(
                (across - want).abs() < 1e-12 * want.abs(),
                "{name}: p changes by {across} across a row, hydrostatic {want}"
            );
        }
        if name == "open" {
            // p = 0 on the Outflow side: the top row half a cell below it.
            let want = -2.0 * -9.81 * 0.5 * g.dy;
            assert!(
                (at(p, 3, top) - want).abs() < 1e-12,
                "open: p = {}",
                at(p, 3, top)
            );
        }
    }
}

/// A soft neo-Hookean disk (the twenty disks' soft material: density 1.5, G = 1) released at
/// rest 1.3 cells above the floor of a closed box settles on it and the flow comes to rest: the
/// kinetic energy after t = 3.5 stays below 1e-3 of its peak (before the split the
/// viscous step's shear of the carrier's `gΔt` at the walls kept a circulation of 0.6 of the
/// peak).
#[test]
fn a_soft_disk_released_at_rest_near_the_floor_settles() {
    let text = r#"Scene(name: "disk", domain: (x: (0.0, 1.0), y: (0.0, 1.0)), grid: (nx: 32, ny: 32),
        time: (end: 4.0, cfl: 0.4),
        fluid: (density: 1.0, viscosity: 0.01), gravity: (0.0, -1.0),
        solids: [(name: "soft", shape: Disk(center: (0.5, 0.19), radius: 0.15), density: 1.5,
            viscosity: 0.01, law: (name: "neo_hookean", parameters: {"G": 1.0}))],
        boundaries: (x_min: NoSlip, x_max: NoSlip, y_min: NoSlip, y_max: NoSlip))"#;
    let mut s = simulation(text);
    let grid = s.grid.clone();
    let mut peak = 0.0f64;
    let mut late = 0.0f64;
    run_until(&mut s, 4.0, |s, _| {
        let ke = kinetic_energy(&grid, s);
        peak = peak.max(ke);
        if s.state.t > 3.5 {
            late = late.max(ke);
        }
    });
    eprintln!(
        "soft disk: kinetic energy peak {peak:.3e}, largest after t = 3.5 {late:.3e}, ratio {:.2e}",
        late / peak
    );
    assert!(peak > 5e-5, "the disk barely fell: peak {peak:e}");
    assert!(
        late < 1e-3 * peak,
        "not at rest: {late:e} after t = 3.5, peak {peak:e}"
    );
}
