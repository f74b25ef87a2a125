use super::resolve::is_path;
use super::*;
use crate::NeoHookeanReference;

#[test]
fn reference_law_passes_the_tangent_check() {
    let c = check_tangent(&NeoHookeanReference { g: 1e6 }).unwrap();
    assert!(c.passed(), "{c}");
    assert!(c.worst_relative_error < 1e-8, "{c}");
    let c = check_tangent_full(&NeoHookeanReference { g: 1e6 }).unwrap();
    assert!(c.passed() && c.worst_relative_error < 1e-8, "{c}");
}

/// A built-in law whose 3-D tangent misses the out-of-plane shears' cross terms (right in-plane,
/// wrong in 3-D): τ = B·B with the in-plane square's tangent padded with the identity.
struct InPlaneOnlyTangent;

impl crate::ConstitutiveLaw for InPlaneOnlyTangent {
    fn name(&self) -> &str {
        "in_plane_only_tangent"
    }
    fn evaluate(
        &self,
        b: &[crate::Sym],
        tau: &mut [crate::Sym],
        tangent: Option<&mut [crate::Tangent]>,
    ) -> Result<(), LawError> {
        for (t, b) in tau.iter_mut().zip(b) {
            let [b11, b22, b33, b12] = *b;
            *t = [
                b11 * b11 + b12 * b12,
                b22 * b22 + b12 * b12,
                b33 * b33,
                b12 * (b11 + b22),
            ];
        }
        if let Some(j) = tangent {
            for (j, b) in j.iter_mut().zip(b) {
                let [b11, b22, b33, b12] = *b;
                *j = [
                    2.0 * b11,
                    0.0,
                    0.0,
                    2.0 * b12,
                    0.0,
                    2.0 * b22,
                    0.0,
                    2.0 * b12,
                    0.0,
                    0.0,
                    2.0 * b33,
                    0.0,
                    b12,
                    b12,
                    0.0,
                    b11 + b22,
                ];
            }
        }
        Ok(())
    }
    fn evaluate_full(
        &self,
        b: &[crate::Sym6],
        tau: &mut [crate::Sym6],
        tangent: Option<&mut [crate::Tangent6]>,
    ) -> Result<(), LawError> {
        for (t, b) in tau.iter_mut().zip(b) {
            let [b11, b22, b33, b12, b23, b13] = *b;
            *t = [
                b11 * b11 + b12 * b12 + b13 * b13,
                b22 * b22 + b12 * b12 + b23 * b23,
                b33 * b33 + b13 * b13 + b23 * b23,
                b11 * b12 + b12 * b22 + b13 * b23,
                b12 * b13 + b22 * b23 + b23 * b33,
                b11 * b13 + b12 * b23 + b13 * b33,
            ];
        }
        if let Some(j) = tangent {
            let mut four = [[0.0; 16]; 1];
            for (j, b) in j.iter_mut().zip(b) {
                self.evaluate(
                    &[[b[0], b[1], b[2], b[3]]],
                    &mut [[0.0; 4]],
                    Some(&mut four),
                )?;
                *j = [0.0; 36];
                for a in 0..4 {
                    for c in 0..4 {
                        j[6 * a + c] = four[0][4 * a + c];
                    }
                }
                j[6 * 4 + 4] = 2.0 * b[1];
                j[6 * 5 + 5] = 2.0 * b[0];
            }
        }
        Ok(())
    }
}

/// The full check sees what the in-plane one cannot: a tangent right on in-plane tensors and
/// wrong in its out-of-plane rows and columns.
#[test]
fn the_full_check_catches_a_tangent_wrong_out_of_plane_only() {
    let in_plane = check_tangent(&InPlaneOnlyTangent).unwrap();
    assert!(in_plane.passed(), "{in_plane}");
    let full = check_tangent_full(&InPlaneOnlyTangent).unwrap();
    assert!(!full.passed(), "{full}");
    let (a, b) = full.worst_entry_names();
    assert!(
        ["23", "13"].contains(&a) || ["23", "13"].contains(&b),
        "{full}"
    );
}

#[test]
fn check_states_are_symmetric_positive_definite() {
    for b in tangent_check_states() {
        assert!(b[0] > 0.0 && b[2] > 0.0 && b[0] * b[1] - b[3] * b[3] > 0.0);
    }
    for b in tangent_check_states_full() {
        let [b11, b22, b33, b12, b23, b13] = b;
        let minor2 = b11 * b22 - b12 * b12;
        let det = b11 * (b22 * b33 - b23 * b23) - b12 * (b12 * b33 - b23 * b13)
            + b13 * (b12 * b23 - b22 * b13);
        assert!(b11 > 0.0 && minor2 > 0.0 && det > 0.0, "{b:?}");
    }
    // Every component varies across the full states, the out-of-plane shears included.
    let states = tangent_check_states_full();
    for c in 0..6 {
        assert!(states.iter().any(|b| b[c].abs() > 0.05), "component {c}");
    }
}

#[test]
fn names_and_paths() {
    assert!(is_path("./libx.so") && is_path("x.dll") && is_path("a/b"));
    assert!(!is_path("neo_hookean"));
    assert_eq!(
        library_file_name("neo_hookean"),
        format!(
            "{}efsi_law_neo_hookean{}",
            std::env::consts::DLL_PREFIX,
            std::env::consts::DLL_SUFFIX
        )
    );
    let e = resolve_law("no_such_law_xyz", Path::new(".")).unwrap_err();
    assert_eq!(e.law, "no_such_law_xyz");
    assert!(e.message.contains("target"), "{e}");
}

