//! The normal-velocity faces an implicit stage solves for ([`UnknownFaces`]) and the compact
//! vectors of the linear solvers on them: one order (the u-faces line by line, then the v-faces
//! line by line) shared by the viscous stage, the elastic system and their preconditioners, and
//! the scatter / gather between a compact vector and the velocity fields, rows in parallel.

use efsi_core::bc::FaceRange;
use efsi_core::{BoundarySet, Field, Grid, Region, Stagger};
use efsi_linalg::par;

/// The normal-velocity faces an implicit stage solves for, in one compact order: the u-faces line
/// by line, then the v-faces line by line (the lines of [`UnknownFaces::u_region`], then of
/// [`UnknownFaces::v_region`]). Compact vectors of the linear solvers use this order.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct UnknownFaces {
    /// Unknown u-faces along x (all rows).
    pub(crate) ux: FaceRange,
    /// Unknown v-faces along y (all columns).
    pub(crate) vy: FaceRange,
    /// The unknown u- and v-faces as grid regions.
    u: Region,
    v: Region,
}

impl UnknownFaces {
    /// The unknown faces of `grid` under `bc`.
    pub(crate) fn new(grid: &Grid, bc: &BoundarySet) -> Self {
        let (ux, vy) = (bc.normal_faces(0, grid.nx), bc.normal_faces(1, grid.ny));
        UnknownFaces {
            ux,
            vy,
            u: Region::of(grid, Stagger::XFace).range(0, ux.lo, ux.hi),
            v: Region::of(grid, Stagger::YFace).range(1, vy.lo, vy.hi),
        }
    }

    /// The unknown u-faces as a grid region (the first part of a compact vector, line by line).
    pub(crate) fn u_region(&self) -> Region {
        self.u
    }

    /// The unknown v-faces as a grid region (the second part of a compact vector).
    pub(crate) fn v_region(&self) -> Region {
        self.v
    }

    /// Number of unknown u-faces (they come first).
    pub(crate) fn nu(&self) -> usize {
        self.u.size()
    }

    /// Number of unknowns.
    pub(crate) fn len(&self) -> usize {
        self.nu() + self.v.size()
    }

    /// Write the compact vector `x` into the unknown faces of `u`, `v`.
    pub(crate) fn scatter(&self, x: &[f64], u: &mut Field, v: &mut Field) {
        self.each_line(x, u, v, |a, b| a.copy_from_slice(b));
    }

    /// `u, v += x` on the unknown faces.
    pub(crate) fn add(&self, x: &[f64], u: &mut Field, v: &mut Field) {
        self.each_line(x, u, v, |a, b| {
            for (a, b) in a.iter_mut().zip(b) {
                *a += b;
            }
        });
    }

    /// `u, v ← x + β (u, v)` on the unknown faces.
    pub(crate) fn xpby(&self, x: &[f64], beta: f64, u: &mut Field, v: &mut Field) {
        self.each_line(x, u, v, |a, b| {
            for (a, b) in a.iter_mut().zip(b) {
                *a = b + beta * *a;
            }
        });
    }

    /// Write the unknown faces of `u`, `v` into the compact vector `x`.
    pub(crate) fn gather(&self, u: &Field, v: &Field, x: &mut [f64]) {
        let (xu, xv) = x.split_at_mut(self.nu());
        for (r, f, x) in [(&self.u, u, xu), (&self.v, v, xv)] {
            if !r.is_empty() {
                par::rows(x, r.len(0))
                    .for_each(|n, row| row.copy_from_slice(f.at(&r.line(n), [0; 3])));
            }
        }
    }

    /// `f(the field's unknown faces on a line, x's row for that line)` for every line of u-
    /// then v-faces, lines in parallel.
    fn each_line(
        &self,
        x: &[f64],
        u: &mut Field,
        v: &mut Field,
        f: impl Fn(&mut [f64], &[f64]) + Sync + Send,
    ) {
        let (xu, xv) = x.split_at(self.nu());
        self.u
            .for_each(u, |l, row| f(row, &xu[l.n * l.len..(l.n + 1) * l.len]));
        self.v
            .for_each(v, |l, row| f(row, &xv[l.n * l.len..(l.n + 1) * l.len]));
    }
}
