//! Geometric multigrid (W-cycle on the fine levels) for five-point (seven-point in 3-D) SPD
//! matrices on the cell grid, used as the
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
//! two fine faces is `2 r_F dZ/dR`).
//!
//! **Cycle.** A W-cycle: pre-smoothing by `ν` red–black Gauss–Seidel sweeps (red then black),
//! restriction of the residual by summing the four children (`R = Pᵀ`), two coarse
//! corrections (the second from the residual of the first; one next to the coarsest level),
//! prolongation `P`, then `ν` sweeps in the reverse colour order (black then red) — the
//! adjoint of the pre-smoother, so the cycle is a symmetric operator; it is positive definite
//! because the smoother converges and each coarse correction is symmetric positive
//! semi-definite (Tatebe 1993 for MG-CG). The coarsest system is solved exactly by a dense
//! Cholesky factor. A V-cycle's iteration count grows with the number of levels (the
//! piecewise-constant transfer has orders `m_P + m_R = 2`, not `> 2`); the W-cycle's does not,
//! at a higher cost per cycle.
//!
//! The two corrections are made on the finest [`W_LEVELS`] = 2 levels only; below them the
//! cycle is a V-cycle. A full W-cycle visits level `l` 2^l times, and the coarse levels (below
//! [`par::PAR_MIN`] cells) run serially, so they would dominate a cycle; with the V below
//! level 2 they are visited 4 times, and the iterations stay those of the full W-cycle within
//! one (the `iteration_table` test: six problem kinds at density ratios 1, 1e2, 1e4 from 64²
//! to 512²).
//!
//! **Three dimensions.** A seven-point [`Stencil5`] (`nz > 1`, [`Stencil5::new_3d`]) gets the
//! same multigrid: aggregates of 2 × 2 × 2 cells (a direction of ≤ 2 cells no longer
//! coarsened), the same coarse rule (the Galerkin coupling across a coarse face scaled by ½
//! when its direction is coarsened — for a constant coefficient again the rediscretised
//! operator, `4·h_f = 2·h_c` per face; the diagonal's excess by the excess scale when all three
//! directions are), the same cycles, the dense Cholesky on ≤ [`COARSEST_CELLS`] cells. The
//! smoother's two half-sweeps run one after the other, each over the lines of cells along x in
//! parallel ((i + j + c) mod 2 the colour), and a three-dimensional matrix is applied to whole
//! vectors only (no window).
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
//! are bit-identical whatever the number of threads.
//!
//! **Allocation.** [`Multigrid::setup`] allocates the hierarchy on the first call and reuses it
//! for later matrices of the same shape or smaller ones (a window of the first, set up each
//! step where a solid moves: [`Stencil5::window_into`], [`Multigrid::apply_window`]); only a
//! matrix larger than every earlier one allocates. [`Preconditioner::apply`] never allocates.
//! A three-dimensional level whose matrix has one coupling per axis (zero across a closed
//! side) and the sum of a cell's couplings on the diagonal — the projection's matrix for one
//! density, and its Galerkin coarsenings where they stay so — holds it as one padded row of
//! each coefficient instead of five arrays of the level's size (module `level`), on every
//! level but the coarsest: the finest level then keeps only its two vectors, the unknowns and
//! the right-hand side. The kernels read the same values either way, so the results are the
//! same bits.

use super::par;
use super::pcg::Preconditioner;
use super::stencil5::{Stencil5, Stencil5View};
use std::sync::{Mutex, MutexGuard, PoisonError, TryLockError};

mod coarsen;
mod coarsest;
mod cycle;
mod fine;
mod level;
mod smoother;
mod transfer;

pub use coarsen::coarsen_into;
use coarsen::{coarsen_levels, factor};
use coarsest::Coarsest;
use cycle::cycle;
pub use fine::FineMatrix;
use level::Level;

/// The hierarchy stops coarsening at this many cells (solved by dense Cholesky).
pub const COARSEST_CELLS: usize = 64;

/// The W-cycle makes two coarse corrections on this many of the finest levels and one (a
/// V-cycle) below them (module docs: "Cycle").
pub const W_LEVELS: usize = 2;

