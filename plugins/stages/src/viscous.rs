//! Semi-implicit viscous step: `ρ (V^{n+1/3} − V*)/Δt = ∇·[μ (∇V + ∇Vᵀ)]` at level `θ`
//! (seed Eq. 12; θ = 1 backward Euler as the seed, θ = ½ Crank–Nicolson).
//!
//! **Operator.** `K(V) = ∇·(2μD)`, `D = ½(∇V + ∇Vᵀ)`, discretised on the MAC grid in its
//! finite-volume (weak) form: normal stresses `τ_xx = 2μ ∂u/∂x`, `τ_yy = 2μ ∂v/∂y` at cell
//! centres with the cell viscosity, shear stress `τ_xy = μ_c (∂u/∂y + ∂v/∂x)` at corners with
//! the average of the four cells' viscosities, and their divergence on the staggered control
//! volumes. Axisymmetric (x = r): `(1/r)∂(r τ_rr)/∂r + ∂τ_rz/∂z − τ_θθ/r` with the hoop stress
//! `τ_θθ = 2μ u_r/r` at the u-face itself, and `(1/r)∂(r τ_rz)/∂r + ∂τ_zz/∂z`; the radius
//! factors come from the grid's metric (zero hoop factor in planar geometry), so both
//! geometries share the code. Multiplied by the control volume, `K` is symmetric negative
//! semi-definite — it is the gradient of the dissipation `−Σ 2μ D:D dV` — and the full
//! components u and v are coupled through `∇Vᵀ` and variable μ.
//!
//! **Solve.** With `δ = V^{n+1/3} − V*` and the mass matrix `M = diag(ρ_f dV_f)` (face density
//! the average of the two cells): `(M − θΔt K) δ = Δt K(V*)`, symmetric positive definite, for
//! both components at once by conjugate gradient ("line solves as in the seed, or better": this
//! solves the coupled system exactly instead of splitting it), preconditioned by the diagonal
//! (Jacobi) or by multigrid V-cycles on the u–u and v–v blocks
//! ([`efsi_linalg::Multigrid`]; scene `numerics.viscous.preconditioner`: `Jacobi`, the
//! default, `Multigrid`, or `Auto`, multigrid once the diffusion number makes Jacobi's
//! iteration count, ~10√(max diag/mass), exceed the ~16 iterations the block preconditioner
//! needs at ≈ 4× the cost each — measured on the drop at 256²: 7.7 against 32 ns per cell and
//! iteration). Jacobi keeps a flow uniform along a periodic direction
//! exactly uniform; the red–black smoother does so only to the solver tolerance.
//!
//! **Initial guess.** `δ/Δt` of the last two steps extrapolated linearly to this one, times
//! `Δt` (zero in the first step): the stopping rule is unchanged (residual ≤ tolerance ×
//! ‖right-hand side‖), only fewer iterations reach it — measured 11 → 7.3 per step on the
//! Re = 1000 cavity at 128², 37.7 → 27.2 on the drop at 128². The history is stage state, kept
//! in snapshots and checkpoints ([`Stage::save`]), so a resumed run continues bit for bit. A
//! run that stops at a steady state (`time.steady`) starts every solve from zero: its test
//! compares successive steps to a tolerance far below the solver's, which only a map without
//! history reaches (the same inputs give the same bits; with the history the last bits keep
//! wandering within the solver tolerance, and the Poiseuille tests never became steady).
//!
//! **Cost.** The operator is applied from coefficients assembled once per step (see
//! `ViscousOperator`) in one vectorised pass per component, and conjugate gradient fuses its
//! vector updates with the residual norm and the Jacobi quotient with its dot product
//! ([`efsi_linalg::Pcg::solve_norm`]).
//!
//! **Parallelism.** The operator (scatter, stress divergence, gather) runs over rows in
//! parallel and CG's reductions have a fixed order: bit-identical on any number of threads. `K(V*)`
//! uses the θ-weighted boundary data `θ bⁿ⁺¹ + (1−θ) bⁿ` (K is affine in b, so this is exactly
//! the θ-scheme's boundary forcing); `δ` obeys the homogeneous conditions
//! ([`efsi_core::bc`]). Unconditionally stable for θ ∈ [½, 1]; θ = 1 damps the stiff modes of a
//! very viscous solid, θ = ½ is second-order in time.

