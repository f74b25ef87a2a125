//! Semi-implicit viscous step: `ρ (V^{n+1/3} − V*)/Δt = ∇·[μ (∇V + ∇Vᵀ)]` at level `θ`
//! (seed Eq. 12; θ = 1 backward Euler as the seed, θ = ½ Crank–Nicolson).
//!
//! **Operator.** `K(V) = vol·∇·(2μD)`, `D = ½(∇V + ∇Vᵀ)`, the one viscous operator of
//! `viscous_operator` (shared with the elastic stage and the block multigrid): normal
//! stresses at cell centres with the cell viscosity, shear on the edges (the corners of a
//! two-dimensional grid) with the harmonic mean of the four cells' viscosities around each, the
//! hoop term in axisymmetric geometry; symmetric negative semi-definite, the velocity
//! components coupled through `∇Vᵀ` and variable μ. The same code runs on two- and
//! three-dimensional grids: the velocity is one field per axis, the unknowns are the u-, v- and
//! (3-D) w-faces in one compact vector (`faces`).
//!
//! **Solve.** With `δ = V^{n+1/3} − V*` and the mass matrix `M = diag(ρ_f dV_f)` (face density
//! the average of the two cells): `(M − θΔt K) δ = Δt K(V*)`, symmetric positive definite, for
//! all components at once by conjugate gradient ("line solves as in the seed, or better": this
//! solves the coupled system exactly instead of splitting it), preconditioned by the diagonal
//! (Jacobi) or by multigrid V-cycles on the diagonal blocks, one per velocity component
//! (five-point stencils in two dimensions, seven-point in three; [`efsi_linalg::Multigrid`];
//! scene `numerics.viscous.preconditioner`: `Jacobi`, the default, `Multigrid`, or `Auto`,
//! multigrid once the diffusion number makes Jacobi's iteration count, ~10√(max diag/mass),
//! exceed the ~16 iterations the block preconditioner needs at about four times the cost
//! each). Jacobi keeps a flow uniform along a periodic direction exactly uniform; the
//! red–black smoother does so only to the solver tolerance. One function makes the choice
//! (`use_block_multigrid`).
//!
//! **Initial guess.** `δ/Δt` of the last two steps extrapolated linearly to this one, times
//! `Δt` (zero in the first step): the stopping rule is unchanged (residual ≤ tolerance ×
//! ‖right-hand side‖), only fewer iterations reach it. The history is stage state, kept
//! in snapshots and checkpoints ([`Stage::save`]), so a resumed run continues bit for bit.
//!
//! **Near a steady state** (`time.steady`), a solve stopped at the tolerance leaves an error that
//! the history carries from step to step: the iterates wander within the tolerance, and with a
//! steady criterion far below it a run may never stop. So once `δ/Δt` of the last two steps
//! agree to `SETTLE` (100) × the tolerance (max norm, relative), each solve must also reduce
//! its warm start's residual `CONTRACT`-fold (10×), down to a floor that keeps the solver's
//! error `e` under a tenth of the steady criterion: `‖e‖∞ ≤ ‖r‖₂/min M ≤ 0.1·steady·Δt`. The
//! error then shrinks geometrically across steps and the fixed point is the discretisation's,
//! whatever the tolerance (`tests/tests/cavity.rs`,
//! `the_cavity_steady_state_does_not_depend_on_the_viscous_tolerance`), and a warm-started solve
//! near a steady state takes few iterations. Where that floor is below round-off
//! (`1e-13 ‖b‖`: the Poiseuille tests at `steady: 1e-12`) the solve starts from zero instead, a
//! map without history, which settles bit for bit, and solves to the strict tolerance 1e-9: a
//! solve from zero stopped at the tolerance would bias the steady state by about
//! `tolerance × U`, far above the discretisation error (`tests/tests/flows.rs`,
//! `hagen_poiseuille_converges_second_order`). The choice reads only the saved history, so a
//! resumed run makes the same one.
//!
//! **Cost.** The operator is applied from coefficients assembled once per step in one
//! vectorised pass per component. With Jacobi the conjugate gradient is the stage's own
//! (`ViscousSystem::solve_jacobi`): the search direction lives in the fields the stencil reads
//! (no copy into them before each product), the update of the iterate and the residual forms
//! `z = r·(1/d)` and both dot products in the same pass, and `p = z + βp` is written into the
//! fields — per unknown and iteration about 18 values moved instead of 22, and no division.
//! The multigrid preconditioner goes through [`efsi_linalg::pcg::solve_norm_in`]; it takes
//! fewer iterations than Jacobi but each costs about four Jacobi iterations, so `Auto` keeps
//! Jacobi while the diagonal-to-mass ratio is below 40 (the falling drop's case). Near a steady
//! state the warm start's residual, which sets the stopping rule, is formed once: the Jacobi
//! solve starts from it instead of forming it again (one product fewer per step).
//!
//! **Parallelism.** The operator (scatter, stress divergence, gather) runs over lines in
//! parallel and CG's reductions have a fixed order: bit-identical on any number of threads. `K(V*)`
//! uses the θ-weighted boundary data `θ bⁿ⁺¹ + (1−θ) bⁿ` (K is affine in b, so this is exactly
//! the θ-scheme's boundary forcing); `δ` obeys the homogeneous conditions
//! ([`efsi_core::bc`]). Unconditionally stable for θ ∈ [½, 1]; θ = 1 damps the stiff modes of a
//! very viscous solid, θ = ½ is second-order in time.
//!
//! **Memory.** Between steps the stage keeps the warm start's two increments (two vectors of
//! unknown faces); the right-hand side, the diagonal and the solver's two vectors are the
//! pipeline's pool's (`scratch`), and so are the search direction's fields (one per axis,
//! where the stencil reads it; the pool's work fields, shared with the projection's pressure
//! increment). The coefficients are stored no larger than they vary (the operator's
//! `Coefficients::compact`): with one viscosity everywhere (a scene of one fluid) off the
//! axisymmetric geometry the cell coefficient and each shear pair's edge weight are one value
//! each, and with one density the mass `dm` of every face is one value; the hoop term is
//! stored in axisymmetric geometry only. Where the viscosity or the density varies, that
//! array is made at the first step that needs it (the same values, so the same bits).
//!
//! **Boundaries.** The stage fills velocity ghosts through one trait (`VelocityGhosts`): the
//! run's [`BoundarySet`] (z sides included on a three-dimensional grid), or, in the tests,
//! the ghosts of a periodic or walled box.

use crate::block_multigrid::ViscousBlocks;
use crate::faces::UnknownFaces;
use crate::scratch::{self, FieldScratch, Scratch};
use crate::viscous_operator::{Coefficients, Diag};
use efsi_core::operators::{face_density, minus};
use efsi_core::scene::{Options, OptionsDecl};
use efsi_core::schedule::VELOCITY;
use efsi_core::{
    BoundarySet, Field, FieldId, Grid, Line, Phase, Scene, Stage, StageError, StagePlugin,
    StageStats, State, StepContext, bc::WallTime,
};
use efsi_linalg::par::{self, dot};
use efsi_linalg::{
    LinearOperator, Norm, SolveStats,
    pcg::{NullSpace, solve_norm_in},
};
use std::borrow::BorrowMut;

