//! The implicit viscous–elastic system and its solve: the operator
//! `M − θ_v Δt K_v − αθΔt² K_J` (see the module docs of [`super`]) and the elastic sub-step.

use super::ElasticPreconditioner;
use super::{Kernels, body_err, err, missing, plus};
use crate::block_multigrid::ViscousBlocks;
use crate::viscous_operator::Coefficients;
use efsi_core::operators::face_density;
use efsi_core::operators::minus;
use efsi_core::{Field, Grid, Index, StageError, StageStats, State, StepContext, unit};
use efsi_laws_host::ConstitutiveLaw;
use efsi_linalg::{BiCgStab, LinearOperator, SolveStats};
use rayon::prelude::*;

pub(super) struct ElasticStage {
    /// The elastic bodies (one: the single solid) and each one's law, in order.
    pub(super) bodies: Vec<super::bodies::ElasticBody>,
    pub(super) laws: Vec<std::sync::Arc<dyn ConstitutiveLaw>>,
    /// Each body's fraction (the state's own for the single solid).
    pub(super) phis: super::bodies::Fractions,
    /// θ of the viscous step, whose implicit operator joins the elastic system (0 if inviscid).
    pub(super) theta: f64,
    /// This step's scheme: θ of B's stretching (`numerics.elastic.theta`; 0.5: Crank–Nicolson
    /// in a split step, 0.75 in a coupled one) and the preconditioner (from scene
    /// `numerics.elastic.preconditioner`), one of `schemes`.
    pub(super) scheme: super::StepScheme,
    /// The split step's scheme and the coupled step's.
    pub(super) schemes: [super::StepScheme; 2],
    /// `numerics.elastic.coupling` (`Split` where the scene cannot couple) and the split
    /// step's wave limit on Δt (the step above which `Auto` couples).
    pub(super) mode: super::ElasticCoupling,
    pub(super) split_dt: f64,
    /// `h/c`, the Δt of one elastic-wave Courant number, and the scene's options: a split
    /// step's stress weight follows its Courant number
    /// ([`super::ElasticOptions::split_stress_weight`]).
    pub(super) wave_step: f64,
    pub(super) options: super::ElasticOptions,
    /// Per body, `τ^{n+1/3}`.
    pub(super) tau: Vec<Vec<Field>>,
    /// Per body, τ(Bⁿ) with this step's weights: the old-time stress of a step whose stress
    /// weight α is below 1 (evaluated only then).
    pub(super) tau_n: Vec<Vec<Field>>,
    pub(super) op: ElasticOperator,
    pub(super) rhs: Vec<f64>,
    pub(super) delta: Vec<f64>,
    pub(super) diag: Vec<f64>,
    pub(super) solver: BiCgStab,
    pub(super) tol: f64,
    pub(super) max_iter: usize,
    /// Whether the elastic stress is implicit (scene `numerics.elastic.implicit`).
    pub(super) implicit: bool,
    /// The block multigrid's effective viscosities × Δt at centres and on the edges of each
    /// shear pair (see [`Kernels::stiffness`]).
    pub(super) blocks: ViscousBlocks,
    pub(super) eta: Field,
    pub(super) eta_k: Vec<Field>,
    /// The bodies' elastic stiffness summed at the centres, for the Jacobi diagonal
    /// ([`ElasticStage::face_terms`]).
    pub(super) stiffness: Field,
    /// `K_η` of those, and the mass plus its hoop term and the diagonal of `M − K_η`.
    pub(super) eta_coefficients: Coefficients,
    pub(super) eta_dm: Vec<f64>,
    pub(super) eta_diag: Vec<f64>,
    /// Work space of the operator, allocated once.
    pub(super) scratch: Scratch,
    /// The coupled step's work space (`numerics.elastic.coupling` `Coupled` or `Auto`), else
    /// `None`.
    pub(super) coupling: Option<super::coupled::Coupling>,
}

/// The elastic operator's work space: the increment as fields (`xw` on a three-dimensional
/// grid only), and per body Δτ (zero outside its solid).
pub(super) struct Scratch {
    pub(super) xu: Field,
    pub(super) xv: Field,
    pub(super) xw: Option<Field>,
    pub(super) dtau: Vec<Vec<Field>>,
}

