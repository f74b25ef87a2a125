//! Body force: `V* ← V* + Δt g` (the gravity term of seed Eq. 11).
//!
//! Gravity is a uniform acceleration, so the step is exact; it runs after advection, and the
//! projection removes its gradient part (a hydrostatic pressure) where the density is uniform.
//! In axisymmetric geometry only the axial component is allowed (the scene checks it).

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

impl Stage for BodyForceStage {
    fn run(&mut self, ctx: &StepContext, state: &mut State) -> Result<StageStats, StageError> {
        let grid = ctx.grid;
        let ux = ctx.bc.normal_faces(0, grid.nx);
        let vy = ctx.bc.normal_faces(1, grid.ny);
        let (gx, gy) = (self.g.0 * ctx.dt, self.g.1 * ctx.dt);
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
