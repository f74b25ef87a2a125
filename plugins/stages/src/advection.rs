//! Explicit advection of momentum: `V* = Vⁿ − Δt (V·∇V)` (seed Eq. 11, there with forward Euler;
//! here the two-stage SSP Runge–Kutta method in time).
//!
//! **Scheme.** Conservative finite-volume form on the staggered control volumes, transporting
//! the control volume's mass `m = ρ_f` (the face density, the average of its two cells) and
//! momentum `m u` with the *same* mass fluxes: `∂m/∂t = −∇·(m a)`, `∂(m u)/∂t = −∇·(m a ⊗ u)`,
//! then `u = (m u)/m`. With uniform density this is the usual `∂u/∂t = −∇·(u ⊗ u)`; at a
//! fluid/solid interface with a density ratio of 1000 it keeps the light fluid's velocity from
//! being advected at full weight into cells that carry mostly solid mass — velocity advection
//! alone makes a dense falling body lose momentum at first order in h, the mass-consistent
//! form does not (Rudman 1998; Raessi & Pitsch 2012). Each face flux is
//! `a·m̃·q` with `a` the advecting velocity interpolated linearly to the face of the control
//! volume and `m̃`, `q` the mass and the advected component reconstructed there by a
//! **TVD upwind-biased MUSCL interpolation with the van Leer limiter** (van Leer 1974):
//! `q = q_C + ½ ψ(r)(q_D − q_C)`, `r = (q_C − q_U)/(q_D − q_C)`, `ψ(r) = (r + |r|)/(1 + |r|)`,
//! where U, C, D are the upwind-upwind, upwind and downwind values. Second-order in space where
//! the field is smooth, first-order and bounded (no new extrema) at steep gradients. In time,
//! SSP-RK2 (Heun: two Euler stages of the mass and momentum, averaged; Shu & Osher 1988), which
//! keeps each Euler stage's TVD bound and is second-order.
//!
//! **Axisymmetric form.** With x = r, `(u·∇u)_r = (1/r)∂(r u u)/∂r + ∂(w u)/∂z` and
//! `(u·∇u)_z = (1/r)∂(r u w)/∂r + ∂(w w)/∂z` (no swirl, so no `u_θ²/r` term): fluxes through
//! r-faces carry the radius at the flux location and the balance is divided by the radius of the
//! control-volume centre — the metric factors of [`efsi_core::grid`], so one code path serves
//! both geometries.
//!
//! **Stability.** Each Euler stage with a TVD limiter of `ψ ≤ 2` is TVD for
//! `Δt (|u|/dx + |v|/dy) ≤ ½`; the stage limits Δt to `CFL · min(1 / (|u|/dx + |v|/dy))` with
//! the scene's CFL (default 0.4). Beyond the bound the scheme is not guaranteed TVD; the
//! cavity scenes run at CFL 1.0. With the `WholeStep` predictor (below) the steady state does
//! not move with the CFL (`tests/tests/cavity.rs`,
//! `the_cavity_steady_state_does_not_depend_on_the_time_step`), so the CFL buys time accuracy
//! only.
//!
//! **Where the second stage looks** (`numerics.advection.predictor`). Heun's second stage
//! evaluates the tendency at the first stage's velocity `V¹ = Vⁿ + Δt A(Vⁿ)`, a prediction
//! from advection alone. Split from the viscous and pressure steps, that makes the discrete
//! steady state depend on Δt: at a steady state the other stages cancel advection, but the
//! stage returns `½Δt (A(V) + A(V + Δt A(V)))`, not `Δt A(V)` — an error ∝ Δt. With
//! `WholeStep` the second stage looks where the whole step is headed instead:
//! `V¹ = Vⁿ + Δt A(Vⁿ) + (Δt/Δtₙ₋₁)(Vⁿ − Y)`, with `Y` the velocity this stage left at the
//! previous step, so `(Vⁿ − Y)/Δtₙ₋₁` is what every other stage added then (pressure,
//! viscosity, body forces). The update is still `Vⁿ + ½Δt (A(Vⁿ) + A(V¹))`; only the point of
//! the second evaluation moves. At a steady state `V¹ = Vⁿ` and the update is exactly
//! `Δt A(Vⁿ)`, so the steady state is that of the spatial discretisation, at any Δt; in a
//! transient the second evaluation is a better estimate of the velocity at the step's end,
//! and the method stays second order. The first step, a step after a restore without the
//! history and a scene that sets `Advection` use `V¹` from advection alone (the classical
//! Heun stage). Default: `WholeStep` in a scene of one fluid, `Advection` in a scene with a
//! solid: there a face the interface crosses changes density between steps by up to the
//! density ratio, so the last step's increments predict the next one's poorly (a dense disk
//! falling through a fluid 1000 times lighter, `tests/tests/two_material.rs`, falls less
//! accurately and loses volume with `WholeStep`). The cost: two full-grid arrays kept from
//! step to step and in snapshots.
//!
//! **Three dimensions.** The same kernels serve a three-dimensional grid: three components,
//! each with fluxes along every axis, `w` on the z-faces, and the convective rate and its
//! limit counting `|w|/dz` (`Δt (|u|/dx + |v|/dy + |w|/dz) ≤ ½` per Euler stage).
//!
//! **Parallelism and memory.** The kernels run over the lines of grid regions, or bands of
//! them, in parallel, each writing its own entries, so results are bit-identical on any
//! number of threads. Each face flux is computed once (a band's lower edge twice): along the
//! lines' axis into a buffer of the line, along axis 1 into a buffer the band's next line
//! reads, along any further axis into a full-grid array. The stage uses [`work`]`(dims)`
//! full-grid arrays while it runs (5 in two dimensions, 9 in three: per component the
//! momentum tendency and the current stage's face masses; one mass tendency, each component's
//! in turn, whose masses and momenta advance as soon as its own tendencies are known; the
//! fluxes along the third axis) — taken from the pipeline's pool of work vectors (`scratch`),
//! which the later stages of the step reuse. The start-of-step velocity, which both Euler
//! stages read, is the run's copy of the step's start where it keeps one for putting a failed
//! step back (`StepContext::start_velocity`: the velocity as the stage finds it, bit for bit,
//! as the advection is the step's first stage to write it); without such a copy the stage
//! makes its own, one array per component, kept from then on. It keeps from one step to the
//! next only the `WholeStep` predictor's history, one array per component.

