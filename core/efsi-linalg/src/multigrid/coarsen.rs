//! Building the hierarchy's matrices: 2 × 2 aggregation and the scaled Galerkin coarse matrix
//! of each level from its finer neighbour (module docs: "Hierarchy").

use super::level::Level;
use super::transfer::RUN;
use crate::par;
use crate::stencil5::{Stencil5, Stencil5View};

/// Cells per aggregate along a direction of `n` cells: 2, or 1 once `n ≤ 2`.
pub(super) fn factor(n: usize) -> usize {
    if n > 2 { 2 } else { 1 }
}

/// The coarse matrix of `a` (module docs: half the Galerkin product of the piecewise-constant
/// aggregation along each coarsened direction), into `c` (reshaped as needed). The excess of
/// the diagonal over the couplings is summed over each aggregate and multiplied by
/// `excess_scale` when both directions are coarsened (½ for Dirichlet faces, 1 for a mass
/// term).
pub fn coarsen_into(a: &Stencil5, c: &mut Stencil5, excess_scale: f64) {
    coarsen_view_into(a.view(), c, excess_scale);
}

/// [`coarsen_into`] from a borrowed matrix.
pub(super) fn coarsen_view_into(a: Stencil5View<'_>, c: &mut Stencil5, excess_scale: f64) {
    if a.is_3d() {
        coarsen_3d(a, c, excess_scale);
        return;
    }
    let g = Aggregation::of(a, excess_scale);
    let (cx, cy) = (g.cx, g.cy);
    if c.nx != cx || c.ny != cy || c.len() != cx * cy {
        c.reshape(cx, cy, a.periodic_x, a.periodic_y);
    }
    c.periodic_x = a.periodic_x;
    c.periodic_y = a.periodic_y;
    // Coarse rows in parallel. Each fine row's couplings and excesses are computed in runs
    // (they vectorise), then added to the coarse row's sums fine row by fine row, child by
    // child — every coarse entry sums its children in the order (j, i), so the sums do not
    // depend on the number of threads.
    let n = cx * cy;
    let lanes = (&mut c.east[..n], &mut c.north[..n], &mut c.diag[..n]);
    par::rows(lanes, cx)
        .work(g.fy * a.nx)
        .for_each(|jc, (ce, cn, cd)| g.coarse_row(a, jc, (ce, cn, cd)));
    let mut diag = std::mem::take(&mut c.diag);
    let cc = &*c;
    par::rows(&mut diag[..], cx).for_each(|jc, row| {
        for (ic, d) in row.iter_mut().enumerate() {
            let kc = jc * cx + ic;
            *d += cc.east[kc] + cc.north[kc] + cc.west(kc, ic) + cc.south(kc, jc);
        }
    });
    c.diag = diag;
}

/// How a two-dimensional matrix of `nx` cells a row is aggregated: the aggregate's height
/// `fy`, the coarse size `cx` × `cy`, the scales of the couplings (`sx`, `sy`) and of the
/// excess (`se`), and `lx` = log₂ of the aggregate's width.
struct Aggregation {
    nx: usize,
    fy: usize,
    cx: usize,
    cy: usize,
    sx: f64,
    sy: f64,
    se: f64,
    lx: u32,
}

/// A fine row's run of couplings and excesses (`len` ≤ [`RUN`] cells from `i0`).
type Run<'r> = (&'r [f64], &'r [f64], &'r [f64]);

impl Aggregation {
    /// The aggregation of `a`; `excess_scale` scales the excess when both directions are
    /// coarsened.
    fn of(a: Stencil5View<'_>, excess_scale: f64) -> Aggregation {
        let (fx, fy) = (factor(a.nx), factor(a.ny));
        // Over-correction: ½ along a coarsened direction (the rediscretised scale), 1 across.
        Aggregation {
            nx: a.nx,
            fy,
            cx: a.nx.div_ceil(fx),
            cy: a.ny.div_ceil(fy),
            sx: if fx == 2 { 0.5 } else { 1.0 },
            sy: if fy == 2 { 0.5 } else { 1.0 },
            se: if fx * fy == 4 { excess_scale } else { 1.0 },
            // i / fx as a shift (fx is 1 or 2): an integer division per cell cost more than
            // the rest.
            lx: fx.trailing_zeros(),
        }
    }

    /// Coarse row `jc`'s couplings and excesses (`ce`, `cn`, `cd`, zeroed first) summed from
    /// its fine rows, fine row by fine row in runs of [`RUN`] cells.
    #[inline]
    fn coarse_row(
        &self,
        a: Stencil5View<'_>,
        jc: usize,
        (ce, cn, cd): (&mut [f64], &mut [f64], &mut [f64]),
    ) {
        let (nx, ny) = (self.nx, a.ny);
        ce.fill(0.0);
        cn.fill(0.0);
        cd.fill(0.0);
        let j1 = (self.fy * jc + self.fy).min(ny);
        let (mut e, mut n, mut x) = ([0.0f64; RUN], [0.0f64; RUN], [0.0f64; RUN]);
        for j in self.fy * jc..j1 {
            let north_face = j + 1 == j1 && self.cy > 1;
            let mut i0 = 0;
            while i0 < nx {
                let len = (nx - i0).min(RUN);
                self.fine_run(a, j, i0, &mut e[..len], &mut n[..len], &mut x[..len]);
                let run = (&e[..len], &n[..len], &x[..len]);
                self.add_run(i0, north_face, run, ce, cn, cd);
                i0 += len;
            }
        }
    }