#[derive(Clone, Debug, Default)]
struct Hierarchy {
    /// The levels; only the first `n` are in use (a smaller matrix reuses the storage of a
    /// larger one's levels).
    levels: Vec<Level>,
    n: usize,
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
    /// Whether a three-dimensional level of one coupling per axis holds its matrix as rows
    /// (module `level`); off only in the tests that compare the two forms.
    uniform_rows: bool,
    /// Behind a mutex, so that a multigrid can live in a structure other threads read (two
    /// blocks of a system, each with its own multigrid, applied in parallel). One application
    /// at a time: a second, concurrent one panics instead of waiting (it could deadlock on the
    /// rayon worker holding the lock).
    h: Mutex<Hierarchy>,
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
            uniform_rows: true,
            h: Mutex::new(Hierarchy::default()),
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

    /// The hierarchy (a panic in another thread's application left nothing half-done that
    /// the next application does not overwrite).
    fn lock(&self) -> MutexGuard<'_, Hierarchy> {
        match self.h.try_lock() {
            Ok(h) => h,
            Err(TryLockError::Poisoned(p)) => p.into_inner(),
            Err(TryLockError::WouldBlock) => {
                panic!(
                    "multigrid: applied from two threads at once (one multigrid per application in flight)"
                )
            }
        }
    }

    /// Number of levels (1 when the matrix is already at most [`COARSEST_CELLS`]).
    pub fn levels(&self) -> usize {
        self.lock().n
    }

    /// Build (first call, or a new shape) or refresh the hierarchy for the matrix `a`.
    /// Allocates only where a level of `a`'s hierarchy needs more storage than that level of
    /// every matrix set up before: a smaller matrix (a window of the first one, say) reuses
    /// the levels in place.
    pub fn setup(&mut self, a: &Stencil5) {
        self.setup_view(a.view());
    }

    /// [`setup`](Self::setup) from a borrowed matrix, which the caller need not keep: the
    /// finest level holds a copy, whose product [`fine_matrix`](Self::fine_matrix) applies.
    pub fn setup_view(&mut self, a: Stencil5View<'_>) {
        let h = self.h.get_mut().unwrap_or_else(PoisonError::into_inner);
        let same = h.n > 0 && {
            let l = &h.levels[0];
            l.nx == a.nx
                && l.ny == a.ny
                && l.nz == a.nz
                && l.periodic_x == a.periodic_x
                && l.periodic_y == a.periodic_y
                && l.periodic_z == a.periodic_z
        };
        if !same {
            let periodic = [a.periodic_x, a.periodic_y, a.periodic_z];
            let reshape = |levels: &mut Vec<Level>, l: usize, shape: [usize; 3]| {
                if l < levels.len() {
                    levels[l].reshape(shape, periodic);
                } else {
                    levels.push(Level::shape(shape, periodic));
                }
            };
            reshape(&mut h.levels, 0, [a.nx, a.ny, a.nz]);
            let (mut nx, mut ny, mut nz, mut n) = (a.nx, a.ny, a.nz, 1);
            while nx * ny * nz > COARSEST_CELLS && (nx > 2 || ny > 2 || nz > 2) {
                nx = nx.div_ceil(factor(nx));
                ny = ny.div_ceil(factor(ny));
                nz = nz.div_ceil(factor(nz));
                reshape(&mut h.levels, n, [nx, ny, nz]);
                if n - 1 < self.mats.len() {
                    self.mats[n - 1].reshape_3d(nx, ny, nz, periodic);
                } else {
                    self.mats.push(Stencil5::new_3d(nx, ny, nz, periodic));
                }
                n += 1;
            }
            h.n = n;
            // The coarsest factor of any matrix fits in this (it never has more cells).
            h.coarsest.reserve(COARSEST_CELLS);
        }
        let n = h.n;
        for (l, lv) in h.levels[..n].iter_mut().enumerate() {
            lv.size_t(l, n, self.gamma);
            lv.keep_arrays = l + 1 == n || !self.uniform_rows;
        }
        h.levels[0].load(a);
        let excess = self.excess_scale;
        let Hierarchy {
            levels, coarsest, ..
        } = h;
        let levels = &mut levels[..n];
        let mats = &mut self.mats[..n - 1];
        // Levels coarsened from a serial-sized one, and the Cholesky factor, with a second
        // thread kept awake for what follows.
        let first_serial = (1..n).find(|&l| levels[l - 1].is_serial()).unwrap_or(n);
        coarsen_levels(a, mats, levels, 1..first_serial, excess);
        par::serial_warm(|| {
            coarsen_levels(a, mats, levels, first_serial..n, excess);
            coarsest.factor(levels.last().expect("at least one level"));
        });
    }

    /// Whether the multigrid is set up for `a` already, bit for bit: [`setup_view`](Self::setup_view)
    /// of `a` would change nothing. Lets a caller that assembles its matrix each time skip the
    /// set-up without keeping a copy of what it was assembled from.
    pub fn is_set_up_for(&self, a: Stencil5View<'_>) -> bool {
        let h = self.lock();
        h.n > 0 && h.levels[0].holds(a)
    }

    /// The preconditioner applied to a window of longer vectors: the matrix set up is
    /// `nx × ny`, and its unknown `(i, j)` is entry `origin + j·stride + i` of `r` and `z`;
    /// entries of `z` outside the window are not touched. [`Preconditioner::apply`] is the
    /// window that is the whole vector (`stride = nx`, `origin = 0`).
    pub fn apply_window(&self, r: &[f64], z: &mut [f64], stride: usize, origin: usize) {
        let mut h = self.lock();
        let n = h.n;
        let Hierarchy {
            levels, coarsest, ..
        } = &mut *h;
        let levels = &mut levels[..n];
        let (nx, ny) = (levels[0].nx, levels[0].ny);
        if nx == 0 || ny == 0 {
            return;
        }
        if levels[0].is_3d() {
            assert!(
                stride == nx && origin == 0,
                "multigrid: a three-dimensional matrix is applied to whole vectors only"
            );
            apply_3d(levels, coarsest, r, z, self.sweeps, self.gamma);
            return;
        }
        assert!(
            nx <= stride && (ny == 0 || origin + (ny - 1) * stride + nx <= r.len().min(z.len())),
            "multigrid: the {nx} × {ny} window at {origin} (rows of {stride}) exceeds the vectors"
        );
        {
            let l0 = &mut levels[0];
            let s = l0.s;
            par::rows(&mut l0.b[s..(ny + 1) * s], s).for_each(|j, row| {
                let o = origin + j * stride;
                row[1..=nx].copy_from_slice(&r[o..o + nx]);
            });
        }
        cycle(levels, coarsest, 0, self.sweeps, self.gamma);
        let l0 = &levels[0];
        let s = l0.s;
        let x = &l0.x;
        if stride == nx && origin == 0 {
            par::rows(&mut z[..nx * ny], nx).for_each(|j, row| {
                row.copy_from_slice(&x[(j + 1) * s + 1..(j + 1) * s + 1 + nx]);
            });
        } else {
            let zw = &mut z[origin..origin + (ny - 1) * stride + nx];
            par::rows(zw, stride).work(nx).for_each(|j, row| {
                let n = row.len().min(nx);
                row[..n].copy_from_slice(&x[(j + 1) * s + 1..(j + 1) * s + 1 + n]);
            });
        }
    }
}

