//! The contact probes (`ContactForce`, `ContactRadius`) read exactly 0 when nothing touches:
//! the sphere impact of `cases/sphere_impact.ron` at 15 cells per radius (`--refine 15/35`),
//! stepped through touch-down, the contact and the lift-off to the case's end.

use efsi_core::scene::Side;
use efsi_core::{Override, Scene};
use efsi_run::SceneOverrides;
use efsi_run::probes::{CONTACT_MIN_SOLID_FRACTION, contact_force, contact_radius, solid_extent};
use efsi_tests::{run_until, workspace_root};

#[test]
fn contact_probes_are_exactly_zero_before_touch_down_and_after_lift_off() {
    let path = workspace_root().join("cases/sphere_impact.ron");
    let scene =
        Scene::load_with(&path, &[Override::Refine(15.0 / 35.0)]).unwrap_or_else(|e| panic!("{e}"));
    let mut sim = efsi_run::simulation(scene, &path, &efsi_stages::builtin())
        .unwrap_or_else(|e| panic!("{e}"));
    let (dz, radius) = (sim.grid.dy, 0.0192);
    assert!(
        (radius / sim.grid.dx - 15.0).abs() < 0.2,
        "{}",
        radius / sim.grid.dx
    );
    let end = sim.scene.time.end;
    // Per step: time, the solid's bottom on the axis, the first row's largest solid fraction,
    // the contact force and radius.
    let mut rows: Vec<(f64, f64, f64, f64, f64)> = Vec::new();
    run_until(&mut sim, end, |sim, _| {
        let phi = sim.state.phi.as_ref().expect("a solid");
        let row_max = (0..sim.grid.nx as isize).fold(0.0f64, |m, i| m.max(phi[(i, 0)]));
        rows.push((
            sim.state.t,
            solid_extent(&sim.grid, &sim.state, 0.0, 0.0).0,
            row_max,
            contact_force(&sim.grid, &sim.state, sim.pipeline().outputs(), Side::YMin),
            contact_radius(&sim.grid, &sim.state, sim.pipeline().outputs(), Side::YMin),
        ));
    });
    // Touch-down and lift-off as the solid fraction sees them: the first and last step with
    // solid (above the probes' threshold) in the row along the substrate.
    let touching = |r: &(f64, f64, f64, f64, f64)| r.2 >= CONTACT_MIN_SOLID_FRACTION;
    let first = rows
        .iter()
        .position(touching)
        .expect("the sphere touches down");
    let last = rows
        .iter()
        .rposition(touching)
        .expect("the sphere touches down");
    assert!(last + 1 < rows.len(), "the sphere lifts off before the end");
    let (t_down, t_up) = (rows[first].0, rows[last].0);
    // The impact is where free fall puts it (gap 0.0381 m at 1.22 m/s: ≈ 29 ms) and the contact
    // lasts a few milliseconds (Hertz: 6.4 ms).
    assert!((0.025..0.033).contains(&t_down), "touch-down at {t_down}");
    assert!(
        (0.003..0.012).contains(&(t_up - t_down)),
        "contact {t_down} → {t_up}"
    );
    for r in rows[..first].iter().chain(&rows[last + 1..]) {
        assert!(
            r.3 == 0.0 && r.3.is_sign_positive() && r.4 == 0.0,
            "no contact at t = {} (first row's φ ≤ {:e}, bottom {:.3e} m) but force {:e}, radius {:e}",
            r.0,
            r.2,
            r.1,
            r.3,
            r.4
        );
    }
    // After lift-off the sphere rises clear of the first row.
    let clear = rows[last + 1..].iter().filter(|r| r.1 > dz).count();
    assert!(clear > 0, "the sphere never rises above the first row");
    // During the contact the probes see it: a force of the order of Hertz's peak (≈ 22 N for
    // the body, 3.5 N per radian) and a footprint of a few cells (Hertz: 8.8 mm; every cell
    // pressing on the wall counts, so the rim's lightly loaded cells too).
    let peak = rows[first..=last].iter().fold(0.0f64, |m, r| m.max(r.3));
    let widest = rows[first..=last].iter().fold(0.0f64, |m, r| m.max(r.4));
    assert!(
        (1.0..10.0).contains(&peak),
        "peak contact force {peak} N per radian"
    );
    assert!(
        (2.0 * sim.grid.dx..0.8 * radius).contains(&widest),
        "widest footprint {widest} m"
    );
    // The trap: a trace of solid in the first row below the probes' threshold is not contact.
    // The VOF sets round-off wisps (φ < 1e-14) to zero, so a run may leave none there: after
    // the lift-off, put one just below the threshold in every cell of the row.
    let traces = rows[..first]
        .iter()
        .chain(&rows[last + 1..])
        .filter(|r| r.2 > 0.0)
        .count();
    let phi = sim.state.phi.as_mut().expect("a solid");
    for i in 0..sim.grid.nx as isize {
        phi[(i, 0)] = 0.9 * CONTACT_MIN_SOLID_FRACTION;
    }
    let force = contact_force(&sim.grid, &sim.state, sim.pipeline().outputs(), Side::YMin);
    let footprint = contact_radius(&sim.grid, &sim.state, sim.pipeline().outputs(), Side::YMin);
    assert!(
        force == 0.0 && force.is_sign_positive() && footprint == 0.0,
        "a trace below the threshold taken for contact: force {force:e}, radius {footprint:e}"
    );
    eprintln!(
        "touch-down {:.2} ms, lift-off {:.2} ms, peak force {peak:.3} N/rad, footprint {:.2} mm, \
         {traces} steps outside the contact with a trace of solid in the first row of the run",
        1e3 * t_down,
        1e3 * t_up,
        1e3 * widest
    );
}
