//! The momentum advection on three-dimensional grids (`Grid::new_3d`), from the same kernels as
//! the planar and axisymmetric stage: a uniform flow kept, momentum and mass conserved in a
//! triply periodic box, a planar flow extruded along z advanced plane by plane exactly as on
//! the planar grid, the spatial operator's second order, and the time-step limit counting
//! `|w|/dz`. Ghosts are filled here by a periodic wrap (or sampled from the exact field).

use efsi_core::{Field, Geometry, Grid, Region, Stagger};
use efsi_stages::advection::{
    History, Start, advance, advective_dt, start_len, tendencies, work_len,
};
use std::f64::consts::TAU;

const FACES: [Stagger; 3] = [Stagger::XFace, Stagger::YFace, Stagger::ZFace];

/// The coordinates of index `[i, j, k]` at location `at` of `g`.
fn position(g: &Grid, at: Stagger, [i, j, k]: [isize; 3]) -> [f64; 3] {
    let o = at.nodal();
    [
        if o[0] == 1 { g.xf(i) } else { g.xc(i) },
        if o[1] == 1 { g.yf(j) } else { g.yc(j) },
        if o[2] == 1 { g.zf(k) } else { g.zc(k) },
    ]
}

/// `f` sampled at location `at` of `g`, ghosts included.
fn sample(g: &Grid, at: Stagger, f: impl Fn([f64; 3]) -> f64) -> Field {
    let mut p = Field::zeros(g);
    for n in 0..p.data().len() {
        let x = position(g, at, p.index_of(n));
        p.data_mut()[n] = f(x);
    }
    p
}

/// Periodic ghosts along every axis of `g`: each index outside `[0, n_a)` along an axis takes
/// the value of its image inside (the face `n_a` is the face `0`).
fn wrap(g: &Grid, f: &mut Field) {
    let n = g.n().map(|n| n as isize);
    for s in 0..f.data().len() {
        let i = f.index_of(s);
        let image = std::array::from_fn(|a| {
            if a < g.dims() {
                i[a].rem_euclid(n[a])
            } else {
                i[a]
            }
        });
        if image != i {
            f.data_mut()[s] = f[image];
        }
    }
}

/// Every face of each component in a periodic box: the faces `0..n_c` along its own axis.
fn periodic_faces(g: &Grid) -> Vec<Region> {
    (0..g.dims())
        .map(|c| Region::of(g, FACES[c]).range(c, 0, g.n()[c] as isize))
        .collect()
}

/// A smooth periodic function of the unit box: a sum of a few modes with coefficients from a
/// fixed pseudo-random sequence seeded by `seed` (z-independent when `planar`).
fn smooth(seed: u64, planar: bool) -> impl Fn([f64; 3]) -> f64 {
    let mut s = seed
        .wrapping_mul(6364136223846793005)
        .wrapping_add(1442695040888963407);
    let mut next = move || {
        s = s
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (s >> 11) as f64 / (1u64 << 53) as f64
    };
    let modes: Vec<([f64; 3], f64, f64)> = (0..4)
        .map(|_| {
            let k = [
                1.0 + (next() * 2.0).floor(),
                1.0 + (next() * 2.0).floor(),
                if planar { 0.0 } else { (next() * 3.0).floor() },
            ];
            (k, 0.5 * next() + 0.1, TAU * next())
        })
        .collect();
    move |x| {
        modes.iter().fold(0.0, |s, (k, a, p)| {
            s + a * (TAU * (k[0] * x[0] + k[1] * x[1] + k[2] * x[2]) + p).sin()
        })
    }
}

/// A velocity with component `c` equal to `f(c, x)` at its faces, ghosts wrapped.
fn periodic_velocity(g: &Grid, f: impl Fn(usize, [f64; 3]) -> f64) -> Vec<Field> {
    (0..g.dims())
        .map(|c| {
            let mut v = sample(g, FACES[c], |x| f(c, x));
            wrap(g, &mut v);
            v
        })
        .collect()
}

