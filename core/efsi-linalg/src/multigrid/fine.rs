//! The product of the matrix a multigrid was last set up for, from its finest level's padded
//! copy: a caller that sets the multigrid up from a borrowed matrix
//! ([`Multigrid::setup_view`]) keeps no copy of its own for conjugate gradient's products.

use super::Multigrid;
use crate::par;
use crate::pcg::LinearOperator;

/// `y = A x` for the matrix `A` of the last [`Multigrid::setup`] or
/// [`Multigrid::setup_view`] ([`Multigrid::fine_matrix`]).
///
/// The same bits as [`Stencil5::mul`](crate::Stencil5::mul) of that matrix: the same terms in
/// the same order (diagonal, east, west, north, south, then the periodic x-wrap), read from
/// the padded copy, whose entries are the matrix's (the couplings that cross a closed side,
/// which `mul` skips, are not read).
#[derive(Clone, Copy, Debug)]
pub struct FineMatrix<'a>(&'a Multigrid);

impl Multigrid {
    /// The matrix the multigrid was last set up for, as an operator (see [`FineMatrix`]).
    /// Applying it and the preconditioner at the same time from two threads panics, as two
    /// applications of the preconditioner do.
    pub fn fine_matrix(&self) -> FineMatrix<'_> {
        FineMatrix(self)
    }
}

impl FineMatrix<'_> {
    /// `y = A x` (rows in parallel; the same bits on any number of threads).
    pub fn mul(&self, x: &[f64], y: &mut [f64]) {
        let h = self.0.lock();
        let l = &h.levels[0];
        if l.is_3d() {
            mul_3d(l, x, y);
            return;
        }
        let (nx, ny, s) = (l.nx, l.ny, l.s);
        let (px, py) = (l.periodic_x, l.periodic_y);
        assert_eq!(
            x.len(),
            nx * ny,
            "multigrid matrix: vector length ≠ matrix size"
        );
        assert_eq!(
            y.len(),
            nx * ny,
            "multigrid matrix: vector length ≠ matrix size"
        );
        if nx == 0 || ny == 0 {
            return;
        }
        let (d, ce, cn) = (&l.diag[..], &l.ce[..], &l.cn[..]);
        par::rows(y, nx).for_each(|j, yr| {
            let r = j * nx;
            // Padded index of cell (0, j); row j's couplings are those of `Stencil5` row j.
            let p = (j + 1) * s + 1;
            let (xr, dr, er) = (&x[r..r + nx], &d[p..p + nx], &ce[p..p + nx]);
            for ((y, d), x) in yr.iter_mut().zip(dr).zip(xr) {
                *y = d * x;
            }
            for ((y, e), x) in yr[..nx - 1].iter_mut().zip(&er[..nx - 1]).zip(&xr[1..]) {
                *y -= e * x;
            }
            for ((y, e), x) in yr[1..].iter_mut().zip(&er[..nx - 1]).zip(&xr[..nx - 1]) {
                *y -= e * x;
            }
            // Row j's north couplings (row ny − 1's: the wrap, or zero unless periodic).
            let nr = &cn[p..p + nx];
            if j + 1 < ny {
                let xn = &x[r + nx..r + 2 * nx];
                for ((y, n), x) in yr.iter_mut().zip(nr).zip(xn) {
                    *y -= n * x;
                }
            } else if py {
                for ((y, n), x) in yr.iter_mut().zip(nr).zip(&x[..nx]) {
                    *y -= n * x;
                }
            }
            // Row j − 1's north couplings (for row 0 the ghost row: the wrap).
            let ns = &cn[p - s..p - s + nx];
            if j > 0 {
                let xs = &x[r - nx..r];
                for ((y, n), x) in yr.iter_mut().zip(ns).zip(xs) {
                    *y -= n * x;
                }
            } else if py {
                let t = (ny - 1) * nx;
                for ((y, n), x) in yr.iter_mut().zip(ns).zip(&x[t..t + nx]) {
                    *y -= n * x;
                }
            }
            if px {
                let c = er[nx - 1];
                yr[nx - 1] -= c * xr[0];
                yr[0] -= c * xr[nx - 1];
            }
        });
    }
}

impl LinearOperator for FineMatrix<'_> {
    fn apply(&mut self, x: &[f64], y: &mut [f64]) {
        self.mul(x, y);
    }
}

/// [`FineMatrix::mul`] of a three-dimensional level: the terms of
/// [`Stencil5::mul`](crate::Stencil5::mul) in its order (diagonal, east, west, north, south,
/// top, bottom; a periodic neighbour across the wrap, whose coupling the ghost entry holds),
/// so the same bits.
fn mul_3d(l: &super::level::Level, x: &[f64], y: &mut [f64]) {
    let (nx, ny, nz) = (l.nx, l.ny, l.nz);
    let plane = nx * ny;
    assert_eq!(
        x.len(),
        plane * nz,
        "multigrid matrix: vector length ≠ matrix size"
    );
    assert_eq!(
        y.len(),
        plane * nz,
        "multigrid matrix: vector length ≠ matrix size"
    );
    if plane == 0 {
        return;
    }
    let (px, py, pz) = (l.periodic_x, l.periodic_y, l.periodic_z);
    par::rows(y, nx).for_each(|r, yr| {
        let (j, c) = (r % ny, r / ny);
        let r0 = r * nx;
        let north = if j + 1 < ny {
            Some(r0 + nx)
        } else {
            py.then(|| r0 + nx - plane)
        };
        let south = if j > 0 {
            Some(r0 - nx)
        } else {
            py.then(|| r0 + plane - nx)
        };
        let top = if c + 1 < nz {
            Some(r0 + plane)
        } else {
            pz.then(|| r0 - (nz - 1) * plane)
        };
        let bottom = if c > 0 {
            Some(r0 - plane)
        } else {
            pz.then(|| r0 + (nz - 1) * plane)
        };
        // Term after term, each over the whole row: every entry sees the same operations in
        // the same order as a loop over the entries would apply them (so the same bits), and
        // each pass is a loop over slices without branches or bounds checks.
        let n = nx;
        let yr = &mut yr[..n];
        // The row's coefficients, cell i at index i + 1.
        let [ce, cw, cn, cs, ct, cb, d, _] = l.row(j, c).run(1, n);
        let xr = &x[r0..r0 + n];
        for i in 0..n {
            yr[i] = d[i] * xr[i];
        }
        let (xe, xw) = (&x[r0 + 1..r0 + n], &x[r0..r0 + n - 1]);
        for i in 0..n - 1 {
            yr[i] -= ce[i] * xe[i];
        }
        if px {
            yr[n - 1] -= ce[n - 1] * x[r0];
            yr[0] -= cw[0] * x[r0 + n - 1];
        }
        for i in 1..n {
            yr[i] -= cw[i] * xw[i - 1];
        }
        let faces = [(north, cn), (south, cs), (top, ct), (bottom, cb)];
        for (at, c) in faces {
            if let Some(o) = at {
                let xo = &x[o..o + n];
                for i in 0..n {
                    yr[i] -= c[i] * xo[i];
                }
            }
        }
    });
}
