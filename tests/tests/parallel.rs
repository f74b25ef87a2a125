//! Parallel stages give the same bits on one and on two threads: a few steps of the Re = 1000
//! cavity and of the axisymmetric two-phase drop at 128² (large enough for the parallel paths),
//! (also with the block-multigrid viscous preconditioner), each in a one-thread and a
//! two-thread rayon pool, compared field by field.

use efsi_tests::sim;

const CAVITY: &str = r#"Scene(
    name: "cavity",
    domain: (x: (0.0, 1.0), y: (0.0, 1.0)),
    grid: (nx: 128, ny: 128),
    time: (end: 1.0, cfl: 0.4),
    fluid: (density: 1.0, viscosity: 1e-3),
    boundaries: (x_min: NoSlip, x_max: NoSlip, y_min: NoSlip, y_max: MovingWall(speed: 1.0)),
)"#;

const DROP: &str = r#"Scene(
    name: "drop",
    geometry: Axisymmetric,
    domain: (r: (0.0, 4.0), z: (0.0, 4.0)),
    grid: (nr: 128, nz: 128),
    time: (end: 1.0, fixed_dt: 0.00390625),
    fluid: (density: 1e-3, viscosity: 2e-4),
    gravity: (0.0, -1.0),
    solid: (shape: Disk(center: (0.0, 3.0), radius: 0.5), density: 1.0, viscosity: 1e-2),
    boundaries: (r_min: Axis, r_max: NoSlip, z_min: NoSlip, z_max: NoSlip),
)"#;

/// The raw bits of u, v, p, ρ after `steps` steps on a pool of `threads`.
fn run(text: &str, threads: usize, steps: usize) -> Vec<Vec<u64>> {
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .unwrap()
        .install(|| {
            let mut s = sim(text);
            for _ in 0..steps {
                let dt = s.next_dt(1.0).unwrap();
                s.step(dt).unwrap();
            }
            [&s.state.u, &s.state.v, &s.state.p, &s.state.rho]
                .iter()
                .map(|f| f.data().iter().map(|x| x.to_bits()).collect())
                .collect()
        })
}

#[test]
fn one_and_two_threads_give_bit_identical_steps() {
    // The drop also with the block-multigrid viscous preconditioner (default: Jacobi).
    let drop_mg = DROP.replace(
        "boundaries:",
        "numerics: (viscous: (preconditioner: Multigrid)),\n    boundaries:",
    );
    for (name, text) in [("cavity", CAVITY), ("drop", DROP), ("drop-mg", &drop_mg)] {
        let (a, b) = (run(text, 1, 8), run(text, 2, 8));
        for (k, field) in ["u", "v", "p", "rho"].iter().enumerate() {
            let differ = a[k].iter().zip(&b[k]).filter(|(x, y)| x != y).count();
            assert_eq!(differ, 0, "{name}: {field} differs in {differ} entries");
        }
    }
}
