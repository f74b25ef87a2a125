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
            .deformation
            .as_ref()
            .map_or(0.0, |d| d.elastic_energy)
            .max(0.0);
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
    /// The largest moving-wall speed: imposed velocities the CFL condition must respect even
    /// before the flow has picked them up.
    wall_speed: f64,
    /// The energy guard: `None` until the first step after construction or a restore (the
    /// state is public and may be set up by hand in between), then `Some(None)` where something
    /// supplies energy and the guard is off.
    guard: Option<Option<EnergyGuard>>,
}

impl Simulation {
    /// Build a simulation from a scene and the available stage plugins.
    pub fn new(
        scene: Scene,
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
        // A solid's initial velocity V_s: every face gets the momentum-weighted mixture
        // (φ_f ρ_s V_s + (1 − φ_f) ρ_f V_fluid) / (φ_f ρ_s + (1 − φ_f) ρ_f), φ_f the average
        // fraction of its two cells — the velocity of the face's mixture — so a heavy body's
        // interface faces move with it. The initial projection (Pipeline::initialize) then
        // removes the divergence this leaves at the interface.
        if let Some(solid) = &scene.solid
            && let Some((us, vs)) = solid.velocity
        {
            let mut phi = Field::zeros(&grid);
            crate::interface::fill_fraction(&grid, &solid.shape, &mut phi);
            bc.fill_scalar(&grid, &mut phi, false);
            let (rs, rf) = (solid.density, scene.fluid.density);
            let blend = |f: f64, vs: f64, vf: f64| {
                let (ms, mf) = (f * rs, (1.0 - f) * rf);
                if ms + mf > 0.0 {
                    (ms * vs + mf * vf) / (ms + mf)
                } else {
                    vf
                }
            };
            for j in 0..grid.ny as isize {
                for i in 0..=grid.nx as isize {
                    let f = 0.5 * (phi[(i - 1, j)] + phi[(i, j)]);
                    state.u[(i, j)] = blend(f, us, state.u[(i, j)]);
                }
            }
            for j in 0..=grid.ny as isize {
                for i in 0..grid.nx as isize {
                    let f = 0.5 * (phi[(i, j - 1)] + phi[(i, j)]);
                    state.v[(i, j)] = blend(f, vs, state.v[(i, j)]);
                }
            }
        }
        bc.fill_velocity(&grid, &mut state.u, &mut state.v, 0.0, false);
        bc.fill_scalar(&grid, &mut state.rho, false);
        bc.fill_scalar(&grid, &mut state.mu, false);
        let mut pipeline = pipeline;
        pipeline.initialize(&grid, &bc, &mut state)?;
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

    /// Start the energy guard afresh at the next step (after a restore).
    pub(crate) fn restart_guard(&mut self) {
        self.guard = None;
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
        let dt = if let Some(fixed) = t.fixed_dt {
            fixed
        } else {
            let limit = self
                .pipeline
                .max_dt(&self.grid, &self.state, t.cfl)
                .or_else(|| {
                    (self.scene.physics.advection && self.velocity_scale > 0.0)
                        .then(|| t.cfl * self.grid.dx.min(self.grid.dy) / self.velocity_scale)
                });
            let wall = (self.wall_speed > 0.0)
                .then(|| t.cfl * self.grid.dx.min(self.grid.dy) / self.wall_speed);
            [limit, wall, t.dt_max]
                .into_iter()
                .flatten()
                .reduce(f64::min)
                .unwrap_or(remaining)
        };
        let dt_min = t.dt_min_or_default();
        if dt.is_nan() || dt < dt_min {
            return Err(EfsiError::Unstable {
                dt,
                dt_min,
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
    /// table accelerating upwards at `a` acts like gravity stronger by `a`). Snapshots and
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
        self.state.frame_acceleration = a;
        if a != (0.0, 0.0) {
            // An accelerating frame does work the guard does not account for.
            self.guard = Some(None);
        }
        Ok(())
    }

    /// Set the speed of the moving wall on `side` from the next step on (its profile and
    /// motion still multiply it; [`BoundarySet::set_wall_speed`]): an input that changes between
    /// steps, such as an FMU's lid speed. The step limit that keeps the CFL condition on the
    /// walls follows it; a wall set moving turns the energy guard off (it does work the guard
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
