//! A step that fails inside the elastic stage leaves the state complete: B̃ is back in it, a
//! snapshot of the step's start restores into it, and the run continues from there exactly as
//! before (it fails again at the same step with the same message).

use efsi_core::{Scene, Simulation, Snapshot};
use std::path::{Path, PathBuf};

/// `libefsi_test_law_nan.so`, built next to this test (`target/<profile>/deps` or its parent).
fn nan_law() -> PathBuf {
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

/// A sheared layer whose law (`test_nan`, stress NaN past b11 = 1.01) fails after some steps.
fn scene(law: &Path) -> Scene {
    let text = format!(
        r#"Scene(
    name: "elastic_failure",
    domain: (x: (0.0, 0.0625), y: (0.0, 1.0)),
    grid: (nx: 4, ny: 16),
    time: (end: 0.6, dt_max: 0.01),
    fluid: (density: 1.0, viscosity: 1.0),
    solid: (shape: HalfPlane(normal: (0.0, 1.0), offset: 0.5), density: 1.0, viscosity: 0.0,
            law: (name: "{}", parameters: {{"G": 5.0, "limit": 1.01}})),
    boundaries: (x_min: Periodic, x_max: Periodic, y_min: NoSlip,
                 y_max: MovingWall(speed: 1.0, motion: Sin(omega: 3.141592653589793))),
)"#,
        law.display()
    );
    Scene::from_str_at(&text, Path::new("elastic_failure.ron")).unwrap()
}

/// Step until a step fails; returns the snapshot of its start and the error's text.
fn run_to_failure(sim: &mut Simulation) -> (Snapshot, String) {
    let mut good = sim.snapshot();
    for _ in 0..1000 {
        sim.snapshot_into(&mut good);
        let dt = sim.next_dt(sim.scene.time.end).unwrap();
        if let Err(e) = sim.step(dt) {
            return (good, e.to_string());
        }
    }
    panic!("the law never failed");
}

fn same_bits(a: &Snapshot, b: &Snapshot) -> bool {
    a.t() == b.t()
        && a.step() == b.step()
        && a.state
            .arrays()
            .iter()
            .zip(b.state.arrays())
            .all(|((na, fa), (nb, fb))| {
                na == &nb
                    && fa
                        .data()
                        .iter()
                        .zip(fb.data())
                        .all(|(x, y)| x.to_bits() == y.to_bits())
            })
}

#[test]
fn a_failed_elastic_step_leaves_the_state_restorable() {
    let law = nan_law();
    let mut sim =
        Simulation::new(scene(&law), Path::new("x.ron"), &efsi_stages::builtin()).unwrap();
    let (good, message) = run_to_failure(&mut sim);
    assert!(
        message.contains("stage `elastic`") && message.contains("law `test_nan`"),
        "{message}"
    );
    assert!(
        good.step() > 10,
        "the layer shears for a while first: {message}"
    );
    // B̃ is back in the state: the step's start restores into it, bit for bit.
    assert!(
        sim.state
            .resources
            .get::<efsi_stages::elastic::Deformation>()
            .is_some(),
        "B̃ was not put back"
    );
    sim.restore(&good).unwrap_or_else(|e| panic!("{e}"));
    assert!(same_bits(&sim.snapshot(), &good));
    // And the run continues from there as before: the same step fails the same way.
    let dt = sim.next_dt(sim.scene.time.end).unwrap();
    let again = sim.step(dt).unwrap_err().to_string();
    assert_eq!(again, message);
    assert_eq!(sim.state.step, good.step());
}

/// Three disks falling, each with the `test_nan` law: `a` never fails, `b` and `c` fail as soon
/// as they deform (stress NaN past b11 = 1.0001), in the same step.
fn three_disks(law: &Path) -> Scene {
    let disk = |name: &str, x: f64, y: f64, limit: f64| {
        format!(
            r#"(name: "{name}", shape: Disk(center: ({x}, {y}), radius: 0.1), density: 1.5,
            viscosity: 0.01, velocity: (0.0, -1.0),
            law: (name: "{}", parameters: {{"G": 1.0, "limit": {limit}}}))"#,
            law.display()
        )
    };
    let text = format!(
        r#"Scene(
    name: "three_disks",
    domain: (x: (0.0, 1.0), y: (0.0, 1.0)),
    grid: (nx: 64, ny: 64),
    time: (end: 1.0, cfl: 0.4),
    fluid: (density: 1.0, viscosity: 0.01),
    gravity: (0.0, -1.0),
    solids: [{}, {}, {}],
    boundaries: (x_min: NoSlip, x_max: NoSlip, y_min: NoSlip, y_max: NoSlip),
)"#,
        disk("a", 0.2, 0.5, 100.0),
        disk("b", 0.5, 0.5, 1.0001),
        disk("c", 0.8, 0.5, 1.0001)
    );
    Scene::from_str_at(&text, Path::new("three_disks.ron")).unwrap()
}

#[test]
fn a_failing_body_among_several_is_named_the_same_on_one_and_two_threads() {
    let law = nan_law();
    let fail = |threads: usize| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
            .install(|| {
                let mut sim = Simulation::new(
                    three_disks(&law),
                    Path::new("x.ron"),
                    &efsi_stages::builtin(),
                )
                .unwrap();
                let (good, message) = run_to_failure(&mut sim);
                // Every body's B̃ is back in the state: the step's start restores into it.
                let bodies = sim
                    .state
                    .resources
                    .get::<efsi_stages::elastic::BodyDeformations>()
                    .map(|b| b.bodies.len());
                assert_eq!(bodies, Some(3), "the bodies' B̃ were not put back");
                sim.restore(&good).unwrap_or_else(|e| panic!("{e}"));
                assert!(same_bits(&sim.snapshot(), &good));
                (good.step(), message)
            })
    };
    let (one, two) = (fail(1), fail(2));
    // `b` and `c` fail in the same step, whichever thread sees `c` first: the first of them in
    // the scene's order is named.
    assert!(
        one.1
            .contains("body `b` (solids[1]): law `test_nan`: non-finite stress"),
        "{}",
        one.1
    );
    assert!(!one.1.contains("body `c`"), "{}", one.1);
    assert_eq!(one, two);
}
