//! The coupled elastic step (`numerics.elastic.coupling: Coupled`, and `Auto`'s long steps):
//! the implicit viscous–elastic system solved together with the divergence constraint.
//!
//! # The system
//!
//! With `A = M − θ_v Δt K_v − αθΔt² K_J` the elastic step's operator (mass, implicit viscous
//! and elastic stiffness on the unknown faces; the parent module), `Ĝ` the discrete gradient
//! scaled by the face areas and `F = −Ĝᵀ` the net outflux of a cell, the split step solves
//! `A δ = b` and then projects with the mass alone, `M δ_p = −Δt Ĝ p`, `F(V + δ + δ_p) = 0`.
//! Its correction `δ_p` strains the solid (`B̃^{n+1}` is stretched by it) without the solid's
//! stiffness answering within the step: the strain is stored at stiffness G and given back
//! the next step, which pumps energy into a stiff solid once the shear wave crosses a few
//! cells a step — hence the split step's cap `wave_courant`. The coupled step solves for the
//! velocity increment and the pressure at once,
//!
//! ```text
//!   [ A          Δt Ĝ ] [δ]   [ b                 ]
//!   [ ω (Δt/dV) F   0 ] [p] = [ −ω (Δt/dV) F(V*)  ]      (V* the velocity before the step)
//! ```
//!
//! so that `V* + δ` is divergence-free and `B̃(V* + δ)` is the deformation the stiffness was
//! solved with. The continuity rows measure `Δt ∇·V` (the projection tolerance's unit) and are
//! weighted by `ω = tol_u / (tol_div √N)`, so that a uniform divergence at its tolerance weighs
//! as much as the momentum residual at its own (`N` cells). The projection sub-step then
//! removes what divergence is left with the mass alone, solving for an increment from zero and
//! adding it to this pressure.
//!
//! # The solve
//!
//! Right-preconditioned flexible GMRES ([`efsi_linalg::Fgmres`], Saad 1993) from no increment
//! and the pressure the last step ended with, with the block upper-triangular preconditioner
//! `P = [Â, ΔtĜ; 0, −Ŝ]`: with exact blocks `K P⁻¹` has the single eigenvalue 1 and a minimal
//! polynomial of degree 2. `Â⁻¹` is one application of the elastic step's own preconditioner
//! (the block multigrid V-cycle on the effective-viscosity operator, or Jacobi); `Ŝ⁻¹` is
//! Cahouet & Chabard's (1988) approximation of the Schur complement for unsteady Stokes: per
//! unit volume `A ≈ ρ − η Δ` with `η = θ_v Δt μ + αθΔt² G_eff` (the block multigrid's
//! effective viscosity), and on a gradient `A ∇q = ∇(ρ q − 2η Δq)`, so
//!
//! ```text
//!   S⁻¹ ≈ Δt⁻¹ (ρ Δ⁻¹ + 2η)   ⇒   q = s − (2η/Δt) ∇·V,   ∇·(∇s/ρ) = ∇·V/Δt
//! ```
//!
//! — one multigrid V-cycle of the projection's Poisson operator (`crate::projection`'s
//! matrix) plus a local term: exact for uniform coefficients, and in a fluid (`G_eff = 0`) the
//! viscous-coupled projection. Because `Ŝ` carries the elastic term, the iterations stay
//! bounded at any G and any wave Courant number. Plain Uzawa (Richardson) with the same
//! preconditioner is not enough: a cell with a sliver of solid has air's mass but stiff faces,
//! and the preconditioned spectrum spreads over (0, 3] there.
//!
//! The solve stops when the true residual meets both targets: the momentum residual's 2-norm
//! `numerics.elastic.tolerance` × the split solve's scale, and `max |Δt ∇·V|` the larger of
//! the projection's tolerance and `coupling_tolerance` × the step's divergence scale (that of
//! `V*` or of the explicit elastic increment `M⁻¹ b`, whichever is larger). Each iteration
//! costs one product with `A` (plus a gradient and a divergence), one block-multigrid cycle
//! and one Poisson cycle. A solve that does not converge in `coupling_iterations` is an error
//! with `Coupled`; `Auto` retakes the step split.
//!
//! FGMRES restarts after [`RESTART`] = 60 vectors (the workspace holds `2·60 + 1` vectors of
//! the system's size). While a stiff solid presses on a wall the preconditioned spectrum is
//! spread (the slivers of solid in the wall row) and a cycle of 30 vectors does not span what
//! the next one needs: restarted GMRES then stalls, every cycle leaving the residual where it
//! found it (the 3-D stability map's quarter sphere at G = 1e9 and 1e11 Pa, 4 cells per
//! radius, `cargo xtask bench-paper --case stability_3d`).
//!
//! # The stress at θ
//!
//! The coupled step weights the stress as its stretching weights the velocity: with
//! `B(V) = Bⁿ + E + θΔt H(V; Bⁿ)` it solves `ρ δ/Δt = ∇·[θ τ(B(V)) + (1 − θ) τ(Bⁿ)]` (α = θ,
//! linearised about `B^{n+1/3}` as the split step is). Why: take the 1-D model of a solid in
//! contact, a mass m on a spring k (x the strain, v the velocity), stretched as B is and pushed
//! as the momentum step pushes,
//!
//! ```text
//!   x⁺ = x + Δt (θ v⁺ + (1 − θ) v),      m (v⁺ − v) = −Δt k (α x⁺ + (1 − α) x).
//! ```
//!
//! With `y = (v, x)`, the energy `E = ½⟨y, y⟩ = ½ m v² + ½ k x²` and `A y = (−k x/m, v)`,
//! `⟨A y, y⟩ = 0`. For α = θ the step is the θ-method `Δy = Δt A y_θ`,
//! `y_θ = θ y⁺ + (1 − θ) y = ȳ + (θ − ½) Δy` (`ȳ` the mean of y and y⁺), so
//!
//! ```text
//!   E⁺ − E = ⟨Δy, ȳ⟩ = ⟨Δy, y_θ⟩ − (θ − ½) |Δy|² = −(θ − ½) (m Δv² + k Δx²):
//! ```
//!
//! nothing gained for θ ≥ ½, nothing lost at θ = ½ (the midpoint rule). With the stress at the
//! step's end (α = 1) at θ = ½ the step loses `½ k Δx²` besides — as much as it stores when a
//! compression happens within one step. The 1-D wave's amplification is
//! `((1 + (1 − θ)² s²)/(1 + θ² s²))^{1/2}`: 1 at θ = ½ for every s; at θ = ¾ 0.998, 0.825,
//! 0.62, 0.41, 0.34, 0.33 at s = 0.1, 1, 2, 5, 20, ∞. The model holds for a linear law away
//! from the interface; the law's nonlinearity, B's advection and the VOF step moving φ under a
//! fixed B are outside it.
//!
//! # Limits
//!
//! The coupled step is stable far beyond the split step's cap; Δt is capped at
//! `coupled_wave_courant` elastic-wave Courant numbers `Δt·c/h` for accuracy:
//!
//! - **A contact taken in a few steps loses its rebound.** A stiff solid touches a wall for a
//!   time far below a step at tens of wave Courant numbers. Within such a step the θ-method
//!   loses `(θ − ½)|Δy|²` (above), most of the impact's energy; and the wall row's cell under
//!   the solid, holding a sliver of solid, takes the whole cell's rate of the squeezed fluid
//!   (iso-strain, parent module "The interface") at the stiffness `φ^{1/2} G`. θ = ½ loses
//!   nothing in the 1-D model but lets the sliver and B's advection feed energy back: it is not
//!   for coupled steps that take a contact. `Auto` takes contacts with split steps
//!   ([`super::AUTO_WALL_CELLS`]); `tests/tests/elastic.rs`
//!   (`coupled_step_with_the_stress_at_its_theta_keeps_more_of_an_impact`) asserts the rebound
//!   the default keeps.
//! - **Flight.** Away from walls a long coupled step costs the time error of any step of that
//!   length (first order in time for the solid) and stores no strain from a rigid motion (the
//!   fluid's B is reset before the rates are taken, parent module "Pure fluid"):
//!   `tests/tests/elastic.rs` (`a_stiff_sphere_falls_at_a_large_coupled_cap_without_storing_strain`,
//!   `a_stiff_disk_spins_rigidly_at_large_wave_courant_numbers_with_the_coupled_step`).
//!
//! # References
//!
//! - Y. Saad, SIAM J. Sci. Comput. 14 (1993) 461 — flexible GMRES.
//! - J. Cahouet, J.-P. Chabard, Int. J. Numer. Methods Fluids 8 (1988) 869 — the Schur
//!   complement preconditioner of unsteady Stokes.

