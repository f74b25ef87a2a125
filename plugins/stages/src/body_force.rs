//! Body force: `V* ← V* + Δt (g − a)` (the gravity term of seed Eq. 11, in a frame that may
//! accelerate).
//!
//! `g` is the scene's gravity and `a` the acceleration of the grid's frame with respect to an
//! inertial one ([`State::frame_acceleration`], zero unless set between steps, e.g. by the
//! FMU's base-acceleration input): in the frame of a shaking table the fictitious
//! (d'Alembert) force `−a` adds to gravity. The acceleration is uniform, so the step is exact;
//! it runs after advection. Its gradient part (a hydrostatic pressure where the density is
//! layered) is balanced by the last step's pressure, which the incremental projection's
//! predictor subtracts right after this stage (`projection`), so the viscous step never sees
//! it; in the seed's non-incremental scheme the projection removes it after the viscous step. In axisymmetric geometry only the axial component
//! is allowed (the scene and [`FrameAcceleration::set_frame_acceleration`] check it).
//!
//! **Step limit.** An explicit body force must not move the fluid more than a fraction of a cell
//! per step: with the convective rate `C = max(|u|/dx + |v|/dy)`, the stage allows
//! `Δt ≤ CFL · 2 / (C + √(C² + 4|g − a|/h))` (Kang, Fedkiw & Liu 2000), which equals the
//! advective limit when `g − a = 0` and `CFL·√(h/|g − a|)` from rest.

use efsi_core::scene::Options;
use efsi_core::schedule::VELOCITY;
use efsi_core::{
    BoundarySet, EfsiError, FieldId, Grid, Phase, Region, Scene, Simulation, Stage, StageError,
    StagePlugin, StageStats, Stagger, State, StepContext,
};

/// The body-force stage plugin.
pub struct BodyForce;

/// The acceleration of a simulation's frame, the body force's input.
pub trait FrameAcceleration {
    /// Set the acceleration of the grid's frame with respect to an inertial one, from the next
    /// step on ([`State::frame_acceleration`]: the body force becomes `gravity − a`, so a
    /// table accelerating upwards at `a` acts like gravity stronger by `a`). Set before the
    /// first step, the stages start again from the new frame
    /// ([`Simulation::initialize_stages`]), so a constant acceleration is exactly a change of
    /// gravity. Snapshots and checkpoints carry it. Refused — nothing changes — when the value
    /// is not finite, when it has a radial component in axisymmetric geometry, or when no
    /// body-force stage runs (the body force is scheduled only in scenes with gravity).
    fn set_frame_acceleration(&mut self, a: (f64, f64)) -> Result<(), EfsiError>;
}

impl FrameAcceleration for Simulation {
    fn set_frame_acceleration(&mut self, a: (f64, f64)) -> Result<(), EfsiError> {
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
        if !self.pipeline().has_phase(Phase::BodyForce) {
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
            self.initialize_stages()?;
        }
        Ok(())
    }
}

impl StagePlugin for BodyForce {
    fn name(&self) -> &'static str {
        "body_force"
    }
    fn phase(&self) -> Phase {
        Phase::BodyForce
    }
    fn reads(&self) -> &'static [FieldId] {
        &VELOCITY
    }
    fn writes(&self) -> &'static [FieldId] {
        &VELOCITY
    }
    fn needed(&self, scene: &Scene, _options: &Options) -> bool {
        scene.gravity != (0.0, 0.0)
    }
    fn build(
        &self,
        scene: &Scene,
        _options: &Options,
        _grid: &Grid,
        _bc: &BoundarySet,
        _shared: &mut efsi_core::Resources,
    ) -> Result<Box<dyn Stage>, String> {
        Ok(Box::new(BodyForceStage {
            g: scene.gravity.planar(),
        }))
    }
}

struct BodyForceStage {
    g: (f64, f64),
}

impl BodyForceStage {
    /// `g − a`: gravity in the (possibly accelerating) frame of the grid.
    fn effective(&self, state: &State) -> (f64, f64) {
        let a = state.frame_acceleration;
        (self.g.0 - a.0, self.g.1 - a.1)
    }
}

impl Stage for BodyForceStage {
    fn max_dt(&self, grid: &Grid, state: &State, cfl: f64) -> Option<f64> {
        let c = crate::ops::convective_rate(grid, &state.u, &state.v);
        let (gx, gy) = self.effective(state);
        let g = gx.hypot(gy) / grid.dx.min(grid.dy);
        Some(cfl * 2.0 / (c + (c * c + 4.0 * g).sqrt()))
    }

    fn run(&mut self, ctx: &StepContext, state: &mut State) -> Result<StageStats, StageError> {
        let grid = ctx.grid;
        let ux = ctx.bc.normal_faces(0, grid.nx);
        let vy = ctx.bc.normal_faces(1, grid.ny);
        let (gx, gy) = self.effective(state);
        let (gx, gy) = (gx * ctx.dt, gy * ctx.dt);
        // The unknown faces of each velocity component.
        Region::of(grid, Stagger::XFace)
            .range(0, ux.lo, ux.hi)
            .for_each(&mut state.u, |_, u| u.iter_mut().for_each(|u| *u += gx));
        Region::of(grid, Stagger::YFace)
            .range(1, vy.lo, vy.hi)
            .for_each(&mut state.v, |_, v| v.iter_mut().for_each(|v| *v += gy));
        Ok(StageStats::default())
    }
}
