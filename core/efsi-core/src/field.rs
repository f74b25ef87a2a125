//! Scalar arrays on the staggered grid, with ghost layers.
//!
//! Every [`Field`] has the same padded shape, `(nx+1+2G) × (ny+1+2G) × planes` whatever its
//! staggering ([`Grid::padded`]), so one linear index serves all arrays of a grid and stencils
//! can mix them with fixed offsets (`±1` along x, `±stride` along y, `±plane` along z). A
//! two-dimensional grid has one plane and no ghosts along z, so its fields are laid out exactly
//! as 2-D arrays; a three-dimensional one has `nz + 1 + 2G` planes. Which part of the array is
//! interior depends on the staggering ([`Stagger`]): see the table in [`crate::grid`].
//!
//! The storage index of `[i, j, k]` is `((k + gz)·rows + j + G)·stride + i + G` with `gz` the
//! grid's ghost layers along z ([`Grid::gz`]).

use crate::grid::{G, Grid};
use std::ops::{Index, IndexMut};

/// Where the values of a field live on the MAC grid.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Stagger {
    /// Cell centres.
    Cell,
    /// x-faces (normal velocity u).
    XFace,
    /// y-faces (normal velocity v).
    YFace,
    /// Cell corners (in three dimensions: the edges along z, where `τ_xy` lives).
    Corner,
    /// z-faces (normal velocity w; three-dimensional grids).
    ZFace,
    /// Edges along x (`τ_yz`; three-dimensional grids).
    XEdge,
    /// Edges along y (`τ_xz`; three-dimensional grids).
    YEdge,
}

impl Stagger {
    /// Interior index ranges `(i_end, j_end)` (exclusive) for a grid of `nx × ny` cells.
    pub fn extent(self, nx: usize, ny: usize) -> (usize, usize) {
        let [i, j, _] = self.nodal();
        (nx + i, ny + j)
    }

    /// Whether the location sits on the cell boundaries (1) or at the cell centre (0) along
    /// each axis: its interior extends to `n + 1` indices along an axis where it is 1.
    pub fn nodal(self) -> [usize; 3] {
        match self {
            Stagger::Cell => [0, 0, 0],
            Stagger::XFace => [1, 0, 0],
            Stagger::YFace => [0, 1, 0],
            Stagger::ZFace => [0, 0, 1],
            Stagger::Corner => [1, 1, 0],
            Stagger::XEdge => [0, 1, 1],
            Stagger::YEdge => [1, 0, 1],
        }
    }

    /// Interior index ranges `[i_end, j_end, k_end]` (exclusive) on `grid`: along z, `nz` or
    /// `nz + 1` on a three-dimensional grid and 1 (the plane `k = 0`) on a two-dimensional one.
    pub fn extent3(self, grid: &Grid) -> [usize; 3] {
        let o = self.nodal();
        let nz = if grid.is_3d() { grid.nz + o[2] } else { 1 };
        [grid.nx + o[0], grid.ny + o[1], nz]
    }
}

/// A padded 2-D array of `f64` covering a grid and its ghost layers.
///
/// `Field::default()` is an empty placeholder (no storage), useful with `std::mem::take`.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Field {
    data: Vec<f64>,
    stride: usize,
    rows: usize,
    /// Padded planes (1 in two dimensions) and ghost planes below `k = 0` (0 in two).
    planes: usize,
    gz: usize,
    /// The padded row of `j = 0` in the plane `k = 0`: `gz·rows + G`.
    row0: isize,
}

impl Field {
    /// A zero field shaped for `grid`.
    pub fn zeros(grid: &Grid) -> Self {
        Self::filled(grid, 0.0)
    }

    /// A field shaped for `grid` with every entry (ghosts included) set to `value`.
    pub fn filled(grid: &Grid, value: f64) -> Self {
        let [stride, rows, planes] = grid.padded();
        Field {
            data: vec![value; stride * rows * planes],
            stride,
            rows,
            planes,
            gz: grid.gz(),
            row0: (grid.gz() * rows) as isize + G,
        }
    }

