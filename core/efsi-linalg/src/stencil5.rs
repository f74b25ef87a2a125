//! Symmetric five-point matrices on the cell grid (seven-point on a three-dimensional grid) and
//! their incomplete-Cholesky factor.
//!
//! Unknowns are the cells, numbered `k = (c·ny + j)·nx + i` (`c` the plane along z, 0 on a
//! two-dimensional grid). The matrix is stored by its couplings:
//! `A x |_k = d_k x_k − e_k x_E − e_W x_W − n_k x_N − n_S x_S − t_k x_T − t_B x_B`, with
//! `e_k ≥ 0` the coupling of cell k to its east (+x) neighbour, `n_k ≥ 0` to its north (+y) and
//! `t_k ≥ 0` to its top (+z) neighbour (an M-matrix, as every diffusion operator here is); a
//! two-dimensional matrix (`nz = 1`) has no top couplings. Periodic directions wrap: the east
//! neighbour of the last column is the first column.
//!
//! [`IncompleteCholesky`] is IC(0) with the sparsity of `A` (Meijerink & van der Vorst 1977),
//! in its diagonal form `M = (D̃ + L) D̃⁻¹ (D̃ + Lᵀ)` where `L` is the strictly lower part of `A`
//! and `D̃_k = d_k − e_W²/D̃_W − n_S²/D̃_S` — the seed's "incomplete Cholesky (LDLᵀ)". The
//! periodic wrap couplings are left out of the factor (it stays SPD since dropping
//! off-diagonals of a diagonally dominant M-matrix keeps it so); CG corrects for them.

use super::pcg::{LinearOperator, Preconditioner};

/// A symmetric five-point matrix on an `nx × ny` cell grid, or seven-point on an
/// `nx × ny × nz` one ([`Stencil5::new_3d`]).
#[derive(Clone, Debug)]
pub struct Stencil5 {
    /// Cells along x.
    pub nx: usize,
    /// Cells along y.
    pub ny: usize,
    /// Cells along z (1: a two-dimensional matrix, whose `top` is empty).
    pub nz: usize,
    /// Whether x wraps around.
    pub periodic_x: bool,
    /// Whether y wraps around.
    pub periodic_y: bool,
    /// Whether z wraps around (false on a two-dimensional matrix).
    pub periodic_z: bool,
    /// Diagonal `d_k`.
    pub diag: Vec<f64>,
    /// Coupling to the east neighbour `e_k` (≥ 0; 0 on a closed east boundary).
    pub east: Vec<f64>,
    /// Coupling to the north neighbour `n_k` (≥ 0; 0 on a closed north boundary).
    pub north: Vec<f64>,
    /// Coupling to the top neighbour `t_k` (≥ 0; 0 on a closed top boundary; empty when
    /// `nz = 1`).
    pub top: Vec<f64>,
}

/// A [`Stencil5`] whose arrays are borrowed (from a work pool, say): what
/// [`Multigrid::setup_view`](crate::Multigrid::setup_view) reads, so that a caller whose matrix
/// the multigrid keeps need not keep its own copy.
#[derive(Clone, Copy, Debug)]
pub struct Stencil5View<'a> {
    /// Cells along x.
    pub nx: usize,
    /// Cells along y.
    pub ny: usize,
    /// Cells along z (1 on a two-dimensional matrix).
    pub nz: usize,
    /// Whether x wraps around.
    pub periodic_x: bool,
    /// Whether y wraps around.
    pub periodic_y: bool,
    /// Whether z wraps around.
    pub periodic_z: bool,
    /// Diagonal `d_k` (`nx·ny·nz` values).
    pub diag: &'a [f64],
    /// Coupling to the east neighbour `e_k`.
    pub east: &'a [f64],
    /// Coupling to the north neighbour `n_k`.
    pub north: &'a [f64],
    /// Coupling to the top neighbour `t_k` (empty when `nz = 1`).
    pub top: &'a [f64],
}

