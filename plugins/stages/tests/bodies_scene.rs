//! Scenes of several bodies (`solids: [ … ]`) through the whole time step: the case
//! `cases/two_drops.ron` (two drops of different density falling side by side), and the
//! scene checks that refuse what a scene of bodies may not be.

use efsi_core::{Field, Grid, Scene, Simulation};
use efsi_stages::vof::bodies::{BodyWindow, windows_of};
use efsi_stages::vof::{VofBoundaries, phase_volume};
use std::path::{Path, PathBuf};

fn build(text: &str) -> Result<Simulation, String> {
    let path = Path::new("bodies.ron");
    let scene = Scene::from_str_at(text, path).map_err(|e| e.to_string())?;
    efsi_run::simulation(scene, path, &efsi_stages::builtin()).map_err(|e| e.to_string())
}

fn refused(text: &str) -> String {
    match build(text) {
        Ok(_) => panic!("not refused:\n{text}"),
        Err(e) => e,
    }
}

fn case(name: &str) -> String {
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../cases")
        .join(name);
    std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

/// The bodies' windows, from the VOF stage's record.
fn windows(sim: &Simulation, count: usize) -> Vec<BodyWindow> {
    let record = sim
        .pipeline()
        .save_stages()
        .into_iter()
        .find(|(name, _)| name == "vof")
        .expect("a VOF stage")
        .1;
    windows_of(&sim.grid, VofBoundaries::closed(), count, &record).unwrap()
}

/// `∫ φ y dV / ∫ φ dV` of a field of `grid`.
fn centroid_y(grid: &Grid, phi: &Field) -> f64 {
    let (mut m, mut v) = (0.0, 0.0);
    for j in 0..grid.ny as isize {
        for i in 0..grid.nx as isize {
            let y = grid.y0 + (j as f64 + 0.5) * grid.dy;
            m += phi[(i, j)] * y;
            v += phi[(i, j)];
        }
    }
    m / v
}

#[test]
fn two_drops_fall_side_by_side_each_its_own_volume_and_never_overlapping() {
    let text = case("two_drops.ron").replace("end: 1.0", "end: 0.5");
    let mut sim = build(&text).unwrap();
    let g = sim.grid.clone();
    let start = windows(&sim, 2);
    let v0: Vec<f64> = start.iter().map(|w| w.volume(&g)).collect();
    let y0: Vec<f64> = start
        .iter()
        .map(|w| centroid_y(&g, &w.on_parent(&g)))
        .collect();
    // Each window is a box around its drop, far smaller than the grid.
    for w in &start {
        assert!(
            w.cells() * 4 < g.nx * g.ny,
            "a window of {} cells",
            w.cells()
        );
    }
    let (end, every) = (0.5, 0.125);
    let mut next = every;
    let mut outputs = 0;
    while sim.state.t < end - 1e-12 {
        let dt = sim.next_dt(next).unwrap();
        sim.step(dt).unwrap_or_else(|e| panic!("{e}"));
        if sim.state.t < next - 1e-12 {
            continue;
        }
        next += every;
        outputs += 1;
        let now = windows(&sim, 2);
        for (k, (w, v0)) in now.iter().zip(&v0).enumerate() {
            let drift = (w.volume(&g) - v0).abs() / v0;
            assert!(
                drift <= 1e-10,
                "t = {}: body {k} volume drift {drift:e}",
                sim.state.t
            );
        }
        // The state's fraction is Σ φ_k: at most 1 + 1e-12 in every cell.
        let phi = sim.state.phi.as_ref().unwrap();
        let most = phi.data().iter().fold(0.0f64, |m, x| m.max(*x));
        assert!(most <= 1.0 + 1e-12, "t = {}: Σφ_k = {most}", sim.state.t);
        let total: f64 = now.iter().map(|w| w.volume(&g)).sum();
        assert!((phase_volume(&g, phi) - total).abs() <= 1e-12 * total);
    }
    assert_eq!(outputs, 4);
    // A drop of density ρ_k accelerating from rest in a fluid of density ρ_f = 1 under g = 1,
    // with the added mass of a cylinder in potential flow (coefficient 1), falls
    // ½ g (ρ_k − ρ_f)/(ρ_k + ρ_f) t²: ⅓ g for the light drop, ⅔ g for the heavy one. Drag and
    // the start from rest slow them; each falls between half and all of it, and the heavy one
    // more than twice as far.
    let now = windows(&sim, 2);
    let fall: Vec<f64> = now
        .iter()
        .zip(&y0)
        .map(|(w, y0)| y0 - centroid_y(&g, &w.on_parent(&g)))
        .collect();
    println!(
        "falls at t = 0.5: light {:.5}, heavy {:.5}",
        fall[0], fall[1]
    );
    let ideal = |rho: f64| 0.5 * (rho - 1.0) / (rho + 1.0) * end * end;
    for (f, rho) in fall.iter().zip([2.0, 5.0]) {
        assert!(*f > 0.5 * ideal(rho) && *f < ideal(rho), "{fall:?}");
    }
    assert!(fall[1] > 2.0 * fall[0], "{fall:?}");
}

const SCENE: &str = r#"Scene(name: "b",
    domain: (x: (0.0, 1.0), y: (0.0, 1.0)),
    grid: (nx: 16, ny: 16),
    time: (end: 0.1, fixed_dt: 0.01),
    fluid: (density: 1.0, viscosity: 0.01),
    gravity: (0.0, -1.0),
    BODIES
    boundaries: (x_min: NoSlip, x_max: NoSlip, y_min: NoSlip, y_max: NoSlip))"#;

