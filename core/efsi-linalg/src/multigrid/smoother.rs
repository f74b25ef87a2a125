//! The smoother: red–black Gauss–Seidel sweeps of a level, the two colours fused into one pass
//! over memory and run over chunks of rows in parallel, bit-identical whatever the threads.

use super::level::Level;
use crate::par::{self, SharedSlice};

impl Level {
    /// One red–black Gauss–Seidel sweep: the cells of colour `first` ((i + j) mod 2), then the
    /// others. The two half-sweeps are fused into one pass over memory (the second colour of
    /// row j − 1 right after the first colour of row j, Douglas et al. 2000), in chunks of rows
    /// in parallel: the second colour of each chunk's first and last rows waits for a second
    /// phase, when the first colour is done everywhere. Every update reads the same values as
    /// in two separate half-sweeps, so the result is the same bit for bit, whatever the
    /// chunking and the number of threads.
    pub(super) fn sweep(&mut self, first: usize) {
        if self.is_3d() {
            self.sweep_3d(first);
            return;
        }
        self.fill_ghosts();
        let (nx, ny, s) = (self.nx, self.ny, self.s);
        let second = 1 - first;
        let threads = rayon::current_num_threads();
        let chunk = if self.is_serial() || threads == 1 {
            ny
        } else {
            ny.div_ceil(2 * threads).max(4)
        };
        let rows = Rows {
            xs: SharedSlice::new(&mut self.x),
            b: &self.b[..],
            ce: &self.ce[..],
            cn: &self.cn[..],
            dinv: &self.dinv[..],
            nx,
            s,
            periodic_x: self.periodic_x,
        };
        let chunks = ny.div_ceil(chunk);
        let phase1 = |c: usize| {
            let (r0, r1) = (c * chunk, ((c + 1) * chunk).min(ny));
            for j in r0..r1 {
                rows.relax(first, j);
                if j >= r0 + 2 {
                    rows.relax(second, j - 1);
                }
            }
        };
        let phase2 = |c: usize| {
            let (r0, r1) = (c * chunk, ((c + 1) * chunk).min(ny));
            rows.relax(second, r0);
            if r1 - 1 > r0 {
                rows.relax(second, r1 - 1);
            }
        };
        par::range(chunks).work(chunk * nx).for_each(phase1);
        if self.periodic_y {
            rows.wrap_y(ny);
        }
        // Phase 2 touches two rows per chunk: split only when that is worth a fork.
        par::range(chunks).work(2 * nx).for_each(phase2);
    }
}

/// What a two-dimensional sweep updates and reads: the unknowns (shared between the threads of
/// one phase), the right-hand side, the couplings, the inverse diagonal, and the row layout
/// (`nx` cells a row, stride `s`, one ghost on each side).
struct Rows<'a> {
    xs: SharedSlice<'a>,
    b: &'a [f64],
    ce: &'a [f64],
    cn: &'a [f64],
    dinv: &'a [f64],
    nx: usize,
    s: usize,
    periodic_x: bool,
}

