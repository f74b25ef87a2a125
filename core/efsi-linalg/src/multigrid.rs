//! Geometric multigrid (W-cycle on the fine levels) for five-point SPD matrices on the cell grid, used as the
//! preconditioner of conjugate gradient ("MG-PCG").
//!
//! It works from the assembled [`Stencil5`] alone — the diagonal and the east/north couplings,
//! with periodic wraps — so it serves any symmetric five-point M-matrix (diffusion with a
//! variable, possibly discontinuous coefficient, planar or r-weighted axisymmetric, Neumann,
//! periodic and Dirichlet sides), not only the pressure equation.
//!
//! **Hierarchy.** Cells are aggregated 2 × 2 (an odd count leaves a last aggregate one cell
//! wide; a direction of ≤ 2 cells is no longer coarsened) until at most [`COARSEST_CELLS`]
//! cells remain. The coarse matrix is again five-point: with `P` the piecewise-constant
//! prolongation (each fine cell takes its aggregate's value) it is the Galerkin product `PᵀAP`
//! — the coupling of two aggregates is the sum of the fine couplings across their common face,
//! the excess of the diagonal over the couplings (Dirichlet faces) is summed — scaled by ½
//! along each coarsened direction. Galerkin keeps the coarse problem faithful to the fine
//! coefficient at any jump (an aggregate straddling a light and a heavy cell stays strongly
//! coupled to its light neighbours); the factor ½ is the over-correction that piecewise-constant
//! aggregation needs (Braess 1995; Notay & Vassilevski 2008): for a constant coefficient `PᵀAP`
//! is twice the rediscretised coarse operator, so the plain Galerkin correction of a smooth
//! error would come out half as large as it should. With the factor, a constant coefficient
//! gives exactly the rediscretised operator, planar and axisymmetric (`Σ r_f dz/dr` over the
//! two fine faces is `2 r_F dZ/dR`). Measured on random disks of density ratio 1e4: ½ needs
//! 10 iterations where 0.55 and 0.6 need 12–14 and 14–19, and a coefficient-aware
//! series-resistance coarsening 45–130.
//!
//! **Cycle.** A W-cycle: pre-smoothing by `ν` red–black Gauss–Seidel sweeps (red then black),
//! restriction of the residual by summing the four children (`R = Pᵀ`), two coarse
//! corrections (the second from the residual of the first; one next to the coarsest level),
//! prolongation `P`, then `ν` sweeps in the reverse colour order (black then red) — the
//! adjoint of the pre-smoother, so the cycle is a symmetric operator; it is positive definite
//! because the smoother converges and each coarse correction is symmetric positive
//! semi-definite (Tatebe 1993 for MG-CG). The coarsest system is solved exactly by a dense
//! Cholesky factor. A V-cycle grows with the number of levels (the piecewise-constant transfer
//! has orders `m_P + m_R = 2`, not `> 2`): measured at ratio 1e4, 11 → 14 iterations from 64²
//! to 256², against 10 → 10 for the W-cycle, whose cycle costs ≈ 1.5× a V-cycle's.
//!
//! The two corrections are made on the finest [`W_LEVELS`] = 2 levels only; below them the
//! cycle is a V-cycle. A full W-cycle visits level `l` 2^l times, and the coarse levels (below
//! [`par::PAR_MIN`] cells) run serially: on a 256² grid they were ≈ 30 % of a cycle on one
//! thread and ≈ 40 % on two. With the V below level 2 they are visited 4 times, and the
//! iterations are those of the full W-cycle — the `iteration_table` test over the six problem
//! kinds at ratios 1, 1e2, 1e4 from 64² to 512² gives the same counts everywhere but one
//! (10 instead of 11 at 512²); a W on the finest level alone needed up to 11 where the full
//! W-cycle needs 10.
//!
//! **Singular systems.** Without Dirichlet faces the matrix annihilates constants; residuals
//! the conjugate gradient hands over then sum to zero, restriction keeps that, and the coarsest
//! solve pins one unknown (a consistent singular system), so the cycle stays symmetric and
//! positive definite on the range.
//!
//! **Parallelism and determinism.** Sweeps of one colour, residual–restriction and
//! prolongation run in parallel over rows (rayon) on levels of at least [`par::PAR_MIN`]
//! cells (the restriction counts the fine cells it reads), and so does the set-up (loading the
//! finest level, coarsening by coarse rows); each writes disjoint entries from inputs no one
//! writes in that loop, and every coarse entry sums its children in the same order, so results
//! are bit-identical whatever the number of threads. (Splitting the 4096-cell level too was
//! tried: on this 2-core VM the median cycle got slower — a join on a level that small costs
//! more than half its sweep whenever the other core is not immediately free.)
//!
//! **Allocation.** [`Multigrid::setup`] allocates the hierarchy on the first call and reuses it
//! for later matrices of the same shape; [`Preconditioner::apply`] never allocates.

use super::par::{self, SharedSlice};
use super::pcg::Preconditioner;
use super::stencil5::Stencil5;
use std::cell::RefCell;

/// The hierarchy stops coarsening at this many cells (solved by dense Cholesky).
pub const COARSEST_CELLS: usize = 64;

/// The W-cycle makes two coarse corrections on this many of the finest levels and one (a
/// V-cycle) below them (module docs: "Cycle").
pub const W_LEVELS: usize = 2;

