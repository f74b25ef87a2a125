//! The quick versions of the paper's cases (`cargo xtask bench-paper --quick`): every check of
//! every case must pass.

use efsi_tests::paper::{CASES, Options};

fn quick(name: &str) {
    quick_runs(name, 1)
}

/// [`quick`] `runs` times into the same folder: a rerun must start afresh, not trip over the
/// outputs of the run before.
fn quick_runs(name: &str, runs: usize) {
    let case = CASES.iter().find(|c| c.name == name).expect("case");
    let out = std::env::temp_dir().join(format!("efsi-paper-quick-{}-{name}", std::process::id()));
    let opts = Options {
        quick: true,
        out: out.clone(),
        progress: false,
        overrides: Vec::new(),
    };
    for _ in 0..runs {
        check(
            name,
            &(case.run)(&opts).unwrap_or_else(|e| panic!("{name}: {e}")),
        );
    }
    let _ = std::fs::remove_dir_all(out);
}

/// Every check of `report` passed.
fn check(name: &str, report: &efsi_tests::paper::Report) {
    for c in &report.checks {
        eprintln!(
            "{name}: {} = {} (target {}) {}",
            c.what,
            c.value,
            c.target,
            if c.pass { "pass" } else { "FAIL" }
        );
    }
    for n in &report.notes {
        eprintln!("{name}: {n}");
    }
    assert!(!report.checks.is_empty(), "{name}: no checks");
    let failed: Vec<_> = report
        .checks
        .iter()
        .filter(|c| !c.pass)
        .map(|c| format!("{}: {} (target {})", c.what, c.value, c.target))
        .collect();
    assert!(failed.is_empty(), "{name}: failed checks: {failed:?}");
}

#[test]
fn sphere_impact_quick() {
    quick("sphere_impact");
}

#[test]
fn sphere_impact_3d_quick() {
    quick("sphere_impact_3d");
}

#[test]
fn sphere_oblique_3d_quick() {
    quick("sphere_oblique_3d");
}

#[test]
fn soft_wall_cavity_quick() {
    quick("soft_wall_cavity");
}

#[test]
fn shear_rectangle_quick() {
    quick("shear_rectangle");
}

#[test]
fn oscillating_couette_quick() {
    quick("oscillating_couette");
}

#[test]
fn oscillating_couette_mr_quick() {
    quick("oscillating_couette_mr");
}

#[test]
fn disk_in_cavity_quick() {
    quick("disk_in_cavity");
}

#[test]
fn soft_sphere_in_cube_quick() {
    quick("soft_sphere_in_cube");
}

#[test]
fn two_soft_disks_quick() {
    quick("two_soft_disks");
}

#[test]
fn contact_map_quick() {
    quick("contact_map");
}

#[test]
fn spheres_on_axis_quick() {
    quick("spheres_on_axis");
}

#[test]
fn twenty_disks_quick() {
    quick("twenty_disks");
}

#[test]
fn disks_in_cavity_quick() {
    quick("disks_in_cavity");
}

#[test]
fn oscillating_disk_quick() {
    quick("oscillating_disk");
}

#[test]
fn lid_driven_cube_quick() {
    quick("lid_driven_cube");
}

#[test]
fn stability_quick() {
    // Twice into one folder: a second `bench-paper` into the same `--out` failed every setting
    // (efsi refused to write over the first run's outputs) until the harness cleared the case.
    quick_runs("stability", 2);
}

/// Every setting of the 3-D map stable or refused, the coupled step's (`Coupled`, G = 1e9,
/// ratio 1e3, CFL 0.9, 3 cells per radius) through the sphere's contact with the substrate.
#[test]
fn stability_3d_quick() {
    quick("stability_3d");
}

#[test]
fn extruded_cavity_quick() {
    quick("extruded_cavity");
}

#[test]
fn falling_drop_3d_quick() {
    quick("falling_drop_3d");
}

#[test]
fn vof_transport_3d_quick() {
    quick("vof_transport_3d");
}
