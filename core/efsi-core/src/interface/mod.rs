//! Interface geometry of the solid fraction φ_s: PLIC lines in cells ([`plic`]) and the exact
//! initial fractions of shapes ([`shapes`]). The advection step that uses them is a stage
//! plugin (`efsi_stages::vof`); the geometry lives here because scenes, probes and stages share it.

pub mod plic;
pub mod shapes;

pub use shapes::{Shape, fill_fraction};

use crate::{Field, Grid};

/// The phase volume `Σ φ V` over the interior (per radian in axisymmetric geometry), summed
/// with Neumaier's compensated summation so it can be compared to round-off.
pub fn phase_volume(grid: &Grid, phi: &Field) -> f64 {
    let (mut sum, mut comp) = (0.0f64, 0.0f64);
    for j in 0..grid.ny as isize {
        for i in 0..grid.nx as isize {
            let x = phi[(i, j)] * grid.cell_volume(i);
            let t = sum + x;
            comp += if sum.abs() >= x.abs() {
                (sum - t) + x
            } else {
                (x - t) + sum
            };
            sum = t;
        }
    }
    sum + comp
}