#[cfg(test)]
pub(crate) mod box_ghosts;

mod options;
use options::STRICT_TOLERANCE;
pub use options::{ViscousOptions, ViscousPreconditioner};

/// The viscous stage plugin.
pub struct Viscous;

impl StagePlugin for Viscous {
    /// Planar, axisymmetric and three-dimensional: one dimension-generic code path.
    fn supports(&self, _geometry: efsi_core::Geometry) -> bool {
        true
    }
    fn name(&self) -> &'static str {
        "viscous"
    }
    fn phase(&self) -> Phase {
        Phase::Viscous
    }
    fn reads(&self) -> &'static [FieldId] {
        &[
            FieldId::VelocityX,
            FieldId::VelocityY,
            FieldId::VelocityZ,
            FieldId::Density,
            FieldId::Viscosity,
        ]
    }
    fn writes(&self) -> &'static [FieldId] {
        &VELOCITY
    }
    fn needed(&self, scene: &Scene, options: &Options) -> bool {
        scene.fluid.viscosity > 0.0
            || crate::solid::bodies(options)
                .is_ok_and(|b| b.list.iter().any(|b| b.solid.viscosity(&scene.fluid) > 0.0))
    }
    fn options(&self) -> Option<OptionsDecl> {
        Some(OptionsDecl::of::<ViscousOptions>())
    }

    fn build(
        &self,
        scene: &Scene,
        options: &Options,
        grid: &Grid,
        bc: &BoundarySet,
        shared: &mut efsi_core::Resources,
    ) -> Result<Box<dyn Stage>, String> {
        let o: &ViscousOptions = options.section()?;
        let faces = UnknownFaces::new(grid, bc);
        let mut stage = ViscousStage::new(scene.time.steady, o, grid, bc.clone(), faces, shared);
        // Only a preconditioner that may use them needs the hierarchies (≈ 27 cell-sized
        // arrays, touched by their set-up).
        stage.blocks = (o.preconditioner != ViscousPreconditioner::Jacobi)
            .then(|| ViscousBlocks::new(grid, bc));
        Ok(Box::new(stage))
    }
}

/// Fills the ghosts of a velocity (one field per axis of the grid, ghosts and boundary faces)
/// with the wall speeds of `when`: the boundary conditions of a run ([`BoundarySet`]), or a
/// test's.
pub(crate) trait VelocityGhosts: Clone + Send + Sync {
    /// Fill the ghosts of `vel`.
    fn fill<F: BorrowMut<Field>>(&self, grid: &Grid, vel: &mut [F], when: WallTime);
}

impl VelocityGhosts for BoundarySet {
    /// The sides' rules ([`efsi_core::bc`]), z sides included on a three-dimensional grid.
    fn fill<F: BorrowMut<Field>>(&self, grid: &Grid, vel: &mut [F], when: WallTime) {
        match vel {
            [u, v] => self.fill_velocity_at(grid, u.borrow_mut(), v.borrow_mut(), when),
            [u, v, w] => self.fill_velocity3_at(
                grid,
                u.borrow_mut(),
                v.borrow_mut(),
                Some(w.borrow_mut()),
                when,
            ),
            _ => panic!("BoundarySet fills the ghosts of two or three velocity components"),
        }
    }
}

/// Whether this step's conjugate gradient is preconditioned by the block multigrid (else
/// Jacobi): the scene's `choice`, `Auto` deciding by the largest diagonal-to-mass ratio
/// (`ratio`, computed only then).
fn use_block_multigrid(choice: ViscousPreconditioner, ratio: impl FnOnce() -> f64) -> bool {
    match choice {
        ViscousPreconditioner::Jacobi => false,
        ViscousPreconditioner::Multigrid => true,
        // Jacobi-preconditioned condition number ≲ max(diag/mass); CG needs ~10√κ
        // iterations at 1e-9, at a quarter of the block multigrid's cost per iteration:
        // break-even near κ ≈ 40.
        ViscousPreconditioner::Auto => ratio() > AUTO_MULTIGRID_RATIO,
    }
}

struct ViscousStage<B: VelocityGhosts = BoundarySet> {
    preconditioner: ViscousPreconditioner,
    theta: f64,
    tol: f64,
    max_iter: usize,
    op: ViscousSystem<B>,
    /// The pipeline's work vectors: [`WORK`] of the system's length while the stage runs
    /// (the right-hand side, the diagonal and the solver's two).
    scratch: Scratch,
    /// The pipeline's work fields: the search direction's, one per axis, while the stage runs
    /// (in `op.p`; empty placeholders there between runs).
    fields: FieldScratch,
    /// Block multigrid on the diagonal blocks, the operator's diagonal kept (`None` with
    /// the Jacobi preconditioner, which never uses it).
    blocks: Option<ViscousBlocks>,
    warm: WarmStart,
}

/// The increments `δ` of the last two steps (newest first) and their `Δt`, for the initial
/// guess; `history` counts the valid ones (0–2). While the stage runs, `prev[1]` holds this
/// step's `δ` (its guess is written over the oldest increment, the last read of it), so the
/// stage keeps two vectors of unknowns instead of three.
struct WarmStart {
    /// In a run that stops at a steady state: the relative change of `δ/Δt` between the last
    /// two steps below which the solve's stopping rule changes (module docs), and the run's
    /// `time.steady`; else `None`.
    settle: Option<(f64, f64)>,
    prev: [Vec<f64>; 2],
    prev_dt: [f64; 2],
    history: usize,
    /// Steps remembered ([`WarmStart::remember`]) since the stage was built: tells
    /// [`Stage::undo`] whether the step it undoes got that far.
    remembered: u64,
}

/// Work vectors the stage takes from the pipeline's pool: the right-hand side, the diagonal,
/// and conjugate gradient's two (the block multigrid's conjugate gradient takes the
/// diagonal's place as its third once its blocks are set up from it).
const WORK: usize = 4;

/// Above this largest diagonal-to-mass ratio `Auto` switches from Jacobi to block multigrid.
const AUTO_MULTIGRID_RATIO: f64 = 40.0;

/// In a run that stops at a steady state, the stopping rule changes once `δ/Δt` changes
/// between steps by at most this many solver tolerances (relative; module docs).
const SETTLE: f64 = 100.0;

/// Near a steady state a solve reduces its initial guess's residual at least this much, so
/// the solver's error shrinks geometrically from step to step.
const CONTRACT: f64 = 0.1;

/// The residual a solve near a steady state need not go below: enough to keep the change its
/// error makes under this fraction of `time.steady`.
const STEADY_SHARE: f64 = 0.1;

/// Below this fraction of the right-hand side a residual is round-off: a steady criterion that
/// would need one starts near the steady state from zero instead.
const ROUND_OFF: f64 = 1e-13;

