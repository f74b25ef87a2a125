//! Pressure projection: `V^{n+1} = V^{n+2/3} − Δt ∇p/ρ` with `∇·V^{n+1} = 0`
//! (seed Eqs. 21–23).
//!
//! **Equation.** `∇·(∇p/ρ) = ∇·V^{n+2/3}/Δt`, variable coefficient, with the face density the
//! average of the two cells (so the density stays inside the divergence, smooth across the
//! interface, as the seed asks). Finite-volume form per cell, axisymmetric through the face radii:
//! `Σ_f (A_f/(ρ_f h)) (p_C − p_F) = −(Σ_f A_f V_f·n)/Δt`, a symmetric positive (semi-)definite
//! five-point system ([`efsi_linalg::Stencil5`]). Walls contribute no flux (homogeneous
//! Neumann), periodic sides wrap, outflow sides fix p = 0 on the boundary face. Without an
//! outflow side the system is singular (p up to a constant): the right-hand side is projected on
//! the range (zero sum) and the mean pressure set to zero.
//!
//! **Solver.** Conjugate gradient warm-started from the previous pressure, preconditioned by
//! the geometric multigrid W-cycle of [`efsi_linalg::Multigrid`] (default: iterations
//! independent of the grid and of density ratios up to 1e4) or, as the seed, by incomplete
//! Cholesky IC(0) (scene `numerics.projection.solver: Multigrid | IncompleteCholesky`). It
//! stops when the divergence the correction would leave satisfies `max_cells |∇·V^{n+1}|·Δt ≤
//! tol` (dimensionless: the relative volume change of a cell per step; scene
//! `numerics.projection.tolerance`, default 1e-6), after at least one iteration: the warm start
//! alone often meets the tolerance, and stopping there would leave its divergence in place step
//! after step (a steady state kept `|∇·u|` up to `tol/Δt` and, stopping at 0 and 1 iterations by
//! turns, never settled); one iteration a step drives it to zero across steps. Since
//! `dV·∇·V^{n+1} = −Δt·r` for the residual `r`, the criterion is `max Δt²|r|/dV ≤ tol`, checked
//! on the true residual.
//!
//! **Postcondition** (checked in debug builds): `max |∇·V^{n+1}|·Δt ≤ tol` after the update.
//!
//! **Parallelism.** Assembly, right-hand side, the solver's vector work and the velocity update
//! run over rows in parallel (rayon); each writes its own entries and every reduction has a
//! fixed order, so the result is bit-identical on any number of threads. Nothing is allocated
//! after the first step.

use efsi_core::scene::{Boundary, PressureSolver, Side};
use efsi_core::{
    BoundarySet, FieldId, Grid, Phase, Scene, Stage, StageError, StagePlugin, StageStats, State,
    StepContext, ops,
};
use efsi_linalg::par::{for_each_mut, for_each_row};
use efsi_linalg::{IncompleteCholesky, Multigrid, Norm, Pcg, Stencil5};

/// The projection stage plugin.
pub struct Projection;

impl StagePlugin for Projection {
    fn name(&self) -> &'static str {
        "projection"
    }
    fn phase(&self) -> Phase {
        Phase::Projection
    }
    fn reads(&self) -> &'static [FieldId] {
        &[
            FieldId::VelocityX,
            FieldId::VelocityY,
            FieldId::Density,
            FieldId::Pressure,
        ]
    }
    fn writes(&self) -> &'static [FieldId] {
        &[FieldId::VelocityX, FieldId::VelocityY, FieldId::Pressure]
    }
    fn needed(&self, _scene: &Scene) -> bool {
        true
    }
    fn build(
        &self,
        scene: &Scene,
        grid: &Grid,
        bc: &BoundarySet,
        _shared: &mut efsi_core::Resources,
    ) -> Result<Box<dyn Stage>, String> {
        let n = grid.cells();
        Ok(Box::new(ProjectionStage {
            tol: scene.numerics.projection.tolerance,
            max_iter: scene.numerics.projection.max_iterations,
            a: Stencil5::new(grid.nx, grid.ny, bc.periodic(0), bc.periodic(1)),
            precond: match scene.numerics.projection.solver {
                PressureSolver::Multigrid => Precond::Multigrid(Multigrid::new(2)),
                PressureSolver::IncompleteCholesky => {
                    Precond::IncompleteCholesky(IncompleteCholesky::new())
                }
            },
            pcg: Pcg::new(n),
            b: vec![0.0; n],
            x: vec![0.0; n],
            weight: vec![0.0; n],
            weight_dt: f64::NAN,
            increment: crate::elastic::coupled(scene).then(|| efsi_core::Field::zeros(grid)),
        }))
    }
}

