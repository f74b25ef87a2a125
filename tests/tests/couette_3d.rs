//! Sugiyama's oscillating Couette flow in three dimensions (`cases/oscillating_couette_3d.ron`,
//! issue 41 case 1): the wall moving along `d = (cos 30°, 0, sin 30°)`, periodic in x and z.
//! The flow is the planar case's along `d`: the 3-D velocity along `d` must give the planar
//! error against the start-up reference, the cross-plane component `−sin 30° u + cos 30° w`
//! and `v` stay at round-off (within the projection's tolerance where the stress loads the
//! pressure), a non-linear law (Mooney–Rivlin, whose stress grows with `tr B̃`) gives the
//! planar profile, and the strain energy of the 3-D layer over its depth is the planar one's.

use efsi_core::Simulation;
use efsi_tests::{read_csv, reference, run_until};

/// The direction of the wall's motion, `(cos 30°, sin 30°)` in the x–z plane.
const D: (f64, f64) = (0.866_025_403_784_438_6, 0.5);

/// The two laws: Sugiyama's neo-Hookean layer, and the Mooney–Rivlin one of
/// `tests/references/oscillating_couette_mr/` (`L = 0.4`, `μ_f = 0.02`, `μ_s = 0.002`, `V = 0.4`).
#[derive(Clone, Copy)]
enum Law {
    NeoHookean,
    MooneyRivlin,
}

/// The Couette scene at `n` cells across, Δt `dt`, planar or in three dimensions (4 cells
/// along x, and along z in 3-D), with the bench's numerics (Crank–Nicolson viscous step,
/// `Strict` tolerances: `tests/src/paper/couette.rs`).
fn scene(law: Law, n: usize, dt: f64, three_d: bool) -> Simulation {
    scene_with(
        law,
        n,
        dt,
        three_d,
        efsi_stages::elastic::ElasticCoupling::Auto,
    )
}

/// [`scene`] with the elastic step's `coupling`.
fn scene_with(
    law: Law,
    n: usize,
    dt: f64,
    three_d: bool,
    coupling: efsi_stages::elastic::ElasticCoupling,
) -> Simulation {
    let kind = law;
    let (l, mu_f, mu_s, v, law) = match law {
        Law::NeoHookean => (
            1.0,
            1.0,
            0.0,
            1.0,
            r#"(name: "neo_hookean", parameters: {"G": 5.0})"#,
        ),
        Law::MooneyRivlin => (
            0.4,
            0.02,
            0.002,
            0.4,
            r#"(name: "mooney_rivlin", parameters: {"C1": 0.02, "C2": 0.0, "C3": 0.04})"#,
        ),
    };
    let w = 4.0 * l / n as f64;
    let text = if three_d {
        format!(
            r#"Scene(name: "c3", geometry: Cartesian3D,
    domain: (x: (0.0, {w:e}), y: (0.0, {l:e}), z: (0.0, {w:e})),
    grid: (nx: 4, ny: {n}, nz: 4),
    time: (end: 100.0, cfl: 0.4, dt_max: {dt:e}),
    fluid: (density: 1.0, viscosity: {mu_f:e}),
    solid: (shape: HalfSpace(normal: (0.0, 1.0, 0.0), offset: {h:e}), density: 1.0,
            viscosity: {mu_s:e}, law: {law}),
    boundaries: (x_min: Periodic, x_max: Periodic, y_min: NoSlip,
        y_max: MovingWall(speed: {v:e}, motion: Sin(omega: 3.141592653589793),
                          direction: ({c:e}, 0.0, {s:e})),
        z_min: Periodic, z_max: Periodic))"#,
            h = 0.5 * l,
            c = D.0,
            s = D.1,
        )
    } else {
        format!(
            r#"Scene(name: "c2",
    domain: (x: (0.0, {w:e}), y: (0.0, {l:e})),
    grid: (nx: 4, ny: {n}),
    time: (end: 100.0, cfl: 0.4, dt_max: {dt:e}),
    fluid: (density: 1.0, viscosity: {mu_f:e}),
    solid: (shape: HalfPlane(normal: (0.0, 1.0), offset: {h:e}), density: 1.0,
            viscosity: {mu_s:e}, law: {law}),
    boundaries: (x_min: Periodic, x_max: Periodic, y_min: NoSlip,
        y_max: MovingWall(speed: {v:e}, motion: Sin(omega: 3.141592653589793))))"#,
            h = 0.5 * l,
        )
    };
    let mut scene = efsi_tests::scene(&text);
    scene.numerics.preset = efsi_core::scene::Preset::Strict;
    scene.numerics.set(&efsi_stages::viscous::ViscousOptions {
        theta: 0.5,
        ..Default::default()
    });
    scene.numerics.set(&efsi_stages::elastic::ElasticOptions {
        coupling,
        ..Default::default()
    });
    // The Mooney–Rivlin layer loads the pressure: its projection is converged to round-off
    // (see `a_mooney_rivlin_layer_sheared_obliquely_gives_the_planar_profile`).
    if let Law::MooneyRivlin = kind {
        scene
            .numerics
            .set(&efsi_stages::projection::ProjectionOptions {
                tolerance: Some(1e-14),
                ..Default::default()
            });
    }
    let path = efsi_tests::workspace_root().join("cases/oscillating_couette_3d.ron");
    efsi_run::simulation(scene, &path, &efsi_stages::builtin()).unwrap_or_else(|e| panic!("{e}"))
}