/// `steps` advection steps of `vel` with the density `rho` on a periodic box, the WholeStep
/// history kept from step to step; the work pool after the last (its first arrays are the
/// control volumes' final masses).
fn run(g: &Grid, vel: &mut [Field], rho: &Field, dt: f64, steps: usize) -> Vec<f64> {
    let cv = periodic_faces(g);
    let mut pool = vec![0.0; work_len(g)];
    let mut copies = vec![0.0; start_len(g)];
    let mut history = History::new(g);
    for _ in 0..steps {
        let mut v: Vec<&mut Field> = vel.iter_mut().collect();
        let mut fill = |v: &mut [&mut Field]| v.iter_mut().for_each(|f| wrap(g, f));
        advance(
            g,
            &cv,
            dt,
            &mut v,
            rho,
            &mut pool,
            Start::Copy(&mut copies),
            Some(&mut history),
            &mut fill,
        );
    }
    pool
}

fn cube(n: usize) -> Grid {
    Grid::new_3d([n, n, n], (0.0, 1.0), (0.0, 1.0), (0.0, 1.0))
}

/// A density between 0.5 and 2.5, smooth and periodic, ghosts wrapped.
fn density(g: &Grid, planar: bool) -> Field {
    let f = smooth(99, planar);
    let mut rho = sample(g, Stagger::Cell, |x| 1.5 + f(x).clamp(-1.0, 1.0));
    wrap(g, &mut rho);
    rho
}

#[test]
fn a_uniform_flow_is_kept_exactly_and_to_round_off_over_a_variable_density() {
    let g = Grid::new_3d([8, 6, 5], (0.0, 1.0), (0.0, 0.75), (0.0, 0.5));
    let speed = [0.7, -0.3, 0.45];
    let uniform = periodic_velocity(&g, |c, _| speed[c]);
    let mut vel = uniform.clone();
    // With a uniform density of 1 the fluxes cancel exactly and `(m u)/m` is `u`.
    run(&g, &mut vel, &Field::filled(&g, 1.0), 0.01, 3);
    for c in 0..3 {
        for l in (0..periodic_faces(&g)[c].lines()).map(|n| periodic_faces(&g)[c].line(n)) {
            assert!(
                vel[c].at(&l, [0; 3]).iter().all(|&u| u == speed[c]),
                "u_{c}"
            );
        }
    }
    let mut vel = uniform;
    run(&g, &mut vel, &density(&g, false), 0.01, 3);
    let worst = (0..3).fold(0.0f64, |m, c| {
        let r = periodic_faces(&g)[c];
        r.max(m, |l| {
            let u = vel[c].at(&l, [0; 3]);
            u.iter().fold(0.0f64, |m, u| m.max((u - speed[c]).abs()))
        })
    });
    assert!(worst < 2e-15, "variable density: {worst:e}");
}

/// A smooth bump of the unit box: 1 in the middle, 0 with all its derivatives within a
/// quarter of each side.
fn bump(x: [f64; 3]) -> f64 {
    x.iter().fold(1.0, |b, &x| {
        let s = 2.0 * (x.rem_euclid(1.0) - 0.25);
        if s <= 0.0 || s >= 1.0 {
            0.0
        } else {
            b * (4.0 - 1.0 / (s * (1.0 - s))).exp()
        }
    })
}