use crate::block_multigrid::{Diagonal, ViscousBlocks};
use efsi_core::G;
use efsi_core::scene::ViscousPreconditioner;
use efsi_core::schedule::VELOCITY;
use efsi_core::{
    BoundarySet, Field, FieldId, Grid, Phase, Scene, Stage, StageError, StagePlugin, StageStats,
    State, StepContext,
    bc::{UnknownFaces, WallTime},
};
use efsi_linalg::par::{self, dot, for_each_row, for_each_row_sum, for_each_row2};
use efsi_linalg::{LinearOperator, Norm, Pcg, SolveStats};

/// The viscous stage plugin.
pub struct Viscous;

impl StagePlugin for Viscous {
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
            FieldId::Density,
            FieldId::Viscosity,
        ]
    }
    fn writes(&self) -> &'static [FieldId] {
        &VELOCITY
    }
    fn needed(&self, scene: &Scene) -> bool {
        scene.fluid.viscosity > 0.0
            || scene
                .solid
                .as_ref()
                .is_some_and(|s| s.viscosity(&scene.fluid) > 0.0)
    }
    fn build(
        &self,
        scene: &Scene,
        grid: &Grid,
        bc: &BoundarySet,
    ) -> Result<Box<dyn Stage>, String> {
        let faces = UnknownFaces::new(grid, bc);
        let n = faces.len();
        Ok(Box::new(ViscousStage {
            preconditioner: scene.numerics.viscous.preconditioner,
            theta: scene.numerics.viscous.theta,
            tol: scene.numerics.viscous.tolerance,
            max_iter: scene.numerics.viscous.max_iterations,
            op: ViscousOperator {
                grid: grid.clone(),
                bc: bc.clone(),
                faces,
                mu_corner: Field::zeros(grid),
                mass: vec![0.0; n],
                hoop: vec![0.0; n],
                dm: vec![0.0; n],
                theta_dt: 0.0,
                cxx: Field::zeros(grid),
                cyy: Field::zeros(grid),
                gc: Field::zeros(grid),
                xu: Field::zeros(grid),
                xv: Field::zeros(grid),
            },
            pcg: Pcg::new(n),
            rhs: vec![0.0; n],
            delta: vec![0.0; n],
            diag: vec![0.0; n],
            warm: WarmStart {
                enabled: scene.time.steady.is_none(),
                prev: [vec![0.0; n], vec![0.0; n]],
                prev_dt: [0.0; 2],
                history: 0,
            },
            blocks: ViscousBlocks::new(grid, bc),
        }))
    }
}

struct ViscousStage {
    preconditioner: ViscousPreconditioner,
    theta: f64,
    tol: f64,
    max_iter: usize,
    op: ViscousOperator,
    pcg: Pcg,
    rhs: Vec<f64>,
    delta: Vec<f64>,
    diag: Vec<f64>,
    /// Block multigrid on the u–u and v–v blocks, the operator's diagonal kept.
    blocks: ViscousBlocks,
    warm: WarmStart,
}

/// The increments `δ` of the last two steps (newest first) and their `Δt`, for the initial
/// guess; `history` counts the valid ones (0–2).
struct WarmStart {
    /// Off in a run that stops at a steady state (module docs).
    enabled: bool,
    prev: [Vec<f64>; 2],
    prev_dt: [f64; 2],
    history: usize,
}

/// Above this largest diagonal-to-mass ratio `Auto` switches from Jacobi to block multigrid.
const AUTO_MULTIGRID_RATIO: f64 = 40.0;