/// The velocity along the wall's motion and across it at the u points of the first column
/// (every column is the same), and the largest |v|: planar `(u, 0)`, in 3-D
/// `(d·(u, w), d⊥·(u, w))`.
fn profile(sim: &Simulation) -> (Vec<f64>, Vec<f64>, f64) {
    let s = &sim.state;
    let ny = sim.grid.ny as isize;
    let (mut along, mut across) = (Vec::new(), Vec::new());
    for j in 0..ny {
        match &s.w {
            Some(w) => {
                let (u, w) = (s.u[[0, j, 0]], w[[0, j, 0]]);
                along.push(D.0 * u + D.1 * w);
                across.push(-D.1 * u + D.0 * w);
            }
            None => {
                along.push(s.u[[0, j, 0]]);
                across.push(0.0);
            }
        }
    }
    let v = s.v.data().iter().fold(0.0_f64, |m, v| m.max(v.abs()));
    (along, across, v)
}

/// The strain energy `∫ W dV` of the elastic stage's last update, per unit depth along z in
/// 3-D (the planar one is per unit depth already): the two layers are `nx` cells wide along x
/// and the 3-D one as deep along z.
fn strain_energy(sim: &Simulation) -> f64 {
    let e = sim
        .state
        .resources
        .get::<efsi_stages::elastic::Deformation>()
        .map_or(f64::NAN, |d| d.elastic_energy);
    e / sim.grid.dz / sim.grid.nz as f64
}

/// Max |u − u_ref| at the cell centres against the start-up reference at `t`.
fn error(u: &[f64], t: &str) -> f64 {
    let n = u.len();
    let y: Vec<f64> = (0..n).map(|j| (j as f64 + 0.5) / n as f64).collect();
    let (h, c) = read_csv(&reference(&format!(
        "oscillating_couette/from_rest/u_profile_t_{t}.csv"
    )));
    let col = |name: &str| &c[h.iter().position(|x| x == name).unwrap()];
    let (ry, ru) = (col("y"), col("u"));
    let at = |x: f64| {
        let k = ry.partition_point(|&r| r < x).clamp(1, ry.len() - 1);
        let f = (x - ry[k - 1]) / (ry[k] - ry[k - 1]);
        ru[k - 1] + f * (ru[k] - ru[k - 1])
    };
    y.iter()
        .zip(u)
        .map(|(&y, &u)| (u - at(y)).abs())
        .fold(0.0, f64::max)
}

/// Neo-Hookean at 32 cells, t = 1 (Δt = 2e-3, the bench's combined series): the 3-D error
/// along the wall's motion equals the planar one to 1e-3 of itself (the two solve the same
/// equations plane by plane; they differ by the linear solvers' tolerances), the velocity
/// across it stays below 1e-12 of the wall's speed, and so does v. The strain energy per unit
/// depth is the planar one's to 1e-5 of itself: the two differ by the normal components' O(h²)
/// (the 3-D stretching of `B̃₁₃` takes products of the edges' means where a centre takes the
/// mean of the products), which the flow along the wall does not see.
#[test]
fn the_oblique_couette_flow_is_the_planar_one_along_the_wall() {
    let (n, dt) = (32, 2e-3);
    let mut p = scene(Law::NeoHookean, n, dt, false);
    let mut q = scene(Law::NeoHookean, n, dt, true);
    let mut worst_across = 0.0_f64;
    run_until(&mut p, 1.0, |_, _| {});
    run_until(&mut q, 1.0, |sim, _| {
        let (_, across, v) = profile(sim);
        let a = across.iter().fold(v, |m, x| m.max(x.abs()));
        worst_across = worst_across.max(a);
    });
    let (e2, e3) = (error(&profile(&p).0, "1"), error(&profile(&q).0, "1"));
    let (w2, w3) = (strain_energy(&p), strain_energy(&q));
    eprintln!(
        "t = 1, {n} cells: planar error {e2:.6e}, 3-D {e3:.6e}; worst across {worst_across:.3e}; \
         strain energy per depth planar {w2:.12e}, 3-D {w3:.12e}"
    );
    assert!(e2 < 6e-4, "planar error {e2:e}");
    assert!(w2 > 1e-2, "planar strain energy {w2:e}");
    assert!(
        (w3 - w2).abs() <= 1e-5 * w2,
        "3-D strain energy per depth {w3:e} ≠ planar {w2:e}"
    );
    assert!(
        (e3 - e2).abs() <= 1e-3 * e2,
        "3-D error {e3:e} ≠ planar {e2:e}"
    );
    assert!(
        worst_across <= 1e-12,
        "velocity across the wall's motion {worst_across:e}"
    );
}