/// One level: the matrix in a padded layout (one ghost ring), and the work vectors.
#[derive(Clone, Debug, Default)]
struct Level {
    nx: usize,
    ny: usize,
    periodic_x: bool,
    periodic_y: bool,
    /// Padded row length `nx + 2`.
    s: usize,
    diag: Vec<f64>,
    dinv: Vec<f64>,
    /// Coupling to the east neighbour; the west coupling of cell `k` is `ce[k − 1]` (the ghost
    /// column holds the periodic wrap, or 0).
    ce: Vec<f64>,
    /// Coupling to the north neighbour; the south coupling of `k` is `cn[k − s]`.
    cn: Vec<f64>,
    x: Vec<f64>,
    b: Vec<f64>,
    /// The first coarse correction while a W-cycle computes the second.
    t: Vec<f64>,
}

impl Level {
    fn shape(a: &Stencil5) -> Self {
        let m = (a.nx + 2) * (a.ny + 2);
        Level {
            nx: a.nx,
            ny: a.ny,
            periodic_x: a.periodic_x,
            periodic_y: a.periodic_y,
            s: a.nx + 2,
            diag: vec![0.0; m],
            dinv: vec![0.0; m],
            ce: vec![0.0; m],
            cn: vec![0.0; m],
            x: vec![0.0; m],
            b: vec![0.0; m],
            t: vec![0.0; m],
        }
    }

    /// Whether the level is below [`par::PAR_MIN`] cells, so its sweeps run on one thread.
    fn is_serial(&self) -> bool {
        self.nx * self.ny < par::PAR_MIN
    }

    #[inline(always)]
    fn p(&self, i: usize, j: usize) -> usize {
        (j + 1) * self.s + i + 1
    }

    /// Copy the coefficients of `a` (same shape) into the padded layout: row copies in
    /// parallel, one array at a time (they vectorise).
    fn load(&mut self, a: &Stencil5) {
        let (nx, ny, s) = (self.nx, self.ny, self.s);
        let (px, py) = (a.periodic_x, a.periodic_y);
        let rows = s..(ny + 1) * s;
        par::for_each_row(&mut self.ce[rows.clone()], s, |j, row| {
            let src = &a.east[j * nx..(j + 1) * nx];
            row[1..=nx].copy_from_slice(src);
            // The closed east side has no coupling; the west ghost holds the wrap coupling.
            if !px {
                row[nx] = 0.0;
            }
            row[0] = if px { src[nx - 1] } else { 0.0 };
        });
        par::for_each_row(&mut self.cn[rows.clone()], s, |j, row| {
            if j + 1 < ny || py {
                row[1..=nx].copy_from_slice(&a.north[j * nx..(j + 1) * nx]);
            } else {
                row[1..=nx].fill(0.0);
            }
        });
        for i in 0..nx {
            self.cn[i + 1] = if py { a.north[(ny - 1) * nx + i] } else { 0.0 };
        }
        par::for_each_row2(
            &mut self.diag[rows.clone()],
            &mut self.dinv[rows],
            s,
            |j, d, di| {
                let src = &a.diag[j * nx..(j + 1) * nx];
                d[1..=nx].copy_from_slice(src);
                for (di, d) in di[1..=nx].iter_mut().zip(src) {
                    *di = if *d > 0.0 { 1.0 / d } else { 0.0 };
                }
            },
        );
    }

    /// Periodic ghosts of `x` (closed sides keep zero ghosts, multiplied by zero couplings).
    fn fill_ghosts(&mut self) {
        let (nx, ny, s) = (self.nx, self.ny, self.s);
        if self.periodic_x {
            for j in 1..=ny {
                self.x[j * s] = self.x[j * s + nx];
                self.x[j * s + nx + 1] = self.x[j * s + 1];
            }
        }
        if self.periodic_y {
            let (bot, top) = (s, ny * s);
            for i in 1..=nx {
                self.x[i] = self.x[top + i];
                self.x[(ny + 1) * s + i] = self.x[bot + i];
            }
        }
    }