/// `y = M x − θΔt K_v x − (Δt²/2) Σ_k vol ∇·(J_k : H(x; B̃_kⁿ))` on the compact unknown
/// faces, summed over the elastic bodies.
pub(super) struct ElasticOperator {
    /// Each elastic body's kernels (on the whole grid, or on the body's window; the unknown
    /// faces the whole grid's in all).
    pub(super) ks: Vec<Kernels>,
    /// The whole grid and its sides.
    pub(super) frame: super::bodies::Frame,
    /// Per body, the increment's stretching (on the body's kernels' grid).
    pub(super) db: Vec<Vec<Field>>,
    pub(super) mass: Vec<f64>,
    /// `Δt²/2`.
    pub(super) c: f64,
    /// `θΔt` of the viscous step (0 without viscosity), and the viscosities it uses.
    pub(super) theta_dt: f64,
    pub(super) mu: Field,
    /// The edge viscosities of each shear pair.
    pub(super) mu_edges: Vec<Field>,
    /// `θΔt K_v`, its coefficients set each step (zero without viscosity).
    pub(super) viscous: Coefficients,
    /// `mass` plus the hoop term of `θΔt K_v`.
    pub(super) dm: Vec<f64>,
}

/// The elastic operator bound to this step's deformation and work space. After
/// [`apply`](LinearOperator::apply), `xu`, `xv` (and `xw`) hold `x` scattered, ghosts filled.
pub(super) struct OperatorCtx<'a> {
    pub(super) op: &'a mut ElasticOperator,
    /// The bodies' deformations (their `start` and `relax`), in the order of `op.ks`.
    pub(super) d: &'a [super::Deformation],
    pub(super) xu: &'a mut Field,
    pub(super) xv: &'a mut Field,
    pub(super) xw: Option<&'a mut Field>,
    pub(super) dtau: &'a mut [Vec<Field>],
}

impl<'a> OperatorCtx<'a> {
    /// The operator of this step's deformations `d` (one per body), working in `scratch`.
    pub(super) fn new(
        op: &'a mut ElasticOperator,
        scratch: &'a mut Scratch,
        d: &'a [super::Deformation],
    ) -> Self {
        OperatorCtx {
            op,
            d,
            xu: &mut scratch.xu,
            xv: &mut scratch.xv,
            xw: scratch.xw.as_mut(),
            dtau: &mut scratch.dtau,
        }
    }
}

impl LinearOperator for OperatorCtx<'_> {
    fn apply(&mut self, x: &[f64], y: &mut [f64]) {
        let op = &mut *self.op;
        let (xu, xv) = (&mut *self.xu, &mut *self.xv);
        let mut xw = self.xw.as_deref_mut();
        let (k0, frame) = (&op.ks[0], &op.frame);
        match xw.as_deref_mut() {
            Some(xw) => k0.faces.scatter_to(x, &mut [&mut *xu, &mut *xv, xw]),
            None => k0.faces.scatter(x, xu, xv),
        }
        frame
            .bc
            .fill_velocity3(&frame.grid, xu, xv, xw.as_deref_mut(), 0.0, true);
        let vel = super::velocity(xu, xv, xw.as_deref());
        op.viscous.product(&vel, &op.dm, Some(x), y);
        // The increment's stress lives in each body's solid: gradients, stretching and
        // tangent there, each body's increment stretched by its own Bⁿ (the bodies in
        // parallel), then the forces summed in the bodies' order.
        let parts = (op.ks.par_iter_mut())
            .zip(self.d.par_iter())
            .zip(self.dtau.par_iter_mut())
            .zip(op.db.par_iter_mut());
        parts.for_each(|(((k, d), dtau), db)| {
            let cw = k.solid_c;
            k.with_velocity_near(&vel, cw, |k, vel| k.gradient_in(vel, cw));
            k.stretch_in(&d.start, 1.0, None, Some(&d.relax), db, cw);
            k.apply_tangent(db, dtau);
        });
        for (k, dtau) in op.ks.iter().zip(self.dtau.iter()) {
            k.force_sub(dtau, op.c, y);
        }
    }
}

impl ElasticStage {
    /// B = I and its rates from the initial velocity (the solid fraction set: the stages
    /// writing material fields initialise first).
    pub(super) fn initialize(&mut self, state: &mut State) -> Result<(), StageError> {
        self.fit(state)?;
        let mut held = super::bodies::Held::take(state).ok_or_else(missing)?;
        let r = self.initialize_held(state, held.all());
        held.put(state);
        r
    }

