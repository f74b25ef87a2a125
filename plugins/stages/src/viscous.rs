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
//! ([`efsi_core::solver::Multigrid`]; scene `numerics.viscous.preconditioner`: `Jacobi`, the
//! default, `Multigrid`, or `Auto`, multigrid once the diffusion number makes Jacobi's
//! iteration count, ~10√(max diag/mass), exceed the ~16 iterations the block preconditioner
//! needs at twice the cost each). Jacobi keeps a flow uniform along a periodic direction
//! exactly uniform; the red–black smoother does so only to the solver tolerance.
//!
//! **Parallelism.** The operator (scatter, stress divergence, gather) runs over rows in
//! parallel and CG's reductions have a fixed order: bit-identical on any number of threads. `K(V*)`
//! uses the θ-weighted boundary data `θ bⁿ⁺¹ + (1−θ) bⁿ` (K is affine in b, so this is exactly
//! the θ-scheme's boundary forcing); `δ` obeys the homogeneous conditions
//! ([`efsi_core::bc`]). Unconditionally stable for θ ∈ [½, 1]; θ = 1 damps the stiff modes of a
//! very viscous solid, θ = ½ is second-order in time.

use efsi_core::G;
use efsi_core::scene::ViscousPreconditioner;
use efsi_core::schedule::VELOCITY;
use efsi_core::solver::par::{dot, for_each_row};
use efsi_core::solver::{LinearOperator, Multigrid, Pcg, Preconditioner, SolveStats, Stencil5};
use efsi_core::{
    BoundarySet, Field, FieldId, Grid, Phase, Scene, Stage, StageError, StagePlugin, StageStats,
    State, StepContext,
    bc::{FaceRange, UnknownFaces, WallTime},
};

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
                theta_dt: 0.0,
                xu: Field::zeros(grid),
                xv: Field::zeros(grid),
                ku: Field::zeros(grid),
                kv: Field::zeros(grid),
                mu: Field::zeros(grid),
            },
            pcg: Pcg::new(n),
            rhs: vec![0.0; n],
            delta: vec![0.0; n],
            diag: vec![0.0; n],
            blocks: BlockMultigrid::new(grid, bc),
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
    blocks: BlockMultigrid,
}

/// Above this largest diagonal-to-mass ratio `Auto` switches from Jacobi to block multigrid.
const AUTO_MULTIGRID_RATIO: f64 = 12.0;

/// Preconditioner: multigrid on the two diagonal blocks of `M − θΔt K` (u–u and v–v, each a
/// five-point matrix on its faces), dropping the u–v coupling of the shear stress.
struct BlockMultigrid {
    au: Stencil5,
    av: Stencil5,
    mu: Multigrid,
    mv: Multigrid,
}

impl BlockMultigrid {
    fn new(grid: &Grid, bc: &BoundarySet) -> Self {
        let faces = UnknownFaces::new(grid, bc);
        let nur = (faces.ux.hi - faces.ux.lo) as usize;
        let nvr = (faces.vy.hi - faces.vy.lo) as usize;
        // V(1,1) with the mass carried whole to the coarse levels. Measured on the drop at 128²:
        // 15.9 iterations; V(2,2) 15.4 and W-cycles 15.4–15.9 at up to 1.5× the cost (the
        // dropped u–v coupling, not the block solve, sets the count); the halved excess 19.7.
        let mg = || Multigrid::new(1).with_w_cycle(false).with_excess_scale(1.0);
        let mut b = BlockMultigrid {
            au: Stencil5::new(nur, grid.ny, bc.periodic(0), bc.periodic(1)),
            av: Stencil5::new(grid.nx, nvr, bc.periodic(0), bc.periodic(1)),
            mu: mg(),
            mv: mg(),
        };
        // Allocate the hierarchies now: `Auto` may first choose multigrid in a later step,
        // which must not allocate.
        b.mu.setup(&b.au);
        b.mv.setup(&b.av);
        b
    }

