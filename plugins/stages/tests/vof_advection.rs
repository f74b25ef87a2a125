//! The VOF PLIC stage on the classic advection benchmarks, without Navier–Stokes (STYLE §11).
//!
//! Set-up as in `tests/references/vof_advection/README.md`, so the L1 errors compare apples to
//! apples with Basilisk's Youngs-normal runs:
//! - unit square, initial fractions from the exact shape;
//! - face velocities from a **vertex** stream function, `u = −ψ_y`, `v = ψ_x` as one-sided
//!   differences along the face, so the discrete field is exactly divergence-free;
//! - time-dependent fields evaluated at mid-step;
//! - Courant ½ on the maximum speed, `D = ½ h / u_max`, with **Basilisk's time-step sequence**
//!   ([`basilisk_dt_sequence`]). The README says "fixed dt", but the CSV's `steps` column (523,
//!   1035, 2059, 4107 for the vortex; 900, 1789 for Zalesak) is the fixed-dt count plus 11:
//!   Basilisk's `timestep()` starts from `D/11` and grows `dt ← (dt + D/10)/1.1`, and
//!   `dtnext()` shrinks steps to land on event times. With one event at `T/2` for the vortex and
//!   deformation runs (none for Zalesak) this harness reproduces both the `steps` and the final
//!   `dt` columns of the CSV exactly for the vortex and deformation runs, and for Zalesak within
//!   one step and 2e-5 in dt ([`time_steps_match_the_reference`]). With a strictly fixed dt the
//!   errors change by ≲ 1 %, except the under-resolved N = 64 vortex (E1 = 1.2465e-2, 1.105× the
//!   reference, against 1.1191e-2, 0.992×, with the reference's steps). [`fixed_dt`] is used for the cases
//!   without a Basilisk reference;
//! - `E1 = Σ |f(T) − f(0)| h²` (Rider & Kothe's L1 shape error).
//!
//! Every step must conserve the phase volume to 1e-12 relative and keep `0 ≤ φ ≤ 1` to
//! round-off (the largest clipped excursion ≤ 1e-12). Run with `--nocapture` to see the measured
//! errors and timings. The two most expensive cases are named `slow_*` (N = 256 vortex, 4107
//! steps; Zalesak 200², 1788 steps); they run by default and the whole file takes a few seconds
//! in release on one core.

use efsi_core::{Field, Geometry, Grid};
use efsi_stages::vof::{Shape, VofAdvector, VofBoundaries, fill_fraction, phase_volume};
use std::f64::consts::PI;
use std::time::Instant;

/// Reference L1 errors `E1` of Basilisk's PLIC VOF with **Youngs** normals, hard-coded from
/// `tests/references/vof_advection/vof_plic_errors_basilisk.csv` (column `E1_sum_abs_df_h2`,
/// rows `normals = youngs`).
mod reference {
    /// `zalesak_slotted_disk_T1, youngs, N = 100`.
    pub const ZALESAK_100: f64 = 1.663774e-3;
    /// `zalesak_slotted_disk_T1, youngs, N = 200`.
    pub const ZALESAK_200: f64 = 7.197844e-4;
    /// `rider_kothe_single_vortex_T8, youngs, N = 32`.
    pub const VORTEX_T8_32: f64 = 6.356247e-2;
    /// `rider_kothe_single_vortex_T8, youngs, N = 64`.
    pub const VORTEX_T8_64: f64 = 1.127891e-2;
    /// `rider_kothe_single_vortex_T8, youngs, N = 128`.
    pub const VORTEX_T8_128: f64 = 2.232326e-3;
    /// `rider_kothe_single_vortex_T8, youngs, N = 256`.
    pub const VORTEX_T8_256: f64 = 6.067606e-4;
    /// `deformation_16vortex_T2_periodic, youngs, N = 128`.
    pub const DEFORMATION_T2_128: f64 = 7.248829e-3;
    /// Columns `steps` and `dt` (the last step): (case, N, steps, dt), to check that the
    /// time-step sequence is Basilisk's.
    pub const STEPS: [(&str, usize, usize, f64); 7] = [
        ("zalesak", 100, 900, 1.124859e-3),
        ("zalesak", 200, 1789, 5.624297e-4),
        ("vortex", 32, 523, 1.5625e-2),
        ("vortex", 64, 1035, 7.8125e-3),
        ("vortex", 128, 2059, 3.90625e-3),
        ("vortex", 256, 4107, 1.953125e-3),
        ("deformation", 128, 523, 3.90625e-3),
    ];
}