    /// One red–black Gauss–Seidel sweep: the cells of colour `first` ((i + j) mod 2), then the
    /// others. The two half-sweeps are fused into one pass over memory (the second colour of
    /// row j − 1 right after the first colour of row j, Douglas et al. 2000), in chunks of rows
    /// in parallel: the second colour of each chunk's first and last rows waits for a second
    /// phase, when the first colour is done everywhere. Every update reads the same values as
    /// in two separate half-sweeps, so the result is the same bit for bit, whatever the
    /// chunking and the number of threads.
    fn sweep(&mut self, first: usize) {
        self.fill_ghosts();
        let (nx, ny, s, px) = (self.nx, self.ny, self.s, self.periodic_x);
        let second = 1 - first;
        let xs = SharedSlice::new(&mut self.x);
        let (b, ce, cn, dinv) = (&self.b[..], &self.ce[..], &self.cn[..], &self.dinv[..]);
        // Update the cells of `colour` in row j, then refresh the row's periodic ghosts.
        let row = |colour: usize, j: usize| {
            let base = (j + 1) * s + 1;
            let o = base + ((colour + j) & 1);
            let end = base + nx;
            if o < end {
                // The row's cells of `colour` are o, o + 2, …: a counted loop over slices of
                // exactly the length it touches, so that no index needs a bounds check.
                let cnt = (end - o).div_ceil(2);
                let len = 2 * cnt - 1;
                let (b, dinv) = (&b[o..o + len], &dinv[o..o + len]);
                let (ce, cw) = (&ce[o..o + len], &ce[o - 1..o - 1 + len]);
                let (cn, cs) = (&cn[o..o + len], &cn[o - s..o - s + len]);
                for m in 0..cnt {
                    let t = 2 * m;
                    let k = o + t;
                    // SAFETY: a row update writes only cells of `colour` in row j and reads
                    // their neighbours (the other colour) and row j's ghosts. The phases below
                    // never run two updates concurrently where one writes what the other
                    // touches: in phase 1 a chunk updates the second colour only of rows whose
                    // neighbour rows are in the same chunk; in phase 2 only second-colour
                    // cells of distinct rows are written, reading first-colour cells nobody
                    // writes.
                    unsafe {
                        let v = (b[t]
                            + ce[t] * xs.get(k + 1)
                            + cw[t] * xs.get(k - 1)
                            + cn[t] * xs.get(k + s)
                            + cs[t] * xs.get(k - s))
                            * dinv[t];
                        xs.set(k, v);
                    }
                }
            }
            if px {
                // SAFETY: row j's ghost cells are touched by row j's updates only.
                unsafe {
                    xs.set(base - 1, xs.get(base + nx - 1));
                    xs.set(base + nx, xs.get(base));
                }
            }
        };
        let threads = rayon::current_num_threads();
        let chunk = if self.is_serial() || threads == 1 {
            ny
        } else {
            ny.div_ceil(2 * threads).max(4)
        };
        let chunks = ny.div_ceil(chunk);
        let phase1 = |c: usize| {
            let (r0, r1) = (c * chunk, ((c + 1) * chunk).min(ny));
            for j in r0..r1 {
                row(first, j);
                if j >= r0 + 2 {
                    row(second, j - 1);
                }
            }
        };
        let phase2 = |c: usize| {
            let (r0, r1) = (c * chunk, ((c + 1) * chunk).min(ny));
            row(second, r0);
            if r1 - 1 > r0 {
                row(second, r1 - 1);
            }
        };
        par::for_each_index(chunks, chunk * nx, phase1);
        if self.periodic_y {
            // The second colour of rows 0 and ny − 1 reads the first colour across the wrap.
            let x = &mut self.x;
            for i in 1..=nx {
                x[i] = x[ny * s + i];
                x[(ny + 1) * s + i] = x[s + i];
            }
        }
        // Phase 2 touches two rows per chunk: split only when that is worth a fork.
        par::for_each_index(chunks, 2 * nx, phase2);
    }

    /// `out[t] = (b − A x)[k0 + t]` for a run of cells of one row (ghosts filled), over slices (it
    /// vectorises).
    #[inline(always)]
    fn residual_run(&self, k0: usize, out: &mut [f64]) {
        let (n, s) = (out.len(), self.s);
        let x = &self.x[k0 - s..k0 + s + n];
        let (xc, xe, xw) = (&x[s..s + n], &x[s + 1..s + 1 + n], &x[s - 1..s - 1 + n]);
        let (xn, xs) = (&x[2 * s..2 * s + n], &x[..n]);
        let (b, d) = (&self.b[k0..k0 + n], &self.diag[k0..k0 + n]);
        let (ce, cw) = (&self.ce[k0..k0 + n], &self.ce[k0 - 1..k0 - 1 + n]);
        let (cn, cs) = (&self.cn[k0..k0 + n], &self.cn[k0 - s..k0 - s + n]);
        for t in 0..n {
            out[t] =
                b[t] - d[t] * xc[t] + ce[t] * xe[t] + cw[t] * xw[t] + cn[t] * xn[t] + cs[t] * xs[t];
        }
    }
}

/// Dense Cholesky solve of the coarsest level (one unknown pinned if the matrix is singular).
#[derive(Clone, Debug, Default)]
struct Coarsest {
    m: usize,
    l: Vec<f64>,
    y: Vec<f64>,
    singular_pin: bool,
}

impl Coarsest {
    fn factor(&mut self, lv: &Level) {
        let m = lv.nx * lv.ny;
        self.m = m;
        self.l.clear();
        self.l.resize(m * m, 0.0);
        self.y.resize(m, 0.0);
        let nx = lv.nx;
        let singular = (0..lv.ny).all(|j| {
            (0..nx).all(|i| {
                let p = lv.p(i, j);
                lv.diag[p] - (lv.ce[p] + lv.ce[p - 1] + lv.cn[p] + lv.cn[p - lv.s])
                    <= 1e-12 * lv.diag[p]
            })
        });
        let a = &mut self.l;
        for j in 0..lv.ny {
            for i in 0..nx {
                let k = j * nx + i;
                let p = lv.p(i, j);
                a[k * m + k] += lv.diag[p];
                // Neighbours (with wraps): subtract couplings; periodic self-wraps cancel.
                let nb = [
                    (lv.ce[p], (i + 1) % nx, j),
                    (lv.ce[p - 1], (i + nx - 1) % nx, j),
                    (lv.cn[p], i, (j + 1) % lv.ny),
                    (lv.cn[p - lv.s], i, (j + lv.ny - 1) % lv.ny),
                ];
                for (c, ii, jj) in nb {
                    if c != 0.0 {
                        a[k * m + jj * nx + ii] -= c;
                    }
                }
            }
        }
        if singular {
            for k in 0..m {
                a[k] = 0.0;
                a[k * m] = 0.0;
            }
            a[0] = 1.0;
        }
        // In-place Cholesky, lower triangle.
        for c in 0..m {
            let mut d = a[c * m + c];
            for k in 0..c {
                d -= a[c * m + k] * a[c * m + k];
            }
            let d = if d > 0.0 { d.sqrt() } else { f64::MIN_POSITIVE };
            a[c * m + c] = d;
            for r in c + 1..m {
                let mut v = a[r * m + c];
                for k in 0..c {
                    v -= a[r * m + k] * a[c * m + k];
                }
                a[r * m + c] = v / d;
            }
        }
        self.singular_pin = singular;
    }
}