fn with(bodies: &str) -> String {
    SCENE.replace("BODIES", bodies)
}

const A: &str = r#"(name: "a", shape: Disk(center: (0.3, 0.5), radius: 0.1), density: 2.0)"#;
const B: &str = r#"(name: "b", shape: Disk(center: (0.7, 0.5), radius: 0.1), density: 3.0)"#;

#[test]
fn a_scene_of_bodies_is_refused_naming_the_body_and_the_setting() {
    let list = |v: &[&str]| format!("solids: [{}],", v.join(", "));
    assert!(build(&with(&list(&[A, B]))).is_ok());
    // Touching (centres 0.2 apart) is not an overlap.
    assert!(build(&with(&list(&[A, &B.replace("0.7", "0.5")]))).is_ok());
    // The pair measure needs a pair; the per-body probes run for one body as for several.
    let probes = |b: &str, p: &str| {
        with(b).replace(
            "boundaries:",
            &format!("output: (probes: [{p}]), boundaries:"),
        )
    };
    let e = refused(&probes(&list(&[A]), "BodyContact"));
    assert!(
        e.contains("output.probes[0]") && e.contains("BodyContact measures pairs of bodies"),
        "{e}"
    );
    assert!(build(&probes(&list(&[A, B]), "BodyContact, SolidOverlap")).is_ok());
    assert!(build(&probes(&list(&[A]), "SolidCentroid, SolidOverlap")).is_ok());
    let law = B.replace(
        "3.0)",
        "3.0, law: (name: \"neo_hookean\", parameters: {\"G\": 100.0}))",
    );
    // Each scene's bodies and the fragments its refusal holds.
    let refusals: [(String, &[&str]); 11] = [
        (
            format!(
                "solid: (shape: Disk(center: (0.5, 0.5), radius: 0.1), density: 2.0), {}",
                list(&[A])
            ),
            &["solids", "both `solid` and `solids`"],
        ),
        ("solids: [],".into(), &["solids: an empty list"]),
        (
            list(&[A, &A.replace("0.3", "0.7")]),
            &["solids[1].name", "also the name of solids[0]"],
        ),
        (
            list(&[A, &B.replace("\"b\"", "\"\"")]),
            &["solids[1].name: empty"],
        ),
        (
            list(&[A, &B.replace("\"b\"", "\"b c\"")]),
            &["solids[1].name", "' '"],
        ),
        // Overlap at t = 0: the disks at 0.3 and 0.45 (radius 0.1) share a lens.
        (
            list(&[A, &B.replace("0.7", "0.45")]),
            &["solids[1].shape", "\"b\" overlaps body \"a\""],
        ),
        (
            list(&[A, &B.replace("(0.7, 0.5)", "(3.0, 0.5)")]),
            &["solids[1].shape", "covers no cell"],
        ),
        (
            list(&[A, &B.replace("3.0)", "-3.0)")]),
            &["solids[1].density", "body \"b\""],
        ),
        // A body's law is loaded as its own: a missing library is named by the body's path.
        (
            list(&[A, &law.replace("neo_hookean", "no_such_law_xyz")]),
            &["solids[1].law", "no_such_law_xyz"],
        ),
        // A misspelt setting: the message lists a body's settings (`solid:` without a name).
        (
            list(&[A, &B.replace("density", "densty")]),
            &[
                "solids.[1].densty: Unexpected field named `densty` in `BodySpec`, expected one \
                 of `name`, `shape`, `density`, `viscosity`, `velocity`, or `law` instead",
            ],
        ),
        (
            format!(
                "solid: {},",
                A.replace("name: \"a\", ", "").replace("density", "densty")
            ),
            &[
                "solid.densty: Unexpected field named `densty` in `Solid`, expected one of \
                 `shape`, `density`, `viscosity`, `velocity`, or `law` instead",
            ],
        ),
    ];
    for (bodies, fragments) in refusals {
        let e = refused(&with(&bodies));
        assert!(fragments.iter().all(|f| e.contains(f)), "{bodies}: {e}");
    }
}

