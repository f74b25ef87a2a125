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
//! **Parallelism and memory.** Tendencies run over bands of rows in parallel, each face flux
//! computed once and kept only for the row that needs it (no full-grid flux arrays); updates
//! run over rows in parallel (rayon); each band or row writes its own faces, so results are
//! bit-identical on any number of threads. The stage uses 8 full-grid arrays while it runs —
//! the tendencies (4), the start-of-step velocity (2) and the current stage's face masses (2)
//! — taken from the pipeline's pool of work vectors (`scratch`), which the later stages of the
//! step reuse. It keeps from one step to the next only the `WholeStep` predictor's two arrays.

use crate::faces::UnknownFaces;
use crate::scratch::{self, Scratch};
use efsi_core::scene::options::StageOptions;
use efsi_core::scene::{Options, OptionsDecl};
use efsi_core::schedule::VELOCITY;
use efsi_core::{
    BoundarySet, Field, FieldId, Grid, Phase, Region, Scene, Stage, StageError, StagePlugin,
    StageStats, State, StepContext,
};
use efsi_linalg::par::{self, copy};
use serde::{Deserialize, Serialize};

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
    fn name(&self) -> &'static str {
        "advection"
    }
    fn phase(&self) -> Phase {
        Phase::Advection
    }
    fn reads(&self) -> &'static [FieldId] {
        &[FieldId::VelocityX, FieldId::VelocityY, FieldId::Density]
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
        // Band edges: at most one band per BAND rows of the tallest family (the v-faces with
        // an outflow side have ny + 1 rows), plus the top edge.
        // A band edge holds one padded row of the fields.
        let [row, rows, planes] = grid.padded();
        let bands = (grid.ny + 1).div_ceil(BAND);
        let padded = row * rows * planes;
        let carry = if whole_step(scene, options)? {
            Some(Carry {
                u: vec![0.0; padded],
                v: vec![0.0; padded],
                dt: 0.0,
            })
        } else {
            None
        };
        Ok(Box::new(AdvectionStage {
            carry,
            scratch: Scratch::reserve(shared, WORK * padded),
            edge_m: vec![0.0; (bands + 1) * row],
            edge_q: vec![0.0; (bands + 1) * row],
            row_x: (0..bands).map(|_| vec![0.0; 2 * row]).collect(),
        }))
    }
}

/// Rows of tendencies per band of the fused flux-and-difference pass (bands run in parallel).
const BAND: usize = 16;

/// Full-grid work arrays the stage takes from the pipeline's pool, in this order: the
/// momentum tendencies `−∇·(m a ⊗ u)` on u- and v-faces, the mass tendencies `−∇·(m a)`, the
/// start-of-step velocity (the start-of-step face masses are recomputed from the density,
/// which advection does not change), and the current stage's face masses.
const WORK: usize = 8;

/// What the `WholeStep` predictor keeps from step to step: the velocity the stage left at the
/// previous step (`Y` in the module docs, padded like the fields) and that step's Δt (0: no
/// history yet).
struct Carry {
    u: Vec<f64>,
    v: Vec<f64>,
    dt: f64,
}

struct AdvectionStage {
    /// The `WholeStep` predictor's history (`None` with `Advection`).
    carry: Option<Carry>,
    /// The pipeline's work vectors ([`WORK`] padded full-grid arrays while the stage runs).
    scratch: Scratch,
    /// Mass and momentum fluxes through the bottom edge of each band of rows, and the top of
    /// the last (scratch, one padded row per edge).
    edge_m: Vec<f64>,
    edge_q: Vec<f64>,
    /// Each band's mass and momentum fluxes through the x-faces of its current row (scratch).
    row_x: Vec<Vec<f64>>,
}

/// van Leer limited face value for advecting velocity `a` between `c0` (left/below) and `c1`,
/// with `cm` left of `c0` and `c2` right of `c1`.
#[inline(always)]
pub(crate) fn face_value(a: f64, cm: f64, c0: f64, c1: f64, c2: f64) -> f64 {
    let (up, c, d) = if a >= 0.0 { (cm, c0, c1) } else { (c2, c1, c0) };
    let denom = d - c;
    if denom.abs() < 1e-300 {
        return c;
    }
    let r = (c - up) / denom;
    let psi = (r + r.abs()) / (1.0 + r.abs());
    c + 0.5 * psi * denom
}

