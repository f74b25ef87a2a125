//! The stages' `numerics` sections: defaults, the strict preset, the checks each stage declares,
//! and the scene's round trip — through the declarations of the shipped plugins, as
//! `Simulation::new` checks them.

use efsi_core::Scene;
use efsi_core::scene::options::check_sections;
use efsi_core::scene::{Preset, StageOptions};
use efsi_run::SceneOverrides;
use efsi_stages::advection::AdvectionOptions;
use efsi_stages::elastic::{ElasticCoupling, ElasticOptions};
use efsi_stages::projection::{PressureSolver, ProjectionOptions};
use efsi_stages::viscous::ViscousOptions;
use std::path::Path;

const MIN: &str = r#"Scene(
    name: "t",
    domain: (x: (0.0, 1.0), y: (0.0, 1.0)),
    grid: (nx: 8, ny: 8),
    time: (end: 1.0),
    fluid: (density: 1.0, viscosity: 0.01),
    boundaries: (x_min: NoSlip, x_max: NoSlip, y_min: NoSlip, y_max: MovingWall(speed: 1.0)),
)"#;

/// The scene with `numerics` set to `n`, loaded and its sections checked by the shipped plugins.
fn with(n: &str) -> Result<Scene, String> {
    let text = MIN.replace("time:", &format!("numerics: {n},\n    time:"));
    let mut s = Scene::from_str_at(&text, Path::new("scene.ron")).map_err(|e| e.to_string())?;
    check_sections(&mut s, &efsi_stages::builtin()).map_err(|(f, m)| format!("{f}: {m}"))?;
    Ok(s)
}

/// Section `O` as a check of `s` (a copy) reads it for the stages' builds.
fn get<O: StageOptions>(s: &Scene) -> O {
    let mut s = s.clone();
    let options = check_sections(&mut s, &efsi_stages::builtin()).unwrap();
    options.section::<O>().unwrap().clone()
}

#[test]
fn defaults_apply_where_the_scene_is_silent() {
    let s = with("()").unwrap();
    let p: ProjectionOptions = get(&s);
    // The projection's tolerance, unset, is the scene's: 1e-4 with one fluid, 1e-6 with a
    // second material. The settings in force as JSON name it; the section's text keeps it unset,
    // so a checked scene given a solid afterwards resolves it anew.
    assert_eq!((p.tolerance, p.solver), (None, PressureSolver::Multigrid));
    let json = |s: &Scene, section: &str, field: &str| s.numerics.in_force(section, field).cloned();
    assert_eq!(json(&s, "projection", "tolerance"), Some(1e-4.into()));
    // So do the other defaults that depend on the scene: the advection's predictor (`WholeStep`
    // with one fluid, `Advection` with a second material) and the incremental projection (on
    // unless the scene has an elastic solid).
    assert_eq!(json(&s, "advection", "predictor"), Some("WholeStep".into()));
    assert_eq!(json(&s, "projection", "incremental"), Some(true.into()));
    assert_eq!(p.tolerance_in(&s), 1e-4);
    let text = MIN.replace(
        "time:",
        "solid: (shape: Disk(center: (0.5, 0.5), radius: 0.2), density: 2.0, viscosity: 0.01),\n    time:",
    );
    let mut two = Scene::from_str_at(&text, Path::new("two.ron")).unwrap();
    check_sections(&mut two, &efsi_stages::builtin()).unwrap();
    assert_eq!(json(&two, "projection", "tolerance"), Some(1e-6.into()));
    assert_eq!(
        json(&two, "advection", "predictor"),
        Some("Advection".into())
    );
    assert_eq!(json(&two, "projection", "incremental"), Some(true.into()));
    let mut later = s.clone();
    later.solid = two.solid.clone();
    assert_eq!(get::<ProjectionOptions>(&later).tolerance_in(&later), 1e-6);
    assert_eq!(get::<ViscousOptions>(&s).tolerance, 1e-3);
    assert_eq!(get::<ElasticOptions>(&s).tolerance, 1e-6);
    // Unset: the scene decides (`WholeStep` in a scene of one fluid).
    assert_eq!(get::<AdvectionOptions>(&s).predictor, None);
    // The checked scene holds every declared section with its settings in force.
    let names: Vec<&str> = s.numerics.sections().map(|(n, _)| n).collect();
    assert_eq!(
        names,
        ["advection", "contact", "elastic", "projection", "viscous"]
    );
}

