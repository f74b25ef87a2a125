use super::*;
use crate::{IncompleteCholesky, Pcg};

/// A small deterministic generator (xorshift64*), for reproducible random problems.
struct Rng(u64);
impl Rng {
    fn next(&mut self) -> f64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        (self.0.wrapping_mul(0x2545_F491_4F6C_DD1D) >> 11) as f64 / (1u64 << 53) as f64
    }
}

/// Sides: `[x_min, x_max, y_min, y_max]`; `Some(true)` Dirichlet, `Some(false)` Neumann;
/// `periodic` pairs override.
#[derive(Clone, Copy)]
struct Problem {
    n: usize,
    axisymmetric: bool,
    periodic_x: bool,
    dirichlet_top: bool,
    ratio: f64,
    seed: u64,
}

/// The projection's matrix `Σ_f A_f/(ρ_f h)(p_C − p_F)` on the unit square (r ∈ [0, 1]
/// with the axis at r = 0 when axisymmetric) for a density of random disks `ratio` times
/// heavier than the surroundings.
fn pressure_matrix(p: Problem) -> Stencil5 {
    let (nx, ny) = (p.n, p.n);
    let h = 1.0 / p.n as f64;
    let mut rng = Rng(p.seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) | 1);
    let disks: Vec<(f64, f64, f64)> = (0..6)
        .map(|_| (rng.next(), rng.next(), 0.05 + 0.15 * rng.next()))
        .collect();
    let rho = |i: usize, j: usize| {
        let (x, y) = ((i as f64 + 0.5) * h, (j as f64 + 0.5) * h);
        if disks
            .iter()
            .any(|&(cx, cy, r)| (x - cx).powi(2) + (y - cy).powi(2) < r * r)
        {
            p.ratio
        } else {
            1.0
        }
    };
    let rf = |i: usize| if p.axisymmetric { i as f64 * h } else { 1.0 };
    let rc = |i: usize| {
        if p.axisymmetric {
            (i as f64 + 0.5) * h
        } else {
            1.0
        }
    };
    let mut a = Stencil5::new(nx, ny, p.periodic_x, false);
    for j in 0..ny {
        for i in 0..nx {
            let k = j * nx + i;
            a.east[k] = if i + 1 < nx || p.periodic_x {
                let ie = (i + 1) % nx;
                rf(i + 1) / (0.5 * (rho(i, j) + rho(ie, j)))
            } else {
                0.0
            };
            a.north[k] = if j + 1 < ny {
                rc(i) / (0.5 * (rho(i, j) + rho(i, j + 1)))
            } else {
                0.0
            };
        }
    }
    for j in 0..ny {
        for i in 0..nx {
            let k = j * nx + i;
            let w = if i > 0 {
                a.east[k - 1]
            } else if p.periodic_x {
                a.east[k + nx - 1]
            } else {
                0.0
            };
            let s = if j > 0 { a.north[k - nx] } else { 0.0 };
            let mut d = a.east[k] + a.north[k] + w + s;
            if p.dirichlet_top && j + 1 == ny {
                d += 2.0 * rc(i) / rho(i, j);
            }
            a.diag[k] = d;
        }
    }
    a
}

fn maxabs(r: &[f64]) -> f64 {
    r.iter().fold(0.0f64, |m, v| m.max(v.abs()))
}

/// Right-hand side: random, made consistent (zero sum) when the matrix is singular.
fn rhs(p: Problem) -> Vec<f64> {
    let mut rng = Rng(p.seed + 17);
    let mut b: Vec<f64> = (0..p.n * p.n).map(|_| rng.next() - 0.5).collect();
    if !p.dirichlet_top {
        let mean = b.iter().sum::<f64>() / b.len() as f64;
        b.iter_mut().for_each(|v| *v -= mean);
    }
    b
}

const TOL: f64 = 1e-9;

fn solve_mg(p: Problem) -> (Vec<f64>, usize) {
    let mut a = pressure_matrix(p);
    let b = rhs(p);
    let mut mg = Multigrid::new(2);
    mg.setup(&a);
    let mut x = vec![0.0; b.len()];
    let tol = TOL * maxabs(&b);
    let st = Pcg::new(b.len()).solve(&mut a, &mg, &b, &mut x, tol, 500, maxabs);
    assert!(st.converged, "MG-PCG failed on n = {}: {st:?}", p.n);
    (x, st.iterations)
}

