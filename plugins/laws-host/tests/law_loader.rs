//! The law-plugin loader against real plugin libraries: the shipped laws, the test-only
//! plugins (wrong tangent, panicking, broken descriptor, NaN, a version-1 library) and the law
//! template built from a copy.
//!
//! The libraries are built by `cargo build --workspace`, and by `cargo test -p efsi-laws-host`
//! too (efsi-laws-host lists them as dev-dependencies, so cargo builds them into
//! `target/<profile>/deps` next to this test binary, which is on the loader's search path).

use efsi_laws_host::loader::{LAW_PATH_ENV, library_file_name, resolve_law, search_dirs};
use efsi_laws_host::{
    ConstitutiveLaw, FD_TANGENT_TOLERANCE, LawError, Listed, LoadedLaw, Sym, Sym6, Tangent,
    Tangent6, check_library, describe, list_laws,
};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::Instant;

/// A law as a scene names it: its name and parameter values.
struct LawSpec {
    name: String,
    parameters: BTreeMap<String, f64>,
}

/// [`efsi_laws_host::load_law`] of `spec`.
fn load_law(spec: &LawSpec, dir: &Path) -> Result<LoadedLaw, LawError> {
    efsi_laws_host::load_law(&spec.name, &spec.parameters, dir)
}

/// A law spec from a name and `(parameter, value)` pairs.
fn spec(name: &str, params: &[(&str, f64)]) -> LawSpec {
    LawSpec {
        name: name.to_string(),
        parameters: params
            .iter()
            .map(|(k, v)| (k.to_string(), *v))
            .collect::<BTreeMap<_, _>>(),
    }
}

fn load(name: &str, params: &[(&str, f64)]) -> Result<LoadedLaw, LawError> {
    load_law(&spec(name, params), Path::new("."))
}

/// The path of a test-only plugin library, by library name (e.g. `efsi_test_law_panic`).
fn test_plugin(lib: &str) -> PathBuf {
    let file = format!(
        "{}{lib}{}",
        std::env::consts::DLL_PREFIX,
        std::env::consts::DLL_SUFFIX
    );
    let dirs = search_dirs();
    dirs.iter()
        .map(|d| d.join(&file))
        .find(|p| p.is_file())
        .unwrap_or_else(|| {
            panic!(
                "{file} is in none of {dirs:?}: build the law plugins with `cargo build --workspace` first"
            )
        })
}

fn eval(law: &dyn ConstitutiveLaw, b: &[Sym]) -> Result<(Vec<Sym>, Vec<Tangent>), LawError> {
    let mut tau = vec![[0.0; 4]; b.len()];
    let mut j = vec![[0.0; 16]; b.len()];
    law.evaluate(b, &mut tau, Some(&mut j))?;
    Ok((tau, j))
}

fn eval_full(
    law: &dyn ConstitutiveLaw,
    b: &[Sym6],
) -> Result<(Vec<Sym6>, Vec<Tangent6>), LawError> {
    let mut tau = vec![[0.0; 6]; b.len()];
    let mut j = vec![[0.0; 36]; b.len()];
    law.evaluate_full(b, &mut tau, Some(&mut j))?;
    Ok((tau, j))
}

fn embed(b: &Sym) -> Sym6 {
    [b[0], b[1], b[2], b[3], 0.0, 0.0]
}

fn close(a: &[f64], b: &[f64], tol: f64) -> bool {
    a.iter().zip(b).all(|(x, y)| (x - y).abs() <= tol)
}

const STATES: [Sym; 3] = [
    [1.0, 1.0, 1.0, 0.0],
    [1.3, 0.8, 1.05, 0.2],
    [0.6, 0.9, 0.7, -0.15],
];

#[test]
fn shipped_laws_load_by_name_and_pass_the_tangent_check() {
    for (name, params) in [
        ("neo_hookean", vec![("G", 1.8e5)]),
        ("saint_venant_kirchhoff", vec![("lambda", 1e6), ("mu", 2e5)]),
        ("mooney_rivlin", vec![("C1", 1e5), ("C2", 3e4), ("C3", 5e4)]),
    ] {
        let law = load(name, &params).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(law.name(), name);
        let check = law.tangent_check();
        assert!(check.passed());
        assert!(
            check.worst_relative_error < 1e-8,
            "{name}: {check} (expected round-off only)"
        );
        eprintln!("{name}: {check}");
        let full = law
            .tangent_check_full()
            .expect("a version-2 law has a 3-D check");
        assert!(
            full.passed() && full.worst_relative_error < 1e-8,
            "{name}: {full}"
        );
        assert_eq!(full.worst_state.len(), 6);
        eprintln!("{name} (3-D): {full}");
        let expect_file = library_file_name(name);
        assert!(law.info().path.ends_with(&expect_file));
        assert_eq!(law.info().abi_version, 2);
        assert!(law.evaluates_full());
        // The same law for a 3-D scene.
        let law =
            efsi_laws_host::load_law_3d(name, &spec(name, &params).parameters, Path::new("."))
                .unwrap_or_else(|e| panic!("{e}"));
        assert!(law.tangent_check_full().unwrap().passed());
    }
}