/// Allowed ratio of our `E1` to the reference.
const RATIO: f64 = 1.1;

/// Face velocities from a stream function sampled at the cell corners.
///
/// Planar: `u = −(ψ_{i,j+1} − ψ_{i,j})/Δy`, `v = (ψ_{i+1,j} − ψ_{i,j})/Δx`.
/// Axisymmetric (Stokes stream function): `r_f u = −Δ_zψ/Δz`, `r_c v = Δ_rψ/Δr`, so that
/// `Δz Δ(r_f u) + r_c Δr Δv = 0` in every cell. `u = 0` on the axis.
fn velocity_from_streamfunction(
    grid: &Grid,
    psi: impl Fn(f64, f64) -> f64,
    u: &mut Field,
    v: &mut Field,
) {
    let (nx, ny) = (grid.nx as isize, grid.ny as isize);
    let p = |i: isize, j: isize| psi(grid.xf(i), grid.yf(j));
    let axi = grid.is_axisymmetric();
    for j in 0..ny {
        for i in 0..=nx {
            let d = -(p(i, j + 1) - p(i, j)) / grid.dy;
            let rf = grid.metric.rx(i);
            u[(i, j)] = if !axi {
                d
            } else if rf > 0.0 {
                d / rf
            } else {
                0.0
            };
        }
    }
    for j in 0..=ny {
        for i in 0..nx {
            v[(i, j)] = (p(i + 1, j) - p(i, j)) / grid.dx / grid.metric.rc(i);
        }
    }
}

/// What one run measured.
#[derive(Debug)]
struct Run {
    /// `Σ |f(T) − f(0)| V` (r-weighted in axisymmetric geometry).
    e1: f64,
    /// `e1 / Σ f(0) V`.
    e_rel: f64,
    /// Largest `|V(t) − V(0)| / V(0)` over all steps.
    drift: f64,
    /// Largest clipped excursion over all steps.
    clip: f64,
    /// Largest flux Courant number.
    cfl: f64,
    steps: u64,
    /// Wall time spent in `VofAdvector::step` only.
    secs: f64,
    cells: usize,
}

impl Run {
    fn ns_per_cell_step(&self) -> f64 {
        self.secs * 1e9 / (self.cells as f64 * self.steps as f64)
    }
}

