//! The model and its stepper: a scene turned into a grid, boundary conditions, a state and a
//! checked pipeline, advanced one step at a time. The run loop and the outputs are separate
//! (crate `efsi-run`), so tests and the FMU drive a [`Simulation`] directly; its evolving data
//! is copied out and back with [`Simulation::snapshot`] and [`Simulation::restore`]
//! ([`crate::snapshot`]).

use crate::bc::BoundarySet;
use crate::error::EfsiError;
use crate::field::Field;
use crate::field::Stagger;
use crate::grid::{Geometry, Grid};
use crate::loops::Region;
use crate::scene::{InitialVelocity, Options, Scene, Side};
use crate::schedule::{Pipeline, StagePlugin, StepContext};
use crate::state::State;
use std::path::{Path, PathBuf};

/// A check of every step that may stop a run, added by the driver that builds the simulation
/// ([`Simulation::add_check`]; crate `efsi-run` adds its energy guard). [`Simulation::step`]
/// calls [`before`](Self::before) ahead of the pipeline and [`after`](Self::after) once the
/// step's time and count are set; an error from `after` is the step's. What a check carries
/// from step to step travels in snapshots ([`crate::Snapshot::checks`]) and checkpoints.
pub trait StepCheck: Send {
    /// Its name, which labels its record in a snapshot.
    fn name(&self) -> &'static str;
    /// Before the step, on the state it starts from (default: nothing).
    fn before(&mut self, _scene: &Scene, _ctx: &StepContext, _state: &State) {}
    /// After the step, on the state it left.
    fn after(&mut self, scene: &Scene, ctx: &StepContext, state: &State) -> Result<(), EfsiError>;
    /// Its record of what carries from step to step, into `out` (contents replaced, allocation
    /// reused: the run loop snapshots before every step).
    fn save_into(&self, out: &mut Vec<f64>);
    /// Take back a record of [`save_into`](Self::save_into) (empty when the snapshot holds none
    /// for it), so that the steps after a restore are judged as those of the run it continues.
    fn restore(&mut self, record: &[f64]);
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
    /// The scene's checked sections in their owners' types ([`Options`]), from which the
    /// stages were built.
    options: Options,
    pipeline: Pipeline,
    /// The velocity components `u`, `v`, `w` (`None` in two dimensions) before the step, when
    /// the scene stops at steady state and the step is not told the state it starts from
    /// ([`step_from`](Self::step_from)): made at the first such step.
    previous: Option<[Option<Field>; 3]>,
    last_change: f64,
    velocity_scale: f64,
    /// The step checks, in the order added.
    checks: Vec<Box<dyn StepCheck>>,
}

impl Simulation {
    /// Build a simulation from a scene and the available stage plugins.
    pub fn new(
        mut scene: Scene,
        scene_path: &Path,
        plugins: &[&dyn StagePlugin],
    ) -> Result<Self, EfsiError> {
        // Scenes built or changed in code (the paper's cases, tools) get the loader's checks too.
        scene
            .validate()
            .map_err(|(field, message)| EfsiError::Config {
                path: scene_path.to_path_buf(),
                field,
                message,
            })?;
        // The sections the stages own (`solid`, `numerics`), checked by their plugins and read
        // once into their types; an error an override caused names the override.
        let options = scene.check_options(scene_path, plugins)?;
        Simulation::with_options(scene, options, scene_path, plugins)
    }

    /// Build a simulation from a scene whose sections were checked already with the same
    /// `plugins` ([`Scene::check_options`], which returned `options`): a driver that compares
    /// the checked scene with another (a checkpoint's) builds from it without reading its
    /// sections a second time.
    pub fn with_options(
        scene: Scene,
        options: Options,
        scene_path: &Path,
        plugins: &[&dyn StagePlugin],
    ) -> Result<Self, EfsiError> {
        let grid = scene.build_grid();
        let bc = BoundarySet::new(&scene.boundaries, &grid);
        let mut pipeline = Pipeline::build(&scene, &options, &grid, &bc, plugins)?;
        let state = Self::initial_state(&scene, &grid, &bc, &mut pipeline)?;
        let scale = Self::velocity_scale(&scene, &grid, &bc, &state);
        Self::check_first_step(&scene, scale, scene_path)?;
        Ok(Simulation {
            scene,
            scene_path: scene_path.to_path_buf(),
            grid,
            bc,
            state,
            options,
            pipeline,
            previous: None,
            last_change: f64::INFINITY,
            velocity_scale: scale,
            checks: Vec::new(),
        })
    }