    /// Linear index of `(i, j)` in the plane `k = 0`; ghosts have negative or past-the-end
    /// indices.
    #[inline(always)]
    pub fn idx(&self, i: isize, j: isize) -> usize {
        debug_assert!(
            i >= -G && (i + G) < self.stride as isize,
            "i = {i} out of range"
        );
        debug_assert!(
            j >= -G && (j + G) < self.rows as isize,
            "j = {j} out of range"
        );
        (j + self.row0) as usize * self.stride + (i + G) as usize
    }

    /// Linear index of `[i, j, k]` (ghosts included), bounds-checked along every axis.
    #[inline(always)]
    pub fn idx3(&self, [i, j, k]: [isize; 3]) -> usize {
        let gz = self.gz as isize;
        assert!(
            (-G..self.stride as isize - G).contains(&i)
                && (-G..self.rows as isize - G).contains(&j)
                && (-gz..self.planes as isize - gz).contains(&k),
            "[{i}, {j}, {k}] out of range"
        );
        ((k + gz) as usize * self.rows + (j + G) as usize) * self.stride + (i + G) as usize
    }

    /// The index `[i, j, k]` of storage position `n` (the inverse of [`Field::idx3`]).
    pub fn index_of(&self, n: usize) -> [isize; 3] {
        assert!(n < self.data.len(), "storage index {n} out of range");
        let (row, i) = (n / self.stride, n % self.stride);
        let (k, j) = (row / self.rows, row % self.rows);
        [
            i as isize - G,
            j as isize - G,
            k as isize - self.gz as isize,
        ]
    }

    /// Offset between `[i, j, k]` and `[i, j, k+1]` in the linear storage (the plane size).
    #[inline(always)]
    pub fn plane(&self) -> usize {
        self.stride * self.rows
    }

    /// Number of padded planes (1 in two dimensions).
    #[inline(always)]
    pub fn planes(&self) -> usize {
        self.planes
    }

    /// Number of ghost planes on each side along z (0 in two dimensions).
    #[inline(always)]
    pub fn gz(&self) -> usize {
        self.gz
    }

    /// Storage offset of `shift` (`s_x + s_y·stride + s_z·plane`).
    #[inline(always)]
    pub fn offset(&self, [a, b, c]: [isize; 3]) -> isize {
        a + b * self.stride as isize + c * self.plane() as isize
    }

    /// Offset between `(i, j)` and `(i, j+1)` in the linear storage.
    #[inline(always)]
    pub fn stride(&self) -> usize {
        self.stride
    }

    /// Number of padded rows.
    #[inline(always)]
    pub fn rows(&self) -> usize {
        self.rows
    }

    /// The raw storage, ghosts included.
    #[inline(always)]
    pub fn data(&self) -> &[f64] {
        &self.data
    }

    /// The raw storage, mutable.
    #[inline(always)]
    pub fn data_mut(&mut self) -> &mut [f64] {
        &mut self.data
    }

    /// Set every entry (ghosts included) to `value`.
    pub fn fill(&mut self, value: f64) {
        self.data.fill(value);
    }

    /// Copy all values from `other` (same shape); in parallel chunks on large grids.
    pub fn copy_from(&mut self, other: &Field) {
        efsi_linalg::par::copy(&mut self.data, &other.data);
    }

    /// Number of interior planes of location `stagger`: 1 in two dimensions, `nz` or `nz + 1`
    /// in three.
    fn kz(&self, stagger: Stagger) -> usize {
        if self.gz == 0 {
            1
        } else {
            self.planes - 1 - 2 * self.gz + stagger.nodal()[2]
        }
    }

    /// The interior values of row `j` of plane `k` at location `stagger` of an `nx × ny` grid.
    fn interior_row(&self, stagger: Stagger, nx: usize, ny: usize, j: usize, k: usize) -> &[f64] {
        let (ie, _) = stagger.extent(nx, ny);
        let o = self.idx3([0, j as isize, k as isize]);
        &self.data[o..o + ie]
    }

    /// Maximum of |value| over the interior of the given staggering (every plane).
    pub fn max_abs(&self, stagger: Stagger, nx: usize, ny: usize) -> f64 {
        let (_, je) = stagger.extent(nx, ny);
        let mut m = 0.0f64;
        for k in 0..self.kz(stagger) {
            for j in 0..je {
                for v in self.interior_row(stagger, nx, ny, j, k) {
                    m = m.max(v.abs());
                }
            }
        }
        m
    }

