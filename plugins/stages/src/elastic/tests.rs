use super::limits::wave_limit;
use super::*;
use crate::solid::{SceneSolid, Shape};
use efsi_core::Scene;
use efsi_laws_host::ConstitutiveLaw;
use efsi_laws_host::NeoHookeanReference;
use efsi_laws_host::Sym;

/// A layer of full cells (rows 0–2) under a row of cells a third full (row 3) on an 8×8
/// grid, μ_f = 1, μ_s = 0.5; B is `bs` in every cell holding solid, I elsewhere. For each
/// shipped law, the stress the stage applies is the law's at the solid's own B times the
/// documented weight: `φ^{1/2}` at a centre (less the rest stress), `a/(aκ)` at a corner of
/// solid fraction `a` (the PLIC quarters: 1 and 0.6 around the corners of row 3, a = 0.8); and
/// the tangent's increment is the law's tangent at B times the same weight.
#[test]
fn each_shipped_law_sees_the_solids_own_deformation_at_the_interface() {
    let text = r#"Scene(
name: "interface",
domain: (x: (0.0, 1.0), y: (0.0, 1.0)),
grid: (nx: 8, ny: 8),
time: (end: 1.0),
fluid: (density: 1.0, viscosity: 1.0),
boundaries: (x_min: NoSlip, x_max: NoSlip, y_min: NoSlip, y_max: NoSlip),
)"#;
    let scene = Scene::from_str_at(text, std::path::Path::new("interface.ron")).unwrap();
    let grid = Grid::new(scene.geometry, 8, 8, scene.domain.x, scene.domain.y);
    let bc = BoundarySet::new(&scene.boundaries, &grid);
    let (mu_f, mu_s, phi3) = (1.0, 0.5, 0.3);
    let mut phi = Field::zeros(&grid);
    // Ghosts included: rows below 3 solid, row 3 cut, the rest fluid.
    Region::whole(&grid).for_each(&mut phi, |l, row| {
        row.fill(match l.start[1] {
            ..3 => 1.0,
            3 => phi3,
            _ => 0.0,
        })
    });
    // A deformation with stretch and shear (det B ≠ 1 does not matter here).
    let bs: Sym = [1.3, 0.85, 0.95, 0.2];
    let laws: [(&str, &[(&str, f64)]); 3] = [
        ("neo_hookean", &[("G", 2.0)]),
        ("mooney_rivlin", &[("C1", 0.7), ("C2", 0.2), ("C3", 0.4)]),
        ("saint_venant_kirchhoff", &[("lambda", 4.0), ("mu", 1.8)]),
    ];
    for (name, params) in laws {
        let params = params.iter().map(|&(k, v)| (k.to_string(), v)).collect();
        let law = efsi_laws_host::load_law(name, &params, std::path::Path::new("."))
            .unwrap_or_else(|e| panic!("{name}: {e}"));
        let mut k = Kernels::new(&grid, &bc, mu_f, mu_s);
        k.set_weights(&phi);
        let mut b: [Field; 4] = std::array::from_fn(|_| Field::zeros(&grid));
        let whole = Region::whole(&grid);
        for (c, b) in b.iter_mut().enumerate() {
            let (wt, fluid) = if c == 3 {
                (&k.edge[0].wc, 0.0)
            } else {
                (&k.w, 1.0)
            };
            whole.for_each(b, |l, b| {
                for (b, w) in b.iter_mut().zip(wt.at(&l, [0; 3])) {
                    *b = if *w > 0.0 { bs[c] } else { fluid };
                }
            });
        }
        let mut tau: [Field; 4] = std::array::from_fn(|_| Field::zeros(&grid));
        k.evaluate(&law, &b, &mut tau, true).unwrap();
        let (mut ts, mut ti) = ([[0.0; 4]], [[0.0; 4]]);
        let mut js = [[0.0; 16]];
        law.evaluate(&[bs], &mut ts, Some(&mut js)).unwrap();
        law.evaluate(&[[1.0, 1.0, 1.0, 0.0]], &mut ti, None)
            .unwrap();
        let close = |got: f64, want: f64, what: &str| {
            assert!(
                (got - want).abs() <= 1e-12 * (1.0 + want.abs()),
                "{name}: {what}: {got:e} ≠ {want:e}"
            );
        };
        // The interface centre (row 3) and a full one (row 1).
        for (j, w) in [(3, phi3.sqrt()), (1, 1.0)] {
            for c in 0..3 {
                close(
                    tau[c][[4, j, 0]],
                    w * (ts[0][c] - ti[0][c]),
                    "centre stress",
                );
            }
        }
        // The corners of row 3: a = (1 + 1 + 0.6 + 0.6)/4 = 0.8; inside the layer a = 1.
        let a = 0.8;
        let ak = a + mu_s * (1.0 - a) / mu_f;
        close(
            tau[3][[4, 3, 0]],
            a / ak * ts[0][3],
            "interface corner shear",
        );
        close(tau[3][[4, 2, 0]], ts[0][3], "solid corner shear");
        // Above row 3 the corners' quarters hold no solid: no shear stress.
        close(tau[3][[4, 4, 0]], 0.0, "corner without solid");
        // The tangent: a uniform increment db gives the law's J·db times the same weights.
        let db: Sym = [0.01, -0.02, 0.005, 0.03];
        let mut dbf: [Field; 4] = std::array::from_fn(|_| Field::zeros(&grid));
        for (c, f) in dbf.iter_mut().enumerate() {
            f.fill(db[c]);
        }
        let mut dtau: [Field; 4] = std::array::from_fn(|_| Field::zeros(&grid));
        k.apply_tangent(&dbf, &mut dtau);
        let jdb = |r: usize| (0..4).map(|c| js[0][4 * r + c] * db[c]).sum::<f64>();
        for c in 0..3 {
            close(dtau[c][[4, 3, 0]], phi3.sqrt() * jdb(c), "centre tangent");
        }
        close(
            dtau[3][[4, 3, 0]],
            a / ak * jdb(3),
            "interface corner tangent",
        );
    }
}