/// Through the plugin: rotating a 3-D `B̃` rotates `τ` (`τ(Q B̃ Qᵀ) = Q τ(B̃) Qᵀ`) for each shipped
/// law, at the full check states and fixed rotations about three different axes.
#[test]
fn shipped_laws_are_objective_in_3d() {
    let rotations = [
        rotation([1.0, 2.0, 3.0], 0.7),
        rotation([0.0, 0.0, 1.0], 2.1),
        rotation([-1.0, 0.5, 0.2], -1.3),
    ];
    let states = efsi_laws_host::loader::tangent_check_states_full();
    for (name, params) in [
        ("neo_hookean", vec![("G", 1.8e5)]),
        ("saint_venant_kirchhoff", vec![("lambda", 1e6), ("mu", 2e5)]),
        ("mooney_rivlin", vec![("C1", 1e5), ("C2", 3e4), ("C3", 5e4)]),
    ] {
        let law = load(name, &params).unwrap();
        let (tau, _) = eval_full(&law, &states).unwrap();
        // The law's stress scale over the states (τ(I) vanishes for Saint Venant–Kirchhoff).
        let scale = tau.iter().flatten().fold(0.0_f64, |m, x| m.max(x.abs()));
        for q in &rotations {
            let rotated: Vec<Sym6> = states.iter().map(|b| rotate(q, b)).collect();
            let (tau_r, _) = eval_full(&law, &rotated).unwrap();
            for (k, t) in tau.iter().enumerate() {
                let want = rotate(q, t);
                assert!(
                    close(&tau_r[k], &want, 1e-12 * scale),
                    "{name} state {k}: {:?} vs {want:?}",
                    tau_r[k]
                );
            }
            // The rotation changes the states (the assertion above has something to test).
            assert!(!close(&rotated[5], &states[5], 1e-3));
        }
    }
}

/// The rotation by `angle` about `axis` (Rodrigues).
fn rotation(axis: [f64; 3], angle: f64) -> [[f64; 3]; 3] {
    let n = (axis[0] * axis[0] + axis[1] * axis[1] + axis[2] * axis[2]).sqrt();
    let [x, y, z] = axis.map(|a| a / n);
    let (s, c) = angle.sin_cos();
    let t = 1.0 - c;
    [
        [t * x * x + c, t * x * y - s * z, t * x * z + s * y],
        [t * x * y + s * z, t * y * y + c, t * y * z - s * x],
        [t * x * z - s * y, t * y * z + s * x, t * z * z + c],
    ]
}

/// `Q B Qᵀ` of a stored symmetric tensor `[11, 22, 33, 12, 23, 13]`.
fn rotate(q: &[[f64; 3]; 3], b: &Sym6) -> Sym6 {
    let m = [[b[0], b[3], b[5]], [b[3], b[1], b[4]], [b[5], b[4], b[2]]];
    let r = |i: usize, j: usize| {
        let mut x = 0.0;
        for (k, mk) in m.iter().enumerate() {
            for (l, mkl) in mk.iter().enumerate() {
                x += q[i][k] * mkl * q[j][l];
            }
        }
        x
    };
    [r(0, 0), r(1, 1), r(2, 2), r(0, 1), r(1, 2), r(0, 2)]
}

/// A version-2 law on an in-plane `B̃` embedded in six components (13 = 23 = 0) gives its
/// in-plane numbers, bit for bit, through the plugin's two entry points.
#[test]
fn full_evaluation_of_an_in_plane_b_is_the_in_plane_evaluation() {
    let states = efsi_laws_host::loader::tangent_check_states();
    let embedded: Vec<Sym6> = states.iter().map(embed).collect();
    for (name, params) in [
        ("neo_hookean", vec![("G", 1.8e5)]),
        ("saint_venant_kirchhoff", vec![("lambda", 1e6), ("mu", 2e5)]),
        ("mooney_rivlin", vec![("C1", 1e5), ("C2", 3e4), ("C3", 5e4)]),
    ] {
        let law = load(name, &params).unwrap();
        let (t4, j4) = eval(&law, &states).unwrap();
        let (t6, j6) = eval_full(&law, &embedded).unwrap();
        for k in 0..states.len() {
            assert_eq!(t6[k][..4], t4[k], "{name} state {k}");
            assert_eq!(t6[k][4..], [0.0, 0.0], "{name} state {k}");
            for a in 0..4 {
                assert_eq!(j6[k][6 * a..6 * a + 4], j4[k][4 * a..4 * a + 4], "{name}");
            }
        }
    }
}

