//! One level of the hierarchy: its matrix in a padded layout (one ghost ring) with the work
//! vectors, loaded from a [`Stencil5`](crate::Stencil5), its periodic ghosts and its residual.
//!
//! A three-dimensional matrix with one coupling per axis — the same value across every face
//! normal to that axis, zero across a closed side — and the diagonal the sum of a cell's
//! couplings (the projection's matrix of a fluid of one density on a uniform grid) is held as
//! one padded row of each kind ([`Uniform`]) instead of five arrays of the level's size: every
//! kernel reads a row's coefficients through [`Level::row`], the same values either way, so
//! the same bits. The coarsest level, which its dense factor reads entry by entry, keeps the
//! arrays.

use super::W_LEVELS;
use crate::par;
use crate::stencil5::Stencil5View;

/// One level: the matrix in a padded layout (one ghost ring; on a three-dimensional level
/// also a ghost plane below and above), and the work vectors.
#[derive(Clone, Debug, Default)]
pub(super) struct Level {
    pub(super) nx: usize,
    pub(super) ny: usize,
    /// Cells along z (1 on a two-dimensional level, which has no ghost planes).
    pub(super) nz: usize,
    pub(super) periodic_x: bool,
    pub(super) periodic_y: bool,
    pub(super) periodic_z: bool,
    /// Padded row length `nx + 2`.
    pub(super) s: usize,
    /// Padded plane length `(nx + 2)(ny + 2)`.
    pub(super) sp: usize,
    /// Offset of plane 0: `sp` on a three-dimensional level (below it the ghost plane), 0 on a
    /// two-dimensional one.
    pub(super) zo: usize,
    pub(super) diag: Vec<f64>,
    pub(super) dinv: Vec<f64>,
    /// Coupling to the east neighbour; the west coupling of cell `k` is `ce[k − 1]` (the ghost
    /// column holds the periodic wrap, or 0).
    pub(super) ce: Vec<f64>,
    /// Coupling to the north neighbour; the south coupling of `k` is `cn[k − s]`.
    pub(super) cn: Vec<f64>,
    /// Coupling to the top neighbour; the bottom coupling of `k` is `ct[k − sp]` (empty on a
    /// two-dimensional level).
    pub(super) ct: Vec<f64>,
    pub(super) x: Vec<f64>,
    pub(super) b: Vec<f64>,
    /// The first coarse correction while a W-cycle computes the second: allocated only on the
    /// levels a second correction is made on ([`Level::needs_t`]), empty elsewhere.
    pub(super) t: Vec<f64>,
    /// A three-dimensional matrix of one coupling per axis (module docs): `diag`, `dinv`,
    /// `ce`, `cn` and `ct` are then empty.
    pub(super) uniform: Option<Uniform>,
    /// Whether the level keeps a uniform matrix in arrays too: the coarsest, whose dense
    /// factor reads them entry by entry (set by `Multigrid::setup_view` before loading).
    pub(super) keep_arrays: bool,
}

/// A three-dimensional matrix whose couplings along each axis are one value `c[a]` (zero across
/// a closed side, the wrap's across a periodic one) and whose diagonal is the sum of a cell's
/// six couplings, added as the projection assembles it (east, north, top, west, south,
/// bottom): one padded row of each coefficient (index 0 the west ghost, `i + 1` cell `i`).
#[derive(Clone, Debug, Default)]
pub(super) struct Uniform {
    c: [f64; 3],
    /// `s + 1` values: a zero, then a row's east couplings (the west ghost's the wrap's or 0),
    /// so that the west couplings are the same values one to the left.
    east: Vec<f64>,
    /// A row of the y coupling, of the z coupling and of zeros.
    cy: Vec<f64>,
    cz: Vec<f64>,
    zero: Vec<f64>,
    /// The diagonal and its inverse of a row for each of the 16 ways its cells are coupled
    /// north, south, top and bottom ([`Level::class`]), `s` values each.
    diag: Vec<f64>,
    dinv: Vec<f64>,
}

