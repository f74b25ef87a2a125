//! Helpers shared by the CLI's integration tests: scratch folders, running `efsi`, scenes.

#![allow(dead_code)]

use std::path::{Path, PathBuf};
use std::process::{Child, Command, Output, Stdio};
use std::time::{Duration, Instant};

/// A test's scratch folder, made fresh; removed when the test passes and kept when it fails
/// (a panic), for a look at what the run left. Derefs to its path.
pub struct Scratch(PathBuf);

impl std::ops::Deref for Scratch {
    type Target = Path;
    fn deref(&self) -> &Path {
        &self.0
    }
}

impl AsRef<Path> for Scratch {
    fn as_ref(&self) -> &Path {
        &self.0
    }
}

impl Drop for Scratch {
    fn drop(&mut self) {
        if !std::thread::panicking() {
            let _ = std::fs::remove_dir_all(&self.0);
        }
    }
}

/// A fresh scratch folder for test `name` (see [`Scratch`]).
pub fn tmp(name: &str) -> Scratch {
    let d = std::env::temp_dir().join(format!("efsi-cli-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    Scratch(d)
}

/// Run `efsi args…` to its end.
pub fn efsi(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_efsi"))
        .args(args)
        .output()
        .expect("run efsi")
}

/// Standard error as text.
pub fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// A cavity of `n`² cells to `end`, probes at every step unless `probe_every` is given.
pub fn cavity(name: &str, n: usize, end: f64, output: &str) -> String {
    format!(
        r#"Scene(
    name: "{name}",
    domain: (x: (0.0, 1.0), y: (0.0, 1.0)),
    grid: (nx: {n}, ny: {n}),
    time: (end: {end:?}, cfl: 0.5),
    fluid: (density: 1.0, viscosity: 0.01),
    boundaries: (x_min: NoSlip, x_max: NoSlip, y_min: NoSlip, y_max: MovingWall(speed: 1.0)),
    output: ({output}),
)
"#
    )
}

/// Lines in `dir/probes.csv` (0 if absent).
pub fn probe_rows(dir: &Path) -> usize {
    std::fs::read_to_string(dir.join("probes.csv")).map_or(0, |s| s.lines().count())
}

/// Start `efsi args…` with standard error piped.
pub fn spawn(args: &[&str]) -> Child {
    Command::new(env!("CARGO_BIN_EXE_efsi"))
        .args(args)
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .expect("spawn efsi")
}

/// Wait until `dir/probes.csv` has more than `rows` lines while `child` runs.
pub fn wait_rows(child: &mut Child, dir: &Path, rows: usize) {
    let start = Instant::now();
    while probe_rows(dir) <= rows {
        assert!(
            child.try_wait().unwrap().is_none(),
            "efsi ended before it could be interrupted"
        );
        assert!(start.elapsed() < Duration::from_secs(60), "no progress");
        std::thread::sleep(Duration::from_millis(5));
    }
}

/// Send `signal` to `child` and wait for it: exit code, standard error and the time it took
/// to exit after the signal.
pub fn signal(child: Child, signal: i32) -> (Option<i32>, String, Duration) {
    let t0 = Instant::now();
    // SAFETY: plain kill(2) on a child we spawned and have not waited for.
    let r = unsafe { libc::kill(child.id() as libc::pid_t, signal) };
    assert_eq!(r, 0);
    let out = child.wait_with_output().unwrap();
    (out.status.code(), stderr(&out), t0.elapsed())
}

/// Every row of `dir/probes.csv` has the header's number of columns, parses as numbers and
/// ends with a newline; returns the number of rows.
pub fn assert_csv_whole(dir: &Path) -> usize {
    let csv = std::fs::read_to_string(dir.join("probes.csv")).unwrap();
    assert!(
        csv.ends_with('\n'),
        "probes.csv ends mid-row: {:?}",
        &csv[csv.len().saturating_sub(80)..]
    );
    let mut lines = csv.lines();
    let columns = lines.next().unwrap().split(',').count();
    let mut rows = 0;
    for l in lines {
        let v: Vec<&str> = l.split(',').collect();
        assert_eq!(v.len(), columns, "{l}");
        for x in v {
            let v: f64 = x.parse().unwrap_or_else(|_| panic!("`{x}` in {l}"));
            if v.is_finite() {
                // Whole: 17 decimals and an exponent (`{:.17e}`), not a cut-off prefix.
                let digits = x.split_once('e').and_then(|(m, _)| m.split_once('.'));
                assert_eq!(digits.map(|d| d.1.len()), Some(17), "cut `{x}` in {l}");
            }
        }
        rows += 1;
    }
    rows
}

/// A law plugin library built with the workspace, by library name.
pub fn law_library(lib: &str) -> PathBuf {
    let file = format!(
        "{}{lib}{}",
        std::env::consts::DLL_PREFIX,
        std::env::consts::DLL_SUFFIX
    );
    let bin = Path::new(env!("CARGO_BIN_EXE_efsi")).parent().unwrap();
    [bin.to_path_buf(), bin.join("deps")]
        .iter()
        .map(|d| d.join(&file))
        .find(|p| p.is_file())
        .unwrap_or_else(|| panic!("{file} not built next to {}", bin.display()))
}

/// A small box with an elastic block whose law is `law` (a library path) with `params`.
pub fn solid_scene(law: &str, params: &str) -> String {
    solid_scene_with_output(law, params, "probe_every: 0.05, probes: [KineticEnergy]")
}

/// [`solid_scene`] with the `output` section's settings given.
pub fn solid_scene_with_output(law: &str, params: &str, output: &str) -> String {
    format!(
        r#"Scene(
    name: "solid",
    domain: (x: (0.0, 0.0625), y: (0.0, 1.0)),
    grid: (nx: 4, ny: 16),
    time: (end: 0.6, dt_max: 0.01),
    fluid: (density: 1.0, viscosity: 1.0),
    solid: (shape: HalfPlane(normal: (0.0, 1.0), offset: 0.5), density: 1.0, viscosity: 0.0,
            law: (name: "{law}", parameters: {{{params}}})),
    boundaries: (x_min: Periodic, x_max: Periodic, y_min: NoSlip,
                 y_max: MovingWall(speed: 1.0, motion: Sin(omega: 3.141592653589793))),
    output: ({output}),
)
"#
    )
}
