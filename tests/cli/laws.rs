//! `efsi laws --check`: the load-time tangent check run on the libraries given, with a non-zero
//! exit code for a law that fails it.

mod common;

use common::{law_library, tmp};
use std::process::{Command, Output};

fn efsi(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_efsi"))
        .args(args)
        .output()
        .expect("run efsi")
}

/// The worst relative error a `--check` line reports.
fn worst_error(line: &str) -> f64 {
    let rest = line
        .split("worst relative error ")
        .nth(1)
        .unwrap_or_else(|| panic!("no error figure in: {line}"));
    rest.split_whitespace().next().unwrap().parse().unwrap()
}

#[test]
fn laws_check_passes_a_good_law_and_fails_a_wrong_tangent() {
    let good = law_library("efsi_law_neo_hookean");
    let wrong = law_library("efsi_test_law_wrong_tangent");

    let o = efsi(&["laws", "--check", good.to_str().unwrap()]);
    let out = String::from_utf8_lossy(&o.stdout);
    assert_eq!(
        o.status.code(),
        Some(0),
        "{out}{}",
        String::from_utf8_lossy(&o.stderr)
    );
    assert!(out.starts_with("neo_hookean ("), "{out}");
    assert!(out.contains("tangent check passed"), "{out}");
    assert!(out.contains("over 26 states (0 skipped)"), "{out}");
    assert!(worst_error(&out) < 1e-8, "{out}");

    // A failing law among good ones: every library is checked, the exit code is 2.
    let o = efsi(&[
        "laws",
        "--check",
        good.to_str().unwrap(),
        wrong.to_str().unwrap(),
    ]);
    let (out, err) = (
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr),
    );
    assert_eq!(o.status.code(), Some(2), "{out}{err}");
    assert!(
        out.contains("neo_hookean (") && out.contains("passed"),
        "{out}"
    );
    assert!(
        err.contains("test_wrong_tangent (") && err.contains("tangent check FAILED"),
        "{err}"
    );
    assert!(worst_error(&err) > 1e-5, "{err}");

    // A library that does not exist is an error naming it, exit code 2.
    let o = efsi(&["laws", "--check", "/nonexistent/libefsi_law_x.so"]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(
        err.contains("library not found: /nonexistent/libefsi_law_x.so"),
        "{err}"
    );
}

/// `efsi laws LIB` describes LIB only; `efsi laws` alone every law on the search path.
#[test]
fn laws_with_a_library_lists_that_library_only() {
    let nan = law_library("efsi_test_law_nan");
    let o = efsi(&["laws", nan.to_str().unwrap()]);
    let out = String::from_utf8_lossy(&o.stdout);
    assert_eq!(o.status.code(), Some(0), "{out}");
    assert!(out.starts_with("test_nan — "), "{out}");
    assert!(!out.contains("neo_hookean"), "{out}");
    let o = efsi(&["laws"]);
    let out = String::from_utf8_lossy(&o.stdout);
    assert!(out.contains("neo_hookean — "), "{out}");
    assert!(!out.contains("test_nan — "), "{out}");
}

/// A law undefined at B = 0 (NaN below a floor of b11, as an Ogden law with logarithms)
/// passes the check and runs the sphere impact: efsi never calls a law where there is no
/// solid (the corners of the solid's window that hold none). The law and its whole parameter
/// map replace the scene's with one `--set`.
#[test]
fn a_law_undefined_without_solid_runs_the_sphere() {
    let lib = law_library("efsi_test_law_nan");
    let o = efsi(&["laws", "--check", lib.to_str().unwrap()]);
    assert_eq!(
        o.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&o.stdout)
    );
    let d = tmp("floor_law");
    let law = format!(
        r#"solid.law=(name: "{}", parameters: {{"G": 180000.0, "limit": 100.0, "floor": 0.01}})"#,
        lib.display()
    );
    let scene = concat!(env!("CARGO_MANIFEST_DIR"), "/cases/sphere_impact.ron");
    let o = efsi(&[
        "run",
        scene,
        "--set",
        &law,
        "--refine",
        "0.3",
        "--set",
        "time.end=0.001",
        "--out",
        d.join("run").to_str().unwrap(),
        "-q",
    ]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(0), "{err}");
    let record = std::fs::read_to_string(d.join("run/run.json")).unwrap();
    assert!(
        record.contains("\"floor\""),
        "the scene's law is the one set: {record}"
    );
    std::fs::remove_dir_all(&d).unwrap();
}