fn cases(n: usize) -> Vec<Problem> {
    let mut v = Vec::new();
    for (k, (axisymmetric, periodic_x, dirichlet_top)) in [
        (false, false, false),
        (true, false, false),
        (false, true, false),
        (false, false, true),
        (true, false, true),
        (false, true, true),
    ]
    .into_iter()
    .enumerate()
    {
        v.push(Problem {
            n,
            axisymmetric,
            periodic_x,
            dirichlet_top,
            ratio: 1e4,
            seed: 3 + k as u64,
        });
    }
    v
}

#[test]
fn coarse_matrix_of_a_constant_coefficient_is_the_rediscretised_one() {
    // Planar: unit couplings on 8×8 → unit couplings on 4×4; axisymmetric: r_f couplings.
    for axisymmetric in [false, true] {
        let p = Problem {
            n: 8,
            axisymmetric,
            periodic_x: false,
            dirichlet_top: true,
            ratio: 1.0,
            seed: 1,
        };
        let a = pressure_matrix(p);
        let mut c = Stencil5::new(1, 1, false, false);
        coarsen_into(&a, &mut c, 0.5);
        let want = pressure_matrix(Problem { n: 4, ..p });
        for k in 0..16 {
            assert!(
                (c.east[k] - want.east[k]).abs() < 1e-12,
                "{axisymmetric} e{k}"
            );
            assert!((c.north[k] - want.north[k]).abs() < 1e-12 * want.north[k].max(1.0));
            assert!((c.diag[k] - want.diag[k]).abs() < 1e-12 * want.diag[k]);
        }
    }
}

#[test]
fn mg_pcg_converges_on_density_jumps_and_matches_ic_pcg() {
    for p in cases(64) {
        let (x_mg, it_mg) = solve_mg(p);
        let mut a = pressure_matrix(p);
        let b = rhs(p);
        let mut ic = IncompleteCholesky::new();
        ic.factor(&a);
        let mut x_ic = vec![0.0; b.len()];
        let tol = TOL * maxabs(&b);
        let st = Pcg::new(b.len()).solve(&mut a, &ic, &b, &mut x_ic, tol, 20000, maxabs);
        assert!(st.converged);
        // Singular systems: compare up to the constant.
        let shift = if p.dirichlet_top {
            0.0
        } else {
            (x_mg.iter().sum::<f64>() - x_ic.iter().sum::<f64>()) / b.len() as f64
        };
        let scale = maxabs(&x_ic);
        let diff = x_mg
            .iter()
            .zip(&x_ic)
            .fold(0.0f64, |m, (a, b)| m.max((a - shift - b).abs()));
        assert!(
            diff < 1e-6 * scale,
            "solutions differ by {diff:e} (scale {scale:e})"
        );
        assert!(
            it_mg * 4 < st.iterations,
            "MG {it_mg} vs IC {} iterations",
            st.iterations
        );
        assert!(it_mg <= 30, "MG-PCG took {it_mg} iterations");
    }
}

#[test]
fn iterations_grow_less_than_20_percent_from_64_to_256() {
    for (p64, p256) in cases(64).into_iter().zip(cases(256)) {
        let (_, i64) = solve_mg(p64);
        let (_, i256) = solve_mg(p256);
        assert!(
            (i256 as f64) < 1.2 * i64 as f64,
            "{i64} → {i256} iterations (axisymmetric {}, periodic {}, Dirichlet {})",
            p64.axisymmetric,
            p64.periodic_x,
            p64.dirichlet_top
        );
    }
}

/// The table behind the module docs' figures: MG-PCG iterations for the six problem kinds
/// at density ratios 1, 1e2, 1e4 and 64² to 512² (a few seconds; run with
/// `cargo test -p efsi-linalg --lib iteration_table -- --ignored --nocapture`).
#[test]
#[ignore]
fn iteration_table() {
    for ratio in [1.0, 1e2, 1e4] {
        for n in [64, 128, 256, 512] {
            let mut line = format!("ratio {ratio:e} n {n}:");
            for mut p in cases(n) {
                p.ratio = ratio;
                let (_, it) = solve_mg(p);
                line += &format!(" {it}");
            }
            println!("{line}");
        }
    }
}

#[test]
fn one_and_two_threads_give_identical_bits() {
    let p = cases(128)[1];
    let run = |t| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(t)
            .build()
            .unwrap()
            .install(|| solve_mg(p))
    };
    let ((x1, i1), (x2, i2)) = (run(1), run(2));
    assert_eq!(i1, i2);
    assert!(x1.iter().zip(&x2).all(|(a, b)| a.to_bits() == b.to_bits()));
}