/// `y = M x − θΔt K x` on the compact vector of unknown faces (u, then v, then w), `K` the one
/// viscous operator ([`crate::viscous_operator`]) with the cell viscosities and their harmonic
/// edge means, its coefficients set once per step; the hoop term is diagonal and folded with
/// the mass into `dm`.
struct ViscousSystem<B: VelocityGhosts = BoundarySet> {
    grid: Grid,
    /// The boundary conditions, for the homogeneous ghosts of the search direction.
    bc: B,
    faces: UnknownFaces,
    /// `θΔt K`'s coefficients ([`Coefficients::compact`]).
    k: Coefficients,
    /// `mass + hoop`: the diagonal of `M − θΔt K` without the stencil's part, per unknown
    /// face; or, with `dm_uniform`, one value for every face, as one line of it (a uniform
    /// density without a hoop term). Sized at the first step that needs it.
    dm: Vec<f64>,
    dm_uniform: bool,
    theta_dt: f64,
    /// One field per axis, where the products read their argument (the search direction of
    /// [`ViscousSystem::solve_jacobi`]).
    p: Vec<Field>,
}

impl<B: VelocityGhosts> ViscousSystem<B> {
    /// The system of `grid` on its unknown `faces` under `bc`, coefficients zero.
    fn new(grid: &Grid, bc: B, faces: UnknownFaces) -> Self {
        ViscousSystem {
            grid: grid.clone(),
            bc,
            k: Coefficients::compact(grid, faces),
            faces,
            dm: Vec::new(),
            dm_uniform: false,
            theta_dt: 0.0,
            p: (0..grid.dims()).map(|_| Field::zeros(grid)).collect(),
        }
    }

    /// The step's coefficients from the cell viscosities `mu` (ghosts filled) and densities
    /// `rho`: `θΔt K`, mass plus hoop term `dm` (face density the average of the two cells),
    /// and the diagonal of the full matrix into `diag` (rows in parallel).
    fn assemble(&mut self, mu: &Field, rho: &Field, diag: &mut [f64]) {
        self.k.set_viscosity_weights(&self.grid, mu, self.theta_dt);
        self.set_mass(rho);
        self.k.diagonal(self.dm(), diag);
    }

    /// `dm`, the face masses plus the hoop term, from the cell densities `rho`: one value
    /// where `rho` is uniform (ghosts included) and there is no hoop term — each face's mass
    /// is then that of the first (the same two densities, radius factor one), and the hoop
    /// term adds zero.
    fn set_mass(&mut self, rho: &Field) {
        let (g, faces) = (&self.grid, &self.faces);
        let first = (0..g.dims()).find(|&a| !faces.region(a).is_empty());
        let rd = rho.data();
        let same = rd.iter().all(|x| x.to_bits() == rd[0].to_bits());
        if let Some(a) = first.filter(|_| same && self.k.hoop_free()) {
            let l = faces.region(a).line(0);
            self.dm.resize(self.k.line_len().max(l.len), 0.0);
            mass(g, a, &l, rho, &mut self.dm);
            let one = self.dm[0];
            self.dm.fill(one);
            self.dm_uniform = true;
            return;
        }
        self.dm.resize(faces.len(), 0.0);
        self.dm_uniform = false;
        let hoops = self.k.hoop_diag();
        let (hoops, same) = match hoops {
            Diag::Faces(h) => (faces.split(h), false),
            Diag::Uniform(z) => ([z; 3], true),
        };
        for (a, dm) in faces.split_mut(&mut self.dm).into_iter().enumerate() {
            let (r, hoop) = (faces.region(a), hoops[a]);
            if r.is_empty() {
                continue;
            }
            par::rows(dm, r.len(0)).for_each(|n, dms| {
                let l = r.line(n);
                mass(g, a, &l, rho, dms);
                let hoop = if same { hoop } else { &hoop[n * l.len..] };
                for (dm, h) in dms.iter_mut().zip(hoop) {
                    *dm += h;
                }
            });
        }
    }

    /// `dm` as the diagonal of a product ([`Diag`]).
    fn dm(&self) -> Diag<'_> {
        if self.dm_uniform {
            Diag::Uniform(&self.dm)
        } else {
            Diag::Faces(&self.dm)
        }
    }

    /// The largest ratio of `diag` to the face mass, `Auto`'s choice of preconditioner (the
    /// masses recomputed: only this rule needs them, so they are not stored).
    fn max_diag_to_mass(&self, rho: &Field, diag: &[f64]) -> f64 {
        let (g, faces) = (&self.grid, &self.faces);
        let ratio = |d: f64, ms: f64| if ms > 0.0 { d / ms } else { 0.0 };
        let mut m = 0.0f64;
        let mut ms = Vec::new();
        for (a, diag) in faces.split(diag).into_iter().enumerate() {
            let r = faces.region(a);
            for n in 0..r.lines() {
                let l = r.line(n);
                ms.resize(l.len, 0.0);
                mass(g, a, &l, rho, &mut ms);
                for (d, ms) in diag[n * l.len..(n + 1) * l.len].iter().zip(&ms) {
                    m = m.max(ratio(*d, *ms));
                }
            }
        }
        m
    }
}

/// The masses `ρ_f dV_f` of the `a`-faces of line `l` into `out` (face density the average of
/// the two cells; the radius factor at x-faces for u, at cell centres for the others).
#[inline(always)]
fn mass(g: &Grid, a: usize, l: &Line, rho: &Field, out: &mut [f64]) {
    let (lo, hi) = (rho.at(l, minus(a)), rho.at(l, [0; 3]));
    let r = if a == 0 {
        g.metric.rx_on(l, 0)
    } else {
        g.metric.rc_on(l, 0)
    };
    let ([hx, hy, hz], n) = (g.h(), l.len);
    let (lo, hi, r) = (&lo[..n], &hi[..n], &r[..n]);
    let three = g.dims() == 3;
    for (k, m) in out[..n].iter_mut().enumerate() {
        let area = face_density(lo[k], hi[k]) * r[k] * hx * hy;
        *m = if three { area * hz } else { area };
    }
}

impl<B: VelocityGhosts> ViscousSystem<B> {
    /// `y = A x` from the compact `x`, returning `x·y` (through the fields `p`, which it
    /// overwrites).
    fn product(&mut self, x: &[f64], y: &mut [f64]) -> f64 {
        self.faces.scatter_to(x, &mut self.p);
        self.fill_search_ghosts();
        self.k.product(&self.p, self.dm(), Some(x), y)
    }

    /// The homogeneous boundary ghosts of the fields `p`.
    fn fill_search_ghosts(&mut self) {
        self.bc.fill(&self.grid, &mut self.p, WallTime::Homogeneous);
    }

    /// `r = b − A x` (and `q = A x`; the fields then hold `x`).
    fn residual(&mut self, b: &[f64], x: &[f64], r: &mut [f64], q: &mut [f64]) {
        self.product(x, q);
        par::chunks(&mut *r).for_each(|o, r| {
            let (b, q) = (&b[o..o + r.len()], &q[o..o + r.len()]);
            for ((r, b), q) in r.iter_mut().zip(b).zip(q) {
                *r = b - q;
            }
        });
    }