/// `numerics.preset: Strict` tightens every tolerance to its strict value, keeps a tighter one
/// set beside it, survives the round trip through RON, and `Default` changes nothing.
#[test]
fn strict_preset_tightens_each_tolerance() {
    let s = with("(preset: Strict)").unwrap();
    assert_eq!(
        (
            get::<ProjectionOptions>(&s).tolerance_in(&s),
            get::<ViscousOptions>(&s).tolerance,
            get::<ElasticOptions>(&s).tolerance
        ),
        (1e-10, 1e-9, 1e-10)
    );
    let s = with("(preset: Strict, projection: (tolerance: 1e-12), viscous: (tolerance: 1e-3))")
        .unwrap();
    assert_eq!(get::<ProjectionOptions>(&s).tolerance, Some(1e-12));
    assert_eq!(get::<ViscousOptions>(&s).tolerance, 1e-9);
    let back = Scene::from_str_at(&s.to_ron(), Path::new("back.ron")).unwrap();
    assert_eq!(back.numerics.preset, Preset::Strict);
    assert_eq!(get::<ProjectionOptions>(&back).tolerance, Some(1e-12));
    let s = with("(preset: Default, viscous: (tolerance: 1e-4))").unwrap();
    assert_eq!(get::<ViscousOptions>(&s).tolerance, 1e-4);
    assert_eq!(get::<ProjectionOptions>(&s).tolerance_in(&s), 1e-4);
}

/// The elastic coupling: Auto by default, Split and Coupled by name (round trip); its tolerance,
/// iteration cap and its need of the implicit step checked by field.
#[test]
fn elastic_coupling_is_a_scene_option_checked_by_field() {
    let el = |e: &str| with(&format!("(elastic: {e})"));
    assert_eq!(
        get::<ElasticOptions>(&el("()").unwrap()).coupling,
        ElasticCoupling::Auto
    );
    let s = el("(coupling: Coupled, coupling_tolerance: 1e-4)").unwrap();
    let o: ElasticOptions = get(&s);
    assert_eq!(o.coupling, ElasticCoupling::Coupled);
    assert_eq!(o.coupling_tolerance, 1e-4);
    assert_eq!(o.stretch_theta(true), 0.75);
    assert_eq!(o.wave_cap(), 25.0);
    let split = get::<ElasticOptions>(&el("(coupling: Split)").unwrap());
    assert_eq!((split.stretch_theta(false), split.wave_cap()), (0.5, 4.0));
    for coupled in [false, true] {
        assert_eq!(
            get::<ElasticOptions>(&el("(theta: 0.6)").unwrap()).stretch_theta(coupled),
            0.6
        );
    }
    // Auto: each step its scheme's θ; Δt may reach the coupled step's cap, by default 200
    // (Coupled's 25 when set so).
    let auto: ElasticOptions = get(&el("()").unwrap());
    assert_eq!(auto.coupling, ElasticCoupling::Auto);
    assert_eq!(
        (
            auto.stretch_theta(false),
            auto.stretch_theta(true),
            auto.wave_cap()
        ),
        (0.5, 0.75, 200.0)
    );
    let capped = get::<ElasticOptions>(&el("(coupled_wave_courant: 25.0)").unwrap());
    assert_eq!(capped.wave_cap(), 25.0);
    // …and with the explicit elastic step it is accepted (every step is then split).
    assert!(el("(implicit: false)").is_ok());
    let back = Scene::from_str_at(&s.to_ron(), Path::new("back.ron")).unwrap();
    assert_eq!(
        get::<ElasticOptions>(&back).coupling,
        ElasticCoupling::Coupled
    );
    for (e, needles) in [
        (
            "(coupling: Coupled, coupling_tolerance: 0.0)",
            &["numerics.elastic.coupling_tolerance", "(0, 1)"][..],
        ),
        (
            "(coupling_tolerance: 1.5)",
            &["numerics.elastic.coupling_tolerance"],
        ),
        (
            "(coupling: Coupled, coupling_iterations: 0)",
            &["numerics.elastic.coupling_iterations", "≥ 1"],
        ),
        (
            "(coupling: Coupled, implicit: false)",
            &["numerics.elastic.coupling", "implicit"],
        ),
        ("(theta: 0.4)", &["numerics.elastic.theta", "[0.5, 1]"]),
        (
            "(coupling: Monolithic)",
            &["numerics.elastic", "Monolithic"],
        ),
        (
            "(wave_courant: 10.0)",
            &["numerics.elastic.wave_courant", "must be in (0, 4]"],
        ),
        (
            "(coupling: Coupled, coupled_wave_courant: 400.0)",
            &[
                "numerics.elastic.coupled_wave_courant",
                "must be in (0, 200]",
            ],
        ),
    ] {
        let m = el(e).unwrap_err();
        for n in needles {
            assert!(m.contains(n), "{e}: expected `{n}` in: {m}");
        }
    }
}

#[test]
fn pressure_solver_is_a_scene_option() {
    let s = with("(projection: (solver: IncompleteCholesky, tolerance: 1e-9))").unwrap();
    let p: ProjectionOptions = get(&s);
    assert_eq!(p.solver, PressureSolver::IncompleteCholesky);
    assert_eq!(p.tolerance, Some(1e-9));
    let again = Scene::from_str_at(&s.to_ron(), Path::new("again.ron")).unwrap();
    assert_eq!(
        get::<ProjectionOptions>(&again).solver,
        PressureSolver::IncompleteCholesky
    );
    let m = with("(projection: (solver: Jacobi))").unwrap_err();
    assert!(
        m.contains("numerics.projection") && m.contains("Jacobi"),
        "{m}"
    );
}