impl Coarsest {
    fn solve(&mut self, lv: &mut Level) {
        let (m, nx) = (self.m, lv.nx);
        let (l, y) = (&self.l, &mut self.y);
        for k in 0..m {
            y[k] = lv.b[lv.p(k % nx, k / nx)];
        }
        if self.singular_pin {
            y[0] = 0.0;
        }
        for r in 0..m {
            let mut v = y[r];
            for k in 0..r {
                v -= l[r * m + k] * y[k];
            }
            y[r] = v / l[r * m + r];
        }
        for r in (0..m).rev() {
            let mut v = y[r];
            for k in r + 1..m {
                v -= l[k * m + r] * y[k];
            }
            y[r] = v / l[r * m + r];
        }
        for k in 0..m {
            let p = lv.p(k % nx, k / nx);
            lv.x[p] = y[k];
        }
    }
}

/// Cells per aggregate along a direction of `n` cells: 2, or 1 once `n ≤ 2`.
fn factor(n: usize) -> usize {
    if n > 2 { 2 } else { 1 }
}

/// The coarse matrix of `a` (module docs: half the Galerkin product of the piecewise-constant
/// aggregation along each coarsened direction), into `c` (reshaped as needed). The excess of
/// the diagonal over the couplings is summed over each aggregate and multiplied by
/// `excess_scale` when both directions are coarsened (½ for Dirichlet faces, 1 for a mass
/// term).
pub fn coarsen_into(a: &Stencil5, c: &mut Stencil5, excess_scale: f64) {
    let (nx, ny) = (a.nx, a.ny);
    let (fx, fy) = (factor(nx), factor(ny));
    let (cx, cy) = (nx.div_ceil(fx), ny.div_ceil(fy));
    if c.nx != cx || c.ny != cy || c.len() != cx * cy {
        *c = Stencil5::new(cx, cy, a.periodic_x, a.periodic_y);
    }
    c.periodic_x = a.periodic_x;
    c.periodic_y = a.periodic_y;
    // Over-correction: ½ along a coarsened direction (the rediscretised scale), 1 across.
    let sx = if fx == 2 { 0.5 } else { 1.0 };
    let sy = if fy == 2 { 0.5 } else { 1.0 };
    let se = if fx * fy == 4 { excess_scale } else { 1.0 };
    // i / fx as a shift (fx is 1 or 2): an integer division per cell cost more than the rest.
    let lx = fx.trailing_zeros();
    // Coarse rows in parallel. Each fine row's couplings and excesses are computed in runs
    // (they vectorise), then added to the coarse row's sums fine row by fine row, child by
    // child — every coarse entry sums its children in the order (j, i), so the sums do not
    // depend on the number of threads.
    let (ce, cn, cd) = (
        SharedSlice::new(&mut c.east),
        SharedSlice::new(&mut c.north),
        SharedSlice::new(&mut c.diag),
    );
    par::for_each_index(cy, fy * nx, |jc| {
        let row0 = jc * cx;
        for kc in row0..row0 + cx {
            // SAFETY: coarse row jc writes only its own entries (here and below).
            unsafe {
                ce.set(kc, 0.0);
                cn.set(kc, 0.0);
                cd.set(kc, 0.0);
            }
        }
        let j1 = (fy * jc + fy).min(ny);
        let (mut e, mut n, mut x) = ([0.0f64; RUN], [0.0f64; RUN], [0.0f64; RUN]);
        for j in fy * jc..j1 {
            let last_y = j + 1 == ny;
            let north_face = j + 1 == j1 && cy > 1;
            let mut i0 = 0;
            while i0 < nx {
                let len = (nx - i0).min(RUN);
                let k0 = j * nx + i0;
                let (e, n, x) = (&mut e[..len], &mut n[..len], &mut x[..len]);
                e.copy_from_slice(&a.east[k0..k0 + len]);
                if i0 + len == nx && !a.periodic_x {
                    e[len - 1] = 0.0;
                }
                if last_y && !a.periodic_y {
                    n.fill(0.0);
                } else {
                    n.copy_from_slice(&a.north[k0..k0 + len]);
                }
                for t in 0..len {
                    let k = k0 + t;
                    let i = i0 + t;
                    let excess = a.diag[k] - (e[t] + n[t] + a.west(k, i) + a.south(k, j));
                    x[t] = if excess > 1e-12 * a.diag[k] {
                        se * excess
                    } else {
                        0.0
                    };
                }
                for t in 0..len {
                    let i = i0 + t;
                    let kc = row0 + (i >> lx);
                    // A fine face between two aggregates (or across the periodic wrap)
                    // couples them; a periodic direction of one coarse cell couples the cell
                    // to itself: no coupling.
                    let east_face = (i + 1 == nx || (i + 1) >> lx != i >> lx) && cx > 1;
                    // SAFETY: as above.
                    unsafe {
                        if east_face {
                            ce.set(kc, ce.get(kc) + sx * e[t]);
                        }
                        if north_face {
                            cn.set(kc, cn.get(kc) + sy * n[t]);
                        }
                        if x[t] != 0.0 {
                            cd.set(kc, cd.get(kc) + x[t]);
                        }
                    }
                }
                i0 += len;
            }
        }
    });
    let mut diag = std::mem::take(&mut c.diag);
    let cc = &*c;
    par::for_each_row(&mut diag, cx, |jc, row| {
        for (ic, d) in row.iter_mut().enumerate() {
            let kc = jc * cx + ic;
            *d += cc.east[kc] + cc.north[kc] + cc.west(kc, ic) + cc.south(kc, jc);
        }
    });
    c.diag = diag;
}

