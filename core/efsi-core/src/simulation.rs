//! The model and its stepper: a scene turned into a grid, boundary conditions, a state and a
//! checked pipeline, advanced one step at a time. The run loop and the outputs are separate
//! (crate `efsi-run`), so tests and the FMU drive a [`Simulation`] directly; its evolving data
//! is copied out and back with [`Simulation::snapshot`] and [`Simulation::restore`]
//! ([`crate::snapshot`]).

use crate::bc::BoundarySet;
use crate::error::EfsiError;
use crate::field::Field;
use crate::grid::Grid;
use crate::scene::{Boundary, InitialVelocity, Scene, Side};
use crate::schedule::{Pipeline, StagePlugin, StepContext};
use crate::state::State;
use std::path::{Path, PathBuf};

/// How far the kinetic + potential energy may rise above its start, as a multiple of the energy
/// the initial motion, the initial strain and gravity can have supplied, before a run is
/// stopped as unstable ([`EfsiError::EnergyGrowth`]). The stability map's stable runs stayed
/// below 0.003 of it; a run pumping energy in (a Saint Venant–Kirchhoff sphere at 10 cells per
/// radius: 800× in 60 ms) passes it within milliseconds, long before a NaN would appear.
pub const ENERGY_GUARD: f64 = 1.0;

/// The energy guard's record: the start, and the largest release of potential energy so far.
/// Active only where nothing else supplies energy — no moving wall, no frame acceleration, no
/// outflow boundary, no gravity along a periodic direction (walls at rest, axes, free-slip
/// walls and periodic boundaries across gravity supply none).
#[derive(Clone, Copy, Debug)]
struct EnergyGuard {
    /// Kinetic + potential energy at the start.
    mech0: f64,
    /// Potential energy at the start.
    pe0: f64,
    /// Kinetic + strain energy at the start.
    supply0: f64,
    /// The largest drop of potential energy below its start so far.
    release: f64,
    /// An absolute allowance for round-off (1e-9 of the energies involved).
    floor: f64,
}

impl EnergyGuard {
    fn energies(grid: &Grid, state: &State, gravity: (f64, f64)) -> (f64, f64, f64) {
        let ke = crate::ops::kinetic_energy(grid, &state.u, &state.v, &state.rho);
        let pe = crate::ops::potential_energy(grid, &state.rho, gravity);
        let ee = state
            .resources
            .iter()
            .fold(0.0, |e, r| e + r.stored_energy().max(0.0));
        (ke, pe, ee)
    }

    fn start(grid: &Grid, state: &State, scene: &Scene, wall_speed: f64) -> Option<Self> {
        if wall_speed != 0.0 || state.frame_acceleration != (0.0, 0.0) {
            return None;
        }
        // Fluid leaving or entering through an outflow, or gravity along a periodic direction
        // (a flow driven round and round), changes the energy without a potential for it.
        let b = &scene.boundaries;
        let open = Side::ALL
            .iter()
            .any(|&side| matches!(b.get(side), Boundary::Outflow));
        let periodic = |side: Side| matches!(b.get(side), Boundary::Periodic);
        let driven = (periodic(Side::XMin) && scene.gravity.0 != 0.0)
            || (periodic(Side::YMin) && scene.gravity.1 != 0.0);
        if open || driven {
            return None;
        }
        let (ke, pe, ee) = Self::energies(grid, state, scene.gravity);
        let mut mass = 0.0;
        for j in 0..grid.ny as isize {
            for i in 0..grid.nx as isize {
                mass += state.rho[(i, j)] * grid.cell_volume(i);
            }
        }
        let reach =
            scene.gravity.0.hypot(scene.gravity.1) * (grid.x1() - grid.x0).max(grid.y1() - grid.y0);
        let floor = (1e-9 * (ke + ee + mass * reach)).max(1e-300);
        [ke, pe, ee]
            .iter()
            .all(|x| x.is_finite())
            .then_some(EnergyGuard {
                mech0: ke + pe,
                pe0: pe,
                supply0: ke + ee,
                release: 0.0,
                floor,
            })
    }
}