/// [`face_value`] in van Leer's harmonic form, one division instead of two and no branch on
/// the data: with `p = q_C − q_U` and `q = q_D − q_C`, `½ψ(p/q)·q = pq/(p + q)` where
/// `pq > 0`, else 0 — the same limiter, rounded differently.
#[inline(always)]
fn limited(a: f64, cm: f64, c0: f64, c1: f64, c2: f64) -> f64 {
    let pos = a >= 0.0;
    let up = if pos { cm } else { c2 };
    let c = if pos { c0 } else { c1 };
    let d = if pos { c1 } else { c0 };
    let (p, q) = (c - up, d - c);
    let pq = p * q;
    c + if pq > 0.0 { pq / (p + q) } else { 0.0 }
}

/// Largest stable Δt of the explicit convective term at Courant number `cfl`
/// ([`crate::ops::convective_rate`]).
pub fn advective_dt(grid: &Grid, u: &Field, v: &Field, cfl: f64) -> Option<f64> {
    let rate = crate::ops::convective_rate(grid, u, v);
    (rate > 0.0).then(|| cfl / rate)
}

/// Flux `(a m̃, a m̃ q̃)` through a control-volume face with advecting velocity `a`, from the
/// masses `m` and values `q` of the four control volumes along the flux direction.
#[inline(always)]
fn flux(a: f64, m: [f64; 4], q: [f64; 4]) -> (f64, f64) {
    let fm = a * limited(a, m[0], m[1], m[2], m[3]);
    (fm, fm * limited(a, q[0], q[1], q[2], q[3]))
}

/// A family of control volumes (centred on the u- or the v-faces): its face fluxes and their
/// balance (methods inlined into [`tendencies`]' loops).
trait Family: Sync {
    /// (Mass, momentum) flux through the x-face of the control volume left of face `k`.
    fn xflux(&self, k: usize) -> (f64, f64);
    /// (Mass, momentum) flux through the y-face of the control volume below face `k`.
    fn yflux(&self, k: usize) -> (f64, f64);
    /// (Momentum, mass) tendency of the control volume of column `i` from its west, east,
    /// south and north fluxes.
    fn diff(&self, i: isize, f: [(f64, f64); 4]) -> (f64, f64);
}

/// What both families read: the velocity, the face masses of the family, the metric.
struct Flow<'a> {
    u: &'a [f64],
    v: &'a [f64],
    m: &'a [f64],
    s: usize,
    metric: &'a efsi_core::grid::Metric,
    dx: f64,
    dy: f64,
}

#[inline(always)]
fn at(d: &[f64], k: usize, o: usize) -> [f64; 4] {
    [d[k - 2 * o], d[k - o], d[k], d[k + o]]
}

/// u control volumes, centred on x-faces: east/west faces at cell centres (the flux through
/// the centre left of face k), north/south faces at corners (v averaged over the two columns;
/// the flux below face k).
struct UFamily<'a>(Flow<'a>);

impl Family for UFamily<'_> {
    #[inline(always)]
    fn xflux(&self, k: usize) -> (f64, f64) {
        let f = &self.0;
        flux(0.5 * (f.u[k - 1] + f.u[k]), at(f.m, k, 1), at(f.u, k, 1))
    }
    #[inline(always)]
    fn yflux(&self, k: usize) -> (f64, f64) {
        let f = &self.0;
        flux(
            0.5 * (f.v[k - 1] + f.v[k]),
            at(f.m, k, f.s),
            at(f.u, k, f.s),
        )
    }
    #[inline(always)]
    fn diff(&self, i: isize, [w, e, so, no]: [(f64, f64); 4]) -> (f64, f64) {
        let (m, dx, dy) = (self.0.metric, self.0.dx, self.0.dy);
        let r = m.rx(i);
        if r == 0.0 {
            return (0.0, 0.0);
        }
        let (re, rw) = (m.rc(i), m.rc(i - 1));
        (
            -((re * e.1 - rw * w.1) / (dx * r) + (no.1 - so.1) / dy),
            -((re * e.0 - rw * w.0) / (dx * r) + (no.0 - so.0) / dy),
        )
    }
}