/// Advance `phi` by the time steps `dts`; `vel(t, u, v)` sets the face velocities at time `t`
/// (called at every mid-step when `unsteady`, once otherwise). Asserts conservation and bounds
/// after every step.
fn run(
    name: &str,
    grid: &Grid,
    bounds: VofBoundaries,
    phi: &mut Field,
    mut vel: impl FnMut(f64, &mut Field, &mut Field),
    unsteady: bool,
    dts: &[f64],
) -> Run {
    let phi0 = phi.clone();
    let (mut u, mut v) = (Field::zeros(grid), Field::zeros(grid));
    let mut adv = VofAdvector::new(grid, bounds);
    let vol0 = phase_volume(grid, phi);
    let mut r = Run {
        e1: 0.0,
        e_rel: 0.0,
        drift: 0.0,
        clip: 0.0,
        cfl: 0.0,
        steps: dts.len() as u64,
        secs: 0.0,
        cells: grid.cells(),
    };
    let mut t = 0.0;
    vel(0.5 * dts[0], &mut u, &mut v);
    for (n, &dt) in dts.iter().enumerate() {
        if unsteady && n > 0 {
            vel(t + 0.5 * dt, &mut u, &mut v);
        }
        let t0 = Instant::now();
        let st = adv.step(grid, phi, &[&u, &v], dt, n as u64);
        t += dt;
        r.secs += t0.elapsed().as_secs_f64();
        let drift = (phase_volume(grid, phi) - vol0).abs() / vol0;
        assert!(drift <= 1e-12, "{name}: step {n}: volume drift {drift:e}");
        assert!(
            st.max_clipped <= 1e-12,
            "{name}: step {n}: φ left [0,1] by {:e}",
            st.max_clipped
        );
        r.drift = r.drift.max(drift);
        r.clip = r.clip.max(st.max_clipped);
        r.cfl = r.cfl.max(st.cfl);
    }
    for j in 0..grid.ny as isize {
        for i in 0..grid.nx as isize {
            let f = phi[(i, j)];
            assert!((0.0..=1.0).contains(&f), "{name}: φ({i},{j}) = {f}");
            r.e1 += (f - phi0[(i, j)]).abs() * grid.cell_volume(i);
        }
    }
    r.e_rel = r.e1 / vol0;
    println!(
        "{name}: E1 = {:.4e} (Erel {:.3e}), volume drift {:.1e}, max clip {:.1e}, CFL {:.3}, {} steps, {:.2} s in step = {:.0} ns/cell-step",
        r.e1,
        r.e_rel,
        r.drift,
        r.clip,
        r.cfl,
        r.steps,
        r.secs,
        r.ns_per_cell_step()
    );
    r
}

/// `⌈T / D⌉` equal steps of `T / ⌈T / D⌉`, `D = ½ h / u_max`.
fn fixed_dt(t_end: f64, h: f64, umax: f64) -> Vec<f64> {
    let n = (t_end / (0.5 * h / umax)).ceil();
    vec![t_end / n; n as usize]
}

/// The time steps Basilisk takes to `T` with the cap `D = ½ h / u_max` (Courant ½), landing on
/// the intermediate event times `events`: its `timestep()` growth limiter
/// (`dt = (previous + 0.1 D)/1.1` while below `D`, `previous` starting at 0) followed by
/// `dtnext()`, which shrinks the step so that an integer number of steps lands on the next event
/// (tolerance `TEPS = 1e-4`). Transcribed from Basilisk `src/timestep.h` (`timestep`) and
/// `src/grid/events.h` (`dtnext`).
fn basilisk_dt_sequence(t_end: f64, h: f64, umax: f64, events: &[f64]) -> Vec<f64> {
    let cap = 0.5 * h / umax;
    let (mut t, mut previous) = (0.0f64, 0.0f64);
    let mut dts = Vec::new();
    while t_end - t > 1e-12 * t_end {
        let tnext = events
            .iter()
            .copied()
            .find(|&e| e > t + 1e-12 * t_end)
            .unwrap_or(t_end);
        let mut dt = cap;
        if dt > previous {
            dt = (previous + 0.1 * dt) / 1.1;
        }
        previous = dt;
        let n = ((tnext - t) / dt) as u64;
        if n == 0 {
            dt = tnext - t;
        } else {
            let dt1 = (tnext - t) / n as f64;
            if dt1 > dt * (1.0 + 1e-4) {
                dt = (tnext - t) / (n + 1) as f64;
            } else if dt1 < dt {
                dt = dt1;
            }
        }
        dts.push(dt);
        t += dt;
    }
    dts
}

fn unit_square(n: usize) -> Grid {
    Grid::new(Geometry::Planar, n, n, (0.0, 1.0), (0.0, 1.0))
}

