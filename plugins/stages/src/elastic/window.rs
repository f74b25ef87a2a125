//! The windows of grid points the elastic kernels run over, as regions of the loop abstraction,
//! and the stencils that join the centres and the edges of the staggered tensor.
//!
//! A shear pair `(a, b)` of [`SHEAR`](crate::viscous_operator::SHEAR) lives on the edges along
//! the third axis `c`; the edge `I` sits at the low faces of cell `I` along `a` and `b` and at
//! the cell's centre along `c` (a two-dimensional grid has the pair `[0, 1]` only, on the cell
//! corners). Its four cells are `I − e_a − e_b, I − e_b, I − e_a, I` ([`cells_of_edge`]); a cell's
//! four edges of the pair are `I, I + e_a, I + e_b, I + e_a + e_b` ([`edges_of_cell`]).

use efsi_core::{Field, Grid, Index, Line, Region, Stagger, unit};

/// A box of grid points `[i0, i1] × [j0, j1] × [k0, k1]` (inclusive; empty when `i0 > i1`), of
/// centres or of one family of edges: the bounding box of the solid or of the material, which
/// the kernels visit as a [`Region`] ([`Window::region`]). On a two-dimensional grid
/// `k0 = k1 = 0`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) struct Window {
    pub(super) i0: isize,
    pub(super) i1: isize,
    pub(super) j0: isize,
    pub(super) j1: isize,
    pub(super) k0: isize,
    pub(super) k1: isize,
}

impl Window {
    /// The window `lo ≤ I ≤ hi` (component-wise).
    pub(super) fn boxed(lo: Index, hi: Index) -> Self {
        Window {
            i0: lo[0],
            i1: hi[0],
            j0: lo[1],
            j1: hi[1],
            k0: lo[2],
            k1: hi[2],
        }
    }

    /// The lowest point.
    pub(super) fn lo(self) -> Index {
        [self.i0, self.j0, self.k0]
    }

    /// The highest point.
    pub(super) fn hi(self) -> Index {
        [self.i1, self.j1, self.k1]
    }

    /// Whether `(i, j)` is a point of the window's rows (any plane).
    #[inline(always)]
    pub(super) fn contains(self, i: isize, j: isize) -> bool {
        (self.i0..=self.i1).contains(&i) && (self.j0..=self.j1).contains(&j)
    }

    /// Whether `at` is a point of the window.
    #[inline(always)]
    pub(super) fn contains3(self, at: Index) -> bool {
        self.contains(at[0], at[1]) && (self.k0..=self.k1).contains(&at[2])
    }

    /// The position of `at` (a point of the window) among its points, line by line (`i`
    /// fastest, then `j`, then `k`): its entry in a batch packed in the window's order.
    #[inline(always)]
    pub(super) fn offset(self, at: Index) -> usize {
        let (w, h) = (self.i1 - self.i0 + 1, self.j1 - self.j0 + 1);
        (((at[2] - self.k0) * h + at[1] - self.j0) * w + at[0] - self.i0) as usize
    }

    /// The point at position `q` ([`Window::offset`]).
    pub(super) fn point(self, q: usize) -> Index {
        let (w, h) = (
            (self.i1 - self.i0 + 1).max(1) as usize,
            (self.j1 - self.j0 + 1).max(1) as usize,
        );
        let (i, j, k) = (q % w, (q / w) % h, q / (w * h));
        [
            self.i0 + i as isize,
            self.j0 + j as isize,
            self.k0 + k as isize,
        ]
    }

    /// Number of points.
    pub(super) fn points(self) -> usize {
        if self.i0 > self.i1 || self.j0 > self.j1 || self.k0 > self.k1 {
            0
        } else {
            ((self.i1 - self.i0 + 1) * (self.j1 - self.j0 + 1) * (self.k1 - self.k0 + 1)) as usize
        }
    }

    /// The bounding box of `self` and `other` (either empty: the other).
    pub(super) fn union(self, other: Window) -> Window {
        match (self.points(), other.points()) {
            (0, _) => other,
            (_, 0) => self,
            _ => {
                let (a, b, c, d) = (self.lo(), self.hi(), other.lo(), other.hi());
                Window::boxed(
                    std::array::from_fn(|x| a[x].min(c[x])),
                    std::array::from_fn(|x| b[x].max(d[x])),
                )
            }
        }
    }

    /// No point.
    pub(super) const EMPTY: Window = Window {
        i0: 0,
        i1: -1,
        j0: 0,
        j1: -1,
        k0: 0,
        k1: -1,
    };

    /// The window's points as a region of `grid` (its lines are the window's rows, in order:
    /// point `n` of line `l` is entry `l.n · l.len + n` of a batch packed row by row).
    pub(super) fn region(self, grid: &Grid) -> Region {
        Region::of(grid, Stagger::Cell)
            .range(0, self.i0, self.i1 + 1)
            .range(1, self.j0, self.j1 + 1)
            .range(2, self.k0, self.k1 + 1)
    }

    /// The edges at `at` touching a centre of `self`: along the edges' nodal axes the low and
    /// high edges of each centre within `[0, n]`, along their centred axis the centres' own
    /// indices. With [`Stagger::Corner`] on a two-dimensional grid, the corners `(i, j)`
    /// (lower-left of centre `(i, j)`) within `[0, nx] × [0, ny]`.
    pub(super) fn edges(self, grid: &Grid, at: Stagger) -> Window {
        if self.points() == 0 {
            return Window::EMPTY;
        }
        let (lo, hi, n, nodal) = (self.lo(), self.hi(), grid.n(), at.nodal());
        Window::boxed(
            std::array::from_fn(|a| if nodal[a] == 1 { lo[a].max(0) } else { lo[a] }),
            std::array::from_fn(|a| {
                if nodal[a] == 1 {
                    (hi[a] + 1).min(n[a] as isize)
                } else {
                    hi[a]
                }
            }),
        )
    }
}

/// `I + s`.
#[inline(always)]
pub(super) fn plus([i, j, k]: Index, [a, b, c]: Index) -> Index {
    [i + a, j + b, k + c]
}

/// `−s`.
#[inline(always)]
fn neg([a, b, c]: Index) -> Index {
    [-a, -b, -c]
}

/// The four cells around an edge `I` of the shear pair `[a, b]` (lower-left, lower-right,
/// upper-left, upper-right in the `a`–`b` plane), as shifts from `I`.
pub(super) fn cells_of_edge([a, b]: [usize; 2]) -> [Index; 4] {
    let (ea, eb) = (unit(a), unit(b));
    [neg(plus(ea, eb)), neg(eb), neg(ea), [0; 3]]
}

/// The four edges of the shear pair `[a, b]` of a cell `I` (lower-left, lower-right,
/// upper-left, upper-right in the `a`–`b` plane), as shifts from `I`.
pub(super) fn edges_of_cell([a, b]: [usize; 2]) -> [Index; 4] {
    let (ea, eb) = (unit(a), unit(b));
    [[0; 3], ea, eb, plus(ea, eb)]
}

/// A field's values at four shifts from the indices of a line (e.g. [`cells_of_edge`]).
#[derive(Clone, Copy)]
pub(super) struct Four<'a>([&'a [f64]; 4]);

impl<'a> Four<'a> {
    /// `f` on `line` shifted by each of `shifts`.
    #[inline(always)]
    pub(super) fn new(f: &'a Field, line: &Line, shifts: [Index; 4]) -> Self {
        let at = |m: usize| f.at(line, shifts[m]);
        Four([at(0), at(1), at(2), at(3)])
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
