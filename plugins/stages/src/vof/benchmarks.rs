//! The classic three-dimensional VOF transport benchmarks, without Navier–Stokes (STYLE §11):
//! the PLIC advection of [`VofAdvector`] on [`Grid::new_3d`] with the face velocities prescribed
//! directly. The stage's tests (`tests/vof_advection3d.rs`) and the `vof_transport_3d` case of
//! `cargo xtask bench-paper` both run them from here.
//!
//! - Face velocities are **face averages** of the analytic field: the exact flux through each
//!   face over its area (the fields are separable, so the integrals are closed forms). Their
//!   per-cell sum is the integral of `∇·u = 0` over the cell, so the discrete field is
//!   divergence-free to round-off. Time-dependent fields are evaluated at mid-step.
//! - Courant ½ on the largest face speed at `t = 0`: `Δt = ½ h / u_max`, fixed, the last step
//!   shortened to land on the final time.
//! - Initial fractions from the exact shapes ([`fill_fraction`]).
//! - `E1 = Σ |φ(T) − φ(0)| h³`, unnormalised (the L1 shape error of Enright et al. 2002 and
//!   Aulisa et al. 2007; Rider & Kothe's in two dimensions); [`TransportRun::volume`] is the
//!   phase volume `Σ φ(0) h³` for a normalised error.
//!
//! The two tests:
//! - [`deformation`]: LeVeque's (1996) three-dimensional deformation field as Enright et al.
//!   (2002) set it, a sphere of radius 0.15 at (0.35, 0.35, 0.35) in the unit cube, period
//!   `T = 3`, closed sides:
//!   `u = 2 sin²(πx) sin(2πy) sin(2πz) g`, `v = −sin(2πx) sin²(πy) sin(2πz) g`,
//!   `w = −sin(2πx) sin(2πy) sin²(πz) g`, `g = cos(πt/T)`; the sphere is stretched to its
//!   thinnest at `T/2` and comes back at `T`.
//! - [`slotted_sphere_revolution`]: Enright et al.'s slotted sphere ([`slotted_sphere`], their
//!   100³ case scaled to the unit cube) carried through one revolution about the axis
//!   `x = y = ½` (along z) at angular speed 2π, in the slab `|z − ½| ≤ 3/16` that holds it.

use super::{Shape, VofAdvector, VofBoundaries, fill_fraction, phase_volume};
use efsi_core::{Field, Grid, Region, Stagger};
use std::f64::consts::PI;
use std::time::Instant;

/// The radius of the deformed sphere.
pub const DEFORMATION_RADIUS: f64 = 0.15;
/// The centre of the deformed sphere.
pub const DEFORMATION_CENTER: (f64, f64, f64) = (0.35, 0.35, 0.35);
/// The period of the deformation field.
pub const DEFORMATION_PERIOD: f64 = 3.0;
/// `E1` of [`deformation`] at 32³ as this scheme measures it: the regression figure the tests
/// and the quick `bench-paper` case hold it to (within 2 %).
pub const MEASURED_DEFORMATION_32: f64 = 7.561558e-3;
/// `E1` of [`slotted_sphere_revolution`] at 32 cells per unit length, likewise.
pub const MEASURED_SLOTTED_SPHERE_32: f64 = 2.106231e-3;

/// `∫_a^b sin(2πs) ds`.
fn int_sin2pi(a: f64, b: f64) -> f64 {
    ((2.0 * PI * a).cos() - (2.0 * PI * b).cos()) / (2.0 * PI)
}

/// The three face-velocity fields of `grid`, zero.
pub fn zero_velocity(grid: &Grid) -> [Field; 3] {
    std::array::from_fn(|_| Field::zeros(grid))
}

/// Set each face-normal component `vel[a]` on its faces (interior and boundary faces) to
/// `f(a, face's lowest corner, face's highest corner)`.
fn set_faces(
    grid: &Grid,
    vel: &mut [Field; 3],
    f: impl Fn(usize, [f64; 3], [f64; 3]) -> f64 + Sync,
) {
    let at = [Stagger::XFace, Stagger::YFace, Stagger::ZFace];
    for (a, v) in vel.iter_mut().enumerate() {
        Region::of(grid, at[a]).for_each(v, |l, v| {
            for (v, [i, j, k]) in v.iter_mut().zip(l.indices()) {
                let lo = [grid.xf(i), grid.yf(j), grid.zf(k)];
                let mut hi = [grid.xf(i + 1), grid.yf(j + 1), grid.zf(k + 1)];
                hi[a] = lo[a];
                *v = f(a, lo, hi);
            }
        });
    }
}

