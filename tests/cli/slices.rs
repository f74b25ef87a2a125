//! Plane slices of a three-dimensional run (`output.slices`) and `efsi plot --slice`: the
//! slice files hold the box's cell values interpolated to the plane, continue across a resume
//! as in one run, are listed by `describe-output`, and are drawn; bad requests are refused by
//! name.

mod common;

use common::{efsi, stderr, tmp};
use efsi_run::output::read::{VtrData, read_pvd, read_vtr};
use std::path::Path;

/// A lid-driven cube of 8³ cells to `end`, its VTK files every 0.1, a slice `z0.5` at the same
/// times (between two cell layers) and a slice `side` (x = 0.3, the pressure only) every 0.05.
fn cube(end: f64) -> String {
    format!(
        r#"Scene(
    name: "slice_cube",
    geometry: Cartesian3D,
    domain: (x: (0.0, 1.0), y: (0.0, 1.0), z: (0.0, 1.0)),
    grid: (nx: 8, ny: 8, nz: 8),
    time: (end: {end:?}),
    fluid: (density: 1.0, viscosity: 0.01),
    boundaries: (x_min: NoSlip, x_max: NoSlip, y_min: NoSlip, y_max: MovingWall(speed: 1.0),
                 z_min: NoSlip, z_max: NoSlip),
    output: (vtk_every: 0.1, probes: [KineticEnergy],
             slices: [(normal: Z, at: 0.5),
                      (name: "side", normal: X, at: 0.3, every: 0.05, fields: ["pressure"])]),
)
"#
    )
}

/// Run `scene` (text) into `dir/run` (`extra` arguments after it); the run folder.
fn run(dir: &Path, name: &str, scene: &str, extra: &[&str]) -> std::path::PathBuf {
    let file = dir.join(format!("{name}.ron"));
    std::fs::write(&file, scene).unwrap();
    let out = dir.join(name);
    let mut args = vec![
        "run",
        file.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "-q",
    ];
    args.extend(extra);
    let o = efsi(&args);
    assert!(o.status.success(), "{}", stderr(&o));
    out
}

/// The slice `z0.5` is the mean of the two cell layers around z = 0.5 of the box's file of the
/// same step, every array, bit for bit, and what `efsi plot --slice z=0.5` draws (the reader's
/// plane); the slice `side` holds the pressure only, on the plane x = 0.3.
#[test]
fn slices_hold_the_box_interpolated_to_the_plane() {
    let d = tmp("slices");
    let out = run(&d, "cube", &cube(0.2), &[]);
    let fields = read_pvd(&out.join("fields.pvd")).unwrap();
    let slices = read_pvd(&out.join("slices/z0.5.pvd")).unwrap();
    let times = |e: &[(f64, std::path::PathBuf)]| e.iter().map(|x| x.0).collect::<Vec<_>>();
    assert_eq!(times(&slices), times(&fields));
    assert_eq!(times(&slices), [0.0, 0.1, 0.2]);
    for ((_, box_file), (_, slice_file)) in fields.iter().zip(&slices) {
        let (b, s) = (read_vtr(box_file).unwrap(), read_vtr(slice_file).unwrap());
        assert!(!s.is_3d());
        assert_eq!(s.coordinates[..2], b.coordinates[..2]);
        assert_eq!(s.coordinates[2], [0.5]);
        assert_eq!(s.cells3(), [8, 8, 1]);
        let names = |d: &VtrData| d.cells.iter().map(|a| a.name.clone()).collect::<Vec<_>>();
        assert_eq!(names(&s), names(&b));
        for a in &b.cells {
            // Cell layers 3 and 4 have their centres at 0.4375 and 0.5625: weight ½ each.
            let c = a.components;
            let layer = |k: usize| &a.values[k * 64 * c..(k + 1) * 64 * c];
            let want: Vec<f64> = layer(3)
                .iter()
                .zip(layer(4))
                .map(|(p, q)| 0.5 * p + 0.5 * q)
                .collect();
            assert_eq!(s.cell(&a.name).unwrap().values, want, "{}", a.name);
        }
        assert_eq!(s, b.plane(2, 0.5).unwrap());
        assert_eq!(s.time, b.time);
    }
    // x = 0.3 lies between the centres 0.1875 and 0.3125 of columns 1 and 2: weight 0.9 on 2.
    let side = read_pvd(&out.join("slices/side.pvd")).unwrap();
    assert_eq!(times(&side), [0.0, 0.05, 0.1, 3.0 * 0.05, 0.2]);
    let (b, s) = (
        read_vtr(&fields[2].1).unwrap(),
        read_vtr(&side[4].1).unwrap(),
    );
    assert_eq!(s.coordinates[0], [0.3]);
    assert_eq!(s.plane_axes(), (1, 2));
    let names: Vec<&str> = s.cells.iter().map(|a| a.name.as_str()).collect();
    assert_eq!(names, ["pressure"]);
    let p = &b.cell("pressure").unwrap().values;
    for (n, got) in s.cell("pressure").unwrap().values.iter().enumerate() {
        let (j, k) = (n % 8, n / 8);
        let at = |i: usize| p[(k * 8 + j) * 8 + i];
        let want = 0.1 * at(1) + 0.9 * at(2);
        assert!(
            (got - want).abs() <= 1e-12 * want.abs().max(1.0),
            "{n}: {got} {want}"
        );
    }
    // describe-output lists them.
    let o = efsi(&["describe-output", out.to_str().unwrap()]);
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(o.status.success(), "{}", stderr(&o));
    for needle in [
        "z0.5: the plane z = 0.5, every 0.1, slices/z0.5.pvd: velocity, pressure, density",
        "side: the plane x = 0.3, every 0.05, slices/side.pvd: pressure",
    ] {
        assert!(text.contains(needle), "{needle} in {text}");
    }
}