/// [`wave_limit`] of `scene` once its sections are checked by the shipped plugins.
fn limits_of(
    scene: &Scene,
    grid: &Grid,
    law: &dyn efsi_laws_host::ConstitutiveLaw,
) -> Result<super::limits::WaveLimits, String> {
    let mut scene = scene.clone();
    let options = efsi_core::scene::options::check_sections(&mut scene, &crate::builtin())
        .map_err(|(f, m)| format!("{f}: {m}"))?;
    wave_limit(&scene, &options, grid, law)
}

#[test]
fn laws_without_a_stable_rest_state_and_fixed_steps_beyond_the_wave_limit_are_refused() {
    let text = r#"Scene(
name: "limits",
domain: (x: (0.0, 1.0), y: (0.0, 1.0)),
grid: (nx: 16, ny: 16),
time: (end: 1.0, fixed_dt: 0.01),
fluid: (density: 1.0, viscosity: 1.0),
solid: (shape: Disk(center: (0.5, 0.5), radius: 0.25), density: 4.0,
        law: (name: "neo_hookean", parameters: {"G": 100.0})),
boundaries: (x_min: NoSlip, x_max: NoSlip, y_min: NoSlip, y_max: NoSlip),
)"#;
    let mut scene = Scene::from_str_at(text, std::path::Path::new("limits.ron")).unwrap();
    scene
        .numerics
        .update(|o: &mut crate::elastic::ElasticOptions| {
            o.coupling = crate::elastic::ElasticCoupling::Split
        })
        .unwrap();
    let grid = Grid::new(scene.geometry, 16, 16, scene.domain.x, scene.domain.y);
    // Neo-Hookean with a negative shear modulus: no stable rest state.
    let e = limits_of(&scene, &grid, &NeoHookeanReference { g: -1.0 }).unwrap_err();
    assert!(
        e.contains("shear stiffness at rest") && e.contains("not positive"),
        "{e}"
    );
    // c = √(100/4) = 5, h = 1/16: the limit is 4·h/c = 0.05; 0.01 passes, 0.1 is refused.
    let law = NeoHookeanReference { g: 100.0 };
    let dt = limits_of(&scene, &grid, &law).unwrap();
    assert!((dt.split - 0.05).abs() < 1e-12, "{dt:?}");
    assert_eq!(dt.coupled, dt.split, "no coupled step with Split");
    let mut fast = scene.clone();
    fast.time.fixed_dt = Some(0.1);
    let e = limits_of(&fast, &grid, &law).unwrap_err();
    assert!(e.contains("set time.fixed_dt ≤ 5.0000e-2"), "{e}");
    // The coupled step's cap is 25 wave Courant numbers (0.3125 s here): 0.1 passes, 2 does
    // not, and the refusal names the coupled step's option.
    fast.numerics
        .update(|o: &mut crate::elastic::ElasticOptions| {
            o.coupling = crate::elastic::ElasticCoupling::Coupled
        })
        .unwrap();
    let dt = limits_of(&fast, &grid, &law).unwrap();
    assert!((dt.coupled - 0.3125).abs() < 1e-12, "{dt:?}");
    assert!((dt.split - 0.05).abs() < 1e-12, "{dt:?}");
    // Auto: the same split limit and its own default cap, 200 against Coupled's 25; its
    // refusal names both options.
    let mut auto = fast.clone();
    auto.numerics
        .update(|o: &mut crate::elastic::ElasticOptions| {
            o.coupling = crate::elastic::ElasticCoupling::Auto
        })
        .unwrap();
    let a = limits_of(&auto, &grid, &law).unwrap();
    assert_eq!(a.split, dt.split);
    assert!((a.coupled - 2.5).abs() < 1e-12, "{a:?}");
    for (s, limit) in [(&mut fast, "≤ 3.1250e-1"), (&mut auto, "≤ 2.5000e0")] {
        s.time.fixed_dt = Some(3.0);
        let e = limits_of(s, &grid, &law).unwrap_err();
        assert!(
            e.contains("numerics.elastic.coupled_wave_courant") && e.contains(limit),
            "{e}"
        );
    }
    let e = limits_of(&auto, &grid, &law).unwrap_err();
    assert!(e.contains("numerics.elastic.wave_courant"), "{e}");
    // A disk 3 cells across is refused (below MIN_CELLS_ACROSS = 5); 8 cells across is not.
    let mut small = scene.clone();
    small
        .update_solid(|s| {
            s.shape = Shape::Disk {
                center: (0.5, 0.5),
                radius: 1.5 / 16.0,
            }
        })
        .unwrap();
    let e = limits_of(&small, &grid, &law).unwrap_err();
    assert!(
        e.contains("cells across") && e.contains("refine the grid"),
        "{e}"
    );
}