use super::ElasticPreconditioner;
use super::err;
use super::solve::{ElasticStage, OperatorCtx};
use crate::block_multigrid::ViscousBlocks;
use crate::faces::UnknownFaces;
use crate::projection;
use efsi_core::operators::minus;
use efsi_core::{BoundarySet, Field, Grid, Region, StageError, Stagger, State, StepContext, unit};
use efsi_linalg::par;
use efsi_linalg::{
    Accept, Fgmres, FlexiblePreconditioner, LinearOperator, Multigrid, Preconditioner, SolveStats,
    Stencil5,
};

/// Krylov vectors kept before FGMRES restarts (the module docs' "The solve": why so many).
const RESTART: usize = 60;

/// The coupled step's work space: the saddle-point system's vectors, the projection's Poisson
/// system and its multigrid, FGMRES.
pub(super) struct Coupling {
    /// Stop when the divergence left is this fraction of the step's divergence scale (scene
    /// `numerics.elastic.coupling_tolerance`), or the projection's tolerance.
    rel_tol: f64,
    proj_tol: f64,
    max_iter: usize,
    poisson: Stencil5,
    mg: Multigrid,
    fgmres: Fgmres,
    /// `[b; c]` and `[δ; p]`: per unknown face, then per cell.
    rhs: Vec<f64>,
    x: Vec<f64>,
    /// Per cell: `Δt/dV`, and the Poisson right-hand side and solution of the preconditioner.
    dt_vol: Vec<f64>,
    pb: Vec<f64>,
    ps: Vec<f64>,
    /// Per unknown face: the preconditioner's velocity right-hand side.
    ru: Vec<f64>,
    /// A pressure as a cell field with ghosts (for its gradient), one for the operator and one
    /// for the preconditioner.
    q: Field,
    qp: Field,
    /// The Δt of `dt_vol` (it changes only with Δt).
    weight_dt: f64,
}