mod kernels;

use crate::scratch::Scratch;
use efsi_core::scene::options::StageOptions;
use efsi_core::scene::{Options, OptionsDecl};
use efsi_core::schedule::VELOCITY;
use efsi_core::{
    BoundarySet, Field, FieldId, Grid, Phase, Region, Scene, Stage, StageError, StagePlugin,
    StageStats, State, StepContext,
};
use efsi_linalg::par::copy;
use kernels::{Euler, FACES, Work};
use serde::{Deserialize, Serialize};

pub(crate) use kernels::face_value;
pub use kernels::{convective_rate, work};

/// The advection's options (`numerics.advection`).
#[derive(Clone, Debug, Default, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct AdvectionOptions {
    /// Where the second Runge–Kutta stage evaluates the advection (module docs). Default
    /// (unset): `WholeStep` in a scene of one fluid, `Advection` in a scene with a solid.
    #[serde(default)]
    pub predictor: Option<AdvectionPredictor>,
}

/// The velocity at which Heun's second stage evaluates the advection.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum AdvectionPredictor {
    /// The first stage's velocity, advection alone (the classical Heun stage; the steady
    /// state carries an error ∝ Δt).
    Advection,
    /// The first stage's velocity plus the last step's increments of every other stage,
    /// rescaled to this Δt: the steady state does not depend on Δt.
    WholeStep,
}

impl StageOptions for AdvectionOptions {
    const SECTION: &'static str = "advection";

    fn validate(&self, _scene: &Scene) -> Result<(), (&'static str, String)> {
        Ok(())
    }

    fn resolve(&mut self, scene: &Scene, _options: &Options) {
        self.predictor.get_or_insert(default_predictor(scene));
    }
}

/// The predictor of a scene that sets none: `WholeStep` with one fluid, `Advection` with a
/// solid (a `solid` section).
fn default_predictor(scene: &Scene) -> AdvectionPredictor {
    if crate::second_material(scene) {
        AdvectionPredictor::Advection
    } else {
        AdvectionPredictor::WholeStep
    }
}

/// Whether `scene`'s advection predicts its second stage with the whole step's increments.
fn whole_step(scene: &Scene, options: &Options) -> Result<bool, String> {
    let o: &AdvectionOptions = options.section()?;
    Ok(o.predictor.unwrap_or(default_predictor(scene)) == AdvectionPredictor::WholeStep)
}

/// The advection stage plugin.
pub struct Advection;