#[test]
fn momentum_and_mass_are_conserved_in_a_triply_periodic_box() {
    // A random smooth flow and a density between 1 and 2.8 inside the box, at rest over a
    // uniform density near its sides: every flux between two control volumes enters both.
    let g = Grid::new_3d([16, 12, 10], (0.0, 1.0), (0.0, 1.0), (0.0, 1.0));
    let f = smooth(99, false);
    let mut rho = sample(&g, Stagger::Cell, |x| {
        1.9 + 0.9 * bump(x) * f(x).clamp(-1.0, 1.0)
    });
    wrap(&g, &mut rho);
    let fields = [smooth(1, false), smooth(2, false), smooth(3, false)];
    let mut vel = periodic_velocity(&g, |c, x| bump(x) * fields[c](x));
    let cv = periodic_faces(&g);
    let len = rho.data().len();
    // Σ m u and Σ m over the control volumes of each component, with masses `m(c, line)`.
    let totals = |vel: &[Field], m: &(dyn Fn(usize, &efsi_core::Line) -> Vec<f64> + Sync)| {
        (0..3)
            .map(|c| {
                cv[c].sum(|l| {
                    let (u, m) = (vel[c].at(&l, [0; 3]), m(c, &l));
                    let p = u.iter().zip(&m).fold(0.0, |s, (u, m)| s + u * m);
                    [
                        p,
                        m.iter().sum::<f64>(),
                        u.iter().zip(&m).fold(0.0, |s, (u, m)| s + (u * m).abs()),
                    ]
                })
            })
            .collect::<Vec<_>>()
    };
    let start = totals(&vel, &|c, l| {
        let below = {
            let mut s = [0; 3];
            s[c] = -1;
            s
        };
        let (lo, hi) = (rho.at(l, below), rho.at(l, [0; 3]));
        lo.iter().zip(hi).map(|(a, b)| 0.5 * (a + b)).collect()
    });
    // One step: the next would start again from the masses of the (unchanged) cell densities,
    // which the VOF stage advects in a run.
    let pool = run(&g, &mut vel, &rho, 0.01, 1);
    let end = totals(&vel, &|c, l| {
        l.on(&pool[c * len..(c + 1) * len], [0; 3]).to_vec()
    });
    for c in 0..3 {
        let [p0, m0, scale] = start[c];
        let [p1, m1, _] = end[c];
        let dp = (p1 - p0).abs() / scale;
        let dm = (m1 - m0).abs() / m0;
        println!("component {c}: momentum {dp:e}, mass {dm:e} (relative change)");
        assert!(dp < 1e-14, "momentum {c}: relative change {dp:e}");
        assert!(dm < 1e-14, "mass {c}: relative change {dm:e}");
    }
    // The flow did change: the test is not of a fixed point.
    let moved = cv[0].max(0.0, |l| {
        let (u, u0) = (vel[0].at(&l, [0; 3]), l);
        let x: Vec<f64> = (0..u0.len)
            .map(|n| {
                let p = position(&g, Stagger::XFace, u0.index(n));
                (u[n] - bump(p) * fields[0](p)).abs()
            })
            .collect();
        x.into_iter().fold(0.0, f64::max)
    });
    assert!(moved > 1e-4, "the velocity changed by {moved:e}");
}

#[test]
fn a_planar_flow_extruded_along_z_is_advanced_plane_by_plane_as_on_the_planar_grid() {
    let (nx, ny, nz) = (14, 10, 3);
    let g2 = Grid::new(Geometry::Planar, nx, ny, (0.0, 1.0), (0.0, 1.0));
    let g3 = Grid::new_3d([nx, ny, nz], (0.0, 1.0), (0.0, 1.0), (0.0, 0.3));
    let fields = [smooth(5, true), smooth(6, true)];
    let f = |c: usize, x: [f64; 3]| if c < 2 { fields[c](x) } else { 0.0 };
    let (mut v2, mut v3) = (periodic_velocity(&g2, f), periodic_velocity(&g3, f));
    let (r2, r3) = (density(&g2, true), density(&g3, true));
    run(&g2, &mut v2, &r2, 0.02, 3);
    run(&g3, &mut v3, &r3, 0.02, 3);
    for c in 0..2 {
        let r = Region::of(&g2, FACES[c]);
        for n in 0..r.lines() {
            let l = r.line(n);
            for k in 0..nz as isize {
                for (m, [i, j, _]) in l.indices().enumerate() {
                    assert_eq!(
                        v3[c][[i, j, k]],
                        v2[c].at(&l, [0; 3])[m],
                        "u_{c}[{i}, {j}, {k}]"
                    );
                }
            }
        }
    }
    assert!(v3[2].data().iter().all(|&w| w == 0.0), "w stays zero");
    assert!(v2[0] != periodic_velocity(&g2, f)[0], "the flow moved");
}