#[derive(Clone, Debug, Default)]
struct Hierarchy {
    levels: Vec<Level>,
    coarsest: Coarsest,
}

/// Geometric multigrid W-cycle preconditioner for a [`Stencil5`] (module docs).
///
/// ```
/// use efsi_linalg::{Multigrid, Pcg, Stencil5};
/// let n = 32;
/// let mut a = Stencil5::new(n, n, false, false);
/// for j in 0..n {
///     for i in 0..n {
///         let k = j * n + i;
///         a.east[k] = if i + 1 < n { 1.0 } else { 0.0 };
///         a.north[k] = if j + 1 < n { 1.0 } else { 0.0 };
///         a.diag[k] = 4.0; // Dirichlet all round (ghost at half a cell folded in)
///     }
/// }
/// let mut mg = Multigrid::new(2);
/// mg.setup(&a);
/// let b = vec![1.0; n * n];
/// let mut x = vec![0.0; n * n];
/// let maxabs = |r: &[f64]| r.iter().fold(0.0f64, |m, v| m.max(v.abs()));
/// let st = Pcg::new(n * n).solve(&mut a, &mg, &b, &mut x, 1e-10, 100, maxabs);
/// assert!(st.converged && st.iterations < 15);
/// ```
#[derive(Debug)]
pub struct Multigrid {
    sweeps: usize,
    gamma: usize,
    excess_scale: f64,
    /// The coarse matrices (levels 1, 2, …).
    mats: Vec<Stencil5>,
    h: RefCell<Hierarchy>,
}

impl Multigrid {
    /// A preconditioner with `sweeps` red–black Gauss–Seidel sweeps before and after each
    /// coarse correction (≥ 1); call [`Multigrid::setup`] before use.
    pub fn new(sweeps: usize) -> Self {
        Multigrid {
            sweeps: sweeps.max(1),
            gamma: 2,
            excess_scale: 0.5,
            mats: Vec::new(),
            h: RefCell::new(Hierarchy::default()),
        }
    }

    /// A V-cycle (`false`: one coarse correction per level) instead of the default W-cycle.
    pub fn with_w_cycle(mut self, w: bool) -> Self {
        self.gamma = if w { 2 } else { 1 };
        self
    }

    /// How the excess of the diagonal over the couplings is carried to a 2 × 2 coarser level:
    /// ½ of its sum (default; right for Dirichlet faces, like the couplings) or all of it
    /// (`1.0`, right for a mass or reaction term `M + K`, whose Galerkin mass is exact).
    pub fn with_excess_scale(mut self, scale: f64) -> Self {
        self.excess_scale = scale;
        self
    }

    /// Number of levels (1 when the matrix is already at most [`COARSEST_CELLS`]).
    pub fn levels(&self) -> usize {
        self.h.borrow().levels.len()
    }

    /// Build (first call, or a new shape) or refresh the hierarchy for the matrix `a`.
    /// Allocates only when the shape changes.
    pub fn setup(&mut self, a: &Stencil5) {
        let h = self.h.get_mut();
        let same = h.levels.first().is_some_and(|l| {
            l.nx == a.nx
                && l.ny == a.ny
                && l.periodic_x == a.periodic_x
                && l.periodic_y == a.periodic_y
        });
        if !same {
            h.levels.clear();
            self.mats.clear();
            h.levels.push(Level::shape(a));
            let (mut nx, mut ny) = (a.nx, a.ny);
            while nx * ny > COARSEST_CELLS && (nx > 2 || ny > 2) {
                nx = nx.div_ceil(factor(nx));
                ny = ny.div_ceil(factor(ny));
                let m = Stencil5::new(nx, ny, a.periodic_x, a.periodic_y);
                h.levels.push(Level::shape(&m));
                self.mats.push(m);
            }
        }
        h.levels[0].load(a);
        let excess = self.excess_scale;
        let Hierarchy { levels, coarsest } = h;
        let n = levels.len();
        // Levels coarsened from a serial-sized one, and the Cholesky factor, with a second
        // thread kept awake for what follows.
        let first_serial = (1..n).find(|&l| levels[l - 1].is_serial()).unwrap_or(n);
        coarsen_levels(a, &mut self.mats, levels, 1..first_serial, excess);
        let mats = &mut self.mats;
        par::serial_warm(|| {
            coarsen_levels(a, mats, levels, first_serial..n, excess);
            coarsest.factor(levels.last().expect("at least one level"));
        });
    }
}