/// LeVeque's / Enright's deformation field at time `t` (period `period`), as face averages (see
/// the module's documentation).
pub fn deformation_velocity(grid: &Grid, vel: &mut [Field; 3], t: f64, period: f64) {
    let g = (PI * t / period).cos();
    let h = grid.h();
    set_faces(grid, vel, |a, lo, hi| {
        // The component's sin² factor at the face, the average of sin(2π·) across it on the
        // two other axes.
        let s2 = (PI * lo[a]).sin().powi(2);
        let (b, c) = ((a + 1) % 3, (a + 2) % 3);
        let avg = |e: usize| int_sin2pi(lo[e], hi[e]) / h[e];
        let sign = if a == 0 { 2.0 } else { -1.0 };
        sign * s2 * avg(b) * avg(c) * g
    });
}

/// Rigid rotation about the axis `x = y = ½` (along z), one revolution per unit time, as face
/// averages (the field is linear: its value at the face centre).
pub fn rotation_velocity(grid: &Grid, vel: &mut [Field; 3]) {
    let w = 2.0 * PI;
    set_faces(grid, vel, |a, lo, hi| {
        let mid = |e: usize| 0.5 * (lo[e] + hi[e]);
        match a {
            0 => -w * (mid(1) - 0.5),
            1 => w * (mid(0) - 0.5),
            _ => 0.0,
        }
    });
}

/// The largest face speed of `vel` over the grid.
pub fn max_speed(grid: &Grid, vel: &[Field; 3]) -> f64 {
    let at = [Stagger::XFace, Stagger::YFace, Stagger::ZFace];
    (0..3)
        .map(|a| {
            Region::of(grid, at[a]).max(0.0, |l| {
                vel[a]
                    .at(&l, [0; 3])
                    .iter()
                    .fold(0.0f64, |m, v| m.max(v.abs()))
            })
        })
        .fold(0.0, f64::max)
}

/// The figures of one transport run.
#[derive(Clone, Debug)]
pub struct TransportRun {
    /// Cells per unit length (along x).
    pub n: usize,
    /// Cells of the grid.
    pub cells: usize,
    /// Time steps taken.
    pub steps: usize,
    /// `Σ |φ(T) − φ(0)| h³`.
    pub e1: f64,
    /// The phase volume `Σ φ(0) h³`.
    pub volume: f64,
    /// Largest `|V(t) − V(0)| / V(0)` over the steps.
    pub drift: f64,
    /// Largest excursion out of `[0, 1]` clipped by a sweep ([`super::AdvectStats`]).
    pub max_clipped: f64,
    /// Smallest φ at the end.
    pub min: f64,
    /// Largest φ at the end.
    pub max: f64,
    /// Largest Courant number of a sweep.
    pub cfl: f64,
    /// Wall time of the steps (s).
    pub seconds: f64,
}

impl std::fmt::Display for TransportRun {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "{} cells per unit length ({} cells): {} steps, E1 = {:.6e}, drift {:.2e}, clipped {:.2e}, φ ∈ [{:e}, {}], CFL {:.3}, {:.1} s ({:.0} ns/cell-step)",
            self.n,
            self.cells,
            self.steps,
            self.e1,
            self.drift,
            self.max_clipped,
            self.min,
            self.max,
            self.cfl,
            self.seconds,
            self.seconds * 1e9 / (self.steps as f64 * self.cells as f64)
        )
    }
}

/// Advect `phi0` on `grid` with the sides `bounds` to `t_end` with the velocity `set(vel, t)`
/// (re-evaluated at mid-step when `time_dependent`), `Δt = ½ h / u_max` with `u_max` the
/// largest face speed at `t = 0`.
pub fn transport(
    grid: &Grid,
    bounds: VofBoundaries,
    phi0: &Field,
    t_end: f64,
    set: impl Fn(&mut [Field; 3], f64),
    time_dependent: bool,
) -> TransportRun {
    let h = grid.dx.min(grid.dy).min(grid.dz);
    let mut vel = zero_velocity(grid);
    set(&mut vel, 0.0);
    let dt0 = 0.5 * h / max_speed(grid, &vel);
    let steps = (t_end / dt0 - 1e-9).ceil() as usize;
    let mut phi = phi0.clone();
    let mut adv = VofAdvector::new(grid, bounds);
    let v0 = phase_volume(grid, &phi);
    let (mut drift, mut clipped, mut cfl) = (0.0f64, 0.0f64, 0.0f64);
    let start = Instant::now();
    let mut t = 0.0;
    for n in 0..steps {
        let dt = dt0.min(t_end - t);
        if time_dependent {
            set(&mut vel, t + 0.5 * dt);
        }
        let [u, v, w] = &vel;
        let st = adv.step(grid, &mut phi, &[u, v, w], dt, n as u64);
        t += dt;
        drift = drift.max(((phase_volume(grid, &phi) - v0) / v0).abs());
        clipped = clipped.max(st.max_clipped);
        cfl = cfl.max(st.cfl);
    }
    let seconds = start.elapsed().as_secs_f64();
    let (e1, min, max) = compare(grid, &phi, phi0);
    TransportRun {
        n: grid.nx,
        cells: grid.cells(),
        steps,
        e1,
        volume: v0,
        drift,
        max_clipped: clipped,
        min,
        max,
        cfl,
        seconds,
    }
}

