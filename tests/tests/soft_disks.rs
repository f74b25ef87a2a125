//! Two identical soft neo-Hookean disks in head-on approach in a fluid at rest
//! (`cases/two_soft_disks.ron`, issue 42's case 1): each body keeps its own fraction and its
//! own deformation. Checked at every step: the mirror symmetry about x = 1, the total momentum,
//! no overlap, each body's volume, that it is one piece, and its strain energy; over the run,
//! that the bodies meet and part again.

use efsi_core::body_fractions::BodyFractions;
use efsi_core::{Field, Grid, Region, Simulation, Stagger, State};
use efsi_run::probes::{solid_moments, solid_pieces};
use efsi_tests::run_until;
use std::path::Path;

/// The case, to `end`.
fn two_soft_disks(end: f64) -> Simulation {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../cases/two_soft_disks.ron");
    let text = std::fs::read_to_string(&path).unwrap();
    let mut scene = efsi_core::Scene::from_str_at(&text, &path).unwrap_or_else(|e| panic!("{e}"));
    scene.source_dir = path.parent().map(Path::to_path_buf);
    scene.output = Default::default();
    scene.time.end = end;
    efsi_run::simulation(scene, &path, &efsi_stages::builtin()).unwrap_or_else(|e| panic!("{e}"))
}

/// Per body: volume, centroid (x, y), velocity (u, v), and the number of its pieces.
fn bodies(grid: &Grid, state: &State) -> Vec<[f64; 6]> {
    let all = state
        .resources
        .get::<BodyFractions>()
        .expect("several bodies");
    let mut phi = Field::zeros(grid);
    all.bodies
        .iter()
        .map(|b| {
            b.fill(&mut phi);
            let m = solid_moments(grid, state, &phi);
            [
                m.volume,
                m.centroid[0],
                m.centroid[1],
                m.velocity[0],
                m.velocity[1],
                solid_pieces(grid, &phi).count as f64,
            ]
        })
        .collect()
}

/// The momentum `∫ρV dV` (per unit depth): each face's velocity times the mean density of its
/// two cells and the cell area.
fn momentum(grid: &Grid, state: &State) -> [f64; 2] {
    let (rho, dv) = (&state.rho, grid.dx * grid.dy);
    let mut p = [0.0; 2];
    for (a, vel) in [&state.u, &state.v].into_iter().enumerate() {
        let faces = Region::of(
            grid,
            if a == 0 {
                Stagger::XFace
            } else {
                Stagger::YFace
            },
        );
        for l in (0..faces.lines()).map(|n| faces.line(n)) {
            for at in l.indices() {
                let mut lo = at;
                lo[a] -= 1;
                p[a] += 0.5 * (rho[lo] + rho[at]) * vel[at] * dv;
            }
        }
    }
    p
}

/// The largest `Σ_k φ_k` of a cell.
fn most_solid(grid: &Grid, state: &State) -> f64 {
    let phi = state.phi.as_ref().expect("a solid fraction");
    Region::of(grid, Stagger::Cell).max(0.0, |l| {
        phi.at(&l, [0; 3]).iter().fold(0.0, |m: f64, &f| m.max(f))
    })
}

#[test]
fn two_soft_disks_meet_and_part_mirror_symmetric_each_with_its_own_deformation() {
    let mut sim = two_soft_disks(0.8);
    let grid = sim.grid.clone();
    let start = bodies(&grid, &sim.state);
    let speed = start[0][3];
    assert!(speed > 0.49, "the left disk starts at {speed}");
    let ke0 = efsi_run::probes::kinetic_energy(&grid, &sim.state);
    let mut worst = [0.0f64; 6];
    let mut gap_min = f64::INFINITY;
    let (mut met, mut parted) = (false, false);
    let mut energy_max = 0.0f64;
    let gap0 = start[1][1] - start[0][1] - 0.4;
    let mut gap_end = f64::NAN;
    run_until(&mut sim, 0.8, |sim, _| {
        let s = &sim.state;
        let b = bodies(&grid, s);
        let (l, r) = (b[0], b[1]);
        // Mirror images about x = 1: x_l + x_r = 2, y_l = y_r, u_l = −u_r, v_l = v_r.
        worst[0] = worst[0].max((l[1] + r[1] - 2.0).abs() / 2.0);
        worst[1] = worst[1].max((l[2] - r[2]).abs());
        worst[2] = worst[2].max((l[3] + r[3]).abs() / speed);
        // Momentum (zero by symmetry), relative to one disk's at the start.
        let p = momentum(&grid, s);
        worst[3] = worst[3].max(p[0].abs().max(p[1].abs()) / (start[0][0] * speed));
        // No overlap, each body's volume.
        worst[4] = worst[4].max(most_solid(&grid, s) - 1.0);
        for (now, then) in b.iter().zip(&start) {
            worst[5] = worst[5].max((now[0] - then[0]).abs() / then[0]);
            assert_eq!(now[5], 1.0, "a body in {} pieces at t = {}", now[5], s.t);
        }
        // Strain energies: finite, per body, and with the kinetic energy never above the
        // start's (the fluid and the solids' viscosity dissipate).
        let all = s.resources.get::<BodyFractions>().unwrap();
        let e: Vec<f64> = all.bodies.iter().map(|b| b.elastic_energy).collect();
        assert!(e.iter().all(|e| e.is_finite() && *e >= 0.0), "{e:?}");
        let ke = efsi_run::probes::kinetic_energy(&grid, s);
        energy_max = energy_max.max((ke + e[0] + e[1]) / ke0);
        // The distance of the centroids less a diameter: negative once the disks meet and
        // flatten against the film between them; parting is the left disk moving left after,
        // at a quarter of its starting speed or more.
        let gap = r[1] - l[1] - 0.4;
        gap_min = gap_min.min(gap);
        gap_end = gap;
        met |= gap < 0.0;
        parted |= met && l[3] < -0.25 * speed;
    });
    eprintln!(
        "mirror x {:.2e}, y {:.2e}, u {:.2e}; momentum {:.2e}; max Σφ − 1 {:.2e}; volume {:.2e}; \
         gap {gap0:.4} → min {gap_min:.4} → {gap_end:.4}; max energy / start {energy_max:.4}; \
         met {met}, parted {parted}",
        worst[0], worst[1], worst[2], worst[3], worst[4], worst[5]
    );
    assert!(worst[0] <= 1e-12, "mirror x {:e}", worst[0]);
    assert!(worst[1] <= 1e-12, "mirror y {:e}", worst[1]);
    assert!(worst[2] <= 1e-12, "mirror u {:e}", worst[2]);
    assert!(worst[3] <= 1e-12, "momentum {:e}", worst[3]);
    assert!(worst[4] <= 1e-12, "overlap {:e}", worst[4]);
    assert!(worst[5] <= 1e-10, "volume {:e}", worst[5]);
    assert!(energy_max <= 1.0, "energy grew to {energy_max}");
    assert!(met, "the disks did not meet: smallest gap {gap_min}");
    assert!(parted, "the disks met and did not part");
    // Apart again, farther than they started.
    assert!(
        gap_end > gap0,
        "gap {gap_end} at the end, {gap0} at the start"
    );
}

