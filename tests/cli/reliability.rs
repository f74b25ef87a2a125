//! Reliability of the `efsi` command, end to end: a real SIGINT / SIGTERM stops a run cleanly
//! (exit code 130 / 143, a checkpoint, complete VTK and CSV files) and `efsi resume` finishes
//! it with the same outputs as an uninterrupted run; a changed scene or law is refused on
//! resume; an output folder that cannot be created is reported before the run (exit code 1);
//! law plugins that are missing, of another ABI, panicking or returning NaN are reported by
//! name (exit codes 2, 2, 2, 3).

mod common;

use common::{efsi, law_library, probe_rows, stderr, tmp};
use std::path::Path;
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

/// A 32² cavity long enough (≈ 2500 steps) to be interrupted twice.
const LONG: &str = r#"Scene(
    name: "long_cavity",
    domain: (x: (0.0, 1.0), y: (0.0, 1.0)),
    grid: (nx: 32, ny: 32),
    time: (end: 40.0, cfl: 0.5),
    fluid: (density: 1.0, viscosity: 0.01),
    boundaries: (x_min: NoSlip, x_max: NoSlip, y_min: NoSlip, y_max: MovingWall(speed: 1.0)),
    output: (vtk_every: 2.0, probe_every: 0.1, probes: [Point(name: "u_c", field: "u", at: (0.5, 0.5)), KineticEnergy]),
)
"#;

/// Start `efsi args…`, wait until `dir/probes.csv` has more than `rows` lines, then send
/// `signal`; returns the exit code and stderr.
fn interrupt(args: &[&str], dir: &Path, rows: usize, signal: i32) -> (Option<i32>, String) {
    let mut child: Child = Command::new(env!("CARGO_BIN_EXE_efsi"))
        .args(args)
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .expect("spawn efsi");
    let start = Instant::now();
    while probe_rows(dir) <= rows {
        assert!(
            child.try_wait().unwrap().is_none(),
            "efsi ended before it could be interrupted"
        );
        assert!(start.elapsed() < Duration::from_secs(60), "no progress");
        std::thread::sleep(Duration::from_millis(5));
    }
    // SAFETY: plain kill(2) on the child we spawned (still running: not yet waited for).
    let r = unsafe { libc::kill(child.id() as libc::pid_t, signal) };
    assert_eq!(r, 0);
    let out = child.wait_with_output().unwrap();
    (out.status.code(), stderr(&out))
}

/// Every output file is complete: VTK files are whole XML documents, the CSV rows all have the
/// header's columns and strictly increasing times, no temporary file is left.
fn assert_outputs_complete(dir: &Path) {
    for sub in ["", "fields", "profiles", "checkpoint"] {
        for e in std::fs::read_dir(dir.join(sub)).unwrap() {
            let p = e.unwrap().path();
            let name = p.file_name().unwrap().to_string_lossy().into_owned();
            assert!(!name.ends_with(".tmp"), "left over: {}", p.display());
            if name.ends_with(".vtr") || name.ends_with(".pvd") {
                let b = std::fs::read(&p).unwrap();
                assert!(
                    b.starts_with(b"<?xml") && b.ends_with(b"</VTKFile>\n"),
                    "{} is not a complete VTK file",
                    p.display()
                );
            }
        }
    }
    let csv = std::fs::read_to_string(dir.join("probes.csv")).unwrap();
    let mut lines = csv.lines();
    assert_eq!(lines.next(), Some("t,u_c,kinetic_energy"));
    let mut last = -1.0;
    for l in lines {
        let v: Vec<f64> = l.split(',').map(|x| x.parse().unwrap()).collect();
        assert_eq!(v.len(), 3, "{l}");
        assert!(v[0] > last, "times not increasing at {l}");
        last = v[0];
    }
    assert!(csv.ends_with('\n'));
}

