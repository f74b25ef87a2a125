//! The VOF stage: transport of the solid fraction and the two-material properties
//! (seed Eqs. 4–6, Fig. 1 step 5).
//!
//! `∂φ_s/∂t + V·∇φ_s = 0` is advanced with the geometric PLIC scheme of [`super::advect`] on
//! the step-average velocity `½(Vⁿ + Vⁿ⁺¹)` — both are divergence-free to the projection
//! tolerance, so their average is too — which makes the displacement of a body second-order in
//! time (exact in free fall; with `Vⁿ⁺¹` alone every step would add `½gΔt²` of error), then
//! `ρ = (1 − φ_s) ρ_f + φ_s ρ_s` and `μ = (1 − φ_s) μ_f + φ_s μ_s` (Eqs. 5–6), with the seed's
//! default `μ_s = μ_f ρ_s/ρ_f` unless the scene sets `solid.viscosity`.
//!
//! **Geometries.** One code path for planar, axisymmetric and three-dimensional grids: the
//! step-average velocity has one face field per axis (`u`, `v`, and `w` on a Cartesian3D
//! grid), the transport sweeps every axis ([`super::advect`]), the sides are closed (walls,
//! `Symmetry`, the axis) or periodic, z sides included, and an `Outflow` side is refused.
//! In three dimensions the stage serves a second fluid (a drop) and an elastic solid alike.
//!
//! **Several bodies** (`solids: [ … ]` with more than one entry): each body's fraction φ_k is
//! transported on its own window of the grid ([`super::bodies`]) by the same kernel and the
//! same sub-steps, bodies in the scene's order; the state's solid fraction is `Σ_k φ_k`, and
//! `ρ = (1 − Σ φ_k) ρ_f + Σ φ_k ρ_k`, `μ` likewise. Each body's initial velocity is blended into
//! the face velocities as for one body, the mixture's momentum over all materials of the face.
//! The stage's record ([`Stage::save`]: the windows) carries the bodies through snapshots and
//! checkpoints. After its initialization and every step the stage copies the windows into the
//! state ([`efsi_core::body_fractions`]), where the probes per body and the VTK array
//! `body_id` ([`BODY_ID`]) read them. A scene of one body (`solid:`, or a list of one) runs the one-field path above.
//!
//! **Initial state.** φ_s from the exact fractions of the scene's shape (the solid's initial
//! velocity is set with the other initial conditions, in [`efsi_core::Simulation::new`]).
//!
//! **Stability.** The split sweeps need a Courant number ≤ ½ per direction (Weymouth & Yue);
//! next to the axis an outward radial flux can empty up to twice `|u|Δt/Δr` of a cell. The
//! stage does not limit Δt for it (the scene's CFL number governs the step): when a step's
//! interface Courant number, `Δt·max(2|u_r|/Δr, |v|/Δz)` there and `Δt·max(|u|/Δx, |v|/Δy)`
//! elsewhere (`Δt·max(|u|/Δx, |v|/Δy, |w|/Δz)` in three dimensions), exceeds ½ — a CFL above
//! ½, an impact — the transport takes as many equal sub-steps as keep each sweep at most
//! 0.45, and refuses a sweep above ½. Sub-cycling rather
//! than capping Δt lets a scene with a solid run at its own CFL; the stability map
//! (`tests/src/paper/stability.rs`) holds those runs stable.
//!
//! **Postconditions.** `0 ≤ φ_s ≤ 1` exactly (tiny round-off excursions are clipped and the
//! clipped volume is bounded by 1e-12 of a cell, checked in debug builds); the phase volume
//! `Σ φ_s V` is conserved to round-off.

