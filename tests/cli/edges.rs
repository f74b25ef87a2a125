//! The command line driven as an adversary did (issue 44): overrides nested 10,000 levels,
//! output intervals of 1e-300, run files that are `/dev/zero`, `--threads 100000`, a file-size
//! limit, grids refined to nothing and domains that overflow, numbers at the ends of `f64` in
//! messages, an override blamed for another's value, duplicate profile fields and
//! `efsi plot --time NaN`. Each asserts the exit code and the message.

mod common;

use common::*;
use std::path::Path;
use std::process::{Command, Output};
use std::time::Duration;

/// Standard error holds no number printed in full (a run of more than 20 digits).
fn assert_compact(err: &str) {
    let mut run = 0;
    for c in err.chars() {
        run = if c.is_ascii_digit() { run + 1 } else { 0 };
        assert!(run <= 20, "a number in hundreds of digits: {err}");
    }
}

/// `efsi check` and `efsi run` of `scene` with `args` both exit with 2 and every needle.
fn refused(dir: &Path, scene: &Path, args: &[&str], needles: &[&str]) -> String {
    let scene = scene.to_str().unwrap();
    let out = dir.join("out");
    let mut last = String::new();
    for mut cmd in [
        vec!["check", scene],
        vec!["run", scene, "-q", "--out", out.to_str().unwrap()],
    ] {
        cmd.extend_from_slice(args);
        let o = efsi(&cmd);
        let err = stderr(&o);
        assert_eq!(o.status.code(), Some(2), "{cmd:?}: {err}");
        for n in needles {
            assert!(err.contains(n), "`{n}` not in: {err}");
        }
        assert_compact(&err);
        assert!(err.len() < 1_500, "{} bytes: {err}", err.len());
        last = err;
    }
    assert!(!out.join("probes.csv").exists(), "the run started");
    last
}

fn write(dir: &Path, name: &str, text: &str) -> std::path::PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, text).unwrap();
    p
}

/// Item 3: a `--set` value nested 10,000 levels is refused naming the override, cut short.
#[test]
fn deeply_nested_override_values_are_refused_by_name() {
    let d = tmp("nesting");
    let scene = write(&d, "c.ron", &cavity("c", 8, 0.1, "probes: [KineticEnergy]"));
    let deep = format!("{}1{}", "(".repeat(10_000), ")".repeat(10_000));
    for path in ["grid.nx", "domain.x", "solid.shape"] {
        let set = format!("{path}={deep}");
        let err = refused(
            &d,
            &scene,
            &["--set", &set],
            &[
                &format!("set {path}=(((("),
                "characters): ",
                "nested deeper than 128 levels, the most a scene may nest",
            ],
        );
        assert!(!err.contains(&"(".repeat(100)), "{err}");
    }
    // A string setting takes the text as the name: too long for a folder, refused.
    let set = format!("name={deep}");
    refused(
        &d,
        &scene,
        &["--set", &set],
        &[
            "set name=((((",
            "name: must be a non-empty name",
            "of at most 200 bytes",
        ],
    );
    // At the limit a value is read (and refused for its type, not its depth).
    let ok = format!("{}1{}", "(".repeat(120), ")".repeat(120));
    let set = format!("domain.x={ok}");
    let err = refused(&d, &scene, &["--set", &set], &["set domain.x="]);
    assert!(!err.contains("nested deeper"), "{err}");
}