/// The preconditioner the scene chose.
enum Precond {
    Multigrid(Multigrid),
    IncompleteCholesky(IncompleteCholesky),
}

struct ProjectionStage {
    tol: f64,
    max_iter: usize,
    a: Stencil5,
    precond: Precond,
    pcg: Pcg,
    b: Vec<f64>,
    x: Vec<f64>,
    weight: Vec<f64>,
    /// The Δt the weights were computed for (they change only with it).
    weight_dt: f64,
    /// With the coupled elastic step (`numerics.elastic.coupling: Coupled`), which has already
    /// made the velocity nearly divergence-free and left its pressure in the state: the
    /// pressure increment that removes what remains, solved for from zero, applied to the
    /// velocity and added to that pressure. `None` in the split step.
    increment: Option<efsi_core::Field>,
}

/// Assemble the projection's five-point matrix `Σ_f (A_f/(ρ_f h)) (p_C − p_F)` from the density
/// (rows in parallel).
pub(crate) fn assemble(a: &mut Stencil5, grid: &Grid, bc: &BoundarySet, rho: &efsi_core::Field) {
    let (nx, ny) = (grid.nx, grid.ny);
    let m = &grid.metric;
    let (dx, dy) = (grid.dx, grid.dy);
    let px = bc.periodic(0);
    let py = bc.periodic(1);
    for_each_row(&mut a.east, nx, |j, row| {
        let jj = j as isize;
        for (i, e) in row.iter_mut().enumerate() {
            let ii = i as isize;
            *e = if i + 1 < nx || px {
                let ie = if i + 1 < nx { ii + 1 } else { 0 };
                m.rx(ii + 1) * dy / (ops::face_density(rho[(ii, jj)], rho[(ie, jj)]) * dx)
            } else {
                0.0
            };
        }
    });
    for_each_row(&mut a.north, nx, |j, row| {
        let jj = j as isize;
        for (i, n) in row.iter_mut().enumerate() {
            let ii = i as isize;
            *n = if j + 1 < ny || py {
                let jn = if j + 1 < ny { jj + 1 } else { 0 };
                m.rc(ii) * dx / (ops::face_density(rho[(ii, jj)], rho[(ii, jn)]) * dy)
            } else {
                0.0
            };
        }
    });
    let outflow = |s: Side| *bc.get(s) == Boundary::Outflow;
    let (o_xmin, o_xmax, o_ymin, o_ymax) = (
        outflow(Side::XMin),
        outflow(Side::XMax),
        outflow(Side::YMin),
        outflow(Side::YMax),
    );
    let (east, north) = (&a.east, &a.north);
    for_each_row(&mut a.diag, nx, |j, row| {
        let jj = j as isize;
        for (i, dk) in row.iter_mut().enumerate() {
            let k = j * nx + i;
            let ii = i as isize;
            let w = if i > 0 {
                east[k - 1]
            } else if px {
                east[k + nx - 1]
            } else {
                0.0
            };
            let s = if j > 0 {
                north[k - nx]
            } else if py {
                north[k + (ny - 1) * nx]
            } else {
                0.0
            };
            let mut d = east[k] + north[k] + w + s;
            // Outflow sides: p = 0 on the boundary face, half a cell away.
            let r = rho[(ii, jj)];
            if i == 0 && o_xmin {
                d += 2.0 * m.rx(0) * dy / (r * dx);
            }
            if i + 1 == nx && o_xmax {
                d += 2.0 * m.rx(ii + 1) * dy / (r * dx);
            }
            if j == 0 && o_ymin {
                d += 2.0 * m.rc(ii) * dx / (r * dy);
            }
            if j + 1 == ny && o_ymax {
                d += 2.0 * m.rc(ii) * dx / (r * dy);
            }
            *dk = d;
        }
    });
}