/// A hierarchy set up for a large matrix and then for a smaller one (a window of it) reuses its
/// storage and gives the same bits as a hierarchy built for the smaller one alone; and
/// [`Multigrid::apply_window`] on the window of long vectors is [`Preconditioner::apply`] on the
/// window's own vectors, leaving the rest of `z` alone.
#[test]
fn a_window_reuses_the_hierarchy_and_matches_a_fresh_one() {
    let p = Problem {
        n: 96,
        axisymmetric: true,
        periodic_x: false,
        dirichlet_top: true,
        ratio: 1e3,
        seed: 7,
    };
    let a = pressure_matrix(p);
    let (i0, j0, wx, wy) = (17, 30, 41, 53);
    let mut w = Stencil5::new(0, 0, false, false);
    a.window_into((i0, j0), (wx, wy), &mut w);
    assert_eq!(
        (w.nx, w.ny, w.periodic_x, w.periodic_y),
        (wx, wy, false, false)
    );
    // The principal submatrix: the diagonal kept, the couplings across the window's edges gone.
    for j in 0..wy {
        for i in 0..wx {
            let (k, g) = (j * wx + i, (j0 + j) * a.nx + i0 + i);
            assert_eq!(w.diag[k], a.diag[g]);
            assert_eq!(w.east[k], if i + 1 < wx { a.east[g] } else { 0.0 });
            assert_eq!(w.north[k], if j + 1 < wy { a.north[g] } else { 0.0 });
        }
    }
    let mut reused = Multigrid::new(2);
    reused.setup(&a);
    let big = reused.levels();
    reused.setup(&w);
    let mut fresh = Multigrid::new(2);
    fresh.setup(&w);
    assert_eq!(reused.levels(), fresh.levels());
    assert!(big > reused.levels());
    let mut rng = Rng(3);
    let r: Vec<f64> = (0..a.len()).map(|_| rng.next() - 0.5).collect();
    let rw: Vec<f64> = (0..wy)
        .flat_map(|j| r[(j0 + j) * a.nx + i0..(j0 + j) * a.nx + i0 + wx].to_vec())
        .collect();
    let (mut z1, mut z2) = (vec![0.0; rw.len()], vec![0.0; rw.len()]);
    fresh.apply(&rw, &mut z1);
    reused.apply(&rw, &mut z2);
    assert!(z1.iter().zip(&z2).all(|(a, b)| a.to_bits() == b.to_bits()));
    let mut z = vec![f64::NAN; a.len()];
    reused.apply_window(&r, &mut z, a.nx, j0 * a.nx + i0);
    for j in 0..a.ny {
        for i in 0..a.nx {
            let g = j * a.nx + i;
            if (j0..j0 + wy).contains(&j) && (i0..i0 + wx).contains(&i) {
                assert_eq!(z[g].to_bits(), z1[(j - j0) * wx + i - i0].to_bits());
            } else {
                assert!(z[g].is_nan(), "({i}, {j}) outside the window was written");
            }
        }
    }
    // Back to the whole matrix: the same bits as before the window.
    let mut again = Multigrid::new(2);
    again.setup(&a);
    reused.setup(&a);
    let (mut z3, mut z4) = (vec![0.0; a.len()], vec![0.0; a.len()]);
    again.apply(&r, &mut z3);
    reused.apply(&r, &mut z4);
    assert!(z3.iter().zip(&z4).all(|(a, b)| a.to_bits() == b.to_bits()));
}

/// A window spanning a periodic direction whole keeps the wrap; one that does not is closed.
#[test]
fn a_window_keeps_a_periodic_wrap_only_when_it_spans_the_direction() {
    let p = Problem {
        n: 32,
        axisymmetric: false,
        periodic_x: true,
        dirichlet_top: false,
        ratio: 10.0,
        seed: 2,
    };
    let a = pressure_matrix(p);
    assert!(a.periodic_x);
    let mut w = Stencil5::new(0, 0, false, false);
    a.window_into((0, 4), (32, 10), &mut w);
    assert!(w.periodic_x && !w.periodic_y);
    assert_eq!(w.east[31], a.east[4 * 32 + 31]);
    a.window_into((3, 4), (20, 10), &mut w);
    assert!(!w.periodic_x);
    assert_eq!(w.east[19], 0.0);
}

