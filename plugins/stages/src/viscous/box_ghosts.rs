//! Ghosts of a box whose sides are each periodic or a no-slip wall, along every axis of a two-
//! or three-dimensional grid: the rules of [`efsi_core::bc`] (a wall's boundary faces zero, odd
//! reflection of the normal and tangential components, even reflection of cell scalars), for
//! tests of the dimension-generic kernels on grids whose z sides the boundary conditions do not
//! fill.

use super::VelocityGhosts;
use efsi_core::bc::{FaceRange, WallTime};
use efsi_core::{Field, Grid};
use std::borrow::BorrowMut;

/// Each axis periodic (`true`) or closed by no-slip walls.
#[derive(Clone, Copy, Debug)]
pub(crate) struct BoxGhosts {
    pub(crate) periodic: [bool; 3],
}

impl BoxGhosts {
    /// The unknown faces along each axis of `grid`: all `n` of a periodic one, the `n − 1`
    /// between its walls.
    pub(crate) fn ranges(&self, grid: &Grid) -> Vec<FaceRange> {
        let n = grid.n();
        (0..grid.dims())
            .map(|a| FaceRange {
                lo: if self.periodic[a] { 0 } else { 1 },
                hi: n[a] as isize,
            })
            .collect()
    }

    /// Fill the ghosts of `f`, a field of `nodal` (1) or centred (0) positions along each axis,
    /// the normal velocity of axis `normal` (`None` for a cell scalar, reflected evenly).
    pub(crate) fn fill_one(
        &self,
        grid: &Grid,
        f: &mut Field,
        nodal: [usize; 3],
        normal: Option<usize>,
    ) {
        let n = grid.n();
        for a in 0..grid.dims() {
            let na = n[a] as isize;
            let sign = if normal.is_some() { -1.0 } else { 1.0 };
            for q in 0..f.data().len() {
                let idx = f.index_of(q);
                let i = idx[a];
                let at = |k: isize| {
                    let mut m = idx;
                    m[a] = k;
                    m
                };
                let value = if nodal[a] == 1 {
                    if self.periodic[a] {
                        match i {
                            _ if i < 0 => Some(f[at(i + na)]),
                            _ if i >= na => Some(f[at(i - na)]),
                            _ => None,
                        }
                    } else {
                        match i {
                            0 => Some(0.0),
                            _ if i == na => Some(0.0),
                            _ if i < 0 => Some(-f[at(-i)]),
                            _ if i > na => Some(-f[at(2 * na - i)]),
                            _ => None,
                        }
                    }
                } else if self.periodic[a] {
                    match i {
                        _ if i < 0 => Some(f[at(i + na)]),
                        _ if i >= na => Some(f[at(i - na)]),
                        _ => None,
                    }
                } else {
                    match i {
                        _ if i < 0 => Some(sign * f[at(-1 - i)]),
                        _ if i >= na => Some(sign * f[at(2 * na - 1 - i)]),
                        _ => None,
                    }
                };
                if let Some(x) = value {
                    f.data_mut()[q] = x;
                }
            }
        }
    }

    /// The ghosts of a cell scalar (even reflection at walls).
    pub(crate) fn fill_scalar(&self, grid: &Grid, f: &mut Field) {
        self.fill_one(grid, f, [0; 3], None);
    }
}

impl VelocityGhosts for BoxGhosts {
    /// Walls at rest whatever `when`.
    fn fill<F: BorrowMut<Field>>(&self, grid: &Grid, vel: &mut [F], _when: WallTime) {
        for (c, f) in vel.iter_mut().enumerate() {
            let mut nodal = [0; 3];
            nodal[c] = 1;
            self.fill_one(grid, f.borrow_mut(), nodal, Some(c));
        }
    }
}