    /// The two blocks from the cell and corner viscosities and the diagonal `diag` of the full
    /// matrix; then the multigrid hierarchies.
    fn setup(&mut self, g: &Grid, op: &ViscousOperator, diag: &[f64]) {
        let m = &g.metric;
        let (dx, dy) = (g.dx, g.dy);
        let td = op.theta_dt;
        let (mu, mc) = (op.mu.data(), op.mu_corner.data());
        let s = op.mu.stride();
        let (ux, vy) = (op.faces.ux, op.faces.vy);
        let (nur, nx, ny) = (self.au.nx, g.nx, g.ny);
        let (px, py) = (self.au.periodic_x, self.au.periodic_y);
        for j in 0..ny {
            for c in 0..nur {
                let i = ux.lo + c as isize;
                let k = op.mu.idx(i, j as isize);
                let kc = j * nur + c;
                // u(i) – u(i+1) through the normal stress at cell i; u(j) – u(j+1) through the
                // shear stress at corner (i, j+1).
                self.au.east[kc] = if c + 1 < nur || px {
                    td * dy * m.rc(i) * 2.0 * mu[k] / dx
                } else {
                    0.0
                };
                self.au.north[kc] = if j + 1 < ny || py {
                    td * dx * m.rx(i) * mc[k + s] / dy
                } else {
                    0.0
                };
                self.au.diag[kc] = diag[kc];
            }
        }
        let nu = nur * ny;
        let nvr = self.av.ny;
        for jr in 0..nvr {
            let j = vy.lo + jr as isize;
            for i in 0..nx {
                let k = op.mu.idx(i as isize, j);
                let kc = jr * nx + i;
                self.av.east[kc] = if i + 1 < nx || px {
                    td * dy * m.rx(i as isize + 1) * mc[k + 1] / dx
                } else {
                    0.0
                };
                self.av.north[kc] = if jr + 1 < nvr || py {
                    td * dx * m.rc(i as isize) * 2.0 * mu[k] / dy
                } else {
                    0.0
                };
                self.av.diag[kc] = diag[nu + kc];
            }
        }
        // The diagonal of the full matrix bounds the block's couplings (it counts the wall
        // terms too), so each block is a diagonally dominant M-matrix.
        self.mu.setup(&self.au);
        self.mv.setup(&self.av);
    }
}

impl Preconditioner for BlockMultigrid {
    fn apply(&self, r: &[f64], z: &mut [f64]) {
        let nu = self.au.len();
        let (zu, zv) = z.split_at_mut(nu);
        self.mu.apply(&r[..nu], zu);
        self.mv.apply(&r[nu..], zv);
    }
}

/// `y = M x − θΔt K_h x` on the compact vector of unknown faces (u first, then v).
struct ViscousOperator {
    grid: Grid,
    bc: BoundarySet,
    faces: UnknownFaces,
    mu: Field,
    mu_corner: Field,
    mass: Vec<f64>,
    theta_dt: f64,
    xu: Field,
    xv: Field,
    ku: Field,
    kv: Field,
}

