//! Row loops over the staggered fields and the windows of grid points the elastic kernels
//! run over.

use efsi_core::{Field, G};
use rayon::prelude::*;

/// A window kernel with at least this many points runs its rows in parallel.
pub(super) const PAR_POINTS: usize = 1024;

/// Run `body(j, rows)` over the rows `j0..=j1` of the fields `a, b, c` (`rows[n]` is row `j` of
/// the n-th field, ghosts included: point `i` at `i + G`), in parallel when `par`. Each row
/// writes only its own entries, so the result does not depend on the number of threads.
pub(super) fn rows3(
    [a, b, c]: [&mut Field; 3],
    (j0, j1): (isize, isize),
    par: bool,
    body: impl Fn(isize, [&mut [f64]; 3]) + Sync + Send,
) {
    if j0 > j1 {
        return;
    }
    let s = a.stride();
    let (lo, hi) = (a.idx(-G, j0), a.idx(-G, j1) + s);
    let (a, b, c) = (
        &mut a.data_mut()[lo..hi],
        &mut b.data_mut()[lo..hi],
        &mut c.data_mut()[lo..hi],
    );
    if par {
        a.par_chunks_mut(s)
            .zip(b.par_chunks_mut(s))
            .zip(c.par_chunks_mut(s))
            .enumerate()
            .for_each(|(r, ((a, b), c))| body(j0 + r as isize, [a, b, c]));
    } else {
        a.chunks_mut(s)
            .zip(b.chunks_mut(s))
            .zip(c.chunks_mut(s))
            .enumerate()
            .for_each(|(r, ((a, b), c))| body(j0 + r as isize, [a, b, c]));
    }
}

/// [`rows3`] for two fields.
pub(super) fn rows2(
    [a, b]: [&mut Field; 2],
    (j0, j1): (isize, isize),
    par: bool,
    body: impl Fn(isize, [&mut [f64]; 2]) + Sync + Send,
) {
    if j0 > j1 {
        return;
    }
    let s = a.stride();
    let (lo, hi) = (a.idx(-G, j0), a.idx(-G, j1) + s);
    let (a, b) = (&mut a.data_mut()[lo..hi], &mut b.data_mut()[lo..hi]);
    if par {
        a.par_chunks_mut(s)
            .zip(b.par_chunks_mut(s))
            .enumerate()
            .for_each(|(r, (a, b))| body(j0 + r as isize, [a, b]));
    } else {
        a.chunks_mut(s)
            .zip(b.chunks_mut(s))
            .enumerate()
            .for_each(|(r, (a, b))| body(j0 + r as isize, [a, b]));
    }
}

/// [`rows3`] for one field.
pub(super) fn rows1(
    a: &mut Field,
    (j0, j1): (isize, isize),
    par: bool,
    body: impl Fn(isize, &mut [f64]) + Sync + Send,
) {
    if j0 > j1 {
        return;
    }
    let s = a.stride();
    let (lo, hi) = (a.idx(-G, j0), a.idx(-G, j1) + s);
    let a = &mut a.data_mut()[lo..hi];
    if par {
        a.par_chunks_mut(s)
            .enumerate()
            .for_each(|(r, a)| body(j0 + r as isize, a));
    } else {
        a.chunks_mut(s)
            .enumerate()
            .for_each(|(r, a)| body(j0 + r as isize, a));
    }
}

/// The position of point `i` in a row of [`rows3`] / [`rows1`].
#[inline(always)]
pub(super) fn at(i: isize) -> usize {
    (i + G) as usize
}

/// A rectangle of grid points `[i0, i1] × [j0, j1]` (inclusive; empty when `i0 > i1`), of
/// centres or of corners.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) struct Window {
    pub(super) i0: isize,
    pub(super) i1: isize,
    pub(super) j0: isize,
    pub(super) j1: isize,
}

impl Window {
    pub(super) fn new(i0: isize, i1: isize, j0: isize, j1: isize) -> Self {
        Window { i0, i1, j0, j1 }
    }

    /// Whether `(i, j)` is a point of the window.
    #[inline(always)]
    pub(super) fn contains(self, i: isize, j: isize) -> bool {
        (self.i0..=self.i1).contains(&i) && (self.j0..=self.j1).contains(&j)
    }

    /// Number of points.
    pub(super) fn points(self) -> usize {
        if self.i0 > self.i1 || self.j0 > self.j1 {
            0
        } else {
            ((self.i1 - self.i0 + 1) * (self.j1 - self.j0 + 1)) as usize
        }
    }

    /// The rows `(j0, j1)`.
    pub(super) fn rows(self) -> (isize, isize) {
        (self.j0, self.j1)
    }

    /// No point.
    pub(super) const EMPTY: Window = Window {
        i0: 0,
        i1: -1,
        j0: 0,
        j1: -1,
    };

    /// The corners `(i, j)` (lower-left of centre `(i, j)`) touching a centre of `self`,
    /// within `[0, nx] × [0, ny]`.
    pub(super) fn corners(self, nx: isize, ny: isize) -> Window {
        if self.i0 > self.i1 {
            return Window::EMPTY;
        }
        Window::new(
            self.i0.max(0),
            (self.i1 + 1).min(nx),
            self.j0.max(0),
            (self.j1 + 1).min(ny),
        )
    }
}
