//! Output failures in the middle of a run: a full disk (a file size limit, `RLIMIT_FSIZE`, in
//! the child process) leaves `probes.csv` ending with a whole row (issue 20 item 3), and any
//! output that cannot be written still saves the checkpoint and `run.json` saying why the run
//! stopped (item 8); `efsi resume` then finishes the run with an uninterrupted run's bytes.

mod common;

use common::*;
use std::os::unix::process::CommandExt;
use std::path::Path;
use std::process::Command;

/// `efsi args…` with a file size limit of `bytes` (SIGXFSZ ignored, so a write past it fails
/// with EFBIG as on a full disk).
fn efsi_limited(args: &[&str], bytes: u64) -> std::process::Output {
    let mut cmd = Command::new(env!("CARGO_BIN_EXE_efsi"));
    cmd.args(args);
    // SAFETY: only async-signal-safe calls (setrlimit, signal) between fork and exec.
    unsafe {
        cmd.pre_exec(move || {
            let limit = libc::rlimit {
                rlim_cur: bytes,
                rlim_max: bytes,
            };
            if libc::setrlimit(libc::RLIMIT_FSIZE, &limit) != 0 {
                return Err(std::io::Error::last_os_error());
            }
            libc::signal(libc::SIGXFSZ, libc::SIG_IGN);
            Ok(())
        });
    }
    cmd.output().expect("run efsi")
}

fn run_json_stop(dir: &Path) -> serde_json::Value {
    let json: serde_json::Value =
        serde_json::from_slice(&std::fs::read(dir.join("run.json")).unwrap()).unwrap();
    json["stop"].clone()
}

/// The same scene run without trouble into `whole`; its `probes.csv`.
fn uninterrupted(scene: &str, whole: &Path) -> Vec<u8> {
    let o = efsi(&["run", scene, "--out", whole.to_str().unwrap(), "-q"]);
    assert!(o.status.success(), "{}", stderr(&o));
    std::fs::read(whole.join("probes.csv")).unwrap()
}

#[test]
fn a_full_disk_leaves_whole_rows_and_a_checkpoint_to_resume_from() {
    let d = tmp("fsize");
    let scene = d.join("scene.ron");
    // ≈ 650 steps, a row of three columns each: ≈ 45 kB of probes; the checkpoint ≈ 10 kB.
    std::fs::write(
        &scene,
        cavity("full", 8, 40.0, "probes: [KineticEnergy, MaxSpeed]"),
    )
    .unwrap();
    let (scene, out) = (scene.to_str().unwrap(), d.join("out"));
    let limit = 16_000;
    let o = efsi_limited(&["run", scene, "--out", out.to_str().unwrap(), "-q"], limit);
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(1), "{err}");
    for needle in [
        "probes.csv: File too large",
        "the file ends with its last whole row (",
        "the last good state (step ",
        "was saved to the checkpoint ",
    ] {
        assert!(err.contains(needle), "`{needle}` not in: {err}");
    }
    let rows = assert_csv_whole(&out);
    let len = std::fs::metadata(out.join("probes.csv")).unwrap().len();
    assert!(len <= limit && len > limit - 100, "{len} bytes");
    assert!(rows > 100, "{rows} rows");
    let stop = run_json_stop(&out);
    assert_eq!(stop["Failed"]["exit_code"], 1, "{stop}");
    assert!(
        stop["Failed"]["error"]
            .as_str()
            .unwrap()
            .contains("File too large"),
        "{stop}"
    );
    // With room again, resume finishes it as if nothing had happened.
    let o = efsi(&["resume", out.to_str().unwrap(), "-q"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let whole = uninterrupted(scene, &d.join("whole"));
    assert!(
        std::fs::read(out.join("probes.csv")).unwrap() == whole,
        "probes.csv differs from the uninterrupted run's"
    );
    assert_eq!(run_json_stop(&out), "EndTime");
    std::fs::remove_dir_all(&d).unwrap();
}

#[test]
fn an_output_that_cannot_be_written_saves_the_checkpoint_and_says_why_in_run_json() {
    let d = tmp("blocked");
    let scene = d.join("scene.ron");
    std::fs::write(
        &scene,
        cavity(
            "blocked",
            8,
            2.0,
            "vtk_every: 0.5, probe_every: 0.05, probes: [KineticEnergy], \
             profiles: [Line(name: \"u\", from: (0.5, 0.0), to: (0.5, 1.0), points: 5, fields: [\"u\"], at: [0.5, 1.5])]",
        ),
    )
    .unwrap();
    let (scene, out) = (scene.to_str().unwrap(), d.join("out"));
    // A folder where the profile at t = 1.5 goes: it cannot be replaced by a file.
    let blocked = out.join("profiles/u_t1.5.csv");
    std::fs::create_dir_all(&blocked).unwrap();
    let o = efsi(&["run", scene, "--out", out.to_str().unwrap(), "-q"]);
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(1), "{err}");
    for needle in [
        &*blocked.to_string_lossy(),
        "the last good state (step ",
        "was saved to the checkpoint ",
    ] {
        assert!(err.contains(needle), "`{needle}` not in: {err}");
    }
    let stop = run_json_stop(&out);
    assert_eq!(stop["Failed"]["exit_code"], 1, "{stop}");
    assert!(out.join("checkpoint/latest.efsick").is_file());
    // Unblocked, the resumed run writes what was missing and ends as an uninterrupted one.
    std::fs::remove_dir(&blocked).unwrap();
    let o = efsi(&["resume", out.to_str().unwrap(), "-q"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let whole = d.join("whole");
    assert!(std::fs::read(out.join("probes.csv")).unwrap() == uninterrupted(scene, &whole));
    for f in ["fields.pvd", "profiles/u_t1.5.csv", "profiles/u_t0.5.csv"] {
        assert!(
            std::fs::read(out.join(f)).unwrap() == std::fs::read(whole.join(f)).unwrap(),
            "{f} differs"
        );
    }
    std::fs::remove_dir_all(&d).unwrap();
}