/// After a set-up for the whole matrix, set-ups for windows of any shape (odd, one cell wide or
/// tall, below the coarsest size) reuse every vector of the hierarchy: no pointer or capacity
/// changes, so a window that moves and resizes each step allocates nothing.
#[test]
fn windows_of_any_shape_reuse_the_whole_matrix_storage() {
    let p = Problem {
        n: 75,
        axisymmetric: true,
        periodic_x: false,
        dirichlet_top: false,
        ratio: 1e2,
        seed: 11,
    };
    let a = pressure_matrix(p);
    let mut mg = Multigrid::new(1).with_w_cycle(false).with_excess_scale(1.0);
    mg.setup(&a);
    let storage = |mg: &Multigrid| {
        let h = mg.lock();
        let mut v: Vec<(usize, usize)> = Vec::new();
        for l in &h.levels {
            for x in [&l.diag, &l.dinv, &l.ce, &l.cn, &l.x, &l.b, &l.t] {
                v.push((x.as_ptr() as usize, x.capacity()));
            }
        }
        for m in &mg.mats {
            for x in [&m.diag, &m.east, &m.north] {
                v.push((x.as_ptr() as usize, x.capacity()));
            }
        }
        for x in [&h.coarsest.l, &h.coarsest.y] {
            v.push((x.as_ptr() as usize, x.capacity()));
        }
        (v, h.levels.len(), mg.mats.len())
    };
    let before = storage(&mg);
    let mut w = Stencil5::new(0, 0, false, false);
    for (origin, shape) in [
        ((3, 5), (71, 69)),
        ((0, 0), (75, 1)),
        ((10, 0), (1, 75)),
        ((2, 2), (7, 9)),
        ((1, 1), (8, 8)),
        ((0, 0), (3, 74)),
        ((40, 30), (35, 45)),
        ((0, 0), (75, 75)),
    ] {
        a.window_into(origin, shape, &mut w);
        mg.setup(&w);
        let mut rng = Rng(5);
        let r: Vec<f64> = (0..w.len()).map(|_| rng.next() - 0.5).collect();
        let mut z = vec![0.0; w.len()];
        mg.apply(&r, &mut z);
        assert!(z.iter().all(|x| x.is_finite()), "{shape:?}");
        assert_eq!(
            storage(&mg),
            before,
            "window {shape:?} at {origin:?} reallocated"
        );
    }
}

#[test]
fn the_second_correction_buffer_lives_only_where_it_is_made() {
    let a = pressure_matrix(Problem {
        n: 64,
        axisymmetric: false,
        periodic_x: false,
        dirichlet_top: false,
        ratio: 1.0,
        seed: 3,
    });
    for w in [true, false] {
        let mut mg = Multigrid::new(2).with_w_cycle(w);
        mg.setup(&a);
        let h = mg.lock();
        assert_eq!(h.n, 4);
        for (l, lv) in h.levels[..h.n].iter().enumerate() {
            let used = w && (1..=W_LEVELS).contains(&l) && l + 1 < h.n;
            assert_eq!(lv.t.is_empty(), !used, "level {l}, W-cycle {w}");
        }
    }
}

#[test]
fn the_fine_matrix_product_is_the_stencils_bit_for_bit() {
    let mut rng = Rng(17);
    for (nx, ny) in [(7, 5), (1, 6), (6, 1), (40, 33)] {
        for (px, py) in [(false, false), (true, false), (false, true), (true, true)] {
            let mut a = Stencil5::new(nx, ny, px, py);
            for v in [&mut a.diag, &mut a.east, &mut a.north] {
                v.iter_mut().for_each(|x| *x = rng.next() + 0.1);
            }
            let x: Vec<f64> = (0..nx * ny).map(|_| rng.next() - 0.5).collect();
            let (mut y1, mut y2) = (vec![0.0; nx * ny], vec![0.0; nx * ny]);
            a.mul(&x, &mut y1);
            let mut mg = Multigrid::new(2);
            mg.setup_view(a.view());
            mg.fine_matrix().mul(&x, &mut y2);
            let bits = |y: &[f64]| y.iter().map(|v| v.to_bits()).collect::<Vec<_>>();
            assert_eq!(bits(&y1), bits(&y2), "{nx} × {ny}, periodic {px} {py}");
        }
    }
}

#[test]
fn a_matrix_set_up_already_is_recognised_bit_for_bit() {
    let mut a = pressure_matrix(Problem {
        n: 20,
        axisymmetric: true,
        periodic_x: false,
        dirichlet_top: true,
        ratio: 1e2,
        seed: 5,
    });
    let mut mg = Multigrid::new(2);
    assert!(!mg.is_set_up_for(a.view()));
    mg.setup(&a);
    assert!(mg.is_set_up_for(a.view()));
    // A closed side's coupling is not part of the matrix set up.
    a.east[19] = 7.0;
    a.north[19 * 20 + 3] = 7.0;
    assert!(mg.is_set_up_for(a.view()));
    let k = 7 * 20 + 4;
    let d = a.diag[k];
    a.diag[k] = f64::from_bits(d.to_bits() + 1);
    assert!(!mg.is_set_up_for(a.view()));
    a.diag[k] = d;
    a.north[k] *= 2.0;
    assert!(!mg.is_set_up_for(a.view()));
}