/// v control volumes, centred on y-faces: east/west faces at corners (u averaged over the two
/// rows; the flux left of face k), north/south faces at cell centres (the flux below face k).
struct VFamily<'a>(Flow<'a>);

impl Family for VFamily<'_> {
    #[inline(always)]
    fn xflux(&self, k: usize) -> (f64, f64) {
        let f = &self.0;
        flux(0.5 * (f.u[k - f.s] + f.u[k]), at(f.m, k, 1), at(f.v, k, 1))
    }
    #[inline(always)]
    fn yflux(&self, k: usize) -> (f64, f64) {
        let f = &self.0;
        flux(
            0.5 * (f.v[k - f.s] + f.v[k]),
            at(f.m, k, f.s),
            at(f.v, k, f.s),
        )
    }
    #[inline(always)]
    fn diff(&self, i: isize, [w, e, so, no]: [(f64, f64); 4]) -> (f64, f64) {
        let (m, dx, dy) = (self.0.metric, self.0.dx, self.0.dy);
        let (re, rw, r) = (m.rx(i + 1), m.rx(i), m.rc(i));
        (
            -((re * e.1 - rw * w.1) / (dx * r) + (no.1 - so.1) / dy),
            -((re * e.0 - rw * w.0) / (dx * r) + (no.0 - so.0) / dy),
        )
    }
}

/// The tendencies of one control-volume family, `rows = qt.len() / s` padded rows from padded
/// index `r0`, faces `i0..i1` of each row: `(qt, mt)[k] = fam.diff(i, [west, east, south,
/// north])` with the (mass, momentum) fluxes `fam.xflux(k)` through the face left of `k` and
/// `fam.yflux(k)` through the face below. Each flux is computed once, without a full-grid flux array: the
/// rows are split into bands of [`BAND`] rows (in parallel); the fluxes through a band's bottom
/// edge (and the top of the last) are computed first into `edge_*`, then each band walks its
/// rows upwards: the x-face fluxes of the row into the band's `row_x`, the fluxes below the
/// next row into that row's own tendency entries (overwritten once read). The floating-point
/// operations per entry are those of storing every flux and differencing them, so the results
/// are the same, bit for bit, on any number of threads.
#[allow(clippy::too_many_arguments)]
fn tendencies(
    qt: &mut [f64],
    mt: &mut [f64],
    edge_m: &mut [f64],
    edge_q: &mut [f64],
    row_x: &mut [Vec<f64>],
    s: usize,
    r0: usize,
    (i0, i1): (isize, isize),
    fam: &impl Family,
) {
    let rows = qt.len() / s;
    if rows == 0 || i1 <= i0 {
        return;
    }
    let nb = rows.div_ceil(BAND);
    let (em, eq) = (&mut edge_m[..(nb + 1) * s], &mut edge_q[..(nb + 1) * s]);
    let (c0, c1) = ((i0 + efsi_core::G) as usize, (i1 + efsi_core::G) as usize);
    par::rows((&mut *em, &mut *eq), s).for_each(|b, (fm, fq)| {
        y_row(fam, r0 + (b * BAND).min(rows) * s, c0..c1, fm, fq);
    });
    let (em, eq) = (&*em, &*eq);
    let len = qt.len();
    par::rows(
        (qt, mt, par::per_row(&mut row_x[..nb], BAND * s, len)),
        BAND * s,
    )
    .for_each(|b, (qb, mb, x)| {
        let x = x.item();
        let n = qb.len() / s;
        let (xm, xq) = x.split_at_mut(s);
        qb[c0..c1].copy_from_slice(&eq[b * s + c0..b * s + c1]);
        mb[c0..c1].copy_from_slice(&em[b * s + c0..b * s + c1]);
        for jr in 0..n {
            let k0 = r0 + (b * BAND + jr) * s;
            let (qr, qn) = qb[jr * s..].split_at_mut(s);
            let (mr, mn) = mb[jr * s..].split_at_mut(s);
            let (nm, nq): (&[f64], &[f64]) = if jr + 1 == n {
                (&em[(b + 1) * s..], &eq[(b + 1) * s..])
            } else {
                y_row(fam, k0 + s, c0..c1, mn, qn);
                (mn, qn)
            };
            x_row(fam, k0, c0..c1 + 1, xm, xq);
            diff_row(fam, c0..c1, [xm, xq, nm, nq], qr, mr);
        }
    });
}