/// A run to 0.1 with a checkpoint, resumed to 0.2 (the file's end moved), writes the same
/// slices, and the same collections, as the run to 0.2 in one go.
#[test]
fn slices_continue_across_a_resume() {
    let d = tmp("slices-resume");
    let whole = run(&d, "whole", &cube(0.2), &[]);
    let parts = run(&d, "parts", &cube(0.1), &["--checkpoint-every", "0.1"]);
    std::fs::write(d.join("parts.ron"), cube(0.2)).unwrap();
    let o = efsi(&["resume", parts.to_str().unwrap(), "-q"]);
    assert!(o.status.success(), "{}", stderr(&o));
    for pvd in ["slices/z0.5.pvd", "slices/side.pvd", "fields.pvd"] {
        let read = |dir: &Path| std::fs::read_to_string(dir.join(pvd)).unwrap();
        assert_eq!(read(&parts), read(&whole), "{pvd}");
        for (_, file) in read_pvd(&whole.join(pvd)).unwrap() {
            let twin = parts.join(file.strip_prefix(&whole).unwrap());
            assert_eq!(
                std::fs::read(&file).unwrap(),
                std::fs::read(&twin).unwrap(),
                "{}",
                file.display()
            );
        }
    }
}

/// `efsi plot` of a three-dimensional run draws the plane `--slice` names (a PNG of the
/// documented size, coloured), and refuses to draw without one, saying how.
#[test]
fn plot_draws_a_slice_of_a_three_dimensional_run() {
    let d = tmp("slices-plot");
    let out = run(&d, "cube", &cube(0.1), &[]);
    let dir = out.to_str().unwrap();
    let o = efsi(&["plot", dir]);
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(2), "{err}");
    for needle in ["is three-dimensional (8×8×8 cells)", "--slice z=0.5"] {
        assert!(err.contains(needle), "{needle} in {err}");
    }
    assert!(!out.join("plots/probes.png").exists(), "nothing written");
    let o = efsi(&["plot", dir, "--slice", "z=0.5"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let png = out.join("plots/velocity_t0.1_z0.5.png");
    let img = image::open(&png).unwrap().to_rgb8();
    assert_eq!(img.dimensions(), (900, 900));
    let coloured = img.pixels().filter(|p| p.0 != [255, 255, 255]).count();
    assert!(coloured as f64 > 0.3 * 900.0 * 900.0, "{coloured}");
    let o = efsi(&["plot", dir, "--slice", "y=0.25", "--field", "pressure"]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(out.join("plots/pressure_t0.1_y0.25.png").is_file());
    for (slice, needle) in [
        ("z=1.5", "z = 1.5 is outside the box's [0, 1]"),
        ("w=0.5", "`w` is not an axis"),
        ("z", "expected AXIS=POSITION"),
    ] {
        let o = efsi(&["plot", dir, "--slice", slice]);
        let err = stderr(&o);
        assert_eq!(o.status.code(), Some(2), "{err}");
        assert!(err.contains(needle), "{needle} in {err}");
    }
}

/// A slice in a planar scene, outside the box, or of an array no stage provides is refused,
/// naming the setting.
#[test]
fn bad_slices_are_refused_by_name() {
    let d = tmp("slices-bad");
    let scene = d.join("cube.ron");
    std::fs::write(&scene, cube(0.1)).unwrap();
    let planar = d.join("square.ron");
    std::fs::write(
        &planar,
        common::cavity("square", 8, 0.1, "slices: [(normal: Z, at: 0.5)]"),
    )
    .unwrap();
    let check = |file: &Path, set: &[&str]| {
        let mut args = vec!["check", file.to_str().unwrap()];
        for s in set {
            args.extend(["--set", s]);
        }
        efsi(&args)
    };
    for (file, set, needles) in [
        (
            &planar,
            &[][..],
            &["output.slices[0]", "three-dimensional box", "Planar"][..],
        ),
        (
            &scene,
            &["output.slices[1].at=1.25"],
            &[
                "output.slices[1].at",
                "x = 1.25 is outside the box's [0, 1]",
            ],
        ),
        (
            &scene,
            &["output.slices[0].fields=[\"temperature\"]"],
            &["output.slices[0].fields[0]", "unknown field `temperature`"],
        ),
        (
            &scene,
            &["output.slices[1].name=\"z0.5\""],
            &["output.slices[1].name", "unique file stem"],
        ),
    ] {
        let o = check(file, set);
        let err = stderr(&o);
        assert_eq!(o.status.code(), Some(2), "{set:?}: {err}");
        for n in needles {
            assert!(err.contains(n), "{set:?}: `{n}` in {err}");
        }
    }
    let o = check(&scene, &[]);
    assert!(o.status.success(), "{}", stderr(&o));
}