/// A box of `n` cells over `[0, 1] × [0, 0.8] × [0, 0.6]` with the sides `sides` (x, y, z
/// pairs), and its boundary set.
fn box3(n: [usize; 3], sides: [Boundary; 3]) -> (Grid, BoundarySet) {
    let grid = Grid::new_3d(n, (0.0, 1.0), (0.0, 0.8), (0.0, 0.6));
    let [x, y, z] = sides;
    let mut b = efsi_core::scene::Boundaries::planar(x.clone(), x, y.clone(), y);
    (b.z_min, b.z_max) = (Some(z.clone()), Some(z));
    let bc = BoundarySet::new(&b, &grid);
    (grid, bc)
}

/// The position of index `I` of location `at` (nodal axes on the cell faces).
fn position(g: &Grid, at: efsi_core::Stagger, [i, j, k]: Index) -> [f64; 3] {
    let o = at.nodal();
    [
        if o[0] == 1 { g.xf(i) } else { g.xc(i) },
        if o[1] == 1 { g.yf(j) } else { g.yc(j) },
        if g.is_3d() {
            if o[2] == 1 { g.zf(k) } else { g.zc(k) }
        } else {
            0.0
        },
    ]
}

/// A field of location `at` set to `f(x)` at every entry, ghosts included.
fn sample(g: &Grid, at: efsi_core::Stagger, f: impl Fn([f64; 3]) -> f64 + Sync) -> Field {
    let mut out = Field::zeros(g);
    Region::whole(g).for_each(&mut out, |l, row| {
        for (n, i) in l.indices().enumerate() {
            row[n] = f(position(g, at, i));
        }
    });
    out
}

/// The velocity components `V(x)` on their faces of `g`, ghosts included (two or three).
fn velocity_field(g: &Grid, v: impl Fn([f64; 3]) -> [f64; 3] + Sync) -> Vec<Field> {
    use efsi_core::Stagger::{XFace, YFace, ZFace};
    let faces = [XFace, YFace, ZFace];
    (0..g.dims())
        .map(|a| sample(g, faces[a], |x| v(x)[a]))
        .collect()
}

/// The kernels of a solid filling `g` (φ = 1 everywhere, μ_f = μ_s = 1) and B = I with its
/// rates for the velocity `vel`, as the elastic stage initialises them.
fn solid_everywhere(g: &Grid, bc: &BoundarySet, vel: &[&Field]) -> (Kernels, Deformation) {
    let mut k = Kernels::new(g, bc, 1.0, 1.0);
    k.set_weights(&Field::filled(g, 1.0));
    let mut d = Deformation::zeros(g);
    d.set_identity();
    d.relax.iter_mut().for_each(|r| r.fill(1.0));
    k.fill_ghosts(&mut d.b);
    k.gradient(vel);
    k.advect(vel, &d.b, &mut d.advection);
    for (p, a) in d.advection_prev.iter_mut().zip(&d.advection) {
        p.copy_from(a);
    }
    k.stretch(&d.b, 1.0, None, None, &mut d.stretching);
    (k, d)
}

/// One step of `dt` of the stage's law-free path at θ = ½ for a steady velocity: the explicit
/// part, the predictor `B(V)` and the end-of-step update with its Picard pass.
fn step(k: &mut Kernels, d: &mut Deformation, first: &mut [Field], vel: &[&Field], dt: f64) {
    let th = 0.5;
    k.reset_fluid(d);
    d.begin_step(dt, 1.0, th);
    k.gradient(vel);
    let base = Some((&d.start[..], &d.explicit[..]));
    k.stretch(&d.start, th * dt, base, Some(&d.relax), &mut d.b);
    k.fill_ghosts(&mut d.b);
    k.update(vel, d, first, th * dt, true);
}

/// The largest `|f − want|` over the interior of the location of component `c`.
fn max_error(g: &Grid, f: &Field, c: usize, want: f64) -> f64 {
    Region::of(g, Deformation::stagger(c)).max(0.0, |l| {
        f.at(&l, [0; 3])
            .iter()
            .fold(0.0, |m: f64, x| m.max((x - want).abs()))
    })
}