use super::advect::{self, VofAdvector, VofBoundaries, VofSide};
use super::bodies::BodyWindow;
use super::shapes::fill_fraction;
use crate::scratch::Scratch;
use crate::solid::Shape;
use efsi_core::body_fractions::{BodyFraction, BodyFractions};
use efsi_core::operators::minus;
use efsi_core::scene::{Boundary, Options, Side, Vector};
use efsi_core::{
    BoundarySet, Field, FieldId, Grid, OutputDecl, OutputKind, Phase, Region, Scene, Stage,
    StageError, StagePlugin, StageStats, Stagger, State, StepContext,
};
use efsi_linalg::par::{self, REDUCE_CHUNK};
use rayon::prelude::*;

/// The VOF stage plugin.
pub struct Vof;

impl StagePlugin for Vof {
    fn name(&self) -> &'static str {
        "vof"
    }
    fn phase(&self) -> Phase {
        Phase::Interface
    }
    fn reads(&self) -> &'static [FieldId] {
        &[
            FieldId::VelocityX,
            FieldId::VelocityY,
            FieldId::VelocityZ,
            FieldId::SolidFraction,
        ]
    }
    fn writes(&self) -> &'static [FieldId] {
        &[FieldId::SolidFraction, FieldId::Density, FieldId::Viscosity]
    }
    fn needed(&self, scene: &Scene, _options: &Options) -> bool {
        crate::second_material(scene)
    }
    /// Every geometry: the transport's sweeps, the mixing and the Courant check run over the
    /// grid's axes.
    fn supports(&self, _geometry: efsi_core::Geometry) -> bool {
        true
    }
    fn check_scene(
        &self,
        scene: &mut Scene,
        options: &mut Options,
    ) -> efsi_core::validate::Checked {
        crate::solid::check(scene, options)
    }
    /// The VTK array `body_id` of a scene of several bodies ([`BODY_ID`]).
    fn outputs(&self) -> &'static [OutputDecl] {
        &[BODY_ID]
    }
    fn build(
        &self,
        scene: &Scene,
        options: &Options,
        grid: &Grid,
        bc: &BoundarySet,
        shared: &mut efsi_core::Resources,
    ) -> Result<Box<dyn Stage>, String> {
        let bodies = crate::solid::bodies(options)?;
        let solid = &bodies.list[0].solid;
        let side = |s: Side| match bc.get(s) {
            Boundary::Periodic => Ok(VofSide::Periodic),
            Boundary::Outflow => Err(format!(
                "boundaries.{s}: a solid cannot leave through an Outflow side (the VOF step has closed and periodic sides)"
            )),
            _ => Ok(VofSide::Closed),
        };
        // The z sides of a two-dimensional grid do not exist (the advector ignores them).
        let z_side = |s: Side| {
            if grid.is_3d() {
                side(s)
            } else {
                Ok(VofSide::Closed)
            }
        };
        let bounds = VofBoundaries {
            x_lo: side(Side::XMin)?,
            x_hi: side(Side::XMax)?,
            y_lo: side(Side::YMin)?,
            y_hi: side(Side::YMax)?,
            z_lo: z_side(Side::ZMin)?,
            z_hi: z_side(Side::ZMax)?,
        };
        let advector = VofAdvector::lending(grid, bounds)?;
        let many = (bodies.list.len() > 1).then(|| Many {
            bodies: bodies
                .list
                .iter()
                .map(|b| ManyBody {
                    name: b.name.clone(),
                    rho: b.solid.density,
                    mu: b.solid.viscosity(&scene.fluid),
                    shape: b.solid.shape.clone(),
                    velocity: b.solid.velocity,
                })
                .collect(),
            windows: Vec::new(),
            stats: Vec::new(),
            bounds,
            grid: grid.clone(),
        });
        Ok(Box::new(VofStage {
            many,
            advector,
            scratch: Scratch::reserve(shared, advect::work_len(grid)),
            rho: (scene.fluid.density, solid.density),
            mu: (scene.fluid.viscosity, solid.viscosity(&scene.fluid)),
            shape: solid.shape.clone(),
            initial_velocity: solid.velocity,
            adv: (0..grid.dims()).map(|_| Field::zeros(grid)).collect(),
        }))
    }
}

