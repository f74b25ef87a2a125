//! Body force: `V* ← V* + Δt (g − a)` (the gravity term of seed Eq. 11, in a frame that may
//! accelerate).
//!
//! `g` is the scene's gravity and `a` the acceleration of the grid's frame with respect to an
//! inertial one ([`State::frame_acceleration`], zero unless set between steps, e.g. by the
//! FMU's base-acceleration input): in the frame of a shaking table the fictitious
//! (d'Alembert) force `−a` adds to gravity. The acceleration is uniform, so the step is exact;
//! it runs after advection, and the projection removes its gradient part (a hydrostatic
//! pressure) where the density is uniform. In axisymmetric geometry only the axial component
//! is allowed (the scene and [`efsi_core::Simulation::set_frame_acceleration`] check it).
//!
//! **Step limit.** An explicit body force must not move the fluid more than a fraction of a cell
//! per step: with the convective rate `C = max(|u|/dx + |v|/dy)`, the stage allows
//! `Δt ≤ CFL · 2 / (C + √(C² + 4|g − a|/h))` (Kang, Fedkiw & Liu 2000), which equals the
//! advective limit when `g − a = 0` and `CFL·√(h/|g − a|)` from rest.

use efsi_core::schedule::VELOCITY;
use efsi_core::{
    BoundarySet, FieldId, Grid, Phase, Scene, Stage, StageError, StagePlugin, StageStats, State,
    StepContext,
};

/// The body-force stage plugin.
pub struct BodyForce;

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
    fn needed(&self, scene: &Scene) -> bool {
        scene.gravity != (0.0, 0.0)
    }
    fn build(
        &self,
        scene: &Scene,
        _grid: &Grid,
        _bc: &BoundarySet,
    ) -> Result<Box<dyn Stage>, String> {
        Ok(Box::new(BodyForceStage { g: scene.gravity }))
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
        let mut c = 0.0f64;
        for j in 0..grid.ny as isize {
            for i in 0..grid.nx as isize {
                let uu = state.u[(i, j)].abs().max(state.u[(i + 1, j)].abs());
                let vv = state.v[(i, j)].abs().max(state.v[(i, j + 1)].abs());
                c = c.max(uu / grid.dx + vv / grid.dy);
            }
        }
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
        for j in 0..grid.ny as isize {
            for i in ux.lo..ux.hi {
                state.u[(i, j)] += gx;
            }
        }
        for j in vy.lo..vy.hi {
            for i in 0..grid.nx as isize {
                state.v[(i, j)] += gy;
            }
        }
        Ok(StageStats::default())
    }
}