/// Mooney–Rivlin at 16 cells to t = 2: the 3-D profile along the wall's motion is the planar
/// one to 1e-6 of the wall's speed, and the velocity across it stays at round-off. Its stress
/// grows with `tr B̃`, so its normal stress `τ₂₂` varies across the layer and loads the
/// pressure; the projection is converged to round-off here (tolerance 1e-14). At the `Strict`
/// tolerance (`max |∇·V| Δt ≤ 1e-10`) the 3-D projection leaves v ~1e-11, not uniform in x and
/// z (the planar one happens to converge to 1e-20), the VOF step hands that residual to φ, and
/// once a full cell has drifted below the bulk shear gradient's threshold (`1 − 1e-9`, after
/// ~100 steps) the stencil switches cell by cell and the profiles part at O(h²) (1e-3): what
/// this test would then measure is the projection's tolerance, not the elastic kernels. The
/// strain energy per unit depth is the planar one's to 2e-4 of itself (the normal components'
/// O(h²) of the neo-Hookean test, largest in the interface row at 16 cells).
#[test]
fn a_mooney_rivlin_layer_sheared_obliquely_gives_the_planar_profile() {
    let (n, dt) = (16, 4e-3);
    let mut p = scene(Law::MooneyRivlin, n, dt, false);
    let mut q = scene(Law::MooneyRivlin, n, dt, true);
    run_until(&mut p, 2.0, |_, _| {});
    run_until(&mut q, 2.0, |_, _| {});
    let ((a2, _, _), (a3, across, v)) = (profile(&p), profile(&q));
    let diff = a2
        .iter()
        .zip(&a3)
        .map(|(a, b)| (a - b).abs())
        .fold(0.0, f64::max);
    let peak = a2.iter().fold(0.0_f64, |m, a| m.max(a.abs()));
    let across = across.iter().fold(v, |m, x| m.max(x.abs()));
    let (w2, w3) = (strain_energy(&p), strain_energy(&q));
    eprintln!(
        "MR t = 2, {n} cells: max |U3 − U2| {diff:.3e} (peak {peak:.3e}), across {across:.3e}; \
         strain energy per depth planar {w2:.12e}, 3-D {w3:.12e}"
    );
    assert!(peak > 0.05, "peak {peak:e}");
    assert!(diff <= 1e-6 * 0.4, "max |U3 − U2| = {diff:e}");
    assert!(w2 > 1e-5, "planar strain energy {w2:e}");
    assert!(
        (w3 - w2).abs() <= 2e-4 * w2,
        "3-D strain energy per depth {w3:e} ≠ planar {w2:e}"
    );
    assert!(
        across <= 1e-12,
        "velocity across the wall's motion {across:e}"
    );
}

/// The coupled elastic–pressure step (`coupling: Coupled`) in three dimensions: neo-Hookean
/// at 16 cells to t = 1 (Δt = 4e-3), the profile along the wall's motion is the planar coupled
/// run's to 1e-3 of its peak (the saddle-point solves stop at their tolerances, 2.5e-4 of the
/// peak apart), and the velocity across it stays below 1e-9 of the wall's speed.
#[test]
fn the_coupled_step_in_three_dimensions_gives_the_planar_coupled_profile() {
    use efsi_stages::elastic::ElasticCoupling::Coupled;
    let (n, dt) = (16, 4e-3);
    let mut p = scene_with(Law::NeoHookean, n, dt, false, Coupled);
    let mut q = scene_with(Law::NeoHookean, n, dt, true, Coupled);
    run_until(&mut p, 1.0, |_, _| {});
    run_until(&mut q, 1.0, |_, _| {});
    let ((a2, _, _), (a3, across, v)) = (profile(&p), profile(&q));
    let diff = a2
        .iter()
        .zip(&a3)
        .map(|(a, b)| (a - b).abs())
        .fold(0.0, f64::max);
    let peak = a2.iter().fold(0.0_f64, |m, a| m.max(a.abs()));
    let across = across.iter().fold(v, |m, x| m.max(x.abs()));
    eprintln!(
        "coupled t = 1, {n} cells: max |U3 − U2| {diff:.3e} (peak {peak:.3e}), across {across:.3e}"
    );
    assert!(peak > 0.1, "peak {peak:e}");
    assert!(diff <= 1e-3 * peak, "max |U3 − U2| = {diff:e}");
    assert!(
        across <= 1e-9,
        "velocity across the wall's motion {across:e}"
    );
}
