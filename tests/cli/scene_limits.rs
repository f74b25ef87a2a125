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
        &["--checkpoint-every: checkpoint_every: must be at least time.dt_min = 1e-12"],
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

/// `efsi run` on `text` fails numerically (exit code 3) with every needle and none of `not`.
fn fails(name: &str, text: &str, needles: &[&str], not: &[&str]) {
    let d = tmp(name);
    let scene = d.join("scene.ron");
    std::fs::write(&scene, text).unwrap();
    let out = d.join("out");
    let o = efsi(&[
        "run",
        scene.to_str().unwrap(),
        "-q",
        "--out",
        out.to_str().unwrap(),
    ]);
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(3), "{name}: {err}");
    for n in needles {
        assert!(err.contains(n), "{name}: `{n}` not in: {err}");
    }
    for n in not {
        assert!(!err.contains(n), "{name}: `{n}` in: {err}");
    }
    std::fs::remove_dir_all(&d).unwrap();
}

/// Item 10: probe columns that would break the CSV's alignment.
#[test]
fn probe_columns_must_be_distinct_csv_names() {
    let with = |probes: &str| cavity("c", 8, 1.0, &format!("probes: [{probes}]"));
    let point = |name: &str| format!("Point(name: \"{name}\", field: \"u\", at: (0.5, 0.5))");
    for (k, name) in ["a,b", "", "x\\ny", "say \\\"hi\\\""].iter().enumerate() {
        refused(
            &format!("probe_name{k}"),
            &with(&point(name)),
            &[],
            &[
                "output.probes[0].name: must be a non-empty CSV column name without commas, quotes or control characters",
            ],
        );
    }
    refused(
        "probe_t",
        &with(&point("t")),
        &[],
        &["output.probes[0]: its column `t` is already the time column's"],
    );
    refused(
        "probe_twice",
        &with("KineticEnergy, MaxSpeed, KineticEnergy"),
        &[],
        &["output.probes[2]: its column `kinetic_energy` is already output.probes[0]'s"],
    );
    refused(
        "probe_builtin",
        &with(&format!("MaxSpeed, {}", point("max_speed"))),
        &[],
        &["output.probes[1]: its column `max_speed` is already output.probes[0]'s"],
    );
}