/// Item 7: output and checkpoint intervals of 1e-300 with `time.dt_min = 1e-300` are refused
/// against the run's length; the densest allowed run stops on SIGTERM.
#[test]
fn intervals_tiny_against_the_run_are_refused_and_dense_runs_stop() {
    let d = tmp("intervals");
    let base = cavity("c", 8, 1.0, "probes: [KineticEnergy]")
        .replace("cfl: 0.5", "cfl: 0.5, dt_min: 1e-300");
    for (field, out) in [
        (
            "probe_every",
            "probe_every: 1e-300, probes: [KineticEnergy]",
        ),
        ("vtk_every", "vtk_every: 1e-300, probes: [KineticEnergy]"),
    ] {
        let scene = write(
            &d,
            &format!("{field}.ron"),
            &base.replace("probes: [KineticEnergy]", out),
        );
        refused(
            &d,
            &scene,
            &[],
            &[&format!(
                "output.{field}: must be at least time.end/1e12 = 1e-12, got 1e-300: a run has at most 1e12 outputs of one kind"
            )],
        );
    }
    let scene = write(&d, "ck.ron", &base);
    let out = d.join("ck_out");
    let o = efsi(&[
        "run",
        scene.to_str().unwrap(),
        "-q",
        "--out",
        out.to_str().unwrap(),
        "--checkpoint-every",
        "1e-300",
    ]);
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(
        err.contains("--checkpoint-every: checkpoint_every: must be at least time.end/1e12 = 1e-12, got 1e-300"),
        "{err}"
    );
    // The densest allowed: probes every 1e-12 of a run of 1 (1e12 rows to go); SIGTERM ends it.
    let scene = write(
        &d,
        "dense.ron",
        &base.replace(
            "probes: [KineticEnergy]",
            "probe_every: 1e-12, probes: [KineticEnergy]",
        ),
    );
    let out = d.join("dense_out");
    let mut child = spawn(&[
        "run",
        scene.to_str().unwrap(),
        "-q",
        "--out",
        out.to_str().unwrap(),
    ]);
    wait_rows(&mut child, &out, 20);
    let (code, err, took) = signal(child, libc::SIGTERM);
    assert_eq!(code, Some(143), "{err}");
    assert!(took < Duration::from_secs(5), "{took:?}");
    assert_csv_whole(&out);
}

