//! The planar call forms of three of the framework's operators ([`efsi_core::operators`]) for
//! the elastic stage's two-dimensional kernels, which pass the velocity as `u, v` and a cell as
//! `(i, j)`: each is the generic operator on `[u, v]`, bit for bit. Every other stage calls
//! [`efsi_core::operators`] itself; these forms go when the elastic kernels take the velocity
//! as one slice per axis, as the others do.

use efsi_core::{Field, Grid, operators};

pub use efsi_core::operators::face_density;

/// [`operators::net_outflux`] of the planar velocity `(u, v)` out of cell `(i, j)`.
#[inline]
pub fn net_outflux(grid: &Grid, u: &Field, v: &Field, i: isize, j: isize) -> f64 {
    operators::net_outflux(grid, &[u, v], [i, j, 0])
}

/// [`operators::kinetic_energy`] of the planar velocity `(u, v)`.
pub fn kinetic_energy(grid: &Grid, u: &Field, v: &Field, rho: &Field) -> f64 {
    operators::kinetic_energy(grid, &[u, v], rho)
}