#[test]
fn range_text() {
    let p = ParamInfo {
        name: "G".into(),
        unit: "Pa".into(),
        description: String::new(),
        default: 1.0,
        min: 0.0,
        max: f64::INFINITY,
        min_exclusive: true,
        max_exclusive: false,
    };
    assert_eq!(p.range_text(), "(0, ∞)");
    assert!(!p.contains(0.0) && p.contains(1e9) && !p.contains(f64::INFINITY));
}

/// Every law library built beside the tests (the shipped laws and the test plugins) passes the
/// file check that runs before `dlopen`; a copy cut short anywhere in its loadable bytes fails
/// it.
#[test]
fn built_law_libraries_pass_the_file_check() {
    let mut checked = 0;
    for dir in search_dirs() {
        for e in std::fs::read_dir(&dir).into_iter().flatten().flatten() {
            let p = e.path();
            let name = p.file_name().unwrap().to_string_lossy().into_owned();
            if (name.starts_with("libefsi_law_") || name.starts_with("libefsi_test_law_"))
                && name.ends_with(".so")
            {
                elf::check_library_file(&p).unwrap_or_else(|e| panic!("{}: {e}", p.display()));
                checked += 1;
            }
        }
    }
    assert!(checked >= 3, "{checked} libraries found");
}

/// A law whose full evaluation is the reference neo-Hookean's, but whose in-plane shear stress
/// is 0.1 % off: the two evaluations are not one law.
struct TwoLaws;

impl crate::ConstitutiveLaw for TwoLaws {
    fn name(&self) -> &str {
        "two_laws"
    }
    fn evaluate(
        &self,
        b: &[crate::Sym],
        tau: &mut [crate::Sym],
        tangent: Option<&mut [crate::Tangent]>,
    ) -> Result<(), LawError> {
        NeoHookeanReference { g: 2.0 }.evaluate(b, tau, tangent)?;
        for t in tau.iter_mut() {
            t[3] *= 1.001;
        }
        Ok(())
    }
    fn evaluate_full(
        &self,
        b: &[crate::Sym6],
        tau: &mut [crate::Sym6],
        tangent: Option<&mut [crate::Tangent6]>,
    ) -> Result<(), LawError> {
        NeoHookeanReference { g: 2.0 }.evaluate_full(b, tau, tangent)
    }
}

/// The embedding check: the reference law's two evaluations agree exactly, a law computing the
/// full square in another order agrees to round-off, and two different laws are caught at the
/// component that differs.
#[test]
fn the_embedding_check_compares_the_two_evaluations() {
    let c = check_embedding(&NeoHookeanReference { g: 3.0 }).unwrap();
    assert_eq!(c.worst_relative_difference, 0.0, "{c}");
    assert_eq!(c.states, 26);
    let c = check_embedding(&InPlaneOnlyTangent).unwrap();
    assert!(c.passed() && c.worst_relative_difference < 1e-15, "{c}");
    let c = check_embedding(&TwoLaws).unwrap();
    assert!(!c.passed(), "{c}");
    assert_eq!(c.worst_entry, "τ12", "{c}");
    assert!((c.in_plane / c.full - 1.001).abs() < 1e-12, "{c}");
    assert!(c.worst_relative_difference > 1e-4, "{c}");
}

/// Past `b11 = 1.2` the law has no value in either evaluation (NaN): those states are skipped;
/// with `full_only` its in-plane evaluation fails there too but its full one does not, which is a
/// disagreement.
struct Domain {
    full_only: bool,
}

impl crate::ConstitutiveLaw for Domain {
    fn name(&self) -> &str {
        "domain"
    }
    fn evaluate(
        &self,
        b: &[crate::Sym],
        tau: &mut [crate::Sym],
        tangent: Option<&mut [crate::Tangent]>,
    ) -> Result<(), LawError> {
        if let Some(k) = b.iter().position(|b| b[0] > 1.2) {
            return Err(LawError {
                law: "domain".into(),
                message: "outside the domain".into(),
                cell: Some(k),
            });
        }
        NeoHookeanReference { g: 1.0 }.evaluate(b, tau, tangent)
    }
    fn evaluate_full(
        &self,
        b: &[crate::Sym6],
        tau: &mut [crate::Sym6],
        tangent: Option<&mut [crate::Tangent6]>,
    ) -> Result<(), LawError> {
        if !self.full_only
            && let Some(k) = b.iter().position(|b| b[0] > 1.2)
        {
            return Err(LawError {
                law: "domain".into(),
                message: "outside the domain".into(),
                cell: Some(k),
            });
        }
        NeoHookeanReference { g: 1.0 }.evaluate_full(b, tau, tangent)
    }
}

#[test]
fn the_embedding_check_skips_states_outside_the_domain() {
    let c = check_embedding(&Domain { full_only: false }).unwrap();
    assert!(c.passed() && c.states < 26 && c.states >= 13, "{c}");
    let skipped = tangent_check_states().iter().filter(|b| b[0] > 1.2).count();
    assert_eq!(c.states, 26 - skipped);
    let c = check_embedding(&Domain { full_only: true }).unwrap();
    assert!(!c.passed(), "{c}");
    assert!(c.worst_entry.contains("the full evaluation only"), "{c}");
}
