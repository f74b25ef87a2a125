//! The oblique sphere impact in three dimensions (`cases/sphere_oblique_3d.ron`, issue 41 case
//! 3) at a coarse grid: the sphere strikes the substrate at 30° from its normal, on half of the
//! box (the Symmetry plane z = 0 holds the plane of motion).

use efsi_tests::paper::{Options, execute_built, load_case, probes};

/// The scene at 5 cells per radius (Δx = 3.84 mm, a box of 25 × 15 × 10 cells) to 14 ms: the
/// sphere rebounds with a normal restitution in [0.8, 1] (measured 0.878; 0.948 at 10 cells per
/// radius), keeps its tangential velocity to 5 % (0.9992), turns the way the substrate's drag
/// turns it (ω_z < 0) while it mostly slides (|ω_z| R / u ≤ 0.2; 0.07), stays one piece and
/// keeps its volume to 1e-10. Before and after the contact: the probe samples (every 0.1 ms)
/// beside the span where the contact force exceeds 2 % of its peak.
#[test]
fn a_sphere_striking_the_substrate_at_30_degrees_rebounds_sliding_in_one_piece() {
    let (scene, path) = load_case("sphere_oblique_3d.ron").expect("scene");
    let out = std::env::temp_dir().join(format!("efsi-oblique-3d-{}", std::process::id()));
    let set = [
        "domain.x=(-0.0384, 0.0576)",
        "domain.y=(0.0, 0.0576)",
        "domain.z=(0.0, 0.0384)",
        "grid.nx=25",
        "grid.ny=15",
        "grid.nz=10",
        "time.end=0.014",
        "output.vtk_every=0.014",
    ];
    let opts = Options {
        quick: true,
        out: out.clone(),
        progress: false,
        overrides: set
            .iter()
            .map(|s| efsi_core::Override::parse(s).expect("override"))
            .collect(),
    };
    let scene = opts.adjust(scene).expect("5 cells per radius");
    let sim = efsi_run::simulation(scene, &path, &efsi_stages::builtin()).expect("built");
    let (_, run) = execute_built(sim, &out.join("run"), "oblique, 5 cells per radius", &opts)
        .unwrap_or_else(|e| panic!("the oblique impact failed: {e}"));
    let p = probes(&run.dir).expect("probes");
    let col = |name: &str| {
        p.col(name)
            .unwrap_or_else(|e| panic!("no column {name}: {e}"))
    };
    let (f, u, v, spin) = (
        col("contact_force"),
        col("solid_u"),
        col("solid_v"),
        col("solid_spin_z"),
    );
    let peak = f.iter().fold(0.0_f64, |m, &x| m.max(x));
    let on: Vec<usize> = (0..f.len()).filter(|&i| f[i] > 0.02 * peak).collect();
    let (before, after) = (on[0] - 1, on[on.len() - 1] + 1);
    assert!(after < f.len(), "the contact lasts to the end");
    let (e_n, e_t) = (-v[after] / v[before], u[after] / u[before]);
    let roll = spin[after] * 0.0192 / u[after];
    eprintln!(
        "e_n {e_n:.4}, e_t {e_t:.4}, ω_z {:.3} rad/s, ω_z R/u {roll:.3}",
        spin[after]
    );
    assert!((0.8..=1.0).contains(&e_n), "normal restitution {e_n}");
    assert!((0.95..=1.0).contains(&e_t), "tangential restitution {e_t}");
    assert!(
        spin[after] < 0.0 && roll.abs() <= 0.2,
        "spin {}",
        spin[after]
    );
    let pieces = col("solid_pieces");
    assert!(pieces.iter().all(|&n| n == 1.0), "pieces {pieces:?}");
    let vol = col("solid_volume");
    let drift = vol.iter().map(|x| (x - vol[0]).abs()).fold(0.0, f64::max) / vol[0];
    assert!(drift <= 1e-10, "volume drift {drift:e}");
    let _ = std::fs::remove_dir_all(&out);
}