/// A scene ready to step.
pub struct Simulation {
    /// The scene as read.
    pub scene: Scene,
    /// Where the scene came from (for messages).
    pub scene_path: PathBuf,
    /// The grid.
    pub grid: Grid,
    /// The boundary conditions.
    pub bc: BoundarySet,
    /// The fields and time.
    pub state: State,
    pipeline: Pipeline,
    previous: Option<(Field, Field)>,
    last_change: f64,
    velocity_scale: f64,
    /// The largest moving-wall speed (a wall that moves supplies energy: the energy guard is
    /// off). It is part of the velocity scale of the first step; after that Δt follows the
    /// velocities inside the domain, which is what the advection scheme's stability depends
    /// on (a wall's tangential speed is carried by no face flux).
    wall_speed: f64,
    /// The energy guard: `None` until the first step after construction or a restore (the
    /// state is public and may be set up by hand in between), then `Some(None)` where something
    /// supplies energy and the guard is off.
    guard: Option<Option<EnergyGuard>>,
}

impl Simulation {
    /// Build a simulation from a scene and the available stage plugins.
    pub fn new(
        mut scene: Scene,
        scene_path: &Path,
        plugins: &[&dyn StagePlugin],
    ) -> Result<Self, EfsiError> {
        let config = |field: &str, message: String| EfsiError::Config {
            path: scene_path.to_path_buf(),
            field: field.into(),
            message,
        };
        // Scenes built or changed in code (the paper's cases, tools) get the loader's checks too.
        scene
            .validate()
            .map_err(|(field, message)| config(&field, message))?;
        // The stages' `numerics` sections, checked by the plugins that declare them; an error
        // an override caused names the override.
        scene.check_options(scene_path, plugins)?;
        let grid = Grid::new(
            scene.geometry,
            scene.grid.nx,
            scene.grid.ny,
            scene.domain.x,
            scene.domain.y,
        );
        let bc = BoundarySet::new(&scene.boundaries, &grid);
        let pipeline = Pipeline::build(&scene, &grid, &bc, plugins)?;
        let mut state = State::new(
            &grid,
            scene.fluid.density,
            scene.fluid.viscosity,
            pipeline.fields(),
        );
        pipeline.init_state(&grid, &mut state);
        // Initial velocity.
        match &scene.initial_velocity {
            InitialVelocity::Rest => {}
            InitialVelocity::Uniform((a, b)) => {
                state.u.fill(*a);
                state.v.fill(*b);
            }
            InitialVelocity::SinSinStream {
                amplitude,
                wavenumbers,
            } => {
                if grid.is_axisymmetric() {
                    return Err(config(
                        "initial_velocity",
                        "SinSinStream is a planar stream function; not available in axisymmetric geometry".into(),
                    ));
                }
                let psi = |x: f64, y: f64| {
                    amplitude * (wavenumbers.0 * x).sin() * (wavenumbers.1 * y).sin()
                };
                for j in -1..=grid.ny as isize {
                    for i in -1..=grid.nx as isize + 1 {
                        let (x, y0, y1) = (grid.xf(i), grid.yf(j), grid.yf(j + 1));
                        state.u[(i, j)] = (psi(x, y1) - psi(x, y0)) / grid.dy;
                    }
                }
                for j in -1..=grid.ny as isize + 1 {
                    for i in -1..=grid.nx as isize {
                        let (x0, x1, y) = (grid.xf(i), grid.xf(i + 1), grid.yf(j));
                        state.v[(i, j)] = -(psi(x1, y) - psi(x0, y)) / grid.dx;
                    }
                }
            }
        }
        // A solid's initial velocity is blended in by the stage that owns the solid fraction
        // (the VOF stage's initialize).
        bc.fill_velocity(&grid, &mut state.u, &mut state.v, 0.0, false);
        bc.fill_scalar(&grid, &mut state.rho, false);
        bc.fill_scalar(&grid, &mut state.mu, false);
        let mut pipeline = pipeline;
        pipeline.initialize(&grid, &bc, &mut state)?;
        // A solid that covers no cell (outside the domain, far below a cell, an empty
        // intersection) would leave a run without one, its probes NaN.
        if scene.solid.is_some()
            && let Some(phi) = &state.phi
            && (0..grid.ny as isize).all(|j| (0..grid.nx as isize).all(|i| phi[(i, j)] <= 0.0))
        {
            return Err(config(
                "solid.shape",
                format!(
                    "covers no cell of the {}×{} grid (outside the domain, much smaller than a \
                     cell of {:e} × {:e}, or empty): the run would have no solid",
                    grid.nx, grid.ny, grid.dx, grid.dy
                ),
            ));
        }
        // A velocity scale bounds the first step when the fluid starts at rest.
        let mut wall_speed = 0.0f64;
        for side in Side::ALL {
            if let Boundary::MovingWall { speed, .. } = scene.boundaries.get(side) {
                wall_speed = wall_speed.max(speed.abs());
            }
        }
        let mut scale = wall_speed;
        let lx = grid.x1() - grid.x0;
        let ly = grid.y1() - grid.y0;
        scale = scale.max((scene.gravity.0.hypot(scene.gravity.1) * lx.max(ly)).sqrt());
        scale = scale.max(state.u.max_abs(crate::Stagger::XFace, grid.nx, grid.ny));
        scale = scale.max(state.v.max_abs(crate::Stagger::YFace, grid.nx, grid.ny));
        if scene.time.fixed_dt.is_none()
            && scene.time.dt_max.is_none()
            && (!scene.physics.advection || scale == 0.0)
        {
            return Err(config(
                "time.dt_max",
                if scene.physics.advection {
                    "nothing in this scene sets a velocity scale (no moving wall, gravity or initial velocity) \
                     from which to choose the first step: set time.dt_max or time.fixed_dt"
                        .into()
                } else {
                    "advection is off, so no CFL condition limits the step: set time.dt_max or time.fixed_dt".into()
                },
            ));
        }
        let previous = scene
            .time
            .steady
            .map(|_| (state.u.clone(), state.v.clone()));
        Ok(Simulation {
            scene,
            scene_path: scene_path.to_path_buf(),
            grid,
            bc,
            state,
            pipeline,
            previous,
            last_change: f64::INFINITY,
            velocity_scale: scale,
            wall_speed,
            guard: None,
        })
    }

