//! Sampling fields at points and along lines, and the time-series probes of `probes.csv`.

use crate::field::Field;
use crate::grid::Grid;
use crate::ops;
use crate::scene::ProbeSpec;
use crate::state::State;

/// Bilinear interpolation of a staggered field at `(x, y)`; `(ox, oy)` is the position of
/// index (0, 0) in cell units (`(0.5, 0.5)` for cell centres, `(0, 0.5)` for x-faces, …).
/// Ghost values are used near the boundary, so a point on a wall gets the wall value.
pub fn interpolate(grid: &Grid, f: &Field, (ox, oy): (f64, f64), (x, y): (f64, f64)) -> f64 {
    let fi = (x - grid.x0) / grid.dx - ox;
    let fj = (y - grid.y0) / grid.dy - oy;
    let i0 = (fi.floor() as isize).clamp(-1, grid.nx as isize);
    let j0 = (fj.floor() as isize).clamp(-1, grid.ny as isize);
    let wx = (fi - i0 as f64).clamp(0.0, 1.0);
    let wy = (fj - j0 as f64).clamp(0.0, 1.0);
    (1.0 - wy) * ((1.0 - wx) * f[(i0, j0)] + wx * f[(i0 + 1, j0)])
        + wy * ((1.0 - wx) * f[(i0, j0 + 1)] + wx * f[(i0 + 1, j0 + 1)])
}

/// A named field sampled at a point (names from [`crate::scene::FIELD_NAMES`]).
pub fn sample(grid: &Grid, state: &State, field: &str, at: (f64, f64)) -> f64 {
    let u = || interpolate(grid, &state.u, (0.0, 0.5), at);
    let v = || interpolate(grid, &state.v, (0.5, 0.0), at);
    match field {
        "u" => u(),
        "v" => v(),
        "speed" => u().hypot(v()),
        "p" => interpolate(grid, &state.p, (0.5, 0.5), at),
        "density" => interpolate(grid, &state.rho, (0.5, 0.5), at),
        "viscosity" => interpolate(grid, &state.mu, (0.5, 0.5), at),
        "solid_fraction" => state
            .phi
            .as_ref()
            .map_or(f64::NAN, |f| interpolate(grid, f, (0.5, 0.5), at)),
        _ => f64::NAN,
    }
}

/// Column names of a probe in `probes.csv`.
pub fn columns(p: &ProbeSpec) -> Vec<String> {
    match p {
        ProbeSpec::Point { name, .. } => vec![name.clone()],
        ProbeSpec::KineticEnergy => vec!["kinetic_energy".into()],
        ProbeSpec::MaxDivergence => vec!["max_divergence".into()],
        ProbeSpec::MaxSpeed => vec!["max_speed".into()],
        ProbeSpec::SolidVolume => vec!["solid_volume".into()],
        ProbeSpec::SolidCentroid => vec!["solid_x".into(), "solid_y".into()],
        ProbeSpec::SolidVelocity => vec!["solid_u".into(), "solid_v".into()],
    }
}

/// Append the probe's values to `out`.
pub fn evaluate(p: &ProbeSpec, grid: &Grid, state: &State, out: &mut Vec<f64>) {
    match p {
        ProbeSpec::Point { field, at, .. } => out.push(sample(grid, state, field, *at)),
        ProbeSpec::KineticEnergy => {
            out.push(ops::kinetic_energy(grid, &state.u, &state.v, &state.rho))
        }
        ProbeSpec::MaxDivergence => out.push(ops::max_abs_div(grid, &state.u, &state.v)),
        ProbeSpec::MaxSpeed => {
            let mut m = 0.0f64;
            for j in 0..grid.ny as isize {
                for i in 0..grid.nx as isize {
                    let (a, b) = ops::centre_velocity(&state.u, &state.v, i, j);
                    m = m.max(a.hypot(b));
                }
            }
            out.push(m)
        }
        ProbeSpec::SolidVolume | ProbeSpec::SolidCentroid | ProbeSpec::SolidVelocity => {
            let Some(phi) = &state.phi else {
                out.extend(std::iter::repeat_n(f64::NAN, columns(p).len()));
                return;
            };
            let m = solid_moments(grid, state, phi);
            match p {
                ProbeSpec::SolidVolume => out.push(m.volume),
                ProbeSpec::SolidCentroid => out.extend([m.centroid.0, m.centroid.1]),
                _ => out.extend([m.velocity.0, m.velocity.1]),
            }
        }
    }
}

/// Volume, centroid and volume-weighted velocity of the solid phase.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SolidMoments {
    /// `∫φ dV` (per radian when axisymmetric).
    pub volume: f64,
    /// `∫φ x dV / ∫φ dV`.
    pub centroid: (f64, f64),
    /// `∫φ u dV / ∫φ dV` with the cell-centre velocity.
    pub velocity: (f64, f64),
}

/// The moments of `phi` over the grid.
pub fn solid_moments(grid: &Grid, state: &State, phi: &Field) -> SolidMoments {
    let (mut v, mut mx, mut my, mut mu, mut mv) = (0.0, 0.0, 0.0, 0.0, 0.0);
    for j in 0..grid.ny as isize {
        for i in 0..grid.nx as isize {
            let w = phi[(i, j)] * grid.cell_volume(i);
            if w == 0.0 {
                continue;
            }
            let (a, b) = ops::centre_velocity(&state.u, &state.v, i, j);
            v += w;
            mx += w * grid.xc(i);
            my += w * grid.yc(j);
            mu += w * a;
            mv += w * b;
        }
    }
    let inv = if v > 0.0 { 1.0 / v } else { f64::NAN };
    SolidMoments {
        volume: v,
        centroid: (mx * inv, my * inv),
        velocity: (mu * inv, mv * inv),
    }
}
