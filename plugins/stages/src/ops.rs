//! Discrete operators named after the mathematics, shared by stages, probes and tests.
//!
//! All are finite-volume forms on the MAC grid with the axisymmetric metric: a flux through an
//! x-face is weighted by the face radius `r_f`, through a y-face by the cell radius `r_c`, and the
//! balance is divided by the control volume's radius (see [`efsi_core::grid`]).

use efsi_core::{Field, Grid};

/// The density on the face between two cells of densities `a` and `b`: their arithmetic mean.
/// The one face-density rule of every stage: the mass of a momentum control volume (advection,
/// viscous and elastic steps) and `1/ρ_f` in the pressure equation and its correction — the
/// density stays inside the divergence, smooth across an interface (seed Eqs. 21–23).
#[inline(always)]
pub fn face_density(a: f64, b: f64) -> f64 {
    0.5 * (a + b)
}

/// `∇·u` at cell `(i, j)`: `(r_{i+1} u_{i+1} − r_i u_i)/(r_c dx) + (v_{j+1} − v_j)/dy`.
#[inline(always)]
pub fn div(grid: &Grid, u: &Field, v: &Field, i: isize, j: isize) -> f64 {
    let m = &grid.metric;
    let k = u.idx(i, j);
    let s = u.stride();
    let ud = u.data();
    let vd = v.data();
    (m.rx(i + 1) * ud[k + 1] - m.rx(i) * ud[k]) / (m.rc(i) * grid.dx)
        + (vd[k + s] - vd[k]) / grid.dy
}

/// Net volume flux out of cell `(i, j)`: `∮ u·n dA`, i.e. `vol·∇·u` (per radian when axisymmetric).
#[inline(always)]
pub fn net_outflux(grid: &Grid, u: &Field, v: &Field, i: isize, j: isize) -> f64 {
    let m = &grid.metric;
    let k = u.idx(i, j);
    let s = u.stride();
    let ud = u.data();
    let vd = v.data();
    (m.rx(i + 1) * ud[k + 1] - m.rx(i) * ud[k]) * grid.dy + m.rc(i) * (vd[k + s] - vd[k]) * grid.dx
}

/// `max |∇·u|` over all cells.
pub fn max_abs_div(grid: &Grid, u: &Field, v: &Field) -> f64 {
    let mut m = 0.0f64;
    for j in 0..grid.ny as isize {
        for i in 0..grid.nx as isize {
            m = m.max(div(grid, u, v, i, j).abs());
        }
    }
    m
}

/// Velocity at the centre of cell `(i, j)` (average of the two faces of each component).
#[inline]
pub fn centre_velocity(u: &Field, v: &Field, i: isize, j: isize) -> (f64, f64) {
    (
        0.5 * (u[(i, j)] + u[(i + 1, j)]),
        0.5 * (v[(i, j)] + v[(i, j + 1)]),
    )
}

/// Kinetic energy `½∫ρ|u|² dV` (per radian when axisymmetric), with face-centred quadrature;
/// rows in parallel, summed in row order (the same bits on any number of threads).
pub fn kinetic_energy(grid: &Grid, u: &Field, v: &Field, rho: &Field) -> f64 {
    let m = &grid.metric;
    let [e] = efsi_linalg::par::range(grid.ny).work(grid.nx).fold(
        [0.0; 1],
        |j| {
            let j = j as isize;
            let mut e = 0.0;
            for i in 0..grid.nx as isize {
                // Half of each of the cell's four faces belongs to it.
                let eu =
                    0.5 * (m.rx(i) * u[(i, j)].powi(2) + m.rx(i + 1) * u[(i + 1, j)].powi(2)) / 2.0;
                let ev = 0.5 * m.rc(i) * (v[(i, j)].powi(2) + v[(i, j + 1)].powi(2)) / 2.0;
                e += rho[(i, j)] * (eu + ev) * grid.dx * grid.dy;
            }
            [e]
        },
        efsi_linalg::par::add,
    );
    e
}

/// `−∫ρ g·x dV` over the cells (per radian in axisymmetric geometry).
/// Rows in parallel, summed in row order (the same bits on any number of threads).
pub fn potential_energy(grid: &Grid, rho: &Field, (gx, gy): (f64, f64)) -> f64 {
    let [e] = efsi_linalg::par::range(grid.ny).work(grid.nx).fold(
        [0.0; 1],
        |j| {
            let j = j as isize;
            let mut e = 0.0;
            for i in 0..grid.nx as isize {
                e -= rho[(i, j)] * (gx * grid.xc(i) + gy * grid.yc(j)) * grid.cell_volume(i);
            }
            [e]
        },
        efsi_linalg::par::add,
    );
    e
}
