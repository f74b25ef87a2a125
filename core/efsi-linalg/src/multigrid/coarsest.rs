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
    pub(super) fn solve(&mut self, lv: &mut Level) {
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