/// Each stage's ranges, by field, and a misspelt or unknown name named with where it is.
#[test]
fn bad_settings_name_the_setting_and_where_it_is() {
    for (n, needles) in [
        (
            "(viscous: (max_iterations: 0))",
            &["numerics.viscous.max_iterations", "must be ≥ 1"][..],
        ),
        (
            "(projection: (tolerance: 1e-308))",
            &[
                "numerics.projection.tolerance",
                "must be in [2.220446049250313e-16, 1)",
            ],
        ),
        ("(viscous: (theta: 0.2))", &["numerics.viscous.theta"]),
        (
            "(projection: (tolerence: 1e-3))",
            &["numerics.projection", "tolerence", "line 5, column"],
        ),
        (
            "(pressure: (tolerance: 1e-3))",
            &[
                "numerics.pressure",
                "no stage has a section `pressure`",
                "projection",
            ],
        ),
        (
            "(projection: (tolerance: NaN))",
            &["numerics.projection.tolerance"],
        ),
    ] {
        let m = with(n).unwrap_err();
        for needle in needles {
            assert!(m.contains(needle), "{n}: expected `{needle}` in: {m}");
        }
    }
}

/// A scene built in code sets a section by its type; `update` changes one field of it.
#[test]
fn sections_are_set_and_updated_in_code() {
    let mut s = with("()").unwrap();
    s.numerics
        .update(|p: &mut ProjectionOptions| p.tolerance = Some(1e-8))
        .unwrap();
    assert_eq!(get::<ProjectionOptions>(&s).tolerance, Some(1e-8));
    assert_eq!(get::<ProjectionOptions>(&s).max_iterations, 10000);
    s.numerics.set(&ViscousOptions {
        theta: 0.5,
        ..ViscousOptions::default()
    });
    let back = Scene::from_str_at(&s.to_ron(), Path::new("back.ron")).unwrap();
    assert_eq!(get::<ViscousOptions>(&back).theta, 0.5);
    assert_eq!(get::<ProjectionOptions>(&back).tolerance, Some(1e-8));
}

/// An override that names a section no stage has, or sets a stage's setting out of range, is
/// refused when the simulation is built, naming the override; the file's own mistakes name the
/// setting.
#[test]
fn simulation_refuses_bad_sections_naming_the_override() {
    use efsi_core::{Override, Simulation};
    let build = |overrides: &[Override], numerics: &str| {
        let text = MIN.replace("time:", &format!("numerics: {numerics},\n    time:"));
        let scene = Scene::from_str_with(&text, Path::new("scene.ron"), overrides)
            .map_err(|e| e.to_string())?;
        Simulation::new(scene, Path::new("scene.ron"), &efsi_stages::builtin())
            .map(|_| ())
            .map_err(|e| e.to_string())
    };
    let m = build(&[Override::set("numerics.pressure.tolerance", 1e-3)], "()").unwrap_err();
    assert!(
        m.contains("set numerics.pressure.tolerance=") && m.contains("no stage has a section"),
        "{m}"
    );
    let m = build(&[Override::set("numerics.viscous.tolerance", 2.0)], "()").unwrap_err();
    assert!(
        m.contains("set numerics.viscous.tolerance=2") && m.contains("must be in"),
        "{m}"
    );
    let m = build(&[], "(viscous: (tolerance: 2.0))").unwrap_err();
    assert!(
        m.starts_with("scene.ron: numerics.viscous.tolerance: must be in"),
        "{m}"
    );
    // A section the scene does not need is still checked (a typo stays a typo).
    let m = build(&[], "(elastic: (tolerance: 0.0))").unwrap_err();
    assert!(m.contains("numerics.elastic.tolerance"), "{m}");
    build(
        &[Override::set(
            "numerics.projection.solver",
            "IncompleteCholesky",
        )],
        "()",
    )
    .unwrap();
}

/// A stage's setting the scene leaves out reads as the stage's default through
/// `get_in_force` (what the Python binding and the FMU's start values use); `get` alone sees
/// only what the scene holds.
#[test]
fn settings_in_force_read_the_stages_defaults() {
    use efsi_core::OverrideValue;
    let s = Scene::from_str_at(MIN, Path::new("scene.ron")).unwrap();
    let builtin = efsi_stages::builtin();
    assert_eq!(
        s.get_in_force("numerics.projection.tolerance", &builtin)
            .unwrap(),
        OverrideValue::Float(1e-4)
    );
    assert_eq!(
        s.get_in_force("numerics.viscous.preconditioner", &builtin)
            .unwrap(),
        OverrideValue::Str("Jacobi".into())
    );
    assert!(s.get("numerics.projection.tolerance").is_err());
    assert_eq!(
        s.get_in_force("grid.nx", &builtin).unwrap(),
        OverrideValue::Int(8)
    );
}