struct VofStage {
    /// The bodies of a scene of several ([`super::bodies`]); `None` for one body, whose
    /// fraction is the state's and whose material is `rho`, `mu`, `shape`.
    many: Option<Many>,
    /// The advector, whose work arrays come from `scratch`.
    advector: VofAdvector,
    /// The pipeline's work vectors (the advector's [`advect::work_len`] values while the
    /// stage runs).
    scratch: Scratch,
    rho: (f64, f64),
    mu: (f64, f64),
    shape: Shape,
    /// The solid's initial velocity, until it is blended into the starting velocity (the
    /// first [`Stage::initialize`]).
    initial_velocity: Option<Vector>,
    /// The velocity at the end of the previous step (Vⁿ), then the step average: one face
    /// field per axis of the grid (u, v, and w in three dimensions).
    adv: Vec<Field>,
}

impl VofStage {
    /// ½(Vⁿ + Vⁿ⁺¹) in place of the stored Vⁿ — except in the `first` step, whose Vⁿ is the
    /// initial condition, not yet projected (a solid's initial velocity blended into the
    /// fluid's is not solenoidal at the interface): there Vⁿ⁺¹ alone.
    fn step_average(&mut self, state: &State, first: bool) {
        let w = if first { 0.0 } else { 0.5 };
        for (a, b) in self.adv.iter_mut().zip(velocity(state)) {
            let b = b.data();
            par::chunks(a.data_mut()).for_each(|o, a| {
                for (x, y) in a.iter_mut().zip(&b[o..]) {
                    *x = w * *x + (1.0 - w) * y;
                }
            });
        }
    }

    /// Transport the interface over the step in `n` equal sub-steps with the step-average
    /// velocity: `phi` itself for one body, every body's window for several.
    fn transport(
        &mut self,
        ctx: &StepContext,
        phi: &mut Field,
        n: u64,
    ) -> Result<super::AdvectStats, String> {
        let mut st = super::AdvectStats::default();
        let mut add = |s: super::AdvectStats| {
            st.cfl = st.cfl.max(s.cfl);
            st.max_clipped = st.max_clipped.max(s.max_clipped);
            st.clipped_volume += s.clipped_volume;
        };
        let dims = self.adv.len();
        let vel: [&Field; 3] = std::array::from_fn(|a| &self.adv[a.min(dims - 1)]);
        let dt = ctx.dt / n as f64;
        if let Some(many) = &mut self.many {
            // The bodies in parallel, each on its own window and work arrays; the statistics
            // gathered in the bodies' order.
            many.stats.resize_with(many.windows.len(), Vec::new);
            let parts = many.windows.par_iter_mut().zip(many.stats.par_iter_mut());
            par::try_each(parts, |_, (w, stats)| {
                stats.clear();
                for k in 0..n {
                    stats.push(w.step(ctx.grid, &vel[..dims], dt, ctx.step * n + k)?);
                }
                Ok::<(), String>(())
            })?;
            many.stats.iter().flatten().copied().for_each(&mut add);
        } else {
            let mut pool = self.scratch.lock();
            for k in 0..n {
                let s = self.advector.step_in(
                    &mut pool,
                    ctx.grid,
                    phi,
                    &vel[..dims],
                    dt,
                    ctx.step * n + k,
                );
                add(s);
            }
        }
        Ok(st)
    }
    /// The solid's initial velocity V_s: every face gets the momentum-weighted mixture
    /// (φ_f ρ_s V_s + (1 − φ_f) ρ_f V_fluid) / (φ_f ρ_s + (1 − φ_f) ρ_f), φ_f the average
    /// fraction of its two cells — the velocity of the face's mixture — so a heavy body's
    /// interface faces move with it. The initial projection (`Pipeline::initialize`) then
    /// removes the divergence this leaves at the interface. Once, before the first step.
    fn blend_initial_velocity(
        &self,
        grid: &Grid,
        bc: &BoundarySet,
        state: &mut State,
        solid_velocity: Vector,
    ) {
        let mut phi = Field::zeros(grid);
        fill_fraction(grid, &self.shape, &mut phi);
        bc.fill_scalar(grid, &mut phi, false);
        let (rf, rs) = self.rho;
        let blend = |f: f64, vs: f64, vf: f64| {
            let (ms, mf) = (f * rs, (1.0 - f) * rf);
            if ms + mf > 0.0 {
                (ms * vs + mf * vf) / (ms + mf)
            } else {
                vf
            }
        };
        let faces = [Stagger::XFace, Stagger::YFace, Stagger::ZFace];
        let components = [Some(&mut state.u), Some(&mut state.v), state.w.as_mut()];
        for (a, (vel, solid)) in components
            .into_iter()
            .zip(solid_velocity.xyz())
            .enumerate()
            .filter_map(|(a, (vel, s))| vel.map(|vel| (a, (vel, s))))
        {
            Region::of(grid, faces[a]).for_each(vel, |l, vel| {
                // φ_f: the face average of the fractions of the face's two cells.
                let (lo, hi) = (phi.at(&l, minus(a)), phi.at(&l, [0; 3]));
                for (n, v) in vel.iter_mut().enumerate() {
                    *v = blend(0.5 * (lo[n] + hi[n]), solid, *v);
                }
            });
        }
        let w = state.w.as_mut();
        bc.fill_velocity3(grid, &mut state.u, &mut state.v, w, 0.0, false);
    }

