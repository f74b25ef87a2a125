use super::resolve::is_path;
use super::*;
use crate::NeoHookeanReference;

#[test]
fn reference_law_passes_the_tangent_check() {
    let c = check_tangent(&NeoHookeanReference { g: 1e6 }).unwrap();
    assert!(c.passed(), "{c}");
    assert!(c.worst_relative_error < 1e-8, "{c}");
}

#[test]
fn check_states_are_symmetric_positive_definite() {
    for b in tangent_check_states() {
        assert!(b[0] > 0.0 && b[2] > 0.0 && b[0] * b[1] - b[3] * b[3] > 0.0);
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
