//! The `deformation` sub-step of the implicit-momentum stage: the end-of-step update `B̃^{n+1} = B̃(V^{n+1})` (seed Eqs. 24–25),
//! then the next step's rates, the end-of-step stress and the strain energy.

use super::{
    AUTO_COUPLED_GAIN, AUTO_STRAIN_SHARE, AUTO_WALL_CELLS, Deformation, ElasticCoupling, Kernels,
    body_err, err, missing,
};
use efsi_core::{Field, Grid, StageError, StageStats, State, StepContext, unit};
use efsi_laws_host::ConstitutiveLaw;
use rayon::prelude::*;

pub(super) struct DeformationStage {
    /// The elastic bodies (one: the single solid), each one's law and kernels, in order.
    pub(super) bodies: Vec<super::bodies::ElasticBody>,
    pub(super) laws: Vec<std::sync::Arc<dyn ConstitutiveLaw>>,
    pub(super) ks: Vec<Kernels>,
    /// Each body's fraction (the state's own for the single solid).
    pub(super) phis: super::bodies::Fractions,
    /// θ of B's stretching (`numerics.elastic.theta`) in a split step and in a coupled one.
    pub(super) thetas: [f64; 2],
    /// `numerics.elastic.coupling` (`Split` where the scene cannot couple).
    pub(super) mode: super::ElasticCoupling,
    /// Which sides are walls (x min, x max, y min, y max, then z min, z max on a
    /// three-dimensional grid): `NoSlip`, `MovingWall`, `FreeSlip`, `Symmetry`.
    pub(super) walls: Vec<bool>,
    /// Per body, the first pass of the update (the stretching evaluated on Bⁿ; see the module
    /// docs), on its kernels' grid.
    pub(super) first: Vec<Vec<Field>>,
    /// The whole grid and its sides.
    pub(super) frame: super::bodies::Frame,
    /// The elastic-wave limits on Δt.
    pub(super) limits: super::limits::WaveLimits,
}

impl DeformationStage {
    /// B and its history, shared with the elastic sub-step ([`Deformation`](super::Deformation)).
    pub(super) fn init_state(&self, grid: &Grid, state: &mut State) {
        super::bodies::init_state(&self.bodies, grid, state);
    }

    /// The split step's wave limit, or the coupled step's with `Coupled`.
    pub(super) fn max_dt(&self, _grid: &Grid, _state: &State, _cfl: f64) -> Option<f64> {
        let dt = match self.mode {
            ElasticCoupling::Coupled => self.limits.coupled,
            ElasticCoupling::Split | ElasticCoupling::Auto => self.limits.split,
        };
        dt.is_finite().then_some(dt)
    }

    /// With `Auto`, the coupled step's wave limit where the other stages allow steps at least
    /// [`AUTO_COUPLED_GAIN`] times the split step's and the solid is not busy deforming: its
    /// strain energy at most [`AUTO_STRAIN_SHARE`] of the flow's kinetic energy.
    pub(super) fn lift_dt(
        &self,
        grid: &Grid,
        state: &State,
        own: f64,
        others: Option<f64>,
    ) -> Option<f64> {
        let lifted = self.mode == ElasticCoupling::Auto
            && others.is_none_or(|o| o >= AUTO_COUPLED_GAIN * own)
            && self.limits.coupled.is_finite();
        if !lifted {
            return None;
        }
        let strain = super::bodies::deformations(state)
            .iter()
            .map(|d| d.elastic_energy)
            .sum::<f64>();
        let vel = super::velocity(&state.u, &state.v, state.w.as_ref());
        let kinetic = kinetic_energy(grid, &vel, &state.rho);
        (strain <= AUTO_STRAIN_SHARE * kinetic && !self.near_wall(grid, state, self.limits.coupled))
            .then_some(self.limits.coupled)
    }