    /// [`Stage::initialize`] for several bodies: their windows, the blended initial velocity,
    /// `Σ φ_k`, ρ and μ.
    fn initialize_many(
        &mut self,
        many: &mut Many,
        grid: &Grid,
        bc: &BoundarySet,
        state: &mut State,
    ) -> Result<(), StageError> {
        let full = many.place(grid)?;
        if self.initial_velocity.take().is_some()
            || many.bodies.iter().any(|b| b.velocity.is_some())
        {
            many.blend_initial_velocity(grid, bc, state, self.rho.0, full);
            for b in &mut many.bodies {
                b.velocity = None;
            }
        }
        let mut phi = state.phi.take().ok_or_else(missing)?;
        many.mix(
            &self.advector,
            (self.rho.0, self.mu.0),
            &mut phi,
            &mut state.rho,
            &mut state.mu,
        );
        state.phi = Some(phi);
        many.publish(state);
        self.keep_velocity(state);
        Ok(())
    }

    /// Keep the state's velocity (Vⁿ for the next step's average).
    fn keep_velocity(&mut self, state: &State) {
        for (a, b) in self.adv.iter_mut().zip(velocity(state)) {
            a.copy_from(b);
        }
    }

    /// ρ and μ from φ (seed Eqs. 5–6), interior and ghosts alike.
    fn mix(&self, phi: &Field, rho: &mut Field, mu: &mut Field) {
        let (rf, rs) = self.rho;
        let (mf, ms) = self.mu;
        let phi = phi.data();
        par::rows((rho.data_mut(), mu.data_mut()), REDUCE_CHUNK).for_each(|c, (r, m)| {
            let o = c * REDUCE_CHUNK;
            for ((r, m), f) in r.iter_mut().zip(m).zip(&phi[o..]) {
                *r = (1.0 - f) * rf + f * rs;
                *m = (1.0 - f) * mf + f * ms;
            }
        });
    }
}

/// The bodies of a scene of several, each with its fraction on its window.
struct Many {
    bodies: Vec<ManyBody>,
    /// One per body, in the scene's order (made by [`Stage::initialize`]).
    windows: Vec<BodyWindow>,
    /// Each body's statistics of its last step's sub-steps (reused).
    stats: Vec<Vec<super::AdvectStats>>,
    /// The sides of the grid.
    bounds: VofBoundaries,
    /// The grid (the windows' parent).
    grid: Grid,
}

/// One body's name, material, shape and initial velocity.
struct ManyBody {
    name: String,
    rho: f64,
    mu: f64,
    shape: Shape,
    velocity: Option<Vector>,
}