/// Levels `range` of the hierarchy from their finer neighbours (`a` is level 0's matrix,
/// `mats[l − 1]` level l's).
fn coarsen_levels(
    a: &Stencil5,
    mats: &mut [Stencil5],
    levels: &mut [Level],
    range: std::ops::Range<usize>,
    excess_scale: f64,
) {
    for l in range {
        let (done, rest) = mats.split_at_mut(l - 1);
        let fine = if l == 1 { a } else { &done[l - 2] };
        coarsen_into(fine, &mut rest[0], excess_scale);
        levels[l].load(&rest[0]);
    }
}

/// Cells per block of a row in [`restrict`] (even).
const RUN: usize = 64;

/// `c.b = R (f.b − A f.x)`: the residual of the fine level summed over each aggregate, fine row
/// by fine row in the order (i, j) of the children — runs of residuals computed over slices,
/// then added pairwise (the same sums, in the same order, as one child at a time).
fn restrict(f: &Level, c: &mut Level) {
    let fx = if c.nx < f.nx { 2 } else { 1 };
    let fy = if c.ny < f.ny { 2 } else { 1 };
    let (fnx, fny, cnx, cs) = (f.nx, f.ny, c.nx, c.s);
    // A coarse row sums `fy` fine rows: split the loop by the fine work.
    par::for_each_row_weighted(&mut c.b[cs..(c.ny + 1) * cs], cs, fy * f.s, |jc, row| {
        let out = &mut row[1..=cnx];
        out.fill(0.0);
        let mut r = [0.0f64; RUN];
        for j in fy * jc..(fy * jc + fy).min(fny) {
            let base = f.p(0, j);
            let mut i0 = 0;
            while i0 < fnx {
                let len = (fnx - i0).min(RUN);
                let r = &mut r[..len];
                f.residual_run(base + i0, r);
                if fx == 2 {
                    let o = &mut out[i0 / 2..];
                    let pairs = len / 2;
                    for (m, o) in o[..pairs].iter_mut().enumerate() {
                        *o = *o + r[2 * m] + r[2 * m + 1];
                    }
                    if len % 2 == 1 {
                        o[pairs] += r[len - 1];
                    }
                } else {
                    for (o, r) in out[i0..i0 + len].iter_mut().zip(r.iter()) {
                        *o += r;
                    }
                }
                i0 += len;
            }
        }
    });
}

/// `f.x += P c.x`: piecewise-constant prolongation of the coarse correction.
fn prolong(f: &mut Level, c: &Level) {
    let fx = if c.nx < f.nx { 2 } else { 1 };
    let fy = if c.ny < f.ny { 2 } else { 1 };
    let (fnx, fs) = (f.nx, f.s);
    par::for_each_row(&mut f.x[fs..(f.ny + 1) * fs], fs, |j, row| {
        let crow = &c.x[c.p(0, j / fy)..];
        let row = &mut row[1..=fnx];
        if fx == 2 {
            for (pair, cx) in row.chunks_mut(2).zip(crow) {
                for x in pair {
                    *x += cx;
                }
            }
        } else {
            for (x, cx) in row.iter_mut().zip(crow) {
                *x += cx;
            }
        }
    });
}

/// `levels[l].x ≈ A_l⁻¹ levels[l].b`, from zero: smoothing, `gamma` coarse corrections
/// (1: V-cycle, 2: W-cycle), smoothing in reverse order.
fn cycle(levels: &mut [Level], coarsest: &mut Coarsest, l: usize, sweeps: usize, gamma: usize) {
    let nl = levels.len();
    if l + 1 == nl {
        coarsest.solve(&mut levels[l]);
        return;
    }
    {
        let lv = &mut levels[l];
        lv.x.fill(0.0);
        for _ in 0..sweeps {
            lv.sweep(0);
        }
        lv.fill_ghosts();
        let (f, c) = levels.split_at_mut(l + 1);
        restrict(&f[l], &mut c[0]);
    }
    let g = if l + 2 == nl || l >= W_LEVELS {
        1
    } else {
        gamma
    };
    for k in 0..g {
        if k > 0 {
            // Next correction from the residual of the current one.
            let c = &mut levels[l + 1];
            c.fill_ghosts();
            let mut t = std::mem::take(&mut c.t);
            let (cnx, cs) = (c.nx, c.s);
            par::for_each_row(&mut t[cs..(c.ny + 1) * cs], cs, |j, row| {
                c.residual_run(c.p(0, j), &mut row[1..=cnx]);
            });
            c.t = t;
            std::mem::swap(&mut c.b, &mut c.t);
            std::mem::swap(&mut c.x, &mut c.t);
        }
        if levels[l + 1].is_serial() && !levels[l].is_serial() {
            // The serial coarse levels: keep a second thread awake for the sweeps after them.
            par::serial_warm(|| cycle(levels, coarsest, l + 1, sweeps, gamma));
        } else {
            cycle(levels, coarsest, l + 1, sweeps, gamma);
        }
        if k > 0 {
            let c = &mut levels[l + 1];
            let t = &c.t;
            par::for_each_chunk(&mut c.x, |o, x| {
                let n = x.len();
                for (x, t) in x.iter_mut().zip(&t[o..o + n]) {
                    *x += t;
                }
            });
        }
    }
    let (f, c) = levels.split_at_mut(l + 1);
    let lv = &mut f[l];
    prolong(lv, &c[0]);
    for _ in 0..sweeps {
        lv.sweep(1);
    }
}