impl Coupling {
    pub(super) fn new(
        grid: &Grid,
        bc: &BoundarySet,
        faces: usize,
        el: &super::ElasticOptions,
        proj_tol: f64,
    ) -> Self {
        let n = grid.cells();
        Coupling {
            rel_tol: el.coupling_tolerance,
            proj_tol,
            max_iter: el.coupling_iterations,
            poisson: if grid.is_3d() {
                let periodic = projection::three_d::periodic_axes(bc, grid);
                Stencil5::new_3d(grid.nx, grid.ny, grid.nz, periodic)
            } else {
                Stencil5::new(grid.nx, grid.ny, bc.periodic(0), bc.periodic(1))
            },
            mg: Multigrid::new(2),
            fgmres: Fgmres::new(faces + n, RESTART),
            rhs: vec![0.0; faces + n],
            x: vec![0.0; faces + n],
            dt_vol: vec![0.0; n],
            pb: vec![0.0; n],
            ps: vec![0.0; n],
            ru: vec![0.0; faces],
            q: Field::zeros(grid),
            qp: Field::zeros(grid),
            weight_dt: f64::NAN,
        }
    }
}

/// `y += c Ĝ q` on the unknown faces (`Ĝ q` = face area × the jump of `q` across the face, so
/// that `F = −Ĝᵀ` for the net outflux `F`), `q` a cell field whose ghosts are filled.
fn add_gradient(faces: &UnknownFaces, g: &Grid, q: &Field, c: f64, y: &mut [f64]) {
    let (m, area) = (&g.metric, face_areas(g));
    // The faces normal to axis a, between the cells I − e_a and I, of area `r A_a` (x-faces,
    // r = r_f; the others r = r_c; `A_a` the product of the other axes' cell sizes).
    for (a, y) in faces.split_mut(y).into_iter().enumerate().take(g.dims()) {
        let r = faces.region(a);
        if r.is_empty() {
            continue;
        }
        let h = area[a];
        par::rows(y, r.len(0)).for_each(|n, row| {
            let l = r.line(n);
            let (lo, hi) = (q.at(&l, minus(a)), q.at(&l, [0; 3]));
            let area = if a == 0 {
                m.rx_on(&l, 0)
            } else {
                m.rc_on(&l, 0)
            };
            for (n, y) in row.iter_mut().enumerate() {
                *y += c * area[n] * h * (hi[n] - lo[n]);
            }
        });
    }
}