impl Stencil5View<'_> {
    /// The coupling of cell `k` (in column `i`) to its west neighbour: the east coupling of
    /// the cell to its west, across the periodic wrap in the first column, 0 at a closed side.
    #[inline(always)]
    pub fn west(&self, k: usize, i: usize) -> f64 {
        if i > 0 {
            self.east[k - 1]
        } else if self.periodic_x {
            self.east[k + self.nx - 1]
        } else {
            0.0
        }
    }

    /// The coupling of cell `k` (in row `j`) to its south neighbour (as [`west`](Self::west)).
    #[inline(always)]
    pub fn south(&self, k: usize, j: usize) -> f64 {
        if j > 0 {
            self.north[k - self.nx]
        } else if self.periodic_y {
            self.north[k + (self.ny - 1) * self.nx]
        } else {
            0.0
        }
    }

    /// The coupling of cell `k` (in plane `c`) to its bottom neighbour (as
    /// [`west`](Self::west)); 0 on a two-dimensional matrix.
    #[inline(always)]
    pub fn bottom(&self, k: usize, c: usize) -> f64 {
        let plane = self.nx * self.ny;
        if self.nz <= 1 {
            0.0
        } else if c > 0 {
            self.top[k - plane]
        } else if self.periodic_z {
            self.top[k + (self.nz - 1) * plane]
        } else {
            0.0
        }
    }

    /// Whether the matrix is three-dimensional (`nz > 1`).
    #[inline(always)]
    pub fn is_3d(&self) -> bool {
        self.nz > 1
    }
}