    /// The update after the projection of a step that was `coupled` or split.
    pub(super) fn run(
        &mut self,
        ctx: &StepContext,
        state: &mut State,
        coupled: bool,
    ) -> Result<StageStats, StageError> {
        let f = &self.frame;
        let places = super::bodies::places(state);
        super::bodies::fit_kernels(&mut self.ks, places, &f.grid, &f.bc, &f.sides);
        for (first, k) in self.first.iter_mut().zip(&self.ks) {
            let c = Deformation::components(&k.grid);
            super::bodies::reshape(first, &k.grid, c);
        }
        let mut held = super::bodies::Held::take(state).ok_or_else(missing)?;
        let r = self.update_held(ctx, state, held.all(), coupled);
        held.put(state);
        super::bodies::record_energies(&self.bodies, state);
        r
    }

    /// [`run`](Self::run) on the bodies' deformations `ds`, held outside the state: each
    /// body's update with its own weights, then its stress and strain energy.
    fn update_held(
        &mut self,
        ctx: &StepContext,
        state: &State,
        ds: &mut [super::Deformation],
        coupled: bool,
    ) -> Result<StageStats, StageError> {
        let phi = state
            .phi
            .as_ref()
            .ok_or_else(|| err("deformation", "the solid fraction is not allocated".into()))?;
        self.phis
            .refresh(&self.bodies, &self.ks, state)
            .map_err(|m| err("deformation", m))?;
        let a = self.thetas[usize::from(coupled)] * ctx.dt;
        // The Picard pass, except in a coupled step beyond the split step's wave limit, which
        // ends with B̃^{n+1} = B̃(V^{n+1}), the tensor its implicit stiffness was solved with
        // (see the module docs).
        let picard = !(coupled && ctx.dt > self.limits.split * (1.0 + 1e-6));
        let vel = super::velocity(&state.u, &state.v, state.w.as_ref());
        let (phis, bodies) = (&self.phis, &self.bodies);
        let parts = (self.ks.par_iter_mut())
            .zip(ds.par_iter_mut())
            .zip(self.laws.par_iter())
            .zip(self.first.par_iter_mut());
        efsi_linalg::par::try_each(parts, |n, (((k, d), law), first)| {
            k.set_weights(phis.of(n, phi));
            k.with_velocity_near(&vel, k.near_c, |k, vel| k.update(vel, d, first, a, picard));
            // The end-of-step stress and the elastic energy.
            k.evaluate(law.as_ref(), &d.b, &mut d.stress, false)
                .map_err(|m| body_err("deformation", &bodies[n], m))?;
            d.elastic_energy = k
                .strain_energy(law.as_ref(), &d.b)
                .map_err(|m| body_err("deformation", &bodies[n], m))?;
            Ok(())
        })?;
        Ok(StageStats::default())
    }

    /// Whether a cell mostly solid (φ > ½) is within [`AUTO_WALL_CELLS`] cells of a wall, or
    /// would be after a step of `dt` at its velocity: an impact `Auto` takes with split steps.
    fn near_wall(&self, grid: &Grid, state: &State, dt: f64) -> bool {
        let Some(phi) = state.phi.as_ref() else {
            return false;
        };
        let (n, h, dims) = (grid.n().map(|n| n as isize), grid.h(), grid.dims());
        let last = |a: usize| if a < dims { n[a] - 1 } else { 0 };
        // The solids' cells as of the last update; before the first one, every cell.
        let solid = self.ks[1..]
            .iter()
            .fold(self.ks[0].solid_on_grid(), |c, k| {
                c.union(k.solid_on_grid())
            });
        let c = match solid {
            c if c.points() > 0 => c,
            _ => super::Window::boxed([0; 3], std::array::from_fn(last)),
        };
        let cells = super::Window::boxed(
            std::array::from_fn(|a| c.lo()[a].max(0)),
            std::array::from_fn(|a| c.hi()[a].min(last(a))),
        )
        .region(grid);
        let vel = super::velocity(&state.u, &state.v, state.w.as_ref());
        let reach =
            |gap: f64, toward: f64, h: f64| gap - toward.max(0.0) * dt < AUTO_WALL_CELLS * h;
        (0..cells.lines()).map(|m| cells.line(m)).any(|l| {
            let phi = phi.at(&l, [0; 3]);
            let faces: [(&[f64], &[f64]); 3] = std::array::from_fn(|a| {
                let a = a.min(dims - 1);
                (vel[a].at(&l, [0; 3]), vel[a].at(&l, unit(a)))
            });
            l.indices().enumerate().any(|(m, at)| {
                if phi[m] <= 0.5 {
                    return false;
                }
                (0..dims).any(|a| {
                    let vc = 0.5 * (faces[a].0[m] + faces[a].1[m]);
                    let (lo, hi) = (self.walls[2 * a], self.walls[2 * a + 1]);
                    (lo && reach(at[a] as f64 * h[a], -vc, h[a]))
                        || (hi && reach((n[a] - 1 - at[a]) as f64 * h[a], vc, h[a]))
                })
            })
        })
    }
}