/// A version-1 library (a frozen copy of the version-1 interface, Mooney–Rivlin with version
/// 1's arithmetic): loads and runs on in-plane tensors as before, with numbers equal bit for
/// bit to the version-2 `mooney_rivlin`'s in-plane ones and to its full evaluation of the same
/// tensors embedded in six components; a 3-D scene refuses it naming the version.
#[test]
fn a_version_1_library_runs_in_plane_and_is_refused_in_3d() {
    let path = test_plugin("efsi_test_law_v1");
    let name = path.to_str().unwrap();
    let params = [("C1", 1e5), ("C2", 3e4), ("C3", 5e4)];
    let v1 = load(name, &params).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(v1.name(), "test_v1_mooney_rivlin");
    assert_eq!(v1.info().abi_version, 1);
    assert!(!v1.evaluates_full());
    assert!(v1.tangent_check().worst_relative_error < 1e-8);
    assert!(v1.tangent_check_full().is_none());

    let v2 = load("mooney_rivlin", &params).unwrap();
    let states = efsi_laws_host::loader::tangent_check_states();
    let (t1, j1) = eval(&v1, &states).unwrap();
    let (t2, j2) = eval(&v2, &states).unwrap();
    assert_eq!(t1, t2);
    assert_eq!(j1, j2);
    let embedded: Vec<Sym6> = states.iter().map(embed).collect();
    let (t6, j6) = eval_full(&v2, &embedded).unwrap();
    for k in 0..states.len() {
        assert_eq!(t6[k][..4], t1[k]);
        for a in 0..4 {
            assert_eq!(j6[k][6 * a..6 * a + 4], j1[k][4 * a..4 * a + 4]);
        }
    }

    // In 3-D: refused at load, and a full evaluation is an error naming the version.
    let e = efsi_laws_host::load_law_3d(name, &spec(name, &params).parameters, Path::new("."))
        .unwrap_err();
    eprintln!("{e}");
    assert_eq!(e.law, "test_v1_mooney_rivlin");
    for want in [
        "built for ABI v1",
        "in-plane tensors only",
        "rebuild it against efsi-law-sdk",
        "(ABI v2) to use it in a 3-D scene",
    ] {
        assert!(e.message.contains(want), "{want:?} not in: {e}");
    }
    let e2 = eval_full(&v1, &embedded).unwrap_err();
    assert_eq!(e2.message, e.message);
    assert_eq!(e2.cell, None);

    // `efsi laws --check` runs the in-plane check only; the listing names the version.
    let check = check_library(&path).unwrap();
    assert!(
        check.passed() && check.full.is_none() && check.embedding.is_none(),
        "{check:?}"
    );
    let text = describe(&path).unwrap().to_string();
    assert!(text.contains("ABI v1: in-plane tensors only"), "{text}");
}

#[test]
fn check_library_runs_both_checks_of_a_version_2_law() {
    let path = resolve_law("saint_venant_kirchhoff", Path::new(".")).unwrap();
    let check = check_library(&path).unwrap();
    assert!(check.passed());
    assert_eq!(check.in_plane.worst_state.len(), 4);
    let full = check.full.unwrap();
    assert_eq!((full.states, full.skipped), (26, 0));
    assert!(full.worst_relative_error < 1e-8, "{full}");
    // The SDK's two evaluations agree bit for bit on in-plane tensors.
    let embedding = check.embedding.unwrap();
    assert_eq!(embedding.worst_relative_difference, 0.0, "{embedding}");
    assert!(
        describe(&path)
            .unwrap()
            .to_string()
            .contains("ABI v2: full and in-plane tensors")
    );
    // The wrong tangent fails both.
    let wrong = check_library(&test_plugin("efsi_test_law_wrong_tangent")).unwrap();
    assert!(!wrong.passed() && !wrong.in_plane.passed());
    let full = wrong.full.unwrap();
    assert!(!full.passed(), "{full}");
    assert!(
        (full.tangent / full.finite_difference - 1.5).abs() < 1e-6,
        "{full}"
    );
}

