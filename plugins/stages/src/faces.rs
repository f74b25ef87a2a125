//! The normal-velocity faces an implicit stage solves for ([`UnknownFaces`]) and the compact
//! vectors of the linear solvers on them: one order (the u-faces line by line, then the
//! v-faces, then on a three-dimensional grid the w-faces, each line by line in storage order)
//! shared by the viscous stage, the elastic system and their preconditioners, and the scatter /
//! gather between a compact vector and the velocity fields, lines in parallel.
//!
//! A velocity is passed as one field per axis of the grid (u, v and, in three dimensions, w),
//! as owned fields (`&[Field]`) or references (`&[&Field]`, `&mut [&mut Field]`).

use efsi_core::bc::FaceRange;
use efsi_core::{BoundarySet, Field, Grid, Region, Stagger};
use efsi_linalg::par;
use std::borrow::{Borrow, BorrowMut};

/// The face location of each axis' normal velocity.
const FACES: [Stagger; 3] = [Stagger::XFace, Stagger::YFace, Stagger::ZFace];

/// The normal-velocity faces an implicit stage solves for, in one compact order: the u-faces
/// line by line, then the v-faces, then (three dimensions) the w-faces. Compact vectors of the
/// linear solvers use this order; [`UnknownFaces::region`] maps it to the fields' storage.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct UnknownFaces {
    /// Unknown u-faces along x (all rows).
    pub(crate) ux: FaceRange,
    /// Unknown v-faces along y (all columns).
    pub(crate) vy: FaceRange,
    /// The unknown faces of each axis as grid regions (empty past the grid's axes).
    regions: [Region; 3],
    dims: usize,
}

impl UnknownFaces {
    /// The unknown faces of `grid` under `bc`: along each axis `a`, the faces
    /// `bc.normal_faces(a, n_a)` (the z sides' answer on a three-dimensional grid).
    pub(crate) fn new(grid: &Grid, bc: &BoundarySet) -> Self {
        let n = grid.n();
        let ranges: Vec<FaceRange> = (0..grid.dims()).map(|a| bc.normal_faces(a, n[a])).collect();
        Self::with_ranges(grid, &ranges)
    }

    /// The faces `ranges[a]` along each axis `a` of `grid` (all of them across it).
    pub(crate) fn with_ranges(grid: &Grid, ranges: &[FaceRange]) -> Self {
        let dims = grid.dims();
        assert_eq!(ranges.len(), dims, "one face range per axis");
        let regions = std::array::from_fn(|a| {
            let r = Region::of(grid, FACES[a]);
            match ranges.get(a) {
                Some(f) => r.range(a, f.lo, f.hi),
                None => r.range(a, 0, 0),
            }
        });
        UnknownFaces {
            ux: ranges[0],
            vy: ranges[1],
            regions,
            dims,
        }
    }

    /// The unknown faces normal to axis `a` as a grid region (part `a` of a compact vector,
    /// line by line).
    pub(crate) fn region(&self, a: usize) -> Region {
        self.regions[a]
    }

    /// The unknown u-faces as a grid region (the first part of a compact vector, line by line).
    pub(crate) fn u_region(&self) -> Region {
        self.regions[0]
    }

    /// Number of unknown u-faces (they come first).
    #[cfg(test)]
    pub(crate) fn nu(&self) -> usize {
        self.regions[0].size()
    }

    /// Number of unknowns.
    pub(crate) fn len(&self) -> usize {
        self.regions.iter().map(Region::size).sum()
    }

    /// The parts of a compact vector, one per axis (the third empty in two dimensions).
    pub(crate) fn split<'a>(&self, x: &'a [f64]) -> [&'a [f64]; 3] {
        let (a, rest) = x.split_at(self.regions[0].size());
        let (b, c) = rest.split_at(self.regions[1].size());
        [a, b, c]
    }

    /// [`split`](Self::split), mutable.
    pub(crate) fn split_mut<'a>(&self, x: &'a mut [f64]) -> [&'a mut [f64]; 3] {
        let (a, rest) = x.split_at_mut(self.regions[0].size());
        let (b, c) = rest.split_at_mut(self.regions[1].size());
        [a, b, c]
    }

    /// Call `f(compact index, axis, storage index)` for every unknown face, in order.
    #[cfg(test)]
    pub(crate) fn for_each_axis(&self, mut f: impl FnMut(usize, usize, usize)) {
        let mut c = 0;
        for (a, r) in self.regions.iter().enumerate() {
            for n in 0..r.lines() {
                let l = r.line(n);
                for m in 0..l.len {
                    f(c, a, l.linear(m));
                    c += 1;
                }
            }
        }
    }

    /// Write the compact vector `x` into the unknown faces of the velocity `vel`.
    pub(crate) fn scatter_to<F: BorrowMut<Field>>(&self, x: &[f64], vel: &mut [F]) {
        self.each_line(x, vel, |a, b| a.copy_from_slice(b));
    }

    /// Write the compact vector `x` into the unknown faces of `u`, `v` (the two-dimensional
    /// form of [`scatter_to`](Self::scatter_to)).
    pub(crate) fn scatter(&self, x: &[f64], u: &mut Field, v: &mut Field) {
        self.scatter_to(x, &mut [u, v]);
    }

    /// `vel += x` on the unknown faces.
    pub(crate) fn add<F: BorrowMut<Field>>(&self, x: &[f64], vel: &mut [F]) {
        self.each_line(x, vel, |a, b| {
            for (a, b) in a.iter_mut().zip(b) {
                *a += b;
            }
        });
    }

    /// `vel ← x + β vel` on the unknown faces.
    pub(crate) fn xpby<F: BorrowMut<Field>>(&self, x: &[f64], beta: f64, vel: &mut [F]) {
        self.each_line(x, vel, |a, b| {
            for (a, b) in a.iter_mut().zip(b) {
                *a = b + beta * *a;
            }
        });
    }

    /// Write the unknown faces of the velocity `vel` into the compact vector `x`.
    pub(crate) fn gather<F: Borrow<Field> + Sync>(&self, vel: &[F], x: &mut [f64]) {
        for (a, x) in self.split_mut(x).into_iter().enumerate().take(self.dims) {
            let (r, f) = (&self.regions[a], vel[a].borrow());
            if !r.is_empty() {
                par::rows(x, r.len(0))
                    .for_each(|n, row| row.copy_from_slice(f.at(&r.line(n), [0; 3])));
            }
        }
    }

    /// `f(the field's unknown faces on a line, x's row for that line)` for every line of each
    /// component's faces in turn, lines in parallel.
    fn each_line<F: BorrowMut<Field>>(
        &self,
        x: &[f64],
        vel: &mut [F],
        f: impl Fn(&mut [f64], &[f64]) + Sync + Send,
    ) {
        assert_eq!(vel.len(), self.dims, "one velocity component per axis");
        for ((r, x), field) in self.regions.iter().zip(self.split(x)).zip(vel) {
            r.for_each(field.borrow_mut(), |l, row| {
                f(row, &x[l.n * l.len..(l.n + 1) * l.len])
            });
        }
    }
}