    /// The energy guard's record, for a snapshot: empty before the guard starts (the first
    /// step), `[0]` when it is off, `[1, mech0, pe0, supply0, release, floor]` when it is on.
    pub(crate) fn guard_record_into(&self, out: &mut Vec<f64>) {
        out.clear();
        match &self.guard {
            None => {}
            Some(None) => out.push(0.0),
            Some(Some(g)) => out.extend([1.0, g.mech0, g.pe0, g.supply0, g.release, g.floor]),
        }
    }

    /// Put the energy guard back from a record of [`Self::guard_record_into`], so that its
    /// verdict does not depend on where a run was stopped and resumed; a record that does not
    /// fit starts it afresh at the next step. Off while something supplies energy now (a moving
    /// wall, a frame acceleration).
    pub(crate) fn set_guard_record(&mut self, r: &[f64]) {
        self.guard = match r {
            [x] if *x == 0.0 => Some(None),
            [x, mech0, pe0, supply0, release, floor] if *x == 1.0 => Some(Some(EnergyGuard {
                mech0: *mech0,
                pe0: *pe0,
                supply0: *supply0,
                release: *release,
                floor: *floor,
            })),
            _ => None,
        };
        if self.guard.is_some()
            && (self.wall_speed != 0.0 || self.state.frame_acceleration != (0.0, 0.0))
        {
            self.guard = Some(None);
        }
    }

    /// The pipeline (for printing, timings and statistics).
    pub fn pipeline(&self) -> &Pipeline {
        &self.pipeline
    }

    pub(crate) fn pipeline_mut(&mut self) -> &mut Pipeline {
        &mut self.pipeline
    }

    /// The private stepping data a snapshot carries: the last rate of change and the velocity
    /// scale. (`previous` is not: [`step`](Self::step) overwrites it before reading it.)
    pub(crate) fn stepping(&self) -> (f64, f64) {
        (self.last_change, self.velocity_scale)
    }

    pub(crate) fn set_stepping(&mut self, last_change: f64, velocity_scale: f64) {
        self.last_change = last_change;
        self.velocity_scale = velocity_scale;
    }