impl Rows<'_> {
    /// Update the cells of `colour` in row j, then refresh the row's periodic ghosts.
    #[inline]
    fn relax(&self, colour: usize, j: usize) {
        let (xs, nx, s) = (self.xs, self.nx, self.s);
        let base = (j + 1) * s + 1;
        let o = base + ((colour + j) & 1);
        let end = base + nx;
        // Everything this row touches: its cells, their neighbours and the row's ghosts.
        xs.check(base - 1 - s..end + 1 + s);
        if o < end {
            // The row's cells of `colour` are o, o + 2, …: a counted loop over slices of
            // exactly the length it touches, so that no index needs a bounds check.
            let cnt = (end - o).div_ceil(2);
            let len = 2 * cnt - 1;
            let (b, dinv) = (&self.b[o..o + len], &self.dinv[o..o + len]);
            let (ce, cw) = (&self.ce[o..o + len], &self.ce[o - 1..o - 1 + len]);
            let (cn, cs) = (&self.cn[o..o + len], &self.cn[o - s..o - s + len]);
            for m in 0..cnt {
                let t = 2 * m;
                let k = o + t;
                // SAFETY: inside the span checked above. A row update writes only cells of
                // `colour` in row j and reads their neighbours (the other colour) and row
                // j's ghosts. The sweep's phases never run two updates concurrently where one
                // writes what the other touches: in phase 1 a chunk updates the second colour
                // only of rows whose neighbour rows are in the same chunk; in phase 2 only
                // second-colour cells of distinct rows are written, reading first-colour cells
                // nobody writes.
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
        if self.periodic_x {
            // SAFETY: row j's ghost cells are touched by row j's updates only.
            unsafe {
                xs.set(base - 1, xs.get(base + nx - 1));
                xs.set(base + nx, xs.get(base));
            }
        }
    }

    /// Refresh the ghost rows across a periodic y wrap (of `ny` rows) between the two phases:
    /// the second colour of rows 0 and ny − 1 reads the first colour across the wrap.
    fn wrap_y(&self, ny: usize) {
        let (xs, nx, s) = (self.xs, self.nx, self.s);
        xs.check(0..(ny + 2) * s);
        for i in 1..=nx {
            // SAFETY: serial code between the two parallel phases, inside the checked span.
            unsafe {
                xs.set(i, xs.get(ny * s + i));
                xs.set((ny + 1) * s + i, xs.get(s + i));
            }
        }
    }
}

impl Level {
    /// One red–black Gauss–Seidel sweep of a three-dimensional level: the cells of colour
    /// `first` ((i + j + c) mod 2), then the others, each half-sweep over the rows in parallel
    /// after the periodic ghosts are refreshed. A cell's neighbours have the other colour, so
    /// the rows of one half-sweep are independent and the result is the same bit for bit
    /// whatever the threads (across an odd periodic wrap a neighbour of the same colour is
    /// read from its ghost, as it was before the half-sweep).
    fn sweep_3d(&mut self, first: usize) {
        let (nx, ny, nz, s, sp) = (self.nx, self.ny, self.nz, self.s, self.sp);
        let serial = self.is_serial();
        for colour in [first, 1 - first] {
            self.fill_ghosts();
            let zo = self.zo;
            // The unknowns out of the level while the rows read its matrix.
            let mut x = std::mem::take(&mut self.x);
            let xs = SharedSlice::new(&mut x);
            let lv = &*self;
            let b = &lv.b[..];
            let row = |r: usize| {
                let (j, c) = (r % ny, r / ny);
                let base = zo + c * sp + (j + 1) * s + 1;
                let o = base + ((colour + j + c) & 1);
                let end = base + nx;
                xs.check(base - 1 - sp..end + 1 + sp);
                if o >= end {
                    return;
                }
                // The row's cells of `colour` are o, o + 2, …: a counted loop over slices of
                // exactly the length it touches, so that no index needs a bounds check (as in
                // the two-dimensional `Rows::relax`). The coefficients are the row's
                // (`Level::row`, index 0 the west ghost at `base − 1`).
                let cnt = (end - o).div_ceil(2);
                let len = 2 * cnt - 1;
                let coef = lv.row(j, c);
                let t0 = o - (base - 1);
                let [ce, cw, cn, cs, ct, cb, _, dinv] = coef.run(t0, len);
                let bo = &b[o..o + len];
                for m in 0..cnt {
                    let (t, k) = (2 * m, o + 2 * m);
                    // SAFETY: inside the span checked above; a half-sweep writes only cells
                    // of `colour`, each row its own, and reads cells of the other colour and
                    // ghosts, which no one writes during it.
                    unsafe {
                        let v = (bo[t]
                            + ce[t] * xs.get(k + 1)
                            + cw[t] * xs.get(k - 1)
                            + cn[t] * xs.get(k + s)
                            + cs[t] * xs.get(k - s)
                            + ct[t] * xs.get(k + sp)
                            + cb[t] * xs.get(k - sp))
                            * dinv[t];
                        xs.set(k, v);
                    }
                }
            };
            if serial {
                (0..ny * nz).for_each(row);
            } else {
                par::range(ny * nz).work(nx).for_each(row);
            }
            self.x = x;
        }
    }
}
