//! The VOF stage in a Cartesian3D scene: a second fluid runs (the transport, the mixing, the
//! sides), a planar drop extruded along a periodic z falls as the planar one, an elastic solid
//! runs with it, a solid starts with its three-component velocity, and what stays
//! two-dimensional or is not allowed in three is refused by name (a 2-D shape; an initial solid
//! velocity of two components; an elastic solid fewer than five cells across).

use efsi_core::{Scene, Simulation};
use efsi_run::probes::solid_moments;
use efsi_stages::vof::phase_volume;
use std::path::{Path, PathBuf};

/// Why the scene `text` is refused (a panic if it is not).
fn refused(text: &str) -> String {
    match build(text) {
        Ok(_) => panic!("not refused:\n{text}"),
        Err(e) => e,
    }
}

/// A simulation of the scene `text`, or the error building it.
fn build(text: &str) -> Result<Simulation, String> {
    let path = Path::new("vof_stage3d.ron");
    let scene = Scene::from_str_at(text, path).map_err(|e| e.to_string())?;
    efsi_run::simulation(scene, path, &efsi_stages::builtin()).map_err(|e| e.to_string())
}

/// Step `sim` to `end`.
fn run(sim: &mut Simulation, end: f64) {
    while sim.state.t < end - 1e-12 {
        let dt = sim.next_dt(end).unwrap();
        sim.step(dt).unwrap_or_else(|e| panic!("{e}"));
    }
}

/// A dense drop (density 10 in 1) in the unit square, falling under gravity 1: the planar disk,
/// or the cylinder along z of the same section in a slab of two periodic cells along z.
fn drop_scene(three: bool) -> String {
    let (geometry, domain_z, grid_z, shape, gravity, sides_z) = if three {
        (
            "Cartesian3D",
            ", z: (0.0, 0.125)",
            ", nz: 2",
            "Cylinder(center: (0.5, 0.6, 0.0625), radius: 0.2, length: 1.0, axis: Z)",
            "(0.0, -1.0, 0.0)",
            ", z_min: Periodic, z_max: Periodic",
        )
    } else {
        (
            "Planar",
            "",
            "",
            "Disk(center: (0.5, 0.6), radius: 0.2)",
            "(0.0, -1.0)",
            "",
        )
    };
    format!(
        "Scene(name: \"drop\", geometry: {geometry},
            domain: (x: (0.0, 1.0), y: (0.0, 1.0){domain_z}),
            grid: (nx: 16, ny: 16{grid_z}),
            time: (end: 0.3, fixed_dt: 0.01),
            fluid: (density: 1.0, viscosity: 0.01),
            gravity: {gravity},
            numerics: (projection: (tolerance: 1e-12)),
            solid: (shape: {shape}, density: 10.0, viscosity: 0.05),
            boundaries: (x_min: Symmetry, x_max: NoSlip, y_min: NoSlip, y_max: NoSlip{sides_z}))"
    )
}

#[test]
fn a_drop_extruded_along_a_periodic_z_falls_as_the_planar_drop() {
    let mut planar = build(&drop_scene(false)).unwrap();
    let mut slab = build(&drop_scene(true)).unwrap();
    let phi = |s: &Simulation| s.state.phi.clone().expect("a drop");
    let v0 = (
        phase_volume(&planar.grid, &phi(&planar)),
        phase_volume(&slab.grid, &phi(&slab)),
    );
    // The same section: the slab holds the planar area times its depth.
    assert!((v0.1 / 0.125 - v0.0).abs() < 1e-13, "{v0:?}");
    let end = 0.3;
    run(&mut planar, end);
    run(&mut slab, end);
    let (mp, ms) = (
        solid_moments(&planar.grid, &planar.state, &phi(&planar)),
        solid_moments(&slab.grid, &slab.state, &phi(&slab)),
    );
    let fall = 0.6 - mp.centroid[1];
    let dy = (ms.centroid[1] - mp.centroid[1]).abs();
    let dz = (ms.centroid[2] - 0.0625).abs();
    let w = slab
        .state
        .w
        .as_ref()
        .unwrap()
        .data()
        .iter()
        .fold(0.0f64, |m, w| m.max(w.abs()));
    let drift = [
        (phase_volume(&planar.grid, &phi(&planar)) - v0.0).abs() / v0.0,
        (phase_volume(&slab.grid, &phi(&slab)) - v0.1).abs() / v0.1,
    ];
    eprintln!(
        "t = {end}: planar fall {fall:.6}, |Δy| slab − planar {dy:.3e}, |z − z0| {dz:.3e}, \
         max|w| {w:.3e}, volume drift {drift:?}"
    );
    // It falls (free fall 0.045 minus the drag), the slab with it to the difference of the
    // two interface reconstructions (mixed Youngs–centred normals in three dimensions, Youngs'
    // in two), straight down, with no flow along z, and both keep their volume.
    assert!(fall > 0.03 && fall < 0.045, "{fall}");
    assert!(dy < 1e-4 * fall.max(1.0), "{dy:e}");
    assert!(dz < 1e-12 && w < 1e-9, "{dz:e} {w:e}");
    assert!(drift.iter().all(|&d| d < 1e-12), "{drift:?}");
    let (lo, hi) = phi(&slab)
        .data()
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), &f| {
            (l.min(f), h.max(f))
        });
    assert!(lo >= 0.0 && hi <= 1.0, "{lo} {hi}");
}