/// The area of a face normal to each axis, `Π_{b≠a} h_b` over the grid's axes (the radius
/// aside).
fn face_areas(g: &Grid) -> [f64; 3] {
    let (h, dims) = (g.h(), g.dims());
    std::array::from_fn(|a| {
        let mut o = (0..dims).filter(|&b| b != a);
        let first = o.next().map_or(1.0, |b| h[b]);
        o.fold(first, |s, b| s * h[b])
    })
}

/// `out = c (Δt/dV) F(V)` per cell (`dt_vol` = Δt/dV, `F` the net outflux of the velocity
/// `vel`, one field per axis: `Σ_a A_a (r u_a(I + e_a) − r u_a(I))`), lines in parallel.
fn outflux_per_volume(g: &Grid, vel: &[&Field], dt_vol: &[f64], c: f64, out: &mut [f64]) {
    let (m, area, cells) = (&g.metric, face_areas(g), Region::of(g, Stagger::Cell));
    par::rows(&mut *out, g.nx).for_each(|r, row| {
        let l = cells.line(r);
        let (rlo, rhi, rc) = (m.rx_on(&l, 0), m.rx_on(&l, 1), m.rc_on(&l, 0));
        let (u0, u1) = (vel[0].at(&l, [0; 3]), vel[0].at(&l, unit(0)));
        let dt_vol = &dt_vol[r * l.len..];
        for (n, y) in row.iter_mut().enumerate() {
            let mut f = (rhi[n] * u1[n] - rlo[n] * u0[n]) * area[0];
            for (b, v) in vel.iter().enumerate().skip(1) {
                let (v0, v1) = (v.at(&l, [0; 3]), v.at(&l, unit(b)));
                f += rc[n] * (v1[n] - v0[n]) * area[b];
            }
            *y = c * dt_vol[n] * f;
        }
    });
}

/// Copy a per-cell vector into a cell field and fill its ghosts (homogeneous).
fn to_field(g: &Grid, bc: &BoundarySet, x: &[f64], f: &mut Field) {
    Region::of(g, Stagger::Cell).for_each(&mut *f, |l, row| {
        row.copy_from_slice(&x[l.n * l.len..][..l.len]);
    });
    bc.fill_scalar(g, f, true);
}

/// The saddle-point operator `[A, ΔtĜ; ω (Δt/dV) F, 0]` on `[δ; p]`.
struct Saddle<'a> {
    a: OperatorCtx<'a>,
    grid: &'a Grid,
    bc: &'a BoundarySet,
    dt: f64,
    omega: f64,
    dt_vol: &'a [f64],
    q: &'a mut Field,
    nf: usize,
}