impl StagePlugin for Advection {
    /// Planar, axisymmetric and three-dimensional: one dimension-generic code path.
    fn supports(&self, _geometry: efsi_core::Geometry) -> bool {
        true
    }
    fn name(&self) -> &'static str {
        "advection"
    }
    fn phase(&self) -> Phase {
        Phase::Advection
    }
    fn reads(&self) -> &'static [FieldId] {
        &[
            FieldId::VelocityX,
            FieldId::VelocityY,
            FieldId::VelocityZ,
            FieldId::Density,
        ]
    }
    fn writes(&self) -> &'static [FieldId] {
        &VELOCITY
    }
    fn needed(&self, scene: &Scene, _options: &Options) -> bool {
        scene.physics.advection
    }
    fn options(&self) -> Option<OptionsDecl> {
        Some(OptionsDecl::of::<AdvectionOptions>())
    }
    fn build(
        &self,
        scene: &Scene,
        options: &Options,
        grid: &Grid,
        _bc: &BoundarySet,
        shared: &mut efsi_core::Resources,
    ) -> Result<Box<dyn Stage>, String> {
        let history = whole_step(scene, options)?.then(|| History::new(grid));
        Ok(Box::new(AdvectionStage {
            history,
            scratch: Scratch::reserve(shared, work_len(grid)),
            start: Vec::new(),
        }))
    }
}

/// Values of the work arrays [`advance`] needs on `grid` ([`work`] padded full-grid arrays).
pub fn work_len(grid: &Grid) -> usize {
    work(grid.dims()) * grid.padded().iter().product::<usize>()
}

/// Values of the copy of the start-of-step velocity [`advance`] makes where the caller keeps
/// none ([`Start::Copy`]): one padded array per component.
pub fn start_len(grid: &Grid) -> usize {
    grid.dims() * grid.padded().iter().product::<usize>()
}

/// The velocity at the start of the step, which both Euler stages read.
pub enum Start<'a> {
    /// The caller's copy (one field per component, bit for bit the velocity given to
    /// [`advance`], ghosts included).
    Kept(&'a [&'a Field]),
    /// No copy: [`advance`] makes one in these [`start_len`] values.
    Copy(&'a mut [f64]),
}

/// What the `WholeStep` predictor keeps from step to step: the velocity the stage left at the
/// previous step (`Y` in the module docs, one array per component, padded like the fields) and
/// that step's Δt (0: no history yet).
#[derive(Clone, Debug)]
pub struct History {
    vel: Vec<Vec<f64>>,
    dt: f64,
}

impl History {
    /// No history yet, for the velocity components of `grid`.
    pub fn new(grid: &Grid) -> Self {
        let len = grid.padded().iter().product();
        History {
            vel: (0..grid.dims()).map(|_| vec![0.0; len]).collect(),
            dt: 0.0,
        }
    }

    /// The number of values of the saved history: Δt and the arrays.
    fn saved_len(&self) -> usize {
        1 + self.vel.iter().map(Vec::len).sum::<usize>()
    }
}

/// The unknown faces of each velocity component of `grid` under `bc`: the control volumes
/// the advection updates.
fn control_volumes(grid: &Grid, bc: &BoundarySet) -> [Region; 3] {
    let n = grid.n();
    std::array::from_fn(|c| {
        let faces = Region::of(grid, FACES[c]);
        if c < grid.dims() {
            let r = bc.normal_faces(c, n[c]);
            faces.range(c, r.lo, r.hi)
        } else {
            faces
        }
    })
}