/// `libefsi_test_law_nan.so`, built next to this test (`target/<profile>/deps` or its parent).
fn a_law() -> PathBuf {
    let file =
        efsi_laws_host::loader::library_file_name("*").replace("efsi_law_*", "efsi_test_law_nan");
    let exe = std::env::current_exe().unwrap();
    let deps = exe.parent().unwrap();
    [deps.to_path_buf(), deps.parent().unwrap().to_path_buf()]
        .iter()
        .map(|d| d.join(&file))
        .find(|p| p.is_file())
        .unwrap_or_else(|| panic!("{file} is not built next to {}", exe.display()))
}

/// A 3-D scene of 8³ cells with the `solid` section `solid`.
fn solid_3d(solid: &str) -> String {
    format!(
        "Scene(name: \"s\", geometry: Cartesian3D,
            domain: (x: (0.0, 1.0), y: (0.0, 1.0), z: (0.0, 1.0)),
            grid: (nx: 8, ny: 8, nz: 8),
            time: (end: 0.1, dt_max: 0.01),
            fluid: (density: 1.0, viscosity: 0.01),
            solid: {solid},
            boundaries: (x_min: NoSlip, x_max: NoSlip, y_min: NoSlip, y_max: NoSlip,
                         z_min: NoSlip, z_max: NoSlip))"
    )
}

#[test]
fn an_elastic_solid_runs_and_what_stays_two_dimensional_is_refused_by_name() {
    let sphere = "Sphere(center: (0.5, 0.5, 0.5), radius: 0.25)";
    // A drop runs.
    let drop = format!("(shape: {sphere}, density: 2.0)");
    if let Err(e) = build(&solid_3d(&drop)) {
        panic!("a 3-D drop is refused: {e}");
    }
    // An elastic solid runs in three dimensions (the VOF and the implicit-momentum stages):
    // a ball six cells across (radius 0.375 on 8³) takes steps and stays at rest in a fluid at
    // rest. One four cells across (radius 0.25) is refused by the elastic stage's floor.
    let elastic = |radius: f64| {
        format!(
            "(shape: Sphere(center: (0.5, 0.5, 0.5), radius: {radius}), density: 1.0, \
             law: (name: \"{}\", parameters: {{\"G\": 5.0}}))",
            a_law().display()
        )
    };
    let mut sim = build(&solid_3d(&elastic(0.375)))
        .unwrap_or_else(|e| panic!("a 3-D elastic solid is refused: {e}"));
    run(&mut sim, 0.05);
    let s = &sim.state;
    let w = s.w.as_ref().expect("a 3-D state has w");
    let speed = [&s.u, &s.v, w]
        .iter()
        .flat_map(|f| f.data())
        .fold(0.0_f64, |m, x| m.max(x.abs()));
    assert!(
        s.t >= 0.05 - 1e-12 && speed < 1e-12,
        "t {} |V| {speed:e}",
        s.t
    );
    let e = refused(&solid_3d(&elastic(0.25)));
    assert!(
        e.contains("solid.shape") && e.contains("cells across"),
        "{e}"
    );
    // A two-dimensional shape in a three-dimensional scene, and the mix of both.
    let disk = "(shape: Disk(center: (0.5, 0.5), radius: 0.25), density: 2.0)";
    let e = refused(&solid_3d(disk));
    assert!(e.contains("solid.shape") && e.contains("Sphere"), "{e}");
    let mixed =
        format!("(shape: Union([{sphere}, Disk(center: (0.5, 0.5), radius: 0.25)]), density: 2.0)");
    let e = refused(&solid_3d(&mixed));
    assert!(e.contains("solid.shape"), "{e}");
    // The section's velocity has one component per axis: two are refused in 3-D.
    let moving = format!("(shape: {sphere}, density: 2.0, velocity: (0.0, -1.0))");
    let e = refused(&solid_3d(&moving));
    assert!(e.contains("solid.velocity"), "{e}");
    // A solid cannot leave through an Outflow side.
    let text = solid_3d(&drop).replace("z_max: NoSlip", "z_max: Outflow");
    let e = refused(&text);
    assert!(e.contains("z_max") && e.contains("Outflow"), "{e}");
}

/// A dense sphere (1000 in 1) given an initial velocity of three components starts with it:
/// the faces it covers take the solid's velocity, the interface faces the mixture's, so the
/// solid's mean velocity is the given one less the fluid's share (within 5e-3, every
/// component in the same ratio); a 2-D velocity in a 3-D scene is refused naming the
/// components.
#[test]
fn a_solid_starts_with_its_three_component_velocity() {
    let given = [0.2, -0.4, 0.3];
    let solid = format!(
        "(shape: Sphere(center: (0.5, 0.5, 0.5), radius: 0.25), density: 1000.0, \
         velocity: ({}, {}, {}))",
        given[0], given[1], given[2]
    );
    let sim = build(&solid_3d(&solid)).unwrap_or_else(|e| panic!("{e}"));
    let phi = sim.state.phi.as_ref().expect("a solid");
    let v = solid_moments(&sim.grid, &sim.state, phi).velocity;
    eprintln!("solid velocity after the initial projection: {v:?}");
    // Each component 0.3 % short of the given one (the fluid's share of the interface faces'
    // momentum), all in the same ratio: the direction is the given one.
    let ratio = [0, 1, 2].map(|a| v[a] / given[a]);
    for (a, r) in ratio.iter().enumerate() {
        assert!(
            (r - 1.0).abs() < 5e-3,
            "component {a}: {} against {}",
            v[a],
            given[a]
        );
        assert!((r - ratio[0]).abs() < 1e-9, "{ratio:?}");
    }
    let two = "(shape: Sphere(center: (0.5, 0.5, 0.5), radius: 0.25), density: 2.0, \
               velocity: (0.2, -0.4))";
    let e = refused(&solid_3d(two));
    assert!(
        e.contains("solid.velocity") && e.contains("three components"),
        "{e}"
    );
}