impl LinearOperator for Saddle<'_> {
    fn apply(&mut self, x: &[f64], y: &mut [f64]) {
        let (xd, xp) = x.split_at(self.nf);
        let (yu, yc) = y.split_at_mut(self.nf);
        // A δ; the operator leaves δ scattered, ghosts filled, in its scratch fields.
        self.a.apply(xd, yu);
        let (g, om) = (self.grid, self.omega);
        let vel = super::velocity(&*self.a.xu, &*self.a.xv, self.a.xw.as_deref());
        outflux_per_volume(g, &vel, self.dt_vol, om, yc);
        to_field(g, self.bc, xp, self.q);
        add_gradient(&self.a.op.ks[0].faces, g, self.q, self.dt, yu);
    }
}

/// The velocity block's approximate inverse: the elastic step's preconditioner.
enum VelocityBlock<'a> {
    Jacobi(&'a [f64]),
    Multigrid(&'a ViscousBlocks),
}

/// The block upper-triangular preconditioner `[Â, ΔtĜ; 0, −Ŝ]⁻¹`: the pressure from the
/// Cahouet–Chabard approximation of the Schur complement (one multigrid cycle of the
/// projection's Poisson operator plus the local term `2η/Δt`), then the velocity from one
/// application of the elastic step's preconditioner to `r_u − ΔtĜ p`.
struct BlockTriangular<'a> {
    a: VelocityBlock<'a>,
    faces: &'a UnknownFaces,
    poisson: &'a Multigrid,
    eta: &'a Field,
    grid: &'a Grid,
    bc: &'a BoundarySet,
    dt: f64,
    omega: f64,
    singular: bool,
    pb: &'a mut [f64],
    ps: &'a mut [f64],
    ru: &'a mut [f64],
    qp: &'a mut Field,
    nf: usize,
}

impl FlexiblePreconditioner for BlockTriangular<'_> {
    fn apply(&mut self, r: &[f64], z: &mut [f64]) {
        let (ru, rc) = r.split_at(self.nf);
        let (zu, zp) = z.split_at_mut(self.nf);
        let (g, dt, om) = (self.grid, self.dt, self.omega);
        let nx = g.nx;
        // The pressure: with the flux residual v = dV r_c/(ωΔt), solve the Poisson equation
        // `−dV ∇·(∇s/ρ) = v/Δt` (one cycle) and add `2η v/(Δt dV)`.
        par::rows(&mut *self.pb, nx).for_each(|j, row| {
            for (i, b) in row.iter_mut().enumerate() {
                *b = g.cell_volume(i as isize) * rc[j * nx + i] / (om * dt * dt);
            }
        });
        if self.singular {
            let mean = self.pb.iter().sum::<f64>() / self.pb.len() as f64;
            self.pb.iter_mut().for_each(|b| *b -= mean);
        }
        self.poisson.apply(self.pb, self.ps);
        let (ps, eta, cells) = (&*self.ps, self.eta, Region::of(g, Stagger::Cell));
        par::rows(&mut *zp, nx).for_each(|j, row| {
            let eta = eta.at(&cells.line(j), [0; 3]);
            for (i, z) in row.iter_mut().enumerate() {
                let c = j * nx + i;
                *z = ps[c] + 2.0 * eta[i] * rc[c] / (om * dt * dt);
            }
        });
        // The velocity: Â⁻¹ (r_u − ΔtĜ p).
        to_field(g, self.bc, zp, self.qp);
        self.ru.copy_from_slice(ru);
        add_gradient(self.faces, g, self.qp, -dt, self.ru);
        match self.a {
            VelocityBlock::Jacobi(d) => {
                for ((z, r), d) in zu.iter_mut().zip(self.ru.iter()).zip(d) {
                    *z = r / d;
                }
            }
            VelocityBlock::Multigrid(m) => m.apply(self.ru, zu),
        }
    }
}