/// The slotted disk: R = 0.15 at (0.5, 0.75), slot |x − 0.5| < 0.025 up to y = 0.85.
fn zalesak_shape() -> Shape {
    Shape::Difference(
        Box::new(Shape::Disk {
            center: (0.5, 0.75),
            radius: 0.15,
        }),
        Box::new(Shape::Rectangle {
            min: (0.475, 0.5),
            max: (0.525, 0.85),
        }),
    )
}

/// Zalesak: one counter-clockwise revolution, ω = 2π about (½, ½), ψ = π r².
fn zalesak(n: usize) -> Run {
    let g = unit_square(n);
    let mut phi = Field::zeros(&g);
    fill_fraction(&g, &zalesak_shape(), &mut phi);
    // Max speed over the square: ω·|corner − centre| = 2π·√½.
    let dts = basilisk_dt_sequence(1.0, g.dx, PI * 2f64.sqrt(), &[]);
    let psi = |x: f64, y: f64| PI * ((x - 0.5).powi(2) + (y - 0.5).powi(2));
    let gg = g.clone();
    run(
        &format!("zalesak {n}²"),
        &g,
        VofBoundaries::closed(),
        &mut phi,
        move |_, u, v| velocity_from_streamfunction(&gg, psi, u, v),
        false,
        &dts,
    )
}

/// Rider–Kothe single vortex: circle R = 0.15 at (0.5, 0.75),
/// ψ = (1/π) sin²(πx) sin²(πy) cos(πt/T), error at t = T.
fn single_vortex(n: usize, t_end: f64) -> Run {
    let g = unit_square(n);
    let mut phi = Field::zeros(&g);
    let disk = Shape::Disk {
        center: (0.5, 0.75),
        radius: 0.15,
    };
    fill_fraction(&g, &disk, &mut phi);
    let dts = basilisk_dt_sequence(t_end, g.dx, 1.0, &[0.5 * t_end]);
    let (mut u0, mut v0) = (Field::zeros(&g), Field::zeros(&g));
    let psi = |x: f64, y: f64| (PI * x).sin().powi(2) * (PI * y).sin().powi(2) / PI;
    velocity_from_streamfunction(&g, psi, &mut u0, &mut v0);
    run(
        &format!("single vortex T={t_end} {n}²"),
        &g,
        VofBoundaries::closed(),
        &mut phi,
        |t, u, v| {
            let c = (PI * t / t_end).cos();
            for (d, s) in u.data_mut().iter_mut().zip(u0.data()) {
                *d = c * s;
            }
            for (d, s) in v.data_mut().iter_mut().zip(v0.data()) {
                *d = c * s;
            }
        },
        true,
        &dts,
    )
}

fn check(r: &Run, reference: f64) {
    let ratio = r.e1 / reference;
    println!("    E1 / Basilisk-Youngs = {ratio:.3}");
    assert!(
        ratio <= RATIO,
        "E1 = {:.4e} is {ratio:.3}× the reference {reference:.4e}",
        r.e1
    );
}

#[test]
fn zalesak_100() {
    check(&zalesak(100), reference::ZALESAK_100);
}

/// Expensive: 200², 1788 steps.
#[test]
fn slow_zalesak_200() {
    check(&zalesak(200), reference::ZALESAK_200);
}

#[test]
fn single_vortex_t8_32() {
    check(&single_vortex(32, 8.0), reference::VORTEX_T8_32);
}

#[test]
fn single_vortex_t8_64() {
    check(&single_vortex(64, 8.0), reference::VORTEX_T8_64);
}

#[test]
fn single_vortex_t8_128() {
    check(&single_vortex(128, 8.0), reference::VORTEX_T8_128);
}

/// Expensive: 256², 4107 steps (the timing quoted in the stage's docs comes from this run).
#[test]
fn slow_single_vortex_t8_256() {
    check(&single_vortex(256, 8.0), reference::VORTEX_T8_256);
}

