//! Project automation.
//!
//! - `cargo xtask test`: everything CI runs — formatting, clippy and rustdoc (warnings are
//!   errors), the Rust test suite, and the Python tests (VTK files read back by the official `vtk` wheel,
//!   the FMUs, the `efsi` Python package built by maturin and installed there, sweeps on a local
//!   Dask cluster) in a virtual environment under `target/venv` that it creates on first use.
//! - `cargo xtask run SCENE [ARGS…]`: build the whole workspace in release (the `efsi` binary
//!   and the law plugin libraries it loads) and run `efsi run SCENE ARGS…`.
//! - `cargo xtask ghia DIR RE`: max |deviation| of a finished cavity run's last centreline
//!   profiles (`DIR/profiles/u_x0.5_t*.csv`, `v_y0.5_t*.csv`) from Ghia et al. (1982); refuses a
//!   run whose Reynolds number (`ρ U L / μ` of the scene in `DIR/run.json`) is not `RE`, and names
//!   the Reynolds numbers the reference has when it has no column for `RE`.
//! - `cargo xtask bench [--quick] [--cases LIST] [--threads N] [--repeat R] [--out DIR]`: the
//!   Re = 1000 lid-driven cavity and the axisymmetric falling drop (cases `cavity<N>`,
//!   `drop<N>`, suffix `-ic` for the IC(0) pressure preconditioner, `-vmg` for the block
//!   multigrid viscous one) and the sphere impact at 35 cells per radius (case `sphere`, the
//!   whole run of `cases/sphere_impact.ron`; `-ej` for the Jacobi-preconditioned elastic step;
//!   default `cavity128,cavity256,drop128,drop256,sphere`), each on one thread and on N
//!   (default all), for ns
//!   per cell-step in total and per stage, solver iterations per step and the drop's fall;
//!   medians of R runs (the 1- and N-thread runs alternate; the speed-up of each pair is
//!   printed as a range and kept in the JSON), written to `DIR/bench.json` (default
//!   `target/bench`). A benchmark, not a test: timings are never asserted. With `--roofline`
//!   it also measures the machine's triad bandwidth and prints, per case and stage, the bytes
//!   per cell-step of a compulsory-traffic model, the achieved bandwidth and its fraction of the
//!   limit ([`roofline`]).
//! - `cargo xtask fmu [SCENE [--parameter PATH[=UNIT]] [--input NAME[=UNIT]]
//!   [--output PROBE[=UNIT]] [--range NAME=MIN..MAX]…]`: build the FMU library and the shipped
//!   laws (profile `fmu-release`: release code, stripped) and package the scene as
//!   `target/fmu/<name>.fmu` (FMI 2.0 Co-Simulation) and `target/fmu/<name>_fmi3.fmu` (FMI 3.0),
//!   with their documentation and licence; without a scene, the sphere impact.

mod roofline;
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
            "install the Python test requirements (vtk, numpy, pytest, fmpy, ecospy, maturin, dask, pandas, pyarrow)",
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

/// The cargo profile the FMUs' libraries are built with (release code, stripped; see the
/// workspace's Cargo.toml) and its output folder under `target/`.
const FMU_PROFILE: &str = "fmu-release";