/// A uniform simple shear `u_a = γ̇ x_b` in each of the six (component, axis) pairs of a
/// periodic 3-D box (the velocity linear across the periodic sides: set at every entry) gives
/// the analytic `B(t)`: `B_aa = 1 + (γ̇t)²`, `B_ab = γ̇t`, the rest the identity. The scheme
/// (Crank–Nicolson with one Picard pass: Heun's method) integrates this polynomial solution
/// exactly, so the error is round-off after 40 steps.
#[test]
fn a_uniform_simple_shear_in_each_plane_of_a_3d_box_gives_the_analytic_b() {
    let (g, bc) = box3(
        [6, 5, 4],
        [Boundary::Periodic, Boundary::Periodic, Boundary::Periodic],
    );
    let (rate, dt, steps) = (0.7, 0.05, 40);
    for a in 0..3 {
        for b in (0..3).filter(|&b| b != a) {
            let vel = velocity_field(&g, |x| {
                let mut v = [0.0; 3];
                v[a] = rate * x[b];
                v
            });
            let vel: Vec<&Field> = vel.iter().collect();
            let (mut k, mut d) = solid_everywhere(&g, &bc, &vel);
            let mut first = Deformation::zeros(&g).b;
            for _ in 0..steps {
                step(&mut k, &mut d, &mut first, &vel, dt);
            }
            let gt = rate * dt * steps as f64;
            let shear = 3 + PAIR[a][b];
            for (c, f) in d.b.iter().enumerate() {
                let want = match c {
                    _ if c == a => 1.0 + gt * gt,
                    0..3 => 1.0,
                    _ if c == shear => gt,
                    _ => 0.0,
                };
                let e = max_error(&g, f, c, want);
                assert!(
                    e <= 1e-13,
                    "u_{a} = γ̇ x_{b}: B{} off by {e:e} (want {want})",
                    Deformation::COMPONENTS[c]
                );
            }
        }
    }
}

/// A rigid rotation `V = ω × x` about an oblique axis keeps B = I to round-off in every
/// component (the stretching `L + Lᵀ` of a rotation vanishes, the advection of a uniform B
/// by a divergence-free velocity too), in a box with walls along x, periodic along y and a
/// symmetry plane along z.
#[test]
fn a_rigid_rotation_keeps_the_identity_in_3d() {
    let (g, bc) = box3(
        [6, 5, 4],
        [Boundary::NoSlip, Boundary::Periodic, Boundary::Symmetry],
    );
    let w = [0.3, -0.5, 0.8];
    let c = [0.5, 0.4, 0.3];
    let vel = velocity_field(&g, |x| {
        let r = [x[0] - c[0], x[1] - c[1], x[2] - c[2]];
        [
            w[1] * r[2] - w[2] * r[1],
            w[2] * r[0] - w[0] * r[2],
            w[0] * r[1] - w[1] * r[0],
        ]
    });
    let vel: Vec<&Field> = vel.iter().collect();
    let (mut k, mut d) = solid_everywhere(&g, &bc, &vel);
    let mut first = Deformation::zeros(&g).b;
    for _ in 0..20 {
        step(&mut k, &mut d, &mut first, &vel, 0.02);
    }
    for (c, f) in d.b.iter().enumerate() {
        let e = max_error(&g, f, c, if c < 3 { 1.0 } else { 0.0 });
        assert!(
            e <= 1e-14,
            "B{} off the identity by {e:e}",
            Deformation::COMPONENTS[c]
        );
    }
}

/// A planar field (velocity, B, and a solid block whose interface lies on the faces, so the
/// planar PLIC quarters and the three-dimensional edge fractions agree) extruded along a
/// periodic z: the three-dimensional gradients, stretching, advection and end-of-step update
/// give the planar kernels' values in every plane, B₁₃ = B₂₃ = 0.
#[test]
fn a_planar_field_extruded_along_a_periodic_z_gives_the_planar_kernels() {
    use efsi_core::Stagger::{Cell, Corner};
    let (n, sides) = ([12, 10], [Boundary::NoSlip, Boundary::FreeSlip]);
    let g2 = Grid::new(
        efsi_core::Geometry::Planar,
        n[0],
        n[1],
        (0.0, 1.0),
        (0.0, 0.8),
    );
    let b2 = efsi_core::scene::Boundaries::planar(
        sides[0].clone(),
        sides[0].clone(),
        sides[1].clone(),
        sides[1].clone(),
    );
    let bc2 = BoundarySet::new(&b2, &g2);
    let (g3, bc3) = box3(
        [n[0], n[1], 3],
        [sides[0].clone(), sides[1].clone(), Boundary::Periodic],
    );
    let vel = |x: [f64; 3]| {
        let (s, c) = ((3.0 * x[0] + 1.0).sin(), (2.0 * x[1] - 0.5).cos());
        [s * c, 0.4 * c * c - 0.3 * s, 0.0]
    };
    let phi = |x: [f64; 3]| {
        let inside = (0.25..0.65).contains(&x[0]) && (0.2..0.5).contains(&x[1]);
        f64::from(u8::from(inside))
    };
    let b0 = |c: usize, x: [f64; 3]| match c {
        0 => 1.1 + 0.2 * (4.0 * x[0]).sin() * x[1],
        1 => 0.9 + 0.1 * (3.0 * x[1]).cos() + 0.05 * x[0],
        2 => 1.0 + 0.05 * x[0] * x[1],
        _ => 0.1 * (5.0 * x[0] * x[1]).sin(),
    };
    let mut out = Vec::new();
    for (g, bc) in [(&g2, &bc2), (&g3, &bc3)] {
        let v = velocity_field(g, vel);
        let v: Vec<&Field> = v.iter().collect();
        let mut k = Kernels::new(g, bc, 1.0e-2, 0.5);
        k.set_weights(&sample(g, Cell, phi));
        let mut d = Deformation::zeros(g);
        for c in 0..4 {
            let at = if c < 3 { Cell } else { Corner };
            d.b[c] = sample(g, at, |x| b0(c, x));
        }
        d.relax.iter_mut().for_each(|r| r.fill(1.0));
        k.fill_ghosts(&mut d.b);
        k.gradient(&v);
        k.advect(&v, &d.b, &mut d.advection);
        let mut h = Deformation::zeros(g).b;
        k.stretch(&d.b, 1.0, None, None, &mut h);
        let a1 = d.advection.clone();
        let mut first = Deformation::zeros(g).b;
        for (p, a) in d.advection_prev.iter_mut().zip(&d.advection) {
            p.copy_from(a);
        }
        d.stretching.clone_from(&h);
        step(&mut k, &mut d, &mut first, &v, 0.01);
        let lk: Vec<Field> = k.lk[0].to_vec();
        out.push((k.lc.to_vec(), lk, h, a1, d.b));
    }
    let (p2, p3) = (&out[0], &out[1]);
    let mut worst = 0.0f64;
    let parts: [(&str, &[Field], &[Field]); 5] = [
        ("L at centres", &p2.0[..], &p3.0[..]),
        ("L at corners", &p2.1[..], &p3.1[..]),
        ("H", &p2.2[..], &p3.2[..]),
        ("∇·(VB)", &p2.3[..], &p3.3[..]),
        ("B after a step", &p2.4[..], &p3.4[..]),
    ];
    for (name, f2, f3) in parts {
        for (c, (f2, f3)) in f2.iter().zip(f3).enumerate() {
            // The interior of the plane, at every plane.
            let at = match (name, c) {
                ("L at corners", _) => Corner,
                (_, 0..3) | ("L at centres", _) => Cell,
                _ => Corner,
            };
            let r2 = Region::of(&g2, at);
            for l in (0..r2.lines()).map(|m| r2.line(m)) {
                for i in l.indices() {
                    for kz in 0..3 {
                        let (x, y) = (f2[i], f3[[i[0], i[1], kz]]);
                        let e = (x - y).abs();
                        worst = worst.max(e);
                        assert!(
                            e <= 1e-14 * (1.0 + x.abs()),
                            "{name} {c} at {i:?}, k = {kz}: {x} ≠ {y}"
                        );
                    }
                }
            }
        }
        if f3.len() > 4 {
            for (c, f) in f3.iter().enumerate().skip(4) {
                let e = max_error(&g3, f, c, 0.0);
                assert!(
                    e <= 1e-14,
                    "{name}: component {c} of the planar field is {e:e}"
                );
            }
        }
    }
    assert!(worst <= 1e-14, "{worst:e}");
}