// The row loops are functions of their own, not inlined: their arrays are arguments, which
// the compiler knows do not overlap, so the loops vectorise.

/// `(fm, fq)[c] = fam.yflux(k0 + c)` for `c` in `cs`.
#[inline(never)]
fn y_row(fam: &impl Family, k0: usize, cs: std::ops::Range<usize>, fm: &mut [f64], fq: &mut [f64]) {
    for c in cs {
        (fm[c], fq[c]) = fam.yflux(k0 + c);
    }
}

/// `(fm, fq)[c] = fam.xflux(k0 + c)` for `c` in `cs`.
#[inline(never)]
fn x_row(fam: &impl Family, k0: usize, cs: std::ops::Range<usize>, fm: &mut [f64], fq: &mut [f64]) {
    for c in cs {
        (fm[c], fq[c]) = fam.xflux(k0 + c);
    }
}

/// The tendencies of a row from its x-face fluxes `xm, xq`, the fluxes below it in `(mr, qr)`
/// (overwritten) and above it `nm, nq`.
#[inline(never)]
fn diff_row(
    fam: &impl Family,
    cs: std::ops::Range<usize>,
    [xm, xq, nm, nq]: [&[f64]; 4],
    qr: &mut [f64],
    mr: &mut [f64],
) {
    for c in cs {
        let i = c as isize - efsi_core::G;
        let f = [
            (xm[c], xq[c]),
            (xm[c + 1], xq[c + 1]),
            (mr[c], qr[c]),
            (nm[c], nq[c]),
        ];
        (qr[c], mr[c]) = fam.diff(i, f);
    }
}

impl AdvectionStage {
    /// Tendencies of mass and momentum for velocity `(u, v)` and face masses `(mu, mv)`
    /// (ghosts filled), on the unknown faces (see [`tendencies`]).
    #[allow(clippy::too_many_arguments)]
    fn rhs(
        &mut self,
        ctx: &StepContext,
        u: &Field,
        v: &Field,
        [mu, mv]: [&[f64]; 2],
        [qu, qv, mu_, mv_]: [&mut [f64]; 4],
    ) {
        let g = ctx.grid;
        let s = u.stride();
        let flow = |m| Flow {
            u: u.data(),
            v: v.data(),
            m,
            s,
            metric: &g.metric,
            dx: g.dx,
            dy: g.dy,
        };
        let ux = ctx.bc.normal_faces(0, g.nx);
        let vy = ctx.bc.normal_faces(1, g.ny);
        let row0 = |j: isize| u.idx(-efsi_core::G, j);
        let r0 = row0(0);
        let n = g.ny * s;
        tendencies(
            &mut qu[r0..r0 + n],
            &mut mu_[r0..r0 + n],
            &mut self.edge_m,
            &mut self.edge_q,
            &mut self.row_x,
            s,
            r0,
            (ux.lo, ux.hi),
            &UFamily(flow(mu)),
        );
        let rows = (vy.hi - vy.lo).max(0) as usize;
        let r0 = row0(vy.lo);
        let n = rows * s;
        tendencies(
            &mut qv[r0..r0 + n],
            &mut mv_[r0..r0 + n],
            &mut self.edge_m,
            &mut self.edge_q,
            &mut self.row_x,
            s,
            r0,
            (0, g.nx as isize),
            &VFamily(flow(mv)),
        );
    }
}