/// A seven-point matrix of one coupling per axis (`c`), zero across closed sides, its diagonal
/// summed as the projection assembles it (east, north, top, west, south, bottom).
fn uniform_3d(n: [usize; 3], periodic: [bool; 3], c: [f64; 3]) -> Stencil5 {
    let [nx, ny, nz] = n;
    let mut a = Stencil5::new_3d(nx, ny, nz, periodic);
    let on = |yes: bool, v: f64| if yes { v } else { 0.0 };
    for k in 0..nz {
        for j in 0..ny {
            for i in 0..nx {
                let q = (k * ny + j) * nx + i;
                a.east[q] = on(i + 1 < nx || periodic[0], c[0]);
                a.north[q] = on(j + 1 < ny || periodic[1], c[1]);
                a.top[q] = on(k + 1 < nz || periodic[2], c[2]);
            }
        }
    }
    for k in 0..nz {
        for j in 0..ny {
            for i in 0..nx {
                let q = (k * ny + j) * nx + i;
                let w = on(i > 0 || periodic[0], c[0]);
                let s = on(j > 0 || periodic[1], c[1]);
                let b = on(k > 0 || periodic[2], c[2]);
                a.diag[q] = a.east[q] + a.north[q] + a.top[q] + w + s + b;
            }
        }
    }
    a
}

/// A three-dimensional matrix of one coupling per axis is held as rows, not arrays, on every
/// level but the coarsest, and the preconditioner and the product give the same bits as with
/// the arrays; a matrix that differs in one coupling keeps the arrays.
#[test]
fn a_uniform_3d_matrix_is_held_as_rows_with_the_same_bits() {
    let c = [0.7, 1.3, 0.45];
    for n in [[9, 7, 6], [16, 16, 16], [5, 12, 8]] {
        for m in 0..8 {
            let periodic = [m & 1 != 0, m & 2 != 0, m & 4 != 0];
            let a = uniform_3d(n, periodic, c);
            let len = a.len();
            let mut rng = Rng(7 + m as u64);
            let r: Vec<f64> = (0..len).map(|_| rng.next() - 0.5).collect();
            let run = |rows: bool| {
                let mut mg = Multigrid::new(2);
                mg.uniform_rows = rows;
                mg.setup(&a);
                let (mut z, mut y) = (vec![0.0; len], vec![0.0; len]);
                mg.apply(&r, &mut z);
                mg.fine_matrix().mul(&r, &mut y);
                let h = mg.lock();
                let held = h.levels[..h.n]
                    .iter()
                    .map(|l| (l.uniform.is_some(), l.diag.len() + l.ce.len() + l.ct.len()))
                    .collect::<Vec<_>>();
                drop(h);
                (z, y, held, mg.is_set_up_for(a.view()))
            };
            let (z, y, held, set) = run(true);
            let (z0, y0, held0, set0) = run(false);
            let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
            assert_eq!(bits(&z), bits(&z0), "{n:?} {periodic:?}: preconditioner");
            assert_eq!(bits(&y), bits(&y0), "{n:?} {periodic:?}: product");
            assert!(set && set0, "{n:?} {periodic:?}");
            let last = held.len() - 1;
            assert!(last > 0, "{n:?}: one level");
            for (l, &(rows, arrays)) in held.iter().enumerate() {
                assert_eq!(arrays == 0, rows, "{n:?} {periodic:?} level {l}");
            }
            assert!(held[0].0 && !held[last].0, "{n:?} {periodic:?}: {held:?}");
            assert!(held0.iter().all(|&(rows, _)| !rows));
            // One coupling (and its cells' diagonals) changed: arrays.
            let mut b = a.clone();
            b.east[0] *= 2.0;
            b.diag[0] += a.east[0];
            b.diag[1] += a.east[0];
            let mut mg = Multigrid::new(2);
            mg.setup(&b);
            assert!(mg.lock().levels[0].uniform.is_none(), "{n:?} {periodic:?}");
            assert!(!mg.is_set_up_for(a.view()) && mg.is_set_up_for(b.view()));
        }
    }
}
