//! Project automation.
//!
//! - `cargo xtask test`: everything CI runs — formatting, clippy (warnings are errors), the Rust
//!   test suite, and the Python tests (VTK files read back by the official `vtk` wheel) in a
//!   virtual environment under `target/venv` that it creates on first use.
//! - `cargo xtask run SCENE [ARGS…]`: build the whole workspace in release (the `efsi` binary
//!   and the law plugin libraries it loads) and run `efsi run SCENE ARGS…`.
//! - `cargo xtask ghia DIR RE`: max |deviation| of a finished cavity run's last centreline
//!   profiles (`DIR/profiles/u_x0.5_t*.csv`, `v_y0.5_t*.csv`) from Ghia et al. (1982).
//! - `cargo xtask bench [--out DIR]`: the Re = 1000 lid-driven cavity at 128², one thread, for
//!   ns per cell-step in total and per stage and Poisson iterations per step (a benchmark,
//!   not a test: timings are never asserted).
//! - `cargo xtask fmu`: build the sphere-impact FMU library and the shipped laws (release) and
//!   package `target/fmu/sphere_impact.fmu` (FMI 2.0 Co-Simulation) and
//!   `target/fmu/sphere_impact_fmi3.fmu` (FMI 3.0 Co-Simulation).

mod zip;

use std::path::{Path, PathBuf};
use std::process::{Command, ExitCode};

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .parent()
        .expect("workspace root")
        .to_path_buf()
}

fn cargo() -> Command {
    Command::new(std::env::var("CARGO").unwrap_or_else(|_| "cargo".into()))
}

/// Run a command in the workspace root; Err names it if it fails.
fn run(mut cmd: Command, what: &str) -> Result<(), String> {
    eprintln!("==> {what}");
    let status = cmd
        .current_dir(root())
        .status()
        .map_err(|e| format!("{what}: cannot start: {e}"))?;
    if status.success() {
        Ok(())
    } else {
        Err(format!("{what}: failed ({status})"))
    }
}

fn python_env() -> Result<PathBuf, String> {
    let venv = root().join("target/venv");
    let py = venv.join("bin/python");
    let stamp = venv.join(".requirements");
    let req = root().join("tests/python/requirements.txt");
    let wanted = std::fs::read_to_string(&req).map_err(|e| format!("{}: {e}", req.display()))?;
    if !py.exists() {
        let mut c = Command::new("python3");
        c.args(["-m", "venv"]).arg(&venv);
        run(c, "create the Python virtual environment (target/venv)")?;
    }
    if std::fs::read_to_string(&stamp).ok().as_deref() != Some(wanted.as_str()) {
        let mut c = Command::new(&py);
        c.args([
            "-m",
            "pip",
            "install",
            "--quiet",
            "--disable-pip-version-check",
            "-r",
        ])
        .arg(&req);
        run(
            c,
            "install the Python test requirements (vtk, numpy, pytest, fmpy)",
        )?;
        std::fs::write(&stamp, wanted).map_err(|e| e.to_string())?;
    }
    Ok(py)
}

/// The shipped laws' packages and library stems, packaged beside the FMU library.
const LAWS: [(&str, &str); 3] = [
    ("efsi-law-neo-hookean", "efsi_law_neo_hookean"),
    (
        "efsi-law-saint-venant-kirchhoff",
        "efsi_law_saint_venant_kirchhoff",
    ),
    ("efsi-law-mooney-rivlin", "efsi_law_mooney_rivlin"),
];

/// Build (release) and package both FMUs; returns their paths.
fn fmu() -> Result<[PathBuf; 2], String> {
    let mut c = cargo();
    c.args(["build", "--quiet", "--release", "-p", "efsi-fmu"]);
    for (package, _) in LAWS {
        c.args(["-p", package]);
    }
    run(c, "build the FMU library and the shipped laws (release)")?;
    let release = root().join("target/release");
    let read = |p: &Path| std::fs::read(p).map_err(|e| format!("{}: {e}", p.display()));
    let describe = |what: &str| -> Result<Vec<u8>, String> {
        let out = Command::new(release.join("efsi-fmu-description"))
            .arg(what)
            .output()
            .map_err(|e| format!("efsi-fmu-description: {e}"))?;
        if !out.status.success() {
            return Err(format!("efsi-fmu-description {what}: {}", out.status));
        }
        Ok(out.stdout)
    };
    let library = read(&release.join("libsphere_impact.so"))?;
    let laws = LAWS
        .iter()
        .map(|(_, stem)| {
            let name = format!("lib{stem}.so");
            read(&release.join(&name)).map(|d| (name, d))
        })
        .collect::<Result<Vec<_>, _>>()?;
    let scene = describe("scene")?;
    let dir = root().join("target/fmu");
    std::fs::create_dir_all(&dir).map_err(|e| format!("{}: {e}", dir.display()))?;
    let mut made = Vec::new();
    for (version, platform, file) in [
        ("2", "linux64", "sphere_impact.fmu"),
        ("3", "x86_64-linux", "sphere_impact_fmi3.fmu"),
    ] {
        let mut z = zip::Zip::default();
        let add = |z: &mut zip::Zip, name: &str, data: &[u8]| {
            z.add(name, data)
                .map_err(|e| format!("{file}: {name}: {e}"))
        };
        add(&mut z, "modelDescription.xml", &describe(version)?)?;
        add(
            &mut z,
            &format!("binaries/{platform}/sphere_impact.so"),
            &library,
        )?;
        for (name, data) in &laws {
            add(&mut z, &format!("binaries/{platform}/{name}"), data)?;
        }
        add(&mut z, "resources/sphere_impact.ron", &scene)?;
        let path = dir.join(file);
        std::fs::write(&path, z.finish()).map_err(|e| format!("{}: {e}", path.display()))?;
        let bytes = std::fs::metadata(&path).map(|m| m.len()).unwrap_or(0);
        eprintln!(
            "wrote {} (FMI {version}.0 Co-Simulation, {:.1} MB)",
            path.display(),
            bytes as f64 / 1e6
        );
        made.push(path);
    }
    let [a, b] = <[PathBuf; 2]>::try_from(made).map_err(|_| "two FMUs".to_string())?;
    Ok([a, b])
}