/// The coefficients of one padded row of cells of a three-dimensional level, `s` values each:
/// index 0 the west ghost, `i + 1` cell `i` ([`Level::row`]).
pub(super) struct Row<'a> {
    pub(super) ce: &'a [f64],
    pub(super) cw: &'a [f64],
    pub(super) cn: &'a [f64],
    pub(super) cs: &'a [f64],
    pub(super) ct: &'a [f64],
    pub(super) cb: &'a [f64],
    pub(super) diag: &'a [f64],
    pub(super) dinv: &'a [f64],
}

impl<'a> Row<'a> {
    /// The `n` coefficients of each kind from index `t0` of the row:
    /// `[ce, cw, cn, cs, ct, cb, diag, dinv]`.
    #[inline(always)]
    pub(super) fn run(&self, t0: usize, n: usize) -> [&'a [f64]; 8] {
        [
            self.ce, self.cw, self.cn, self.cs, self.ct, self.cb, self.diag, self.dinv,
        ]
        .map(|v| &v[t0..t0 + n])
    }
}

impl Uniform {
    /// The couplings `[c_x, c_y, c_z]` of `a` if it is such a matrix (module docs), bit for bit:
    /// every coupling [`Level::load`] keeps equal to its axis's first, and every diagonal
    /// entry the sum of its cell's couplings in the assembly's order.
    fn of(a: Stencil5View<'_>) -> Option<[f64; 3]> {
        let (nx, ny, nz) = (a.nx, a.ny, a.nz);
        let (px, py, pz) = (a.periodic_x, a.periodic_y, a.periodic_z);
        let plane = nx * ny;
        if plane * nz == 0 || a.top.len() != plane * nz {
            return None;
        }
        let mut c: [Option<u64>; 3] = [None; 3];
        let mut same = |ax: usize, v: &[f64]| {
            v.iter().all(|x| {
                let b = x.to_bits();
                *c[ax].get_or_insert(b) == b
            })
        };
        for r in 0..ny * nz {
            let (j, k) = (r % ny, r / ny);
            let o = r * nx;
            let east = if px { nx } else { nx - 1 };
            if !same(0, &a.east[o..o + east])
                || ((j + 1 < ny || py) && !same(1, &a.north[o..o + nx]))
                || ((k + 1 < nz || pz) && !same(2, &a.top[o..o + nx]))
            {
                return None;
            }
        }
        let c = c.map(|b| b.map_or(0.0, f64::from_bits));
        let (cx, cy, cz) = (c[0], c[1], c[2]);
        let on = |yes: bool, v: f64| if yes { v } else { 0.0 };
        let ok = (0..ny * nz).all(|r| {
            let (j, k) = (r % ny, r / ny);
            let (n, s) = (on(j + 1 < ny || py, cy), on(j > 0 || py, cy));
            let (t, b) = (on(k + 1 < nz || pz, cz), on(k > 0 || pz, cz));
            let d = &a.diag[r * nx..(r + 1) * nx];
            (0..nx).all(|i| {
                let (e, w) = (on(i + 1 < nx || px, cx), on(i > 0 || px, cx));
                (e + n + t + w + s + b).to_bits() == d[i].to_bits()
            })
        });
        ok.then_some(c)
    }

    /// The rows of the couplings `c` for rows of `nx` cells (`s = nx + 2`), `px` whether x wraps.
    fn new(c: [f64; 3], nx: usize, px: bool) -> Self {
        let s = nx + 2;
        let on = |yes: bool, v: f64| if yes { v } else { 0.0 };
        let mut east = vec![0.0; s + 1];
        east[1] = on(px, c[0]);
        for i in 0..nx {
            east[i + 2] = on(i + 1 < nx || px, c[0]);
        }
        let (mut diag, mut dinv) = (vec![0.0; 16 * s], vec![0.0; 16 * s]);
        for class in 0..16 {
            let (n, so) = (on(class & 1 != 0, c[1]), on(class & 2 != 0, c[1]));
            let (t, b) = (on(class & 4 != 0, c[2]), on(class & 8 != 0, c[2]));
            for i in 0..nx {
                let (e, w) = (east[i + 2], east[i + 1]);
                let d = e + n + t + w + so + b;
                diag[class * s + i + 1] = d;
                dinv[class * s + i + 1] = if d > 0.0 { 1.0 / d } else { 0.0 };
            }
        }
        Uniform {
            c,
            east,
            cy: vec![c[1]; s],
            cz: vec![c[2]; s],
            zero: vec![0.0; s],
            diag,
            dinv,
        }
    }
}

