//! Discrete operators named after the mathematics, shared by the stages, probes and run loop.
//!
//! All are finite-volume forms on the MAC grid with the axisymmetric metric: a flux through an
//! x-face is weighted by the face radius `r_f`, through a y-face by the cell radius `r_c`, and the
//! balance is divided by the control volume's radius (see [`crate::grid`]).

use crate::{Field, Grid, Region, Stagger, unit};

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
    (m.rx(i + 1) * u[(i + 1, j)] - m.rx(i) * u[(i, j)]) / (m.rc(i) * grid.dx)
        + (v[(i, j + 1)] - v[(i, j)]) / grid.dy
}

/// Net volume flux out of cell `(i, j)`: `∮ u·n dA`, i.e. `vol·∇·u` (per radian when axisymmetric).
#[inline(always)]
pub fn net_outflux(grid: &Grid, u: &Field, v: &Field, i: isize, j: isize) -> f64 {
    let m = &grid.metric;
    (m.rx(i + 1) * u[(i + 1, j)] - m.rx(i) * u[(i, j)]) * grid.dy
        + m.rc(i) * (v[(i, j + 1)] - v[(i, j)]) * grid.dx
}

/// `max |∇·u|` over all cells.
pub fn max_abs_div(grid: &Grid, u: &Field, v: &Field) -> f64 {
    Region::of(grid, Stagger::Cell).max(0.0, |l| {
        l.indices()
            .fold(0.0f64, |m, [i, j, _]| m.max(div(grid, u, v, i, j).abs()))
    })
}

/// The convective rate `C = max over cells of (max|u|/dx + max|v|/dy)`, each component's
/// largest magnitude on the cell's two faces: the explicit advective limit is `Δt ≤ CFL/C`.
/// A maximum, so the same on any number of threads.
pub fn convective_rate(grid: &Grid, u: &Field, v: &Field) -> f64 {
    Region::of(grid, Stagger::Cell).max(0.0, |l| {
        let (u0, u1) = (u.at(&l, [0; 3]), u.at(&l, unit(0)));
        let (v0, v1) = (v.at(&l, [0; 3]), v.at(&l, unit(1)));
        let mut c = 0.0f64;
        for n in 0..l.len {
            let uu = u0[n].abs().max(u1[n].abs());
            let vv = v0[n].abs().max(v1[n].abs());
            c = c.max(uu / grid.dx + vv / grid.dy);
        }
        c
    })
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
/// lines in parallel, summed in line order (the same bits on any number of threads).
pub fn kinetic_energy(grid: &Grid, u: &Field, v: &Field, rho: &Field) -> f64 {
    let m = &grid.metric;
    let [e] = Region::of(grid, Stagger::Cell).sum(|l| {
        let (rw, re, rc) = (m.rx_on(&l, 0), m.rx_on(&l, 1), m.rc_on(&l, 0));
        let (uw, ue) = (u.at(&l, [0; 3]), u.at(&l, unit(0)));
        let (vs, vn) = (v.at(&l, [0; 3]), v.at(&l, unit(1)));
        let rho = rho.at(&l, [0; 3]);
        let mut e = 0.0;
        for n in 0..l.len {
            // Half of each of the cell's four faces belongs to it.
            let eu = 0.5 * (rw[n] * uw[n].powi(2) + re[n] * ue[n].powi(2)) / 2.0;
            let ev = 0.5 * rc[n] * (vs[n].powi(2) + vn[n].powi(2)) / 2.0;
            e += rho[n] * (eu + ev) * grid.dx * grid.dy;
        }
        [e]
    });
    e
}

/// `−∫ρ g·x dV` over the cells (per radian in axisymmetric geometry).
/// Lines in parallel, summed in line order (the same bits on any number of threads).
pub fn potential_energy(grid: &Grid, rho: &Field, (gx, gy): (f64, f64)) -> f64 {
    let [e] = Region::of(grid, Stagger::Cell).sum(|l| {
        let rho = rho.at(&l, [0; 3]);
        let mut e = 0.0;
        for (n, [i, j, _]) in l.indices().enumerate() {
            e -= rho[n] * (gx * grid.xc(i) + gy * grid.yc(j)) * grid.cell_volume(i);
        }
        [e]
    });
    e
}
