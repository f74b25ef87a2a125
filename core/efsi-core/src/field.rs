//! Scalar arrays on the staggered grid, with ghost layers.
//!
//! Every [`Field`] has the same padded shape, `(nx+1+2G) × (ny+1+2G)`, whatever its staggering,
//! so one linear index serves all arrays of a grid and stencils can mix them with fixed
//! offsets (`±1` along x, `±stride` along y). Which part of the array is interior depends on the
//! staggering ([`Stagger`]): see the table in [`crate::grid`].

use crate::grid::{G, GHOST, Grid};
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
    /// Cell corners.
    Corner,
}

impl Stagger {
    /// Interior index ranges `(i_end, j_end)` (exclusive) for a grid of `nx × ny` cells.
    pub fn extent(self, nx: usize, ny: usize) -> (usize, usize) {
        match self {
            Stagger::Cell => (nx, ny),
            Stagger::XFace => (nx + 1, ny),
            Stagger::YFace => (nx, ny + 1),
            Stagger::Corner => (nx + 1, ny + 1),
        }
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
}

impl Field {
    /// A zero field shaped for `grid`.
    pub fn zeros(grid: &Grid) -> Self {
        Self::filled(grid, 0.0)
    }

    /// A field shaped for `grid` with every entry (ghosts included) set to `value`.
    pub fn filled(grid: &Grid, value: f64) -> Self {
        let stride = grid.nx + 1 + 2 * GHOST;
        let rows = grid.ny + 1 + 2 * GHOST;
        Field {
            data: vec![value; stride * rows],
            stride,
            rows,
        }
    }

    /// Linear index of `(i, j)`; ghosts have negative or past-the-end indices.
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
        (j + G) as usize * self.stride + (i + G) as usize
    }

    /// Offset between `(i, j)` and `(i, j+1)` in the linear storage.
    #[inline(always)]
    pub fn stride(&self) -> usize {
        self.stride
    }

    /// Number of padded rows.
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

    /// Maximum of |value| over the interior of the given staggering.
    pub fn max_abs(&self, stagger: Stagger, nx: usize, ny: usize) -> f64 {
        let (ie, je) = stagger.extent(nx, ny);
        let mut m = 0.0f64;
        for j in 0..je as isize {
            let row = self.idx(0, j);
            for v in &self.data[row..row + ie] {
                m = m.max(v.abs());
            }
        }
        m
    }

    /// Whether every interior value of the given staggering is finite; else the first bad index.
    pub fn first_non_finite(
        &self,
        stagger: Stagger,
        nx: usize,
        ny: usize,
    ) -> Option<(usize, usize)> {
        let (ie, je) = stagger.extent(nx, ny);
        let row = |j: usize| {
            let k = self.idx(0, j as isize);
            &self.data[k..k + ie]
        };
        // The common case, all finite, in one vectorised pass over rows in parallel; only a
        // field that fails it is searched for its first bad value.
        let bad = efsi_linalg::par::range(je).work(ie).fold(
            0.0,
            |j| if all_finite(row(j)) { 0.0 } else { 1.0 },
            f64::max,
        );
        if bad == 0.0 {
            return None;
        }
        (0..je).find_map(|j| row(j).iter().position(|v| !v.is_finite()).map(|i| (i, j)))
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