#[test]
fn neo_hookean_plugin_matches_the_reference_law() {
    let law = load("neo_hookean", &[("G", 2.5e5)]).unwrap();
    let reference = efsi_laws_host::NeoHookeanReference { g: 2.5e5 };
    let (tau, j) = eval(&law, &STATES).unwrap();
    let (tau_r, j_r) = eval(&reference, &STATES).unwrap();
    assert_eq!(tau, tau_r);
    assert_eq!(j, j_r);
}

#[test]
fn missing_parameters_take_their_defaults() {
    let law = load("saint_venant_kirchhoff", &[("mu", 3e5)]).unwrap();
    assert_eq!(
        law.parameter_values(),
        vec![("lambda".to_string(), 4e5), ("mu".to_string(), 3e5)]
    );
    let law = load("neo_hookean", &[]).unwrap();
    assert_eq!(law.parameter_values(), vec![("G".to_string(), 1e5)]);
}

#[test]
fn saint_venant_kirchhoff_equals_mooney_rivlin_with_eq_10_coefficients() {
    let (lambda, mu) = (7e5, 1.5e5);
    let svk = load("saint_venant_kirchhoff", &[("lambda", lambda), ("mu", mu)]).unwrap();
    let mr = load(
        "mooney_rivlin",
        &[
            ("C1", mu),
            ("C2", -mu / 2.0),
            ("C3", (lambda + 2.0 * mu) / 8.0),
        ],
    )
    .unwrap();
    let states = efsi_laws_host::loader::tangent_check_states();
    let (t1, j1) = eval(&svk, &states).unwrap();
    let (t2, j2) = eval(&mr, &states).unwrap();
    for k in 0..states.len() {
        assert!(
            close(&t1[k], &t2[k], 1e-9 * lambda),
            "{:?} {:?}",
            t1[k],
            t2[k]
        );
        assert!(close(&j1[k], &j2[k], 1e-9 * lambda));
    }
    // Stress-free at rest.
    let (t, _) = eval(&svk, &[[1.0, 1.0, 1.0, 0.0]]).unwrap();
    assert!(close(&t[0], &[0.0; 4], 1e-9 * lambda));
}

#[test]
fn wrong_tangent_is_refused_naming_the_law() {
    let path = test_plugin("efsi_test_law_wrong_tangent");
    let e = load(path.to_str().unwrap(), &[("G", 1e5)]).unwrap_err();
    eprintln!("{e}");
    assert_eq!(e.law, "test_wrong_tangent");
    assert!(e.message.contains("refused"), "{e}");
    assert!(e.message.contains("finite differences"), "{e}");
    assert!(e.message.contains("1.500000e5"), "{e}");
    assert!(
        e.message.contains(&format!("{FD_TANGENT_TOLERANCE:e}")),
        "{e}"
    );
}

/// Saint Venant–Kirchhoff with λ = 0 or a small λ, inside its declared range (λ ≥ 0), passes
/// the tangent check: at `B̃ = 0.5 I` its tangent is exactly zero (λ = 0) or of order λ, and the
/// differences' round-off is judged against the law's stiffness at rest, not that zero.
#[test]
fn a_tangent_that_vanishes_at_a_state_is_judged_against_the_law_stiffness() {
    for lambda in [0.0, 1e-3, 1.0] {
        let law = load("saint_venant_kirchhoff", &[("lambda", lambda), ("mu", 1e5)])
            .unwrap_or_else(|e| panic!("λ = {lambda}: {e}"));
        let check = law.tangent_check();
        assert!(check.passed(), "λ = {lambda}: {check}");
        assert!(check.worst_relative_error < 1e-8, "λ = {lambda}: {check}");
        // The state where the tangent vanishes is tested: |J(0.5 I)| ≤ λ (0 for λ = 0).
        let (_, j) = eval(&law, &[[0.5, 0.5, 0.5, 0.0]]).unwrap();
        let biggest = j[0].iter().fold(0.0_f64, |m, x| m.max(x.abs()));
        assert!(biggest <= lambda, "λ = {lambda}: {biggest}");
    }
    // A wrong tangent is still refused.
    let path = test_plugin("efsi_test_law_wrong_tangent");
    assert!(load(path.to_str().unwrap(), &[]).is_err());
}

#[test]
fn missing_library_file() {
    let e = load("definitely_not_a_law", &[]).unwrap_err();
    assert_eq!(e.law, "definitely_not_a_law");
    assert!(
        e.message
            .contains(&library_file_name("definitely_not_a_law")),
        "{e}"
    );
    assert!(e.message.contains(LAW_PATH_ENV), "{e}");

    let e = load_law(
        &spec("laws/libmissing.so", &[]),
        Path::new("/nonexistent/scene/dir"),
    )
    .unwrap_err();
    assert!(e.message.contains("library not found"), "{e}");
    assert!(
        e.message
            .contains("/nonexistent/scene/dir/laws/libmissing.so"),
        "{e}"
    );
}

