//! The coarsest level's exact solve: a dense Cholesky factor, with one unknown pinned when the
//! matrix is singular.

use super::level::Level;

/// Dense Cholesky solve of the coarsest level (one unknown pinned if the matrix is singular).
#[derive(Clone, Debug, Default)]
pub(super) struct Coarsest {
    m: usize,
    pub(super) l: Vec<f64>,
    pub(super) y: Vec<f64>,
    singular_pin: bool,
}

impl Coarsest {
    /// Room for the factor of a level of up to `cells` cells, so that factoring one never
    /// allocates.
    pub(super) fn reserve(&mut self, cells: usize) {
        let (l, y) = (cells * cells, cells);
        self.l.reserve(l.saturating_sub(self.l.len()));
        self.y.reserve(y.saturating_sub(self.y.len()));
    }

    pub(super) fn factor(&mut self, lv: &Level) {
        assert!(
            lv.uniform.is_none(),
            "multigrid: the coarsest level keeps its matrix in arrays"
        );
        if lv.is_3d() {
            self.assemble_3d(lv);
        } else {
            self.assemble_2d(lv);
        }
        self.cholesky();
    }

    /// The dense matrix of a two-dimensional level into `l`, one unknown pinned if singular.
    fn assemble_2d(&mut self, lv: &Level) {
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
        self.pin(singular);
    }

    /// The dense matrix of a three-dimensional level into `l`, one unknown pinned if singular.
    fn assemble_3d(&mut self, lv: &Level) {
        let (nx, ny, nz) = (lv.nx, lv.ny, lv.nz);
        let m = nx * ny * nz;
        self.m = m;
        self.l.clear();
        self.l.resize(m * m, 0.0);
        self.y.resize(m, 0.0);
        let (s, sp) = (lv.s, lv.sp);
        let mut singular = true;
        let a = &mut self.l;
        for c in 0..nz {
            for j in 0..ny {
                for i in 0..nx {
                    let k = (c * ny + j) * nx + i;
                    let p = lv.p3(i, j, c);
                    let off = lv.ce[p]
                        + lv.ce[p - 1]
                        + lv.cn[p]
                        + lv.cn[p - s]
                        + lv.ct[p]
                        + lv.ct[p - sp];
                    singular &= lv.diag[p] - off <= 1e-12 * lv.diag[p];
                    a[k * m + k] += lv.diag[p];
                    let at = |ii: usize, jj: usize, cc: usize| (cc * ny + jj) * nx + ii;
                    let nb = [
                        (lv.ce[p], at((i + 1) % nx, j, c)),
                        (lv.ce[p - 1], at((i + nx - 1) % nx, j, c)),
                        (lv.cn[p], at(i, (j + 1) % ny, c)),
                        (lv.cn[p - s], at(i, (j + ny - 1) % ny, c)),
                        (lv.ct[p], at(i, j, (c + 1) % nz)),
                        (lv.ct[p - sp], at(i, j, (c + nz - 1) % nz)),
                    ];
                    for (v, q) in nb {
                        if v != 0.0 {
                            a[k * m + q] -= v;
                        }
                    }
                }
            }
        }
        self.pin(singular);
    }

    /// Pin unknown 0 of a singular matrix (its row and column replaced by the identity's).
    fn pin(&mut self, singular: bool) {
        let (m, a) = (self.m, &mut self.l);
        if singular {
            for k in 0..m {
                a[k] = 0.0;
                a[k * m] = 0.0;
            }
            a[0] = 1.0;
        }
        self.singular_pin = singular;
    }

    /// Factor `l` in place.
    fn cholesky(&mut self) {
        let (m, a) = (self.m, &mut self.l);
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
    }
}

impl Coarsest {
    pub(super) fn solve(&mut self, lv: &mut Level) {
        let (m, nx, ny) = (self.m, lv.nx, lv.ny);
        let (l, y) = (&self.l, &mut self.y);
        // Padded index of unknown k ((i, j) on a two-dimensional level, (i, j, c) otherwise).
        let p = |k: usize| lv.p3(k % nx, (k / nx) % ny, k / (nx * ny));
        for k in 0..m {
            y[k] = lv.b[p(k)];
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
        for (k, y) in y.iter().enumerate() {
            let q = lv.p3(k % nx, (k / nx) % ny, k / (nx * ny));
            lv.x[q] = *y;
        }
    }
}
