//! The coupled elastic step (`numerics.elastic.coupling: Coupled`): the implicit
//! viscous–elastic system solved together with the divergence constraint.
//!
//! # The system
//!
//! With `A = M − θ_v Δt K_v − θ Δt² K_J` the elastic step's operator (mass, implicit viscous
//! and elastic stiffness on the unknown faces), `Ĝ` the discrete gradient scaled by the face
//! areas and `F = −Ĝᵀ` the net outflux of a cell, the split step solves `A δ = b` and then
//! projects with the mass alone, `M δ_p = −Δt Ĝ p`, `F(V + δ + δ_p) = 0`. Its correction `δ_p`
//! strains the solid (`B̃^{n+1}` is stretched by it) without the solid's stiffness answering
//! within the step: the strain is stored at stiffness G and given back next step, which pumps
//! energy once the shear wave crosses ≈ 5 cells a step. The coupled step solves for the
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
//! as much as the momentum residual at its own (`N` cells).
//!
//! # The solve
//!
//! Right-preconditioned flexible GMRES ([`efsi_linalg::Fgmres`]) from no increment and the
//! pressure the last step ended with, with the block upper-triangular preconditioner
//! `P = [Â, ΔtĜ; 0, −Ŝ]` — with exact blocks `K P⁻¹` has the single eigenvalue 1 and a minimal
//! polynomial of degree 2. `Â⁻¹` is one application of the elastic step's own preconditioner
//! (the block multigrid V-cycle on the effective-viscosity operator, or Jacobi); `Ŝ⁻¹` is
//! Cahouet–Chabard's approximation of the Schur complement for unsteady Stokes: per unit
//! volume `A ≈ ρ − η Δ` with `η = θ_v Δt μ + θ Δt² G_eff` (the block multigrid's effective
//! viscosity), and on a gradient `A ∇q = ∇(ρ q − 2η Δq)`, so
//!
//! ```text
//!   S⁻¹ ≈ Δt⁻¹ (ρ Δ⁻¹ + 2η)   ⇒   q = s − (2η/Δt) ∇·V,   ∇·(∇s/ρ) = ∇·V/Δt
//! ```
//!
//! — one multigrid V-cycle of the projection's Poisson operator plus a local term: exact for
//! uniform coefficients, and in a fluid (`G_eff = 0`) the viscous-coupled projection. A cycle
//! more of the Poisson solve did not reduce the iterations (the velocity block bounds them).
//! The solve stops when the true residual meets both tolerances: the momentum residual's
//! 2-norm `numerics.elastic.tolerance` × the split solve's scale, and `max |Δt ∇·V|` the larger of
//! the projection's tolerance and `coupling_tolerance` × the step's divergence scale (that of
//! `V*` or of the explicit elastic increment `M⁻¹ b`, whichever is larger). The projection
//! stage then removes what divergence is left with the mass alone (it solves for it from
//! zero and adds its pressure). Each iteration costs one product with `A` (the elastic
//! operator plus a gradient and a divergence), one block-multigrid cycle and one Poisson
//! cycle: on the seed's sphere (35 cells per radius, tolerance 1e-8) 16 iterations a step
//! where the split step's BiCGSTAB takes 9.5 (each with two products and two cycles).
//!
//! An earlier version ran FGMRES on the pressure's Schur complement alone, each product a
//! BiCGSTAB solve with `A` to 1e-2 of the outer tolerance: 64 inner iterations a step, 2.6×
//! the split step's cost where this one costs ≈ 1.4×. Plain Uzawa (Richardson) with the same
//! preconditioner stalls: a cell with a sliver of solid has air's mass but stiff faces, and
//! the preconditioner's eigenvalues spread over (0, 3] there.
//!
//! # The stress at θ
//!
//! The coupled step weights the stress in its momentum step as its stretching weights the
//! velocity: with `B(V) = Bⁿ + E + θΔt H(V; Bⁿ)` (see the parent module) it solves
//! `ρ δ/Δt = ∇·[θ τ(B(V)) + (1 − θ) τ(Bⁿ)]`, linearised about `B^{n+1/3}` as the split step is:
//! `(M − θ_v Δt K_v − θ² Δt² K_J) δ = Δt·vol·∇·[θ τ^{n+1/3} + (1 − θ) τⁿ]` (one more law
//! evaluation a step, `τ(Bⁿ)` without its tangent). The split step near its wave cap keeps
//! the stress at the step's end (θ = ½, weight 1 on `τ^{n+1}`; below an elastic-wave Courant
//! number of 1 it takes the midpoint, see the parent module's "θ of the stress"), whose
//! damping it needs there: with the midpoint
//! `½(τⁿ + τ^{n+1})` the map's sphere under `Split` gains 2.1 % of its budget at G = 1e9 Pa and
//! 3.1 % at 1e7 (total at 16 ms +4.4 % and +21 %).
//!
//! Why: take the 1-D model of a solid in contact, a mass m on a spring k (x the strain, v the
//! velocity), stretched as B is and pushed as the momentum step pushes,
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
//! 0.62, 0.41, 0.34, 0.33 at s = 0.1, 1, 2, 5, 20, ∞ (stress at the end: 0.996, 0.756, 0.500,
//! 0.225, 0.315, 0.333; see the parent module's table). The model holds for a linear law away
//! from the interface; what the discrete solid adds is outside it: the law's nonlinearity, B's
//! advection, and at the interface the VOF step moving φ under a fixed B (see "Limits").
//!
//! # Limits
//!
//! The solve is not what limits the step: the Schur approximation carries the elastic term
//! (`θΔt² G_eff` in `η`), and FGMRES takes 20–32 iterations a step at any G and any wave
//! Courant number (the stability map's sphere at G = 1e7–1e11 Pa and caps from 25 to 1000
//! wave Courant numbers). Δt is capped at `coupled_wave_courant` (default 25, at most 200)
//! elastic-wave Courant numbers `Δt·c/h` for what the solid does with long steps:
//!
//! - **Strain left by a rigid motion** — no longer: it was the fluid's one-step stretch of B
//!   reaching the solid (see "Pure fluid" in the parent module), which the map's sphere at
//!   G = 1e9 Pa falling at 50 wave Courant numbers held as 7.3e-3 of its kinetic energy, at
//!   100–400 as 5e-2–0.55 (the fall gaining 1.5–18 % of its energy). Reset, the fall keeps
//!   at most 1.3e-9 at 50 and 3.2e-5 at 400, without gain.
//! - **A contact taken in a few steps.** The map's sphere at G = 1e9 Pa (8 cells per radius)
//!   touches the wall for ≈ 0.35 ms (split steps: contact force from 1.35 to 1.75 ms), a few
//!   steps at 25 wave Courant numbers and less than one at 200. Two things then lose its
//!   rebound: at 16 ms it moves up at 0.957, 0.647, 0.095 m/s with caps of 8, 25, 50 (θ = ¾,
//!   the stress at θ; with the stress at the step's end 0.893, 0.506, 0.020) and rests on the
//!   wall at 200 (the split step at 4: 1.030). At G = 1e7 Pa and a cap of 8: 0.641 (end: 0.513);
//!   from 25 on it rests on the wall either way. At 1e11 Pa and 25: 0.843 (end: 0.739).
//!   1. *The stress at the step's end* — now at θ (above). With the stress at the step's end
//!      and θ = ½ the step lost `½ ∫ w G |B^{n+1} − Bⁿ|²`: at 200 the impact step turned the
//!      sphere's kinetic energy (3.96e-3 J/rad) into 2.06e-3 of strain and lost 1.90e-3. At
//!      θ = ¾ what the step loses is the θ-method's `(θ − ½)|Δy|²`, still most of an impact
//!      taken in one step. At θ = ½ (`theta: 0.5`, the midpoint rule) the step loses nothing
//!      in the 1-D model, and the run gains through the next mechanism: 1.117, 1.175, 1.195
//!      m/s at 16 ms with caps of 8, 25, 200, kinetic + potential 5.0 %, 16 %, 21 % of the
//!      budget above its start (an elastic rebound, e = 1, would leave at ≈ 1.12) — θ = ½ is
//!      not for coupled steps that take a contact.
//!   2. *The wall row's sliver.* The contact is far below the grid (Hertz: 0.09 mm of
//!      approach, 1/26 of a cell); in long steps what stops and relaunches the sphere is the
//!      wall row's cell on the axis, holding φ = 1e-3–7e-2 of solid, whose normal components
//!      take the whole cell's rate (iso-strain, see "The interface" in the parent module) —
//!      the squeeze of the air between the sphere and the wall, `v/h` — at the stiffness
//!      `φ^{1/2} G`. It holds 87–97 % of the strain energy in contact (B₂₂ − 1 = −0.19 with
//!      the midpoint step at 200), is stretched as the sphere leaves (adhesion: the coupled
//!      step that made `Auto`'s wall margin 1.5 cells stretched it to B₂₂ − 1 = +0.044 and
//!      took 12.6 % of the kinetic energy), and what strain it still holds when it drops
//!      below `PHI_MIN` is reset with it. The solid fraction moving at fixed B changes the
//!      stored `φ^{1/2} W(B)` too: with the midpoint step at 8, +1.11e-3 J/rad gained and
//!      −0.75e-3 lost that way over the run against a budget of 5.1e-3. With the weight `φ`
//!      instead of `φ^{1/2}` the sliver is softer and the rebound closer (split 1.073,
//!      coupled at 25 and θ = ½: 1.033), but at 200 the run pumps energy. Over a run at the
//!      default θ = ¾ and cap 25 that way +1.60e-3 J/rad are gained and −0.78e-3 lost; the
//!      elastic stages take the net back as strain (−0.82e-3) and lose 2.30e-3 of kinetic
//!      energy (at 8: +1.02e-3, −0.61e-3 and 0.79e-3; at 200: +1.39e-3, −0.36e-3, 3.97e-3).
//!      B's advection in contact moves as much: at 200 with θ = ½ it changes the strain
//!      energy by −16.9e-3 and +3.8e-3 J/rad over the run, and the elastic step after the
//!      impact stores 13.8e-3 J/rad (2.7 budgets) — a cure of the sliver alone would not make
//!      a contact taken in one step conservative.
//!
//!   Those long steps are stable: no run failed and none gained more than 3e-5 of its budget
//!   (8 cells per radius at G = 1e7 and 1e9 Pa to 200; 6 cells per radius, CFL 0.5 and 0.9,
//!   G = 1e7, 1e9, 1e11 Pa at 100 and 200).
//!
//! With the cap every run of the map (6 and 8 cells per radius, G = 1e7–1e11 Pa, CFL 0.1–0.9)
//! stays stable at 25 and 50, and the runs measured at 100 and 200 too; the cap is kept for the
//! rebound, not for stability. `Auto` takes
//! the contact with split steps instead (see `ElasticCoupling::Auto`).