    /// The couplings `e`, `n` of fine row j's cells from `i0` (zero across a side that is not
    /// periodic), and their excesses `x` (scaled; zero where the diagonal does not exceed the
    /// couplings by more than 1e-12 of itself).
    #[inline]
    fn fine_run(
        &self,
        a: Stencil5View<'_>,
        j: usize,
        i0: usize,
        e: &mut [f64],
        n: &mut [f64],
        x: &mut [f64],
    ) {
        let (nx, ny, len) = (a.nx, a.ny, e.len());
        let k0 = j * nx + i0;
        e.copy_from_slice(&a.east[k0..k0 + len]);
        if i0 + len == nx && !a.periodic_x {
            e[len - 1] = 0.0;
        }
        if j + 1 == ny && !a.periodic_y {
            n.fill(0.0);
        } else {
            n.copy_from_slice(&a.north[k0..k0 + len]);
        }
        for t in 0..len {
            let k = k0 + t;
            let i = i0 + t;
            let excess = a.diag[k] - (e[t] + n[t] + a.west(k, i) + a.south(k, j));
            x[t] = if excess > 1e-12 * a.diag[k] {
                self.se * excess
            } else {
                0.0
            };
        }
    }

    /// Add a fine run (from cell `i0` of a fine row; `north_face`: the row is the last of its
    /// aggregates) into the coarse row's sums, child by child.
    #[inline]
    fn add_run(
        &self,
        i0: usize,
        north_face: bool,
        (e, n, x): Run<'_>,
        ce: &mut [f64],
        cn: &mut [f64],
        cd: &mut [f64],
    ) {
        let (nx, lx) = (self.nx, self.lx);
        for t in 0..e.len() {
            let i = i0 + t;
            let kc = i >> lx;
            // A fine face between two aggregates (or across the periodic wrap) couples them;
            // a periodic direction of one coarse cell couples the cell to itself: no coupling.
            let east_face = (i + 1 == nx || (i + 1) >> lx != i >> lx) && self.cx > 1;
            if east_face {
                ce[kc] += self.sx * e[t];
            }
            if north_face {
                cn[kc] += self.sy * n[t];
            }
            if x[t] != 0.0 {
                cd[kc] += x[t];
            }
        }
    }
}

/// [`coarsen_view_into`] of a three-dimensional matrix: the same rule along z (a top coupling
/// across a coarse face scaled by ½ when z is coarsened; the excess by `excess_scale` when all
/// three directions are), fine cell by fine cell in the order (i, j, c).
fn coarsen_3d(a: Stencil5View<'_>, c: &mut Stencil5, excess_scale: f64) {
    let (nx, ny, nz) = (a.nx, a.ny, a.nz);
    let (fx, fy, fz) = (factor(nx), factor(ny), factor(nz));
    let (cx, cy, cz) = (nx.div_ceil(fx), ny.div_ceil(fy), nz.div_ceil(fz));
    let periodic = [a.periodic_x, a.periodic_y, a.periodic_z];
    c.reshape_3d(cx, cy, cz, periodic);
    let half = |f: usize| if f == 2 { 0.5 } else { 1.0 };
    let (sx, sy, sz) = (half(fx), half(fy), half(fz));
    let se = if fx * fy * fz == 8 { excess_scale } else { 1.0 };
    let (lx, ly, lz) = (
        fx.trailing_zeros(),
        fy.trailing_zeros(),
        fz.trailing_zeros(),
    );
    for k in 0..nz {
        for j in 0..ny {
            for i in 0..nx {
                let f = (k * ny + j) * nx + i;
                let kc = ((k >> lz) * cy + (j >> ly)) * cx + (i >> lx);
                let e = if i + 1 == nx && !a.periodic_x {
                    0.0
                } else {
                    a.east[f]
                };
                let n = if j + 1 == ny && !a.periodic_y {
                    0.0
                } else {
                    a.north[f]
                };
                let t = if k + 1 == nz && !a.periodic_z {
                    0.0
                } else {
                    a.top[f]
                };
                let excess =
                    a.diag[f] - (e + n + t + a.west(f, i) + a.south(f, j) + a.bottom(f, k));
                // A fine face between two aggregates (or across the periodic wrap) couples
                // them; a periodic direction of one coarse cell couples the cell to itself: no
                // coupling.
                if (i + 1 == nx || (i + 1) >> lx != i >> lx) && cx > 1 {
                    c.east[kc] += sx * e;
                }
                if (j + 1 == ny || (j + 1) >> ly != j >> ly) && cy > 1 {
                    c.north[kc] += sy * n;
                }
                if (k + 1 == nz || (k + 1) >> lz != k >> lz) && cz > 1 {
                    c.top[kc] += sz * t;
                }
                if excess > 1e-12 * a.diag[f] {
                    c.diag[kc] += se * excess;
                }
            }
        }
    }
    for k in 0..cz {
        for j in 0..cy {
            for i in 0..cx {
                let kc = (k * cy + j) * cx + i;
                let off = c.east[kc] + c.north[kc] + c.top[kc];
                let v = c.view();
                let off = off + v.west(kc, i) + v.south(kc, j) + v.bottom(kc, k);
                c.diag[kc] += off;
            }
        }
    }
}

/// Levels `range` of the hierarchy from their finer neighbours (`a` is level 0's matrix,
/// `mats[l − 1]` level l's).
pub(super) fn coarsen_levels(
    a: Stencil5View<'_>,
    mats: &mut [Stencil5],
    levels: &mut [Level],
    range: std::ops::Range<usize>,
    excess_scale: f64,
) {
    for l in range {
        let (done, rest) = mats.split_at_mut(l - 1);
        let fine = if l == 1 { a } else { done[l - 2].view() };
        coarsen_view_into(fine, &mut rest[0], excess_scale);
        levels[l].load(rest[0].view());
    }
}