    /// The smallest diagonal mass (a lower bound of the system's eigenvalues).
    fn min_mass(&self) -> f64 {
        self.dm.iter().fold(f64::INFINITY, |m, &d| m.min(d))
    }

    /// Jacobi-preconditioned conjugate gradient for `A x = b` from the guess in `x`, stopping
    /// when `‖r‖₂ ≤ tol` for the true residual (the iterates of
    /// [`efsi_linalg::pcg::solve_norm_in`] with the diagonal, up to rounding: the order of the
    /// reductions' partial sums, and `z = r·dinv` with `dinv` the diagonal's reciprocal, one
    /// multiplication instead of a division per unknown and iteration — the division was a
    /// quarter of the update pass's time without AVX). The search direction `p` lives in the fields `p`,
    /// where the stencil reads it, instead of a compact vector copied into them before every
    /// product: one copy pass and one read of `p` fewer per iteration (the step is bound by
    /// memory traffic). `work` holds `r` and `q` (which holds `A p`, then `z`); while a true
    /// residual borrows the fields, `p` waits in `r` (whose recursive value the true residual
    /// replaces) and the true residual is formed in `q`, the two then trading places. With `start` the
    /// caller has already formed `r = b − A x` (and `q = A x`, the fields holding `x`,
    /// [`residual`](Self::residual)) for this `x`, and the solve starts from it instead of
    /// forming it again. Rows in parallel, partial sums added in row order: the same bits on
    /// any number of threads.
    #[allow(clippy::too_many_arguments)]
    fn solve_jacobi(
        &mut self,
        [mut r, mut q]: [&mut [f64]; 2],
        dinv: &[f64],
        b: &[f64],
        x: &mut [f64],
        tol: f64,
        max_iter: usize,
        start: Start,
    ) -> SolveStats {
        let precondition = |r: &[f64], q: &mut [f64]| jacobi(r, dinv, q);
        // r = b − A x and ‖r‖₂ (the fields then hold x).
        let true_residual = |sys: &mut Self, x: &[f64], r: &mut [f64], q: &mut [f64]| {
            sys.residual(b, x, r, q);
            Norm::L2.of(r)
        };
        let mut res = match start {
            Start::Residual => Norm::L2.of(r),
            Start::Guess => true_residual(self, x, r, q),
        };
        if res == 0.0 {
            return SolveStats {
                iterations: 0,
                residual: res,
                converged: true,
            };
        }
        // z = r/d, r·z; p = z.
        let mut rz = precondition(r, q);
        self.faces.scatter_to(q, &mut self.p);
        let mut it = 0;
        while it < max_iter {
            self.fill_search_ghosts();
            let pq = self.k.product(&self.p, self.dm(), None, q);
            if pq <= 0.0 || !pq.is_finite() {
                break;
            }
            let (rr, mut rz_new) = self.update(rz / pq, dinv, x, r, q);
            res = rr.sqrt();
            it += 1;
            if res <= tol {
                // Confirm with the true residual, formed in q; p waits in r meanwhile.
                self.faces.gather(&self.p, r);
                self.product(x, q);
                par::chunks(&mut *q).for_each(|o, q| {
                    let n = q.len();
                    for (q, b) in q.iter_mut().zip(&b[o..o + n]) {
                        *q = b - *q;
                    }
                });
                res = Norm::L2.of(q);
                if res <= tol {
                    return SolveStats {
                        iterations: it,
                        residual: res,
                        converged: true,
                    };
                }
                std::mem::swap(&mut r, &mut q);
                self.faces.scatter_to(q, &mut self.p);
                rz_new = precondition(r, q);
            }
            let beta = rz_new / rz;
            rz = rz_new;
            // p = z + β p, in the fields.
            self.faces.xpby(q, beta, &mut self.p);
        }
        SolveStats {
            iterations: it,
            residual: res,
            converged: res <= tol,
        }
    }

    /// One pass of the iteration, lines of unknown faces in parallel: `x += α p` (`p` in the
    /// fields), `r −= α q`, `z = r·dinv` over `q`; returns `‖r‖²` and `r·z`, partials added in
    /// line order (u-lines, then v-lines, then w-lines).
    fn update(
        &self,
        alpha: f64,
        dinv: &[f64],
        x: &mut [f64],
        r: &mut [f64],
        q: &mut [f64],
    ) -> (f64, f64) {
        let f = &self.faces;
        let (xs, rs, qs, ds) = (
            f.split_mut(x),
            f.split_mut(r),
            f.split_mut(q),
            f.split(dinv),
        );
        let row = |p: &[f64], d: &[f64], x: &mut [f64], r: &mut [f64], q: &mut [f64]| {
            let n = x.len();
            let (p, d, r, q) = (&p[..n], &d[..n], &mut r[..n], &mut q[..n]);
            for (x, p) in x.iter_mut().zip(p) {
                *x += alpha * p;
            }
            for ((r, q), d) in r.iter_mut().zip(q.iter_mut()).zip(d) {
                *r -= alpha * *q;
                *q = *r * d;
            }
            let (r, q) = (&*r, &*q);
            (par::sum4(n, |k| r[k] * r[k]), par::sum4(n, |k| r[k] * q[k]))
        };
        let add = |s: (f64, f64), p: (f64, f64)| (s.0 + p.0, s.1 + p.1);
        let (mut rr, mut rz) = (0.0, 0.0);
        for ((((a, x), r), q), d) in xs.into_iter().enumerate().zip(rs).zip(qs).zip(ds) {
            let region = f.region(a);
            if region.is_empty() {
                continue;
            }
            let p = &self.p[a];
            let len = region.len(0);
            let (a, b) = par::rows((x, r, q), len).fold(
                (0.0, 0.0),
                |j, (x, r, q)| row(p.at(&region.line(j), [0; 3]), &d[j * len..], x, r, q),
                add,
            );
            (rr, rz) = (rr + a, rz + b);
        }
        (rr, rz)
    }
}

/// What [`ViscousSystem::solve_jacobi`] starts from.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Start {
    /// The initial guess alone: the solve forms its residual.
    Guess,
    /// The initial guess with its residual `r = b − A x` and `q = A x` already formed (the
    /// fields holding `x`).
    Residual,
}

/// `z = r·dinv` over `q`, returning `r·z` (chunk partials added in order).
fn jacobi(r: &[f64], dinv: &[f64], q: &mut [f64]) -> f64 {
    par::chunks(q).fold(
        0.0,
        |o, z| {
            let n = z.len();
            let (r, d) = (&r[o..o + n], &dinv[o..o + n]);
            for ((z, r), d) in z.iter_mut().zip(r).zip(d) {
                *z = r * d;
            }
            let z = &*z;
            par::sum4(n, |k| r[k] * z[k])
        },
        |a, b| a + b,
    )
}

