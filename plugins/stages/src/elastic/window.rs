//! The windows of grid points the elastic kernels run over, as regions of the loop abstraction,
//! and the stencils that join the centres and the corners of the staggered tensor.

use efsi_core::{Field, Grid, Index, Line, Region, Stagger};

/// A rectangle of grid points `[i0, i1] × [j0, j1]` (inclusive; empty when `i0 > i1`), of
/// centres or of corners: the bounding box of the solid or of the material, which the kernels
/// visit as a [`Region`] ([`Window::region`]).
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

    /// No point.
    pub(super) const EMPTY: Window = Window {
        i0: 0,
        i1: -1,
        j0: 0,
        j1: -1,
    };

    /// The window's points as a region of `grid` (its lines are the window's rows, in order:
    /// point `n` of line `l` is entry `l.n · l.len + n` of a batch packed row by row).
    pub(super) fn region(self, grid: &Grid) -> Region {
        Region::of(grid, Stagger::Cell)
            .range(0, self.i0, self.i1 + 1)
            .range(1, self.j0, self.j1 + 1)
    }

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

/// `I + s`.
#[inline(always)]
pub(super) fn plus([i, j, k]: Index, [a, b, c]: Index) -> Index {
    [i + a, j + b, k + c]
}

/// The four cells around a corner `I` (lower-left, lower-right, upper-left, upper-right), as
/// shifts from `I`.
pub(super) const CELLS_OF_CORNER: [Index; 4] = [[-1, -1, 0], [0, -1, 0], [-1, 0, 0], [0, 0, 0]];

/// The four corners of a cell `I` (lower-left, lower-right, upper-left, upper-right), as shifts
/// from `I`.
pub(super) const CORNERS_OF_CELL: [Index; 4] = [[0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0]];

/// A field's values at four shifts from the indices of a line (e.g. [`CELLS_OF_CORNER`]).
#[derive(Clone, Copy)]
pub(super) struct Four<'a>([&'a [f64]; 4]);

impl<'a> Four<'a> {
    /// `f` on `line` shifted by each of `shifts`.
    #[inline(always)]
    pub(super) fn new(f: &'a Field, line: &Line, shifts: [Index; 4]) -> Self {
        Four(shifts.map(|s| f.at(line, s)))
    }

    /// The four values' mean at point `n` of the line: `¼ (f₀ + f₁ + f₂ + f₃)`.
    #[inline(always)]
    pub(super) fn avg(&self, n: usize) -> f64 {
        let f = &self.0;
        0.25 * (f[0][n] + f[1][n] + f[2][n] + f[3][n])
    }

    /// `Σ w_m f_m` at point `n`, with the weights `w` at the line's own indices.
    #[inline(always)]
    pub(super) fn weighted(&self, w: &[&[f64]; 4], n: usize) -> f64 {
        let f = &self.0;
        w[0][n] * f[0][n] + w[1][n] * f[1][n] + w[2][n] * f[2][n] + w[3][n] * f[3][n]
    }

    /// The value at shift `m` and point `n`.
    #[inline(always)]
    pub(super) fn get(&self, m: usize, n: usize) -> f64 {
        self.0[m][n]
    }
}