/// `y = M x − θΔt K_h x` on the compact vector of unknown faces (u first, then v).
///
/// `K_h` is applied from coefficients assembled once per step, with `θΔt` and the metric
/// factors folded in (module docs): `a_c = θΔt·2μ_c·r_c·Δy/Δx` on cells for the u-equation's
/// normal stress, `b_c = θΔt·2μ_c·r_c·Δx/Δy` for the v-equation's, and one corner weight
/// `g = θΔt·r·μ_corner`, whose shear flux `g·((Δx/Δy)·Δ_y u + Δ_x v)` enters the u-equation
/// (and `g·(Δ_y u + (Δy/Δx)·Δ_x v)` the v-equation) — the coefficient of `v` in the u-row is
/// the coefficient of `u` in the v-row, so the matrix is symmetric by construction. The hoop
/// term `θΔt·2μ_f r ΔxΔy/r²` is diagonal and folded with the mass into `dm`.
struct ViscousOperator {
    grid: Grid,
    bc: BoundarySet,
    faces: UnknownFaces,
    mu_corner: Field,
    mass: Vec<f64>,
    /// The hoop term `θΔt·2μ_f r ΔxΔy/r²` of each unknown face (zero on v-faces and in planar
    /// geometry).
    hoop: Vec<f64>,
    /// `mass + hoop`: the diagonal of `M − θΔt K` without the stencil's part.
    dm: Vec<f64>,
    theta_dt: f64,
    /// Cell coefficients of the normal stresses (u- and v-equations) and corner weights.
    cxx: Field,
    cyy: Field,
    gc: Field,
    xu: Field,
    xv: Field,
}

impl ViscousOperator {
    /// The step's coefficients from the cell viscosities `mu` (ghosts filled) and densities
    /// `rho`: corner viscosities, `cxx`, `cyy`, corner weights, masses, hoop terms, and the
    /// diagonal of the full matrix into `diag` (rows in parallel).
    fn assemble(&mut self, mu: &Field, rho: &Field, diag: &mut [f64]) {
        let g = &self.grid;
        let m = &g.metric;
        let (dx, dy) = (g.dx, g.dy);
        let td = self.theta_dt;
        let s = mu.stride();
        let mud = mu.data();
        let (ax, ay) = (td * 2.0 * dy / dx, td * 2.0 * dx / dy);
        {
            let (cxx, cyy) = (self.cxx.data_mut(), self.cyy.data_mut());
            for_each_row2(cxx, cyy, s, |jr, cx, cy| {
                let row = &mud[jr * s..(jr + 1) * s];
                for (c, ((cx, cy), mu)) in cx.iter_mut().zip(cy.iter_mut()).zip(row).enumerate() {
                    let r = m.rc(c as isize - G);
                    *cx = ax * r * mu;
                    *cy = ay * r * mu;
                }
            });
        }
        corner_coefficients(g, mu, td, &mut self.mu_corner, &mut self.gc);
        let (ux, vy) = (self.faces.ux, self.faces.vy);
        let nur = (ux.hi - ux.lo) as usize;
        let nu = self.faces.nu();
        let nx = g.nx;
        let rd = rho.data();
        let (cxx, cyy, gd) = (self.cxx.data(), self.cyy.data(), self.gc.data());
        let (alpha, beta) = (dx / dy, dy / dx);
        let idx = |i: isize, j: isize| mu.idx(i, j);
        let (mu_m, mu_v) = self.mass.split_at_mut(nu);
        let (ho_u, ho_v) = self.hoop.split_at_mut(nu);
        let (dm_u, dm_v) = self.dm.split_at_mut(nu);
        let (dg_u, dg_v) = diag.split_at_mut(nu);
        if nur > 0 {
            for_each_row2(mu_m, ho_u, nur, |j, ms, hs| {
                for (c, (ms, hs)) in ms.iter_mut().zip(hs.iter_mut()).enumerate() {
                    let i = ux.lo + c as isize;
                    let k = idx(i, j as isize);
                    *ms = 0.5 * (rd[k - 1] + rd[k]) * m.rx(i) * dx * dy;
                    let h = m.hoop_x(i);
                    *hs = td * dx * dy * m.rx(i) * (mud[k - 1] + mud[k]) * h * h;
                }
            });
            let (ms, hs) = (&*mu_m, &*ho_u);
            for_each_row2(dm_u, dg_u, nur, |j, dms, dgs| {
                for (c, (dm, dg)) in dms.iter_mut().zip(dgs.iter_mut()).enumerate() {
                    let k = idx(ux.lo + c as isize, j as isize);
                    let q = j * nur + c;
                    *dm = ms[q] + hs[q];
                    *dg = *dm + (cxx[k] + cxx[k - 1]) + alpha * (gd[k + s] + gd[k]);
                }
            });
        }
        ho_v.fill(0.0);
        for_each_row2(mu_v, dm_v, nx, |jr, ms, dms| {
            let j = vy.lo + jr as isize;
            for (i, (ms, dm)) in ms.iter_mut().zip(dms.iter_mut()).enumerate() {
                let k = idx(i as isize, j);
                *ms = 0.5 * (rd[k - s] + rd[k]) * m.rc(i as isize) * dx * dy;
                *dm = *ms;
            }
        });
        let dms = &*dm_v;
        for_each_row(dg_v, nx, |jr, dgs| {
            let j = vy.lo + jr as isize;
            for (i, dg) in dgs.iter_mut().enumerate() {
                let k = idx(i as isize, j);
                *dg = dms[jr * nx + i] + (cyy[k] + cyy[k - s]) + beta * (gd[k + 1] + gd[k]);
            }
        });
    }