    /// [`initialize`](Self::initialize) of the bodies' deformations `ds`, held outside the
    /// state.
    fn initialize_held(
        &mut self,
        state: &State,
        ds: &mut [super::Deformation],
    ) -> Result<(), StageError> {
        // The solid fraction is set: the stages writing material fields initialise first.
        let phi = state
            .phi
            .as_ref()
            .ok_or_else(|| err("elastic", "the solid fraction is not allocated".into()))?;
        self.phis
            .refresh(&self.bodies, &self.op.ks, state)
            .map_err(|m| err("elastic", m))?;
        let vel = super::velocity(&state.u, &state.v, state.w.as_ref());
        for (n, (k, d)) in self.op.ks.iter_mut().zip(ds.iter_mut()).enumerate() {
            d.set_identity();
            for r in &mut d.relax {
                r.fill(1.0);
            }
            k.set_weights(self.phis.of(n, phi));
            k.fill_ghosts(&mut d.b);
            k.with_velocity(&vel, |k, vel| {
                k.gradient(vel);
                k.advect(vel, &d.b, &mut d.advection);
            });
            for (p, a) in d.advection_prev.iter_mut().zip(&d.advection) {
                p.copy_from(a);
            }
            k.stretch(&d.b, 1.0, None, None, &mut d.stretching);
        }
        Ok(())
    }

    /// The elastic sub-step; whether it was a coupled one besides its statistics. Takes B̃
    /// out of the state for the step and puts it back on every exit, failed or not: a failed
    /// step leaves the state complete, so the run loop (or an FMU) can restore the step's
    /// start into it.
    pub(super) fn run(
        &mut self,
        ctx: &StepContext,
        state: &mut State,
    ) -> Result<(StageStats, bool), StageError> {
        self.fit(state)?;
        let mut held = super::bodies::Held::take(state).ok_or_else(missing)?;
        let result = self.advance(ctx, state, held.all());
        held.put(state);
        result
    }

    /// The bodies' deformations on the windows around their fractions
    /// ([`super::bodies::place_all`]), and the kernels and each body's work arrays on them.
    fn fit(&mut self, state: &mut State) -> Result<(), StageError> {
        let f = &self.op.frame;
        super::bodies::place_all(&self.bodies, &f.grid, state).map_err(|m| err("elastic", m))?;
        let places = super::bodies::places(state);
        super::bodies::fit_kernels(&mut self.op.ks, places, &f.grid, &f.bc, &f.sides);
        let scratch = self
            .tau
            .iter_mut()
            .zip(&mut self.tau_n)
            .zip(&mut self.scratch.dtau)
            .zip(&mut self.op.db);
        for ((((tau, tau_n), dtau), db), k) in scratch.zip(&self.op.ks) {
            let c = super::Deformation::components(&k.grid);
            for t in [tau, tau_n, dtau, db] {
                super::bodies::reshape(t, &k.grid, c);
            }
        }
        Ok(())
    }

    /// One elastic step with B̃ (`d`) held outside the state: choose the split or the coupled
    /// step (`numerics.elastic.coupling`; with `Auto` by Δt), [`predict`](Self::predict) the
    /// deformation at the step's first third and its stress, [`assemble`](Self::assemble) the
    /// implicit system, [`solve`](Self::solve) it for the velocity increment and add it, then
    /// [`correct`](Self::correct) the deformation with the new velocity. Returns whether the
    /// step taken was a coupled one (`Auto`'s failed coupled solve is retaken split).
    fn advance(
        &mut self,
        ctx: &StepContext,
        state: &mut State,
        d: &mut [super::Deformation],
    ) -> Result<(StageStats, bool), StageError> {
        let coupled =
            self.coupling.is_some() && super::coupled_step(self.mode, ctx.dt, self.split_dt);
        self.set_scheme(coupled, ctx.dt);
        self.predict(ctx, state, d)?;
        let (bnorm, scale) = self.assemble(ctx, state);
        let (stats, coupled) = if !coupled {
            (self.solve(ctx, state, d, bnorm, scale)?, false)
        } else {
            match self.solve_coupled(ctx, state, d, bnorm, scale) {
                Ok(stats) => (stats, true),
                // `Auto` chose the coupled step and its solve did not converge: the step is
                // taken split instead, from the same start (the velocity is as it was; B back
                // to Bⁿ). One split step above its wave cap does not pump energy in the way a
                // run of them does, and the energy guard watches what follows.
                Err(_) if self.mode == super::ElasticCoupling::Auto => {
                    for d in d.iter_mut() {
                        for (b, s) in d.b.iter_mut().zip(&d.start) {
                            b.copy_from(s);
                        }
                    }
                    self.set_scheme(false, ctx.dt);
                    self.predict(ctx, state, d)?;
                    let (bnorm, scale) = self.assemble(ctx, state);
                    (self.solve(ctx, state, d, bnorm, scale)?, false)
                }
                Err(e) => return Err(e),
            }
        };
        self.correct(ctx, state, d);
        Ok((StageStats { solve: Some(stats) }, coupled))
    }