impl ElasticStage {
    /// The coupled step in place of the split solve (see the module docs): FGMRES on the
    /// saddle-point system for the velocity increment and the pressure, both applied; the
    /// projection sub-step removes what divergence is left and adds its pressure.
    pub(super) fn solve_coupled(
        &mut self,
        ctx: &StepContext,
        state: &mut State,
        d: &[super::Deformation],
        bnorm: f64,
        scale: f64,
    ) -> Result<SolveStats, StageError> {
        let Some(mut cp) = self.coupling.take() else {
            return Err(err("elastic", "the coupled step has no work space".into()));
        };
        let r = self.solve_coupled_with(&mut cp, ctx, state, d, bnorm, scale);
        self.coupling = Some(cp);
        r
    }

    fn solve_coupled_with(
        &mut self,
        cp: &mut Coupling,
        ctx: &StepContext,
        state: &mut State,
        d: &[super::Deformation],
        bnorm: f64,
        scale: f64,
    ) -> Result<SolveStats, StageError> {
        let (g, bc, dt) = (ctx.grid, ctx.bc, ctx.dt);
        let nf = self.delta.len();
        cp.set_dt(g, dt);
        // The divergence of V^{n+1/3} (its boundary values at the step's end), and of the
        // explicit elastic increment M⁻¹ b: the scale the divergence target is relative to.
        let t = ctx.t + dt;
        bc.fill_velocity3(g, &mut state.u, &mut state.v, state.w.as_mut(), t, false);
        let (rc, w) = (&mut cp.rhs[nf..], &cp.dt_vol);
        let vel = super::velocity(&state.u, &state.v, state.w.as_ref());
        outflux_per_volume(g, &vel, w, -1.0, rc);
        let div0 = max_abs(&cp.rhs[nf..]);
        let div_b = self.increment_divergence(cp, g, bc);
        if bnorm == 0.0 && div0 == 0.0 {
            return Ok(SolveStats {
                iterations: 0,
                residual: 0.0,
                converged: true,
            });
        }
        let tols = Targets::new(
            self.tol * scale,
            cp.proj_tol.max(cp.rel_tol * div0.max(div_b)),
            g,
        );
        cp.rhs[..nf].copy_from_slice(&self.rhs);
        cp.rhs[nf..].iter_mut().for_each(|c| *c *= tols.omega);
        // The preconditioners: the elastic step's (velocity), the projection's Poisson
        // multigrid (pressure).
        self.setup_preconditioner(g, d);
        if self.scheme.preconditioner == ElasticPreconditioner::Jacobi {
            // η for the Schur complement's local term (the multigrid's setup made it).
            self.effective_viscosity(d);
        }
        if g.is_3d() {
            let a = &mut cp.poisson;
            let periodic = projection::three_d::periodic_axes(bc, g);
            let parts = [&mut a.diag, &mut a.east, &mut a.north, &mut a.top].map(|v| &mut v[..]);
            projection::three_d::assemble_3d_into(parts, g, periodic, &state.rho);
        } else {
            projection::assemble(&mut cp.poisson, g, bc, &state.rho);
        }
        cp.mg.setup(&cp.poisson);
        // From no increment and the pressure the last step ended with (the seed's scheme keeps
        // the whole pressure, which changes little from one step to the next).
        cp.x[..nf].fill(0.0);
        let (p, cells) = (&state.p, Region::of(g, Stagger::Cell));
        par::rows(&mut cp.x[nf..], g.nx)
            .for_each(|j, row| row.copy_from_slice(p.at(&cells.line(j), [0; 3])));
        let (st, worst) = self.solve_saddle(cp, ctx, d, &tols);
        if !st.converged {
            return Err(self.unconverged(&st, worst, scale, &tols));
        }
        self.apply(cp, g, bc, state);
        Ok(SolveStats {
            iterations: st.iterations,
            residual: worst.0 / bnorm.max(f64::MIN_POSITIVE),
            converged: true,
        })
    }