    /// `y = d∘x − θΔt K_h^{stencil}(u, v)` on the unknown faces, with `u`, `v` the fields (ghosts
    /// filled) and `x` their compact vector of unknowns, or the fields' own values when `None`
    /// (rows in parallel; each row writes its own entries). Returns `x·y`, summed by rows in
    /// order (the same on any number of threads).
    fn stencil(&self, u: &Field, v: &Field, d: &[f64], x: Option<&[f64]>, y: &mut [f64]) -> f64 {
        let g = &self.grid;
        let (alpha, beta) = (g.dx / g.dy, g.dy / g.dx);
        let s = u.stride();
        let (ud, vd) = (u.data(), v.data());
        let (cxx, cyy, gd) = (self.cxx.data(), self.cyy.data(), self.gc.data());
        let (ux, vy) = (self.faces.ux, self.faces.vy);
        let nur = (ux.hi - ux.lo) as usize;
        let nu = self.faces.nu();
        let nx = g.nx;
        let (yu, yv) = y.split_at_mut(nu);
        let (du, dv) = d.split_at(nu);
        let (xu, xv) = match x {
            Some(x) => {
                let (a, b) = x.split_at(nu);
                (Some(a), Some(b))
            }
            None => (None, None),
        };
        let mut xy = 0.0;
        if nur > 0 {
            xy = for_each_row_sum(yu, nur, |j, yr| {
                let n = yr.len();
                let k0 = u.idx(ux.lo, j as isize);
                let q0 = j * nur;
                let uc = &ud[k0..k0 + n];
                let ue = &ud[k0 + 1..k0 + 1 + n];
                let uw = &ud[k0 - 1..k0 - 1 + n];
                let un = &ud[k0 + s..k0 + s + n];
                let us = &ud[k0 - s..k0 - s + n];
                let vc = &vd[k0..k0 + n];
                let vw = &vd[k0 - 1..k0 - 1 + n];
                let vn = &vd[k0 + s..k0 + s + n];
                let vnw = &vd[k0 + s - 1..k0 + s - 1 + n];
                let ac = &cxx[k0..k0 + n];
                let aw = &cxx[k0 - 1..k0 - 1 + n];
                let gs = &gd[k0..k0 + n];
                let gn = &gd[k0 + s..k0 + s + n];
                let dr = &du[q0..q0 + n];
                let xr = xu.map_or(uc, |x| &x[q0..q0 + n]);
                for c in 0..n {
                    let f_s = gs[c] * (alpha * (uc[c] - us[c]) + (vc[c] - vw[c]));
                    let f_n = gn[c] * (alpha * (un[c] - uc[c]) + (vn[c] - vnw[c]));
                    let k = ac[c] * (ue[c] - uc[c]) - aw[c] * (uc[c] - uw[c]) + (f_n - f_s);
                    yr[c] = dr[c] * xr[c] - k;
                }
                let yr = &*yr;
                par::sum4(n, |c| xr[c] * yr[c])
            });
        }
        xy + for_each_row_sum(yv, nx, |jr, yr| {
            let n = yr.len();
            let k0 = v.idx(0, vy.lo + jr as isize);
            let q0 = jr * nx;
            let vc = &vd[k0..k0 + n];
            let ve = &vd[k0 + 1..k0 + 1 + n];
            let vw = &vd[k0 - 1..k0 - 1 + n];
            let vn = &vd[k0 + s..k0 + s + n];
            let vs = &vd[k0 - s..k0 - s + n];
            let uc = &ud[k0..k0 + n];
            let us = &ud[k0 - s..k0 - s + n];
            let ue = &ud[k0 + 1..k0 + 1 + n];
            let use_ = &ud[k0 + 1 - s..k0 + 1 - s + n];
            let bc = &cyy[k0..k0 + n];
            let bs = &cyy[k0 - s..k0 - s + n];
            let gw = &gd[k0..k0 + n];
            let ge = &gd[k0 + 1..k0 + 1 + n];
            let dr = &dv[q0..q0 + n];
            let xr = xv.map_or(vc, |x| &x[q0..q0 + n]);
            for c in 0..n {
                let f_w = gw[c] * ((uc[c] - us[c]) + beta * (vc[c] - vw[c]));
                let f_e = ge[c] * ((ue[c] - use_[c]) + beta * (ve[c] - vc[c]));
                let k = bc[c] * (vn[c] - vc[c]) - bs[c] * (vc[c] - vs[c]) + (f_e - f_w);
                yr[c] = dr[c] * xr[c] - k;
            }
            let yr = &*yr;
            par::sum4(n, |c| xr[c] * yr[c])
        })
    }
}

