//! Parallel stages give the same bits on one and on two threads: a few steps of the Re = 1000
//! cavity and of the axisymmetric two-phase drop at 128² (large enough for the parallel paths),
//! (also with the block-multigrid viscous preconditioner), each in a one-thread and a
//! two-thread rayon pool, compared field by field.

use efsi_tests::scenes::{CAVITY, DROP};
use efsi_tests::sim;

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