impl<B: VelocityGhosts> LinearOperator for ViscousSystem<B> {
    fn apply(&mut self, x: &[f64], y: &mut [f64]) {
        self.apply_dot(x, y);
    }

    /// The product `x·y` comes from the stencil's own pass.
    fn apply_dot(&mut self, x: &[f64], y: &mut [f64]) -> f64 {
        self.product(x, y)
    }
}

impl WarmStart {
    /// This step's `δ`, in `prev[1]` while the stage runs (the oldest increment once
    /// [`guess`](Self::guess) has read it).
    fn delta(&mut self) -> &mut Vec<f64> {
        &mut self.prev[1]
    }

    /// The initial guess of `δ` into [`delta`](Self::delta): `δ/Δt` extrapolated linearly in
    /// time from the last two steps (from the last one alone after one step; zero at first),
    /// times this step's `Δt`, each entry written over the oldest increment's after reading it.
    fn guess(&mut self, dt: f64) {
        let [d1, d2] = self.prev_dt;
        let (c1, c2) = match self.history {
            0 => (0.0, 0.0),
            1 => (dt / d1, 0.0),
            _ => {
                let w = (dt + d1) / (d1 + d2);
                (dt / d1 * (1.0 + w), -dt / d2 * w)
            }
        };
        let [p1, p2] = &mut self.prev;
        par::chunks(&mut p2[..]).for_each(|o, d| {
            let p1 = &p1[o..o + d.len()];
            for (d, a) in d.iter_mut().zip(p1) {
                *d = c1 * a + c2 * *d;
            }
        });
    }

    /// In a run that stops at a steady state and has come close to one, its `time.steady`:
    /// `δ/Δt` of the last two steps differ by at most `settle` of the newest, in the max norm.
    fn settled(&self) -> Option<f64> {
        let (settle, steady) = self.settle?;
        if self.history < 2 {
            return None;
        }
        let [d1, d2] = self.prev_dt;
        let [p1, p2] = &self.prev;
        let (diff, size) = p1.iter().zip(p2).fold((0.0f64, 0.0f64), |(d, m), (a, b)| {
            let (a, b) = (a / d1, b / d2);
            (d.max((a - b).abs()), m.max(a.abs()))
        });
        (diff <= settle * size).then_some(steady)
    }

    /// Keep this step's `δ` (in [`delta`](Self::delta)) and `Δt` for the next initial guess.
    fn remember(&mut self, dt: f64) {
        self.prev.swap(0, 1);
        self.prev_dt = [dt, self.prev_dt[0]];
        self.history = (self.history + 1).min(2);
        self.remembered += 1;
    }
}

impl<B: VelocityGhosts> ViscousStage<B> {
    /// The stage for the options `o` and the scene's `time.steady` on `grid`, its unknown
    /// `faces` under `bc`, its work vectors reserved in the pipeline's pool `shared` (no block
    /// multigrid).
    fn new(
        steady: Option<f64>,
        o: &ViscousOptions,
        grid: &Grid,
        bc: B,
        faces: UnknownFaces,
        shared: &mut efsi_core::Resources,
    ) -> Self {
        let n = faces.len();
        let mut op = ViscousSystem::new(grid, bc, faces);
        // The search direction's fields are the pipeline's, lent for each run.
        op.p.iter_mut().for_each(|f| *f = Field::default());
        ViscousStage {
            preconditioner: o.preconditioner,
            theta: o.theta,
            tol: o.tolerance,
            max_iter: o.max_iterations,
            op,
            scratch: Scratch::reserve(shared, WORK * n),
            fields: FieldScratch::reserve(shared, grid, grid.dims()),
            warm: WarmStart {
                settle: steady.map(|steady| (SETTLE * o.tolerance, steady)),
                prev: [vec![0.0; n], vec![0.0; n]],
                prev_dt: [0.0; 2],
                history: 0,
                remembered: 0,
            },
            blocks: None,
        }
    }

    /// The right-hand side `Δt·K(V*, θ bⁿ⁺¹ + (1−θ) bⁿ)` into `rhs`, with the boundary
    /// conditions `walls` of the step `[t, t + dt]`; returns its 2-norm. `K` is affine in the
    /// boundary data `b`, so this is the θ-weighted sum of the implicit and explicit parts'
    /// boundary forcing; the stencil with the hoop term as its diagonal gives `−θΔt·K(V*)`.
    fn right_hand_side<F: BorrowMut<Field> + Sync>(
        &self,
        walls: &B,
        [t, dt]: [f64; 2],
        vel: &mut [F],
        rhs: &mut [f64],
    ) -> f64 {
        let when = WallTime::Blend {
            t0: t,
            t1: t + dt,
            theta: self.theta,
        };
        walls.fill(&self.op.grid, vel, when);
        let k = &self.op.k;
        k.product(vel, k.hoop_diag(), None, rhs);
        let scale = -1.0 / self.theta;
        par::chunks(&mut *rhs).for_each(|_, row| {
            row.iter_mut().for_each(|r| *r *= scale);
        });
        dot(rhs, rhs).sqrt()
    }
}

/// The warm start of a solve (in `warm.delta()`) and its tolerance, from the relative
/// tolerance `rel` and the right-hand side's norm `bnorm`. Near a steady state (module docs):
/// the warm start's residual reduced CONTRACT-fold, down to what keeps the solver's error
/// under a share of the steady criterion; a criterion at round-off starts from zero and solves
/// to the strict tolerance (a solve from zero biases the steady state by its error). `r` and
/// `q` are work vectors; where the rule needs the warm start's residual it leaves it there
/// (`r = b − A x`, `q = A x`) and says so ([`Start::Residual`]), for the solve to start from.
fn warm_start<B: VelocityGhosts>(
    warm: &mut WarmStart,
    op: &mut ViscousSystem<B>,
    dt: f64,
    rel: f64,
    bnorm: f64,
    [rhs, r, q]: [&mut [f64]; 3],
) -> (f64, Start) {
    let tol = rel * bnorm;
    let Some(steady) = warm.settled() else {
        warm.guess(dt);
        return (tol, Start::Guess);
    };
    let floor = STEADY_SHARE * steady * dt * op.min_mass();
    if floor < ROUND_OFF * bnorm {
        warm.delta().fill(0.0);
        (tol.min(STRICT_TOLERANCE * bnorm), Start::Guess)
    } else {
        warm.guess(dt);
        op.residual(rhs, warm.delta(), r, q);
        let tol = tol.min(CONTRACT * dot(r, r).sqrt()).max(floor);
        (tol, Start::Residual)
    }
}

impl Stage for ViscousStage {
    /// Forget the warm start's history (a new run starts from zero).
    fn initialize(
        &mut self,
        _grid: &Grid,
        _bc: &BoundarySet,
        _state: &mut State,
    ) -> Result<(), StageError> {
        self.warm.history = 0;
        Ok(())
    }

    /// The warm start's history: `[count, Δt₁, Δt₂]`, then the `count` last increments
    /// (newest first), so that a restored run continues bit for bit.
    fn save(&self) -> Vec<f64> {
        let mut v = Vec::new();
        self.save_into(&mut v);
        v
    }