    /// θ, the stress weight and the preconditioner of a coupled or a split step of `dt`.
    fn set_scheme(&mut self, coupled: bool, dt: f64) {
        self.scheme = self.schemes[usize::from(coupled)];
        // The explicit elastic step (`implicit: false`) keeps the stress at the step's end.
        if !coupled && self.implicit {
            self.scheme.alpha = self.options.split_stress_weight(dt / self.wave_step);
        }
    }

    /// Bⁿ and the explicit part E of the step, the interface corners' relaxation, then
    /// `B̃^{n+1/3} = B̃(V^{n+1/3})` and its stress and tangent.
    fn predict(
        &mut self,
        ctx: &StepContext,
        state: &State,
        ds: &mut [super::Deformation],
    ) -> Result<(), StageError> {
        let dt = ctx.dt;
        let r = if state.dt_prev > 0.0 {
            dt / state.dt_prev
        } else {
            0.0
        };
        let phi = state
            .phi
            .as_ref()
            .ok_or_else(|| err("elastic", "the solid fraction is not allocated".into()))?;
        self.phis
            .refresh(&self.bodies, &self.op.ks, state)
            .map_err(|m| err("elastic", m))?;
        let vel = super::velocity(&state.u, &state.v, state.w.as_ref());
        let (theta, alpha) = (self.scheme.theta, self.scheme.alpha);
        let (phis, bodies) = (&self.phis, &self.bodies);
        let parts = (self.op.ks.par_iter_mut())
            .zip(ds.par_iter_mut())
            .zip(self.laws.par_iter())
            .zip(self.tau.par_iter_mut().zip(self.tau_n.par_iter_mut()));
        efsi_linalg::par::try_each(parts, |n, (((k, d), law), (tau, tau_n))| {
            k.set_weights(phis.of(n, phi));
            k.reset_fluid(d);
            d.begin_step(dt, r, theta);
            if alpha < 1.0 {
                k.evaluate(law.as_ref(), &d.start, tau_n, false)
                    .map_err(|m| body_err("elastic", &bodies[n], m))?;
            }
            k.relaxation(law.as_ref(), &d.start, dt, &mut d.explicit, &mut d.relax)
                .map_err(|m| body_err("elastic", &bodies[n], m))?;
            k.with_velocity_near(&vel, k.near_c, |k, vel| k.gradient(vel));
            k.stretch(
                &d.start,
                theta * dt,
                Some((&d.start[..], &d.explicit[..])),
                Some(&d.relax),
                &mut d.b,
            );
            k.fill_ghosts(&mut d.b);
            k.evaluate(law.as_ref(), &d.b, tau, true)
                .map_err(|m| body_err("elastic", &bodies[n], m))
        })
    }