impl Many {
    /// The bodies' windows from their shapes' exact fractions, and their fractions on the whole
    /// grid (for the initial velocity).
    fn place(&mut self, grid: &Grid) -> Result<Vec<Field>, StageError> {
        let mut full = Vec::new();
        self.windows.clear();
        for b in &self.bodies {
            let mut phi = Field::zeros(grid);
            fill_fraction(grid, &b.shape, &mut phi);
            self.windows
                .push(BodyWindow::around(grid, self.bounds, &phi).map_err(stage_error)?);
            full.push(phi);
        }
        Ok(full)
    }

    /// The bodies' initial velocities: every face gets the momentum-weighted mixture
    /// `(Σ φ_k ρ_k V_k + (1 − Σ φ_k) ρ_f V_fluid) / (Σ φ_k ρ_k + (1 − Σ φ_k) ρ_f)`, φ_k the
    /// average fraction of body k in the face's two cells (a body without a velocity moves
    /// with the fluid); the initial projection removes the divergence this leaves.
    fn blend_initial_velocity(
        &self,
        grid: &Grid,
        bc: &BoundarySet,
        state: &mut State,
        rho_f: f64,
        mut phis: Vec<Field>,
    ) {
        if self.bodies.iter().all(|b| b.velocity.is_none()) {
            return;
        }
        for phi in &mut phis {
            bc.fill_scalar(grid, phi, false);
        }
        let faces = [Stagger::XFace, Stagger::YFace, Stagger::ZFace];
        let components = [Some(&mut state.u), Some(&mut state.v), state.w.as_mut()];
        for (a, vel) in components
            .into_iter()
            .enumerate()
            .filter_map(|(a, vel)| vel.map(|vel| (a, vel)))
        {
            Region::of(grid, faces[a]).for_each(vel, |l, vel| {
                // The bodies with a fraction beside the line's faces, in order: the others'
                // terms are zeros, which leave the sums as they are.
                let f: Vec<(&ManyBody, &[f64], &[f64])> = self
                    .bodies
                    .iter()
                    .zip(&phis)
                    .map(|(b, p)| (b, p.at(&l, minus(a)), p.at(&l, [0; 3])))
                    .filter(|(_, lo, hi)| lo.iter().chain(*hi).any(|&x| x != 0.0))
                    .collect();
                for (n, v) in vel.iter_mut().enumerate() {
                    let (mut m, mut p, mut s) = (0.0, 0.0, 0.0);
                    for (b, lo, hi) in &f {
                        let phi = 0.5 * (lo[n] + hi[n]);
                        let vb = b.velocity.map_or(*v, |vb| vb.xyz()[a]);
                        s += phi;
                        m += phi * b.rho;
                        p += phi * b.rho * vb;
                    }
                    let mf = (1.0 - s).max(0.0) * rho_f;
                    if m + mf > 0.0 {
                        *v = (p + mf * *v) / (m + mf);
                    }
                }
            });
        }
        let w = state.w.as_mut();
        bc.fill_velocity3(grid, &mut state.u, &mut state.v, w, 0.0, false);
    }

    /// Each body's window and `φ_k` into the state's [`BodyFractions`] (for the probes and
    /// outputs per body).
    fn publish(&self, state: &mut State) {
        if let Some(all) = state.resources.get_mut::<BodyFractions>() {
            for (w, b) in self.windows.iter().zip(&mut all.bodies) {
                w.publish(b);
            }
        }
    }

    /// `Σ_k φ_k` into `phi` (interior; the caller fills the ghosts).
    fn total(&self, phi: &mut Field) {
        phi.fill(0.0);
        for w in &self.windows {
            w.add_into(phi, 1.0);
        }
    }