/// Kinetic energy `½∫ρ|V|² dV` (per radian when axisymmetric) of the velocity `vel` (one field
/// per axis), with face-centred quadrature: half of each of a cell's two faces along each axis
/// belongs to it. Lines in parallel, summed in line order (the same bits on any number of
/// threads).
fn kinetic_energy(grid: &Grid, vel: &[&Field], rho: &Field) -> f64 {
    let (m, h) = (&grid.metric, grid.h());
    let [e] = efsi_core::Region::of(grid, efsi_core::Stagger::Cell).sum(|l| {
        let (rw, re, rc) = (m.rx_on(&l, 0), m.rx_on(&l, 1), m.rc_on(&l, 0));
        let faces: [(&[f64], &[f64]); 3] = std::array::from_fn(|a| {
            let a = a.min(vel.len() - 1);
            (vel[a].at(&l, [0; 3]), vel[a].at(&l, unit(a)))
        });
        let rho = rho.at(&l, [0; 3]);
        let mut e = 0.0;
        for n in 0..l.len {
            let (uw, ue) = (faces[0].0[n], faces[0].1[n]);
            let mut s = 0.5 * (rw[n] * uw.powi(2) + re[n] * ue.powi(2)) / 2.0;
            for (lo, hi) in &faces[1..vel.len()] {
                s += 0.5 * rc[n] * (lo[n].powi(2) + hi[n].powi(2)) / 2.0;
            }
            e += h[..vel.len()].iter().fold(rho[n] * s, |p, h| p * h);
        }
        [e]
    });
    e
}

impl Kernels {
    /// The end-of-step update of `d` for the velocity `vel` at `V^{n+1}`, the law aside (the
    /// weights set for the step's solid fraction): `B̃^{n+1} = B̃ⁿ + E + a H(V^{n+1}; ·)` with
    /// `a = θΔt` (seed Eq. 24, equivalently Eq. 25) — stretching the Picard pass's tensor
    /// (kept in `first`) if `picard`, else `B̃ⁿ` — the fluid's B back to the identity, then
    /// the next step's rates `Aⁿ⁺¹ = ∇·(V^{n+1} B̃^{n+1})` (the step's own `A` kept as the
    /// previous) and `H(V^{n+1}; B̃^{n+1})`.
    pub(super) fn update(
        &mut self,
        vel: &[&Field],
        d: &mut Deformation,
        first: &mut [Field],
        a: f64,
        picard: bool,
    ) {
        self.gradient(vel);
        let base = Some((&d.start[..], &d.explicit[..]));
        if picard {
            // The first pass writes near the material only; beyond it (where the second pass's
            // edge averages reach) it holds the step's B, the identity there.
            for (f, b) in first.iter_mut().zip(&d.b) {
                f.copy_from(b);
            }
            self.stretch(&d.start, a, base, Some(&d.relax), first);
            self.fill_ghosts(first);
        }
        // The update stretches the first pass's tensor (Picard) or the step's start.
        let from = if picard { &*first } else { &d.start[..] };
        self.stretch(from, a, base, Some(&d.relax), &mut d.b);
        // The fluid's B back to the identity before the rates are taken and the interface
        // moves: stretched by the fluid's velocity gradient, it would flow into the solid
        // through the next step's advection and stay in the cells the solid enters (see
        // "Pure fluid" in the module docs).
        self.reset_fluid_b(&mut d.b);
        self.fill_ghosts(&mut d.b);
        std::mem::swap(&mut d.advection, &mut d.advection_prev);
        self.advect(vel, &d.b, &mut d.advection);
        self.stretch(&d.b, 1.0, None, None, &mut d.stretching);
    }
}