/// `Σ |φ − φ₀| h³`, and the smallest and largest `φ`.
fn compare(grid: &Grid, phi: &Field, phi0: &Field) -> (f64, f64, f64) {
    let cells = Region::of(grid, Stagger::Cell);
    let [e1] = cells.sum(|l| {
        let (a, b) = (phi.at(&l, [0; 3]), phi0.at(&l, [0; 3]));
        [a.iter().zip(b).map(|(a, b)| (a - b).abs()).sum::<f64>()]
    });
    let min = -cells.max(f64::NEG_INFINITY, |l| {
        phi.at(&l, [0; 3])
            .iter()
            .fold(f64::NEG_INFINITY, |m, v| m.max(-v))
    });
    let max = cells.max(f64::NEG_INFINITY, |l| {
        phi.at(&l, [0; 3])
            .iter()
            .fold(f64::NEG_INFINITY, |m, v| m.max(*v))
    });
    (e1 * grid.dx * grid.dy * grid.dz, min, max)
}

/// The unit cube with `n³` cells.
pub fn unit_cube(n: usize) -> Grid {
    Grid::new_3d([n; 3], (0.0, 1.0), (0.0, 1.0), (0.0, 1.0))
}

/// The deformation test at `n³` (see the module's documentation), closed sides. The field's
/// spatial factor is evaluated once (at `t = 0`, where `g = 1`) and scaled by `g(t)` at each
/// step: the same bits as [`deformation_velocity`] at `t`, without its trigonometry per face
/// and step.
pub fn deformation(n: usize) -> TransportRun {
    let grid = unit_cube(n);
    let mut phi0 = Field::zeros(&grid);
    let sphere = Shape::Sphere {
        center: DEFORMATION_CENTER,
        radius: DEFORMATION_RADIUS,
    };
    fill_fraction(&grid, &sphere, &mut phi0);
    let period = DEFORMATION_PERIOD;
    let mut base = zero_velocity(&grid);
    deformation_velocity(&grid, &mut base, 0.0, period);
    transport(
        &grid,
        VofBoundaries::closed(),
        &phi0,
        period,
        |vel, t| scale_faces(&grid, vel, &base, (PI * t / period).cos()),
        true,
    )
}

/// Set each face velocity of `vel` to `g` times that of `base`.
fn scale_faces(grid: &Grid, vel: &mut [Field; 3], base: &[Field; 3], g: f64) {
    let at = [Stagger::XFace, Stagger::YFace, Stagger::ZFace];
    for (a, v) in vel.iter_mut().enumerate() {
        Region::of(grid, at[a]).for_each(v, |l, v| {
            for (v, b) in v.iter_mut().zip(base[a].at(&l, [0; 3])) {
                *v = b * g;
            }
        });
    }
}

/// Enright et al.'s slotted sphere (their 100³ case scaled to the unit cube): radius 0.15 at
/// (0.5, 0.75, 0.5), a slot 0.05 wide and 0.125 deep from the bottom of the sphere, through it
/// along z.
pub fn slotted_sphere() -> Shape {
    Shape::Difference(
        Box::new(Shape::Sphere {
            center: (0.5, 0.75, 0.5),
            radius: 0.15,
        }),
        Box::new(Shape::Box {
            min: (0.475, 0.5, 0.0),
            max: (0.525, 0.725, 1.0),
        }),
    )
}

/// One revolution of the [`slotted_sphere`] about the axis `x = y = ½` at `n` cells per unit
/// length (a multiple of 16), in the slab `|z − ½| ≤ 3/16` that holds the sphere (closed sides;
/// `w = 0`).
///
/// # Panics
/// If `n` is not a multiple of 16.
pub fn slotted_sphere_revolution(n: usize) -> TransportRun {
    assert!(n.is_multiple_of(16), "{n} cells: not a multiple of 16");
    let nz = 3 * n / 8;
    let grid = Grid::new_3d([n, n, nz], (0.0, 1.0), (0.0, 1.0), (0.3125, 0.6875));
    let mut phi0 = Field::zeros(&grid);
    fill_fraction(&grid, &slotted_sphere(), &mut phi0);
    transport(
        &grid,
        VofBoundaries::closed(),
        &phi0,
        1.0,
        |vel, _| rotation_velocity(&grid, vel),
        false,
    )
}