    /// The Δt for the next step, at most `until − t` (to land on an output time or the end).
    pub fn next_dt(&self, until: f64) -> Result<f64, EfsiError> {
        let t = &self.scene.time;
        let remaining = until - self.state.t;
        let h = self.grid.dx.min(self.grid.dy);
        // Each candidate limit with what sets it (for the message when Δt collapses).
        let (dt, cause) = if let Some(fixed) = t.fixed_dt {
            (fixed, "time.fixed_dt".to_string())
        } else {
            let stage = self
                .pipeline
                .limiting_stage(&self.grid, &self.state, t.cfl)
                .map(|(name, d)| {
                    (
                        d,
                        format!(
                            "the stability limit of the stage `{name}` (time.cfl = {}{})",
                            crate::scene::num(t.cfl),
                            if name == "deformation" {
                                ", numerics.elastic.wave_courant (coupled_wave_courant with the coupled step) and the solid's stiffness: the elastic wave speed"
                            } else {
                                ", and the velocity it sees"
                            }
                        ),
                    )
                });
            let advective =
                (self.scene.physics.advection && self.velocity_scale > 0.0).then(|| {
                    (
                        t.cfl * h / self.velocity_scale,
                        format!(
                            "the advective CFL limit time.cfl·h/|u| (time.cfl = {}, |u| = {:.3e})",
                            crate::scene::num(t.cfl),
                            self.velocity_scale
                        ),
                    )
                });
            let dt_max = t.dt_max.map(|d| (d, "time.dt_max".to_string()));
            [stage.or(advective), dt_max]
                .into_iter()
                .flatten()
                .reduce(|a, b| if b.0 < a.0 { b } else { a })
                .unwrap_or((remaining, "the time left".to_string()))
        };
        let dt_min = t.dt_min_or_default();
        if dt.is_nan() || dt < dt_min {
            let floor = if t.dt_min.is_some() {
                "time.dt_min as set".to_string()
            } else {
                format!(
                    "the default 1e-12·time.end, time.end = {}",
                    crate::scene::num(t.end)
                )
            };
            let velocity = cause.contains("|u|") || cause.contains("velocity it sees");
            let advice = if velocity && t.cfl >= 1e-3 {
                "if the velocity is growing without bound, lower time.cfl or check the scene's \
                 forcing; if the scene is right, set time.dt_min lower"
            } else {
                "set time.dt_min lower, or change the setting named"
            };
            return Err(EfsiError::Unstable {
                dt,
                dt_min,
                cause: format!("Δt was set by {cause}; time.dt_min is {floor}: {advice}"),
                t: self.state.t,
                step: self.state.step,
            });
        }
        // Land exactly on `until` by splitting what remains into equal steps no larger than
        // `dt`: a cut step would change Δt abruptly, and the projection's splitting error (and
        // so the discrete solution near singular corners) depends on Δt.
        if dt >= remaining * (1.0 - 1e-9) {
            return Ok(remaining);
        }
        let n = (remaining / dt * (1.0 - 1e-12)).ceil();
        Ok(remaining / n)
    }

    /// Advance by one step of size `dt`.
    pub fn step(&mut self, dt: f64) -> Result<(), EfsiError> {
        if let Some((pu, pv)) = &mut self.previous {
            pu.copy_from(&self.state.u);
            pv.copy_from(&self.state.v);
        }
        let ctx = StepContext {
            grid: &self.grid,
            bc: &self.bc,
            t: self.state.t,
            dt,
            step: self.state.step,
        };
        if self.guard.is_none() {
            self.guard = Some(EnergyGuard::start(
                &self.grid,
                &self.state,
                &self.scene,
                self.wall_speed,
            ));
        }
        self.pipeline.run_step(&ctx, &mut self.state)?;
        self.state.t += dt;
        self.state.step += 1;
        self.state.dt_prev = dt;
        if let Some(Some(g)) = &mut self.guard {
            let (ke, pe, _) = EnergyGuard::energies(&self.grid, &self.state, self.scene.gravity);
            g.release = g.release.max(g.pe0 - pe);
            let supplied = g.supply0 + g.release;
            let gain = ke + pe - g.mech0;
            if gain > ENERGY_GUARD * supplied + g.floor {
                return Err(EfsiError::EnergyGrowth {
                    t: self.state.t,
                    step: self.state.step,
                    gain,
                    supplied,
                    limit: ENERGY_GUARD,
                });
            }
        }
        if let Some((pu, pv)) = &self.previous {
            let (nx, ny) = (self.grid.nx as isize, self.grid.ny as isize);
            let ux = self.bc.normal_faces(0, self.grid.nx);
            let vy = self.bc.normal_faces(1, self.grid.ny);
            let mut m = 0.0f64;
            for j in 0..ny {
                for i in ux.lo..ux.hi {
                    m = m.max((self.state.u[(i, j)] - pu[(i, j)]).abs());
                }
            }
            for j in vy.lo..vy.hi {
                for i in 0..nx {
                    m = m.max((self.state.v[(i, j)] - pv[(i, j)]).abs());
                }
            }
            self.last_change = m / dt;
        }
        Ok(())
    }