/// Item 11: settings that used to run and write nothing (no solid, NaN columns) or fail late.
#[test]
fn settings_that_would_run_with_nothing_are_refused() {
    let law = law_library("efsi_law_neo_hookean");
    let solid = solid_scene(law.to_str().unwrap(), r#""G": 5.0"#);
    let shape = "HalfPlane(normal: (0.0, 1.0), offset: 0.5)";
    for (k, other) in [
        "Disk(center: (5.0, 5.0), radius: 0.1)",
        "Disk(center: (0.03, 0.5), radius: 1e-300)",
        "Intersection([Disk(center: (0.03, 0.2), radius: 0.1), Disk(center: (0.03, 0.8), radius: 0.1)])",
    ]
    .iter()
    .enumerate()
    {
        refused(
            &format!("no_solid{k}"),
            &solid.replace(shape, other),
            &[],
            &["solid.shape: covers no cell of the 4×16 grid", "the run would have no solid"],
        );
    }
    let probes = |p: &str| solid.replace("probes: [KineticEnergy]", &format!("probes: [{p}]"));
    refused(
        "extent_nan",
        &probes("SolidExtent(at: NaN)"),
        &[],
        &["output.probes[0].at: x = NaN is outside the domain's [0, 0.0625]"],
    );
    refused(
        "extent_outside",
        &probes("SolidExtent(at: 2.0)"),
        &[],
        &["output.probes[0].at: x = 2 is outside the domain's [0, 0.0625]"],
    );
    let no_law = solid.replace(
        &format!(
            ", viscosity: 0.0,\n            law: (name: \"{}\", parameters: {{\"G\": 5.0}})",
            law.display()
        ),
        ", viscosity: 0.0",
    );
    assert_ne!(no_law, solid);
    refused(
        "elastic_energy_no_law",
        &no_law.replace("probes: [KineticEnergy]", "probes: [ElasticEnergy]"),
        &[],
        &["output.probes[0]: ElasticEnergy needs a solid with a law (solid.law)"],
    );
    let fluid = |output: &str| cavity("c", 8, 1.0, output);
    refused(
        "fraction_point",
        &fluid("probes: [Point(name: \"f\", field: \"solid_fraction\", at: (0.5, 0.5))]"),
        &[],
        &["output.probes[0].field: solid_fraction needs a solid, and the scene has none"],
    );
    refused(
        "fraction_profile",
        &fluid(
            "profiles: [Line(name: \"f\", from: (0.5, 0.0), to: (0.5, 1.0), points: 5, fields: [\"solid_fraction\"])]",
        ),
        &[],
        &["output.profiles[0].fields: solid_fraction needs a solid, and the scene has none"],
    );
    let numerics = |n: &str| {
        cavity("c", 8, 1.0, "probes: [KineticEnergy]")
            .replace("fluid: (", &format!("numerics: ({n}),\n    fluid: ("))
    };
    refused(
        "viscous_iterations",
        &numerics("viscous: (max_iterations: 0)"),
        &[],
        &["numerics.viscous.max_iterations: must be ≥ 1"],
    );
    refused(
        "tolerance",
        &numerics("projection: (tolerance: 1e-308)"),
        &[],
        &[
            "numerics.projection.tolerance: must be in [2.220446049250313e-16, 1)",
            "got 1e-308",
        ],
    );
}

/// Item 9: a message names the limit that set Δt and the setting behind it. A first step below
/// `time.dt_min` is the scene's own conflict (issue 44 item 13): refused before the run, exit
/// code 2, not labelled an unstable run.
#[test]
fn a_collapsing_step_names_the_limit_and_the_setting() {
    let base = cavity("c", 8, 1.0, "probes: [KineticEnergy]");
    refused(
        "steady_long",
        &base.replace("end: 1.0, cfl: 0.5", "end: 1e12, cfl: 0.5, steady: 1e-6"),
        &[],
        &[
            "time.dt_min: the first step, Δt = ",
            "set by the ",
            "is below time.dt_min's default 1e-12·time.end = 1 (time.end = 1e12)",
            "set time.dt_min lower, or change the setting that limits Δt",
        ],
    );
    refused(
        "tiny_cfl",
        &base.replace("cfl: 0.5", "cfl: 1e-308"),
        &[],
        &[
            "time.dt_min: the first step, Δt = ",
            "time.cfl = 1e-308",
            "set time.dt_min lower, or change the setting that limits Δt",
        ],
    );
    // A first step below the default floor, with the floor set below it: accepted.
    let d = tmp("tiny_cfl_floor");
    let scene = d.join("scene.ron");
    std::fs::write(
        &scene,
        base.replace("cfl: 0.5", "cfl: 1e-12, dt_min: 1e-20"),
    )
    .unwrap();
    let o = efsi(&["check", scene.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    for (f, v) in [("fixed_dt", "1e-13"), ("dt_max", "1e-13")] {
        refused(
            f,
            &base.replace("cfl: 0.5", &format!("cfl: 0.5, {f}: {v}")),
            &[],
            &[&format!(
                "time.{f}: 1e-13 is below time.dt_min's default 1e-12·time.end = 1e-12"
            )],
        );
    }
    let law = law_library("efsi_law_neo_hookean");
    fails(
        "elastic_iterations",
        &solid_scene(law.to_str().unwrap(), r#""G": 5.0"#).replace(
            "fluid: (",
            "numerics: (elastic: (max_iterations: 1)),\n    fluid: (",
        ),
        &[
            "BiCGSTAB did not converge in 1 iterations, the limit numerics.elastic.max_iterations",
            "raise numerics.elastic.max_iterations",
        ],
        &["reduce the time step"],
    );
}

/// Item 13: messages that printed 309 digits, stumbled on a byte-order mark, gave a library's
/// advice for deep nesting, or said "not found" / "dlopen failed" about a law file.
#[test]
fn messages_say_what_is_wrong_in_the_scene_s_terms() {
    let base = cavity("c", 8, 1.0, "probes: [KineticEnergy]");
    refused(
        "huge_cfl",
        &base.replace("cfl: 0.5", "cfl: 1e308"),
        &[],
        &["time.cfl: must be in (0, 1], got 1e308\n"],
    );
    // A byte-order mark first is accepted.
    let d = tmp("bom");
    let scene = d.join("scene.ron");
    std::fs::write(&scene, format!("\u{feff}{base}")).unwrap();
    let o = efsi(&["check", scene.to_str().unwrap()]);
    assert!(o.status.success(), "{}", stderr(&o));
    // Nesting beyond the reader's limit.
    let mut shape = "Disk(center: (0.5, 0.5), radius: 0.1)".to_string();
    for _ in 0..200 {
        shape = format!("Union([{shape}])");
    }
    let deep = base.replace(
        "fluid: (",
        &format!("solid: (shape: {shape}, density: 1.0),\n    fluid: ("),
    );
    refused(
        "deep",
        &deep,
        &[],
        &["nested deeper than the scene reader allows (128 levels)"],
    );
    // Law files that are not libraries.
    let broken = d.join("broken.so");
    std::fs::write(&broken, b"not a shared object").unwrap();
    for (law, needle) in [
        (
            d.display().to_string(),
            "is a folder, not a law library file".to_string(),
        ),
        (
            "/dev/null".to_string(),
            "/dev/null is not a regular file".to_string(),
        ),
        (
            broken.display().to_string(),
            format!(
                "{} is not a loadable library: not an ELF shared library (no ELF magic number at its start)",
                broken.display()
            ),
        ),
    ] {
        refused(
            "law_file",
            &solid_scene(&law, r#""G": 5.0"#),
            &[],
            &["solid.law", &needle],
        );
    }
    std::fs::remove_dir_all(&d).unwrap();
}

/// Item 6: a scene beyond the machine's memory is refused before anything is allocated.
#[test]
fn scenes_beyond_memory_and_size_limits_are_refused() {
    refused(
        "memory",
        &cavity("c", 10000, 1.0, "probes: [KineticEnergy]"),
        &[],
        &[
            "grid: the run needs about 79.",
            "GB (1.001e8 cells with ghost layers × ≈ 790 B)",
            "of memory available: use a coarser grid",
        ],
    );
    refused(
        "points",
        &cavity(
            "c",
            8,
            1.0,
            "profiles: [Line(name: \"u\", from: (0.5, 0.0), to: (0.5, 1.0), points: 100000000, fields: [\"u\"])]",
        ),
        &[],
        &["output.profiles[0].points: must be in [2, 100000], got 100000000"],
    );
    let o = efsi(&["check", "/dev/zero"]);
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(
        err.contains("/dev/zero: cannot read scene: larger than 4 MiB: not a scene file"),
        "{err}"
    );
}