impl Level {
    /// A zero level of `nx × ny × nz` cells (`nz = 1`: two-dimensional).
    pub(super) fn shape(n: [usize; 3], periodic: [bool; 3]) -> Self {
        let mut l = Level::default();
        l.reshape(n, periodic);
        l
    }

    /// Whether the level is three-dimensional.
    #[inline(always)]
    pub(super) fn is_3d(&self) -> bool {
        self.nz > 1
    }

    /// Length of the padded vectors.
    pub(super) fn padded_len(&self) -> usize {
        let planes = if self.is_3d() { self.nz + 2 } else { 1 };
        self.sp * planes
    }

    /// Reshape to `nx × ny × nz` cells, every vector zero, reusing the storage when it is large
    /// enough (`t` is left to [`Level::size_t`]).
    pub(super) fn reshape(&mut self, [nx, ny, nz]: [usize; 3], periodic: [bool; 3]) {
        (self.nx, self.ny, self.nz, self.s) = (nx, ny, nz, nx + 2);
        self.sp = (nx + 2) * (ny + 2);
        self.zo = if nz > 1 { self.sp } else { 0 };
        (self.periodic_x, self.periodic_y) = (periodic[0], periodic[1]);
        self.periodic_z = nz > 1 && periodic[2];
        let m = self.padded_len();
        self.ct.clear();
        self.uniform = None;
        // A three-dimensional level's matrix is sized when it is loaded (arrays, or none).
        let coefficients = if nz > 1 { 0 } else { m };
        for v in [&mut self.diag, &mut self.dinv, &mut self.ce, &mut self.cn] {
            v.clear();
            v.resize(coefficients, 0.0);
        }
        for v in [&mut self.x, &mut self.b] {
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
            self.padded_len()
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
        self.nx * self.ny * self.nz < par::PAR_MIN
    }

    #[inline(always)]
    pub(super) fn p(&self, i: usize, j: usize) -> usize {
        (j + 1) * self.s + i + 1
    }

    /// Padded index of cell `(i, j, c)` (`c = 0` on a two-dimensional level: [`p`](Self::p)).
    #[inline(always)]
    pub(super) fn p3(&self, i: usize, j: usize, c: usize) -> usize {
        self.zo + c * self.sp + (j + 1) * self.s + i + 1
    }

    /// The span of the padded vectors from the first row of plane 0 to the last row of the last
    /// plane; split into rows of `s`, row `r` is cell row `j = r mod (ny + 2)` of plane
    /// `c = r div (ny + 2)` when `j < ny` (the others are ghost rows). On a two-dimensional
    /// level it is the `ny` rows of cells.
    pub(super) fn rows_span(&self) -> std::ops::Range<usize> {
        let start = self.zo + self.s;
        start..start + ((self.nz - 1) * (self.ny + 2) + self.ny) * self.s
    }

    /// The cell row `(j, c)` of row `r` of [`rows_span`](Self::rows_span), `None` for a
    /// ghost row.
    #[inline(always)]
    pub(super) fn row_jc(&self, r: usize) -> Option<(usize, usize)> {
        let (j, c) = (r % (self.ny + 2), r / (self.ny + 2));
        (j < self.ny).then_some((j, c))
    }

    /// Copy the coefficients of `a` (same shape) into the padded layout: row copies in
    /// parallel, one array at a time (they vectorise).
    pub(super) fn load(&mut self, a: Stencil5View<'_>) {
        if self.is_3d() {
            self.load_3d(a);
            return;
        }
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
        if (nx, ny, self.periodic_x, self.periodic_y) != (a.nx, a.ny, a.periodic_x, a.periodic_y)
            || (self.nz, self.periodic_z) != (a.nz, a.periodic_z)
        {
            return false;
        }
        if self.is_3d() {
            return self.holds_3d(a);
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
        if self.is_3d() {
            self.fill_ghosts_3d();
            return;
        }
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

/// The three-dimensional arms: plane by plane, a line of cells along x the unit of work.
impl Level {
    /// [`load`](Self::load) of a three-dimensional matrix: every ghost coupling holds the
    /// periodic wrap's coupling or 0, a closed side's coupling is 0.
    fn load_3d(&mut self, a: Stencil5View<'_>) {
        let (nx, ny, nz) = (self.nx, self.ny, self.nz);
        let (px, py, pz) = (a.periodic_x, a.periodic_y, a.periodic_z);
        let plane = nx * ny;
        let uniform = (!self.keep_arrays).then(|| Uniform::of(a)).flatten();
        let m = if uniform.is_some() {
            0
        } else {
            self.padded_len()
        };
        for v in [
            &mut self.ce,
            &mut self.cn,
            &mut self.ct,
            &mut self.diag,
            &mut self.dinv,
        ] {
            v.clear();
            v.resize(m, 0.0);
            if m == 0 {
                v.shrink_to_fit();
            }
        }
        self.uniform = uniform.map(|c| Uniform::new(c, nx, px));
        if self.uniform.is_some() {
            return;
        }
        for c in 0..nz {
            for j in 0..ny {
                let r = (c * ny + j) * nx;
                let p = self.p3(0, j, c);
                let src = &a.east[r..r + nx];
                self.ce[p..p + nx].copy_from_slice(src);
                if !px {
                    self.ce[p + nx - 1] = 0.0;
                } else {
                    self.ce[p - 1] = src[nx - 1];
                }
                if j + 1 < ny || py {
                    self.cn[p..p + nx].copy_from_slice(&a.north[r..r + nx]);
                }
                if j == 0 && py {
                    let t = r + (ny - 1) * nx;
                    self.cn[p - self.s..p - self.s + nx].copy_from_slice(&a.north[t..t + nx]);
                }
                if c + 1 < nz || pz {
                    self.ct[p..p + nx].copy_from_slice(&a.top[r..r + nx]);
                }
                if c == 0 && pz {
                    let t = r + (nz - 1) * plane;
                    self.ct[p - self.sp..p - self.sp + nx].copy_from_slice(&a.top[t..t + nx]);
                }
                self.diag[p..p + nx].copy_from_slice(&a.diag[r..r + nx]);
                for (di, d) in self.dinv[p..p + nx].iter_mut().zip(&a.diag[r..r + nx]) {
                    *di = if *d > 0.0 { 1.0 / d } else { 0.0 };
                }
            }
        }
    }

    /// [`holds`](Self::holds) of a three-dimensional matrix of the level's shape.
    fn holds_3d(&self, a: Stencil5View<'_>) -> bool {
        if let Some(u) = &self.uniform {
            let bits = |c: [f64; 3]| c.map(f64::to_bits);
            return Uniform::of(a).is_some_and(|c| bits(c) == bits(u.c));
        }
        let (nx, ny, nz) = (self.nx, self.ny, self.nz);
        let same = |x: &[f64], y: &[f64]| x.iter().zip(y).all(|(x, y)| x.to_bits() == y.to_bits());
        let east = if a.periodic_x {
            nx
        } else {
            nx.saturating_sub(1)
        };
        (0..nz).all(|c| {
            (0..ny).all(|j| {
                let (p, r) = (self.p3(0, j, c), (c * ny + j) * nx);
                same(&self.diag[p..p + nx], &a.diag[r..r + nx])
                    && same(&self.ce[p..p + east], &a.east[r..r + east])
                    && ((j + 1 == ny && !a.periodic_y)
                        || same(&self.cn[p..p + nx], &a.north[r..r + nx]))
                    && ((c + 1 == nz && !a.periodic_z)
                        || same(&self.ct[p..p + nx], &a.top[r..r + nx]))
            })
        })
    }

    /// [`fill_ghosts`](Self::fill_ghosts) of a three-dimensional level: the x ghosts of every
    /// row, then the y ghost rows of every plane, then the z ghost planes (cells only: the
    /// seven-point stencil reads no edge or corner ghost).
    fn fill_ghosts_3d(&mut self) {
        let (nx, ny, nz, s, sp) = (self.nx, self.ny, self.nz, self.s, self.sp);
        if self.periodic_x {
            for c in 0..nz {
                for j in 0..ny {
                    let p = self.p3(0, j, c);
                    self.x[p - 1] = self.x[p + nx - 1];
                    self.x[p + nx] = self.x[p];
                }
            }
        }
        if self.periodic_y {
            for c in 0..nz {
                let (bot, top) = (self.p3(0, 0, c), self.p3(0, ny - 1, c));
                self.x.copy_within(top..top + nx, bot - s);
                self.x.copy_within(bot..bot + nx, top + s);
            }
        }
        if self.periodic_z {
            for j in 0..ny {
                let (bot, top) = (self.p3(0, j, 0), self.p3(0, j, nz - 1));
                self.x.copy_within(top..top + nx, bot - sp);
                self.x.copy_within(bot..bot + nx, top + sp);
            }
        }
    }

    /// [`residual_run`](Self::residual_run) on a three-dimensional level (the run inside one row).
    #[inline(always)]
    pub(super) fn residual_run_3d(&self, k0: usize, out: &mut [f64]) {
        let (n, s, sp) = (out.len(), self.s, self.sp);
        // The run's row (j, c) and its place in the padded row.
        let q = k0 - self.zo;
        let (c, j, t0) = (q / sp, (q % sp) / s - 1, q % s);
        let row = self.row(j, c);
        let x = &self.x[k0 - sp..k0 + sp + n];
        let (xc, xe, xw) = (
            &x[sp..sp + n],
            &x[sp + 1..sp + 1 + n],
            &x[sp - 1..sp - 1 + n],
        );
        let (xn, xs) = (&x[sp + s..sp + s + n], &x[sp - s..sp - s + n]);
        let (xt, xb) = (&x[2 * sp..2 * sp + n], &x[..n]);
        let [ce, cw, cn, cs, ct, cb, d, _] = row.run(t0, n);
        let b = &self.b[k0..k0 + n];
        for t in 0..n {
            out[t] = b[t] - d[t] * xc[t]
                + ce[t] * xe[t]
                + cw[t] * xw[t]
                + cn[t] * xn[t]
                + cs[t] * xs[t]
                + ct[t] * xt[t]
                + cb[t] * xb[t];
        }
    }

    /// Which of the north, south, top and bottom couplings of the cells of row `(j, c)` are
    /// not across a closed side (bits 0–3).
    #[inline(always)]
    fn class(&self, j: usize, c: usize) -> usize {
        let (py, pz) = (self.periodic_y, self.periodic_z);
        usize::from(j + 1 < self.ny || py)
            | usize::from(j > 0 || py) << 1
            | usize::from(c + 1 < self.nz || pz) << 2
            | usize::from(c > 0 || pz) << 3
    }

    /// The coefficients of the padded row of cells `(j, c)` of a three-dimensional level
    /// ([`Row`]), from the arrays or the [`Uniform`] rows: the same values.
    #[inline(always)]
    pub(super) fn row(&self, j: usize, c: usize) -> Row<'_> {
        let (s, sp) = (self.s, self.sp);
        let Some(u) = &self.uniform else {
            let q = self.p3(0, j, c) - 1;
            return Row {
                ce: &self.ce[q..q + s],
                cw: &self.ce[q - 1..q - 1 + s],
                cn: &self.cn[q..q + s],
                cs: &self.cn[q - s..q],
                ct: &self.ct[q..q + s],
                cb: &self.ct[q - sp..q - sp + s],
                diag: &self.diag[q..q + s],
                dinv: &self.dinv[q..q + s],
            };
        };
        let class = self.class(j, c);
        let (y, z, zero) = (&u.cy[..s], &u.cz[..s], &u.zero[..s]);
        let k = class * s;
        Row {
            ce: &u.east[1..=s],
            cw: &u.east[..s],
            cn: if class & 1 != 0 { y } else { zero },
            cs: if class & 2 != 0 { y } else { zero },
            ct: if class & 4 != 0 { z } else { zero },
            cb: if class & 8 != 0 { z } else { zero },
            diag: &u.diag[k..k + s],
            dinv: &u.dinv[k..k + s],
        }
    }
}