/// Face masses (densities) from the cell densities, ghosts included (rows in parallel): on
/// u-faces every padded row but the last, columns 1.. and column 0 a copy of column 1; on
/// v-faces every padded row from the second, row 0 a copy of row 1, all columns but the last.
/// The u-faces' last row and the v-faces' last column, outside every stencil, are set to zero
/// (the arrays come from the shared pool, whatever they held).
fn face_masses(rho: &Field, mu: &mut [f64], mv: &mut [f64]) {
    let s = rho.stride();
    let rows = rho.rows();
    let r = rho.data();
    mu[(rows - 1) * s..].fill(0.0);
    mv.iter_mut().skip(s - 1).step_by(s).for_each(|m| *m = 0.0);
    par::rows(&mut mu[..(rows - 1) * s], s).for_each(|j, row| {
        let rr = &r[j * s..(j + 1) * s];
        for c in 1..s {
            row[c] = crate::ops::face_density(rr[c - 1], rr[c]);
        }
        row[0] = row[1];
    });
    par::rows(&mut *mv, s).for_each(|j, row| {
        let j = j.max(1);
        let (lo, hi) = (&r[(j - 1) * s..j * s], &r[j * s..(j + 1) * s]);
        for c in 0..s - 1 {
            row[c] = 0.5 * (lo[c] + hi[c]);
        }
    });
}

/// One Euler stage of SSP-RK2 on the unknown faces of one family ([`Euler::update`]).
struct Euler<'a> {
    dt: f64,
    /// `Δt/Δtₙ₋₁` of the `WholeStep` predictor, 0 without history.
    lag: f64,
    /// Whether this is the second stage (averaged with the start of the step).
    second: bool,
    rho: &'a Field,
}

impl Euler<'_> {
    /// The velocity `x` and face mass `m1` of the faces of `region` (normal to axis `a`) after
    /// an Euler stage from the current values with the tendencies `q` (momentum) and `dm`
    /// (mass); `x0` is the start-of-step velocity and `y` the velocity this stage left at the
    /// previous step (empty without history). Lines in parallel, each writing its own faces.
    fn update(
        &self,
        region: Region,
        a: usize,
        x: &mut Field,
        m1: &mut [f64],
        [x0, y, q, dm]: [&[f64]; 4],
    ) {
        let (dt, lag, second) = (self.dt, self.lag, self.second);
        let below = efsi_core::operators::minus(a);
        let m1 = region.storage(m1);
        region.for_each((x, m1), |l, (xr, mr)| {
            let n = l.len;
            let (x0, q, dm) = (
                &l.on(x0, [0; 3])[..n],
                &l.on(q, [0; 3])[..n],
                &l.on(dm, [0; 3])[..n],
            );
            let y = if lag != 0.0 {
                &l.on(y, [0; 3])[..n]
            } else {
                &[]
            };
            let (rho_lo, rho_hi) = (&self.rho.at(&l, below)[..n], &self.rho.at(&l, [0; 3])[..n]);
            let (xr, mr) = (&mut xr[..n], &mut mr[..n]);
            for c in 0..n {
                // The other stages' increment added to the first stage's velocity.
                let other = if lag != 0.0 {
                    lag * (x0[c] - y[c])
                } else {
                    0.0
                };
                // (m, m u) after an Euler step from the current stage values (the second
                // stage from the first's momentum, without that increment).
                let m_e = mr[c] + dt * dm[c];
                let q_e = if second && lag != 0.0 {
                    mr[c] * (xr[c] - other) + dt * q[c]
                } else {
                    mr[c] * xr[c] + dt * q[c]
                };
                let (m_new, q_new) = if !second {
                    (m_e, q_e)
                } else {
                    // The start-of-step face mass, as `face_masses` gave it.
                    let a = crate::ops::face_density(rho_lo[c], rho_hi[c]);
                    (0.5 * (a + m_e), 0.5 * (a * x0[c] + q_e))
                };
                mr[c] = m_new;
                xr[c] = q_new / m_new;
                if !second && lag != 0.0 {
                    xr[c] += other;
                }
            }
        });
    }
}