use super::ElasticPreconditioner;
use super::err;
use super::solve::{ElasticStage, OperatorCtx};
use crate::block_multigrid::ViscousBlocks;
use crate::faces::UnknownFaces;
use crate::ops;
use crate::projection;
use efsi_core::{BoundarySet, Field, Grid, StageError, State, StepContext};
use efsi_linalg::par;
use efsi_linalg::{
    Accept, Fgmres, FlexiblePreconditioner, LinearOperator, Multigrid, Preconditioner, SolveStats,
    Stencil5,
};

/// Krylov vectors kept before FGMRES restarts.
const RESTART: usize = 30;

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
            poisson: Stencil5::new(grid.nx, grid.ny, bc.periodic(0), bc.periodic(1)),
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
    let (m, dx, dy) = (&g.metric, g.dx, g.dy);
    let (yu, yv) = y.split_at_mut(faces.nu());
    let lo = faces.ux.lo;
    let nur = (faces.ux.hi - lo).max(0) as usize;
    if nur > 0 {
        par::rows(&mut *yu, nur).for_each(|j, row| {
            let j = j as isize;
            for (t, y) in row.iter_mut().enumerate() {
                let i = lo + t as isize;
                *y += c * m.rx(i) * dy * (q[(i, j)] - q[(i - 1, j)]);
            }
        });
    }
    let vlo = faces.vy.lo;
    par::rows(&mut *yv, g.nx).for_each(|r, row| {
        let j = vlo + r as isize;
        for (i, y) in row.iter_mut().enumerate() {
            let i = i as isize;
            *y += c * m.rc(i) * dx * (q[(i, j)] - q[(i, j - 1)]);
        }
    });
}