/// One step of the momentum advection (SSP-RK2 on `(m, m u)`, module docs) of the velocity
/// `vel` (one component per axis of `grid`, ghosts filled) with the cell densities `rho`
/// (ghosts filled), on the control volumes `cv[c]` of each component (its unknown faces).
/// `fill` fills the velocity's ghosts between the two Runge–Kutta stages; `history` is the
/// `WholeStep` predictor's (updated), `None` for the `Advection` predictor; `start` the
/// start-of-step velocity's copy, or room for one. `pool` holds at least [`work_len`] values;
/// on return its first `dims` arrays of the fields' padded length hold the control volumes'
/// masses at the end of the step (the momentum is their product with the velocity).
#[allow(clippy::too_many_arguments)]
pub fn advance(
    grid: &Grid,
    cv: &[Region],
    dt: f64,
    vel: &mut [&mut Field],
    rho: &Field,
    pool: &mut [f64],
    start: Start<'_>,
    history: Option<&mut History>,
    fill: &mut dyn FnMut(&mut [&mut Field]),
) {
    // SSP-RK2 (Heun) on (m, m u):
    //   m¹ = m⁰ + Δt Lm(m⁰, V⁰),  (m u)¹ = m⁰u⁰ + Δt Lq(m⁰, V⁰),  u¹ = (m u)¹/m¹,
    //   m* = ½m⁰ + ½(m¹ + Δt Lm(m¹, V¹)),  (m u)* = ½m⁰u⁰ + ½((m u)¹ + Δt Lq(m¹, V¹)).
    let dims = grid.dims();
    assert_eq!(vel.len(), dims, "one velocity component per axis");
    let len = rho.data().len();
    let mut w = Work::cut(pool, dims, len);
    for c in 0..dims {
        kernels::face_masses(grid, rho, c, w.m[c]);
    }
    let x0: [&[f64]; 3] = match start {
        Start::Kept(f) => {
            assert!(f.len() == dims, "one start velocity component per axis");
            std::array::from_fn(|c| f.get(c).map_or(&[][..], |f| f.data()))
        }
        Start::Copy(copies) => {
            let copies = &mut copies[..dims * len];
            for (x0, v) in copies.chunks_exact_mut(len).zip(vel.iter()) {
                copy(x0, v.data());
            }
            let copies = &*copies;
            std::array::from_fn(|c| copies.get(c * len..(c + 1) * len).unwrap_or(&[]))
        }
    };
    // The other stages' increments of the last step, rescaled to this Δt (module docs).
    let (lag, y) = match history.as_deref() {
        Some(h) if h.dt > 0.0 => (dt / h.dt, Some(&h.vel)),
        _ => (0.0, None),
    };
    for stage in 0..2 {
        let step = Euler {
            dt,
            lag,
            second: stage == 1,
            rho,
        };
        // Each component's masses and momenta advance once its tendencies are known (only
        // its own tendencies read its masses); the velocities once every component's are.
        let view: [&Field; 3] = std::array::from_fn(|c| &*vel[c.min(dims - 1)]);
        for c in 0..dims {
            kernels::tendency(grid, cv[c], c, &view[..dims], &mut w);
            let y: &[f64] = y.map_or(&[], |y| &y[c]);
            let Work { qt, mt, m, .. } = &mut w;
            step.advance_mass(cv[c], c, view[c], m[c], [x0[c], y], qt[c], mt);
        }
        for c in 0..dims {
            let y: &[f64] = y.map_or(&[], |y| &y[c]);
            step.velocity(cv[c], vel[c], &*w.m[c], [x0[c], y], &*w.qt[c]);
        }
        if stage == 0 {
            fill(vel);
        }
    }
    if let Some(h) = history {
        for (y, v) in h.vel.iter_mut().zip(vel.iter()) {
            copy(y, v.data());
        }
        h.dt = dt;
    }
}

/// Largest stable Δt of the explicit convective term of the velocity `vel` (one component per
/// axis) at Courant number `cfl` ([`convective_rate`]).
pub fn advective_dt(grid: &Grid, vel: &[&Field], cfl: f64) -> Option<f64> {
    let rate = convective_rate(grid, vel);
    (rate > 0.0).then(|| cfl / rate)
}

