//! Bodies transported on their own windows ([`efsi_stages::vof::bodies`]), without
//! Navier–Stokes, on prescribed discretely divergence-free velocities:
//!
//! - a window step is the full-grid step bit for bit (planar and axisymmetric in a vortex,
//!   three-dimensional in the deformation field), through several moves of the window;
//! - two disks driven against each other by a stagnation-point flow stay two fields of one
//!   piece each, each with its volume to round-off and `Σ φ_k ≤ 1 + 1e-12`, where one fraction
//!   for both (their sum) becomes a single piece.

use efsi_core::{Field, Geometry, Grid, Region, Stagger};
use efsi_stages::vof::benchmarks::{deformation_velocity, max_speed, unit_cube, zero_velocity};
use efsi_stages::vof::bodies::BodyWindow;
use efsi_stages::vof::{Shape, VofAdvector, VofBoundaries, fill_fraction, phase_volume};

/// Face velocities from the stream function `psi` at the cell corners: `r_f Δz u = Δ_z ψ` on
/// x-faces, `r_c Δr v = −Δ_r ψ` on y-faces (r = 1 in planar geometry), so every cell's net
/// volume flux cancels to round-off.
fn stream(g: &Grid, psi: impl Fn(f64, f64) -> f64) -> (Field, Field) {
    let (mut u, mut v) = (Field::zeros(g), Field::zeros(g));
    let (nx, ny) = (g.nx as isize, g.ny as isize);
    let (xf, yf) = (|i: isize| g.xf(i), |j: isize| g.y0 + j as f64 * g.dy);
    for j in 0..ny {
        for i in 0..=nx {
            let r = g.metric.rx(i);
            u[(i, j)] = if r > 0.0 {
                (psi(xf(i), yf(j + 1)) - psi(xf(i), yf(j))) / (r * g.dy)
            } else {
                0.0
            };
        }
    }
    for j in 0..=ny {
        for i in 0..nx {
            v[(i, j)] = -(psi(xf(i + 1), yf(j)) - psi(xf(i), yf(j))) / (g.metric.rc(i) * g.dx);
        }
    }
    (u, v)
}

/// The largest `|φ_a − φ_b|` over the interior cells, compared as bits (0 when equal).
fn differing_cells(g: &Grid, a: &Field, b: &Field) -> usize {
    let cells = Region::of(g, Stagger::Cell);
    let mut n = 0;
    for k in 0..cells.lines() {
        let l = cells.line(k);
        for (x, y) in a.at(&l, [0; 3]).iter().zip(b.at(&l, [0; 3])) {
            n += usize::from(x.to_bits() != y.to_bits());
        }
    }
    n
}

/// Advance one body on the full grid and on its window side by side for `steps` steps of
/// `dt` in the velocity `vel(step)`; assert the window's fraction equals the full grid's bit
/// for bit after every step, and return how often the window moved.
fn window_equals_full(
    g: &Grid,
    shape: &Shape,
    steps: u64,
    dt: f64,
    vel: impl Fn(u64) -> Vec<Field>,
) -> usize {
    let mut full = Field::zeros(g);
    fill_fraction(g, shape, &mut full);
    let bounds = VofBoundaries::closed();
    let mut window = BodyWindow::around(g, bounds, &full).unwrap();
    assert!(window.cells() < g.n().iter().product::<usize>());
    let mut advector = VofAdvector::new(g, bounds);
    let (mut moves, mut at) = (0, window.extent());
    for s in 0..steps {
        let v = vel(s);
        let v: Vec<&Field> = v.iter().collect();
        let a = advector.step(g, &mut full, &v, dt, s);
        let b = window.step(g, &v, dt, s).unwrap();
        assert!(a.cfl <= 0.5, "Courant number {}", a.cfl);
        assert_eq!(
            a.clipped_volume.to_bits(),
            b.clipped_volume.to_bits(),
            "step {s}"
        );
        let diff = differing_cells(g, &full, &window.on_parent(g));
        assert_eq!(diff, 0, "step {s}: {diff} cells differ");
        if window.extent() != at {
            moves += 1;
            at = window.extent();
        }
    }
    moves
}

#[test]
fn a_window_step_is_the_full_grid_step_bit_for_bit_planar_and_axisymmetric() {
    use std::f64::consts::PI;
    for geometry in [Geometry::Planar, Geometry::Axisymmetric] {
        let g = Grid::new(geometry, 48, 48, (0.0, 1.0), (0.0, 1.0));
        // The single vortex sin²(πx) sin²(πy)/π (in r–z about the axis).
        let psi = |x: f64, y: f64| (PI * x).sin().powi(2) * (PI * y).sin().powi(2) / PI;
        let (u, v) = stream(&g, psi);
        let speed = [&u, &v]
            .iter()
            .map(|f| f.data().iter().fold(0.0f64, |m, x| m.max(x.abs())))
            .fold(0.0, f64::max);
        // Courant ≤ ¼ on the faces (up to ½ next to the axis).
        let dt = 0.25 * g.dx / speed;
        let shape = match geometry {
            Geometry::Planar => Shape::Disk {
                center: (0.5, 0.75),
                radius: 0.12,
            },
            _ => Shape::Disk {
                center: (0.0, 0.7),
                radius: 0.12,
            },
        };
        let moves = window_equals_full(&g, &shape, 160, dt, |_| vec![u.clone(), v.clone()]);
        println!("{geometry:?}: the window moved {moves} times in 160 steps");
        assert!(moves >= 2, "{geometry:?}: the window moved {moves} times");
    }
}