    /// `max |Δt ∇·(M⁻¹ b)|` per cell: the divergence of the explicit elastic increment.
    fn increment_divergence(&mut self, cp: &mut Coupling, g: &Grid, bc: &BoundarySet) -> f64 {
        let sc = &mut self.scratch;
        let (mass, rhs) = (&self.op.mass, &self.rhs);
        for (r, (b, m)) in cp.ru.iter_mut().zip(rhs.iter().zip(mass)) {
            *r = b / m;
        }
        match sc.xw.as_mut() {
            Some(xw) => {
                let vel = &mut [&mut sc.xu, &mut sc.xv, xw];
                self.op.ks[0].faces.scatter_to(&cp.ru, vel);
            }
            None => self.op.ks[0].faces.scatter(&cp.ru, &mut sc.xu, &mut sc.xv),
        }
        bc.fill_velocity3(g, &mut sc.xu, &mut sc.xv, sc.xw.as_mut(), 0.0, true);
        let vel = super::velocity(&sc.xu, &sc.xv, sc.xw.as_ref());
        outflux_per_volume(g, &vel, &cp.dt_vol, 1.0, &mut cp.pb);
        max_abs(&cp.pb)
    }

    /// FGMRES on the saddle-point system with the block-triangular preconditioner, from
    /// `cp.x`, until the true residual meets both targets; its statistics and the last
    /// checked residual (momentum 2-norm, `max |Δt ∇·V|`; NaN if never checked).
    fn solve_saddle(
        &mut self,
        cp: &mut Coupling,
        ctx: &StepContext,
        d: &[super::Deformation],
        tols: &Targets,
    ) -> (SolveStats, (f64, f64)) {
        let (g, bc, dt) = (ctx.grid, ctx.bc, ctx.dt);
        let nf = self.delta.len();
        let omega = tols.omega;
        let mut saddle = Saddle {
            a: OperatorCtx::new(&mut self.op, &mut self.scratch, d),
            grid: g,
            bc,
            dt,
            omega,
            dt_vol: &cp.dt_vol,
            q: &mut cp.q,
            nf,
        };
        let faces = saddle.a.op.ks[0].faces;
        let mut pre = BlockTriangular {
            a: match self.scheme.preconditioner {
                ElasticPreconditioner::Jacobi => VelocityBlock::Jacobi(&self.diag),
                _ => VelocityBlock::Multigrid(&self.blocks),
            },
            faces: &faces,
            poisson: &cp.mg,
            eta: &self.eta,
            grid: g,
            bc,
            dt,
            omega,
            singular: !bc.has_pressure_reference(),
            pb: &mut cp.pb,
            ps: &mut cp.ps,
            ru: &mut cp.ru,
            qp: &mut cp.qp,
            nf,
        };
        let mut worst = (f64::NAN, f64::NAN);
        let (tol_u, div_tol) = (tols.momentum, tols.divergence);

        let st = cp.fgmres.solve(
            &mut saddle,
            &mut pre,
            &cp.rhs,
            &mut cp.x,
            tol_u,
            cp.max_iter,
            |r| {
                let (ru, rc) = r.split_at(nf);
                let (mu, mc) = (norm(ru), max_abs(rc) / omega);
                worst = (mu, mc);
                if mu <= tol_u && mc <= div_tol {
                    Accept::Done
                } else {
                    Accept::Continue(0.3 * norm(r))
                }
            },
        );
        (st, worst)
    }

