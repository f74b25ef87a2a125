//! The purely elastic disk (μ_s = 0) of the oscillating-disk case (`cases/oscillating_disk.ron`,
//! after Robinson-Mosher et al.): its interface cuts the corners arbitrarily, down to slivers of
//! solid, and the run must stay within the energy the initial flow supplied and keep the solid's
//! volume.

use efsi_tests::paper::{Options, execute_built, load_case, probes};

#[test]
fn a_purely_elastic_disk_stays_in_its_energy_budget_and_keeps_its_volume() {
    let (mut scene, path) = load_case("oscillating_disk.ron").expect("scene");
    scene.grid.nx = 32;
    scene.grid.ny = 32;
    scene.time.end = 0.3;
    let out = std::env::temp_dir().join(format!("efsi-elastic-disk-{}", std::process::id()));
    let opts = Options {
        quick: true,
        out: out.clone(),
        progress: false,
        overrides: vec![efsi_core::Override::parse("solid.viscosity=0.0").expect("override")],
    };
    let scene = opts.adjust(scene).expect("μ_s = 0");
    let sim = efsi_run::simulation(scene, &path, &efsi_stages::builtin()).expect("built");
    let (_, run) = execute_built(sim, &out.join("run"), "32², μ_s = 0", &opts)
        .unwrap_or_else(|e| panic!("the μ_s = 0 disk at 32² failed: {e}"));
    let p = probes(&run.dir).expect("probes");
    let (t, ke, ee, vol) = (
        p.col("t").unwrap(),
        p.col("kinetic_energy").unwrap(),
        p.col("elastic_energy").unwrap(),
        p.col("solid_volume").unwrap(),
    );
    assert!(
        t[t.len() - 1] >= 0.3 - 1e-9,
        "ended at t = {}",
        t[t.len() - 1]
    );
    // Viscosity only drains: the total never exceeds the initial kinetic energy (the disk
    // starts stress-free) by more than the step's energy error.
    let budget = ke[0];
    let worst = ke
        .iter()
        .zip(ee)
        .map(|(k, e)| (k + e) / budget)
        .fold(0.0, f64::max);
    eprintln!("largest (KE + EE)/KE(0) = {worst}");
    assert!(worst.is_finite() && worst <= 1.0 + 1e-3, "{worst}");
    // The disk is squeezed: it stores a share of the flow's energy.
    let peak = ee.iter().fold(0.0, |m: f64, &e| m.max(e));
    assert!(peak >= 0.05 * budget, "elastic peak {peak:e} of {budget:e}");
    let drift = vol
        .iter()
        .map(|v| ((v - vol[0]) / vol[0]).abs())
        .fold(0.0, f64::max);
    eprintln!("volume drift {drift:e}");
    assert!(drift <= 1e-10, "{drift:e}");
    let _ = std::fs::remove_dir_all(out);
}