/// `cargo xtask fmu [SCENE [FLAGS…]]`: build the FMU library and the shipped laws (profile
/// [`FMU_PROFILE`]) and package the scene as `target/fmu/<name>.fmu` (FMI 2.0) and
/// `target/fmu/<name>_fmi3.fmu` (FMI 3.0); without a scene, the sphere-impact FMU. The flags
/// (`--parameter PATH[=UNIT]`, `--input NAME[=UNIT]`, `--output PROBE[=UNIT]`,
/// `--range NAME=MIN..MAX`) are checked against the scene by `efsi-fmu-package`. Returns the
/// two FMUs' paths.
fn fmu(args: &[String]) -> Result<[PathBuf; 2], String> {
    let mut c = cargo();
    c.args([
        "build",
        "--quiet",
        "--profile",
        FMU_PROFILE,
        "-p",
        "efsi-fmu",
    ]);
    for (package, _) in LAWS {
        c.args(["-p", package]);
    }
    run(
        c,
        "build the FMU library and the shipped laws (stripped release)",
    )?;
    let release = root().join("target").join(FMU_PROFILE);
    let read = |p: &Path| std::fs::read(p).map_err(|e| format!("{}: {e}", p.display()));
    let dir = root().join("target/fmu");
    let staging = dir.join(".staging");
    let _ = std::fs::remove_dir_all(&staging);
    let mut c = Command::new(release.join("efsi-fmu-package"));
    c.arg(&staging);
    if args.is_empty() {
        c.arg("sphere");
    } else {
        c.args(args);
    }
    run(c, "check the FMU's interface against its scene")?;
    let identifier = String::from_utf8(read(&staging.join("identifier"))?)
        .map_err(|_| "identifier: not UTF-8".to_string())?;
    let library = read(&release.join("libefsi_fmu.so"))?;
    let laws = LAWS
        .iter()
        .map(|(_, stem)| {
            let name = format!("lib{stem}.so");
            read(&release.join(&name)).map(|d| (name, d))
        })
        .collect::<Result<Vec<_>, _>>()?;
    let mut made = Vec::new();
    for (version, platform, file) in [
        ("2", "linux64", format!("{identifier}.fmu")),
        ("3", "x86_64-linux", format!("{identifier}_fmi3.fmu")),
    ] {
        let mut z = zip::Zip::default();
        let mut add = |name: &str, data: &[u8]| {
            z.add(name, data)
                .map_err(|e| format!("{file}: {name}: {e}"))
        };
        add(
            "modelDescription.xml",
            &read(&staging.join(format!("modelDescription-{version}.xml")))?,
        )?;
        add(&format!("binaries/{platform}/{identifier}.so"), &library)?;
        for (name, data) in &laws {
            add(&format!("binaries/{platform}/{name}"), data)?;
        }
        add("resources/fmu.ron", &read(&staging.join("fmu.ron"))?)?;
        add("resources/scene.ron", &read(&staging.join("scene.ron"))?)?;
        add(
            "documentation/index.html",
            &read(&staging.join("index.html"))?,
        )?;
        add(
            "documentation/licenses/license.txt",
            &read(&staging.join("license.txt"))?,
        )?;
        let path = dir.join(&file);
        std::fs::write(&path, z.finish()).map_err(|e| format!("{}: {e}", path.display()))?;
        let bytes = std::fs::metadata(&path).map(|m| m.len()).unwrap_or(0);
        eprintln!(
            "wrote {} (FMI {version}.0 Co-Simulation, {:.2} MB; library {:.2} MB)",
            path.display(),
            bytes as f64 / 1e6,
            library.len() as f64 / 1e6
        );
        made.push(path);
    }
    // The reference result (FMI Cross-Check layout) beside the FMUs, where there is one.
    let compat = root().join("fmu/compat").join(&identifier);
    if let Ok(entries) = std::fs::read_dir(&compat) {
        for e in entries {
            let p = e.map_err(|e| e.to_string())?.path();
            if let Some(name) = p.file_name() {
                std::fs::copy(&p, dir.join(name)).map_err(|e| format!("{}: {e}", p.display()))?;
            }
        }
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
    // The API docs build without a warning (broken or private intra-doc links).
    let mut c = cargo();
    c.args(["doc", "--workspace", "--no-deps", "--quiet"])
        .env("RUSTDOCFLAGS", "-D warnings");
    run(c, "cargo doc -D warnings")?;
    let mut c = cargo();
    c.args(["test", "--workspace", "--all-targets"]);
    run(c, "cargo test")?;
    // The binary the Python tests drive, built with the test profile settings (optimised).
    let mut c = cargo();
    c.args(["build", "--quiet", "-p", "efsi", "--profile", "test"]);
    run(c, "build efsi for the Python tests")?;
    // The sphere impact, and two scenes packaged as they are: the oscillating Couette flow
    // with the wall's speed amplitude as a parameter, the disk in a cavity with the lid's speed
    // as an input.
    let [fmu2, _] = fmu(&[])?;
    let strings = |a: &[&str]| a.iter().map(|s| s.to_string()).collect::<Vec<_>>();
    fmu(&strings(&[
        "cases/oscillating_couette.ron",
        "--parameter",
        "boundaries.y_max.speed=m/s",
        "--output",
        "u_interface=m/s",
    ]))?;
    fmu(&strings(&[
        "cases/disk_in_cavity.ron",
        "--input",
        "boundaries.y_max.speed=m/s",
    ]))?;
    let py = python_env()?;
    install_python_package(&py)?;
    let mut c = Command::new(py);
    c.args(["-m", "pytest", "-q", "--durations=5", "tests/python"])
        .env("EFSI_BIN", root().join("target/debug/efsi"))
        .env(
            "EFSI_FMU_DIR",
            fmu2.parent().map(Path::to_path_buf).unwrap_or_default(),
        );
    run(c, "pytest tests/python")
}

/// Build the `efsi` Python package's wheel (python/, maturin, release: `--profile test` would
/// make `cargo rustc` build the test harness instead of the module) into `target/wheels` and
/// install it into the venv of `py`, replacing an earlier one.
fn install_python_package(py: &Path) -> Result<(), String> {
    let wheels = root().join("target/wheels");
    let _ = std::fs::remove_dir_all(&wheels);
    let mut c = Command::new(py);
    c.args(["-m", "maturin", "build", "--quiet", "--release", "-m"])
        .arg(root().join("python/Cargo.toml"))
        .arg("--out")
        .arg(&wheels);
    run(c, "build the efsi Python package (maturin)")?;
    let wheel = std::fs::read_dir(&wheels)
        .map_err(|e| format!("{}: {e}", wheels.display()))?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .find(|p| p.extension().is_some_and(|x| x == "whl"))
        .ok_or_else(|| format!("{}: maturin left no wheel", wheels.display()))?;
    let mut c = Command::new(py);
    c.args([
        "-m",
        "pip",
        "install",
        "--quiet",
        "--disable-pip-version-check",
        "--no-deps",
        "--force-reinstall",
    ])
    .arg(&wheel);
    run(c, "install the efsi Python package into target/venv")
}

/// A benchmark case: `cavity<N>` (Re = 1000 lid-driven cavity, N², t ∈ [0, 2]) or `drop<N>`
/// (axisymmetric drop, ρ 1 in 1e-3, μ 1e-2 in 2e-4, g = 1, box 4 × 4, N², t ∈ [0, 1],
/// Δt = 0.5/N), optionally suffixed `-ic` for the IC(0) pressure preconditioner and/or `-vmg`
/// for the block-multigrid viscous preconditioner; or `sphere`, the sphere impact of
/// `cases/sphere_impact.ron` (35 cells per radius, 82 × 164, the whole run; `--quick` until
/// t = 0.03), suffix `-ej` for the Jacobi-preconditioned elastic step.
struct Case {
    name: String,
    scene: String,
    drop: bool,
    cells: usize,
}

fn case(name: &str, quick: bool) -> Result<Case, String> {
    // Suffixes: -ic (IC(0) pressure preconditioner), -vmg (block multigrid for the viscous
    // step instead of the default Jacobi).
    let (rest, viscous) = match name.strip_suffix("-vmg") {
        Some(b) => (b, "Multigrid"),
        None => (name, "Jacobi"),
    };
    let (base, solver) = match rest.strip_suffix("-ic") {
        Some(b) => (b, "IncompleteCholesky"),
        None => (rest, "Multigrid"),
    };
    let bad = || {
        format!(
            "unknown case `{name}`: expected cavity<N> or drop<N>, optionally -ic, -vmg; or sphere, \
             optionally -ej"
        )
    };
    if let Some(rest) = name.strip_prefix("sphere") {
        // The sphere impact as shipped (35 cells per radius, t ∈ [0, 0.06]); quick: until
        // t = 0.03, just after first contact. Suffix -ej: Jacobi-preconditioned elastic step.
        let elastic = match rest {
            "" => "Multigrid",
            "-ej" => "Jacobi",
            _ => return Err(bad()),
        };
        let path = root().join("cases/sphere_impact.ron");
        let text =
            std::fs::read_to_string(&path).map_err(|e| format!("{}: {e}", path.display()))?;
        let mut scene = text.replace(
            " elastic: (",
            &format!(" elastic: (preconditioner: {elastic}, "),
        );
        if quick {
            scene = scene.replace("end: 0.06,", "end: 0.03,");
        }
        if !scene.contains("preconditioner") || (quick && !scene.contains("end: 0.03,")) {
            return Err(format!("{}: not the expected scene layout", path.display()));
        }
        return Ok(Case {
            name: name.to_string(),
            scene,
            drop: false,
            cells: 82 * 164,
        });
    }
    let (drop, n) = if let Some(n) = base.strip_prefix("cavity") {
        (false, n.parse::<usize>().map_err(|_| bad())?)
    } else if let Some(n) = base.strip_prefix("drop") {
        (true, n.parse::<usize>().map_err(|_| bad())?)
    } else {
        return Err(bad());
    };
    if n < 8 {
        return Err(bad());
    }
    let scene = if drop {
        let end = if quick { 0.25 } else { 1.0 };
        format!(
            r#"// Axisymmetric drop falling from rest (cargo xtask bench).
Scene(
    name: "{name}",
    geometry: Axisymmetric,
    domain: (r: (0.0, 4.0), z: (0.0, 4.0)),
    grid: (nr: {n}, nz: {n}),
    time: (end: {end}, fixed_dt: {dt:e}),
    fluid: (density: 1e-3, viscosity: 2e-4),
    gravity: (0.0, -1.0),
    solid: (shape: Disk(center: (0.0, 3.0), radius: 0.5), density: 1.0, viscosity: 1e-2),
    boundaries: (r_min: Axis, r_max: NoSlip, z_min: NoSlip, z_max: NoSlip),
    numerics: (projection: (solver: {solver}), viscous: (preconditioner: {viscous})),
    output: (probe_every: {end}, probes: [SolidCentroid, SolidVelocity]),
)
"#,
            dt = 0.5 / n as f64
        )
    } else {
        let end = if quick { 0.5 } else { 2.0 };
        format!(
            r#"// Lid-driven cavity, Re = 1000, from rest (cargo xtask bench).
Scene(
    name: "{name}",
    geometry: Planar,
    domain: (x: (0.0, 1.0), y: (0.0, 1.0)),
    grid: (nx: {n}, ny: {n}),
    time: (end: {end}, cfl: 0.4, dt_max: 1.0),
    fluid: (density: 1.0, viscosity: 0.001),
    boundaries: (x_min: NoSlip, x_max: NoSlip, y_min: NoSlip, y_max: MovingWall(speed: 1.0)),
    numerics: (projection: (solver: {solver}), viscous: (preconditioner: {viscous})),
)
"#
        )
    };
    Ok(Case {
        name: name.to_string(),
        scene,
        drop,
        cells: n * n,
    })
}

/// One run's figures.
#[derive(Clone)]
struct Figures {
    total: f64,
    stages: Vec<(String, f64, f64)>,
    steps: f64,
    fall: Option<f64>,
    wall: f64,
}

fn run_case(c: &Case, threads: usize, out: &Path) -> Result<Figures, String> {
    let dir = out.join(format!("{}_t{threads}", c.name));
    let scene = out.join(format!("{}.ron", c.name));
    std::fs::write(&scene, &c.scene).map_err(|e| e.to_string())?;
    let mut cmd = Command::new(root().join("target/release/efsi"));
    cmd.arg("run")
        .arg(&scene)
        .arg("--out")
        .arg(&dir)
        .arg("-q")
        .arg("--threads")
        .arg(threads.to_string())
        // Repeats and reruns replace the case's earlier outputs.
        .arg("--overwrite")
        .stdout(std::process::Stdio::null());
    let status = cmd
        .status()
        .map_err(|e| format!("cannot start efsi: {e}"))?;
    if !status.success() {
        return Err(format!("{}: efsi failed ({status})", c.name));
    }
    let path = dir.join("run.json");
    let text = std::fs::read_to_string(&path).map_err(|e| format!("{}: {e}", path.display()))?;
    let j: serde_json::Value = serde_json::from_str(&text).map_err(|e| e.to_string())?;
    let num = |v: &serde_json::Value| v.as_f64().unwrap_or(f64::NAN);
    let stages = j["stages"]
        .as_array()
        .map(|a| {
            a.iter()
                .map(|s| {
                    (
                        s["name"].as_str().unwrap_or("?").to_string(),
                        num(&s["ns_per_cell_step"]),
                        num(&s["solver_iterations_per_step"]),
                    )
                })
                .collect()
        })
        .unwrap_or_default();
    let fall = if c.drop {
        let p = dir.join("probes.csv");
        let (h, cols) = read_csv(&p)?;
        let z = column(&h, &cols, "solid_y", &p)?;
        Some(z[0] - z[z.len() - 1])
    } else {
        None
    };
    Ok(Figures {
        total: num(&j["ns_per_cell_step"]),
        stages,
        steps: num(&j["steps"]),
        fall,
        wall: num(&j["wall_seconds"]),
    })
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    let n = v.len();
    if n == 0 {
        f64::NAN
    } else if n % 2 == 1 {
        v[n / 2]
    } else {
        0.5 * (v[n / 2 - 1] + v[n / 2])
    }
}

/// Element-wise medians of several runs of one case.
fn median_figures(runs: &[Figures]) -> Figures {
    let mut f = runs[0].clone();
    f.total = median(runs.iter().map(|r| r.total).collect());
    f.wall = median(runs.iter().map(|r| r.wall).collect());
    for (k, s) in f.stages.iter_mut().enumerate() {
        s.1 = median(runs.iter().map(|r| r.stages[k].1).collect());
        s.2 = median(runs.iter().map(|r| r.stages[k].2).collect());
    }
    f
}

fn bench(args: &[String]) -> Result<(), String> {
    let value = |flag: &str| args.windows(2).find(|w| w[0] == flag).map(|w| w[1].clone());
    let quick = args.iter().any(|a| a == "--quick");
    let with_roofline = args.iter().any(|a| a == "--roofline");
    let out = value("--out")
        .map(PathBuf::from)
        .unwrap_or_else(|| root().join("target/bench"));
    let all = std::thread::available_parallelism().map_or(1, |n| n.get());
    let threads: usize = match value("--threads") {
        Some(t) => t
            .parse()
            .map_err(|_| format!("--threads {t}: not a number"))?,
        None => all,
    };
    let repeat: usize = match value("--repeat") {
        Some(t) => t
            .parse()
            .map_err(|_| format!("--repeat {t}: not a number"))?,
        None => 1,
    };
    let names = value("--cases").unwrap_or_else(|| {
        if quick {
            "cavity128,drop128".into()
        } else {
            "cavity128,cavity256,drop128,drop256,sphere".into()
        }
    });
    let cases = names
        .split(',')
        .map(|n| case(n.trim(), quick))
        .collect::<Result<Vec<_>, _>>()?;
    let mut c = cargo();
    c.args(["build", "--quiet", "--release", "-p", "efsi"]);
    run(c, "build efsi (release)")?;
    std::fs::create_dir_all(&out).map_err(|e| e.to_string())?;
    let mut pools = vec![1];
    if threads != 1 {
        pools.push(threads);
    }
    // The bandwidth limits, measured in this run (main memory, last-level cache) per pool size.
    let limits: Vec<(f64, f64)> = if with_roofline {
        pools.iter().map(|&t| roofline::limits(t)).collect()
    } else {
        Vec::new()
    };
    for (&t, (mem, llc)) in pools.iter().zip(&limits) {
        println!(
            "triad, {t} thread(s): main memory {:.1} GB/s, last-level cache {:.1} GB/s",
            mem / 1e9,
            llc / 1e9
        );
    }
    let mut json = Vec::new();
    let mut rows = Vec::new();
    println!(
        "{:<14} {:>3} {:>6} {:>10} {:>8}  per stage: ns/cell-step (solver iterations/step)",
        "case", "thr", "steps", "ns/cell·st", "speedup"
    );
    for c in &cases {
        // Runs alternate between the pool sizes, so that a load change on the machine affects
        // both alike and the ratio is measured within one run of the bench.
        let mut runs: Vec<Vec<Figures>> = vec![Vec::new(); pools.len()];
        for _ in 0..repeat.max(1) {
            for (k, &t) in pools.iter().enumerate() {
                runs[k].push(run_case(c, t, &out)?);
            }
        }
        let base = median_figures(&runs[0]).total;
        for (k, &t) in pools.iter().enumerate() {
            let f = median_figures(&runs[k]);
            let spread = {
                let v: Vec<f64> = runs[k].iter().map(|r| r.total).collect();
                let (lo, hi) = v
                    .iter()
                    .fold((f64::INFINITY, 0.0f64), |(a, b), &x| (a.min(x), b.max(x)));
                (hi - lo) / f.total
            };
            let stages = f
                .stages
                .iter()
                .map(|(n, ns, it)| {
                    if *it > 0.0 {
                        format!("{n} {ns:.0} ({it:.1})")
                    } else {
                        format!("{n} {ns:.0}")
                    }
                })
                .collect::<Vec<_>>()
                .join(", ");
            // The speed-up of each alternating pair of runs: on a VM whose second core comes
            // and goes, their spread says how far to trust the ratio of the medians.
            let pairs: Vec<f64> = runs[0]
                .iter()
                .zip(&runs[k])
                .map(|(a, b)| a.total / b.total)
                .collect();
            let pair_note = if k > 0 && pairs.len() > 1 {
                let (lo, hi) = pairs
                    .iter()
                    .fold((f64::INFINITY, 0.0f64), |(a, b), &x| (a.min(x), b.max(x)));
                format!(" (pairs {lo:.2}–{hi:.2}×)")
            } else {
                String::new()
            };
            let fall = f
                .fall
                .map(|z| {
                    format!(
                        "; fall {z:.4} (½gt² = {:.4})",
                        0.5 * if quick { 0.0625 } else { 1.0 }
                    )
                })
                .unwrap_or_default();
            println!(
                "{:<14} {:>3} {:>6.0} {:>10.1} {:>7.2}×  {stages}{fall}; wall {:.1} s{pair_note}",
                c.name,
                t,
                f.steps,
                f.total,
                base / f.total,
                f.wall
            );
            let roof = limits.get(k).map(|&(mem, llc)| {
                let per_stage: Vec<serde_json::Value> = f
                    .stages
                    .iter()
                    .filter_map(|(n, ns, it)| {
                        let m = roofline::model(n)?;
                        let b = roofline::bytes(m, *it);
                        let bw = b / (ns * 1e-9);
                        rows.push((c.name.clone(), t, n.clone(), *ns, b, bw, bw / mem, bw / llc));
                        Some(serde_json::json!({
                            "name": n, "bytes_per_cell_step": b, "achieved_bytes_per_s": bw,
                            "fraction_of_memory_triad": bw / mem,
                            "fraction_of_cache_triad": bw / llc,
                        }))
                    })
                    .collect();
                let total_bytes: f64 = f
                    .stages
                    .iter()
                    .filter_map(|(n, _, it)| roofline::model(n).map(|m| roofline::bytes(m, *it)))
                    .sum();
                let bw = total_bytes / (f.total * 1e-9);
                rows.push((
                    c.name.clone(),
                    t,
                    "total".into(),
                    f.total,
                    total_bytes,
                    bw,
                    bw / mem,
                    bw / llc,
                ));
                serde_json::json!({
                    "memory_triad_bytes_per_s": mem, "cache_triad_bytes_per_s": llc,
                    "bytes_per_cell_step": total_bytes, "achieved_bytes_per_s": bw,
                    "fraction_of_memory_triad": bw / mem, "fraction_of_cache_triad": bw / llc,
                    "stages": per_stage,
                })
            });
            json.push(serde_json::json!({
                "roofline": roof,
                "case": c.name,
                "threads": t,
                "cells": c.cells,
                "steps": f.steps,
                "repeats": runs[k].len(),
                "ns_per_cell_step": f.total,
                "ns_per_cell_step_runs": runs[k].iter().map(|r| r.total).collect::<Vec<_>>(),
                "spread": spread,
                "speedup_vs_1_thread": base / f.total,
                "speedup_pairs": pairs,
                "wall_seconds": f.wall,
                "fall": f.fall,
                "stages": f.stages.iter().map(|(n, ns, it)| serde_json::json!({
                    "name": n, "ns_per_cell_step": ns, "solver_iterations_per_step": it
                })).collect::<Vec<_>>(),
            }));
        }
    }
    if with_roofline {
        println!(
            "\nroofline (compulsory traffic model: xtask/src/roofline.rs)\n{:<14} {:>3} {:<12} {:>10} {:>10} {:>8} {:>8} {:>8}",
            "case", "thr", "stage", "ns/cell·st", "B/cell·st", "GB/s", "of mem", "of LLC"
        );
        for (case, t, stage, ns, b, bw, fm, fc) in &rows {
            println!(
                "{case:<14} {t:>3} {stage:<12} {ns:>10.1} {b:>10.0} {:>8.2} {:>7.0}% {:>7.0}%",
                bw / 1e9,
                100.0 * fm,
                100.0 * fc
            );
        }
    }
    let path = out.join("bench.json");
    let text = serde_json::to_string_pretty(&serde_json::json!({
        "quick": quick,
        "threads": pools,
        "roofline_models": roofline::MODELS.iter().map(|m| serde_json::json!({
            "stage": m.stage, "values_per_cell_step": m.fixed,
            "values_per_cell_and_iteration": m.per_iteration, "passes": m.passes,
        })).collect::<Vec<_>>(),
        "cases": json,
    }))
    .map_err(|e| e.to_string())?;
    std::fs::write(&path, text).map_err(|e| e.to_string())?;
    eprintln!("figures: {}", path.display());
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
        .ok_or_else(|| {
            format!(
                "{}: no column `{name}`; the columns are: {}",
                path.display(),
                h.join(", ")
            )
        })
}

/// The Reynolds number `ρ U L / μ` of a cavity run, from the effective scene its `run.json`
/// records: `U` the speed of its moving wall, `L` the domain's length along that wall.
fn run_reynolds(run_json: &serde_json::Value) -> Result<f64, String> {
    let scene = &run_json["scene"];
    let num = |v: &serde_json::Value, what: &str| {
        v.as_f64()
            .ok_or_else(|| format!("run.json has no number at scene.{what}"))
    };
    let rho = num(&scene["fluid"]["density"], "fluid.density")?;
    let mu = num(&scene["fluid"]["viscosity"], "fluid.viscosity")?;
    let mut lids = Vec::new();
    for (side, axis) in [
        ("x_min", "y"),
        ("x_max", "y"),
        ("y_min", "x"),
        ("y_max", "x"),
    ] {
        if let Some(w) = scene["boundaries"][side].get("MovingWall") {
            let speed = num(&w["speed"], &format!("boundaries.{side}.speed"))?;
            let d = &scene["domain"][axis];
            let length = num(&d[1], &format!("domain.{axis}[1]"))?
                - num(&d[0], &format!("domain.{axis}[0]"))?;
            lids.push((side, speed, length));
        }
    }
    match lids.as_slice() {
        [(_, speed, length)] => Ok(rho * speed.abs() * length / mu),
        [] => Err("the run's scene has no moving wall: not a lid-driven cavity".into()),
        _ => Err(format!(
            "the run's scene has {} moving walls ({}): not a lid-driven cavity",
            lids.len(),
            lids.iter().map(|l| l.0).collect::<Vec<_>>().join(", ")
        )),
    }
}

/// Check that the run in `dir` is at the Reynolds number `re` (within 1e-6 relative).
fn check_reynolds(dir: &Path, re: f64) -> Result<(), String> {
    let path = dir.join("run.json");
    let text = std::fs::read_to_string(&path).map_err(|e| format!("{}: {e}", path.display()))?;
    let json: serde_json::Value =
        serde_json::from_str(&text).map_err(|e| format!("{}: {e}", path.display()))?;
    let run_re = run_reynolds(&json).map_err(|e| format!("{}: {e}", path.display()))?;
    if (run_re - re).abs() > 1e-6 * re.abs() {
        return Err(format!(
            "{}: the run is at Re = ρ U L / μ = {run_re} (from its scene), not {re}",
            path.display()
        ));
    }
    Ok(())
}

/// The profile with the latest time among `DIR/profiles/<stem>_t*.csv`.
fn last_profile(dir: &Path, stem: &str) -> Result<PathBuf, String> {
    let prefix = format!("{stem}_t");
    let mut best: Option<(f64, PathBuf)> = None;
    for e in std::fs::read_dir(dir.join("profiles"))
        .map_err(|e| format!("{}: {e}", dir.join("profiles").display()))?
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
    let re_value: f64 = re
        .parse()
        .map_err(|_| format!("RE must be a number, got `{re}`"))?;
    check_reynolds(&dir, re_value)?;
    let refs = root().join("tests/references/ghia1982");
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
            column(&rh, &rc, &format!("{field}_Re{re_value}"), &rpath)?,
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
        Some("fmu") => fmu(&args[1..]).map(|_| ()),
        _ => Err(
            "usage: cargo xtask <run SCENE | test | fmu [SCENE [--parameter PATH[=UNIT]] [--input NAME[=UNIT]] [--output PROBE[=UNIT]] [--range NAME=MIN..MAX]…] | bench [--quick] [--roofline] [--cases LIST] \
             [--threads N] [--repeat R] [--out DIR] | bench-paper [--quick] [--case NAME]… \
             [--out DIR] | ghia DIR RE>"
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

#[cfg(test)]
mod tests {
    use super::*;

    fn cavity_json(viscosity: f64, lid: &str) -> serde_json::Value {
        serde_json::json!({"scene": {
            "fluid": {"density": 1.0, "viscosity": viscosity},
            "domain": {"x": [0.0, 2.0], "y": [0.0, 1.0]},
            "boundaries": {"x_min": "NoSlip", "x_max": "NoSlip", "y_min": "NoSlip",
                           lid: {"MovingWall": {"speed": -0.5, "profile": "Uniform", "motion": "Steady"}}},
        }})
    }

    #[test]
    fn ghia_checks_the_runs_reynolds_number() {
        // ρ |U| L / μ with L the lid's length (x for a lid on y_max).
        assert_eq!(run_reynolds(&cavity_json(0.01, "y_max")), Ok(100.0));
        assert_eq!(run_reynolds(&cavity_json(0.01, "x_max")), Ok(50.0));
        let mut no_lid = cavity_json(0.01, "y_max");
        no_lid["scene"]["boundaries"]["y_max"] = "NoSlip".into();
        assert!(
            run_reynolds(&no_lid)
                .unwrap_err()
                .contains("no moving wall")
        );
        let dir = std::env::temp_dir().join(format!("xtask-ghia-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        std::fs::write(
            dir.join("run.json"),
            cavity_json(0.001, "y_max").to_string(),
        )
        .unwrap();
        assert_eq!(check_reynolds(&dir, 1000.0), Ok(()));
        let e = check_reynolds(&dir, 100.0).unwrap_err();
        assert!(e.contains("the run is at Re = ρ U L / μ = 1000"), "{e}");
        assert!(e.contains("not 100"), "{e}");
        // A Reynolds number the reference has no column for: the columns it has are listed.
        std::fs::write(
            dir.join("run.json"),
            cavity_json(0.0025, "y_max").to_string(),
        )
        .unwrap();
        let e = ghia(&[dir.display().to_string(), "400".into()]).unwrap_err();
        assert!(e.contains("profiles: No such file"), "{e}");
        let profiles = dir.join("profiles");
        std::fs::create_dir_all(&profiles).unwrap();
        std::fs::write(
            profiles.join("u_x0.5_t1.csv"),
            "s,x,y,u\n0,0.5,0,0\n1,0.5,1,1\n",
        )
        .unwrap();
        let e = ghia(&[dir.display().to_string(), "400".into()]).unwrap_err();
        assert!(e.contains("no column `u_Re400`"), "{e}");
        assert!(
            e.contains("the columns are: grid_point, y, u_Re100, u_Re1000"),
            "{e}"
        );
        let e = ghia(&[dir.display().to_string(), "fast".into()]).unwrap_err();
        assert!(e.contains("RE must be a number, got `fast`"), "{e}");
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