/// The advection of a rough B by a uniform oblique velocity in a periodic 3-D box is
/// conservative: `Σ ∇·(V B) V` over the cells (normal components) and over the distinct edges
/// of each family (shear) vanishes to round-off, so a step `B − Δt ∇·(V B)` keeps `Σ B V`.
#[test]
fn advection_by_a_uniform_velocity_conserves_the_sum_of_b_in_3d() {
    let (g, bc) = box3(
        [7, 6, 5],
        [Boundary::Periodic, Boundary::Periodic, Boundary::Periodic],
    );
    let vel = velocity_field(&g, |_| [0.7, -0.4, 0.55]);
    let vel: Vec<&Field> = vel.iter().collect();
    let (k, mut d) = solid_everywhere(&g, &bc, &vel);
    // A rough field: a hash of the index.
    for (c, f) in d.b.iter_mut().enumerate() {
        Region::whole(&g).for_each(f, |l, row| {
            for (n, [i, j, kz]) in l.indices().enumerate() {
                let h = (i * 73 + j * 151 + kz * 283 + c as isize * 37).rem_euclid(101);
                row[n] = 1.0 + h as f64 / 101.0;
            }
        });
    }
    k.fill_ghosts(&mut d.b);
    k.advect(&vel, &d.b, &mut d.advection);
    let vol = g.dx * g.dy * g.dz;
    for (c, (a, b)) in d.advection.iter().zip(&d.b).enumerate() {
        // Each distinct point once: along a periodic nodal axis index n is index 0.
        let r = Region::of(&g, efsi_core::Stagger::Cell);
        let [sa, sb] = r
            .sum(|l| {
                let (a, b) = (a.at(&l, [0; 3]), b.at(&l, [0; 3]));
                [a.iter().sum::<f64>(), b.iter().sum::<f64>()]
            })
            .map(|s| s * vol);
        let mean_rate = a.data().iter().map(|x| x.abs()).sum::<f64>() / a.data().len() as f64;
        assert!(
            mean_rate > 0.1,
            "component {c}: no advection ({mean_rate:e})"
        );
        assert!(
            sa.abs() <= 1e-13 * sb,
            "component {}: Σ ∇·(VB) V = {sa:e} against Σ B V = {sb:e}",
            Deformation::COMPONENTS[c]
        );
    }
}