/// `u_c`, `ρ` of the order test: smooth and monotone along every axis in the unit cube (the
/// limiter stays off its first-order branch).
fn monotone(c: usize, [x, y, z]: [f64; 3]) -> f64 {
    match c {
        0 => 1.0 + 0.3 * x + 0.2 * y + 0.1 * z + 0.05 * (x + 2.0 * y + z).sin(),
        1 => 0.5 - 0.2 * x + 0.3 * y + 0.15 * z + 0.05 * (2.0 * x - y + z).cos(),
        2 => -0.4 + 0.1 * x - 0.25 * y + 0.2 * z + 0.04 * (x + y + 2.0 * z).sin(),
        _ => 1.0 + 0.2 * x + 0.1 * y + 0.3 * z + 0.05 * (x - y + z).sin(),
    }
}

/// Largest error of the momentum tendency against `−∇·(ρ u ⊗ u)` on an `n³` grid.
fn tendency_error(n: usize) -> f64 {
    let g = cube(n);
    let vel: Vec<Field> = (0..3)
        .map(|c| sample(&g, FACES[c], |x| monotone(c, x)))
        .collect();
    let rho = sample(&g, Stagger::Cell, |x| monotone(3, x));
    let cv: Vec<Region> = (0..3).map(|c| Region::of(&g, FACES[c])).collect();
    let refs: Vec<&Field> = vel.iter().collect();
    let t = tendencies(&g, &cv, &refs, &rho);
    // ∂_a(ρ u_a u_c) by a fourth-order central difference of the exact product.
    let exact = |c: usize, x: [f64; 3]| {
        let flux = |a: usize, x: [f64; 3]| monotone(3, x) * monotone(a, x) * monotone(c, x);
        -(0..3)
            .map(|a| {
                let e = 1e-3;
                let at = |s: f64| {
                    let mut y = x;
                    y[a] += s * e;
                    flux(a, y)
                };
                (8.0 * (at(1.0) - at(-1.0)) - (at(2.0) - at(-2.0))) / (12.0 * e)
            })
            .sum::<f64>()
    };
    // The control volumes whose stencils stay off the lowest ghost layer of the face masses
    // (a copy of the next one).
    (0..3).fold(0.0f64, |m, c| {
        let inner = (0..3).fold(cv[c], |r, a| r.range(a, 1, r.hi()[a]));
        inner.max(m, |l| {
            let q = t[c][0].at(&l, [0; 3]);
            l.indices().zip(q).fold(0.0f64, |m, (i, q)| {
                m.max((q - exact(c, position(&g, FACES[c], i))).abs())
            })
        })
    })
}

#[test]
fn the_momentum_tendency_is_second_order_on_a_smooth_field() {
    let (e16, e32) = (tendency_error(16), tendency_error(32));
    let order = (e16 / e32).log2();
    println!("momentum tendency, largest error: {e16:e} (16³), {e32:e} (32³), order {order:.3}");
    assert!(
        (1.8..2.3).contains(&order),
        "errors {e16:e} (16³), {e32:e} (32³): order {order:.3}"
    );
}

#[test]
fn the_advective_limit_counts_each_axis() {
    let g = Grid::new_3d([10, 5, 4], (0.0, 1.0), (0.0, 1.0), (0.0, 2.0));
    let mut vel: Vec<Field> = (0..3).map(|_| Field::zeros(&g)).collect();
    vel[0][[3, 2, 1]] = 0.5;
    vel[1][[3, 2, 1]] = -2.0;
    vel[2][[3, 2, 2]] = 1.0;
    // Cell [3, 2, 1]: |u|/dx + |v|/dy + |w|/dz = 0.5/0.1 + 2/0.2 + 1/0.5 = 17.
    let refs: Vec<&Field> = vel.iter().collect();
    let dt = advective_dt(&g, &refs, 0.85).unwrap();
    assert!((dt - 0.05).abs() < 1e-15, "Δt = {dt}");
}