/// The 16-vortex deformation field in a periodic box: exercises periodic sides.
#[test]
fn deformation_periodic_128() {
    let n = 128;
    let t_end = 2.0;
    let g = unit_square(n);
    let mut phi = Field::zeros(&g);
    let disk = Shape::Disk {
        center: (0.5, 0.75),
        radius: 0.15,
    };
    fill_fraction(&g, &disk, &mut phi);
    let dts = basilisk_dt_sequence(t_end, g.dx, 1.0, &[0.5 * t_end]);
    let (mut u0, mut v0) = (Field::zeros(&g), Field::zeros(&g));
    let psi =
        |x: f64, y: f64| (4.0 * PI * (x + 0.5)).sin() * (4.0 * PI * (y + 0.5)).cos() / (4.0 * PI);
    velocity_from_streamfunction(&g, psi, &mut u0, &mut v0);
    let r = run(
        "deformation T=2 periodic 128²",
        &g,
        VofBoundaries::periodic(true, true),
        &mut phi,
        |t, u, v| {
            let c = (PI * t / t_end).cos();
            for (d, s) in u.data_mut().iter_mut().zip(u0.data()) {
                *d = c * s;
            }
            for (d, s) in v.data_mut().iter_mut().zip(v0.data()) {
                *d = c * s;
            }
        },
        true,
        &dts,
    );
    check(&r, reference::DEFORMATION_T2_128);
}

/// A sphere of radius 0.2 centred on the axis, carried along z by a uniform flow through one
/// period of a z-periodic box (64 cells): r-weighted volume to round-off, small shape error.
#[test]
fn axisymmetric_sphere_translation() {
    let (nr, nz) = (32, 64);
    let g = Grid::new(Geometry::Axisymmetric, nr, nz, (0.0, 0.5), (0.0, 1.0));
    let mut phi = Field::zeros(&g);
    let sphere = Shape::Disk {
        center: (0.0, 0.5),
        radius: 0.2,
    };
    fill_fraction(&g, &sphere, &mut phi);
    let exact = 2.0 / 3.0 * 0.2f64.powi(3);
    assert!((phase_volume(&g, &phi) - exact).abs() < 1e-15);
    let dts = fixed_dt(1.0, g.dy, 1.0);
    let r = run(
        "axisymmetric sphere, 64 cells along z",
        &g,
        VofBoundaries::periodic(false, true),
        &mut phi,
        |_, u, v| {
            u.fill(0.0);
            v.fill(1.0);
        },
        false,
        &dts,
    );
    // Reported, with a loose guard: the planar counterpart (below) is the yardstick.
    assert!(r.e_rel < 0.02, "relative shape error {:.3e}", r.e_rel);
}

/// The planar counterpart of the sphere translation (a disk through 64 cells), for comparison.
#[test]
fn planar_disk_translation() {
    let (nx, ny) = (32, 64);
    let g = Grid::new(Geometry::Planar, nx, ny, (0.0, 0.5), (0.0, 1.0));
    let mut phi = Field::zeros(&g);
    fill_fraction(
        &g,
        &Shape::Disk {
            center: (0.25, 0.5),
            radius: 0.2,
        },
        &mut phi,
    );
    let dts = fixed_dt(1.0, g.dy, 1.0);
    let r = run(
        "planar disk, 64 cells along y",
        &g,
        VofBoundaries::periodic(false, true),
        &mut phi,
        |_, u, v| {
            u.fill(0.0);
            v.fill(1.0);
        },
        false,
        &dts,
    );
    assert!(r.e_rel < 0.02, "relative shape error {:.3e}", r.e_rel);
}