    /// Whether every interior value of the given staggering is finite; else the `(i, j)` of
    /// the first bad one ([`Field::first_non_finite3`] also names its plane).
    pub fn first_non_finite(
        &self,
        stagger: Stagger,
        nx: usize,
        ny: usize,
    ) -> Option<(usize, usize)> {
        self.first_non_finite3(stagger, nx, ny)
            .map(|[i, j, _]| (i, j))
    }

    /// Whether every interior value of the given staggering is finite; else the index
    /// `[i, j, k]` of the first bad one in storage order.
    pub fn first_non_finite3(&self, stagger: Stagger, nx: usize, ny: usize) -> Option<[usize; 3]> {
        let (ie, je) = stagger.extent(nx, ny);
        let row = |r: usize| self.interior_row(stagger, nx, ny, r % je, r / je);
        let rows = je * self.kz(stagger);
        // The common case, all finite, in one vectorised pass over rows in parallel; only a
        // field that fails it is searched for its first bad value.
        let bad = efsi_linalg::par::range(rows).work(ie).fold(
            0.0,
            |r| if all_finite(row(r)) { 0.0 } else { 1.0 },
            f64::max,
        );
        if bad == 0.0 {
            return None;
        }
        (0..rows).find_map(|r| {
            let i = row(r).iter().position(|v| !v.is_finite())?;
            Some([i, r % je, r / je])
        })
    }
}

/// Whether every value of `x` is finite: `0·v` is ±0 for a finite `v` and NaN otherwise, so a
/// four-lane sum of it (which vectorises, unlike a loop that can stop early) is 0 exactly when
/// all are.
fn all_finite(x: &[f64]) -> bool {
    let mut s = [0.0f64; 4];
    let mut chunks = x.chunks_exact(4);
    for c in &mut chunks {
        for l in 0..4 {
            s[l] += c[l] * 0.0;
        }
    }
    let tail = chunks.remainder().iter().fold(0.0, |a, v| a + v * 0.0);
    (s[0] + s[1]) + (s[2] + s[3]) + tail == 0.0
}

impl Index<(isize, isize)> for Field {
    type Output = f64;
    #[inline(always)]
    fn index(&self, (i, j): (isize, isize)) -> &f64 {
        &self.data[self.idx(i, j)]
    }
}

impl IndexMut<(isize, isize)> for Field {
    #[inline(always)]
    fn index_mut(&mut self, (i, j): (isize, isize)) -> &mut f64 {
        let k = self.idx(i, j);
        &mut self.data[k]
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::grid::Geometry;

    #[test]
    fn indexing_covers_ghosts() {
        let g = Grid::new(Geometry::Planar, 3, 2, (0.0, 1.0), (0.0, 1.0));
        let mut f = Field::zeros(&g);
        f[(-2, -2)] = 1.0;
        f[(3 + 2, 2 + 2)] = 2.0;
        assert_eq!(f.data()[0], 1.0);
        assert_eq!(*f.data().last().unwrap(), 2.0);
        assert_eq!(f.idx(0, 1) - f.idx(0, 0), f.stride());
    }

    #[test]
    fn first_non_finite_finds_the_first_bad_value_of_the_interior() {
        // Large enough for the parallel path; ghosts are not checked.
        let g = Grid::new(Geometry::Planar, 130, 90, (0.0, 1.0), (0.0, 1.0));
        let mut f = Field::filled(&g, 1.5);
        f[(-1, 3)] = f64::NAN;
        f[(131, 3)] = f64::INFINITY;
        assert_eq!(f.first_non_finite(Stagger::Cell, 130, 90), None);
        f[(130, 7)] = f64::NEG_INFINITY;
        assert_eq!(f.first_non_finite(Stagger::Cell, 130, 90), None);
        assert_eq!(f.first_non_finite(Stagger::XFace, 130, 90), Some((130, 7)));
        for (i, j) in [(129, 60), (5, 60), (0, 2)] {
            f[(i, j)] = f64::NAN;
            assert_eq!(
                f.first_non_finite(Stagger::Cell, 130, 90),
                Some((i as usize, j as usize))
            );
        }
        assert!(all_finite(&[1.0, -2.0, f64::MAX, 0.0, 3.0]));
        assert!(!all_finite(&[1.0, -2.0, f64::MAX, 0.0, f64::INFINITY]));
    }
}
