//! `efsi run` and `efsi check` with `--set PATH=VALUE` and `--refine F`: the effective scene is
//! run and recorded in `run.json` with the overrides; a bad path, a wrong type or an
//! out-of-range value is refused (exit code 2) naming the override; `efsi resume` applies the
//! recorded overrides again.

mod common;

use common::{efsi, tmp};
use std::path::Path;

const CAVITY: &str = r#"Scene(
    name: "tiny_cavity",
    domain: (x: (0.0, 1.0), y: (0.0, 1.0)),
    grid: (nx: 8, ny: 6),
    time: (end: 0.5),
    fluid: (density: 1.0, viscosity: 0.01),
    boundaries: (x_min: NoSlip, x_max: NoSlip, y_min: NoSlip, y_max: MovingWall(speed: 1.0)),
    output: (
        probe_every: 0.05,
        probes: [Point(name: "u_c", field: "u", at: (0.5, 0.5)), KineticEnergy],
    ),
)
"#;

fn text(o: &[u8]) -> String {
    String::from_utf8_lossy(o).into_owned()
}

fn scene_file(dir: &Path, text: &str) -> String {
    let p = dir.join("scene.ron");
    std::fs::write(&p, text).unwrap();
    p.display().to_string()
}

fn run_json(dir: &Path) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(dir.join("run.json")).unwrap()).unwrap()
}

#[test]
fn set_and_refine_change_the_run_and_are_recorded() {
    let d = tmp("ok");
    let scene = scene_file(&d, CAVITY);
    let o = efsi(&[
        "check",
        &scene,
        "--set",
        "grid.nx=10",
        "--set",
        "time.steady=1e-3",
        "--refine",
        "1.5",
    ]);
    assert!(o.status.success(), "{}", text(&o.stderr));
    assert!(
        text(&o.stdout).contains("15×9 cells"),
        "{}",
        text(&o.stdout)
    );

    let out = d.join("out");
    let o = efsi(&[
        "run",
        &scene,
        "--out",
        out.to_str().unwrap(),
        "-q",
        "--set",
        "fluid.viscosity=0.05",
        "--set",
        "output.probes[0].at=(0.25, 0.75)",
        "--set",
        "boundaries.y_max.speed=2",
        "--refine",
        "2",
    ]);
    assert!(o.status.success(), "{}", text(&o.stderr));
    let json = run_json(&out);
    assert_eq!(json["cells"], 16 * 12);
    let s = &json["scene"];
    assert_eq!(s["grid"]["nx"], 16);
    assert_eq!(s["fluid"]["viscosity"], 0.05);
    assert_eq!(
        s["output"]["probes"][0]["Point"]["at"],
        serde_json::json!([0.25, 0.75])
    );
    assert_eq!(s["boundaries"]["y_max"]["MovingWall"]["speed"], 2.0);
    assert_eq!(
        json["overrides"],
        serde_json::json!([
            "set fluid.viscosity=0.05",
            "set output.probes[0].at=(0.25, 0.75)",
            "set boundaries.y_max.speed=2",
            "refine 2"
        ])
    );
    std::fs::remove_dir_all(&d).unwrap();
}

