//! `cargo xtask test`: everything CI runs, the Python tests in `target/venv` included.

use crate::{cargo, root, run};
use std::path::{Path, PathBuf};
use std::process::Command;

/// The Python of the virtual environment `target/venv`, created on first use and given the
/// test requirements (`tests/python/requirements.txt`) whenever they change.
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
            "install the Python test requirements (vtk, numpy, pytest, fmpy, ecospy, tbb, maturin, dask, pandas, pyarrow)",
        )?;
        std::fs::write(&stamp, wanted).map_err(|e| e.to_string())?;
    }
    Ok(py)
}

/// Formatting, clippy and rustdoc (warnings are errors), the Rust tests, the FMUs and the
/// Python tests.
pub(crate) fn test() -> Result<(), String> {
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
    // The sphere impact, and four scenes packaged as they are: the oscillating Couette flow
    // with the wall's speed amplitude as a parameter, the disk in a cavity with the lid's speed
    // as an input, the 3-D drop with its grid as parameters, the 3-D elastic sphere with its
    // grid and height as parameters.
    let [fmu2, _] = crate::fmu::fmu(&[])?;
    let grid = [
        "--parameter",
        "grid.nx",
        "--parameter",
        "grid.ny",
        "--parameter",
        "grid.nz",
    ];
    let scenes: [(&str, &[&str]); 4] = [
        (
            "cases/oscillating_couette.ron",
            &[
                "--parameter",
                "boundaries.y_max.speed=m/s",
                "--output",
                "u_interface=m/s",
            ],
        ),
        (
            "cases/disk_in_cavity.ron",
            &["--input", "boundaries.y_max.speed=m/s"],
        ),
        ("cases/falling_drop_3d.ron", &grid),
        (
            "cases/sphere_impact_3d.ron",
            &[&grid[..], &["--parameter", "solid.shape.center[1]"]].concat(),
        ),
    ];
    for (scene, options) in scenes {
        let args: Vec<String> = std::iter::once(scene)
            .chain(options.iter().copied())
            .map(str::to_string)
            .collect();
        crate::fmu::fmu(&args)?;
    }
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