/// Two shears across the third axis of each other, `u = α z` and `w = β y`, in a periodic 3-D
/// box: `B₂₃ = βt`, `B₃₃ = 1 + β²t²`, `B₁₂ = αβt²/2` (grown only by the xy-edges' third-axis
/// term `L₁₃ B₃₂`), `B₁₃ = αt + αβ²t³/2`, `B₁₁ = 1 + α²t² + α²β²t⁴/4`. The components whose
/// rates are linear in t are exact to round-off; `B₁₃` and `B₁₁` converge at second order in
/// Δt (errors 5.5e-4 and 3.6e-4 at Δt = 0.05, t = 1, a quarter of them at half the step: Heun's
/// method, which the scheme is for a steady velocity).
#[test]
fn shears_across_each_others_third_axis_give_the_analytic_b_at_second_order() {
    let (g, bc) = box3(
        [5, 4, 6],
        [Boundary::Periodic, Boundary::Periodic, Boundary::Periodic],
    );
    let (al, be, t) = (0.8, 0.6, 1.0);
    let vel = velocity_field(&g, |x| [al * x[2], 0.0, be * x[1]]);
    let vel: Vec<&Field> = vel.iter().collect();
    let want = [
        1.0 + al * al * t * t + al * al * be * be * t.powi(4) / 4.0,
        1.0,
        1.0 + be * be * t * t,
        al * be * t * t / 2.0,
        be * t,
        al * t + al * be * be * t.powi(3) / 2.0,
    ];
    let errors = [20, 40].map(|steps| {
        let (mut k, mut d) = solid_everywhere(&g, &bc, &vel);
        let mut first = Deformation::zeros(&g).b;
        for _ in 0..steps {
            step(&mut k, &mut d, &mut first, &vel, t / steps as f64);
        }
        std::array::from_fn::<f64, 6, _>(|c| max_error(&g, &d.b[c], c, want[c]))
    });
    for c in [1, 2, 3, 4] {
        assert!(
            errors[1][c] <= 1e-13,
            "B{}: {:e}",
            Deformation::COMPONENTS[c],
            errors[1][c]
        );
    }
    for c in [0, 5] {
        let order = (errors[0][c] / errors[1][c]).log2();
        assert!(
            errors[0][c] > 1e-5 && errors[0][c] < 1e-3 && (1.9..2.1).contains(&order),
            "B{}: errors {:e}, {:e}, order {order}",
            Deformation::COMPONENTS[c],
            errors[0][c],
            errors[1][c]
        );
    }
}

/// A planar deformation (a rough B̃ in a solid block whose interface lies on the faces, so
/// the planar PLIC quarters and the three-dimensional ones agree) extruded along a periodic z,
/// for the non-linear Mooney–Rivlin law (its stress sees `tr B̃` and `tr B̃²`): the
/// three-dimensional law batches, stress, tangent increment and stress divergence give the
/// planar ones in every plane, `τ₂₃ = τ₁₃ = 0` and no force on the w-faces.
#[test]
fn a_planar_deformation_extruded_along_z_gives_the_planar_stress_and_force() {
    use efsi_core::Stagger::{Cell, Corner};
    let params = [("C1", 0.7), ("C2", 0.2), ("C3", 0.4)]
        .iter()
        .map(|&(k, v)| (k.to_string(), v))
        .collect();
    let law = efsi_laws_host::load_law_3d("mooney_rivlin", &params, std::path::Path::new("."))
        .unwrap_or_else(|e| panic!("{e}"));
    let (n, sides) = ([10, 9], [Boundary::NoSlip, Boundary::FreeSlip]);
    let g2 = Grid::new(
        efsi_core::Geometry::Planar,
        n[0],
        n[1],
        (0.0, 1.0),
        (0.0, 0.8),
    );
    let b2 = efsi_core::scene::Boundaries::planar(
        sides[0].clone(),
        sides[0].clone(),
        sides[1].clone(),
        sides[1].clone(),
    );
    let bc2 = BoundarySet::new(&b2, &g2);
    let (g3, bc3) = box3(
        [n[0], n[1], 3],
        [sides[0].clone(), sides[1].clone(), Boundary::Periodic],
    );
    let phi = |x: [f64; 3]| f64::from(u8::from((0.2..0.7).contains(&x[0]) && x[1] < 0.5));
    let b0 = |c: usize, x: [f64; 3]| match c {
        0 => 1.1 + 0.2 * (4.0 * x[0]).sin() * x[1],
        1 => 0.9 + 0.1 * (3.0 * x[1]).cos() + 0.05 * x[0],
        2 => 1.0 + 0.05 * x[0] * x[1],
        _ => 0.1 * (5.0 * x[0] * x[1]).sin(),
    };
    let mut out = Vec::new();
    for (g, bc) in [(&g2, &bc2), (&g3, &bc3)] {
        let mut k = Kernels::new(g, bc, 1.0e-2, 0.5);
        k.set_weights(&sample(g, Cell, phi));
        let mut b = Deformation::zeros(g).b;
        for (c, f) in b.iter_mut().enumerate().take(4) {
            *f = sample(g, if c < 3 { Cell } else { Corner }, |x| b0(c, x));
        }
        k.fill_ghosts(&mut b);
        let mut tau = Deformation::zeros(g).b;
        k.evaluate(&law, &b, &mut tau, true).unwrap();
        let mut dtau = Deformation::zeros(g).b;
        k.apply_tangent(&b, &mut dtau);
        let mut f = vec![0.0; k.faces.len()];
        k.force(&tau, &mut f);
        let mut fv = velocity_field(g, |_| [0.0; 3]);
        k.faces.scatter_to(&f, &mut fv);
        out.push((tau, dtau, fv));
    }
    let (p2, p3) = (&out[0], &out[1]);
    let mut seen = 0.0f64;
    let same = |name: &str, f2: &Field, f3: &Field, at: efsi_core::Stagger, scale: f64| {
        let r2 = Region::of(&g2, at);
        let mut big = 0.0f64;
        for l in (0..r2.lines()).map(|m| r2.line(m)) {
            for i in l.indices() {
                for kz in 0..3 {
                    let (x, y) = (f2[i], f3[[i[0], i[1], kz]]);
                    assert!(
                        (x - y).abs() <= 1e-13 * (scale + x.abs()),
                        "{name} at {i:?}, k = {kz}: {x} ≠ {y}"
                    );
                    big = big.max(x.abs());
                }
            }
        }
        big
    };
    for c in 0..4 {
        let at = if c < 3 { Cell } else { Corner };
        seen = seen.max(same("τ", &p2.0[c], &p3.0[c], at, 1.0));
        same("J·δB", &p2.1[c], &p3.1[c], at, 1.0);
    }
    for c in 4..6 {
        for (name, f) in [("τ", &p3.0[c]), ("J·δB", &p3.1[c])] {
            let e = max_error(&g3, f, c, 0.0);
            assert!(e <= 1e-14, "{name} {c} of the extruded field: {e:e}");
        }
    }
    let h2 = g2.dx * g2.dy;
    for (a, at) in [efsi_core::Stagger::XFace, efsi_core::Stagger::YFace]
        .into_iter()
        .enumerate()
    {
        // The 3-D force is the planar one times the cells' depth dz.
        let mut f3 = p3.2[a].clone();
        f3.data_mut().iter_mut().for_each(|x| *x /= g3.dz);
        seen = seen.max(same("force", &p2.2[a], &f3, at, h2));
    }
    let fw = p3.2[2].data().iter().fold(0.0f64, |m, x| m.max(x.abs()));
    assert!(fw <= 1e-14 * h2, "force on the w-faces {fw:e}");
    assert!(seen > 0.1, "nothing compared ({seen:e})");
}