    fn save_into(&self, out: &mut Vec<f64>) {
        let w = &self.warm;
        out.clear();
        // Room for the longest history at once: no reallocation as the history fills up.
        out.reserve(3 + w.prev.len() * w.prev[0].len());
        out.extend_from_slice(&[w.history as f64, w.prev_dt[0], w.prev_dt[1]]);
        for p in &w.prev[..w.history] {
            out.extend_from_slice(p);
        }
    }

    fn saved_len(&self) -> usize {
        3 + self.warm.history * self.warm.prev[0].len()
    }

    /// `[remembered, count, Δt₁, Δt₂]`, then the older increment only: a step writes its guess
    /// and its increment over that one (its guess reads it) and keeps the newer one, which it
    /// only moves ([`WarmStart::remember`]).
    fn keep_into(&self, out: &mut Vec<f64>) {
        let w = &self.warm;
        out.clear();
        out.reserve(4 + w.prev[1].len());
        out.extend_from_slice(&[
            w.remembered as f64,
            w.history as f64,
            w.prev_dt[0],
            w.prev_dt[1],
        ]);
        out.extend_from_slice(&w.prev[1]);
    }

    /// What [`keep_into`](Stage::keep_into) kept, back: the newer increment moved back if the
    /// step remembered its own, the older one copied back.
    fn undo(&mut self, kept: &[f64]) -> Result<(), String> {
        let w = &mut self.warm;
        let n = w.prev[1].len();
        if kept.len() != 4 + n {
            return Err(format!(
                "expected the viscous warm start's start of step (4 and {n} values), got {} values",
                kept.len()
            ));
        }
        let remembered = kept[0] as u64;
        if w.remembered == remembered + 1 {
            w.prev.swap(0, 1);
        } else if w.remembered != remembered {
            return Err(format!(
                "kept after {remembered} steps, undone after {}",
                w.remembered
            ));
        }
        w.remembered = remembered;
        w.history = kept[1] as usize;
        w.prev_dt = [kept[2], kept[3]];
        w.prev[1].copy_from_slice(&kept[4..]);
        Ok(())
    }

    /// Nothing (a snapshot without a history: the next solve starts from zero), or what
    /// [`save`](Stage::save) wrote.
    fn restore(&mut self, data: &[f64]) -> Result<(), String> {
        let w = &mut self.warm;
        let n = w.prev[0].len();
        if data.is_empty() {
            w.history = 0;
            return Ok(());
        }
        let count = data[0] as usize;
        if data.len() < 3 || count > 2 || data.len() != 3 + count * n {
            return Err(format!(
                "expected the viscous warm start ([count ≤ 2, Δt₁, Δt₂] and count × {n} values), \
                 got {} values",
                data.len()
            ));
        }
        w.history = count;
        w.prev_dt = [data[1], data[2]];
        for (k, p) in w.prev[..count].iter_mut().enumerate() {
            p.copy_from_slice(&data[3 + k * n..3 + (k + 1) * n]);
        }
        Ok(())
    }

    fn run(&mut self, ctx: &StepContext, state: &mut State) -> Result<StageStats, StageError> {
        let State {
            u, v, w, mu, rho, ..
        } = state;
        let time = [ctx.t, ctx.dt];
        let stats = match w {
            Some(w) => self.step(ctx.bc, time, &mut [u, v, w], mu, rho),
            None => self.step(ctx.bc, time, &mut [u, v], mu, rho),
        }?;
        Ok(StageStats { solve: Some(stats) })
    }
}

impl<B: VelocityGhosts> ViscousStage<B> {
    /// One viscous step `[t, t + dt]` (`time`) of the velocity `vel` (one field per axis) with
    /// the cell viscosities `mu` and densities `rho` (ghosts filled) under the boundary
    /// conditions `walls`: the system assembled, the warm start, the solve, `vel += δ`; the
    /// search direction's fields borrowed from the pipeline's pool for it, zeroed.
    fn step<F: BorrowMut<Field> + Sync>(
        &mut self,
        walls: &B,
        time: [f64; 2],
        vel: &mut [F],
        mu: &Field,
        rho: &Field,
    ) -> Result<SolveStats, StageError> {
        let fields = self.fields.clone();
        fields.swap(&mut self.op.p, true);
        let stats = self.step_in(walls, time, vel, mu, rho);
        fields.swap(&mut self.op.p, false);
        stats
    }