    /// The state the run starts from: the fields `pipeline` uses, its stages' own data, the
    /// scene's initial velocity, the ghosts filled, and the stages initialised
    /// ([`Pipeline::initialize`]).
    fn initial_state(
        scene: &Scene,
        grid: &Grid,
        bc: &BoundarySet,
        pipeline: &mut Pipeline,
    ) -> Result<State, EfsiError> {
        let mut state = State::new(
            grid,
            scene.fluid.density,
            scene.fluid.viscosity,
            pipeline.fields(),
        );
        pipeline.init_state(grid, &mut state);
        set_initial_velocity(&scene.initial_velocity, grid, &mut state);
        // A solid's initial velocity is blended in by the stage that owns the solid fraction
        // (the VOF stage's initialize).
        bc.fill_velocity3(
            grid,
            &mut state.u,
            &mut state.v,
            state.w.as_mut(),
            0.0,
            false,
        );
        bc.fill_scalar(grid, &mut state.rho, false);
        bc.fill_scalar(grid, &mut state.mu, false);
        pipeline.initialize(grid, bc, &mut state)?;
        Ok(state)
    }

    /// A velocity scale that bounds the first step when the fluid starts at rest: the largest
    /// moving-wall speed, the free-fall speed √(|g| L) over the domain's longest side, and the
    /// initial velocity's largest component. After the first step Δt follows the velocities
    /// inside the domain, which is what the advection scheme's stability depends on (a wall's
    /// tangential speed is carried by no face flux).
    fn velocity_scale(scene: &Scene, grid: &Grid, bc: &BoundarySet, state: &State) -> f64 {
        let mut scale = Self::wall_speed(bc);
        let lx = grid.x1() - grid.x0;
        let ly = grid.y1() - grid.y0;
        let lz = if grid.is_3d() {
            grid.nz as f64 * grid.dz
        } else {
            0.0
        };
        scale = scale.max((scene.gravity.norm() * lx.max(ly).max(lz)).sqrt());
        scale = scale.max(state.u.max_abs(crate::Stagger::XFace, grid.nx, grid.ny));
        scale = scale.max(state.v.max_abs(crate::Stagger::YFace, grid.nx, grid.ny));
        if let Some(w) = &state.w {
            scale = scale.max(w.max_abs(crate::Stagger::ZFace, grid.nx, grid.ny));
        }
        scale
    }

    /// Something must choose the first step: a fixed Δt, `time.dt_max`, or (with advection on)
    /// a velocity scale above zero.
    fn check_first_step(scene: &Scene, scale: f64, scene_path: &Path) -> Result<(), EfsiError> {
        if scene.time.fixed_dt.is_none()
            && scene.time.dt_max.is_none()
            && (!scene.physics.advection || scale == 0.0)
        {
            return Err(EfsiError::Config {
                path: scene_path.to_path_buf(),
                field: "time.dt_max".into(),
                message: if scene.physics.advection {
                    "nothing in this scene sets a velocity scale (no moving wall, gravity or initial velocity) \
                     from which to choose the first step: set time.dt_max or time.fixed_dt"
                        .into()
                } else {
                    "advection is off, so no CFL condition limits the step: set time.dt_max or time.fixed_dt".into()
                },
            });
        }
        Ok(())
    }

    /// Add a check of every step ([`StepCheck`]), after those already added.
    pub fn add_check(&mut self, check: Box<dyn StepCheck>) {
        self.checks.push(check);
    }

    /// The step checks, in the order added.
    pub fn checks(&self) -> &[Box<dyn StepCheck>] {
        &self.checks
    }