#[test]
fn a_list_of_one_body_runs_as_the_single_solid() {
    // `solids: [ one ]` and `solid: one` give the same fields, bit for bit.
    let one = A.replace("(name: \"a\", ", "(");
    let mut single = build(&with(&format!("solid: {one},"))).unwrap();
    let mut listed = build(&with(&format!("solids: [{A}],"))).unwrap();
    for _ in 0..5 {
        single.step(0.01).unwrap();
        listed.step(0.01).unwrap();
    }
    assert_eq!(single.state.phi, listed.state.phi);
    assert_eq!(single.state.v, listed.state.v);
}

#[test]
fn viscous_bodies_in_an_inviscid_fluid_schedule_the_viscous_stage() {
    // μ_f = 0, the bodies' μ_k > 0: the viscous stage runs (for one body as for several).
    let inviscid = |b: &str| with(b).replace("viscosity: 0.01", "viscosity: 0.0");
    let a = A.replace("2.0)", "2.0, viscosity: 0.1)");
    for bodies in [format!("solids: [{a}, {B}],"), format!("solids: [{a}],")] {
        let sim = build(&inviscid(&bodies)).unwrap();
        let names = sim.pipeline().stage_names();
        assert!(names.contains(&"viscous"), "{bodies}: {names:?}");
    }
}

/// Two equal drops sent head-on at each other in a fluid at rest, `speed` each.
fn approach(speed: f64) -> String {
    format!(
        r#"Scene(name: "approach",
    domain: (x: (0.0, 2.0), y: (0.0, 1.0)),
    grid: (nx: 64, ny: 32),
    time: (end: 0.5, fixed_dt: 0.005),
    fluid: (density: 1.0, viscosity: 0.01),
    numerics: (projection: (tolerance: 1e-8)),
    solids: [
        (name: "left", shape: Disk(center: (0.6, 0.5), radius: 0.2), density: 4.0,
         velocity: ({speed}, 0.0)),
        (name: "right", shape: Disk(center: (1.4, 0.5), radius: 0.2), density: 4.0,
         velocity: (-{speed}, 0.0)),
    ],
    boundaries: (x_min: NoSlip, x_max: NoSlip, y_min: NoSlip, y_max: NoSlip),
    output: (probe_every: 0.05, probes: [SolidVolume, SolidCentroid, SolidVelocity,
        SolidPieces, SolidOverlap, BodyContact, ContactForce(wall: XMin)]),
)"#
    )
}

/// The scene's probes of the simulation's state, by column name (`probes.csv`'s row).
fn probe_row(sim: &Simulation) -> std::collections::HashMap<String, f64> {
    let o = efsi_run::output::spec::SceneOutput::output_spec(&sim.scene).unwrap();
    let bodies = efsi_run::probes::body_names(&sim.scene);
    let (mut names, mut values) = (Vec::new(), Vec::new());
    for p in &o.probes {
        names.extend(efsi_run::probes::columns(p, sim.grid.geometry, &bodies));
        efsi_run::probes::evaluate(
            p,
            &sim.grid,
            &sim.state,
            sim.scene.gravity,
            sim.pipeline().outputs(),
            &mut values,
        );
    }
    assert_eq!(names.len(), values.len(), "{names:?}");
    names.into_iter().zip(values).collect()
}