    /// The error of a coupled solve that did not converge: diverged (the momentum residual no
    /// smaller than its scale) or out of iterations, with the residuals against their targets.
    fn unconverged(
        &self,
        st: &SolveStats,
        worst: (f64, f64),
        scale: f64,
        tols: &Targets,
    ) -> StageError {
        let (mu, mc) = if worst.0.is_nan() {
            // Never checked: the Krylov estimate of the whole residual did not come down.
            (st.residual, f64::NAN)
        } else {
            worst
        };
        let div_tol = tols.divergence;
        let relative = mu / scale.max(f64::MIN_POSITIVE);
        if relative >= 1.0 || relative.is_nan() {
            return err(
                "elastic",
                format!(
                    "coupled step: FGMRES diverged: after {} iterations the momentum \
                     residual is {relative:.3e} of the scale, no smaller than where it \
                     started, so more iterations will not help (max |∇·V|·Δt {mc:.3e} \
                     against {div_tol:.1e}); check the solid's parameters or reduce the \
                     time step (time.cfl, numerics.elastic.wave_courant)",
                    st.iterations,
                ),
            );
        }
        err(
            "elastic",
            format!(
                "coupled step: FGMRES did not converge in {} iterations, the limit \
                 numerics.elastic.coupling_iterations (momentum residual {:.3e} of the scale \
                 against numerics.elastic.tolerance {:.1e}; max |∇·V|·Δt {:.3e} against \
                 {:.1e}); raise numerics.elastic.coupling_iterations or reduce the time step",
                st.iterations, relative, self.tol, mc, div_tol
            ),
        )
    }

    /// `V += δ` and the pressure `p` of the solution `cp.x = [δ; p]` (mean-free where the
    /// domain has no pressure reference), for the projection to complete (it adds what it
    /// finds).
    fn apply(&self, cp: &Coupling, g: &Grid, bc: &BoundarySet, state: &mut State) {
        let nf = self.delta.len();
        let (delta, p) = cp.x.split_at(nf);
        let faces = &self.op.ks[0].faces;
        match state.w.as_mut() {
            Some(w) => faces.add(delta, &mut [&mut state.u, &mut state.v, w]),
            None => faces.add(delta, &mut [&mut state.u, &mut state.v]),
        }
        let mean = if bc.has_pressure_reference() {
            0.0
        } else {
            p.iter().sum::<f64>() / g.cells() as f64
        };
        Region::of(g, Stagger::Cell).for_each(&mut state.p, |l, row| {
            for (r, p) in row.iter_mut().zip(&p[l.n * l.len..]) {
                *r = p - mean;
            }
        });
        bc.fill_scalar(g, &mut state.p, true);
    }
}

/// The coupled solve's targets: the momentum residual's 2-norm, `max |Δt ∇·V|`, and the
/// weight `ω` of the continuity rows, so that a uniform divergence at its target weighs as
/// much as the momentum residual at its own (`ω = tol_u / (tol_div √N)`, `N` cells).
struct Targets {
    momentum: f64,
    divergence: f64,
    omega: f64,
}

impl Targets {
    fn new(momentum: f64, divergence: f64, g: &Grid) -> Targets {
        let omega = if momentum > 0.0 {
            momentum / (divergence * (g.cells() as f64).sqrt())
        } else {
            1.0
        };
        Targets {
            momentum,
            divergence,
            omega,
        }
    }
}

impl Coupling {
    /// `Δt/dV` per cell for a step of `dt` (recomputed only when Δt changes).
    fn set_dt(&mut self, g: &Grid, dt: f64) {
        if dt != self.weight_dt {
            par::rows(&mut self.dt_vol[..], g.nx).for_each(|_, row| {
                for (i, w) in row.iter_mut().enumerate() {
                    *w = dt / g.cell_volume(i as isize);
                }
            });
            self.weight_dt = dt;
        }
    }
}

fn norm(a: &[f64]) -> f64 {
    efsi_linalg::par::dot(a, a).sqrt()
}

fn max_abs(a: &[f64]) -> f64 {
    a.iter().fold(0.0f64, |m, x| m.max(x.abs()))
}
