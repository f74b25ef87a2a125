//! `efsi plot DIR`: the probe time series and a field at an output time as PNGs of the
//! documented sizes, with something drawn on them; bad requests are refused by name.

mod common;

use common::{efsi, tmp};
use std::path::Path;

/// A viscous drop falling in an axisymmetric box, VTK as Float32 + zlib.
const DROP: &str = r#"Scene(
    name: "plot_drop",
    geometry: Axisymmetric,
    domain: (r: (0.0, 1.0), z: (0.0, 2.0)),
    grid: (nr: 16, nz: 32),
    time: (end: 0.2),
    fluid: (density: 1.0, viscosity: 0.05),
    gravity: (0.0, -1.0),
    solid: (shape: Disk(center: (0.0, 1.2), radius: 0.4), density: 2.0, viscosity: 0.1),
    boundaries: (r_min: Axis, r_max: NoSlip, z_min: NoSlip, z_max: NoSlip),
    output: (vtk_every: 0.1, probe_every: 0.02,
             probes: [KineticEnergy, SolidCentroid, SolidVelocity, MaxSpeed],
             vtk: (precision: Float32, compression: Zlib)),
)
"#;

/// The number of pixels of colour `rgb`.
fn count(path: &Path, rgb: [u8; 3]) -> usize {
    let img = image::open(path).unwrap().to_rgb8();
    img.pixels().filter(|p| p.0 == rgb).count()
}

/// A lid-driven cavity whose corners make the pressure's range a thousand times its interior's.
const CAVITY: &str = r#"Scene(
    name: "plot_cavity",
    domain: (x: (0.0, 1.0), y: (0.0, 1.0)),
    grid: (nx: 24, ny: 24),
    time: (end: 0.5),
    fluid: (density: 1.0, viscosity: 0.01),
    boundaries: (x_min: NoSlip, x_max: NoSlip, y_min: NoSlip, y_max: MovingWall(speed: 1.0)),
    output: (vtk_every: 0.5, probe_every: 0.05, probes: [KineticEnergy]),
)
"#;

/// A fluid scene's default picture is its velocity magnitude with arrows (no contour); the
/// pressure's colour range is its 1st–99th percentile, not the lid corners' spikes.
#[test]
fn a_fluid_scene_shows_its_velocity_with_arrows() {
    let d = tmp("cavity");
    let scene = d.join("cavity.ron");
    std::fs::write(&scene, CAVITY).unwrap();
    let run = d.join("run");
    let o = efsi(&[
        "run",
        scene.to_str().unwrap(),
        "--out",
        run.to_str().unwrap(),
        "-q",
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let o = efsi(&["plot", run.to_str().unwrap()]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let field = run.join("plots/velocity_t0.5.png");
    let (w, h, coloured, colours) = inspect(&field);
    assert_eq!((w, h), (900, 900));
    assert!(coloured > 0.3 && colours > 20, "{coloured} {colours}");
    assert_eq!(count(&field, [230, 30, 30]), 0, "no solid, no contour");
    // The pressure: a spread of colours, not one colour for the interior.
    let o = efsi(&["plot", run.to_str().unwrap(), "--field", "pressure"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let (_, _, _, colours) = inspect(&run.join("plots/pressure_t0.5.png"));
    assert!(colours > 40, "{colours} colours");
    std::fs::remove_dir_all(&d).unwrap();
}

/// Width, height, the share of non-white pixels and the number of distinct colours.
fn inspect(path: &Path) -> (u32, u32, f64, usize) {
    let img = image::open(path)
        .unwrap_or_else(|e| panic!("{}: {e}", path.display()))
        .to_rgb8();
    let (w, h) = img.dimensions();
    let coloured = img.pixels().filter(|p| p.0 != [255, 255, 255]).count();
    let mut colours: Vec<[u8; 3]> = img.pixels().map(|p| p.0).collect();
    colours.sort_unstable();
    colours.dedup();
    (w, h, coloured as f64 / (w * h) as f64, colours.len())
}

#[test]
fn plot_writes_probe_and_field_pngs() {
    let d = tmp("drop");
    let scene = d.join("drop.ron");
    std::fs::write(&scene, DROP).unwrap();
    let run = d.join("run");
    let o = efsi(&[
        "run",
        scene.to_str().unwrap(),
        "--out",
        run.to_str().unwrap(),
        "-q",
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));

    let o = efsi(&["plot", run.to_str().unwrap()]);
    let out = String::from_utf8_lossy(&o.stdout);
    assert!(
        o.status.success(),
        "{out}{}",
        String::from_utf8_lossy(&o.stderr)
    );
    // Six probe columns (kinetic energy, x, y, u, v, max speed): three rows of two panels.
    let (w, h, coloured, colours) = inspect(&run.join("plots/probes.png"));
    assert_eq!((w, h), (1200, 3 * 300));
    assert!(coloured > 0.02 && colours > 3, "{coloured} {colours}");
    // The default picture, at the last output time: the velocity magnitude with its arrows
    // (white) and the solid's φ = ½ contour (red) over it.
    let field = run.join("plots/velocity_t0.2.png");
    assert!(out.contains(&field.display().to_string()), "{out}");
    let (w, h, coloured, colours) = inspect(&field);
    assert_eq!((w, h), (900, 900));
    assert!(coloured > 0.3 && colours > 20, "{coloured} {colours}");
    let contour = count(&field, [230, 30, 30]);
    assert!(contour > 200, "{contour} contour pixels");

    // A chosen field, component and time (the nearest output time, 0.1).
    let o = efsi(&[
        "plot",
        run.to_str().unwrap(),
        "--field",
        "velocity",
        "--component",
        "2",
        "--time",
        "0.09",
        "--out",
        d.join("p").to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let (w, h, coloured, colours) = inspect(&d.join("p/velocity_t0.1.png"));
    assert_eq!((w, h), (900, 900));
    assert!(coloured > 0.3 && colours > 20, "{coloured} {colours}");

    // Bad requests: named, exit code 2.
    for (args, needle) in [
        (vec!["--field", "temperature"], "no field `temperature`"),
        (
            vec!["--field", "velocity", "--component", "3"],
            "has 3 component(s)",
        ),
    ] {
        let mut a = vec!["plot", run.to_str().unwrap()];
        a.extend(args);
        let o = efsi(&a);
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{err}");
        assert!(err.contains(needle), "{err}");
    }
    let o = efsi(&["plot", d.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("not an efsi output folder"));
    std::fs::remove_dir_all(&d).unwrap();
}