#[test]
fn signals_stop_a_run_cleanly_and_resume_finishes_it_identically() {
    let d = tmp("signals");
    let scene = d.join("scene.ron");
    std::fs::write(&scene, LONG).unwrap();
    let (scene, out) = (scene.to_str().unwrap(), d.join("out"));
    let out_s = out.to_str().unwrap();

    // SIGINT during `run`: exit code 130, a checkpoint, complete files.
    let (code, err) = interrupt(
        &["run", scene, "--out", out_s, "-q"],
        &out,
        20,
        libc::SIGINT,
    );
    assert_eq!(code, Some(130), "{err}");
    assert!(err.contains("stopped by signal 2"), "{err}");
    assert!(err.contains("efsi resume"), "{err}");
    assert!(out.join("checkpoint/latest.efsick").is_file());
    assert_outputs_complete(&out);
    let json = std::fs::read_to_string(out.join("run.json")).unwrap();
    assert!(json.contains("\"Interrupted\""), "{json}");
    let rows = probe_rows(&out);

    // SIGTERM during `resume`: exit code 143.
    let (code, err) = interrupt(&["resume", out_s, "-q"], &out, rows + 20, libc::SIGTERM);
    assert_eq!(code, Some(143), "{err}");
    assert_outputs_complete(&out);

    // `resume` finishes; the outputs equal an uninterrupted run's.
    let o = efsi(&["resume", out_s, "-q"]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(String::from_utf8_lossy(&o.stdout).contains("resumed from the checkpoint at step"));
    assert_outputs_complete(&out);
    let whole = d.join("whole");
    let o = efsi(&["run", scene, "--out", whole.to_str().unwrap(), "-q"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let mut files = vec!["probes.csv".to_string(), "fields.pvd".to_string()];
    for e in std::fs::read_dir(whole.join("fields")).unwrap() {
        files.push(format!(
            "fields/{}",
            e.unwrap().file_name().to_string_lossy()
        ));
    }
    assert_eq!(files.len(), 2 + 21, "{files:?}");
    assert_eq!(std::fs::read_dir(out.join("fields")).unwrap().count(), 21);
    for f in &files {
        let (a, b) = (
            std::fs::read(whole.join(f)).unwrap(),
            std::fs::read(out.join(f)).unwrap(),
        );
        assert!(a == b, "{f} differs from the uninterrupted run's");
    }
    assert_eq!(probe_rows(&out), 402);
    std::fs::remove_dir_all(&d).unwrap();
}

/// A small box with an elastic block whose law is `law` (a library path) with `params`, its
/// fields written every 0.2.
fn solid_scene(law: &str, params: &str) -> String {
    common::solid_scene_with_output(
        law,
        params,
        "vtk_every: 0.2, probe_every: 0.05, probes: [KineticEnergy]",
    )
}

#[test]
fn a_law_returning_nan_stops_the_run_naming_the_law() {
    let d = tmp("nan");
    let lib = law_library("efsi_test_law_nan");
    let scene = d.join("scene.ron");
    std::fs::write(
        &scene,
        solid_scene(lib.to_str().unwrap(), r#""G": 5.0, "limit": 1.01"#),
    )
    .unwrap();
    let out = d.join("out");
    let o = efsi(&[
        "run",
        scene.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "-q",
    ]);
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(3), "{err}");
    assert!(
        err.contains("stage `elastic`: law `test_nan`: non-finite stress (B̃ = ")
            && (err.contains(") in cell (i, j) = (") || err.contains(") at corner (i, j) = (")),
        "{err}"
    );
    // The saved state is the start of the failed step: its VTK file, its `.pvd` entry and the
    // checkpoint agree on the step, and every field in it is finite.
    let at = err.find("the last good state (step ").expect(&err) + 26;
    let step: u64 = err[at..].split(',').next().unwrap().parse().unwrap();
    assert!(step > 10, "the law should fail after some shearing: {err}");
    // run.json says why the run stopped.
    let json: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out.join("run.json")).unwrap()).unwrap();
    assert_eq!(json["stop"]["Failed"]["exit_code"], 3, "{json}");
    assert!(
        json["stop"]["Failed"]["error"]
            .as_str()
            .unwrap()
            .contains("law `test_nan`: non-finite stress"),
        "{json}"
    );
    let vtk = format!("fields/solid_{step:06}_last_good.vtr");
    assert!(out.join(&vtk).is_file());
    let pvd = std::fs::read_to_string(out.join("fields.pvd")).unwrap();
    assert!(pvd.contains(&format!(r#"file="{vtk}""#)), "{pvd}");
    let file = efsi_run::CheckpointFile::read(&out.join("checkpoint/latest.efsick")).unwrap();
    assert_eq!(file.record.step(), step);
    let scene = file.scene().unwrap();
    let sim = efsi_run::simulation(scene, &file.scene_path, &efsi_stages::builtin()).unwrap();
    let snap = file.record.into_snapshot(sim.snapshot(), "test").unwrap();
    for (name, f) in snap.state.arrays() {
        assert!(f.data().iter().all(|x| x.is_finite()), "{name}");
    }
    std::fs::remove_dir_all(&d).unwrap();
}

#[test]
fn law_plugin_failures_are_reported_by_name() {
    let d = tmp("laws");
    let scene = d.join("scene.ron");
    let cases: [(String, &str, &[&str]); 3] = [
        (
            d.join("no_such_law.so").display().to_string(),
            r#""G": 5.0"#,
            &["solid.law", "no_such_law.so", "not found"],
        ),
        (
            law_library("efsi_test_law_bad_abi").display().to_string(),
            "",
            &["solid.law", "ABI v3, efsi expects v2"],
        ),
        (
            law_library("efsi_test_law_panic").display().to_string(),
            r#""G": 1e13"#,
            &["law `test_panic`", "panicked", "too stiff"],
        ),
    ];
    for (law, params, needles) in cases {
        std::fs::write(&scene, solid_scene(&law, params)).unwrap();
        for cmd in ["check", "run"] {
            let o =
                efsi(&[cmd, scene.to_str().unwrap(), "-q"][..if cmd == "check" { 2 } else { 3 }]);
            let err = stderr(&o);
            assert_eq!(o.status.code(), Some(2), "{law}: {err}");
            for n in needles {
                assert!(err.contains(n), "expected `{n}` in: {err}");
            }
        }
    }
    std::fs::remove_dir_all(&d).unwrap();
}

#[test]
fn an_output_folder_that_cannot_be_created_is_reported_before_the_run() {
    let d = tmp("unwritable");
    let scene = d.join("scene.ron");
    std::fs::write(&scene, LONG).unwrap();
    let file = d.join("a_file");
    std::fs::write(&file, "not a folder").unwrap();
    let target = file.join("out");
    let t0 = Instant::now();
    let o = efsi(&[
        "run",
        scene.to_str().unwrap(),
        "--out",
        target.to_str().unwrap(),
        "-q",
    ]);
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(err.contains(&*target.to_string_lossy()), "{err}");
    assert!(err.contains("Not a directory"), "{err}");
    assert!(
        o.stdout.is_empty(),
        "it ran: {}",
        String::from_utf8_lossy(&o.stdout)
    );
    assert!(t0.elapsed() < Duration::from_secs(5));
    std::fs::remove_dir_all(&d).unwrap();
}

#[test]
fn resume_refuses_a_changed_scene_or_law_and_accepts_them_restored() {
    let d = tmp("changed");
    // The law is named by a path relative to the scene: a copy of the neo-Hookean library.
    let law = d.join("law.so");
    std::fs::copy(law_library("efsi_law_neo_hookean"), &law).unwrap();
    let scene = d.join("scene.ron");
    let text = solid_scene("law.so", r#""G": 5.0"#);
    std::fs::write(&scene, &text).unwrap();
    let out = d.join("out");
    let out_s = out.to_str().unwrap();
    let o = efsi(&[
        "run",
        scene.to_str().unwrap(),
        "--out",
        out_s,
        "-q",
        "--checkpoint-every",
        "0.25",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));

    std::fs::write(&scene, text.replace("viscosity: 1.0", "viscosity: 2.0")).unwrap();
    let o = efsi(&["resume", out_s, "-q"]);
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(err.contains("cannot resume"), "{err}");
    assert!(err.contains("scene: fluid.viscosity: 1.0 → 2.0"), "{err}");
    // A stage's option the file did not set is compared setting by setting with its default.
    std::fs::write(
        &scene,
        text.replace(
            "fluid: (",
            "numerics: (viscous: (max_iterations: 77)),\n    fluid: (",
        ),
    )
    .unwrap();
    let o = efsi(&["resume", out_s, "-q"]);
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(
        err.contains("scene: numerics.viscous.max_iterations: 10000 → 77"),
        "{err}"
    );

    std::fs::write(&scene, &text).unwrap();
    std::fs::remove_file(&law).unwrap();
    std::fs::copy(law_library("efsi_test_law_panic"), &law).unwrap();
    let o = efsi(&["resume", out_s, "-q"]);
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(
        err.contains("law name `neo_hookean` → `test_panic`"),
        "{err}"
    );
    assert!(err.contains("the library changed"), "{err}");

    std::fs::remove_file(&law).unwrap();
    std::fs::copy(law_library("efsi_law_neo_hookean"), &law).unwrap();
    let o = efsi(&["resume", out_s, "-q"]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(String::from_utf8_lossy(&o.stdout).contains("resumed from the checkpoint at step"));

    // `time.end` may move past the checkpoint (the run continues to it), not before it.
    std::fs::write(&scene, text.replace("end: 0.6", "end: 0.3")).unwrap();
    let o = efsi(&["resume", out_s, "-q"]);
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(
        err.contains("time.end: 0.3 is not after the checkpoint's t"),
        "{err}"
    );
    std::fs::write(&scene, text.replace("end: 0.6", "end: 0.8")).unwrap();
    let o = efsi(&["resume", out_s, "-q"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let probes = std::fs::read_to_string(out.join("probes.csv")).unwrap();
    let last: f64 = probes
        .lines()
        .last()
        .and_then(|l| l.split(',').next())
        .and_then(|t| t.parse().ok())
        .unwrap();
    assert!(
        (last - 0.8).abs() < 1e-9,
        "the continued run ends at {last}"
    );
    std::fs::remove_dir_all(&d).unwrap();
}

#[test]
fn resume_without_a_checkpoint_says_so() {
    let d = tmp("none");
    let o = efsi(&["resume", d.to_str().unwrap()]);
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(err.contains("no checkpoint to resume from"), "{err}");
    std::fs::remove_dir_all(&d).unwrap();
}

/// The limits of the stability map: a fixed step above the elastic-wave limit and a
/// `wave_courant` above its maximum are refused before the run (exit code 2), naming the limit
/// and the setting to change, and nothing is written.
#[test]
fn settings_beyond_the_elastic_wave_limit_are_refused_before_the_run() {
    let d = tmp("wave");
    let law = law_library("efsi_law_neo_hookean");
    let stiff = solid_scene(law.to_str().unwrap(), r#""G": 1e9"#);
    let cases = [
        (
            "fixed_dt",
            stiff.replace("dt_max: 0.01", "fixed_dt: 0.001"),
            &[
                "time.fixed_dt",
                "numerics.elastic.wave_courant",
                "set time.fixed_dt ≤",
            ][..],
        ),
        (
            "wave_courant",
            stiff.replace(
                "fluid: (",
                "numerics: (elastic: (wave_courant: 10.0)),\n    fluid: (",
            ),
            &["numerics.elastic.wave_courant", "must be in (0, 4]"][..],
        ),
    ];
    for (name, text, needles) in cases {
        let scene = d.join(format!("{name}.ron"));
        std::fs::write(&scene, text).unwrap();
        let out = d.join(format!("out_{name}"));
        let o = efsi(&[
            "run",
            scene.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
        ]);
        let err = stderr(&o);
        assert_eq!(o.status.code(), Some(2), "{name}: {err}");
        for n in needles {
            assert!(err.contains(n), "{name}: `{n}` not in: {err}");
        }
        assert!(!out.join("probes.csv").exists(), "{name}: the run started");
    }
    // Within the limit the same stiff solid runs (the step is capped, not refused).
    let scene = d.join("capped.ron");
    std::fs::write(&scene, stiff.replace("end: 0.6", "end: 0.002")).unwrap();
    let out = d.join("out_capped");
    let o = efsi(&[
        "run",
        scene.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "-q",
    ]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    std::fs::remove_dir_all(&d).unwrap();
}

/// A run that pumps energy in without a single non-finite value — the sphere with its elastic
/// stress explicit (`numerics.elastic.implicit: false`) at the implicit step's wave limit, far
/// beyond the explicit step's — is stopped by the energy guard: exit code 3, the message says
/// what grew and what to change, the last good state is saved.
#[test]
fn a_run_gaining_energy_is_stopped_as_unstable() {
    let d = tmp("energy");
    let law = law_library("efsi_law_neo_hookean");
    let scene = d.join("explicit_sphere.ron");
    std::fs::write(
        &scene,
        format!(
            r#"Scene(
    name: "explicit_sphere",
    geometry: Axisymmetric,
    domain: (r: (0.0, 0.045), z: (0.0, 0.09)),
    grid: (nr: 19, nz: 38),
    time: (end: 0.02, cfl: 0.4),
    numerics: (elastic: (implicit: false)),
    fluid: (density: 1.2, viscosity: 1.8e-5),
    gravity: (0.0, -9.81),
    solid: (
        shape: Disk(center: (0.0, 0.0573), radius: 0.0192),
        density: 1106.0,
        velocity: (0.0, -1.22),
        law: (name: "{}", parameters: {{"G": 1.8e5}}),
    ),
    boundaries: (r_min: Axis, r_max: NoSlip, z_min: NoSlip, z_max: NoSlip),
    output: (probe_every: 0.0005, probes: [KineticEnergy, PotentialEnergy]),
)
"#,
            law.display()
        ),
    )
    .unwrap();
    let out = d.join("out");
    let o = efsi(&[
        "run",
        scene.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "-q",
    ]);
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(3), "{err}");
    for needle in [
        "unstable run",
        "the kinetic + potential energy is",
        "the scheme is pumping energy in",
        "lower time.cfl",
        "the last good state (step",
    ] {
        assert!(err.contains(needle), "`{needle}` not in: {err}");
    }
    assert!(out.join("checkpoint/latest.efsick").is_file());
    std::fs::remove_dir_all(&d).unwrap();
}