/// Two drops sent head-on at each other (`approach(2.0)`): the probes per body (volume,
/// centroid, velocity, pieces) are each body's own, and at every output each body keeps its
/// volume to 1e-10 and is one piece, no cell holds more than one cell of bodies
/// (`max_solid_fraction_sum ≤ 1 + 1e-12`), the motion is mirror-symmetric about x = 1 — and the
/// fluid film between them, resolved on the grid, stops the drops and sends them apart again
/// before they share a cell (`shared_volume` 0 throughout).
#[test]
fn two_drops_sent_head_on_stop_and_part_without_sharing_a_cell() {
    let mut sim = build(&approach(2.0).replace("end: 0.5", "end: 0.8")).unwrap();
    let g = sim.grid.clone();
    let row = probe_row(&sim);
    let v0 = [row["left.solid_volume"], row["right.solid_volume"]];
    // The probes per body are the bodies' own: the volume of each window, equal bodies.
    let start = windows(&sim, 2);
    for (w, v) in start.iter().zip(v0) {
        assert!(
            (w.volume(&g) - v).abs() <= 1e-14 * v,
            "{} vs {v}",
            w.volume(&g)
        );
    }
    assert_eq!(v0[0], v0[1]);
    type Row = std::collections::HashMap<String, f64>;
    let gap = |r: &Row| r["right.solid_x"] - r["left.solid_x"];
    let mut gaps = vec![(0.0, gap(&row))];
    let (end, every) = (0.8, 0.05);
    let mut next = every;
    while sim.state.t < end - 1e-12 {
        let dt = sim.next_dt(next).unwrap();
        sim.step(dt).unwrap_or_else(|e| panic!("{e}"));
        if sim.state.t < next - 1e-12 {
            continue;
        }
        next += every;
        let r = probe_row(&sim);
        let t = sim.state.t;
        println!(
            "t {t:.2} centroids {:.5} apart, left u {:.5}, shared {:e} ({} cells), max Σφ {:.15}, largest piece {:.7}",
            gap(&r),
            r["left.solid_u"],
            r["left.right.shared_volume"],
            r["left.right.shared_cells"],
            r["max_solid_fraction_sum"],
            r["left.solid_largest_piece"],
        );
        for (b, v0) in ["left", "right"].iter().zip(v0) {
            let drift = (r[&format!("{b}.solid_volume")] - v0).abs() / v0;
            assert!(drift <= 1e-10, "t = {t}: {b} volume drift {drift:e}");
            assert_eq!(r[&format!("{b}.solid_pieces")], 1.0, "t = {t}: {b}");
            // Flotsam of the transport (regions below 1e-3 of the body) is no piece.
            let largest = r[&format!("{b}.solid_largest_piece")];
            assert!(
                largest > 1.0 - 1e-3 && largest <= 1.0 + 1e-12,
                "t = {t}: {b} {largest}"
            );
        }
        let most = r["max_solid_fraction_sum"];
        assert!(most <= 1.0 + 1e-12, "t = {t}: max Σφ_k = {most}");
        assert_eq!(r["solid_overlap_volume"], 0.0, "t = {t}");
        assert_eq!(r["left.right.shared_volume"], 0.0, "t = {t}");
        assert_eq!(r["left.right.shared_cells"], 0.0, "t = {t}");
        // Mirror symmetry about x = 1 (the split sweeps alternate their order: to a tolerance).
        let mirror = r["left.solid_x"] + r["right.solid_x"] - 2.0;
        let speeds = r["left.solid_u"] + r["right.solid_u"];
        assert!(
            mirror.abs() < 1e-6 && speeds.abs() < 1e-6,
            "t = {t}: {mirror:e} {speeds:e}"
        );
        gaps.push((t, gap(&r)));
    }
    assert_eq!(gaps.len(), 17);
    // The closest approach is inside the run: the drops stop, then part.
    let (k, &(t_min, closest)) = gaps
        .iter()
        .enumerate()
        .min_by(|a, b| a.1.1.total_cmp(&b.1.1))
        .unwrap();
    println!("closest approach: centroids {closest:.5} apart at t = {t_min:.2}");
    assert!(k > 0 && k + 1 < gaps.len(), "{gaps:?}");
    assert!(closest < 0.4 && closest > 0.15, "{gaps:?}");
    assert!(gaps[gaps.len() - 1].1 > closest + 0.01, "{gaps:?}");
}
