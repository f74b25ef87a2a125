//! A moving wall's speed as an input (`Simulation::set_wall_speed`), the hook an FMU's lid-speed
//! input drives: set to the scene's speed it changes nothing, bit for bit; set between steps it
//! acts from the next step on — also in the stages that keep their own copy of the boundary
//! conditions — with Δt set by the velocities inside the domain, not the lid's; bad requests
//! are refused by name.

use efsi_core::scene::Side;
use efsi_core::{Scene, Simulation};
use std::path::Path;

fn cavity(lid: f64) -> Simulation {
    let text = format!(
        r#"Scene(
    name: "lid",
    domain: (x: (0.0, 1.0), y: (0.0, 1.0)),
    grid: (nx: 16, ny: 16),
    time: (end: 1.0, cfl: 0.4, dt_max: 0.02),
    fluid: (density: 1.0, viscosity: 0.01),
    boundaries: (x_min: NoSlip, x_max: NoSlip, y_min: NoSlip, y_max: MovingWall(speed: {lid:?})),
)"#
    );
    let path = Path::new("lid.ron");
    efsi_run::simulation(
        Scene::from_str_at(&text, path).unwrap(),
        path,
        &efsi_stages::builtin(),
    )
    .unwrap()
}

fn advance(sim: &mut Simulation, until: f64) {
    while sim.state.t < until - 1e-12 {
        let dt = sim.next_dt(until).unwrap();
        sim.step(dt).unwrap();
        sim.snap_time(until);
    }
}

fn bits(sim: &Simulation) -> Vec<u64> {
    sim.state
        .u
        .data()
        .iter()
        .chain(sim.state.v.data())
        .chain(sim.state.p.data())
        .map(|x| x.to_bits())
        .collect()
}

#[test]
fn a_lid_set_moving_is_the_scene_with_a_moving_lid() {
    let mut set = cavity(0.0);
    set.set_wall_speed(Side::YMax, 1.0).unwrap();
    let mut scene = cavity(1.0);
    for k in 1..=10 {
        advance(&mut set, 0.05 * k as f64);
        advance(&mut scene, 0.05 * k as f64);
        assert_eq!(set.state.step, scene.state.step);
        assert!(bits(&set) == bits(&scene), "differs by t = {}", set.state.t);
    }
    assert!(set.state.u.max_abs(efsi_core::Stagger::XFace, 16, 16) > 0.1);
}

#[test]
fn a_lid_speed_changed_between_steps_acts_from_the_next_step() {
    let mut a = cavity(1.0);
    let mut b = cavity(1.0);
    advance(&mut a, 0.2);
    advance(&mut b, 0.2);
    b.set_wall_speed(Side::YMax, 3.0).unwrap();
    // Δt follows the velocities inside the cavity (the advection stage's CFL limit), not the
    // lid's speed: the wall's tangential velocity is carried by no face flux. What remains to
    // t = 1 is split into equal steps no longer than that limit and the scene's dt_max.
    let dt = b.next_dt(1.0).unwrap();
    let (stage, limit) = b.pipeline().limiting_stage(&b.grid, &b.state, 0.4).unwrap();
    assert_eq!(stage, "advection");
    assert!(
        limit > 0.4 / 16.0 / 3.0 * 1.5,
        "{limit}: the interior is slower than the new lid"
    );
    let steps = (0.8 / limit.min(0.02) * (1.0 - 1e-12)).ceil();
    assert!(
        (dt - 0.8 / steps).abs() <= 1e-12 * dt,
        "{dt} vs {}",
        0.8 / steps
    );
    advance(&mut a, 0.4);
    advance(&mut b, 0.4);
    let ke = |s: &Simulation| {
        efsi_core::operators::kinetic_energy(&s.grid, &s.state.velocity(), &s.state.rho)
    };
    assert!(ke(&b) > 3.0 * ke(&a), "{} vs {}", ke(&b), ke(&a));
}

#[test]
fn bad_wall_speeds_are_refused_by_name() {
    let mut sim = cavity(1.0);
    let e = sim.set_wall_speed(Side::XMin, 1.0).unwrap_err().to_string();
    assert!(
        e.contains("boundaries.x_min.speed") && e.contains("not a moving wall"),
        "{e}"
    );
    let e = sim
        .set_wall_speed(Side::YMax, f64::NAN)
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("boundaries.y_max.speed") && e.contains("finite"),
        "{e}"
    );
    assert_eq!(sim.bc.moving_wall_speed(Side::YMax), Some(1.0));
    assert_eq!(sim.bc.moving_wall_speed(Side::XMin), None);
}