fn test() -> Result<(), String> {
    let mut c = cargo();
    c.args(["fmt", "--all", "--", "--check"]);
    run(c, "cargo fmt --check")?;
    let mut c = cargo();
    c.args([
        "clippy",
        "--workspace",
        "--all-targets",
        "--quiet",
        "--",
        "-D",
        "warnings",
    ]);
    run(c, "cargo clippy -D warnings")?;
    let mut c = cargo();
    c.args(["test", "--workspace", "--all-targets"]);
    run(c, "cargo test")?;
    // The binary the Python tests drive, built with the test profile settings (optimised).
    let mut c = cargo();
    c.args(["build", "--quiet", "-p", "efsi", "--profile", "test"]);
    run(c, "build efsi for the Python tests")?;
    let [fmu2, fmu3] = fmu()?;
    let py = python_env()?;
    let mut c = Command::new(py);
    c.args(["-m", "pytest", "-q", "--durations=5", "tests/python"])
        .env("EFSI_BIN", root().join("target/debug/efsi"))
        .env("EFSI_FMU2", fmu2)
        .env("EFSI_FMU3", fmu3);
    run(c, "pytest tests/python")
}

fn bench(args: &[String]) -> Result<(), String> {
    let out = args
        .windows(2)
        .find(|w| w[0] == "--out")
        .map(|w| PathBuf::from(&w[1]))
        .unwrap_or_else(|| root().join("target/bench"));
    let mut c = cargo();
    c.args(["build", "--quiet", "--release", "-p", "efsi"]);
    run(c, "build efsi (release)")?;
    let scene = root().join("cases/lid_driven_cavity_re1000.ron");
    let text = std::fs::read_to_string(&scene).map_err(|e| e.to_string())?;
    // A fixed number of steps' worth of time from rest keeps runs comparable.
    let text = text
        .replace("end: 100.0", "end: 2.0")
        .replace("steady: 1e-6", "dt_max: 1.0");
    std::fs::create_dir_all(&out).map_err(|e| e.to_string())?;
    let bench_scene = out.join("cavity_re1000_128.ron");
    std::fs::write(&bench_scene, text).map_err(|e| e.to_string())?;
    let mut c = Command::new(root().join("target/release/efsi"));
    c.arg("run")
        .arg(&bench_scene)
        .arg("--out")
        .arg(out.join("cavity_re1000_128"))
        .arg("-q");
    c.env("RAYON_NUM_THREADS", "1");
    run(c, "Re = 1000 cavity, 128², t ∈ [0, 2], one thread")?;
    eprintln!(
        "figures: {}",
        out.join("cavity_re1000_128/run.json").display()
    );
    Ok(())
}

/// Rows of a CSV (comment lines skipped) as header → values.
fn read_csv(path: &Path) -> Result<(Vec<String>, Vec<Vec<f64>>), String> {
    let text = std::fs::read_to_string(path).map_err(|e| format!("{}: {e}", path.display()))?;
    let mut lines = text
        .lines()
        .filter(|l| !l.starts_with('#') && !l.trim().is_empty());
    let header: Vec<String> = lines
        .next()
        .unwrap_or_default()
        .split(',')
        .map(|s| s.trim().to_string())
        .collect();
    let mut cols = vec![Vec::new(); header.len()];
    for l in lines {
        for (k, v) in l.split(',').enumerate().take(header.len()) {
            cols[k].push(
                v.trim()
                    .parse::<f64>()
                    .map_err(|e| format!("{}: {e}", path.display()))?,
            );
        }
    }
    Ok((header, cols))
}