/// Corner viscosities `mc` (as [`corner_viscosity`], bit for bit) and the corner weights
/// `gc = θΔt·r_corner·mc`, corner rows in parallel.
fn corner_coefficients(grid: &Grid, mu: &Field, td: f64, mc: &mut Field, gc: &mut Field) {
    let m = &grid.metric;
    let s = mu.stride();
    let (nx, ny) = (grid.nx as isize, grid.ny as isize);
    let r0 = mu.idx(-G, 0);
    let rows = (ny + 1) as usize;
    let mud = mu.data();
    let (mcd, gcd) = (
        &mut mc.data_mut()[r0..r0 + rows * s],
        &mut gc.data_mut()[r0..r0 + rows * s],
    );
    for_each_row2(mcd, gcd, s, |jr, mr, gr| {
        let k0 = r0 + jr * s;
        for i in 0..=nx {
            let c = (i + G) as usize;
            let k = k0 + c;
            let q = [mud[k - s - 1], mud[k - s], mud[k - 1], mud[k]];
            let v = if q.iter().all(|&x| x > 0.0) {
                4.0 / q.iter().map(|x| 1.0 / x).sum::<f64>()
            } else {
                0.0
            };
            mr[c] = v;
            gr[c] = td * m.rx(i) * v;
        }
    });
}

/// Corner viscosities: the harmonic mean of the four cells around each corner (zero if any is
/// inviscid). The corner carries the shear stress `μ (∂u/∂y + ∂v/∂x)`; across an interface the
/// two phases shear in series, whose effective viscosity is the harmonic mean — the arithmetic
/// mean would let the more viscous phase drag the other along (an O(1) error in the first cell
/// beside an interface, first order overall).
pub(crate) fn corner_viscosity(grid: &Grid, mu: &Field, out: &mut Field) {
    for j in 0..=grid.ny as isize {
        for i in 0..=grid.nx as isize {
            let m = [
                mu[(i - 1, j - 1)],
                mu[(i, j - 1)],
                mu[(i - 1, j)],
                mu[(i, j)],
            ];
            out[(i, j)] = if m.iter().all(|&x| x > 0.0) {
                4.0 / m.iter().map(|x| 1.0 / x).sum::<f64>()
            } else {
                0.0
            };
        }
    }
}

