//! One level of the hierarchy: its matrix in a padded layout (one ghost ring) with the work
//! vectors, loaded from a [`Stencil5`](crate::Stencil5), its periodic ghosts and its residual.

use super::W_LEVELS;
use crate::par;
use crate::stencil5::Stencil5View;

/// One level: the matrix in a padded layout (one ghost ring), and the work vectors.
#[derive(Clone, Debug, Default)]
pub(super) struct Level {
    pub(super) nx: usize,
    pub(super) ny: usize,
    pub(super) periodic_x: bool,
    pub(super) periodic_y: bool,
    /// Padded row length `nx + 2`.
    pub(super) s: usize,
    pub(super) diag: Vec<f64>,
    pub(super) dinv: Vec<f64>,
    /// Coupling to the east neighbour; the west coupling of cell `k` is `ce[k − 1]` (the ghost
    /// column holds the periodic wrap, or 0).
    pub(super) ce: Vec<f64>,
    /// Coupling to the north neighbour; the south coupling of `k` is `cn[k − s]`.
    pub(super) cn: Vec<f64>,
    pub(super) x: Vec<f64>,
    pub(super) b: Vec<f64>,
    /// The first coarse correction while a W-cycle computes the second: allocated only on the
    /// levels a second correction is made on ([`Level::needs_t`]), empty elsewhere.
    pub(super) t: Vec<f64>,
}

impl Level {
    /// A zero level of `nx × ny` cells.
    pub(super) fn shape(nx: usize, ny: usize, periodic_x: bool, periodic_y: bool) -> Self {
        let mut l = Level::default();
        l.reshape(nx, ny, periodic_x, periodic_y);
        l
    }

    /// Reshape to `nx × ny` cells, every vector zero, reusing the storage when it is large
    /// enough (`t` is left to [`Level::size_t`]).
    pub(super) fn reshape(&mut self, nx: usize, ny: usize, periodic_x: bool, periodic_y: bool) {
        let m = (nx + 2) * (ny + 2);
        (self.nx, self.ny, self.s) = (nx, ny, nx + 2);
        (self.periodic_x, self.periodic_y) = (periodic_x, periodic_y);
        for v in [
            &mut self.diag,
            &mut self.dinv,
            &mut self.ce,
            &mut self.cn,
            &mut self.x,
            &mut self.b,
        ] {
            v.clear();
            v.resize(m, 0.0);
        }
    }

    /// Whether a cycle with `gamma` coarse corrections (2: W-cycle) on a hierarchy of `n`
    /// levels reads level `l`'s `t`: the second correction is made on levels 1..=[`W_LEVELS`]
    /// that are not the coarsest (module `cycle`).
    pub(super) fn needs_t(l: usize, n: usize, gamma: usize) -> bool {
        gamma >= 2 && (1..=W_LEVELS).contains(&l) && l + 1 < n
    }

    /// `t` sized for level `l` of `n` (zero where it is read, empty elsewhere: level 0's and
    /// the coarse levels' were never read), reusing its storage.
    pub(super) fn size_t(&mut self, l: usize, n: usize, gamma: usize) {
        let len = if Self::needs_t(l, n, gamma) {
            (self.nx + 2) * (self.ny + 2)
        } else {
            0
        };
        if self.t.len() != len {
            self.t.clear();
            self.t.resize(len, 0.0);
        }
    }

    /// Whether the level is below [`par::PAR_MIN`] cells, so its sweeps run on one thread.
    pub(super) fn is_serial(&self) -> bool {
        self.nx * self.ny < par::PAR_MIN
    }

    #[inline(always)]
    pub(super) fn p(&self, i: usize, j: usize) -> usize {
        (j + 1) * self.s + i + 1
    }

    /// Copy the coefficients of `a` (same shape) into the padded layout: row copies in
    /// parallel, one array at a time (they vectorise).
    pub(super) fn load(&mut self, a: Stencil5View<'_>) {
        let (nx, ny, s) = (self.nx, self.ny, self.s);
        let (px, py) = (a.periodic_x, a.periodic_y);
        let rows = s..(ny + 1) * s;
        par::rows(&mut self.ce[rows.clone()], s).for_each(|j, row| {
            let src = &a.east[j * nx..(j + 1) * nx];
            row[1..=nx].copy_from_slice(src);
            // The closed east side has no coupling; the west ghost holds the wrap coupling.
            if !px {
                row[nx] = 0.0;
            }
            row[0] = if px { src[nx - 1] } else { 0.0 };
        });
        par::rows(&mut self.cn[rows.clone()], s).for_each(|j, row| {
            if j + 1 < ny || py {
                row[1..=nx].copy_from_slice(&a.north[j * nx..(j + 1) * nx]);
            } else {
                row[1..=nx].fill(0.0);
            }
        });
        for i in 0..nx {
            self.cn[i + 1] = if py { a.north[(ny - 1) * nx + i] } else { 0.0 };
        }
        par::rows((&mut self.diag[rows.clone()], &mut self.dinv[rows]), s).for_each(
            |j, (d, di)| {
                let src = &a.diag[j * nx..(j + 1) * nx];
                d[1..=nx].copy_from_slice(src);
                for (di, d) in di[1..=nx].iter_mut().zip(src) {
                    *di = if *d > 0.0 { 1.0 / d } else { 0.0 };
                }
            },
        );
    }

    /// Whether [`load`](Self::load) of `a` would leave the matrix as it is: same shape and
    /// sides, and bit for bit the entries `load` keeps (a closed side's couplings are zero
    /// whatever `a` holds there). The coarse levels then are `a`'s too: coarsening reads only
    /// those entries.
    pub(super) fn holds(&self, a: Stencil5View<'_>) -> bool {
        let (nx, ny, s) = (self.nx, self.ny, self.s);
        if (nx, ny, self.periodic_x, self.periodic_y) != (a.nx, a.ny, a.periodic_x, a.periodic_y) {
            return false;
        }
        let same = |x: &[f64], y: &[f64]| x.iter().zip(y).all(|(x, y)| x.to_bits() == y.to_bits());
        let east = if a.periodic_x {
            nx
        } else {
            nx.saturating_sub(1)
        };
        (0..ny).all(|j| {
            let (p, r) = ((j + 1) * s + 1, j * nx);
            same(&self.diag[p..p + nx], &a.diag[r..r + nx])
                && same(&self.ce[p..p + east], &a.east[r..r + east])
                && ((j + 1 == ny && !a.periodic_y)
                    || same(&self.cn[p..p + nx], &a.north[r..r + nx]))
        })
    }

    /// Periodic ghosts of `x` (closed sides keep zero ghosts, multiplied by zero couplings).
    pub(super) fn fill_ghosts(&mut self) {
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

    /// `out[t] = (b − A x)[k0 + t]` for a run of cells of one row (ghosts filled), over slices (it
    /// vectorises).
    #[inline(always)]
    pub(super) fn residual_run(&self, k0: usize, out: &mut [f64]) {
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