    pub(crate) fn checks_mut(&mut self) -> &mut [Box<dyn StepCheck>] {
        &mut self.checks
    }

    /// The largest moving-wall speed of `bc`.
    fn wall_speed(bc: &BoundarySet) -> f64 {
        bc.sides()
            .iter()
            .filter_map(|&s| bc.moving_wall_speed(s))
            .fold(0.0, |m: f64, v| m.max(v.abs()))
    }

    /// The scene's checked sections in their owners' types, from which the stages were built.
    pub fn options(&self) -> &Options {
        &self.options
    }

    /// The pipeline (for printing, timings and statistics).
    pub fn pipeline(&self) -> &Pipeline {
        &self.pipeline
    }

    pub(crate) fn pipeline_mut(&mut self) -> &mut Pipeline {
        &mut self.pipeline
    }

    /// The stages' [`Stage::restored`](crate::Stage::restored) with the state just put back.
    pub(crate) fn stages_restored(&mut self) {
        self.pipeline.restored(&mut self.state);
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

    /// The step the scene's limits allow next, before it is shortened to land on `until`, and
    /// what sets it: `time.fixed_dt`, else the smallest of the stages' stability limits (or
    /// the advective CFL limit) and `time.dt_max`, else the time left to `until`.
    pub fn step_limit(&self, until: f64) -> (f64, String) {
        let t = &self.scene.time;
        let remaining = until - self.state.t;
        let mut h = self.grid.dx.min(self.grid.dy);
        if self.grid.is_3d() {
            h = h.min(self.grid.dz);
        }
        if let Some(fixed) = t.fixed_dt {
            (fixed, "time.fixed_dt".to_string())
        } else {
            let stage = self
                .pipeline
                .limiting_stage(&self.grid, &self.state, t.cfl)
                .map(|(name, d)| {
                    (
                        d,
                        format!(
                            "the stability limit of the stage `{name}` (time.cfl = {}, {})",
                            crate::scene::num(t.cfl),
                            self.pipeline.limit_depends_on(name).unwrap_or_default()
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
        }
    }

    /// The Δt for the next step, at most `until − t` (to land on an output time or the end).
    pub fn next_dt(&self, until: f64) -> Result<f64, EfsiError> {
        let t = &self.scene.time;
        let remaining = until - self.state.t;
        let (dt, cause) = self.step_limit(until);
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
        self.step_from(dt, None)
    }

    /// [`step`](Self::step), told a copy of the velocity it starts from, `start` (the run
    /// loop's rollback copy, [`crate::Rollback::Step`]): a scene that stops at steady state
    /// then measures the step's change against it instead of a copy of its own.
    pub(crate) fn step_from(
        &mut self,
        dt: f64,
        start: Option<[Option<&Field>; 3]>,
    ) -> Result<(), EfsiError> {
        let steady = self.scene.time.steady.is_some();
        if steady && start.is_none() {
            let now = velocity(&self.state);
            match &mut self.previous {
                Some(before) => {
                    for (b, now) in before.iter_mut().zip(now) {
                        if let (Some(b), Some(now)) = (b, now) {
                            b.copy_from(now);
                        }
                    }
                }
                None => self.previous = Some(now.map(|f| f.cloned())),
            }
        }
        let ctx = StepContext {
            grid: &self.grid,
            bc: &self.bc,
            t: self.state.t,
            dt,
            step: self.state.step,
            start_velocity: start,
        };
        for c in &mut self.checks {
            c.before(&self.scene, &ctx, &self.state);
        }
        self.pipeline.run_step(&ctx, &mut self.state)?;
        self.state.t += dt;
        self.state.step += 1;
        self.state.dt_prev = dt;
        for c in &mut self.checks {
            c.after(&self.scene, &ctx, &self.state)?;
        }
        let before = match (start, &self.previous) {
            (Some(start), _) => Some(start),
            (None, Some([u, v, w])) => Some([u.as_ref(), v.as_ref(), w.as_ref()]),
            (None, None) => None,
        };
        if let Some(before) = before.filter(|_| steady) {
            // The largest change over the unknown faces of each component (max is exact, so
            // the order of the visit does not matter).
            let mut m = 0.0f64;
            let n = self.grid.n();
            for (a, (b, now)) in before.iter().zip(velocity(&self.state)).enumerate() {
                let (Some(b), Some(now)) = (b, now) else {
                    continue;
                };
                let faces = self.bc.normal_faces(a, n[a]);
                let at = [Stagger::XFace, Stagger::YFace, Stagger::ZFace][a];
                let region = Region::of(&self.grid, at).range(a, faces.lo, faces.hi);
                m = m.max(region.max(0.0, |line| {
                    let (x, y) = (now.at(&line, [0; 3]), b.at(&line, [0; 3]));
                    x.iter()
                        .zip(y)
                        .fold(0.0f64, |m, (x, y)| m.max((x - y).abs()))
                }));
            }
            self.last_change = m / dt;
        }
        Ok(())
    }

    /// Initialise every stage again from the current fields ([`Pipeline::initialize_stages`],
    /// without the initial projection): what a change of frame before the first step asks for
    /// (`efsi_stages::body_force::FrameAcceleration`).
    pub fn initialize_stages(&mut self) -> Result<(), EfsiError> {
        self.pipeline
            .initialize_stages(&self.grid, &self.bc, &mut self.state)
            .map_err(EfsiError::Stage)
    }

    /// Set the speed of the moving wall on `side` from the next step on (its profile and
    /// motion still multiply it; [`BoundarySet::set_wall_speed`]): an input that changes between
    /// steps, such as an FMU's lid speed. It bounds Δt while the fluid is at rest (the velocity
    /// scale of a first step); the step checks see it from the next step on (efsi-run's energy
    /// guard turns off for good once a step runs with a wall moving). Snapshots do not carry it: who sets it sets it again after a
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
        // A lid set moving in a fluid at rest bounds the first step as the scene's would.
        self.velocity_scale = self.velocity_scale.max(Self::wall_speed(&self.bc));
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

/// The velocity components of `state`: `u`, `v` and `w` (`None` in two dimensions).
fn velocity(state: &State) -> [Option<&Field>; 3] {
    [Some(&state.u), Some(&state.v), state.w.as_ref()]
}

impl Scene {
    /// The grid of this scene: [`Grid::new`] in two dimensions, [`Grid::new_3d`] for a
    /// Cartesian3D scene (whose validation guarantees `domain.z` and `grid.nz`).
    pub fn build_grid(&self) -> Grid {
        match (self.geometry, self.domain.z, self.grid.nz) {
            (Geometry::Cartesian3D, Some(z), Some(nz)) => Grid::new_3d(
                [self.grid.nx, self.grid.ny, nz],
                self.domain.x,
                self.domain.y,
                z,
            ),
            (Geometry::Cartesian3D, ..) => {
                panic!("a Cartesian3D scene without domain.z or grid.nz (validate it first)")
            }
            (g, ..) => Grid::new(g, self.grid.nx, self.grid.ny, self.domain.x, self.domain.y),
        }
    }
}

/// Set the fluid's initial velocity of the scene (`initial_velocity`) on every face, ghosts
/// included: a uniform one, or the velocity of the stream function
/// `ψ = A sin(k_x x) sin(k_y y)` (`SinSinStream`, planar only: [`Scene::validate`] refuses it in
/// axisymmetric geometry) as differences of ψ across each face, so that it is discretely
/// divergence-free.
fn set_initial_velocity(initial: &InitialVelocity, grid: &Grid, state: &mut State) {
    match initial {
        InitialVelocity::Rest => {}
        InitialVelocity::Uniform((a, b)) => {
            state.u.fill(*a);
            state.v.fill(*b);
            // In three dimensions the uniform velocity is in the x–y plane (w = 0).
        }
        InitialVelocity::SinSinStream {
            amplitude,
            wavenumbers,
        } => {
            let psi =
                |x: f64, y: f64| amplitude * (wavenumbers.0 * x).sin() * (wavenumbers.1 * y).sin();
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
}