/// An axisymmetric reversing deformation (Stokes stream function
/// ψ = r² sin²(πr) sin²(πz) cos(πt/T)/π on the unit r–z box): exercises the r-fluxes, the axis
/// and the r-weighted inverse α. Conservation and bounds are asserted every step; the shape
/// error at t = T is reported with a loose guard.
#[test]
fn axisymmetric_reversing_deformation() {
    let n = 64;
    let t_end = 2.0;
    let g = Grid::new(Geometry::Axisymmetric, n, n, (0.0, 1.0), (0.0, 1.0));
    let mut phi = Field::zeros(&g);
    let sphere = Shape::Disk {
        center: (0.0, 0.4),
        radius: 0.2,
    };
    fill_fraction(&g, &sphere, &mut phi);
    let (mut u0, mut v0) = (Field::zeros(&g), Field::zeros(&g));
    let psi = |r: f64, z: f64| r * r * (PI * r).sin().powi(2) * (PI * z).sin().powi(2) / PI;
    velocity_from_streamfunction(&g, psi, &mut u0, &mut v0);
    let umax = u0.max_abs(efsi_core::Stagger::XFace, n, n).max(v0.max_abs(
        efsi_core::Stagger::YFace,
        n,
        n,
    ));
    let dts = fixed_dt(t_end, g.dx, umax);
    let r = run(
        "axisymmetric reversing deformation 64²",
        &g,
        VofBoundaries::closed(),
        &mut phi,
        |t, u, v| {
            let c = (PI * t / t_end).cos();
            for (d, s) in u.data_mut().iter_mut().zip(u0.data()) {
                *d = c * s;
            }
            for (d, s) in v.data_mut().iter_mut().zip(v0.data()) {
                *d = c * s;
            }
        },
        true,
        &dts,
    );
    assert!(r.e_rel < 0.05, "relative shape error {:.3e}", r.e_rel);
}

/// The harness takes the same time steps as the reference runs (their count is in the CSV).
#[test]
fn time_steps_match_the_reference() {
    for (case, n, steps, last_dt) in reference::STEPS {
        let (t_end, umax, events) = match case {
            "zalesak" => (1.0, PI * 2f64.sqrt(), vec![]),
            "vortex" => (8.0, 1.0, vec![4.0]),
            _ => (2.0, 1.0, vec![1.0]),
        };
        let dts = basilisk_dt_sequence(t_end, 1.0 / n as f64, umax, &events);
        // Exact for the vortex and deformation runs. Zalesak's reference took one step more
        // (900, 1789; we take 899, 1788) and its last dt differs by 2e-5: its script had some
        // event we do not know of. One step in 900 of a steady rotation changes E1 by < 0.1 %
        // (a fixed-dt run of 889 steps gives 1.678e-3 against 1.680e-3).
        let (tol_n, tol_dt) = if case == "zalesak" {
            (1, 2e-5)
        } else {
            (0, 1e-12)
        };
        assert!(
            dts.len().abs_diff(steps) <= tol_n,
            "{case} {n}: {} steps, reference {steps}",
            dts.len()
        );
        let last = *dts.last().unwrap();
        assert!(
            (last / last_dt - 1.0).abs() <= tol_dt,
            "{case} {n}: last dt {last:e}, reference {last_dt:e}"
        );
        assert!((dts.iter().sum::<f64>() - t_end).abs() < 1e-12 * t_end);
    }
}

/// Shapes are read from RON scenes; unknown fields are errors.
#[test]
fn shapes_deserialize_strictly() {
    let s: Shape = ron::from_str(
        "Difference(Disk(center: (0.5, 0.75), radius: 0.15), Rectangle(min: (0.475, 0.5), max: (0.525, 0.85)))",
    )
    .unwrap();
    assert_eq!(s, zalesak_shape());
    let u: Shape = ron::from_str("Union([HalfPlane(normal: (0.0, 1.0), offset: 0.2), Disk(center: (0.0, 0.5), radius: 0.1)])").unwrap();
    assert!(matches!(u, Shape::Union(ref v) if v.len() == 2));
    let err =
        ron::from_str::<Shape>("Disk(center: (0.5, 0.5), radius: 0.1, colour: 3)").unwrap_err();
    assert!(err.to_string().contains("colour"), "{err}");
}