fn column<'a>(
    h: &[String],
    c: &'a [Vec<f64>],
    name: &str,
    path: &Path,
) -> Result<&'a [f64], String> {
    h.iter()
        .position(|n| n == name)
        .map(|k| c[k].as_slice())
        .ok_or_else(|| format!("{}: no column `{name}`", path.display()))
}

/// The profile with the latest time among `DIR/profiles/<stem>_t*.csv`.
fn last_profile(dir: &Path, stem: &str) -> Result<PathBuf, String> {
    let prefix = format!("{stem}_t");
    let mut best: Option<(f64, PathBuf)> = None;
    for e in
        std::fs::read_dir(dir.join("profiles")).map_err(|e| format!("{}: {e}", dir.display()))?
    {
        let p = e.map_err(|e| e.to_string())?.path();
        let name = p
            .file_name()
            .and_then(|n| n.to_str())
            .unwrap_or_default()
            .to_string();
        if let Some(t) = name
            .strip_prefix(&prefix)
            .and_then(|r| r.strip_suffix(".csv"))
            .and_then(|t| t.parse::<f64>().ok())
            && best.as_ref().is_none_or(|(b, _)| t > *b)
        {
            best = Some((t, p));
        }
    }
    best.map(|(_, p)| p)
        .ok_or_else(|| format!("no {prefix}*.csv in {}", dir.join("profiles").display()))
}

fn ghia(args: &[String]) -> Result<(), String> {
    let [dir, re] = args else {
        return Err("usage: cargo xtask ghia DIR RE".into());
    };
    let dir = PathBuf::from(dir);
    let refs = root().join("../shared/references/ghia1982");
    for (stem, field, coord, file) in [
        (
            "u_x0.5",
            "u",
            "y",
            "ghia1982_u_vertical_centerline_x0.5.csv",
        ),
        (
            "v_y0.5",
            "v",
            "x",
            "ghia1982_v_horizontal_centerline_y0.5.csv",
        ),
    ] {
        let prof = last_profile(&dir, stem)?;
        let (h, c) = read_csv(&prof)?;
        let (s, f) = (column(&h, &c, coord, &prof)?, column(&h, &c, field, &prof)?);
        let rpath = refs.join(file);
        let (rh, rc) = read_csv(&rpath)?;
        let (rs, rf) = (
            column(&rh, &rc, coord, &rpath)?,
            column(&rh, &rc, &format!("{field}_Re{re}"), &rpath)?,
        );
        let mut dev = 0.0f64;
        for (&x, &want) in rs.iter().zip(rf) {
            let k = s.partition_point(|&a| a < x).clamp(1, s.len() - 1);
            let w = (x - s[k - 1]) / (s[k] - s[k - 1]);
            dev = dev.max((f[k - 1] * (1.0 - w) + f[k] * w - want).abs());
        }
        println!(
            "{}: max |{field} − Ghia| = {dev:.4} over {} points",
            prof.display(),
            rs.len()
        );
    }
    Ok(())
}

fn run_scene(args: &[String]) -> Result<(), String> {
    if args.is_empty() {
        return Err("usage: cargo xtask run SCENE [efsi run options]".into());
    }
    let mut c = cargo();
    c.args(["build", "--quiet", "--release", "--workspace"]);
    run(c, "build efsi and the law plugins (release)")?;
    let mut c = Command::new(root().join("target/release/efsi"));
    c.arg("run").args(args);
    let status = c.status().map_err(|e| format!("cannot start efsi: {e}"))?;
    if status.success() {
        Ok(())
    } else {
        std::process::exit(status.code().unwrap_or(1))
    }
}

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let result = match args.first().map(String::as_str) {
        Some("test") => test(),
        Some("bench") => bench(&args[1..]),
        Some("ghia") => ghia(&args[1..]),
        Some("run") => run_scene(&args[1..]),
        Some("bench-paper") => bench_paper(&args[1..]),
        Some("fmu") => fmu().map(|_| ()),
        _ => Err(
            "usage: cargo xtask <run SCENE | test | fmu | bench [--out DIR] | bench-paper \
             [--quick] [--case NAME]… [--out DIR] | ghia DIR RE>"
                .into(),
        ),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("xtask: {e}");
            ExitCode::FAILURE
        }
    }
}

/// `cargo xtask bench-paper [--quick] [--case NAME…] [--out DIR]`: build the workspace (release,
/// so the law libraries exist) and run the paper's cases (`tests/src/paper/`). Exits with the
/// runner's status (1 if a check failed).
fn bench_paper(args: &[String]) -> Result<(), String> {
    let mut c = cargo();
    c.args(["build", "--quiet", "--release", "--workspace"]);
    run(c, "build efsi, the law plugins and bench-paper (release)")?;
    let mut c = Command::new(root().join("target/release/bench-paper"));
    c.args(args).current_dir(root());
    let status = c
        .status()
        .map_err(|e| format!("cannot start bench-paper: {e}"))?;
    if status.success() {
        Ok(())
    } else {
        std::process::exit(status.code().unwrap_or(1))
    }
}