    /// `phi` set to the total `Σ φ_k` (ghosts filled by `advector`'s sides), then
    /// `ρ = (1 − Σ φ_k) ρ_f + Σ φ_k ρ_k` and `μ` likewise from it and the windows, bodies in
    /// order; the ghosts of ρ and μ by `advector`'s sides.
    fn mix(
        &self,
        advector: &VofAdvector,
        (rf, mf): (f64, f64),
        phi: &mut Field,
        rho: &mut Field,
        mu: &mut Field,
    ) {
        self.total(phi);
        advector.fill_ghosts(phi);
        let phi = phi.data();
        par::rows((rho.data_mut(), mu.data_mut()), REDUCE_CHUNK).for_each(|c, (r, m)| {
            let o = c * REDUCE_CHUNK;
            for ((r, m), f) in r.iter_mut().zip(m).zip(&phi[o..]) {
                *r = (1.0 - f) * rf;
                *m = (1.0 - f) * mf;
            }
        });
        for (w, b) in self.windows.iter().zip(&self.bodies) {
            w.add_into(rho, b.rho);
            w.add_into(mu, b.mu);
        }
        advector.fill_ghosts(rho);
        advector.fill_ghosts(mu);
    }
}

fn stage_error(message: String) -> StageError {
    StageError {
        stage: "vof".into(),
        message,
    }
}

fn missing() -> StageError {
    StageError {
        stage: "vof".into(),
        message: "the solid fraction is not allocated".into(),
    }
}

impl Stage for VofStage {
    /// Several bodies: their fractions' copy in the state ([`BodyFractions`]), named, set by
    /// [`Stage::initialize`] and every step.
    fn init_state(&self, _grid: &Grid, state: &mut State) {
        if let Some(many) = &self.many {
            state.resources.insert(BodyFractions {
                bodies: many
                    .bodies
                    .iter()
                    .map(|b| BodyFraction::named(b.name.clone()))
                    .collect(),
            });
        }
    }

    fn initialize(
        &mut self,
        grid: &Grid,
        bc: &BoundarySet,
        state: &mut State,
    ) -> Result<(), StageError> {
        if let Some(mut many) = self.many.take() {
            let res = self.initialize_many(&mut many, grid, bc, state);
            self.many = Some(many);
            return res;
        }
        if let Some(velocity) = self.initial_velocity.take() {
            self.blend_initial_velocity(grid, bc, state, velocity);
        }
        let phi = state.phi.as_mut().ok_or_else(missing)?;
        fill_fraction(grid, &self.shape, phi);
        self.advector.fill_ghosts(phi);
        let phi = state.phi.take().ok_or_else(missing)?;
        self.mix(&phi, &mut state.rho, &mut state.mu);
        state.phi = Some(phi);
        self.keep_velocity(state);
        Ok(())
    }

    // Nothing saved: the end-of-step velocity Vⁿ kept for the next step's average is, between
    // steps, the state's velocity (this stage is the last and writes no velocity), which a
    // snapshot holds already; `restored` takes it back from there (1.1 MB less in every
    // snapshot at 256²).

    /// One body: nothing. Several: the bodies' windows, each its extent and values
    /// ([`BodyWindow::save_into`]), in the scene's order.
    fn save(&self) -> Vec<f64> {
        let mut out = Vec::new();
        self.save_into(&mut out);
        out
    }

    fn save_into(&self, out: &mut Vec<f64>) {
        out.clear();
        if let Some(many) = &self.many {
            for w in &many.windows {
                w.save_into(out);
            }
        }
    }

    /// Several bodies: their windows ([`Self::save`]). One body: nothing, or the previous
    /// velocity (padded u, then v, then w) of a checkpoint written before it was taken from the
    /// state, which is the same and is taken again in `restored`.
    fn restore(&mut self, data: &[f64]) -> Result<(), String> {
        if let Some(many) = &mut self.many {
            many.windows =
                super::bodies::windows_of(&many.grid, many.bounds, many.bodies.len(), data)?;
            return Ok(());
        }
        let n: usize = self.adv.iter().map(|f| f.data().len()).sum();
        if !data.is_empty() && data.len() != n {
            return Err(format!(
                "expected nothing or {n} values (the previous velocity on this grid), got {}",
                data.len()
            ));
        }
        Ok(())
    }