    /// Set the acceleration of the grid's frame with respect to an inertial one, from the next
    /// step on ([`State::frame_acceleration`]: the body force becomes `gravity − a`, so a
    /// table accelerating upwards at `a` acts like gravity stronger by `a`). Set before the
    /// first step, the stages start again from the new frame ([`Pipeline::initialize_stages`]),
    /// so a constant acceleration is exactly a change of gravity. Snapshots and
    /// checkpoints carry it. Refused — nothing changes — when the value is not finite, when
    /// it has a radial component in axisymmetric geometry, or when no body-force stage runs
    /// (the body force is scheduled only in scenes with gravity).
    pub fn set_frame_acceleration(&mut self, a: (f64, f64)) -> Result<(), EfsiError> {
        let refuse = |message: String| EfsiError::Config {
            path: self.scene_path.clone(),
            field: "frame_acceleration".into(),
            message,
        };
        if !(a.0.is_finite() && a.1.is_finite()) {
            return Err(refuse(format!("must be finite, got ({}, {})", a.0, a.1)));
        }
        if self.grid.is_axisymmetric() && a.0 != 0.0 {
            return Err(refuse(format!(
                "must be along z in axisymmetric geometry, got a radial component {}",
                a.0
            )));
        }
        if !self.pipeline.has_phase(crate::Phase::BodyForce) {
            return Err(refuse(
                "no body-force stage runs in this scene (it is scheduled only with gravity): give the scene a gravity"
                    .into(),
            ));
        }
        let changed = self.state.frame_acceleration != a;
        self.state.frame_acceleration = a;
        if changed && self.state.step == 0 {
            // Before the first step the stages start again from the new frame (the incremental
            // projection's starting pressure balances gravity less the acceleration), so a
            // constant acceleration is exactly a change of gravity.
            self.pipeline
                .initialize_stages(&self.grid, &self.bc, &mut self.state)
                .map_err(EfsiError::Stage)?;
        }
        if a != (0.0, 0.0) {
            // An accelerating frame does work the guard does not account for.
            self.guard = Some(None);
        }
        Ok(())
    }

    /// Set the speed of the moving wall on `side` from the next step on (its profile and
    /// motion still multiply it; [`BoundarySet::set_wall_speed`]): an input that changes between
    /// steps, such as an FMU's lid speed. It bounds Δt while the fluid is at rest (the velocity
    /// scale of a first step); a wall set moving turns the energy guard off (it does work the guard
    /// does not account for). Snapshots do not carry it: who sets it sets it again after a
    /// restore. Refused — nothing changes — for a side that is not a moving wall or a speed
    /// that is not finite.
    pub fn set_wall_speed(&mut self, side: Side, speed: f64) -> Result<(), EfsiError> {
        self.bc
            .set_wall_speed(side, speed)
            .map_err(|message| EfsiError::Config {
                path: self.scene_path.clone(),
                field: format!("boundaries.{}.speed", side.field_name()),
                message,
            })?;
        self.wall_speed = Side::ALL
            .iter()
            .filter_map(|&s| self.bc.moving_wall_speed(s))
            .fold(0.0, |m: f64, v| m.max(v.abs()));
        // A lid set moving in a fluid at rest bounds the first step as the scene's would.
        self.velocity_scale = self.velocity_scale.max(self.wall_speed);
        if speed != 0.0 {
            self.guard = Some(None);
        }
        Ok(())
    }

    /// Set the time exactly (after landing on an output time, to avoid round-off drift).
    pub fn snap_time(&mut self, t: f64) {
        if (self.state.t - t).abs() <= 1e-9 * t.abs().max(1e-300) {
            self.state.t = t;
        }
    }

    /// `max |uⁿ⁺¹ − uⁿ|/Δt` of the last step (infinite before the first or when not tracked).
    pub fn rate_of_change(&self) -> f64 {
        self.last_change
    }

    /// Whether the scene asked to stop at steady state and the flow has reached it.
    pub fn is_steady(&self) -> bool {
        self.scene
            .time
            .steady
            .is_some_and(|tol| self.last_change <= tol)
    }
}