impl Stencil5 {
    /// The matrix as a [`Stencil5View`].
    pub fn view(&self) -> Stencil5View<'_> {
        Stencil5View {
            nx: self.nx,
            ny: self.ny,
            nz: self.nz,
            periodic_x: self.periodic_x,
            periodic_y: self.periodic_y,
            periodic_z: self.periodic_z,
            diag: &self.diag,
            east: &self.east,
            north: &self.north,
            top: &self.top,
        }
    }

    /// A zero two-dimensional matrix of the given shape.
    pub fn new(nx: usize, ny: usize, periodic_x: bool, periodic_y: bool) -> Self {
        let n = nx * ny;
        Stencil5 {
            nx,
            ny,
            nz: 1,
            periodic_x,
            periodic_y,
            periodic_z: false,
            diag: vec![0.0; n],
            east: vec![0.0; n],
            north: vec![0.0; n],
            top: Vec::new(),
        }
    }

    /// A zero seven-point matrix on `nx × ny × nz` cells, `periodic` per axis (x, y, z).
    /// With `nz = 1` it is the two-dimensional matrix of [`Stencil5::new`].
    pub fn new_3d(nx: usize, ny: usize, nz: usize, periodic: [bool; 3]) -> Self {
        let mut a = Stencil5::new(0, 0, false, false);
        a.reshape_3d(nx, ny, nz, periodic);
        a
    }

    /// Reshape to `nx × ny` (two-dimensional), every entry zero, reusing the storage when it is
    /// large enough.
    pub fn reshape(&mut self, nx: usize, ny: usize, periodic_x: bool, periodic_y: bool) {
        self.reshape_3d(nx, ny, 1, [periodic_x, periodic_y, false]);
    }

    /// Reshape to `nx × ny × nz`, every entry zero, reusing the storage when it is large
    /// enough (`nz = 1`: two-dimensional, `top` empty and z not periodic).
    pub fn reshape_3d(&mut self, nx: usize, ny: usize, nz: usize, periodic: [bool; 3]) {
        let n = nx * ny * nz;
        (self.nx, self.ny, self.nz) = (nx, ny, nz);
        (self.periodic_x, self.periodic_y) = (periodic[0], periodic[1]);
        self.periodic_z = nz > 1 && periodic[2];
        for v in [&mut self.diag, &mut self.east, &mut self.north] {
            v.clear();
            v.resize(n, 0.0);
        }
        self.top.clear();
        if nz > 1 {
            self.top.resize(n, 0.0);
        }
    }

    /// Whether the matrix is three-dimensional (`nz > 1`).
    pub fn is_3d(&self) -> bool {
        self.nz > 1
    }

    /// The principal submatrix of the rectangle of `nx × ny` cells whose first cell is
    /// `(i0, j0)`, into `out` (reshaped, its storage reused): the same rows, diagonal included,
    /// without the couplings to cells outside — the matrix of the equations inside with the
    /// unknowns outside held at zero. A direction the rectangle spans whole keeps its periodic
    /// wrap. Two-dimensional matrices only.
    pub fn window_into(
        &self,
        (i0, j0): (usize, usize),
        (nx, ny): (usize, usize),
        out: &mut Stencil5,
    ) {
        assert!(!self.is_3d(), "window_into: a two-dimensional matrix only");
        assert!(
            i0 + nx <= self.nx && j0 + ny <= self.ny,
            "window {nx} × {ny} at ({i0}, {j0}) outside the {} × {} matrix",
            self.nx,
            self.ny
        );
        let px = self.periodic_x && nx == self.nx;
        let py = self.periodic_y && ny == self.ny;
        out.reshape(nx, ny, px, py);
        for j in 0..ny {
            let (src, dst) = ((j0 + j) * self.nx + i0, j * nx);
            out.diag[dst..dst + nx].copy_from_slice(&self.diag[src..src + nx]);
            out.east[dst..dst + nx].copy_from_slice(&self.east[src..src + nx]);
            if !px && nx > 0 {
                out.east[dst + nx - 1] = 0.0;
            }
            if j + 1 < ny || py {
                out.north[dst..dst + nx].copy_from_slice(&self.north[src..src + nx]);
            }
        }
    }

    /// The coupling of cell `k` (in column `i`) to its west neighbour: the east coupling of
    /// the cell to its west, across the periodic wrap in the first column, 0 at a closed side.
    #[inline(always)]
    pub fn west(&self, k: usize, i: usize) -> f64 {
        self.view().west(k, i)
    }

    /// The coupling of cell `k` (in row `j`) to its south neighbour (as [`west`](Self::west)).
    #[inline(always)]
    pub fn south(&self, k: usize, j: usize) -> f64 {
        self.view().south(k, j)
    }

    /// The coupling of cell `k` (in plane `c`) to its bottom neighbour (as
    /// [`west`](Self::west)); 0 on a two-dimensional matrix.
    #[inline(always)]
    pub fn bottom(&self, k: usize, c: usize) -> f64 {
        self.view().bottom(k, c)
    }

    /// Number of unknowns.
    pub fn len(&self) -> usize {
        self.diag.len()
    }

    /// Whether there are no unknowns.
    pub fn is_empty(&self) -> bool {
        self.diag.is_empty()
    }

    /// `y = A x` (in parallel over rows for large grids; the same bits on any thread count).
    pub fn mul(&self, x: &[f64], y: &mut [f64]) {
        if self.is_3d() {
            mul_3d(self.view(), x, y);
            return;
        }
        let (nx, ny) = (self.nx, self.ny);
        let (d, e, n) = (&self.diag[..], &self.east[..], &self.north[..]);
        let (px, py) = (self.periodic_x, self.periodic_y);
        assert_eq!(x.len(), nx * ny);
        assert_eq!(y.len(), nx * ny);
        // Row by row in passes over contiguous slices (they vectorise): diagonal, east, west,
        // north, south, then the periodic wraps.
        super::par::rows(y, nx).for_each(|j, yr| {
            let r = j * nx;
            let (xr, dr, er) = (&x[r..r + nx], &d[r..r + nx], &e[r..r + nx]);
            for ((y, d), x) in yr.iter_mut().zip(dr).zip(xr) {
                *y = d * x;
            }
            for ((y, e), x) in yr[..nx - 1].iter_mut().zip(&er[..nx - 1]).zip(&xr[1..]) {
                *y -= e * x;
            }
            for ((y, e), x) in yr[1..].iter_mut().zip(&er[..nx - 1]).zip(&xr[..nx - 1]) {
                *y -= e * x;
            }
            if j + 1 < ny {
                let xn = &x[r + nx..r + 2 * nx];
                for ((y, n), x) in yr.iter_mut().zip(&n[r..r + nx]).zip(xn) {
                    *y -= n * x;
                }
            } else if py {
                for ((y, n), x) in yr.iter_mut().zip(&n[r..r + nx]).zip(&x[..nx]) {
                    *y -= n * x;
                }
            }
            if j > 0 {
                let (xs, ns) = (&x[r - nx..r], &n[r - nx..r]);
                for ((y, n), x) in yr.iter_mut().zip(ns).zip(xs) {
                    *y -= n * x;
                }
            } else if py {
                let t = (ny - 1) * nx;
                for ((y, n), x) in yr.iter_mut().zip(&n[t..t + nx]).zip(&x[t..t + nx]) {
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

/// `y = A x` for a three-dimensional matrix: rows (a line of cells along x, one per `(j, c)`)
/// in parallel, each cell's terms in the order diagonal, east, west, north, south, top,
/// bottom, a periodic neighbour read across the wrap.
pub(crate) fn mul_3d(a: Stencil5View<'_>, x: &[f64], y: &mut [f64]) {
    let (nx, ny, nz) = (a.nx, a.ny, a.nz);
    let plane = nx * ny;
    assert_eq!(x.len(), plane * nz);
    assert_eq!(y.len(), plane * nz);
    if plane == 0 {
        return;
    }
    super::par::rows(y, nx).for_each(|r, yr| {
        let (j, c) = (r % ny, r / ny);
        let r0 = r * nx;
        // The row's north/south/top/bottom neighbour rows, where they exist.
        let north = if j + 1 < ny {
            Some(r0 + nx)
        } else if a.periodic_y {
            Some(r0 + nx - plane)
        } else {
            None
        };
        let south = if j > 0 {
            Some(r0 - nx)
        } else if a.periodic_y {
            Some(r0 + plane - nx)
        } else {
            None
        };
        let top = if c + 1 < nz {
            Some(r0 + plane)
        } else if a.periodic_z {
            Some(r0 - (nz - 1) * plane)
        } else {
            None
        };
        let bottom = if c > 0 {
            Some(r0 - plane)
        } else if a.periodic_z {
            Some(r0 + (nz - 1) * plane)
        } else {
            None
        };
        for (i, y) in yr.iter_mut().enumerate() {
            let k = r0 + i;
            let mut v = a.diag[k] * x[k];
            if i + 1 < nx {
                v -= a.east[k] * x[k + 1];
            } else if a.periodic_x {
                v -= a.east[k] * x[r0];
            }
            if i > 0 {
                v -= a.east[k - 1] * x[k - 1];
            } else if a.periodic_x {
                v -= a.east[r0 + nx - 1] * x[r0 + nx - 1];
            }
            if let Some(n) = north {
                v -= a.north[k] * x[n + i];
            }
            if let Some(s) = south {
                v -= a.north[s + i] * x[s + i];
            }
            if let Some(t) = top {
                v -= a.top[k] * x[t + i];
            }
            if let Some(b) = bottom {
                v -= a.top[b + i] * x[b + i];
            }
            *y = v;
        }
    });
}

impl LinearOperator for Stencil5 {
    fn apply(&mut self, x: &[f64], y: &mut [f64]) {
        self.mul(x, y);
    }
}

/// IC(0) factor of a [`Stencil5`] (periodic wrap couplings omitted).
#[derive(Clone, Debug, Default)]
pub struct IncompleteCholesky {
    nx: usize,
    dinv: Vec<f64>,
    // Couplings of the factored (non-wrapping) part, each also indexed from the other cell so
    // that the sweeps need no boundary tests: `west[k] = east[k−1]` (0 on the first column),
    // `south[k] = north[k−nx]` (0 on the first row), `east`/`north` 0 on the last column/row.
    east: Vec<f64>,
    north: Vec<f64>,
    west: Vec<f64>,
    south: Vec<f64>,
}

impl IncompleteCholesky {
    /// An empty factor; call [`IncompleteCholesky::factor`].
    pub fn new() -> Self {
        Self::default()
    }

    /// Factor `a` (reusing storage); a two-dimensional matrix only.
    pub fn factor(&mut self, a: &Stencil5) {
        assert!(
            !a.is_3d(),
            "incomplete Cholesky: a two-dimensional matrix only"
        );
        let (nx, ny) = (a.nx, a.ny);
        let n = a.len();
        self.nx = nx;
        self.dinv.resize(n, 0.0);
        self.east.resize(n, 0.0);
        self.north.resize(n, 0.0);
        self.west.resize(n, 0.0);
        self.south.resize(n, 0.0);
        let mut d = vec![0.0; 0];
        std::mem::swap(&mut d, &mut self.dinv);
        for j in 0..ny {
            for i in 0..nx {
                let k = j * nx + i;
                self.east[k] = if i + 1 < nx { a.east[k] } else { 0.0 };
                self.north[k] = if j + 1 < ny { a.north[k] } else { 0.0 };
                self.west[k] = if i > 0 { a.east[k - 1] } else { 0.0 };
                self.south[k] = if j > 0 { a.north[k - nx] } else { 0.0 };
                let mut dk = a.diag[k];
                if i > 0 {
                    let e = a.east[k - 1];
                    dk -= e * e * d[k - 1];
                }
                if j > 0 {
                    let s = a.north[k - nx];
                    dk -= s * s * d[k - nx];
                }
                // Guard against a non-positive pivot (cannot happen for a diagonally dominant
                // M-matrix, but the preconditioner must stay SPD whatever the input).
                let dk = if dk > 1e-14 * a.diag[k] {
                    dk
                } else {
                    a.diag[k].max(f64::MIN_POSITIVE)
                };
                d[k] = 1.0 / dk;
            }
        }
        self.dinv = d;
    }
}

impl Preconditioner for IncompleteCholesky {
    fn apply(&self, r: &[f64], z: &mut [f64]) {
        let nx = self.nx;
        let n = r.len();
        let (dinv, w, s, e, no) = (
            &self.dinv[..],
            &self.west[..],
            &self.south[..],
            &self.east[..],
            &self.north[..],
        );
        // Forward: (D̃ + L) w = r.
        z[0] = r[0] * dinv[0];
        for k in 1..nx.min(n) {
            z[k] = (r[k] + w[k] * z[k - 1]) * dinv[k];
        }
        for k in nx..n {
            z[k] = (r[k] + w[k] * z[k - 1] + s[k] * z[k - nx]) * dinv[k];
        }
        // Backward: (D̃ + Lᵀ) z = D̃ w.
        let last_row = n.saturating_sub(nx);
        for k in (last_row..n.saturating_sub(1)).rev() {
            z[k] += e[k] * z[k + 1] * dinv[k];
        }
        for k in (0..last_row).rev() {
            z[k] += (e[k] * z[k + 1] + no[k] * z[k + nx]) * dinv[k];
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Pcg;

    fn laplacian(nx: usize, ny: usize, px: bool) -> Stencil5 {
        let mut a = Stencil5::new(nx, ny, px, false);
        for j in 0..ny {
            for i in 0..nx {
                let k = j * nx + i;
                a.east[k] = if i + 1 < nx || px { 1.0 } else { 0.0 };
                a.north[k] = if j + 1 < ny { 1.0 } else { 0.0 };
            }
        }
        for j in 0..ny {
            for i in 0..nx {
                let k = j * nx + i;
                let w = if i > 0 {
                    a.east[k - 1]
                } else if px {
                    a.east[k + nx - 1]
                } else {
                    0.0
                };
                let s = if j > 0 { a.north[k - nx] } else { 0.0 };
                a.diag[k] = a.east[k] + a.north[k] + w + s + 0.01;
            }
        }
        a
    }

    #[test]
    fn ic_pcg_beats_plain_cg_and_is_exact() {
        for px in [false, true] {
            let mut a = laplacian(40, 30, px);
            let n = a.len();
            let xe: Vec<f64> = (0..n).map(|k| ((k * 7919) % 113) as f64 / 113.0).collect();
            let mut b = vec![0.0; n];
            a.mul(&xe, &mut b);
            let mut ic = IncompleteCholesky::new();
            ic.factor(&a);
            let maxabs = |r: &[f64]| r.iter().fold(0.0f64, |m, v| m.max(v.abs()));
            let mut x = vec![0.0; n];
            let s_ic = Pcg::new(n).solve(&mut a, &ic, &b, &mut x, 1e-12, 5000, maxabs);
            assert!(s_ic.converged);
            for k in 0..n {
                assert!((x[k] - xe[k]).abs() < 1e-9);
            }
            let mut x2 = vec![0.0; n];
            let jacobi = a.diag.clone();
            let s_j =
                Pcg::new(n).solve(&mut a, jacobi.as_slice(), &b, &mut x2, 1e-12, 5000, maxabs);
            assert!(
                s_ic.iterations * 3 < s_j.iterations * 2,
                "IC {} vs Jacobi {}",
                s_ic.iterations,
                s_j.iterations
            );
        }
    }
}