/// The velocity components of `state`, one per axis of `grid` (`w` on a three-dimensional one).
pub(crate) fn velocity<'a>(grid: &Grid, state: &'a State) -> ([&'a Field; 3], usize) {
    let w = state.w.as_ref().unwrap_or(&state.v);
    ([&state.u, &state.v, w], grid.dims())
}

/// The momentum and mass tendencies `(−∇·(m a ⊗ u_c), −∇·(m a))` of each component `c` of the
/// velocity `vel` (ghosts filled) on its control volumes `cv[c]`, with the face masses from the
/// cell densities `rho` (ghosts filled): the stage's spatial operator, for tests and
/// diagnostics (it allocates its work arrays).
pub fn tendencies(grid: &Grid, cv: &[Region], vel: &[&Field], rho: &Field) -> Vec<[Field; 2]> {
    let dims = grid.dims();
    assert_eq!(vel.len(), dims, "one velocity component per axis");
    let mut pool = vec![0.0; work_len(grid)];
    let mut w = Work::cut(&mut pool, dims, rho.data().len());
    for c in 0..dims {
        kernels::face_masses(grid, rho, c, w.m[c]);
    }
    (0..dims)
        .map(|c| {
            kernels::tendency(grid, cv[c], c, vel, &mut w);
            let mut out = [Field::zeros(grid), Field::zeros(grid)];
            for (o, t) in out.iter_mut().zip([&*w.qt[c], &*w.mt]) {
                cv[c].for_each(o, |l, o| o.copy_from_slice(&t[l.n * l.len..][..l.len]));
            }
            out
        })
        .collect()
}

struct AdvectionStage {
    /// The `WholeStep` predictor's history (`None` with `Advection`).
    history: Option<History>,
    /// The pipeline's work vectors ([`work_len`] values while the stage runs).
    scratch: Scratch,
    /// The copy of the start-of-step velocity, in a run that keeps none of its own
    /// ([`start_len`] values from the first such step on; empty before).
    start: Vec<f64>,
}

impl Stage for AdvectionStage {
    fn max_dt(&self, grid: &Grid, state: &State, cfl: f64) -> Option<f64> {
        let (vel, dims) = velocity(grid, state);
        advective_dt(grid, &vel[..dims], cfl)
    }

    fn run(&mut self, ctx: &StepContext, state: &mut State) -> Result<StageStats, StageError> {
        let g = ctx.grid;
        let dims = g.dims();
        let cv = control_volumes(g, ctx.bc);
        let scratch = self.scratch.clone();
        let mut pool = scratch.lock();
        let State { u, v, w, rho, .. } = state;
        // The run's copy of the step's start, if it keeps one of every component.
        let kept = ctx
            .start_velocity
            .filter(|s| s[..dims].iter().all(Option::is_some));
        let fields: [&Field; 3];
        let start = match kept {
            Some(s) => {
                // Past the grid's axes a placeholder, never read.
                fields = std::array::from_fn(|c| s[c.min(dims - 1)].expect("checked above"));
                Start::Kept(&fields[..dims])
            }
            None => {
                let n = start_len(g);
                if self.start.len() != n {
                    self.start = vec![0.0; n];
                }
                Start::Copy(&mut self.start)
            }
        };
        let mut none = Field::default();
        let mut vel = [u, v, w.as_mut().unwrap_or(&mut none)];
        // Between the stages: the boundary conditions at the end of the step.
        let mut fill = |vel: &mut [&mut Field]| match vel {
            [u, v, w] if dims == 3 => {
                ctx.bc
                    .fill_velocity3(g, u, v, Some(&mut **w), ctx.t + ctx.dt, false)
            }
            [u, v, ..] => ctx.bc.fill_velocity(g, u, v, ctx.t + ctx.dt, false),
            _ => unreachable!("two or three velocity components"),
        };
        advance(
            g,
            &cv[..dims],
            ctx.dt,
            &mut vel[..dims],
            rho,
            &mut pool,
            start,
            self.history.as_mut(),
            &mut fill,
        );
        Ok(StageStats::default())
    }

    fn save_into(&self, out: &mut Vec<f64>) {
        out.clear();
        if let Some(h) = &self.history {
            // Room for the history from the first save on: no allocation once it exists.
            out.reserve(h.saved_len());
        }
        if let Some(h) = self.history.as_ref().filter(|h| h.dt > 0.0) {
            out.push(h.dt);
            for v in &h.vel {
                out.extend_from_slice(v);
            }
        }
    }

    fn save(&self) -> Vec<f64> {
        let mut v = Vec::new();
        self.save_into(&mut v);
        v
    }

    fn saved_len(&self) -> usize {
        self.history
            .as_ref()
            .filter(|h| h.dt > 0.0)
            .map_or(0, History::saved_len)
    }

    /// Nothing (no history: the next step's second stage looks from advection alone), or what
    /// [`save`](Stage::save) wrote.
    fn restore(&mut self, data: &[f64]) -> Result<(), String> {
        match &mut self.history {
            Some(h) if data.is_empty() => {
                h.dt = 0.0;
                Ok(())
            }
            Some(h) if data.len() == h.saved_len() && data[0] > 0.0 => {
                h.dt = data[0];
                let n = h.vel[0].len();
                for (v, d) in h.vel.iter_mut().zip(data[1..].chunks_exact(n)) {
                    v.copy_from_slice(d);
                }
                Ok(())
            }
            None if data.is_empty() => Ok(()),
            h => Err(format!(
                "expected the advection's history ([Δt] and {} velocity arrays), got {} values",
                match h.as_ref().map_or(2, |h| h.vel.len()) {
                    3 => "three",
                    _ => "two",
                },
                data.len()
            )),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::face_value;

    #[test]
    fn van_leer_face_value_is_bounded_and_exact_for_linear() {
        // Linear data: second-order exact midpoint.
        assert!((face_value(1.0, 0.0, 1.0, 2.0, 3.0) - 1.5).abs() < 1e-15);
        assert!((face_value(-1.0, 0.0, 1.0, 2.0, 3.0) - 1.5).abs() < 1e-15);
        // Extremum: falls back to upwind.
        assert_eq!(face_value(1.0, 0.0, 1.0, 0.0, 0.0), 1.0);
        // Bounded between neighbours.
        let f = face_value(1.0, 0.0, 0.9, 1.0, 1.0);
        assert!((0.9..=1.0).contains(&f));
    }
}