/// Scatter the compact vector `x` (u faces first, then v) into the fields' unknown faces,
/// rows in parallel.
fn scatter(faces: &UnknownFaces, x: &[f64], u: &mut Field, v: &mut Field) {
    let (ux, vy) = (faces.ux, faces.vy);
    let s = u.stride();
    let nur = (ux.hi - ux.lo) as usize;
    let nx = v.stride() - 1 - 2 * efsi_core::GHOST;
    let nu = faces.nu();
    let r0 = u.idx(-G, 0);
    let ny = nu / nur.max(1);
    if nur > 0 {
        for_each_row(&mut u.data_mut()[r0..r0 + ny * s], s, |j, row| {
            let o = (G + ux.lo) as usize;
            row[o..o + nur].copy_from_slice(&x[j * nur..(j + 1) * nur]);
        });
    }
    let rows = (vy.hi - vy.lo).max(0) as usize;
    let r0 = v.idx(-G, vy.lo);
    let xv = &x[nu..];
    for_each_row(&mut v.data_mut()[r0..r0 + rows * s], s, |j, row| {
        row[G as usize..G as usize + nx].copy_from_slice(&xv[j * nx..(j + 1) * nx]);
    });
}

/// `u, v += x` on the unknown faces (compact `x`: u faces first, then v), rows in parallel.
fn add_compact(faces: &UnknownFaces, x: &[f64], u: &mut Field, v: &mut Field) {
    let (ux, vy) = (faces.ux, faces.vy);
    let s = u.stride();
    let nur = (ux.hi - ux.lo) as usize;
    let nx = v.stride() - 1 - 2 * efsi_core::GHOST;
    let nu = faces.nu();
    if let Some(ny) = nu.checked_div(nur) {
        let r0 = u.idx(-G, 0);
        for_each_row(&mut u.data_mut()[r0..r0 + ny * s], s, |j, row| {
            let o = (G + ux.lo) as usize;
            for (a, b) in row[o..o + nur].iter_mut().zip(&x[j * nur..(j + 1) * nur]) {
                *a += b;
            }
        });
    }
    let rows = (vy.hi - vy.lo).max(0) as usize;
    let r0 = v.idx(-G, vy.lo);
    let xv = &x[nu..];
    for_each_row(&mut v.data_mut()[r0..r0 + rows * s], s, |j, row| {
        let o = G as usize;
        for (a, b) in row[o..o + nx].iter_mut().zip(&xv[j * nx..(j + 1) * nx]) {
            *a += b;
        }
    });
}

impl LinearOperator for ViscousOperator {
    fn apply(&mut self, x: &[f64], y: &mut [f64]) {
        self.apply_dot(x, y);
    }

    /// The product `x·y` comes from the stencil's own pass.
    fn apply_dot(&mut self, x: &[f64], y: &mut [f64]) -> f64 {
        let mut xu = std::mem::take(&mut self.xu);
        let mut xv = std::mem::take(&mut self.xv);
        scatter(&self.faces, x, &mut xu, &mut xv);
        self.bc
            .fill_velocity(&self.grid, &mut xu, &mut xv, 0.0, true);
        let xy = self.stencil(&xu, &xv, &self.dm, Some(x), y);
        self.xu = xu;
        self.xv = xv;
        xy
    }
}

impl WarmStart {
    /// The initial guess of `δ`: `δ/Δt` extrapolated linearly in time from the last two steps
    /// (from the last one alone after one step; zero at first), times this step's `Δt`.
    fn guess(&self, dt: f64, delta: &mut [f64]) {
        let [d1, d2] = self.prev_dt;
        let (c1, c2) = match if self.enabled { self.history } else { 0 } {
            0 => (0.0, 0.0),
            1 => (dt / d1, 0.0),
            _ => {
                let w = (dt + d1) / (d1 + d2);
                (dt / d1 * (1.0 + w), -dt / d2 * w)
            }
        };
        let [p1, p2] = &self.prev;
        par::for_each_chunk(delta, |o, d| {
            let n = d.len();
            let (p1, p2) = (&p1[o..o + n], &p2[o..o + n]);
            for ((d, a), b) in d.iter_mut().zip(p1).zip(p2) {
                *d = c1 * a + c2 * b;
            }
        });
    }