impl Stage for AdvectionStage {
    fn max_dt(&self, grid: &Grid, state: &State, cfl: f64) -> Option<f64> {
        advective_dt(grid, &state.u, &state.v, cfl)
    }

    fn run(&mut self, ctx: &StepContext, state: &mut State) -> Result<StageStats, StageError> {
        // SSP-RK2 (Heun) on (m, m u):
        //   m¹ = m⁰ + Δt Lm(m⁰, V⁰),  (m u)¹ = m⁰u⁰ + Δt Lq(m⁰, V⁰),  u¹ = (m u)¹/m¹,
        //   m* = ½m⁰ + ½(m¹ + Δt Lm(m¹, V¹)),  (m u)* = ½m⁰u⁰ + ½((m u)¹ + Δt Lq(m¹, V¹)).
        let g = ctx.grid;
        let dt = ctx.dt;
        let scratch = self.scratch.clone();
        let mut pool = scratch.lock();
        let [qu, qv, mu_, mv_, u0, v0, m1u, m1v] =
            scratch::take::<WORK>(&mut pool, state.u.data().len());
        face_masses(&state.rho, m1u, m1v);
        copy(u0, state.u.data());
        copy(v0, state.v.data());
        let faces = UnknownFaces::new(g, ctx.bc);
        // The other stages' increments of the last step, rescaled to this Δt (module docs).
        let mut carry = self.carry.take();
        let (lag, yu, yv): (f64, &[f64], &[f64]) = match &carry {
            Some(c) if c.dt > 0.0 => (dt / c.dt, &c.u, &c.v),
            _ => (0.0, &[], &[]),
        };
        for stage in 0..2 {
            self.rhs(
                ctx,
                &state.u,
                &state.v,
                [m1u, m1v],
                [&mut *qu, &mut *qv, &mut *mu_, &mut *mv_],
            );
            let step = Euler {
                dt,
                lag,
                second: stage == 1,
                rho: &state.rho,
            };
            step.update(
                faces.u_region(),
                0,
                &mut state.u,
                m1u,
                [&*u0, yu, &*qu, &*mu_],
            );
            step.update(
                faces.v_region(),
                1,
                &mut state.v,
                m1v,
                [&*v0, yv, &*qv, &*mv_],
            );
            if stage == 0 {
                ctx.bc
                    .fill_velocity(g, &mut state.u, &mut state.v, ctx.t + dt, false);
            }
        }
        if let Some(c) = &mut carry {
            copy(&mut c.u, state.u.data());
            copy(&mut c.v, state.v.data());
            c.dt = dt;
        }
        self.carry = carry;
        Ok(StageStats::default())
    }

    fn save_into(&self, out: &mut Vec<f64>) {
        out.clear();
        if let Some(c) = &self.carry {
            // Room for the history from the first save on: no allocation once it exists.
            out.reserve(1 + c.u.len() + c.v.len());
        }
        if let Some(c) = self.carry.as_ref().filter(|c| c.dt > 0.0) {
            out.push(c.dt);
            out.extend_from_slice(&c.u);
            out.extend_from_slice(&c.v);
        }
    }

    fn save(&self) -> Vec<f64> {
        let mut v = Vec::new();
        self.save_into(&mut v);
        v
    }

    /// Nothing (no history: the next step's second stage looks from advection alone), or what
    /// [`save`](Stage::save) wrote.
    fn restore(&mut self, data: &[f64]) -> Result<(), String> {
        match &mut self.carry {
            Some(c) if data.is_empty() => {
                c.dt = 0.0;
                Ok(())
            }
            Some(c) if data.len() == 1 + c.u.len() + c.v.len() && data[0] > 0.0 => {
                let n = c.u.len();
                c.dt = data[0];
                c.u.copy_from_slice(&data[1..1 + n]);
                c.v.copy_from_slice(&data[1 + n..]);
                Ok(())
            }
            None if data.is_empty() => Ok(()),
            _ => Err(format!(
                "expected the advection's history ([Δt] and two velocity arrays), got {} values",
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