    /// The right-hand side `Δt·vol·∇·τ^{n+1/3}`, the mass, the viscous coefficients and the
    /// Jacobi diagonal. Returns the right-hand side's norm and the residual's scale: the larger
    /// of it and the momentum `‖M V^{n+1/3}‖`, so a body nearly at rest (tiny right-hand side)
    /// is not asked for more digits than its momentum has.
    fn assemble(&mut self, ctx: &StepContext, state: &State) -> (f64, f64) {
        let dt = ctx.dt;
        // The bodies' stresses summed: each vanishes outside its solid.
        let ks = &self.op.ks;
        ks[0].force(&self.tau[0], &mut self.rhs);
        for (k, tau) in ks.iter().zip(&self.tau).skip(1) {
            k.force_sub(tau, -1.0, &mut self.rhs);
        }
        let alpha = self.scheme.alpha;
        if alpha < 1.0 {
            self.rhs.iter_mut().for_each(|r| *r *= alpha);
            for (k, tau_n) in ks.iter().zip(&self.tau_n) {
                k.force_sub(tau_n, alpha - 1.0, &mut self.rhs);
            }
        }
        let g = ctx.grid;
        let c2 = if self.implicit {
            alpha * self.scheme.theta * dt * dt
        } else {
            0.0
        };
        self.op.c = c2;
        self.op.theta_dt = self.theta * dt;
        if self.theta > 0.0 {
            self.op.mu.copy_from(&state.mu);
            self.op.viscous.set_viscosity_edges(
                g,
                &state.mu,
                self.op.theta_dt,
                &mut self.op.mu_edges,
            );
        }
        self.face_terms(g, &state.rho, dt);
        let bnorm = self.rhs.iter().map(|x| x * x).sum::<f64>().sqrt();
        {
            let op = &mut self.op;
            for ((dm, m), h) in op.dm.iter_mut().zip(&op.mass).zip(op.viscous.hoop()) {
                *dm = m + h;
            }
        }
        (bnorm, bnorm.max(self.momentum_norm(state)))
    }

    /// Per unknown face: the mass, the Jacobi diagonal (mass plus the elastic stiffness `c2·e`
    /// and the viscosity `θΔt·μ` bounds of the face's stencil) and the right-hand side times
    /// `Δt`.
    fn face_terms(&mut self, g: &Grid, rho: &Field, dt: f64) {
        let m = &g.metric;
        let (h, dims) = (g.h(), g.dims());
        let (c2, td) = (self.op.c, self.op.theta_dt);
        let ks = &self.op.ks;
        let k = &ks[0];
        let stiffness = &mut self.stiffness;
        let (mu, me) = (&self.op.mu, &self.op.mu_edges);
        let (mass, diag, rhs) = (&mut self.op.mass, &mut self.diag, &mut self.rhs);
        let mm = k.m;
        // The largest diagonal entry of the tangent (normal and shear rows) at a centre.
        let rows: &[usize] = if dims == 2 {
            &[0, 1, 3]
        } else {
            &[0, 1, 2, 3, 4, 5]
        };
        // Zero outside the solid's window (`w = 0`), where the batches hold nothing.
        let stiff_of = |k: &Kernels, at: Index| {
            let o = k.origin;
            let at = [at[0] - o[0], at[1] - o[1], at[2] - o[2]];
            if !k.solid_c.contains3(at) {
                return 0.0;
            }
            let q = k.ci(at);
            let (jm, b) = (&k.cj[q * mm * mm..], &k.cb[q * mm..]);
            let j = rows
                .iter()
                .fold(0.0_f64, |s, &c| s.max(jm[c * (mm + 1)].abs()));
            let b = (0..dims).fold(0.0_f64, |s, c| s.max(b[c].abs()));
            k.w[at] * j * b.max(1e-300)
        };
        // The bodies' stiffnesses summed at the centres (the mixture's tangent), each body's
        // added over its solid's window in the bodies' order (zero elsewhere).
        stiffness.fill(0.0);
        for k in ks {
            let c = k.solid_on_grid();
            for q in 0..c.points() {
                let at = c.point(q);
                stiffness[at] += stiff_of(k, at);
            }
        }
        let stiffness = &*stiffness;
        let stiff = |at: Index| stiffness[at];
        let mut scale = 4.0 / (h[0] * h[0]);
        for a in 1..dims {
            scale += 4.0 / (h[a] * h[a]);
        }
        // The faces normal to axis a, between the cells I − e_a and I, with the edges I and
        // I + e_b of each pair (a, b) beside them.
        let mut c = 0;
        for a in 0..dims {
            let r = k.faces.region(a);
            for l in (0..r.lines()).map(|n| r.line(n)) {
                let area = if a == 0 {
                    m.rx_on(&l, 0)
                } else {
                    m.rc_on(&l, 0)
                };
                let (rlo, rhi) = (rho.at(&l, minus(a)), rho.at(&l, [0; 3]));
                let (mlo, mhi) = (mu.at(&l, minus(a)), mu.at(&l, [0; 3]));
                let beside: [(&[f64], &[f64]); 2] = std::array::from_fn(|o| {
                    let b = (a + 1 + o) % dims.max(2);
                    match (0..dims).contains(&b) && b != a {
                        true => {
                            let e = &me[super::PAIR[a][b]];
                            (e.at(&l, [0; 3]), e.at(&l, unit(b)))
                        }
                        false => (&[][..], &[][..]),
                    }
                });
                for (n, at) in l.indices().enumerate() {
                    let w = h[..dims].iter().fold(area[n], |s, h| s * h);
                    let e = stiff(plus(at, minus(a))).max(stiff(at));
                    mass[c] = face_density(rlo[n], rhi[n]) * w;
                    let mv = if td > 0.0 {
                        let mut x = mlo[n].max(mhi[n]);
                        for (lo, hi) in beside.iter().filter(|(lo, _)| !lo.is_empty()) {
                            x = x.max(lo[n]).max(hi[n]);
                        }
                        2.0 * x
                    } else {
                        0.0
                    };
                    diag[c] = mass[c] + (c2 * e + td * mv) * w * scale;
                    rhs[c] *= dt;
                    c += 1;
                }
            }
        }
    }