/// The edge fractions of a three-dimensional grid come from the cells' PLIC planes in the
/// edges' midpoint sections: for a plane interface (normal mostly along y, where the VOF step's
/// mixed Youngs–centred normal is exact), every cut cell's quarter in the plane of each shear
/// pair `(a, b)` holds the exact share of the quarter square below the plane in the cell's
/// section through its centre along the third axis.
#[test]
fn the_edge_fractions_in_3d_are_the_exact_midpoint_sections_of_a_plane_interface() {
    use crate::vof::plic::rect_fraction;
    use crate::vof::plic3d::{Plane, cuboid_fraction};
    let (g, bc) = box3(
        [6, 8, 5],
        [Boundary::Periodic, Boundary::NoSlip, Boundary::Periodic],
    );
    let h = g.h();
    // The solid below the plane n·x = c (n = (0.25, 1, −0.15), x from the domain's origin).
    let n = [0.25, 1.0, -0.15];
    let c = 0.41;
    let phi_at = |lo: [f64; 3], d: [f64; 3]| {
        let p = Plane::new(n, 0.5, d);
        let s = p.n[0] / n[0];
        let alpha = s * (c - (n[0] * lo[0] + n[1] * lo[1] + n[2] * lo[2]));
        cuboid_fraction(p.n, alpha, d)
    };
    let mut phi = Field::zeros(&g);
    Region::whole(&g).for_each(&mut phi, |l, row| {
        for (m, [i, j, k]) in l.indices().enumerate() {
            let lo = [i as f64 * h[0], j as f64 * h[1], k as f64 * h[2]];
            row[m] = phi_at(lo, h);
        }
    });
    let mut k = Kernels::new(&g, &bc, 1.0, 0.5);
    k.set_weights(&phi);
    let (mut cut, mut worst) = (0, 0.0f64);
    // Quarters whose section share differs from their volume share (the interface crosses
    // the quarter cell but not its section, or not at the same share).
    let mut differ = 0;
    let cells = Region::of(&g, efsi_core::Stagger::Cell);
    for l in (0..cells.lines()).map(|m| cells.line(m)) {
        for [i, j, kk] in l.indices() {
            let f = phi[[i, j, kk]];
            if f <= 1e-9 || f >= 1.0 - 1e-9 {
                continue;
            }
            cut += 1;
            for (p, &([a, b], _)) in SHEAR.iter().enumerate() {
                let e3 = 3 - a - b;
                for q in 0..4 {
                    let mut lo = [i as f64 * h[0], j as f64 * h[1], kk as f64 * h[2]];
                    let mut d = h;
                    (d[a], d[b]) = (0.5 * h[a], 0.5 * h[b]);
                    lo[a] += if q % 2 == 1 { d[a] } else { 0.0 };
                    lo[b] += if q >= 2 { d[b] } else { 0.0 };
                    // The section through the cell's centre along the third axis.
                    let mid = lo[e3] + 0.5 * h[e3];
                    let below = c - n[e3] * mid - n[a] * lo[a] - n[b] * lo[b];
                    let exact = rect_fraction(n[a], n[b], below, d[a], d[b]);
                    let got = k.quarter[p][q][[i, j, kk]];
                    worst = worst.max((got - exact).abs());
                    differ += usize::from((got - phi_at(lo, d)).abs() > 1e-3);
                }
            }
        }
    }
    assert!(differ > 0, "no quarter's section differs from its volume");
    assert!(cut >= 30, "{cut} cut cells");
    assert!(worst <= 1e-9, "quarter fractions off by {worst:e}");
}