/// `check` and `run` refuse the overrides with exit code 2, every needle in the message, and
/// no line:column (the user wrote no such text).
fn refused(args: &[&str], needles: &[&str]) {
    static CALLS: std::sync::atomic::AtomicUsize = std::sync::atomic::AtomicUsize::new(0);
    let k = CALLS.fetch_add(1, std::sync::atomic::Ordering::SeqCst);
    let d = tmp(&format!("refused{k}"));
    let scene = scene_file(&d, CAVITY);
    let out = d.join("out");
    for cmd in [
        vec!["check", scene.as_str()],
        vec!["run", scene.as_str(), "-q", "--out", out.to_str().unwrap()],
    ] {
        let o = efsi(&[cmd.as_slice(), args].concat());
        let err = text(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {err}");
        for n in needles {
            assert!(err.contains(n), "{args:?}: expected `{n}` in: {err}");
        }
        assert!(err.contains(&format!("{scene}: ")), "{err}");
        assert!(!err.contains(&format!("{scene}:1")), "{err}");
        assert!(!err.contains("panicked"), "{err}");
    }
    assert!(!out.join("run.json").exists());
    std::fs::remove_dir_all(&d).unwrap();
}

#[test]
fn an_unknown_path_is_refused_naming_it() {
    refused(
        &["--set", "grid.nxx=12"],
        &["set grid.nxx=12", "`nxx`", "expected one of", "`nx`"],
    );
    refused(
        &["--set", "output.probes[5].at=(0.5, 0.5)"],
        &["set output.probes[5].at", "has 2 elements, no [5]"],
    );
    refused(
        &["--set", "fluid.viscosity.value=1"],
        &["fluid.viscosity is a number, which has no value"],
    );
}

#[test]
fn a_wrong_type_is_refused_naming_the_override() {
    refused(
        &["--set", "grid.nx=1.5"],
        &["set grid.nx=1.5", "expected an integer"],
    );
    refused(
        &["--set", "fluid.viscosity=thick"],
        &["set fluid.viscosity=thick"],
    );
    refused(
        &["--set", "boundaries.x_min=Sticky"],
        &["set boundaries.x_min=Sticky", "`Sticky`", "NoSlip"],
    );
}

#[test]
fn an_out_of_range_value_is_refused_by_the_scene_validation() {
    refused(
        &["--set", "fluid.viscosity=-1"],
        &["set fluid.viscosity=-1: fluid.viscosity: must be a finite number ≥ 0"],
    );
    refused(
        &["--set", "time.cfl=3"],
        &["set time.cfl=3: time.cfl: must be in (0, 1]"],
    );
    refused(&["--refine", "0"], &["refine 0: the factor must be"]);
    refused(
        &["--refine", "5000"],
        &["refine 5000: grid: more than 1e8 cells"],
    );
}

/// A stage's option that does not read as its type is refused when the scene is checked, naming
/// the setting inside the section — among them the two the projection and the elastic stages
/// read to choose their scheme (the incremental correction, the elastic coupling).
#[test]
fn a_malformed_stage_option_is_refused_naming_the_setting() {
    refused(
        &["--set", "numerics.elastic.coupling=Sometimes"],
        &[
            "set numerics.elastic.coupling=Sometimes",
            "numerics.elastic.coupling: ",
            "`Sometimes`",
        ],
    );
    refused(
        &["--set", "numerics.projection.incremental=3"],
        &[
            "set numerics.projection.incremental=3",
            "numerics.projection.incremental: ",
        ],
    );
    // Written in the scene file: the setting, its line and its column.
    let d = tmp("option_in_file");
    let scene = scene_file(
        &d,
        &CAVITY.replace(
            "    time:",
            "    numerics: (projection: (incremental: 3), elastic: (coupling: Auto)),\n    time:",
        ),
    );
    let o = efsi(&["check", &scene]);
    let err = text(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(
        err.contains(&format!("{scene}: numerics.projection.incremental: "))
            && err.contains("(line 5, column "),
        "{err}"
    );
    std::fs::remove_dir_all(&d).unwrap();
}

#[test]
fn a_malformed_override_is_a_usage_error() {
    let d = tmp("usage");
    let scene = scene_file(&d, CAVITY);
    let o = efsi(&["check", &scene, "--set", "grid.nx"]);
    assert_eq!(o.status.code(), Some(2));
    assert!(
        text(&o.stderr).contains("expected PATH=VALUE"),
        "{}",
        text(&o.stderr)
    );
    std::fs::remove_dir_all(&d).unwrap();
}

#[test]
fn resume_applies_the_recorded_overrides_again() {
    let d = tmp("resume");
    let overrides = ["--set", "fluid.viscosity=0.02", "--refine", "2"];
    // The run to 0.75 in one go.
    let whole = d.join("whole");
    let scene = scene_file(&d, &CAVITY.replace("end: 0.5", "end: 0.75"));
    let o = efsi(
        &[
            &["run", &scene, "-q", "--out", whole.to_str().unwrap()],
            &overrides[..],
        ]
        .concat(),
    );
    assert!(o.status.success(), "{}", text(&o.stderr));
    // The same run to 0.5 with a checkpoint, then resumed to 0.75 (the file's end moved).
    let parts = d.join("parts");
    let parts_s = parts.to_str().unwrap();
    let scene = scene_file(&d, CAVITY);
    let o = efsi(
        &[
            &[
                "run",
                &scene,
                "-q",
                "--out",
                parts_s,
                "--checkpoint-every",
                "0.25",
            ],
            &overrides[..],
        ]
        .concat(),
    );
    assert!(o.status.success(), "{}", text(&o.stderr));
    // A change of the file that changes the effective scene is still refused.
    scene_file(
        &d,
        &CAVITY
            .replace("end: 0.5", "end: 0.75")
            .replace("nx: 8", "nx: 10"),
    );
    let o = efsi(&["resume", parts_s, "-q"]);
    let err = text(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(err.contains("scene: grid.nx: 16 → 20"), "{err}");
    // The file as it was (but for its end): the same effective scene, the same numbers.
    scene_file(&d, &CAVITY.replace("end: 0.5", "end: 0.75"));
    let o = efsi(&["resume", parts_s, "-q"]);
    assert!(o.status.success(), "{}", text(&o.stderr));
    let json = run_json(&parts);
    assert_eq!(json["scene"]["grid"]["nx"], 16);
    assert_eq!(json["scene"]["fluid"]["viscosity"], 0.02);
    assert_eq!(json["overrides"], run_json(&whole)["overrides"]);
    assert_eq!(
        std::fs::read_to_string(parts.join("probes.csv")).unwrap(),
        std::fs::read_to_string(whole.join("probes.csv")).unwrap()
    );
    std::fs::remove_dir_all(&d).unwrap();
}