    /// The momentum `‖M V‖` on the unknown faces (summed in their compact order).
    fn momentum_norm(&self, state: &State) -> f64 {
        let mut pnorm = 0.0;
        let mut c = 0;
        let faces = &self.op.ks[0].faces;
        let vel = super::velocity(&state.u, &state.v, state.w.as_ref());
        for (a, f) in vel.iter().enumerate() {
            let r = faces.region(a);
            for l in (0..r.lines()).map(|n| r.line(n)) {
                for &f in f.at(&l, [0; 3]) {
                    let x = self.op.mass[c] * f;
                    pnorm += x * x;
                    c += 1;
                }
            }
        }
        pnorm.sqrt()
    }

    /// The implicit system for the velocity increment (BiCGSTAB with the scene's
    /// preconditioner, to `tolerance × scale`), added to the velocity.
    fn solve(
        &mut self,
        ctx: &StepContext,
        state: &mut State,
        d: &[super::Deformation],
        bnorm: f64,
        scale: f64,
    ) -> Result<SolveStats, StageError> {
        let g = ctx.grid;
        let stats = if bnorm == 0.0 {
            SolveStats {
                iterations: 0,
                residual: 0.0,
                converged: true,
            }
        } else {
            self.delta.fill(0.0);
            self.setup_preconditioner(g, d);
            let (rhs, mut delta) = (
                std::mem::take(&mut self.rhs),
                std::mem::take(&mut self.delta),
            );
            let st = self.solve_a(d, &rhs, &mut delta, self.tol * scale);
            (self.rhs, self.delta) = (rhs, delta);
            if !st.converged {
                return Err(err(
                    "elastic",
                    crate::verdict::unconverged(
                        "BiCGSTAB",
                        st.iterations,
                        st.residual / bnorm,
                        self.tol,
                        "numerics.elastic.tolerance",
                        "numerics.elastic.max_iterations",
                        if self.max_iter < 20 {
                            "raise numerics.elastic.max_iterations"
                        } else {
                            "raise numerics.elastic.max_iterations or reduce the time step"
                        },
                        "the implicit elastic system is too ill-conditioned for it: check the \
                         solid's parameters (a solid viscosity many orders below the fluid's, a \
                         modulus far above the scene's scale), or reduce the time step \
                         (time.cfl, numerics.elastic.wave_courant)",
                    ),
                ));
            }
            let faces = &self.op.ks[0].faces;
            match state.w.as_mut() {
                Some(w) => faces.add(&self.delta, &mut [&mut state.u, &mut state.v, w]),
                None => faces.add(&self.delta, &mut [&mut state.u, &mut state.v]),
            }
            SolveStats {
                residual: st.residual / bnorm,
                ..st
            }
        };
        Ok(stats)
    }