#[test]
fn not_a_library_and_no_entry_symbol() {
    let dir = std::env::temp_dir().join(format!("efsi-law-notlib-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(dir.join("libfake.so"), "not an ELF file").unwrap();
    let e = load_law(&spec("libfake.so", &[]), &dir).unwrap_err();
    assert!(e.message.contains("not a loadable library"), "{e}");
    std::fs::remove_dir_all(&dir).unwrap();

    // A real library without the entry symbol: the C maths library, where it is found.
    let libm = [
        "/lib/x86_64-linux-gnu/libm.so.6",
        "/usr/lib/x86_64-linux-gnu/libm.so.6",
        "/lib/aarch64-linux-gnu/libm.so.6",
        "/usr/lib64/libm.so.6",
        "/usr/lib/libm.so.6",
    ]
    .into_iter()
    .find(|p| Path::new(p).is_file());
    if let Some(libm) = libm {
        let e = load(libm, &[]).unwrap_err();
        assert!(e.message.contains("no `efsi_law_descriptor` symbol"), "{e}");
    } else {
        eprintln!("no libm found: missing-symbol case skipped");
    }
}

#[test]
fn unknown_parameter_lists_the_known_ones() {
    let e = load("saint_venant_kirchhoff", &[("E", 1e6)]).unwrap_err();
    assert_eq!(e.law, "saint_venant_kirchhoff");
    assert!(e.message.contains("unknown parameter `E`"), "{e}");
    assert!(e.message.contains("`lambda` (Pa), `mu` (Pa)"), "{e}");
}

#[test]
fn out_of_range_parameter_names_value_range_and_unit() {
    let e = load("neo_hookean", &[("G", -5.0)]).unwrap_err();
    assert_eq!(
        e.to_string(),
        "law `neo_hookean`: parameter `G` = -5 Pa is out of range: allowed (0, ∞) Pa"
    );
    let e = load("mooney_rivlin", &[("C3", f64::NAN)]).unwrap_err();
    assert!(e.message.contains("`C3` = NaN Pa"), "{e}");
}

#[test]
fn plugin_error_in_create_comes_back_with_its_message() {
    let e = load("mooney_rivlin", &[("C1", 1e4), ("C2", -2e4)]).unwrap_err();
    assert_eq!(e.law, "mooney_rivlin");
    assert!(e.message.contains("could not be created"), "{e}");
    assert!(e.message.contains("2 (C1 + C2)"), "{e}");
}

#[test]
fn panicking_plugin_returns_errors_and_the_process_survives() {
    let path = test_plugin("efsi_test_law_panic");
    let name = path.to_str().unwrap();
    let e = load(name, &[("G", 1e13)]).unwrap_err();
    assert_eq!(e.law, "test_panic");
    assert!(e.message.contains("panicked"), "{e}");
    assert!(e.message.contains("too stiff"), "{e}");

    let law = load(name, &[("G", 1e5)]).unwrap();
    let e = eval(&law, &[[1.0, 1.0, 1.0, 0.0], [11.0, 1.0, 1.0, 0.0]]).unwrap_err();
    assert_eq!(e.law, "test_panic");
    assert_eq!(e.message, "panicked in evaluate: b11 = 11 exceeds 10");
    // Still usable after the caught panic.
    let (tau, _) = eval(&law, &[[2.0, 1.0, 1.0, 0.5]]).unwrap();
    assert_eq!(tau[0], [2e5, 1e5, 1e5, 0.5e5]);
    // The full evaluation catches it alike.
    let e = eval_full(&law, &[[11.0, 1.0, 1.0, 0.0, 0.2, 0.1]]).unwrap_err();
    assert_eq!(e.message, "panicked in evaluate: b11 = 11 exceeds 10");
    let (tau, _) = eval_full(&law, &[[2.0, 1.0, 1.0, 0.5, 0.25, -0.5]]).unwrap();
    assert_eq!(tau[0], [2e5, 1e5, 1e5, 0.5e5, 0.25e5, -0.5e5]);
}

#[test]
fn non_finite_output_names_the_first_bad_cell() {
    let law = load("neo_hookean", &[]).unwrap();
    let b = [
        [1.0, 1.0, 1.0, 0.0],
        [1.0, 1.0, 1.0, 0.0],
        [f64::NAN, 1.0, 1.0, 0.0],
    ];
    let e = eval(&law, &b).unwrap_err();
    assert_eq!(e.law, "neo_hookean");
    assert!(e.message.contains("non-finite stress"), "{e}");
    assert_eq!(e.cell, Some(2), "{e}");
    assert!(e.to_string().contains("at entry 2 of the batch"), "{e}");
    let mut tau = vec![[0.0; 4]; 3];
    let e = law.evaluate(&b, &mut tau, None).unwrap_err();
    assert_eq!(e.cell, Some(2), "{e}");
    // A full batch: the law that turns NaN past a stretch names the first such cell.
    let nan = load(
        test_plugin("efsi_test_law_nan").to_str().unwrap(),
        &[("limit", 1.5)],
    )
    .unwrap();
    let b6 = [
        [1.0, 1.0, 1.0, 0.0, 0.1, 0.1],
        [1.6, 1.0, 1.0, 0.0, 0.1, 0.1],
        [1.7, 1.0, 1.0, 0.0, 0.0, 0.0],
    ];
    let e = eval_full(&nan, &b6).unwrap_err();
    assert_eq!(e.law, "test_nan");
    assert!(e.message.contains("non-finite stress"), "{e}");
    assert_eq!(e.cell, Some(1), "{e}");
}

#[test]
fn library_named_by_path_relative_to_the_scene() {
    let path = resolve_law("mooney_rivlin", Path::new(".")).unwrap();
    let dir = path.parent().unwrap();
    let file = path.file_name().unwrap().to_str().unwrap();
    // `./file` relative to the scene folder, and `<folder>/file` from the folder above.
    let law = load_law(&spec(&format!("./{file}"), &[("C1", 2e5)]), dir).unwrap();
    assert_eq!(law.name(), "mooney_rivlin");
    let folder = dir.file_name().unwrap().to_str().unwrap();
    let law = load_law(
        &spec(&format!("{folder}/{file}"), &[]),
        dir.parent().unwrap(),
    )
    .unwrap();
    assert_eq!(law.parameter_values()[0], ("C1".to_string(), 5e4));
    // An absolute path works regardless of the scene folder.
    let law = load_law(&spec(path.to_str().unwrap(), &[]), Path::new("/")).unwrap();
    assert_eq!(law.name(), "mooney_rivlin");
}

#[test]
fn wrong_abi_version_is_refused() {
    let path = test_plugin("efsi_test_law_bad_abi");
    if std::env::var_os("EFSI_TEST_BAD_ABI").is_some() {
        return; // run by `descriptor_size_and_functions_are_checked` below
    }
    let e = load(path.to_str().unwrap(), &[]).unwrap_err();
    assert!(
        e.message.contains(
            "built for ABI v3, efsi expects v2 (or v1, in-plane tensors only): rebuild the law against efsi-law-sdk"
        ),
        "{e}"
    );
}

/// The broken-descriptor plugin reads `EFSI_TEST_BAD_ABI`; this test re-runs the test binary
/// with it set (no `set_var` in a multi-threaded test process).
#[test]
fn descriptor_size_and_functions_are_checked() {
    if let Ok(mode) = std::env::var("EFSI_TEST_BAD_ABI") {
        let path = test_plugin("efsi_test_law_bad_abi");
        let e = load(path.to_str().unwrap(), &[]).unwrap_err();
        let want = match mode.as_str() {
            "size" => "descriptor size 88 bytes, efsi expects 80 for ABI v2",
            "v1-size" => "descriptor size 80 bytes, efsi expects 72 for ABI v1",
            "functions" => "lacks a create, destroy or evaluate function",
            other => panic!("unknown mode {other}"),
        };
        assert!(e.message.contains(want), "{e}");
        // The name is read only from a descriptor whose layout is trusted.
        let law = if mode.ends_with("size") {
            path.to_str().unwrap()
        } else {
            "test_bad_abi"
        };
        assert_eq!(e.law, law);
        return;
    }
    if !cfg!(target_pointer_width = "64") {
        return;
    }
    for mode in ["size", "v1-size", "functions"] {
        let out = Command::new(std::env::current_exe().unwrap())
            .args(["--exact", "descriptor_size_and_functions_are_checked"])
            .env("EFSI_TEST_BAD_ABI", mode)
            .output()
            .unwrap();
        assert!(
            out.status.success() && String::from_utf8_lossy(&out.stdout).contains("1 passed"),
            "mode {mode}: {}\n{}",
            String::from_utf8_lossy(&out.stdout),
            String::from_utf8_lossy(&out.stderr)
        );
    }
}

/// `$EFSI_LAW_PATH` is searched first: a copy of a law under another name is found there (in a
/// child process, to set the variable without `set_var`).
#[test]
fn law_path_environment_variable_is_searched() {
    if let Some(dir) = std::env::var_os("EFSI_TEST_LAW_PATH_CHILD") {
        let law = load("copied_neo_hookean", &[("G", 3.0)]).unwrap();
        assert!(law.info().path.starts_with(&dir));
        assert_eq!(law.name(), "neo_hookean");
        return;
    }
    let dir = std::env::temp_dir().join(format!("efsi-law-path-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let src = resolve_law("neo_hookean", Path::new(".")).unwrap();
    std::fs::copy(&src, dir.join(library_file_name("copied_neo_hookean"))).unwrap();
    let out = Command::new(std::env::current_exe().unwrap())
        .args(["--exact", "law_path_environment_variable_is_searched"])
        .env(LAW_PATH_ENV, &dir)
        .env("EFSI_TEST_LAW_PATH_CHILD", &dir)
        .output()
        .unwrap();
    std::fs::remove_dir_all(&dir).unwrap();
    assert!(
        out.status.success() && String::from_utf8_lossy(&out.stdout).contains("1 passed"),
        "{}\n{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
}

#[test]
fn describe_and_list_the_shipped_laws() {
    let laws: Vec<_> = list_laws(&[test_plugin("efsi_test_law_wrong_tangent")])
        .into_iter()
        .map(|r| match r {
            Listed::Law(info) => info,
            Listed::Skipped(e) | Listed::Failed(e) => panic!("{e}"),
        })
        .collect();
    let names: Vec<&str> = laws.iter().map(|l| l.name.as_str()).collect();
    for want in [
        "neo_hookean",
        "saint_venant_kirchhoff",
        "mooney_rivlin",
        "test_wrong_tangent",
    ] {
        assert!(names.contains(&want), "{names:?}");
    }
    assert!(
        !names.contains(&"test_panic"),
        "test plugins are not shipped laws"
    );
    let svk = laws
        .iter()
        .find(|l| l.name == "saint_venant_kirchhoff")
        .unwrap();
    let text = svk.to_string();
    eprintln!("{text}");
    assert!(
        text.contains("lambda")
            && text.contains("lambda     Pa   default 400000")
            && text.contains("[0, ∞)")
    );
    let info = describe(&svk.path).unwrap();
    assert_eq!(&info, svk);
    let e = describe(Path::new("/no/such/libefsi_law_x.so")).unwrap_err();
    assert!(e.message.contains("library not found"), "{e}");
}

#[test]
fn batches_of_many_cells_and_threads() {
    let law = std::sync::Arc::new(load("mooney_rivlin", &[("C2", 1e4), ("C3", 2e4)]).unwrap());
    let states = efsi_laws_host::loader::tangent_check_states();
    let b: Vec<Sym> = (0..10_000).map(|k| states[k % states.len()]).collect();
    let (tau, j) = eval(&*law, &b).unwrap();
    let handles: Vec<_> = (0..2)
        .map(|_| {
            let (law, b) = (law.clone(), b.clone());
            std::thread::spawn(move || eval(&*law, &b).unwrap())
        })
        .collect();
    for h in handles {
        let (t2, j2) = h.join().unwrap();
        assert_eq!(t2, tau);
        assert_eq!(j2, j);
    }
    // Empty batches are fine.
    law.evaluate(&[], &mut [], None).unwrap();
    // Mismatched slices are an error, not UB.
    let e = law.evaluate(&b[..2], &mut [[0.0; 4]; 1], None).unwrap_err();
    assert!(e.message.contains("evaluate called with 2"), "{e}");
    // Full batches, from two threads.
    let states6 = efsi_laws_host::loader::tangent_check_states_full();
    let b6: Vec<Sym6> = (0..10_000).map(|k| states6[k % states6.len()]).collect();
    let (tau6, j6) = eval_full(&*law, &b6).unwrap();
    let handles: Vec<_> = (0..2)
        .map(|_| {
            let (law, b6) = (law.clone(), b6.clone());
            std::thread::spawn(move || eval_full(&*law, &b6).unwrap())
        })
        .collect();
    for h in handles {
        assert_eq!(h.join().unwrap(), (tau6.clone(), j6.clone()));
    }
    let e = law
        .evaluate_full(&b6[..3], &mut [[0.0; 6]; 3], Some(&mut [[0.0; 36]; 2]))
        .unwrap_err();
    assert!(e.message.contains("evaluate called with 3"), "{e}");
}

/// Copies `plugins/law-template` to a temporary folder, renames the crate and the law, edits a
/// default, builds it with cargo on its own, loads the library by path and evaluates it.
#[test]
fn the_template_copies_builds_and_loads() {
    let start = Instant::now();
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let template = root.join("plugins/law-template");
    let sdk = std::fs::canonicalize(root.join("plugins/law-sdk")).unwrap();
    let tmp = std::env::temp_dir().join(format!("efsi-law-template-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&tmp);
    let krate = tmp.join("my_gent");
    std::fs::create_dir_all(krate.join("src")).unwrap();

    let edit = |text: String, from: &str, to: &str| {
        assert!(
            text.contains(from),
            "the template no longer contains {from:?}"
        );
        text.replacen(from, to, 1)
    };
    let cargo_toml = std::fs::read_to_string(template.join("Cargo.toml")).unwrap();
    let cargo_toml = edit(cargo_toml, "name = \"efsi-law-gent\"", "name = \"my-gent\"");
    let cargo_toml = edit(
        cargo_toml,
        "name = \"efsi_law_gent\"",
        "name = \"efsi_law_my_gent\"",
    );
    let cargo_toml = edit(
        cargo_toml,
        "path = \"../law-sdk\"",
        &format!("path = {:?}", sdk.to_str().unwrap()),
    );
    std::fs::write(krate.join("Cargo.toml"), cargo_toml + "\n[workspace]\n").unwrap();
    let lib = std::fs::read_to_string(template.join("src/lib.rs")).unwrap();
    let lib = edit(
        lib,
        "const NAME: &'static str = \"gent\"",
        "const NAME: &'static str = \"my_gent\"",
    );
    let lib = edit(
        lib,
        "pub const DEFAULT_JM: f64 = 50.0;",
        "pub const DEFAULT_JM: f64 = 20.0;",
    );
    std::fs::write(krate.join("src/lib.rs"), lib).unwrap();

    let cargo = std::env::var("CARGO").unwrap_or_else(|_| "cargo".to_string());
    let out = Command::new(cargo)
        .args(["build", "--offline", "-j", "1", "--manifest-path"])
        .arg(krate.join("Cargo.toml"))
        .arg("--target-dir")
        .arg(tmp.join("target"))
        .env_remove("CARGO_TARGET_DIR")
        .env_remove("RUSTFLAGS")
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "building the copied template failed:\n{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let built = tmp.join("target/debug").join(library_file_name("my_gent"));
    assert!(built.is_file(), "{} was not built", built.display());

    // Named by a path relative to the "scene" folder `tmp`.
    let rel = built
        .strip_prefix(&tmp)
        .unwrap()
        .to_str()
        .unwrap()
        .to_string();
    let law = load_law(&spec(&rel, &[("G", 2e5)]), &tmp).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(law.name(), "my_gent");
    assert_eq!(
        law.parameter_values(),
        vec![("G".to_string(), 2e5), ("Jm".to_string(), 20.0)]
    );
    assert!(
        law.tangent_check().worst_relative_error < 1e-7,
        "{}",
        law.tangent_check()
    );
    let full = law.tangent_check_full().unwrap();
    assert!(full.worst_relative_error < 1e-7, "{full}");
    let b = [1.4, 0.9, 1.2, 0.3];
    let (tau, _) = eval(&law, &[b]).unwrap();
    let f = 2e5 * 20.0 / (20.0 - (b[0] + b[1] + b[2] - 3.0));
    assert!(close(&tau[0], &b.map(|x| f * x), 1e-9 * f), "{tau:?}");
    // A small locking limit puts some of the check's states outside the law's domain: they are
    // skipped, and the law still loads.
    let stiff = load_law(&spec(&rel, &[("Jm", 0.15)]), &tmp).unwrap_or_else(|e| panic!("{e}"));
    let check = stiff.tangent_check();
    eprintln!("Gent with Jm = 0.15: {check}");
    assert!(check.skipped > 0 && check.passed(), "{check}");
    drop(stiff);
    // Past the locking limit the law gives NaN, reported as a non-finite stress.
    let e = eval(&law, &[b, [30.0, 1.0, 1.0, 0.0]]).unwrap_err();
    assert!(e.message.contains("non-finite stress"), "{e}");
    assert_eq!(e.cell, Some(1), "{e}");
    drop(law);
    std::fs::remove_dir_all(&tmp).unwrap();
    eprintln!(
        "template copied, built and loaded in {:.1} s",
        start.elapsed().as_secs_f64()
    );
}