    /// Vⁿ is the restored state's velocity; the bodies' fractions are published again from the
    /// restored windows (a checkpoint does not carry the state's copy).
    fn restored(&mut self, state: &mut State) {
        self.keep_velocity(state);
        if let Some(many) = &self.many {
            many.publish(state);
        }
    }

    fn run(&mut self, ctx: &StepContext, state: &mut State) -> Result<StageStats, StageError> {
        let mut phi = state.phi.take().ok_or_else(missing)?;
        self.step_average(state, ctx.step == 0);
        // The step was chosen for the velocity at its start; the velocity it ends with (an
        // impact, a release) can be faster. Sub-cycle the transport with the same velocity so
        // each sweep keeps its Courant number ≤ 0.5 (one sub-step, and the same bits, otherwise).
        let courant = courant_rate(ctx.grid, &self.adv) * ctx.dt;
        let n = if courant > 0.5 {
            (courant / 0.45).ceil() as u64
        } else {
            1
        };
        if n > MAX_SUBSTEPS {
            state.phi = Some(phi);
            return Err(StageError {
                stage: "vof".into(),
                message: format!(
                    "the interface's Courant number is {courant:.3} (Δt = {:.3e}), more than {MAX_SUBSTEPS} sub-steps of 0.45; the velocity is growing without bound — lower time.cfl or time.dt_max",
                    ctx.dt
                ),
            });
        }
        let st = match self.transport(ctx, &mut phi, n) {
            Ok(st) => st,
            Err(e) => {
                state.phi = Some(phi);
                return Err(stage_error(e));
            }
        };
        self.keep_velocity(state);
        if let Some(many) = &self.many {
            many.mix(
                &self.advector,
                (self.rho.0, self.mu.0),
                &mut phi,
                &mut state.rho,
                &mut state.mu,
            );
            many.publish(state);
        } else {
            self.advector.fill_ghosts(&mut phi);
            self.mix(&phi, &mut state.rho, &mut state.mu);
        }
        state.phi = Some(phi);
        if st.cfl > 0.5 + 1e-9 {
            return Err(StageError {
                stage: "vof".into(),
                message: format!(
                    "Courant number {:.3} of the interface sweep exceeds 0.5 (Δt = {:.3e}); lower time.cfl or time.dt_max",
                    st.cfl, ctx.dt
                ),
            });
        }
        // Round-off overshoots, and the projection residual the last sweep takes back (≤ 1e-8
        // of a cell), are clipped and their volume returned; more would be a scheme failure.
        debug_assert!(
            st.max_clipped <= 1e-8,
            "VOF clipped {:e} of a cell",
            st.max_clipped
        );
        Ok(StageStats::default())
    }
}

/// The smallest fraction of a body that names a cell in `body_id` (the probes' threshold of a
/// cell holding solid, `efsi_run::probes::PIECE_PHI_MIN`).
pub const BODY_ID_MIN: f64 = 1e-3;

/// The VTK array `body_id` of a scene of several bodies: in each cell the number (1, 2, … in
/// the scene's order of `solids`) of the body holding the largest fraction of it, among those
/// holding more than [`BODY_ID_MIN`]; 0 where none does. One array whatever the number of
/// bodies (a fraction array per body would grow the files with the grid times the bodies):
/// with `solid_fraction` (`Σ_k φ_k`) it draws each body's interface (`efsi plot` colours them)
/// and thresholds each body in ParaView. Absent from a scene of one body.
pub const BODY_ID: OutputDecl = OutputDecl {
    name: "body_id",
    meaning: "the body holding the largest fraction of the cell, numbered 1, 2, … in the order of the scene's `solids` (0: no body holds more than 1e-3 of the cell); present with several bodies",
    unit: "1",
    kind: OutputKind::Array {
        components: |_| vec!["k"],
        values: body_id,
    },
};