impl Stage for ProjectionStage {
    fn projects(&self) -> bool {
        true
    }

    fn run(&mut self, ctx: &StepContext, state: &mut State) -> Result<StageStats, StageError> {
        let grid = ctx.grid;
        let (nx, ny) = (grid.nx, grid.ny);
        let dt = ctx.dt;
        assemble(&mut self.a, grid, ctx.bc, &state.rho);
        match &mut self.precond {
            Precond::Multigrid(mg) => mg.setup(&self.a),
            Precond::IncompleteCholesky(ic) => ic.factor(&self.a),
        }
        // Right-hand side, the residual weights Δt²/dV and the initial guess.
        let (u, v, p) = (&state.u, &state.v, &state.p);
        // −(net volume outflux)/Δt, as `ops::net_outflux` computes it, over slices (it
        // vectorises).
        let (rx, rc, s) = (
            grid.metric.rx_row(nx + 1),
            grid.metric.rc_row(nx),
            u.stride(),
        );
        let (ud, vd, (dx, dy)) = (u.data(), v.data(), (grid.dx, grid.dy));
        for_each_row(&mut self.b, nx, |j, row| {
            let k0 = u.idx(0, j as isize);
            let (uw, ue) = (&ud[k0..k0 + nx], &ud[k0 + 1..k0 + 1 + nx]);
            let (vs, vn) = (&vd[k0..k0 + nx], &vd[k0 + s..k0 + s + nx]);
            let (rw, re) = (&rx[..nx], &rx[1..=nx]);
            for i in 0..nx {
                let out = (re[i] * ue[i] - rw[i] * uw[i]) * dy + rc[i] * (vn[i] - vs[i]) * dx;
                row[i] = -out / dt;
            }
        });
        if dt != self.weight_dt {
            for_each_row(&mut self.weight, nx, |_, row| {
                for (i, w) in row.iter_mut().enumerate() {
                    *w = dt * dt / grid.cell_volume(i as isize);
                }
            });
            self.weight_dt = dt;
        }
        if self.increment.is_some() {
            self.x.fill(0.0);
        } else {
            for_each_row(&mut self.x, nx, |j, row| {
                for (i, x) in row.iter_mut().enumerate() {
                    *x = p[(i as isize, j as isize)];
                }
            });
        }
        let singular = !ctx.bc.has_pressure_reference();
        if singular {
            let mean = self.b.iter().sum::<f64>() / self.b.len() as f64;
            self.b.iter_mut().for_each(|b| *b -= mean);
        }
        let norm = Norm::MaxWeighted(&self.weight);
        let (a, b, x) = (&mut self.a, &self.b, &mut self.x);
        let st = match &self.precond {
            Precond::Multigrid(mg) => {
                self.pcg
                    .solve_norm(a, mg, b, x, self.tol, self.max_iter, norm)
            }
            Precond::IncompleteCholesky(ic) => {
                self.pcg
                    .solve_norm(a, ic, b, x, self.tol, self.max_iter, norm)
            }
        };
        if !st.converged {
            return Err(StageError {
                stage: "projection".into(),
                message: format!(
                    "pressure solve did not converge in {} iterations: max|∇·u|·Δt = {:.3e} > tolerance {:.1e}; \
                     raise numerics.projection.max_iterations or loosen numerics.projection.tolerance",
                    st.iterations, st.residual, self.tol
                ),
            });
        }
        if singular {
            let mean = self.x.iter().sum::<f64>() / self.x.len() as f64;
            for_each_mut(&mut self.x, |_, p| *p -= mean);
        }
        let (x, ps) = (&self.x, state.p.stride());
        let p0 = state.p.idx(0, 0);
        let target = match &mut self.increment {
            Some(f) => f,
            None => &mut state.p,
        };
        for_each_row(&mut target.data_mut()[p0..p0 + ny * ps], ps, |j, row| {
            row[..nx].copy_from_slice(&x[j * nx..(j + 1) * nx]);
        });
        ctx.bc.fill_scalar(grid, target, true);
        if let Some(f) = &self.increment {
            // The pressure is the coupled step's plus what is found here.
            for (p, x) in state.p.data_mut().iter_mut().zip(f.data()) {
                *p += x;
            }
        }
        // V^{n+1} = V^{n+2/3} − Δt ∇p/ρ on the unknown faces (∇ of the increment after the
        // coupled step).
        let ux = ctx.bc.normal_faces(0, nx);
        let vy = ctx.bc.normal_faces(1, ny);
        let (p, rho) = (self.increment.as_ref().unwrap_or(&state.p), &state.rho);
        let s = p.stride();
        let (pd, rd) = (p.data(), rho.data());
        let cx = dt / grid.dx;
        let cy = dt / grid.dy;
        let base = p.idx(0, 0);
        let ud = &mut state.u.data_mut()[base..base + ny * s];
        let (lo, hi) = (ux.lo.max(0) as usize, ux.hi.max(0) as usize);
        for_each_row(ud, s, |j, row| {
            if hi <= lo {
                return;
            }
            // Over slices (it vectorises): faces lo..hi of row j.
            let k = base + j * s + lo;
            let n = hi - lo;
            let (pe, pw) = (&pd[k..k + n], &pd[k - 1..k - 1 + n]);
            let (re, rw) = (&rd[k..k + n], &rd[k - 1..k - 1 + n]);
            for (t, u) in row[lo..hi].iter_mut().enumerate() {
                *u -= cx * (pe[t] - pw[t]) / ops::face_density(re[t], rw[t]);
            }
        });
        let v0 = p.idx(0, vy.lo);
        let vrows = (vy.hi - vy.lo).max(0) as usize;
        let vd = &mut state.v.data_mut()[v0..v0 + vrows * s];
        for_each_row(vd, s, |j, row| {
            let k = v0 + j * s;
            let (pn, ps) = (&pd[k..k + nx], &pd[k - s..k - s + nx]);
            let (rn, rs) = (&rd[k..k + nx], &rd[k - s..k - s + nx]);
            for (i, v) in row[..nx].iter_mut().enumerate() {
                *v -= cy * (pn[i] - ps[i]) / ops::face_density(rn[i], rs[i]);
            }
        });
        if cfg!(debug_assertions) {
            ctx.bc
                .fill_velocity(grid, &mut state.u, &mut state.v, ctx.t + dt, false);
            let d = ops::max_abs_div(grid, &state.u, &state.v) * dt;
            // A non-finite divergence is not this check's to report: the scheduler names the
            // first non-finite velocity (and the stage) right after the stage.
            debug_assert!(
                !d.is_finite()
                    || d <= self.tol * (1.0 + 1e-6) + 1e-15
                    || singular_inconsistent(ctx, state),
                "projection postcondition: max|∇·u|·Δt = {d:e} > {:e}",
                self.tol
            );
        }
        Ok(StageStats { solve: Some(st) })
    }
}

/// A closed domain whose boundary velocities carry a net flux cannot be made divergence-free
/// everywhere; the postcondition does not apply (only reachable with inconsistent scenes).
fn singular_inconsistent(ctx: &StepContext, state: &State) -> bool {
    let g = ctx.grid;
    let mut net = 0.0;
    for j in 0..g.ny as isize {
        for i in 0..g.nx as isize {
            net += ops::net_outflux(g, &state.u, &state.v, i, j);
        }
    }
    !ctx.bc.has_pressure_reference() && net.abs() > 1e-12
}