/// The strain energy of a uniform B filling a 3-D box (periodic, φ = 1): for neo-Hookean the
/// exact `∫ W dV = G/2 (tr B̄ − 3) V` with `B̄ = B / det(B)^{1/3}`; for Mooney–Rivlin (whose
/// energy the four-point quadrature takes) the planar box's energy per unit area of the same
/// in-plane deformation, rotated into an oblique frame in 3-D, times the box's depth — the
/// law on the six-component tensor, principal axes by Jacobi rotations, against the closed
/// form in two dimensions.
#[test]
fn the_strain_energy_of_a_uniform_b_in_3d_is_the_laws() {
    let (g, bc) = box3(
        [4, 3, 2],
        [Boundary::Periodic, Boundary::Periodic, Boundary::Periodic],
    );
    let volume = 1.0 * 0.8 * 0.6;
    let energy = |g: &Grid, bc: &BoundarySet, law: &dyn ConstitutiveLaw, b: &[f64]| {
        let mut k = Kernels::new(g, bc, 1.0, 1.0);
        k.set_weights(&Field::filled(g, 1.0));
        let fields: Vec<Field> = b.iter().map(|&x| Field::filled(g, x)).collect();
        k.strain_energy(law, &fields).unwrap()
    };
    let load = |name: &str, params: &[(&str, f64)]| {
        let params = params.iter().map(|&(k, v)| (k.to_string(), v)).collect();
        efsi_laws_host::load_law(name, &params, std::path::Path::new(".")).unwrap()
    };
    // B = F Fᵀ of a general F, in the components [11, 22, 33, 12, 23, 13].
    let f = [[1.2, 0.3, 0.1], [0.0, 0.9, -0.2], [0.15, 0.05, 1.1]];
    let fft = |i: usize, j: usize| (0..3).map(|k| f[i][k] * f[j][k]).sum::<f64>();
    let b = [
        fft(0, 0),
        fft(1, 1),
        fft(2, 2),
        fft(0, 1),
        fft(1, 2),
        fft(0, 2),
    ];
    let det = b[0] * (b[1] * b[2] - b[4] * b[4]) - b[3] * (b[3] * b[2] - b[4] * b[5])
        + b[5] * (b[3] * b[4] - b[1] * b[5]);
    let gm = 2.0;
    let want = 0.5 * gm * ((b[0] + b[1] + b[2]) / det.cbrt() - 3.0) * volume;
    let got = energy(&g, &bc, &load("neo_hookean", &[("G", gm)]), &b);
    assert!(want > 0.1, "{want}");
    assert!(
        (got - want).abs() <= 1e-10 * want,
        "neo-Hookean: {got:e} against {want:e}"
    );
    // Mooney–Rivlin: a planar B (in-plane stretch and shear, its own out-of-plane stretch)
    // rotated by R (about the axis (1, 2, 2)/3 by 40°) into every component.
    let mr = load("mooney_rivlin", &[("C1", 0.7), ("C2", 0.2), ("C3", 0.4)]);
    let p = [1.3, 0.85, 0.95, 0.2];
    let planar = Grid::new(efsi_core::Geometry::Planar, 4, 3, (0.0, 1.0), (0.0, 0.8));
    let sides = efsi_core::scene::Boundaries::planar(
        Boundary::Periodic,
        Boundary::Periodic,
        Boundary::Periodic,
        Boundary::Periodic,
    );
    let e2 = energy(&planar, &BoundarySet::new(&sides, &planar), &mr, &p);
    let (axis, angle) = ([1.0 / 3.0, 2.0 / 3.0, 2.0 / 3.0], 40f64.to_radians());
    let (c, s) = (angle.cos(), angle.sin());
    let r = |i: usize, j: usize| {
        let cross = match (i, j) {
            (0, 1) => -axis[2],
            (1, 0) => axis[2],
            (0, 2) => axis[1],
            (2, 0) => -axis[1],
            (1, 2) => -axis[0],
            (2, 1) => axis[0],
            _ => 0.0,
        };
        let id = if i == j { 1.0 } else { 0.0 };
        c * id + s * cross + (1.0 - c) * axis[i] * axis[j]
    };
    let m = [[p[0], p[3], 0.0], [p[3], p[1], 0.0], [0.0, 0.0, p[2]]];
    let rot = |i: usize, j: usize| {
        let mut x = 0.0;
        for k in 0..3 {
            for l in 0..3 {
                x += r(i, k) * m[k][l] * r(j, l);
            }
        }
        x
    };
    let b3 = [
        rot(0, 0),
        rot(1, 1),
        rot(2, 2),
        rot(0, 1),
        rot(1, 2),
        rot(0, 2),
    ];
    let e3 = energy(&g, &bc, &mr, &b3);
    assert!(e2 > 0.01, "{e2}");
    assert!(
        (e3 - 0.6 * e2).abs() <= 1e-12 * e2,
        "Mooney–Rivlin: 3-D {e3:e} against the planar {e2:e} × depth 0.6"
    );
}