/// [`BODY_ID`]'s values, cell-major in VTK's order (x fastest); `None` without the bodies'
/// fractions (a scene of one body).
fn body_id(grid: &Grid, state: &State) -> Option<Vec<f64>> {
    let all = state.resources.get::<BodyFractions>()?;
    let [nx, ny, nz] = grid.n().map(|n| n as isize);
    let mut out = Vec::with_capacity(grid.cells());
    for k in 0..nz {
        for j in 0..ny {
            for i in 0..nx {
                out.push(all.id_at([i, j, k], BODY_ID_MIN) as f64);
            }
        }
    }
    Some(out)
}

/// Sub-steps the interface transport may take in one time step before the stage gives up.
const MAX_SUBSTEPS: u64 = 64;

/// The state's face velocities, one per axis of the grid: u, v, and w in three dimensions.
fn velocity(state: &State) -> impl Iterator<Item = &Field> {
    [&state.u, &state.v].into_iter().chain(state.w.as_ref())
}

/// The interface sweep's Courant number per unit Δt, in its flux form: the largest face volume
/// flux over its upwind cell's volume, `|u| r_face / (r_upwind dx)` on x-faces (up to twice
/// `|u|/dx` next to the axis), `|v|/dy` on y-faces and `|w|/dz` on z-faces.
fn courant_rate(grid: &Grid, vel: &[Field]) -> f64 {
    let m = &grid.metric;
    let rate_u = Region::of(grid, Stagger::XFace).max(0.0, |l| {
        let u = vel[0].at(&l, [0; 3]);
        let mut rate = 0.0f64;
        for (n, [i, _, _]) in l.indices().enumerate() {
            let a = u[n];
            let up = if a > 0.0 { i - 1 } else { i };
            let rc = m.rc(up);
            let f = if rc > 0.0 { m.rx(i) / rc } else { 1.0 };
            rate = rate.max(f.max(1.0) * a.abs());
        }
        rate
    });
    let h = grid.h();
    let faces = [Stagger::XFace, Stagger::YFace, Stagger::ZFace];
    (1..vel.len()).fold(rate_u / grid.dx, |rate, a| {
        let most = Region::of(grid, faces[a]).max(0.0, |l| {
            vel[a]
                .at(&l, [0; 3])
                .iter()
                .fold(0.0f64, |r, v| r.max(v.abs()))
        });
        rate.max(most / h[a])
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_courant_rate_counts_every_axis_of_the_grid() {
        // 4 × 4 × 8 cells of 0.25 × 0.25 × 0.125: |u| = 1, |v| = 2 and |w| = 0.5 at one face
        // each give 4, 8 and 4 per unit time; then w = 1.5 at another gives 12.
        let g = Grid::new_3d([4, 4, 8], (0.0, 1.0), (0.0, 1.0), (0.0, 1.0));
        let mut vel: Vec<Field> = (0..3).map(|_| Field::zeros(&g)).collect();
        vel[0][[2, 1, 3]] = -1.0;
        vel[1][[1, 2, 5]] = 2.0;
        vel[2][[3, 3, 4]] = 0.5;
        assert_eq!(courant_rate(&g, &vel), 8.0);
        vel[2][[0, 2, 7]] = -1.5;
        assert_eq!(courant_rate(&g, &vel), 12.0);
        // A z-face velocity outside the interior (a ghost) does not count.
        vel[2][[0, 2, 10]] = 100.0;
        assert_eq!(courant_rate(&g, &vel), 12.0);
        // Two dimensions: the x and y faces only.
        let g = Grid::new(efsi_core::Geometry::Planar, 4, 8, (0.0, 1.0), (0.0, 1.0));
        let mut vel: Vec<Field> = (0..2).map(|_| Field::zeros(&g)).collect();
        vel[0][(1, 1)] = 1.0;
        vel[1][(2, 3)] = 0.25;
        assert_eq!(courant_rate(&g, &vel), 4.0);
    }
}