    /// [`step`](Self::step) with the search direction's fields in place.
    fn step_in<F: BorrowMut<Field> + Sync>(
        &mut self,
        walls: &B,
        [t, dt]: [f64; 2],
        vel: &mut [F],
        mu: &Field,
        rho: &Field,
    ) -> Result<SolveStats, StageError> {
        let scratch = self.scratch.clone();
        let mut pool = scratch.lock();
        let [rhs, diag, r, q] = scratch::take::<WORK>(&mut pool, self.op.faces.len());
        self.op.theta_dt = self.theta * dt;
        self.op.assemble(mu, rho, diag);
        let bnorm = self.right_hand_side(walls, [t, dt], vel, rhs);
        let op = &mut self.op;
        let stats = if bnorm == 0.0 {
            self.warm.delta().fill(0.0);
            self.warm.remember(dt);
            SolveStats {
                iterations: 0,
                residual: 0.0,
                converged: true,
            }
        } else {
            let (tol, start) = warm_start(
                &mut self.warm,
                op,
                dt,
                self.tol,
                bnorm,
                [&mut *rhs, &mut *r, &mut *q],
            );
            let use_mg =
                use_block_multigrid(self.preconditioner, || op.max_diag_to_mass(rho, diag));
            let blocks = self.blocks.as_mut().filter(|_| use_mg);
            let delta = &mut self.warm.prev[1];
            let st = if let Some(blocks) = blocks {
                blocks.setup(&op.k, diag);
                // The blocks hold the diagonal now: its vector is the solver's third.
                solve_norm_in(
                    [r, diag, q],
                    op,
                    &*blocks,
                    rhs,
                    delta,
                    tol,
                    self.max_iter,
                    Norm::L2,
                    NullSpace::None,
                )
            } else {
                // The reciprocal of the diagonal, in place.
                par::chunks(&mut *diag).for_each(|_, d| d.iter_mut().for_each(|d| *d = 1.0 / *d));
                op.solve_jacobi([r, q], diag, rhs, delta, tol, self.max_iter, start)
            };
            // A solve short of the tighter stop near a steady state but within the tolerance
            // is converged.
            if !st.converged && st.residual > self.tol * bnorm {
                // The failed solve's iterate is where the oldest increment was: the history
                // keeps the newest one only.
                self.warm.history = self.warm.history.min(1);
                return Err(StageError {
                    stage: "viscous".into(),
                    message: crate::verdict::unconverged(
                        "conjugate gradient",
                        st.iterations,
                        st.residual / bnorm,
                        self.tol,
                        "numerics.viscous.tolerance",
                        "numerics.viscous.max_iterations",
                        "raise numerics.viscous.max_iterations or reduce the time step",
                        "the viscous system is not positive definite or too ill-conditioned: \
                         check the viscosities and densities, or reduce the time step",
                    ),
                });
            }
            op.faces.add(delta, vel);
            self.warm.remember(dt);
            SolveStats {
                residual: st.residual / bnorm,
                converged: true,
                ..st
            }
        };
        Ok(stats)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::viscous::box_ghosts::BoxGhosts;
    use efsi_core::grid::Geometry;
    use efsi_core::scene::{Boundaries, Boundary};

    /// The stage's own Jacobi CG (search direction in the fields, `z = r·(1/d)`) gives the
    /// iterates of the generic Jacobi-PCG to rounding, in the same number of iterations.
    #[test]
    fn the_field_jacobi_cg_matches_the_generic_one() {
        let grid = Grid::new(Geometry::Axisymmetric, 24, 20, (0.0, 1.0), (0.0, 0.8));
        let b = Boundaries::planar(
            Boundary::Axis,
            Boundary::NoSlip,
            Boundary::NoSlip,
            Boundary::FreeSlip,
        );
        let bc = BoundarySet::new(&b, &grid);
        let faces = UnknownFaces::new(&grid, &bc);
        let n = faces.len();
        let (mut mu, mut rho) = (Field::zeros(&grid), Field::zeros(&grid));
        let m = mu.data().len();
        for (k, (mu, rho)) in mu.data_mut().iter_mut().zip(rho.data_mut()).enumerate() {
            let inside = (k * 7919) % m < m / 3;
            *mu = if inside { 1e-2 } else { 2e-4 };
            *rho = if inside { 1.0 } else { 1e-3 };
        }
        bc.fill_scalar(&grid, &mut mu, false);
        bc.fill_scalar(&grid, &mut rho, false);
        let mut sys = ViscousSystem::new(&grid, bc.clone(), faces);
        sys.theta_dt = 0.01;
        let mut diag = vec![0.0; n];
        sys.assemble(&mu, &rho, &mut diag);
        let rhs: Vec<f64> = (0..n)
            .map(|k| ((k * 2654435761) % 1000) as f64 / 500.0 - 1.0)
            .collect();
        let tol = 1e-10 * dot(&rhs, &rhs).sqrt();
        let (mut r, mut p, mut q) = (vec![0.0; n], vec![0.0; n], vec![0.0; n]);
        let mut x1 = vec![0.0; n];
        let work = [&mut r[..], &mut p[..], &mut q[..]];
        let s1 = solve_norm_in(
            work,
            &mut sys,
            diag.as_slice(),
            &rhs,
            &mut x1,
            tol,
            500,
            Norm::L2,
            NullSpace::None,
        );
        let dinv: Vec<f64> = diag.iter().map(|d| 1.0 / d).collect();
        let mut x2 = vec![0.0; n];
        let work = [&mut r[..], &mut q[..]];
        let s2 = sys.solve_jacobi(work, &dinv, &rhs, &mut x2, tol, 500, Start::Guess);
        assert!(s1.converged && s2.converged, "{s1:?} {s2:?}");
        assert!(s1.iterations.abs_diff(s2.iterations) <= 1, "{s1:?} {s2:?}");
        let scale = x1.iter().fold(0.0f64, |a, x| a.max(x.abs()));
        for (a, b) in x1.iter().zip(&x2) {
            assert!((a - b).abs() <= 1e-8 * scale, "{a} vs {b}");
        }
    }

    /// A solve told that its guess's residual is already formed (`Start::Residual`, as the
    /// warm start near a steady state leaves it) takes the same iterates, bit for bit, as one
    /// that forms it itself.
    #[test]
    fn a_solve_from_a_formed_residual_matches_one_from_the_guess() {
        let grid = Grid::new(Geometry::Planar, 12, 10, (0.0, 1.0), (0.0, 0.8));
        let b = Boundaries::planar(
            Boundary::NoSlip,
            Boundary::NoSlip,
            Boundary::NoSlip,
            Boundary::FreeSlip,
        );
        let bc = BoundarySet::new(&b, &grid);
        let faces = UnknownFaces::new(&grid, &bc);
        let n = faces.len();
        let mu = Field::filled(&grid, 1e-2);
        let rho = Field::filled(&grid, 1.0);
        let mut sys = ViscousSystem::new(&grid, bc, faces);
        sys.theta_dt = 0.05;
        let mut diag = vec![0.0; n];
        sys.assemble(&mu, &rho, &mut diag);
        let dinv: Vec<f64> = diag.iter().map(|d| 1.0 / d).collect();
        let rhs: Vec<f64> = (0..n).map(|k| ((k * 37) % 11) as f64 - 5.0).collect();
        let guess: Vec<f64> = (0..n).map(|k| ((k * 13) % 7) as f64 * 0.1).collect();
        let tol = 1e-9 * dot(&rhs, &rhs).sqrt();
        let mut solve = |start: Start| {
            let (mut r, mut q) = (vec![0.0; n], vec![0.0; n]);
            let mut x = guess.clone();
            if start == Start::Residual {
                sys.residual(&rhs, &x, &mut r, &mut q);
            }
            let st = sys.solve_jacobi([&mut r, &mut q], &dinv, &rhs, &mut x, tol, 500, start);
            (st, x)
        };
        let (s1, x1) = solve(Start::Guess);
        let (s2, x2) = solve(Start::Residual);
        assert!(s1.converged && s1.iterations > 3, "{s1:?}");
        assert_eq!(
            (s1.iterations, s1.residual.to_bits()),
            (s2.iterations, s2.residual.to_bits())
        );
        assert!(x1.iter().zip(&x2).all(|(a, b)| a.to_bits() == b.to_bits()));
    }

    /// A viscous stage on a three-dimensional grid whose ghosts `walls` fills, strict
    /// tolerance, Jacobi.
    fn stage_3d(grid: &Grid, walls: BoxGhosts) -> ViscousStage<BoxGhosts> {
        let o = ViscousOptions {
            tolerance: 1e-10,
            ..ViscousOptions::default()
        };
        let faces = UnknownFaces::with_ranges(grid, &walls.ranges(grid));
        let mut shared = efsi_core::Resources::default();
        ViscousStage::new(None, &o, grid, walls, faces, &mut shared)
    }

    /// `f(x)` at the positions of the faces normal to axis `a` (ghosts included).
    fn face_field(grid: &Grid, a: usize, f: impl Fn([f64; 3]) -> f64) -> Field {
        let mut out = Field::zeros(grid);
        let h = grid.h();
        for q in 0..out.data().len() {
            let i = out.index_of(q);
            let x = [0, 1, 2].map(|d| (i[d] as f64 + if d == a { 0.0 } else { 0.5 }) * h[d]);
            out.data_mut()[q] = f(x);
        }
        out
    }

    /// A backward-Euler step of a divergence-free shear mode in a periodic cube with constant
    /// coefficients: each component is an eigenvector of the discrete operator, so one
    /// iteration lands on the exact discrete decay `1/(1 + Δt ν λ_h)`.
    #[test]
    fn a_three_dimensional_shear_mode_decays_at_the_discrete_rate() {
        let n = 16;
        let grid = Grid::new_3d([n; 3], (0.0, 1.0), (0.0, 1.0), (0.0, 1.0));
        let walls = BoxGhosts {
            periodic: [true; 3],
        };
        let mut stage = stage_3d(&grid, walls);
        let k = 2.0 * std::f64::consts::PI;
        let mode = |a: usize, x: [f64; 3]| {
            let (p, q) = match a {
                0 => (1, 2),
                1 => (0, 2),
                _ => (0, 1),
            };
            (k * x[p]).sin() * (k * x[q]).sin()
        };
        let mut vel: Vec<Field> = (0..3)
            .map(|a| face_field(&grid, a, |x| mode(a, x)))
            .collect();
        let start = vel.clone();
        let (nu, dt) = (0.05, 0.01);
        let (mu, rho) = (Field::filled(&grid, nu), Field::filled(&grid, 1.0));
        let st = stage.step(&walls, [0.0, dt], &mut vel, &mu, &rho).unwrap();
        assert_eq!(st.iterations, 1, "{st:?}");
        let h = 1.0 / n as f64;
        let lambda = 2.0 * 4.0 * (std::f64::consts::PI * h).sin().powi(2) / (h * h);
        let decay = 1.0 / (1.0 + dt * nu * lambda);
        let faces = stage.op.faces;
        faces.for_each_axis(|_, a, q| {
            let (v, v0) = (vel[a].data()[q], start[a].data()[q]);
            assert!(
                (v - decay * v0).abs() <= 1e-12,
                "axis {a}: {v} vs {}",
                decay * v0
            );
        });
    }

    /// The implicit step of a three-dimensional flow with walls on four sides and a heavy,
    /// viscous blob in a light fluid converges to the tolerance in a fixed number of
    /// iterations, the same bits on one and two threads; the true residual of the solution
    /// is checked apart from the solver.
    #[test]
    fn a_three_dimensional_implicit_step_converges_to_the_tolerance() {
        let grid = Grid::new_3d([12, 10, 8], (0.0, 1.2), (0.0, 1.0), (0.0, 0.8));
        let walls = BoxGhosts {
            periodic: [true, false, false],
        };
        let blob = |x: [f64; 3]| {
            let r2 = (x[0] - 0.6).powi(2) + (x[1] - 0.5).powi(2) + (x[2] - 0.4).powi(2);
            r2 < 0.09
        };
        let cell = |f: &dyn Fn([f64; 3]) -> f64| {
            let mut c = Field::zeros(&grid);
            let h = grid.h();
            for q in 0..c.data().len() {
                let i = c.index_of(q);
                c.data_mut()[q] = f([0, 1, 2].map(|d| (i[d] as f64 + 0.5) * h[d]));
            }
            walls.fill_scalar(&grid, &mut c);
            c
        };
        let mu = cell(&|x| if blob(x) { 1e-2 } else { 2e-4 });
        let rho = cell(&|x| if blob(x) { 1.0 } else { 1e-3 });
        let k = 2.0 * std::f64::consts::PI;
        let start: Vec<Field> = (0..3)
            .map(|a| {
                face_field(&grid, a, |x| {
                    (k * x[0] / 1.2 + a as f64).sin()
                        * (3.0 * x[1]).cos()
                        * (2.0 * x[2] + 0.3 * a as f64).sin()
                })
            })
            .collect();
        let run = |threads: usize, multigrid: bool| {
            let mut stage = stage_3d(&grid, walls);
            if multigrid {
                stage.preconditioner = ViscousPreconditioner::Multigrid;
                let faces = stage.op.faces;
                stage.blocks = Some(ViscousBlocks::on(&grid, faces, walls.periodic));
            }
            let mut vel = start.clone();
            walls.fill(&grid, &mut vel, WallTime::Homogeneous);
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap();
            let st = pool
                .install(|| stage.step(&walls, [0.0, 0.01], &mut vel, &mu, &rho))
                .unwrap();
            (st, vel, stage)
        };
        let (st, vel, mut stage) = run(1, false);
        assert!(st.converged && st.residual <= 1e-10, "{st:?}");
        assert_eq!(st.iterations, 23, "{st:?}");
        let same = |p: &[Field], q: &[Field]| {
            p.iter().zip(q).all(|(a, b)| {
                a.data()
                    .iter()
                    .zip(b.data())
                    .all(|(a, b)| a.to_bits() == b.to_bits())
            })
        };
        let (st2, vel2, _) = run(2, false);
        assert_eq!(st2.iterations, st.iterations);
        assert!(same(&vel, &vel2));
        // The seven-point block multigrid: fewer iterations to the same tolerance, the same
        // increment to it, the same bits on one and two threads.
        let (mg, vel_mg, _) = run(1, true);
        assert!(mg.converged && mg.residual <= 1e-10, "{mg:?}");
        assert_eq!(mg.iterations, 12, "{mg:?}");
        let (mg2, vel_mg2, _) = run(2, true);
        assert_eq!(mg2.iterations, mg.iterations);
        assert!(same(&vel_mg, &vel_mg2));
        let diff = vel.iter().zip(&vel_mg).fold(0.0f64, |m, (a, b)| {
            a.data()
                .iter()
                .zip(b.data())
                .fold(m, |m, (a, b)| m.max((a - b).abs()))
        });
        assert!(
            diff <= 1e-8,
            "Jacobi and multigrid increments differ by {diff}"
        );
        // The true residual: A δ against Δt K(V*), δ = V − V*.
        let faces = stage.op.faces;
        let n = faces.len();
        let (mut v0, mut v1) = (vec![0.0; n], vec![0.0; n]);
        let mut moved = start.clone();
        walls.fill(&grid, &mut moved, WallTime::Homogeneous);
        faces.gather(&moved, &mut v0);
        faces.gather(&vel, &mut v1);
        let delta: Vec<f64> = v1.iter().zip(&v0).map(|(a, b)| a - b).collect();
        let mut b = vec![0.0; n];
        let bnorm = stage.right_hand_side(&walls, [0.0, 0.01], &mut moved, &mut b);
        let (mut ad, mut diag) = (vec![0.0; n], vec![0.0; n]);
        stage.op.assemble(&mu, &rho, &mut diag);
        // The search direction's fields, which the product works in, from the pool.
        let fields = stage.fields.clone();
        fields.swap(&mut stage.op.p, true);
        stage.op.product(&delta, &mut ad);
        let r = ad
            .iter()
            .zip(&b)
            .map(|(a, b)| (a - b).powi(2))
            .sum::<f64>()
            .sqrt();
        assert!(r <= 1.01e-10 * bnorm, "residual {r:e} of {bnorm:e}");
        assert!(delta.iter().any(|d| d.abs() > 1e-6 * bnorm));
    }
}
