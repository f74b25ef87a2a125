//! Body force: `V* ← V* + Δt (g − a)` (the gravity term of seed Eq. 11, in a frame that may
//! accelerate).
//!
//! `g` is the scene's gravity and `a` the acceleration of the grid's frame with respect to an
//! inertial one ([`State::frame_acceleration`], zero unless set between steps, e.g. by the
//! FMU's base-acceleration input): in the frame of a shaking table the fictitious
//! (d'Alembert) force `−a` adds to gravity. The acceleration is uniform, so the step is exact;
//! it runs after advection. In axisymmetric geometry only the axial component is allowed (the
//! scene and [`FrameAcceleration::set_frame_acceleration`] check it).
//!
//! **Hydrostatic part.** Where the density is layered, part of `ρ(g − a)` is a gradient that a
//! pressure balances, and the viscous step must not see it (at no-slip walls its implicit step
//! shears the increment into vorticity the projection cannot remove). In the incremental scheme
//! the last step's pressure balances it: the predictor subtracts it right after this stage
//! (`projection`). In the seed's non-incremental scheme (the default with an elastic solid) the
//! stage adds only the excess weight over the carrier fluid, `Δt (1 − ρ_f/ρ_face)(g − a)`, on
//! the components that take part in the split (`projection::hydrostatic`: every non-periodic
//! axis unless an Outflow side lies along it), with `ρ_f` the scene's fluid density and `ρ_face`
//! the projection's face density, and subtracts the carrier's hydrostatic pressure
//! `p_h = ρ_f (g − a)·(x − x_ref)` from the pressure, which the projection adds back after its
//! solve: during the step `p` holds the excess pressure, between steps the whole one. The
//! other components are added whole.
//!
//! On a three-dimensional grid `g` and `a` have three components and the stage adds
//! `Δt (g − a)_c` (times the excess factor on a split axis) to every unknown face of each
//! velocity component `c`, the same loop for every axis.
//!
//! **Step limit.** An explicit body force must not move the fluid more than a fraction of a cell
//! per step: with the convective rate `C = max(|u|/dx + |v|/dy (+ |w|/dz))`
//! ([`crate::advection::convective_rate`]) and `h` the smallest cell size, the stage allows
//! `Δt ≤ CFL · 2 / (C + √(C² + 4|g − a|/h))` (Kang, Fedkiw & Liu 2000), which equals the
//! advective limit when `g − a = 0` and `CFL·√(h/|g − a|)` from rest (the whole `g − a`, split or
//! not: a light body in a heavy fluid rises at it).

use crate::projection::hydrostatic::Hydrostatic;
use efsi_core::scene::Options;
use efsi_core::{
    BoundarySet, EfsiError, FieldId, Grid, Phase, Region, Scene, Simulation, Stage, StageError,
    StagePlugin, StageStats, Stagger, State, StepContext, operators,
};

/// The scene's gravity as three components (z = 0 in a two-dimensional scene).
fn gravity(scene: &Scene) -> [f64; 3] {
    scene.gravity.xyz()
}

/// The location of velocity component `c`.
const FACES: [Stagger; 3] = [Stagger::XFace, Stagger::YFace, Stagger::ZFace];

/// The body-force stage plugin.
pub struct BodyForce;

/// What the stage reads: the velocity and the density.
const READS: [FieldId; 4] = [
    FieldId::VelocityX,
    FieldId::VelocityY,
    FieldId::VelocityZ,
    FieldId::Density,
];

/// What the stage writes: the velocity and the pressure.
const WRITES: [FieldId; 4] = [
    FieldId::VelocityX,
    FieldId::VelocityY,
    FieldId::VelocityZ,
    FieldId::Pressure,
];

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
    /// Planar, axisymmetric and three-dimensional: one dimension-generic code path.
    fn supports(&self, _geometry: efsi_core::Geometry) -> bool {
        true
    }
    fn name(&self) -> &'static str {
        "body_force"
    }
    fn phase(&self) -> Phase {
        Phase::BodyForce
    }
    /// The density for the excess weight of the seed's scheme (module docs).
    fn reads(&self) -> &'static [FieldId] {
        &READS
    }
    /// The pressure: the carrier's hydrostatic part leaves it for the step (module docs).
    fn writes(&self) -> &'static [FieldId] {
        &WRITES
    }
    fn needed(&self, scene: &Scene, _options: &Options) -> bool {
        gravity(scene) != [0.0; 3]
    }
    fn build(
        &self,
        scene: &Scene,
        options: &Options,
        grid: &Grid,
        bc: &BoundarySet,
        shared: &mut efsi_core::Resources,
    ) -> Result<Box<dyn Stage>, String> {
        // Kept for the projection built after (`projection::Projector::new`), which adds back
        // what this stage takes from the pressure.
        let split = *shared.get_or_try_insert_with(|| {
            Ok::<_, String>(Hydrostatic::of(scene, options, grid, bc))
        })?;
        Ok(Box::new(BodyForceStage {
            g: gravity(scene),
            split,
        }))
    }
}