#[test]
fn a_window_step_is_the_full_grid_step_bit_for_bit_in_three_dimensions() {
    let g = unit_cube(24);
    let shape = Shape::Sphere {
        center: (0.35, 0.35, 0.35),
        radius: 0.12,
    };
    let period = 3.0;
    let mut base = zero_velocity(&g);
    deformation_velocity(&g, &mut base, 0.0, period);
    let dt = 0.4 * g.dx / max_speed(&g, &base);
    let moves = window_equals_full(&g, &shape, 40, dt, |s| {
        let mut v = zero_velocity(&g);
        deformation_velocity(&g, &mut v, s as f64 * dt, period);
        v.into_iter().collect()
    });
    println!("3-D: the window moved {moves} times in 40 steps");
    assert!(moves >= 1, "the window moved {moves} times");
}

/// Face-connected regions of cells with `φ > 1e-6` (the probes' piece threshold).
fn pieces(g: &Grid, phi: &Field) -> usize {
    let (nx, ny) = (g.nx as isize, g.ny as isize);
    let mut seen = vec![false; (nx * ny) as usize];
    let holds = |i: isize, j: isize| phi[(i, j)] > 1e-6;
    let mut count = 0;
    for j0 in 0..ny {
        for i0 in 0..nx {
            if seen[(j0 * nx + i0) as usize] || !holds(i0, j0) {
                continue;
            }
            count += 1;
            let mut stack = vec![(i0, j0)];
            seen[(j0 * nx + i0) as usize] = true;
            while let Some((i, j)) = stack.pop() {
                for (a, b) in [(i - 1, j), (i + 1, j), (i, j - 1), (i, j + 1)] {
                    if a < 0 || b < 0 || a >= nx || b >= ny {
                        continue;
                    }
                    let s = &mut seen[(b * nx + a) as usize];
                    if !*s && holds(a, b) {
                        *s = true;
                        stack.push((a, b));
                    }
                }
            }
        }
    }
    count
}

#[test]
fn two_bodies_driven_together_stay_two_fields_of_one_piece_each() {
    // The stagnation-point flow u = −(x − ½), v = y − ½ (exactly divergence-free on the faces
    // up to round-off) drives two disks at x = ½ ∓ 0.18 against the plane x = ½ until each
    // reaches the cell next to it.
    let n = 64;
    let g = Grid::new(Geometry::Planar, n, n, (0.0, 1.0), (0.0, 1.0));
    let (mut u, mut v) = (Field::zeros(&g), Field::zeros(&g));
    for j in 0..=n as isize {
        for i in 0..=n as isize {
            u[(i, j)] = -(g.xf(i) - 0.5);
            v[(i, j)] = g.y0 + j as f64 * g.dy - 0.5;
        }
    }
    let bounds = VofBoundaries::closed();
    let mut bodies: Vec<BodyWindow> = [0.32, 0.68]
        .map(|x| {
            let mut phi = Field::zeros(&g);
            let disk = Shape::Disk {
                center: (x, 0.5),
                radius: 0.15,
            };
            fill_fraction(&g, &disk, &mut phi);
            BodyWindow::around(&g, bounds, &phi).unwrap()
        })
        .into();
    let volume0: Vec<f64> = bodies.iter().map(|b| b.volume(&g)).collect();
    let dt = 0.4 * g.dx / 0.5;
    let steps = (0.9 / dt).ceil() as u64;
    let mut worst = (0.0f64, 0.0f64);
    for s in 0..steps {
        for b in &mut bodies {
            b.step(&g, &[&u, &v], dt, s).unwrap();
        }
        let each: Vec<Field> = bodies.iter().map(|b| b.on_parent(&g)).collect();
        for (k, (phi, v0)) in each.iter().zip(&volume0).enumerate() {
            assert_eq!(pieces(&g, phi), 1, "step {s}: body {k} broke up");
            let drift = (phase_volume(&g, phi) - v0).abs() / v0;
            worst.0 = worst.0.max(drift);
        }
        let mut sum = each[0].clone();
        bodies[1].add_into(&mut sum, 1.0);
        let most = sum.data().iter().fold(0.0f64, |m, x| m.max(*x));
        worst.1 = worst.1.max(most);
        assert!(most <= 1.0 + 1e-12, "step {s}: Σφ_k = {most}");
    }
    println!(
        "{steps} steps: worst relative volume drift {:e}, max Σφ_k {}",
        worst.0, worst.1
    );
    assert!(worst.0 <= 1e-13, "volume drift {:e}", worst.0);
    // Each body reached the cell next to the plane x = ½, so one fraction for both would be
    // one piece: the two bodies touch across that face and only their own fields keep them
    // apart.
    let mut sum = bodies[0].on_parent(&g);
    bodies[1].add_into(&mut sum, 1.0);
    let mid = n as isize / 2;
    let touching = (0..n as isize)
        .filter(|&j| sum[(mid - 1, j)] > 1e-6 && sum[(mid, j)] > 1e-6)
        .count();
    assert!(touching > 0, "the bodies did not reach the mid plane");
    assert_eq!(pieces(&g, &sum), 1, "the sum of the fractions is one piece");
}