/// Item 8: `describe-output`, `plot` and `resume` read files of bounded size, and never a
/// device.
#[test]
fn run_files_that_are_devices_are_refused_unread() {
    let d = tmp("devices");
    let scene = write(
        &d,
        "c.ron",
        &cavity(
            "c",
            8,
            0.2,
            "vtk_every: 0.1, probe_every: 0.05, probes: [KineticEnergy]",
        ),
    );
    let out = d.join("out");
    let o = efsi(&[
        "run",
        scene.to_str().unwrap(),
        "-q",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let out_s = out.to_str().unwrap();

    // A .pvd entry pointing at /dev/zero.
    let pvd = std::fs::read_to_string(out.join("fields.pvd")).unwrap();
    let first = pvd
        .split("file=\"")
        .nth(1)
        .unwrap()
        .split('"')
        .next()
        .unwrap()
        .to_string();
    std::fs::write(out.join("fields.pvd"), pvd.replace(&first, "/dev/zero")).unwrap();
    let o = efsi(&["plot", out_s, "--time", "0"]);
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(
        err.contains("/dev/zero: not a regular file (a device, a pipe or a socket)"),
        "{err}"
    );
    // `--time NaN` (item 16).
    let o = efsi(&["plot", out_s, "--time", "NaN"]);
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(err.contains("--time must be a finite time"), "{err}");

    // run.json as /dev/zero: describe-output.
    std::fs::remove_file(out.join("run.json")).unwrap();
    std::os::unix::fs::symlink("/dev/zero", out.join("run.json")).unwrap();
    let o = efsi(&["describe-output", out_s]);
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(
        err.contains("run.json: not a regular file (a device, a pipe or a socket)"),
        "{err}"
    );
}

/// Item 9: a thread count far beyond the cores is refused, from the option or the environment.
#[test]
fn thread_counts_beyond_a_multiple_of_the_cores_are_refused() {
    let d = tmp("threads");
    let scene = write(
        &d,
        "c.ron",
        &cavity("c", 8, 0.05, "probes: [KineticEnergy]"),
    );
    let out = d.join("out");
    let cores = std::thread::available_parallelism().unwrap().get();
    let limit = format!(
        "at most {} (4 per core; this machine has {cores} cores)",
        4 * cores
    );
    let o = efsi(&[
        "run",
        scene.to_str().unwrap(),
        "-q",
        "--out",
        out.to_str().unwrap(),
        "--threads",
        "100000",
    ]);
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(
        err.contains("--threads: worker threads: 100000 asked for, ") && err.contains(&limit),
        "{err}"
    );
    assert!(!out.exists());
    let o = Command::new(env!("CARGO_BIN_EXE_efsi"))
        .args([
            "run",
            scene.to_str().unwrap(),
            "-q",
            "--out",
            out.to_str().unwrap(),
        ])
        .env("RAYON_NUM_THREADS", "100000")
        .output()
        .unwrap();
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(
        err.contains("$RAYON_NUM_THREADS: worker threads: 100000 asked for"),
        "{err}"
    );
    // At the limit it runs.
    let n = (4 * cores).to_string();
    let o = efsi(&[
        "run",
        scene.to_str().unwrap(),
        "-q",
        "--out",
        out.to_str().unwrap(),
        "--threads",
        &n,
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
}

/// `efsi args…` under a file-size limit of `bytes`.
fn efsi_limited(args: &[&str], bytes: u64) -> Output {
    use std::os::unix::process::CommandExt as _;
    let mut c = Command::new(env!("CARGO_BIN_EXE_efsi"));
    c.args(args);
    // SAFETY: setrlimit only, between fork and exec.
    unsafe {
        c.pre_exec(move || {
            let lim = libc::rlimit {
                rlim_cur: bytes,
                rlim_max: bytes,
            };
            if libc::setrlimit(libc::RLIMIT_FSIZE, &lim) != 0 {
                return Err(std::io::Error::last_os_error());
            }
            Ok(())
        });
    }
    c.output().unwrap()
}

/// Item 10: past a file-size limit the run is not killed by SIGXFSZ: it stops as on a full
/// disk — probes.csv cut back to its last whole row, a checkpoint, run.json saying why — and
/// resumes once there is room.
#[test]
fn a_file_size_limit_stops_a_run_with_a_checkpoint_and_a_record() {
    let d = tmp("fsize");
    let text = cavity(
        "c",
        16,
        200.0,
        "probes: [KineticEnergy, MaxSpeed, MaxDivergence, Point(name: \"p\", field: \"p\", at: (0.5, 0.5))]",
    );
    let scene = write(&d, "c.ron", &text);
    let out = d.join("out");
    let limit = 512 * 1024;
    let o = efsi_limited(
        &[
            "run",
            scene.to_str().unwrap(),
            "-q",
            "--out",
            out.to_str().unwrap(),
        ],
        limit,
    );
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(
        err.contains("probes.csv: File too large")
            && err.contains("the file ends with its last whole row"),
        "{err}"
    );
    assert!(err.contains("was saved to the checkpoint"), "{err}");
    let rows = assert_csv_whole(&out);
    assert!(std::fs::metadata(out.join("probes.csv")).unwrap().len() <= limit);
    assert!(out.join("checkpoint/latest.efsick").is_file());
    assert!(!out.join("checkpoint/room").exists());
    let json: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out.join("run.json")).unwrap()).unwrap();
    let failed = &json["stop"]["Failed"];
    assert_eq!(failed["exit_code"], 1, "{json}");
    assert!(
        failed["error"].as_str().unwrap().contains("File too large"),
        "{json}"
    );
    // With the limit lifted, it resumes from the checkpoint and finishes.
    let o = efsi(&["resume", out.to_str().unwrap(), "-q"]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(assert_csv_whole(&out) > rows);
    assert!(!out.join("checkpoint/room").exists());
}

/// Item 11: a grid refined to nothing, and domains whose extent or cells overflow, are refused
/// naming the setting (and the override).
#[test]
fn grids_under_the_minimum_and_overflowing_domains_are_refused() {
    let d = tmp("grids");
    let scene = write(
        &d,
        "c.ron",
        &cavity("c", 64, 0.1, "probes: [KineticEnergy]"),
    );
    for f in ["1e-308", "0.01"] {
        refused(
            &d,
            &scene,
            &["--refine", f],
            &[
                &format!(
                    "refine {f}: grid.nx: must be at least 2 cells between sides that are not periodic"
                ),
                "got 1",
            ],
        );
    }
    refused(
        &d,
        &scene,
        &["--refine", "1e308"],
        &["refine 1e308: grid: more than 1e8 cells"],
    );
    refused(
        &d,
        &scene,
        &["--set", "domain.x=(-1e308,1e308)"],
        &["set domain.x=(-1e308,1e308): domain.x: its extent 1e308 − -1e308 overflows"],
    );
    refused(
        &d,
        &scene,
        &["--set", "domain.y=(0.0,1e-300)"],
        &[
            "set domain.y=(0.0,1e-300): domain.y: (0, 1e-300) with grid.ny = 64 gives cells of size 1.5625e-302",
        ],
    );
    refused(
        &d,
        &scene,
        &["--set", "domain.x=(1e10,1.0000000000001e10)"],
        &[
            "set domain.x=(1e10,1.0000000000001e10): domain.x: (1e10, 1.0000000000001e10) with grid.nx = 64 gives cells of size",
            "at least 2.220446049250313e-13 of the coordinates",
        ],
    );
    // Ten orders smaller than the adversary's 0.01 of 64 cells is refused; 2 cells across run.
    let o = efsi(&["check", scene.to_str().unwrap(), "--refine", "0.03125"]);
    assert!(o.status.success(), "{}", stderr(&o));
}

/// Item 12: numbers at the ends of `f64` are printed compactly in every message.
#[test]
fn huge_and_tiny_numbers_are_printed_compactly() {
    let d = tmp("numbers");
    let law = law_library("efsi_law_neo_hookean");
    let solid = write(
        &d,
        "s.ron",
        &solid_scene(law.to_str().unwrap(), "\"G\": 1e4"),
    );
    let cavity = write(&d, "c.ron", &cavity("c", 8, 0.1, "probes: [KineticEnergy]"));
    // Refused, the number compact in the message.
    for (scene, set, needle) in [
        (
            &solid,
            "solid.law.parameters.G=-1e308",
            "parameter `G` = -1e308 Pa is out of range",
        ),
        (
            &solid,
            "solid.density=1e308",
            "the density ratio solid/fluid 1e308",
        ),
        (&solid, "numerics.elastic.wave_courant=1e308", "got 1e308"),
        (&solid, "numerics.elastic.theta=1e308", "got 1e308"),
        (&cavity, "time.cfl=1e308", "got 1e308"),
        (&cavity, "fluid.viscosity=-1e308", "got -1e308"),
        (&cavity, "grid.nx=100000000000", "more than 1e8 cells"),
    ] {
        let o = efsi(&["check", scene.to_str().unwrap(), "--set", set]);
        let err = stderr(&o);
        assert_eq!(o.status.code(), Some(2), "{set}: {err}");
        assert!(err.contains(needle), "{set}: `{needle}` not in {err}");
        assert_compact(&err);
    }
    // Accepted or refused, never a number in hundreds of digits.
    for (scene, set) in [
        (&cavity, "fluid.density=1e308"),
        (&cavity, "fluid.density=5e-324"),
        (&cavity, "boundaries.y_max.speed=1e308"),
        (
            &cavity,
            "output.probes[0]=Point(name: \"q\", field: \"u\", at: (1e308, 0.5))",
        ),
        (&solid, "solid.law.parameters.G=1e-300"),
    ] {
        let o = efsi(&["check", scene.to_str().unwrap(), "--set", set]);
        assert_compact(&stderr(&o));
    }
    // The record of an accepted refinement.
    let out = d.join("out");
    let o = efsi(&[
        "run",
        cavity.to_str().unwrap(),
        "-q",
        "--refine",
        "0.3",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let json = std::fs::read_to_string(out.join("run.json")).unwrap();
    assert!(json.contains("\"refine 0.3\""), "{json}");
}

/// Item 13: an error in one override's setting blames that override, not a later one in the
/// same section.
#[test]
fn an_error_blames_the_override_that_set_the_value() {
    let d = tmp("blame");
    let law = law_library("efsi_law_neo_hookean");
    let text = solid_scene(law.to_str().unwrap(), "\"G\": 1e4").replace(
        "HalfPlane(normal: (0.0, 1.0), offset: 0.5)",
        "Disk(center: (0.03, 0.5), radius: 0.02)",
    );
    let scene = write(&d, "s.ron", &text);
    let o = efsi(&[
        "check",
        scene.to_str().unwrap(),
        "--set",
        "solid.shape.radius=0",
        "--set",
        "solid.shape.center[1]=0.05",
    ]);
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(
        err.contains("set solid.shape.radius=0: solid.shape.radius: Disk: radius must be finite and > 0, got 0"),
        "{err}"
    );
    assert!(!err.contains("center[1]"), "{err}");
}

/// Item 16: a profile that names a field twice is refused (its CSV would repeat a column).
#[test]
fn a_profile_naming_a_field_twice_is_refused() {
    let d = tmp("profile");
    let scene = write(
        &d,
        "c.ron",
        &cavity(
            "c",
            8,
            0.1,
            "probes: [KineticEnergy], profiles: [Line(name: \"mid\", from: (0.5, 0.0), to: (0.5, 1.0), points: 5, fields: [\"u\", \"u\", \"v\"])]",
        ),
    );
    refused(
        &d,
        &scene,
        &[],
        &[
            "output.profiles[0].fields[1]: `u` is listed twice (each field is one column of the CSV)",
        ],
    );
}