    /// The operator's scratch stress cleared (it writes Δτ in this step's solid only) and,
    /// unless Jacobi, the block multigrid set up with the effective viscosities `η = θΔt μ +
    /// (Δt²/2) G_eff` at centres and corners, on a window around the solid only, the Jacobi
    /// diagonal elsewhere (`ViscousBlocks::setup_in`; module docs).
    pub(super) fn setup_preconditioner(&mut self, g: &Grid, d: &[super::Deformation]) {
        for f in self.scratch.dtau.iter_mut().flatten() {
            f.fill(0.0);
        }
        if self.scheme.preconditioner != ElasticPreconditioner::Jacobi {
            self.effective_viscosity(d);
            let op = &self.op;
            let pre = &mut self.eta_coefficients;
            pre.set_edges(g, &self.eta, &self.eta_k, 1.0);
            for ((dm, m), h) in self.eta_dm.iter_mut().zip(&op.mass).zip(pre.hoop()) {
                *dm = m + h;
            }
            pre.diagonal(&self.eta_dm, &mut self.eta_diag);
            // The bodies' solid windows' bounding box.
            let c = op.ks[1..]
                .iter()
                .fold(op.ks[0].solid_on_grid(), |c, k| c.union(k.solid_on_grid()));
            let solid = (c.i0 <= c.i1).then_some(((c.i0, c.i1), (c.j0, c.j1)));
            self.blocks.setup_in(pre, &self.eta_diag, solid);
        }
    }

    /// The effective viscosities `η = θΔt μ + (Δt²/2) G_eff` at the centres and corners
    /// (`eta`, `eta_k`): the block multigrid's, and the coupled step's preconditioner's.
    pub(super) fn effective_viscosity(&mut self, d: &[super::Deformation]) {
        let op = &mut self.op;
        let (e, ek) = (&mut self.eta, &mut self.eta_k);
        if op.theta_dt > 0.0 {
            let td = op.theta_dt;
            for (e, m) in e.data_mut().iter_mut().zip(op.mu.data()) {
                *e = td * m;
            }
            for (ek, me) in ek.iter_mut().zip(&op.mu_edges) {
                for (e, m) in ek.data_mut().iter_mut().zip(me.data()) {
                    *e = td * m;
                }
            }
        } else {
            e.fill(0.0);
            for ek in ek.iter_mut() {
                ek.fill(0.0);
            }
        }
        for (k, d) in op.ks.iter_mut().zip(d) {
            k.stiffness(&d.relax, op.c, e, ek);
        }
    }

    /// `A x = rhs` by BiCGSTAB to the absolute residual `tol`, with the scene's preconditioner
    /// (the block multigrid set up for this step, or the Jacobi diagonal).
    pub(super) fn solve_a(
        &mut self,
        d: &[super::Deformation],
        rhs: &[f64],
        x: &mut [f64],
        tol: f64,
    ) -> SolveStats {
        let mut ctxop = OperatorCtx::new(&mut self.op, &mut self.scratch, d);
        match self.scheme.preconditioner {
            ElasticPreconditioner::Jacobi => {
                self.solver
                    .solve(&mut ctxop, self.diag.as_slice(), rhs, x, tol, self.max_iter)
            }
            ElasticPreconditioner::Multigrid | ElasticPreconditioner::Auto => {
                self.solver
                    .solve(&mut ctxop, &self.blocks, rhs, x, tol, self.max_iter)
            }
        }
    }

    /// `B̃^{n+2/3} = B̃(V^{n+2/3})` with the corrected velocity (its boundary values at the
    /// step's end).
    fn correct(&mut self, ctx: &StepContext, state: &mut State, ds: &mut [super::Deformation]) {
        let g = ctx.grid;
        let dt = ctx.dt;
        ctx.bc.fill_velocity3(
            g,
            &mut state.u,
            &mut state.v,
            state.w.as_mut(),
            ctx.t + dt,
            false,
        );
        let vel = super::velocity(&state.u, &state.v, state.w.as_ref());
        let a = self.scheme.theta * dt;
        let parts = self.op.ks.par_iter_mut().zip(ds.par_iter_mut());
        parts.for_each(|(k, d)| {
            k.with_velocity_near(&vel, k.near_c, |k, vel| k.gradient(vel));
            k.stretch(
                &d.start,
                a,
                Some((&d.start[..], &d.explicit[..])),
                Some(&d.relax),
                &mut d.b,
            );
            k.fill_ghosts(&mut d.b);
        });
    }
}
