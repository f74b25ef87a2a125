//! An output folder belongs to one run: a checkpoint copied from another run's folder is
//! refused on resume (issue 20 item 1), a second process in a folder that a run is writing is
//! refused (item 2), and `efsi run` into a folder holding an earlier run refuses unless told
//! `--overwrite`, which leaves nothing of the old run behind (item 7).

mod common;

use common::*;

#[test]
fn a_checkpoint_from_another_run_is_refused_on_resume() {
    let d = tmp("identity");
    let scene = d.join("scene.ron");
    std::fs::write(
        &scene,
        cavity("c", 16, 0.5, "probe_every: 0.05, probes: [KineticEnergy]"),
    )
    .unwrap();
    let scene = scene.to_str().unwrap();
    let (a, b) = (d.join("a"), d.join("b"));
    for (out, visc) in [(&a, "0.01"), (&b, "0.02")] {
        let set = format!("fluid.viscosity={visc}");
        let o = efsi(&[
            "run",
            scene,
            "--set",
            &set,
            "--out",
            out.to_str().unwrap(),
            "-q",
            "--checkpoint-every",
            "0.2",
        ]);
        assert!(o.status.success(), "{}", stderr(&o));
    }
    let probes_b = std::fs::read(b.join("probes.csv")).unwrap();
    let json_b = std::fs::read(b.join("run.json")).unwrap();
    let id_b: serde_json::Value = serde_json::from_slice(&json_b).unwrap();
    let id_b = id_b["run_id"].as_str().unwrap().to_string();
    assert_eq!(id_b.len(), 16, "{id_b}");
    std::fs::copy(
        a.join("checkpoint/latest.efsick"),
        b.join("checkpoint/latest.efsick"),
    )
    .unwrap();
    let o = efsi(&["resume", b.to_str().unwrap(), "-q"]);
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(
        err.contains("cannot resume: the checkpoint was written by run ")
            && err.contains(&format!("this folder's run.json is of run {id_b}"))
            && err.contains("latest.efsick"),
        "{err}"
    );
    // Nothing of B was touched.
    assert_eq!(std::fs::read(b.join("probes.csv")).unwrap(), probes_b);
    assert_eq!(std::fs::read(b.join("run.json")).unwrap(), json_b);
    // B's run.json edited to name A's run (issue 44 item 16): the checkpoint is bound to A's
    // probes.csv too, and B's differs.
    let json_a: serde_json::Value =
        serde_json::from_slice(&std::fs::read(a.join("run.json")).unwrap()).unwrap();
    let id_a = json_a["run_id"].as_str().unwrap();
    let forged = String::from_utf8(json_b.clone())
        .unwrap()
        .replace(&id_b, id_a);
    std::fs::write(b.join("run.json"), &forged).unwrap();
    let o = efsi(&["resume", b.to_str().unwrap(), "-q"]);
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(
        err.contains("probes.csv: its first ")
            && err.contains(
                "bytes are not the rows the checkpoint's run wrote: the checkpoint belongs to another run's folder"
            ),
        "{err}"
    );
    assert_eq!(std::fs::read(b.join("probes.csv")).unwrap(), probes_b);
    // Without a run.json nothing ties the checkpoint to the folder's outputs either; a
    // run.json that is a device is not read (issue 44 item 8).
    std::fs::remove_file(b.join("run.json")).unwrap();
    let o = efsi(&["resume", b.to_str().unwrap(), "-q"]);
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(
        err.contains("run.json cannot be read (") && err.contains("No such file"),
        "{err}"
    );
    std::os::unix::fs::symlink("/dev/zero", b.join("run.json")).unwrap();
    let o = efsi(&["resume", b.to_str().unwrap(), "-q"]);
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(
        err.contains("run.json cannot be read (not a regular file (a device, a pipe or a socket))"),
        "{err}"
    );
    std::fs::remove_dir_all(&d).unwrap();
}

