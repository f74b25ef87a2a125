//! The normal-velocity faces an implicit stage solves for ([`UnknownFaces`]) and the compact
//! vectors of the linear solvers on them: one order (the u-faces row by row, then the v-faces
//! row by row) shared by the viscous stage, the elastic system and their preconditioners, and
//! the scatter / gather between a compact vector and the velocity fields, rows in parallel.

use efsi_core::bc::FaceRange;
use efsi_core::{BoundarySet, Field, G, GHOST, Grid};
use efsi_linalg::par;

/// The normal-velocity faces an implicit stage solves for, in one compact order: the u-faces row
/// by row, then the v-faces row by row. Compact vectors of the linear solvers use this order;
/// [`UnknownFaces::for_each`] maps it to the fields' linear index.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct UnknownFaces {
    /// Unknown u-faces along x (all rows).
    pub(crate) ux: FaceRange,
    /// Unknown v-faces along y (all columns).
    pub(crate) vy: FaceRange,
    nx: usize,
    ny: usize,
}

impl UnknownFaces {
    /// The unknown faces of `grid` under `bc`.
    pub(crate) fn new(grid: &Grid, bc: &BoundarySet) -> Self {
        UnknownFaces {
            ux: bc.normal_faces(0, grid.nx),
            vy: bc.normal_faces(1, grid.ny),
            nx: grid.nx,
            ny: grid.ny,
        }
    }

    /// Number of unknown u-faces (they come first).
    pub(crate) fn nu(&self) -> usize {
        (self.ux.hi - self.ux.lo) as usize * self.ny
    }

    /// Number of unknowns.
    pub(crate) fn len(&self) -> usize {
        self.nu() + (self.vy.hi - self.vy.lo) as usize * self.nx
    }

    /// Call `f(compact index, is_u, linear field index)` for every unknown face, in order.
    #[inline]
    pub(crate) fn for_each(&self, mut f: impl FnMut(usize, bool, usize)) {
        let stride = self.nx + 1 + 2 * GHOST;
        let idx = |i: isize, j: isize| (j + G) as usize * stride + (i + G) as usize;
        let mut c = 0;
        for j in 0..self.ny as isize {
            for i in self.ux.lo..self.ux.hi {
                f(c, true, idx(i, j));
                c += 1;
            }
        }
        for j in self.vy.lo..self.vy.hi {
            for i in 0..self.nx as isize {
                f(c, false, idx(i, j));
                c += 1;
            }
        }
    }

    /// Write the compact vector `x` into the unknown faces of `u`, `v`.
    pub(crate) fn scatter(&self, x: &[f64], u: &mut Field, v: &mut Field) {
        each_face_row(self, x, u, v, |a, b| a.copy_from_slice(b));
    }

    /// `u, v += x` on the unknown faces.
    pub(crate) fn add(&self, x: &[f64], u: &mut Field, v: &mut Field) {
        each_face_row(self, x, u, v, |a, b| {
            for (a, b) in a.iter_mut().zip(b) {
                *a += b;
            }
        });
    }

    /// `u, v ← x + β (u, v)` on the unknown faces.
    pub(crate) fn xpby(&self, x: &[f64], beta: f64, u: &mut Field, v: &mut Field) {
        each_face_row(self, x, u, v, |a, b| {
            for (a, b) in a.iter_mut().zip(b) {
                *a = b + beta * *a;
            }
        });
    }

    /// Write the unknown faces of `u`, `v` into the compact vector `x`.
    pub(crate) fn gather(&self, u: &Field, v: &Field, x: &mut [f64]) {
        let (ux, vy) = (self.ux, self.vy);
        let nur = (ux.hi - ux.lo).max(0) as usize;
        let nu = self.nu();
        let (xu, xv) = x.split_at_mut(nu);
        if nur > 0 {
            par::rows(&mut *xu, nur).for_each(|j, row| {
                let k0 = u.idx(ux.lo, j as isize);
                row.copy_from_slice(&u.data()[k0..k0 + nur]);
            });
        }
        let nx = u.stride() - 1 - 2 * GHOST;
        if nx > 0 {
            par::rows(&mut *xv, nx).for_each(|jr, row| {
                let k0 = v.idx(0, vy.lo + jr as isize);
                row.copy_from_slice(&v.data()[k0..k0 + nx]);
            });
        }
    }
}

/// `f(field row's unknown faces, x's row)` for every row of u- then v-faces, in parallel.
fn each_face_row(
    faces: &UnknownFaces,
    x: &[f64],
    u: &mut Field,
    v: &mut Field,
    f: impl Fn(&mut [f64], &[f64]) + Sync + Send,
) {
    let (ux, vy) = (faces.ux, faces.vy);
    let s = u.stride();
    let nur = (ux.hi - ux.lo).max(0) as usize;
    let nx = s - 1 - 2 * GHOST;
    let nu = faces.nu();
    if let Some(rows) = nu.checked_div(nur) {
        let r0 = u.idx(-G, 0);
        let o = (G + ux.lo) as usize;
        par::rows(&mut u.data_mut()[r0..r0 + rows * s], s).for_each(|j, row| {
            f(&mut row[o..o + nur], &x[j * nur..(j + 1) * nur]);
        });
    }
    let rows = (vy.hi - vy.lo).max(0) as usize;
    let r0 = v.idx(-G, vy.lo);
    let xv = &x[nu..];
    let o = GHOST;
    par::rows(&mut v.data_mut()[r0..r0 + rows * s], s).for_each(|j, row| {
        f(&mut row[o..o + nx], &xv[j * nx..(j + 1) * nx]);
    });
}