/// `out = c (Δt/dV) F(u, v)` per cell (`dt_vol` = Δt/dV, `F` the net outflux), rows in
/// parallel.
fn outflux_per_volume(g: &Grid, u: &Field, v: &Field, dt_vol: &[f64], c: f64, out: &mut [f64]) {
    let nx = g.nx;
    par::rows(&mut *out, nx).for_each(|j, row| {
        for (i, y) in row.iter_mut().enumerate() {
            *y = c * dt_vol[j * nx + i] * ops::net_outflux(g, u, v, i as isize, j as isize);
        }
    });
}

/// Copy a per-cell vector into a cell field and fill its ghosts (homogeneous).
fn to_field(g: &Grid, bc: &BoundarySet, x: &[f64], f: &mut Field) {
    let nx = g.nx;
    for j in 0..g.ny {
        for i in 0..nx {
            f[(i as isize, j as isize)] = x[j * nx + i];
        }
    }
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
        let (xu, xv, w) = (&*self.a.xu, &*self.a.xv, self.dt_vol);
        outflux_per_volume(g, xu, xv, w, om, yc);
        to_field(g, self.bc, xp, self.q);
        add_gradient(&self.a.op.k.faces, g, self.q, self.dt, yu);
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
        let (ps, eta) = (&*self.ps, self.eta);
        par::rows(&mut *zp, nx).for_each(|j, row| {
            let jj = j as isize;
            for (i, z) in row.iter_mut().enumerate() {
                let c = j * nx + i;
                *z = ps[c] + 2.0 * eta[(i as isize, jj)] * rc[c] / (om * dt * dt);
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
    /// projection stage removes what divergence is left and adds its pressure.
    pub(super) fn solve_coupled(
        &mut self,
        ctx: &StepContext,
        state: &mut State,
        d: &super::Deformation,
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
        d: &super::Deformation,
        bnorm: f64,
        scale: f64,
    ) -> Result<SolveStats, StageError> {
        let g = ctx.grid;
        let bc = ctx.bc;
        let dt = ctx.dt;
        let nx = g.nx;
        let nf = self.delta.len();
        if dt != cp.weight_dt {
            par::rows(&mut cp.dt_vol[..], nx).for_each(|_, row| {
                for (i, w) in row.iter_mut().enumerate() {
                    *w = dt / g.cell_volume(i as isize);
                }
            });
            cp.weight_dt = dt;
        }
        // The divergence of V^{n+1/3} (its boundary values at the step's end), and of the
        // explicit elastic increment M⁻¹ b: the scale the divergence target is relative to.
        bc.fill_velocity(g, &mut state.u, &mut state.v, ctx.t + dt, false);
        let (rc, w) = (&mut cp.rhs[nf..], &cp.dt_vol);
        outflux_per_volume(g, &state.u, &state.v, w, -1.0, rc);
        let div0 = max_abs(&cp.rhs[nf..]);
        let div_b = {
            let sc = &mut self.scratch;
            let (mass, rhs) = (&self.op.mass, &self.rhs);
            for (r, (b, m)) in cp.ru.iter_mut().zip(rhs.iter().zip(mass)) {
                *r = b / m;
            }
            self.op.k.faces.scatter(&cp.ru, &mut sc.xu, &mut sc.xv);
            bc.fill_velocity(g, &mut sc.xu, &mut sc.xv, 0.0, true);
            outflux_per_volume(g, &sc.xu, &sc.xv, w, 1.0, &mut cp.pb);
            max_abs(&cp.pb)
        };
        if bnorm == 0.0 && div0 == 0.0 {
            return Ok(SolveStats {
                iterations: 0,
                residual: 0.0,
                converged: true,
            });
        }
        let div_tol = cp.proj_tol.max(cp.rel_tol * div0.max(div_b));
        let tol_u = self.tol * scale;
        // The divergence rows weighted so that a uniform divergence at its tolerance weighs as
        // much as the momentum residual at its own.
        let n = g.cells();
        let omega = if tol_u > 0.0 {
            tol_u / (div_tol * (n as f64).sqrt())
        } else {
            1.0
        };
        cp.rhs[..nf].copy_from_slice(&self.rhs);
        cp.rhs[nf..].iter_mut().for_each(|c| *c *= omega);
        // The preconditioners: the elastic step's (velocity), the projection's Poisson
        // multigrid (pressure).
        self.setup_preconditioner(g, d);
        if self.scheme.preconditioner == ElasticPreconditioner::Jacobi {
            // η for the Schur complement's local term (the multigrid's setup made it).
            self.effective_viscosity(d);
        }
        projection::assemble(&mut cp.poisson, g, bc, &state.rho);
        cp.mg.setup(&cp.poisson);
        // From no increment and the pressure the last step ended with (the seed's scheme keeps
        // the whole pressure, which changes little from one step to the next).
        cp.x[..nf].fill(0.0);
        {
            let xp = &mut cp.x[nf..];
            let p = &state.p;
            par::rows(&mut *xp, nx).for_each(|j, row| {
                for (i, x) in row.iter_mut().enumerate() {
                    *x = p[(i as isize, j as isize)];
                }
            });
        }
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
        let faces = saddle.a.op.k.faces;
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
        if !st.converged {
            let (mu, mc) = if worst.0.is_nan() {
                // Never checked: the Krylov estimate of the whole residual did not come down.
                (st.residual, f64::NAN)
            } else {
                worst
            };
            let relative = mu / scale.max(f64::MIN_POSITIVE);
            if relative >= 1.0 || relative.is_nan() {
                return Err(err(
                    "elastic",
                    format!(
                        "coupled step: FGMRES diverged: after {} iterations the momentum \
                         residual is {relative:.3e} of the scale, no smaller than where it \
                         started, so more iterations will not help (max |∇·V|·Δt {mc:.3e} \
                         against {div_tol:.1e}); check the solid's parameters or reduce the \
                         time step (time.cfl, numerics.elastic.wave_courant)",
                        st.iterations,
                    ),
                ));
            }
            return Err(err(
                "elastic",
                format!(
                    "coupled step: FGMRES did not converge in {} iterations, the limit \
                     numerics.elastic.coupling_iterations (momentum residual {:.3e} of the scale \
                     against numerics.elastic.tolerance {:.1e}; max |∇·V|·Δt {:.3e} against \
                     {:.1e}); raise numerics.elastic.coupling_iterations or reduce the time step",
                    st.iterations,
                    mu / scale.max(f64::MIN_POSITIVE),
                    self.tol,
                    mc,
                    div_tol
                ),
            ));
        }
        // V += δ; the pressure for the projection to complete (it adds what it finds).
        let (delta, p) = cp.x.split_at(nf);
        {
            let (u, v) = (&mut state.u, &mut state.v);
            self.op.k.faces.for_each(|c, is_u, q| {
                if is_u {
                    u.data_mut()[q] += delta[c];
                } else {
                    v.data_mut()[q] += delta[c];
                }
            });
        }
        let mean = if bc.has_pressure_reference() {
            0.0
        } else {
            p.iter().sum::<f64>() / n as f64
        };
        for j in 0..g.ny {
            for i in 0..nx {
                state.p[(i as isize, j as isize)] = p[j * nx + i] - mean;
            }
        }
        bc.fill_scalar(g, &mut state.p, true);
        Ok(SolveStats {
            iterations: st.iterations,
            residual: worst.0 / bnorm.max(f64::MIN_POSITIVE),
            converged: true,
        })
    }
}

fn norm(a: &[f64]) -> f64 {
    efsi_linalg::par::dot(a, a).sqrt()
}

fn max_abs(a: &[f64]) -> f64 {
    a.iter().fold(0.0f64, |m, x| m.max(x.abs()))
}