#[test]
fn a_second_process_in_a_folder_being_written_is_refused() {
    let d = tmp("lock");
    let scene = d.join("scene.ron");
    std::fs::write(
        &scene,
        cavity(
            "long",
            32,
            40.0,
            "probe_every: 0.1, probes: [KineticEnergy]",
        ),
    )
    .unwrap();
    let (scene, out) = (scene.to_str().unwrap(), d.join("out"));
    let out_s = out.to_str().unwrap();
    let mut first = spawn(&["run", scene, "--out", out_s, "-q"]);
    wait_rows(&mut first, &out, 5);
    let pid = first.id();
    for args in [
        vec!["run", scene, "--out", out_s, "-q"],
        vec!["run", scene, "--out", out_s, "-q", "--overwrite"],
        vec!["resume", out_s, "-q"],
    ] {
        let o = efsi(&args);
        let err = stderr(&o);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {err}");
        assert!(
            err.contains(&format!(
                "output folder: another efsi process (pid {pid}) is writing a run in this folder"
            )),
            "{args:?}: {err}"
        );
    }
    let (code, err, _) = signal(first, libc::SIGINT);
    assert_eq!(code, Some(130), "{err}");
    let rows = assert_csv_whole(&out);
    // The first run's rows are all there, each time once.
    let csv = std::fs::read_to_string(out.join("probes.csv")).unwrap();
    let times: Vec<f64> = csv
        .lines()
        .skip(1)
        .map(|l| l.split(',').next().unwrap().parse().unwrap())
        .collect();
    assert_eq!(times.len(), rows);
    for (k, t) in times.iter().enumerate() {
        assert!((t - 0.1 * k as f64).abs() < 1e-9, "row {k}: t = {t}");
    }
    // Once it has ended, the folder is free: resume takes it.
    let mut again = spawn(&["resume", out_s, "-q"]);
    wait_rows(&mut again, &out, rows + 3);
    let (code, err, _) = signal(again, libc::SIGTERM);
    assert_eq!(code, Some(143), "{err}");
    std::fs::remove_dir_all(&d).unwrap();
}

#[test]
fn a_folder_holding_a_run_is_refused_unless_overwrite_and_then_nothing_stale_is_left() {
    let d = tmp("stale");
    let scene = d.join("scene.ron");
    let text = cavity(
        "c",
        8,
        1.0,
        "vtk_every: 0.25, probe_every: 0.1, probes: [KineticEnergy], \
         profiles: [Line(name: \"u\", from: (0.5, 0.0), to: (0.5, 1.0), points: 5, fields: [\"u\"], at: [0.5])]",
    );
    std::fs::write(&scene, &text).unwrap();
    let (scene_s, out) = (scene.to_str().unwrap(), d.join("out"));
    let out_s = out.to_str().unwrap();
    let o = efsi(&[
        "run",
        scene_s,
        "--out",
        out_s,
        "-q",
        "--checkpoint-every",
        "0.3",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let checkpoint = std::fs::read(out.join("checkpoint/latest.efsick")).unwrap();

    // `run` where `resume` was meant: refused, the checkpoint kept.
    let o = efsi(&["run", scene_s, "--out", out_s, "-q"]);
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(2), "{err}");
    for needle in [
        "output folder: holds the outputs of an earlier run (run.json, probes.csv, fields.pvd, 5 VTK files, a checkpoint at step ",
        ", t = 9.000000e-1)",
        &format!("`efsi resume {out_s}` continues it"),
        "--overwrite replaces them",
    ] {
        assert!(err.contains(needle), "`{needle}` not in: {err}");
    }
    assert_eq!(
        std::fs::read(out.join("checkpoint/latest.efsick")).unwrap(),
        checkpoint
    );
    // Files that are not a run's outputs do not make a folder hold a run.
    let other = d.join("other");
    std::fs::create_dir_all(other.join("fields")).unwrap();
    std::fs::write(other.join("notes.txt"), "mine").unwrap();
    let o = efsi(&["run", scene_s, "--out", other.to_str().unwrap(), "-q"]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert_eq!(
        std::fs::read_to_string(other.join("notes.txt")).unwrap(),
        "mine"
    );

    // --overwrite: a run with fewer outputs leaves none of the old ones.
    std::fs::write(
        &scene,
        text.replace("vtk_every: 0.25", "vtk_every: 0.5")
            .replace("at: [0.5]", "at: [0.75]"),
    )
    .unwrap();
    let o = efsi(&["run", scene_s, "--out", out_s, "-q", "--overwrite"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let mut fields: Vec<String> = std::fs::read_dir(out.join("fields"))
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    fields.sort();
    assert_eq!(fields.len(), 3, "{fields:?}");
    let mut profiles: Vec<String> = std::fs::read_dir(out.join("profiles"))
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    profiles.sort();
    // The old run's u_t0.5.csv is gone (a profile is written at its times and at the end).
    assert_eq!(profiles, ["u_t0.75.csv", "u_t1.csv"]);
    assert!(!out.join("checkpoint/latest.efsick").exists());
    let pvd = std::fs::read_to_string(out.join("fields.pvd")).unwrap();
    assert_eq!(pvd.matches("<DataSet").count(), 3, "{pvd}");
    let json: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out.join("run.json")).unwrap()).unwrap();
    assert_eq!(json["stop"], "EndTime");
    assert_eq!(json["scene"]["output"]["vtk_every"], 0.5);
    std::fs::remove_dir_all(&d).unwrap();
}
