//! Settings that would make a run hang, write outside its folder or mislead are refused before
//! anything runs, naming the setting (issue 20): output and checkpoint intervals below the
//! smallest step (item 4), scene names that are not a folder name (item 5); and one Ctrl-C stops
//! a run whose outputs are as dense as allowed.

mod common;

use common::*;
use std::time::Duration;

/// `efsi check` and `efsi run` on `text` both refuse with exit code 2 and every needle.
fn refused(name: &str, text: &str, extra: &[&str], needles: &[&str]) {
    let d = tmp(name);
    let scene = d.join("scene.ron");
    std::fs::write(&scene, text).unwrap();
    let scene = scene.to_str().unwrap();
    let out = d.join("out");
    let run: Vec<&str> = ["run", scene, "-q", "--out", out.to_str().unwrap()]
        .into_iter()
        .chain(extra.iter().copied())
        .collect();
    let checks: Vec<Vec<&str>> = if extra.is_empty() {
        vec![vec!["check", scene], run]
    } else {
        vec![run]
    };
    for args in checks {
        let o = efsi(&args);
        let err = stderr(&o);
        assert_eq!(o.status.code(), Some(2), "{name} {args:?}: {err}");
        for n in needles {
            assert!(err.contains(n), "{name}: `{n}` not in: {err}");
        }
    }
    assert!(!out.join("probes.csv").exists(), "{name}: the run started");
    std::fs::remove_dir_all(&d).unwrap();
}

#[test]
fn intervals_below_the_smallest_step_are_refused() {
    let base = cavity("c", 8, 1.0, "probes: [KineticEnergy]");
    refused(
        "vtk_every",
        &base.replace("probes: [", "vtk_every: 1e-30, probes: ["),
        &[],
        &[
            "output.vtk_every: must be at least time.dt_min = 1e-12",
            "got 1e-30",
        ],
    );
    refused(
        "probe_every",
        &base.replace("probes: [", "probe_every: 1e-14, probes: ["),
        &[],
        &[
            "output.probe_every: must be at least time.dt_min = 1e-12",
            "got 1e-14",
        ],
    );
    refused(
        "probe_every_dt_min",
        &base
            .replace("probes: [", "probe_every: 1e-5, probes: [")
            .replace("cfl: 0.5", "cfl: 0.5, dt_min: 1e-4"),
        &[],
        &[
            "output.probe_every: must be at least time.dt_min = 1e-4",
            "got 1e-5",
        ],
    );
    refused(
        "checkpoint_every",
        &base,
        &["--checkpoint-every", "1e-14"],
        &["--checkpoint-every: checkpoint_every: must be a time of at least time.dt_min = 1e-12"],
    );
}

#[test]
fn one_interrupt_stops_a_run_with_outputs_as_dense_as_allowed() {
    let d = tmp("dense");
    let scene = d.join("scene.ron");
    // Probes every 1e-12 (= time.dt_min): 1e12 steps to the end; a checkpoint interval at the
    // floor as well. Each step still checks the stop flag.
    std::fs::write(
        &scene,
        cavity(
            "dense",
            8,
            1.0,
            "probe_every: 1e-12, probes: [KineticEnergy]",
        ),
    )
    .unwrap();
    let out = d.join("out");
    let mut child = spawn(&[
        "run",
        scene.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "-q",
        "--checkpoint-every",
        "1e-12",
    ]);
    wait_rows(&mut child, &out, 50);
    let (code, err, took) = signal(child, libc::SIGINT);
    assert_eq!(code, Some(130), "{err}");
    assert!(took < Duration::from_secs(2), "{took:?} to stop");
    assert_csv_whole(&out);
    std::fs::remove_dir_all(&d).unwrap();
}

#[test]
fn scene_names_that_are_not_a_folder_name_are_refused() {
    for (k, name) in [".", "..", "a\nb", "...", "tab\there"].iter().enumerate() {
        let text = cavity(&name.escape_default().to_string(), 8, 1.0, "");
        refused(
            &format!("name{k}"),
            &text,
            &[],
            &[
                "name: must be a non-empty name without path separators or control characters, and not `.` or `..`",
                &format!("got {name:?}"),
            ],
        );
    }
}