/// Two soft disks side by side thrown down across a 64² box, to `end`.
fn falling_disks(end: f64) -> Simulation {
    let disk = |name: &str, x: f64| {
        format!(
            r#"(name: "{name}", shape: Disk(center: ({x}, 0.75), radius: 0.1), density: 5.0,
            viscosity: 0.01, velocity: (0.0, -2.0), law: (name: "neo_hookean", parameters: {{"G": 1.0}}))"#
        )
    };
    let text = format!(
        r#"Scene(name: "falling_disks", domain: (x: (0.0, 1.0), y: (0.0, 1.0)),
        grid: (nx: 64, ny: 64), time: (end: {end}, cfl: 0.4),
        fluid: (density: 1.0, viscosity: 0.01), gravity: (0.0, -1.0),
        solids: [{}, {}],
        boundaries: (x_min: NoSlip, x_max: NoSlip, y_min: NoSlip, y_max: NoSlip))"#,
        disk("a", 0.25),
        disk("b", 0.75)
    );
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../cases/falling_disks.ron");
    let mut scene = efsi_core::Scene::from_str_at(&text, &path).unwrap_or_else(|e| panic!("{e}"));
    scene.source_dir = path.parent().map(Path::to_path_buf);
    efsi_run::simulation(scene, &path, &efsi_stages::builtin()).unwrap_or_else(|e| panic!("{e}"))
}

/// The windows of the bodies' deformations.
fn windows(sim: &Simulation) -> Vec<efsi_stages::elastic::Place> {
    let many = sim
        .state
        .resources
        .get::<efsi_stages::elastic::BodyDeformations>();
    many.expect("several bodies").places.clone()
}

#[test]
fn each_body_keeps_its_deformation_on_a_window_that_follows_it_and_is_undone_with_a_snapshot() {
    let end = 0.3;
    let mut sim = falling_disks(end);
    let snap = sim.snapshot();
    let start = windows(&sim);
    let mut seen = vec![start.clone()];
    run_until(&mut sim, end, |sim, _| {
        let w = windows(sim);
        if seen.last() != Some(&w) {
            seen.push(w);
        }
    });
    eprintln!("windows {seen:?}");
    // Each window moves with its body (the disks fall some sixteen cells) and holds a fraction
    // of the grid's 64² cells.
    let last = seen.last().unwrap().clone();
    assert!((0..2).all(|k| last[k] != start[k]), "{seen:?}");
    let cells = |w: &efsi_stages::elastic::Place| w.n.iter().product::<usize>();
    assert!(
        seen.iter().flatten().all(|w| cells(w) <= 64 * 64 / 2),
        "{seen:?}"
    );
    // Back to the start across the moves (the snapshot's windows taken back), and the same
    // run again, bit for bit.
    let after: Vec<Vec<f64>> = sim
        .state
        .arrays()
        .iter()
        .map(|(_, f)| f.data().to_vec())
        .collect();
    sim.restore(&snap).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(windows(&sim), start);
    run_until(&mut sim, end, |_, _| {});
    assert_eq!(windows(&sim), last);
    let again: Vec<Vec<f64>> = sim
        .state
        .arrays()
        .iter()
        .map(|(_, f)| f.data().to_vec())
        .collect();
    assert!(after == again, "the run from the snapshot differs");
}