struct BodyForceStage {
    g: [f64; 3],
    /// The split of gravity of the seed's scheme (module docs), if the scene makes one.
    split: Option<Hydrostatic>,
}

impl BodyForceStage {
    /// `g − a`: gravity in the (possibly accelerating) frame of the grid.
    fn effective(&self, state: &State) -> [f64; 3] {
        Hydrostatic::effective(self.g, state)
    }
}

impl Stage for BodyForceStage {
    fn max_dt(&self, grid: &Grid, state: &State, cfl: f64) -> Option<f64> {
        let (vel, dims) = crate::advection::velocity(grid, state);
        let c = crate::advection::convective_rate(grid, &vel[..dims]);
        let (e, h) = (self.effective(state), grid.h());
        let (e, h) = (&e[..dims], &h[..dims]);
        let g = e[1..].iter().fold(e[0], |s, x| s.hypot(*x))
            / h[1..].iter().fold(h[0], |s, x| s.min(*x));
        Some(cfl * 2.0 / (c + (c * c + 4.0 * g).sqrt()))
    }

    fn run(&mut self, ctx: &StepContext, state: &mut State) -> Result<StageStats, StageError> {
        let grid = ctx.grid;
        let n = grid.n();
        let g = self.effective(state);
        let State { u, v, w, rho, .. } = state;
        let rho = &*rho;
        let vel = [Some(u), Some(v), w.as_mut()];
        // The unknown faces of each velocity component.
        for (c, f) in vel.into_iter().enumerate().take(grid.dims()) {
            let f = f.expect("w on a three-dimensional grid");
            let r = ctx.bc.normal_faces(c, n[c]);
            let gc = g[c] * ctx.dt;
            let faces = Region::of(grid, FACES[c]).range(c, r.lo, r.hi);
            match self.split.filter(|s| s.splits(c)) {
                // The excess weight over the carrier, ρ_face as the projection's.
                Some(s) => {
                    let rf = s.density();
                    let mut below = [0; 3];
                    below[c] = -1;
                    faces.for_each(f, |line, f| {
                        let (ra, rb) = (rho.at(&line, [0; 3]), rho.at(&line, below));
                        for (t, f) in f.iter_mut().enumerate() {
                            *f += gc * (1.0 - rf / operators::face_density(ra[t], rb[t]));
                        }
                    });
                }
                None => faces.for_each(f, |_, f| f.iter_mut().for_each(|f| *f += gc)),
            }
        }
        // The carrier's hydrostatic pressure leaves the pressure until the projection.
        if let Some(s) = &self.split {
            s.add(grid, ctx.bc, g, &mut state.p, -1.0);
        }
        Ok(StageStats::default())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use efsi_core::scene::{Boundaries, Boundary};
    use efsi_core::schedule::StepContext;

    #[test]
    fn three_components_on_a_three_dimensional_grid() {
        let g = Grid::new_3d([4, 3, 5], (0.0, 1.0), (0.0, 0.6), (0.0, 2.0));
        let side = || Boundary::Periodic;
        let mut sides = Boundaries::planar(side(), side(), side(), side());
        sides.z_min = Some(side());
        sides.z_max = Some(side());
        let bc = BoundarySet::new(&sides, &g);
        let mut state = State::new(&g, 1.0, 1e-3, &Default::default());
        state.frame_acceleration = (0.5, 0.25);
        let mut stage = BodyForceStage {
            g: [1.0, -2.0, 3.0],
            split: None,
        };
        // From rest the limit is CFL·√(h/|g − a|), h the smallest cell (0.2).
        let e = (0.5f64 * 0.5 + 2.25 * 2.25 + 3.0 * 3.0).sqrt();
        let dt = stage.max_dt(&g, &state, 0.4).unwrap();
        assert!((dt - 0.4 * (0.2 / e).sqrt()).abs() < 1e-15, "Δt = {dt}");
        let ctx = StepContext {
            grid: &g,
            bc: &bc,
            t: 0.0,
            dt: 0.1,
            step: 0,
            start_velocity: None,
        };
        stage.run(&ctx, &mut state).unwrap();
        let w = state.w.as_ref().unwrap();
        let want = [0.5 * 0.1, -2.25 * 0.1, 3.0 * 0.1];
        for (c, f) in [&state.u, &state.v, w].into_iter().enumerate() {
            let faces = Region::of(&g, FACES[c]).range(c, 0, g.n()[c] as isize);
            for n in 0..f.data().len() {
                let i = f.index_of(n);
                let inside = (0..3).all(|a| (faces.lo()[a]..faces.hi()[a]).contains(&i[a]));
                let v = if inside { want[c] } else { 0.0 };
                assert_eq!(f.data()[n], v, "component {c} at {i:?}");
            }
        }
    }
}