    /// Keep this step's `δ` (in `delta`) and `Δt` for the next initial guess.
    fn remember(&mut self, dt: f64, delta: &mut Vec<f64>) {
        if !self.enabled {
            return;
        }
        let [p1, p2] = &mut self.prev;
        std::mem::swap(p1, p2);
        std::mem::swap(p1, delta);
        self.prev_dt = [dt, self.prev_dt[0]];
        self.history = (self.history + 1).min(2);
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
        out.reserve(3 + w.prev.len() * self.delta.len());
        out.extend_from_slice(&[w.history as f64, w.prev_dt[0], w.prev_dt[1]]);
        for p in &w.prev[..w.history] {
            out.extend_from_slice(p);
        }
    }

    /// Nothing (a snapshot without a history: the next solve starts from zero), or what
    /// [`save`](Stage::save) wrote.
    fn restore(&mut self, data: &[f64]) -> Result<(), String> {
        let n = self.delta.len();
        let w = &mut self.warm;
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
        let g = ctx.grid;
        let op = &mut self.op;
        op.theta_dt = self.theta * ctx.dt;
        op.assemble(&state.mu, &state.rho, &mut self.diag);
        // Right-hand side Δt·K(V*, θ bⁿ⁺¹ + (1−θ) bⁿ): K is affine in the boundary data b, so
        // this is the θ-weighted sum of the implicit and explicit parts' boundary forcing. The
        // stencil with the hoop term as its diagonal gives −θΔt·K(V*).
        let when = WallTime::Blend {
            t0: ctx.t,
            t1: ctx.t + ctx.dt,
            theta: self.theta,
        };
        ctx.bc.fill_velocity_at(g, &mut state.u, &mut state.v, when);
        let rhs = &mut self.rhs;
        op.stencil(&state.u, &state.v, &op.hoop, None, rhs);
        let scale = -1.0 / self.theta;
        for_each_row(rhs, g.nx.max(1), |_, row| {
            row.iter_mut().for_each(|r| *r *= scale);
        });
        let bnorm = dot(rhs, rhs).sqrt();
        let stats = if bnorm == 0.0 {
            self.delta.fill(0.0);
            self.warm.remember(ctx.dt, &mut self.delta);
            SolveStats {
                iterations: 0,
                residual: 0.0,
                converged: true,
            }
        } else {
            self.warm.guess(ctx.dt, &mut self.delta);
            let tol = self.tol * bnorm;
            let use_mg = match self.preconditioner {
                ViscousPreconditioner::Jacobi => false,
                ViscousPreconditioner::Multigrid => true,
                ViscousPreconditioner::Auto => {
                    // Jacobi-preconditioned condition number ≲ max(diag/mass); CG needs
                    // ~10√κ iterations at 1e-9, at a quarter of the block multigrid's cost
                    // per iteration, which needs ~16: break-even near κ ≈ 40.
                    let ratio = self.diag.iter().zip(&op.mass).fold(0.0f64, |m, (d, ms)| {
                        if *ms > 0.0 { m.max(d / ms) } else { m }
                    });
                    ratio > AUTO_MULTIGRID_RATIO
                }
            };
            let st = if use_mg {
                self.blocks.setup(
                    g,
                    Diagonal::Given(&self.diag),
                    &state.mu,
                    &op.mu_corner,
                    op.theta_dt,
                );
                self.pcg.solve_norm(
                    op,
                    &self.blocks,
                    rhs,
                    &mut self.delta,
                    tol,
                    self.max_iter,
                    Norm::L2,
                )
            } else {
                self.pcg.solve_norm(
                    op,
                    self.diag.as_slice(),
                    rhs,
                    &mut self.delta,
                    tol,
                    self.max_iter,
                    Norm::L2,
                )
            };
            if !st.converged {
                return Err(StageError {
                    stage: "viscous".into(),
                    message: format!(
                        "conjugate gradient did not converge in {} iterations (relative residual {:.3e} > {:.1e}); \
                         raise numerics.viscous.max_iterations or reduce the time step",
                        st.iterations,
                        st.residual / bnorm,
                        self.tol
                    ),
                });
            }
            add_compact(&op.faces, &self.delta, &mut state.u, &mut state.v);
            self.warm.remember(ctx.dt, &mut self.delta);
            SolveStats {
                residual: st.residual / bnorm,
                ..st
            }
        };
        Ok(StageStats { solve: Some(stats) })
    }
}