impl Preconditioner for Multigrid {
    fn apply(&self, r: &[f64], z: &mut [f64]) {
        let mut h = self.h.borrow_mut();
        let Hierarchy { levels, coarsest } = &mut *h;
        {
            let l0 = &mut levels[0];
            let (nx, s) = (l0.nx, l0.s);
            assert_eq!(
                r.len(),
                nx * l0.ny,
                "multigrid: vector length ≠ matrix size"
            );
            par::for_each_row(&mut l0.b[s..(l0.ny + 1) * s], s, |j, row| {
                row[1..=nx].copy_from_slice(&r[j * nx..(j + 1) * nx]);
            });
        }
        cycle(levels, coarsest, 0, self.sweeps, self.gamma);
        let l0 = &levels[0];
        let (nx, s) = (l0.nx, l0.s);
        par::for_each_row(z, nx, |j, row| {
            row.copy_from_slice(&l0.x[(j + 1) * s + 1..(j + 1) * s + 1 + nx]);
        });
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{IncompleteCholesky, Pcg};

    /// A small deterministic generator (xorshift64*), for reproducible random problems.
    struct Rng(u64);
    impl Rng {
        fn next(&mut self) -> f64 {
            self.0 ^= self.0 >> 12;
            self.0 ^= self.0 << 25;
            self.0 ^= self.0 >> 27;
            (self.0.wrapping_mul(0x2545_F491_4F6C_DD1D) >> 11) as f64 / (1u64 << 53) as f64
        }
    }

    /// Sides: `[x_min, x_max, y_min, y_max]`; `Some(true)` Dirichlet, `Some(false)` Neumann;
    /// `periodic` pairs override.
    #[derive(Clone, Copy)]
    struct Problem {
        n: usize,
        axisymmetric: bool,
        periodic_x: bool,
        dirichlet_top: bool,
        ratio: f64,
        seed: u64,
    }

    /// The projection's matrix `Σ_f A_f/(ρ_f h)(p_C − p_F)` on the unit square (r ∈ [0, 1]
    /// with the axis at r = 0 when axisymmetric) for a density of random disks `ratio` times
    /// heavier than the surroundings.
    fn pressure_matrix(p: Problem) -> Stencil5 {
        let (nx, ny) = (p.n, p.n);
        let h = 1.0 / p.n as f64;
        let mut rng = Rng(p.seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) | 1);
        let disks: Vec<(f64, f64, f64)> = (0..6)
            .map(|_| (rng.next(), rng.next(), 0.05 + 0.15 * rng.next()))
            .collect();
        let rho = |i: usize, j: usize| {
            let (x, y) = ((i as f64 + 0.5) * h, (j as f64 + 0.5) * h);
            if disks
                .iter()
                .any(|&(cx, cy, r)| (x - cx).powi(2) + (y - cy).powi(2) < r * r)
            {
                p.ratio
            } else {
                1.0
            }
        };
        let rf = |i: usize| if p.axisymmetric { i as f64 * h } else { 1.0 };
        let rc = |i: usize| {
            if p.axisymmetric {
                (i as f64 + 0.5) * h
            } else {
                1.0
            }
        };
        let mut a = Stencil5::new(nx, ny, p.periodic_x, false);
        for j in 0..ny {
            for i in 0..nx {
                let k = j * nx + i;
                a.east[k] = if i + 1 < nx || p.periodic_x {
                    let ie = (i + 1) % nx;
                    rf(i + 1) / (0.5 * (rho(i, j) + rho(ie, j)))
                } else {
                    0.0
                };
                a.north[k] = if j + 1 < ny {
                    rc(i) / (0.5 * (rho(i, j) + rho(i, j + 1)))
                } else {
                    0.0
                };
            }
        }
        for j in 0..ny {
            for i in 0..nx {
                let k = j * nx + i;
                let w = if i > 0 {
                    a.east[k - 1]
                } else if p.periodic_x {
                    a.east[k + nx - 1]
                } else {
                    0.0
                };
                let s = if j > 0 { a.north[k - nx] } else { 0.0 };
                let mut d = a.east[k] + a.north[k] + w + s;
                if p.dirichlet_top && j + 1 == ny {
                    d += 2.0 * rc(i) / rho(i, j);
                }
                a.diag[k] = d;
            }
        }
        a
    }

    fn maxabs(r: &[f64]) -> f64 {
        r.iter().fold(0.0f64, |m, v| m.max(v.abs()))
    }

    /// Right-hand side: random, made consistent (zero sum) when the matrix is singular.
    fn rhs(p: Problem) -> Vec<f64> {
        let mut rng = Rng(p.seed + 17);
        let mut b: Vec<f64> = (0..p.n * p.n).map(|_| rng.next() - 0.5).collect();
        if !p.dirichlet_top {
            let mean = b.iter().sum::<f64>() / b.len() as f64;
            b.iter_mut().for_each(|v| *v -= mean);
        }
        b
    }

    const TOL: f64 = 1e-9;