/// One cycle on a three-dimensional hierarchy: `r` into the finest level's padded right-hand
/// side, the cycle, its solution out into `z` (rows in parallel).
fn apply_3d(
    levels: &mut [Level],
    coarsest: &mut Coarsest,
    r: &[f64],
    z: &mut [f64],
    sweeps: usize,
    gamma: usize,
) {
    let l0 = &mut levels[0];
    let (nx, ny, nz, s) = (l0.nx, l0.ny, l0.nz, l0.s);
    assert!(
        r.len() == nx * ny * nz && z.len() == nx * ny * nz,
        "multigrid: vector length ≠ matrix size"
    );
    let span = l0.rows_span();
    par::rows(&mut l0.b[span], s).for_each(|q, row| {
        let (j, c) = (q % (ny + 2), q / (ny + 2));
        if j < ny {
            let o = (c * ny + j) * nx;
            row[1..=nx].copy_from_slice(&r[o..o + nx]);
        }
    });
    cycle(levels, coarsest, 0, sweeps, gamma);
    let l0 = &levels[0];
    let x = &l0.x;
    par::rows(z, nx).for_each(|q, row| {
        let (j, c) = (q % ny, q / ny);
        let p = l0.p3(0, j, c);
        row.copy_from_slice(&x[p..p + nx]);
    });
}

impl Preconditioner for Multigrid {
    fn apply(&self, r: &[f64], z: &mut [f64]) {
        let (nx, ny) = {
            let h = self.lock();
            (h.levels[0].nx, h.levels[0].ny * h.levels[0].nz)
        };
        assert_eq!(r.len(), nx * ny, "multigrid: vector length ≠ matrix size");
        self.apply_window(r, z, nx, 0);
    }
}

#[cfg(test)]
mod tests;
