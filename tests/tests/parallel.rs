//! Parallel stages give the same bits on one and on two threads: a few steps of the Re = 1000
//! cavity and of the axisymmetric two-phase drop at 128² (large enough for the parallel paths),
//! (also with the block-multigrid viscous preconditioner), and of the sphere impact at 35 cells
//! per radius touching down (the elastic stage, with its block-multigrid and its Jacobi
//! preconditioner), and of three soft disks, two in contact (the bodies stepped in parallel:
//! their VOF windows, deformations and contact halos), each in a one-thread and a two-thread
//! rayon pool, compared field by field.

use efsi_tests::scenes::{CAVITY, DISKS, DROP, SPHERE};
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
            let mut fields = vec![&s.state.u, &s.state.v, &s.state.p, &s.state.rho];
            if let Some(d) = s.state.resources.get::<efsi_stages::elastic::Deformation>() {
                fields.extend(&d.b);
            }
            if let Some(many) = (s.state.resources).get::<efsi_stages::elastic::BodyDeformations>()
            {
                fields.extend(many.bodies.iter().flat_map(|d| &d.b));
            }
            if let Some(phi) = &s.state.phi {
                fields.push(phi);
            }
            fields
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
    let sphere_jacobi = SPHERE.replace(
        "boundaries:",
        "numerics: (elastic: (preconditioner: Jacobi)),\n    boundaries:",
    );
    for (name, text) in [
        ("cavity", CAVITY),
        ("drop", DROP),
        ("drop-mg", &drop_mg),
        ("sphere", SPHERE),
        ("sphere-jacobi", &sphere_jacobi),
        ("disks", DISKS),
    ] {
        let (a, b) = (run(text, 1, 8), run(text, 2, 8));
        let names = ["u", "v", "p", "rho", "B11", "B22", "B33", "B12"];
        let fields = match name {
            "cavity" => 4,
            // φ too.
            "drop" | "drop-mg" => 5,
            "disks" => 4 + 3 * 4 + 1,
            _ => 4 + 4 + 1,
        };
        assert_eq!(a.len(), fields, "{name}");
        for k in 0..a.len() {
            let field = match k {
                _ if k + 1 == a.len() && fields > 4 => "phi".to_string(),
                k if k < 4 => names[k].to_string(),
                k => format!("body {} {}", (k - 4) / 4, names[4 + (k - 4) % 4]),
            };
            let differ = a[k].iter().zip(&b[k]).filter(|(x, y)| x != y).count();
            assert_eq!(differ, 0, "{name}: {field} differs in {differ} entries");
        }
    }
}