    fn solve_mg(p: Problem) -> (Vec<f64>, usize) {
        let mut a = pressure_matrix(p);
        let b = rhs(p);
        let mut mg = Multigrid::new(2);
        mg.setup(&a);
        let mut x = vec![0.0; b.len()];
        let tol = TOL * maxabs(&b);
        let st = Pcg::new(b.len()).solve(&mut a, &mg, &b, &mut x, tol, 500, maxabs);
        assert!(st.converged, "MG-PCG failed on n = {}: {st:?}", p.n);
        (x, st.iterations)
    }

    fn cases(n: usize) -> Vec<Problem> {
        let mut v = Vec::new();
        for (k, (axisymmetric, periodic_x, dirichlet_top)) in [
            (false, false, false),
            (true, false, false),
            (false, true, false),
            (false, false, true),
            (true, false, true),
            (false, true, true),
        ]
        .into_iter()
        .enumerate()
        {
            v.push(Problem {
                n,
                axisymmetric,
                periodic_x,
                dirichlet_top,
                ratio: 1e4,
                seed: 3 + k as u64,
            });
        }
        v
    }

    #[test]
    fn coarse_matrix_of_a_constant_coefficient_is_the_rediscretised_one() {
        // Planar: unit couplings on 8×8 → unit couplings on 4×4; axisymmetric: r_f couplings.
        for axisymmetric in [false, true] {
            let p = Problem {
                n: 8,
                axisymmetric,
                periodic_x: false,
                dirichlet_top: true,
                ratio: 1.0,
                seed: 1,
            };
            let a = pressure_matrix(p);
            let mut c = Stencil5::new(1, 1, false, false);
            coarsen_into(&a, &mut c, 0.5);
            let want = pressure_matrix(Problem { n: 4, ..p });
            for k in 0..16 {
                assert!(
                    (c.east[k] - want.east[k]).abs() < 1e-12,
                    "{axisymmetric} e{k}"
                );
                assert!((c.north[k] - want.north[k]).abs() < 1e-12 * want.north[k].max(1.0));
                assert!((c.diag[k] - want.diag[k]).abs() < 1e-12 * want.diag[k]);
            }
        }
    }

    #[test]
    fn mg_pcg_converges_on_density_jumps_and_matches_ic_pcg() {
        for p in cases(64) {
            let (x_mg, it_mg) = solve_mg(p);
            let mut a = pressure_matrix(p);
            let b = rhs(p);
            let mut ic = IncompleteCholesky::new();
            ic.factor(&a);
            let mut x_ic = vec![0.0; b.len()];
            let tol = TOL * maxabs(&b);
            let st = Pcg::new(b.len()).solve(&mut a, &ic, &b, &mut x_ic, tol, 20000, maxabs);
            assert!(st.converged);
            // Singular systems: compare up to the constant.
            let shift = if p.dirichlet_top {
                0.0
            } else {
                (x_mg.iter().sum::<f64>() - x_ic.iter().sum::<f64>()) / b.len() as f64
            };
            let scale = maxabs(&x_ic);
            let diff = x_mg
                .iter()
                .zip(&x_ic)
                .fold(0.0f64, |m, (a, b)| m.max((a - shift - b).abs()));
            assert!(
                diff < 1e-6 * scale,
                "solutions differ by {diff:e} (scale {scale:e})"
            );
            assert!(
                it_mg * 4 < st.iterations,
                "MG {it_mg} vs IC {} iterations",
                st.iterations
            );
            assert!(it_mg <= 30, "MG-PCG took {it_mg} iterations");
        }
    }

    #[test]
    fn iterations_grow_less_than_20_percent_from_64_to_256() {
        for (p64, p256) in cases(64).into_iter().zip(cases(256)) {
            let (_, i64) = solve_mg(p64);
            let (_, i256) = solve_mg(p256);
            assert!(
                (i256 as f64) < 1.2 * i64 as f64,
                "{i64} → {i256} iterations (axisymmetric {}, periodic {}, Dirichlet {})",
                p64.axisymmetric,
                p64.periodic_x,
                p64.dirichlet_top
            );
        }
    }

    /// The table behind the module docs' figures: MG-PCG iterations for the six problem kinds
    /// at density ratios 1, 1e2, 1e4 and 64² to 512² (a few seconds; run with
    /// `cargo test -p efsi-linalg --lib iteration_table -- --ignored --nocapture`).
    #[test]
    #[ignore]
    fn iteration_table() {
        for ratio in [1.0, 1e2, 1e4] {
            for n in [64, 128, 256, 512] {
                let mut line = format!("ratio {ratio:e} n {n}:");
                for mut p in cases(n) {
                    p.ratio = ratio;
                    let (_, it) = solve_mg(p);
                    line += &format!(" {it}");
                }
                println!("{line}");
            }
        }
    }

    #[test]
    fn one_and_two_threads_give_identical_bits() {
        let p = cases(128)[1];
        let run = |t| {
            rayon::ThreadPoolBuilder::new()
                .num_threads(t)
                .build()
                .unwrap()
                .install(|| solve_mg(p))
        };
        let ((x1, i1), (x2, i2)) = (run(1), run(2));
        assert_eq!(i1, i2);
        assert!(x1.iter().zip(&x2).all(|(a, b)| a.to_bits() == b.to_bits()));
    }
}