impl ViscousOperator {
    /// `(ku, kv) = dV·∇·(2μD(u, v))` on the unknown faces; `u`, `v` with ghosts filled.
    fn stress_divergence(&self, u: &Field, v: &Field, ku: &mut Field, kv: &mut Field) {
        viscous_divergence(
            &self.grid,
            self.faces.ux,
            self.faces.vy,
            &self.mu,
            &self.mu_corner,
            u,
            v,
            ku,
            kv,
        );
    }
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

/// `(ku, kv) = dV·∇·(2μD(u, v))` on the unknown faces `ux` × rows, columns × `vy`, with cell
/// viscosities `mu` and corner viscosities `mc`; `u`, `v` with ghosts filled.
pub(crate) fn viscous_divergence(
    g: &Grid,
    ux: FaceRange,
    vy: FaceRange,
    mu: &Field,
    mc: &Field,
    u: &Field,
    v: &Field,
    ku: &mut Field,
    kv: &mut Field,
) {
    let m = &g.metric;
    let (dx, dy) = (g.dx, g.dy);
    let s = u.stride();
    let (ud, vd, mu, mc) = (u.data(), v.data(), mu.data(), mc.data());
    // Rows in parallel; each row writes its own entries (bit-identical on any thread count).
    let r0 = u.idx(-G, 0);
    let ny = g.ny;
    for_each_row(&mut ku.data_mut()[r0..r0 + ny * s], s, |j, row| {
        let jj = j as isize;
        for i in ux.lo..ux.hi {
            let k = u.idx(i, jj);
            let txx_e = 2.0 * mu[k] * (ud[k + 1] - ud[k]) / dx;
            let txx_w = 2.0 * mu[k - 1] * (ud[k] - ud[k - 1]) / dx;
            let txy_n = mc[k + s] * ((ud[k + s] - ud[k]) / dy + (vd[k + s] - vd[k + s - 1]) / dx);
            let txy_s = mc[k] * ((ud[k] - ud[k - s]) / dy + (vd[k] - vd[k - 1]) / dx);
            let hoop = m.hoop_x(i);
            let mu_f = 0.5 * (mu[k - 1] + mu[k]);
            row[k - r0 - j * s] = dy * (m.rc(i) * txx_e - m.rc(i - 1) * txx_w)
                + dx * m.rx(i) * (txy_n - txy_s)
                - dx * dy * m.rx(i) * 2.0 * mu_f * ud[k] * hoop * hoop;
        }
    });
    let rows = (vy.hi - vy.lo).max(0) as usize;
    let r0 = v.idx(-G, vy.lo);
    for_each_row(&mut kv.data_mut()[r0..r0 + rows * s], s, |jr, row| {
        let j = vy.lo + jr as isize;
        for i in 0..g.nx as isize {
            let k = v.idx(i, j);
            let tyy_n = 2.0 * mu[k] * (vd[k + s] - vd[k]) / dy;
            let tyy_s = 2.0 * mu[k - s] * (vd[k] - vd[k - s]) / dy;
            let txy_e = mc[k + 1] * ((ud[k + 1] - ud[k + 1 - s]) / dy + (vd[k + 1] - vd[k]) / dx);
            let txy_w = mc[k] * ((ud[k] - ud[k - s]) / dy + (vd[k] - vd[k - 1]) / dx);
            row[k - r0 - jr * s] =
                dx * m.rc(i) * (tyy_n - tyy_s) + dy * (m.rx(i + 1) * txy_e - m.rx(i) * txy_w);
        }
    });
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

impl LinearOperator for ViscousOperator {
    fn apply(&mut self, x: &[f64], y: &mut [f64]) {
        let mut xu = std::mem::take(&mut self.xu);
        let mut xv = std::mem::take(&mut self.xv);
        let mut ku = std::mem::take(&mut self.ku);
        let mut kv = std::mem::take(&mut self.kv);
        scatter(&self.faces, x, &mut xu, &mut xv);
        self.bc
            .fill_velocity(&self.grid, &mut xu, &mut xv, 0.0, true);
        self.stress_divergence(&xu, &xv, &mut ku, &mut kv);
        let td = self.theta_dt;
        let (ux, vy) = (self.faces.ux, self.faces.vy);
        let nur = (ux.hi - ux.lo) as usize;
        let nu = self.faces.nu();
        let nx = self.grid.nx;
        let mass = &self.mass;
        let (kud, kvd) = (ku.data(), kv.data());
        let (yu, yv) = y.split_at_mut(nu);
        if nur > 0 {
            for_each_row(yu, nur, |j, row| {
                let k0 = ku.idx(ux.lo, j as isize);
                for (i, y) in row.iter_mut().enumerate() {
                    let c = j * nur + i;
                    *y = mass[c] * x[c] - td * kud[k0 + i];
                }
            });
        }
        for_each_row(yv, nx, |jr, row| {
            let k0 = kv.idx(0, vy.lo + jr as isize);
            for (i, y) in row.iter_mut().enumerate() {
                let c = nu + jr * nx + i;
                *y = mass[c] * x[c] - td * kvd[k0 + i];
            }
        });
        self.xu = xu;
        self.xv = xv;
        self.ku = ku;
        self.kv = kv;
    }
}

impl Stage for ViscousStage {
    fn run(&mut self, ctx: &StepContext, state: &mut State) -> Result<StageStats, StageError> {
        let g = ctx.grid;
        let m = &g.metric;
        let (dx, dy) = (g.dx, g.dy);
        let op = &mut self.op;
        op.theta_dt = self.theta * ctx.dt;
        // Cell and corner viscosities, face densities.
        op.mu.copy_from(&state.mu);
        corner_viscosity(g, &state.mu, &mut op.mu_corner);
        let rho = &state.rho;
        let (mass, diag) = (&mut op.mass, &mut self.diag);
        let (mu, mc) = (&op.mu, &op.mu_corner);
        let td = op.theta_dt;
        let s = mu.stride();
        {
            let (mud, mcd, rd) = (mu.data(), mc.data(), rho.data());
            let (ux, vy) = (op.faces.ux, op.faces.vy);
            let mut c = 0;
            for j in 0..g.ny as isize {
                for i in ux.lo..ux.hi {
                    let k = mu.idx(i, j);
                    mass[c] = 0.5 * (rd[k - 1] + rd[k]) * m.rx(i) * dx * dy;
                    let h = m.hoop_x(i);
                    let kdiag = dy * 2.0 * (m.rc(i) * mud[k] + m.rc(i - 1) * mud[k - 1]) / dx
                        + dx * m.rx(i) * (mcd[k + s] + mcd[k]) / dy
                        + dx * dy * m.rx(i) * (mud[k - 1] + mud[k]) * h * h;
                    diag[c] = mass[c] + td * kdiag;
                    c += 1;
                }
            }
            for j in vy.lo..vy.hi {
                for i in 0..g.nx as isize {
                    let k = mu.idx(i, j);
                    mass[c] = 0.5 * (rd[k - s] + rd[k]) * m.rc(i) * dx * dy;
                    let kdiag = dx * m.rc(i) * 2.0 * (mud[k] + mud[k - s]) / dy
                        + dy * (m.rx(i + 1) * mcd[k + 1] + m.rx(i) * mcd[k]) / dx;
                    diag[c] = mass[c] + td * kdiag;
                    c += 1;
                }
            }
        }
        // Right-hand side Δt·K(V*, θ bⁿ⁺¹ + (1−θ) bⁿ): K is affine in the boundary data b, so
        // this is the θ-weighted sum of the implicit and explicit parts' boundary forcing.
        let when = WallTime::Blend {
            t0: ctx.t,
            t1: ctx.t + ctx.dt,
            theta: self.theta,
        };
        ctx.bc.fill_velocity_at(g, &mut state.u, &mut state.v, when);
        let mut ku = std::mem::take(&mut op.ku);
        let mut kv = std::mem::take(&mut op.kv);
        op.stress_divergence(&state.u, &state.v, &mut ku, &mut kv);
        let rhs = &mut self.rhs;
        op.faces.for_each(|c, is_u, k| {
            rhs[c] = ctx.dt * if is_u { ku.data()[k] } else { kv.data()[k] };
        });
        op.ku = ku;
        op.kv = kv;
        let bnorm = rhs.iter().map(|x| x * x).sum::<f64>().sqrt();
        let stats = if bnorm == 0.0 {
            SolveStats {
                iterations: 0,
                residual: 0.0,
                converged: true,
            }
        } else {
            self.delta.fill(0.0);
            let tol = self.tol * bnorm;
            let use_mg = match self.preconditioner {
                ViscousPreconditioner::Jacobi => false,
                ViscousPreconditioner::Multigrid => true,
                ViscousPreconditioner::Auto => {
                    // Jacobi-preconditioned condition number ≲ max(diag/mass); CG needs
                    // ~10√κ iterations at 1e-9, at half the block multigrid's cost per
                    // iteration, which needs ~16: break-even near κ ≈ 11.
                    let ratio = self.diag.iter().zip(&op.mass).fold(0.0f64, |m, (d, ms)| {
                        if *ms > 0.0 { m.max(d / ms) } else { m }
                    });
                    ratio > AUTO_MULTIGRID_RATIO
                }
            };
            let measure = |r: &[f64]| dot(r, r).sqrt();
            let st = if use_mg {
                self.blocks.setup(g, op, &self.diag);
                self.pcg.solve(
                    op,
                    &self.blocks,
                    rhs,
                    &mut self.delta,
                    tol,
                    self.max_iter,
                    measure,
                )
            } else {
                self.pcg.solve(
                    op,
                    self.diag.as_slice(),
                    rhs,
                    &mut self.delta,
                    tol,
                    self.max_iter,
                    measure,
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
            let delta = &self.delta;
            let (u, v) = (&mut state.u, &mut state.v);
            op.faces.for_each(|c, is_u, k| {
                if is_u {
                    u.data_mut()[k] += delta[c];
                } else {
                    v.data_mut()[k] += delta[c];
                }
            });
            SolveStats {
                residual: st.residual / bnorm,
                ..st
            }
        };
        Ok(StageStats { solve: Some(stats) })
    }
}
