use super::limits::wave_limit;
use super::*;
use crate::solid::{SceneSolid, Shape};
use efsi_laws_host::ConstitutiveLaw;
use efsi_laws_host::NeoHookeanReference;

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
            let (wt, fluid) = if c == 3 { (&k.wc, 0.0) } else { (&k.w, 1.0) };
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
