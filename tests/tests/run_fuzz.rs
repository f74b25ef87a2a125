//! The run loop under generated scenes: a structure-aware fuzzer (proptest, with shrinking).
//!
//! [`scene`] generates `Scene` values — geometry, domain, grid, time settings, fluid, gravity,
//! boundaries, an optional solid (disk, rectangle, half plane, unions, intersections,
//! differences; the built-in reference law or none), outputs (VTK, probes of every kind with
//! generated names, profiles) — mostly within range, with hostile numbers (0, −1, NaN, ±∞,
//! 1e308, 1e-300) and names (`.`, `..`, commas, newlines, `t`) mixed in. Each is written out as
//! RON, loaded from the file and, when accepted, run for a few steps (grids of at most 10×10,
//! at most 4 steps: a time and memory budget of milliseconds and kilobytes per case), stopped
//! by the stop flag set from the progress hook. Properties:
//! - a refusal names the file and the setting (or the stage or law), and is never an I/O
//!   error; nothing panics;
//! - the stop flag is honoured within one step: a run stopped after step N has taken N steps;
//! - every file a run writes is under its output folder;
//! - every row of `probes.csv` has the header's number of columns;
//! - a run stopped, then resumed from its checkpoint to a later stop, leaves the same bytes in
//!   `probes.csv`, `fields.pvd` and the VTK files as one run to that stop.
//!
//! A second target feeds the checkpoint decoder mutated checkpoints whose length and checksum
//! are made valid again, so that mutations reach the decoder's structure rather than stopping at
//! the checksum: it must refuse or decode, never panic, and what it decodes must fit or be
//! refused by the simulation.
//!
//! The time settings include `time.dt_min` down to 1e-300 and the output intervals go down to
//! 1e-300 too: an interval below the smallest step or below `time.end / 1e12` is refused (it
//! once hung the run in its event count before step 1), and one just above runs and stops.
//!
//! A third target applies generated `--set` / `--refine` overrides to the generated scenes
//! (hostile values among them: ±1e308, 5e-324, NaN, values nested 10,000 levels, strings of
//! 100,000 characters, `time.dt_min` and output intervals of 1e-300): a refusal names the file
//! and the override in a message of sane length without numbers in hundreds of digits, else
//! the run behaves as above. A fourth feeds the law loader copies of the real neo-Hookean
//! library cut short anywhere and with bytes of its ELF header, program headers, dynamic table
//! and section headers overwritten, and a library built for another ABI: each is refused with
//! the file named (or loads, where the bytes changed are ones the loader does not use), never
//! a crash.
//!
//! `EFSI_RUN_FUZZ_CASES=N` runs N scenes (default 200; ≈ 2 s), N scenes with overrides,
//! N·4 law libraries and N·8 checkpoints; the seed is fixed (`EFSI_RUN_FUZZ_SEED` changes it).
//! The figures are printed (`--nocapture`).

use efsi_core::scene::{
    Boundaries, Boundary, Domain, Fluid, GridSpec, Section, Side, TimeSpec, Vector, WallMotion,
    WallProfile,
};
use efsi_core::{Geometry, Override, OverrideValue, Scene};
use efsi_run::run::{RunOptions, StopReason, resume, run_with};
use efsi_run::{OutputSpec, ProbeSpec, ProfileSpec, SceneOverrides};
use efsi_stages::solid::{LawSpec, Shape, Solid};
use proptest::prelude::*;
use proptest::test_runner::{Config, RngAlgorithm, TestCaseError, TestRng, TestRunner};
use std::cell::RefCell;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::sync::atomic::{AtomicUsize, Ordering};

/// A number in `lo..hi` mostly, sometimes a hostile one.
fn num(lo: f64, hi: f64) -> BoxedStrategy<f64> {
    prop_oneof![
        200 => lo..hi,
        1 => Just(0.0),
        1 => Just(-1.0),
        1 => Just(f64::NAN),
        1 => Just(f64::INFINITY),
        1 => Just(1e308),
        1 => Just(1e-300),
    ]
    .boxed()
}

fn point() -> BoxedStrategy<(f64, f64)> {
    prop_oneof![
        9 => (num(0.0, 1.0), num(0.0, 1.0)),
        1 => (num(-0.2, 1.2), num(-0.2, 1.2)),
    ]
    .boxed()
}

fn shape() -> BoxedStrategy<Shape> {
    let leaf = prop_oneof![
        (point(), num(0.05, 0.5)).prop_map(|(center, radius)| Shape::Disk { center, radius }),
        (point(), num(0.05, 0.6), num(0.05, 0.6)).prop_map(|(min, w, h)| Shape::Rectangle {
            min,
            max: (min.0 + w, min.1 + h)
        }),
        (point(), num(-0.5, 1.0)).prop_map(|(normal, offset)| Shape::HalfPlane { normal, offset }),
    ];
    leaf.prop_recursive(3, 8, 3, |inner| {
        prop_oneof![
            prop::collection::vec(inner.clone(), 0..3).prop_map(Shape::Union),
            prop::collection::vec(inner.clone(), 0..3).prop_map(Shape::Intersection),
            (inner.clone(), inner).prop_map(|(a, b)| Shape::Difference(Box::new(a), Box::new(b))),
        ]
    })
    .boxed()
}

fn boundary() -> BoxedStrategy<Boundary> {
    prop_oneof![
        3 => Just(Boundary::NoSlip),
        1 => Just(Boundary::FreeSlip),
        1 => Just(Boundary::Outflow),
        1 => Just(Boundary::Periodic),
        1 => Just(Boundary::Outflow),
        2 => (num(-2.0, 2.0), prop::option::of(num(0.01, 0.5)), prop::option::of(num(0.1, 10.0)))
            .prop_map(|(speed, width, omega)| Boundary::MovingWall {
                speed,
                profile: width.map_or(WallProfile::Uniform, |width| WallProfile::Sin2Ramp { width }),
                motion: omega.map_or(WallMotion::Steady, |omega| WallMotion::Sin { omega }),
                direction: None,
            }),
    ]
    .boxed()
}

fn name() -> BoxedStrategy<String> {
    prop_oneof![
        60 => "[a-z][a-z0-9_]{0,6}",
        1 => Just(".".to_string()),
        1 => Just("..".to_string()),
        1 => Just("a,b".to_string()),
        1 => Just("x\ny".to_string()),
        1 => Just(String::new()),
        1 => Just("t".to_string()),
        1 => Just("kinetic_energy".to_string()),
    ]
    .boxed()
}

fn probe() -> BoxedStrategy<ProbeSpec> {
    let field = prop::sample::select(vec!["u", "v", "p", "speed", "density", "solid_fraction"]);
    let side = prop::sample::select(Side::ALL.to_vec());
    prop_oneof![
        4 => (name(), field, point()).prop_map(|(name, f, at)| ProbeSpec::Point { name, field: f.into(), at: at.into() }),
        2 => Just(ProbeSpec::KineticEnergy),
        1 => Just(ProbeSpec::PotentialEnergy),
        1 => Just(ProbeSpec::MaxDivergence),
        1 => Just(ProbeSpec::MaxSpeed),
        1 => Just(ProbeSpec::SolidVolume),
        1 => Just(ProbeSpec::SolidCentroid),
        1 => Just(ProbeSpec::SolidVelocity),
        1 => Just(ProbeSpec::ElasticEnergy),
        1 => side.clone().prop_map(|wall| ProbeSpec::ContactForce { wall }),
        1 => side.prop_map(|wall| ProbeSpec::ContactRadius { wall }),
        1 => num(-0.1, 1.1).prop_map(|at| ProbeSpec::SolidExtent { at, z: None }),
    ]
    .boxed()
}

fn profile() -> BoxedStrategy<ProfileSpec> {
    (
        name(),
        point(),
        point(),
        prop_oneof![8 => 2usize..20, 1 => Just(0usize), 1 => Just(100_000_000usize)],
        prop::collection::vec(prop::sample::select(vec!["u", "v", "p"]), 0..3),
        prop::collection::vec(num(0.0, 0.3), 0..3),
    )
        .prop_map(|(name, from, to, points, fields, at)| ProfileSpec::Line {
            name,
            from: from.into(),
            to: to.into(),
            points,
            fields: fields.into_iter().map(String::from).collect(),
            at,
        })
        .boxed()
}

fn solid() -> BoxedStrategy<Solid> {
    (
        shape(),
        num(0.5, 5.0),
        prop::option::of((num(-1.0, 1.0), num(-1.0, 1.0))),
        prop::option::of(num(1.0, 200.0)),
    )
        .prop_map(|(shape, density, velocity, g)| Solid {
            shape,
            density,
            viscosity: None,
            velocity: velocity.map(Into::into),
            law: g.map(|g| LawSpec {
                name: "neo_hookean".into(),
                parameters: [("G".to_string(), g)].into_iter().collect(),
            }),
        })
        .boxed()
}

/// Cells along one axis: 2 to 10, sometimes 1 (refused between sides that are not periodic).
fn cells() -> BoxedStrategy<usize> {
    prop_oneof![50 => 2usize..=10, 1 => Just(1usize)].boxed()
}

/// An output interval: mostly a fraction of the run, sometimes at or below the smallest step
/// or the run's length / 1e12 (1e-300, 1e-13, 1e-12 × a run of ≤ 0.5).
fn interval() -> BoxedStrategy<f64> {
    prop_oneof![
        100 => num(0.005, 0.2),
        1 => Just(1e-300),
        1 => Just(1e-13),
        1 => Just(1e-12),
        1 => Just(5e-13),
    ]
    .boxed()
}

/// A generated scene (see the module docs).
fn scene() -> impl Strategy<Value = Scene> {
    let time = (
        num(0.02, 0.5),
        num(0.1, 1.0),
        prop::option::of(num(0.001, 0.05)),
        prop::option::of(num(0.001, 0.05)),
        // The smallest step: mostly the default, sometimes as low as 1e-300 (which must not
        // let an output interval as small pass, see `interval`).
        prop::option::weighted(
            0.05,
            prop_oneof![num(1e-6, 1e-3), Just(1e-300), Just(1e-13), Just(1e-12)],
        ),
    );
    let output = (
        prop::option::of(interval()),
        prop::option::of(interval()),
        prop::collection::vec(probe(), 0..4),
        prop::collection::vec(profile(), 0..2),
    );
    (
        name(),
        prop::bool::weighted(0.2),
        // Mostly at least the 2 cells a non-periodic direction needs; sometimes 1.
        (cells(), cells()),
        time,
        (num(0.5, 2.0), num(0.0, 0.1)),
        prop::bool::weighted(0.3),
        prop::collection::vec(boundary(), 4),
        prop::option::weighted(0.4, solid()),
        output,
    )
        .prop_map(
            |(
                name,
                axi,
                (nx, ny),
                (end, cfl, dt_max, fixed_dt, dt_min),
                (density, viscosity),
                gravity,
                b,
                solid,
                (vtk_every, probe_every, probes, profiles),
            )| {
                let geometry = if axi {
                    Geometry::Axisymmetric
                } else {
                    Geometry::Planar
                };
                let mut solid = solid;
                if axi && let Some(s) = &mut solid {
                    s.velocity = s.velocity.map(|v| (0.0, v.1).into());
                }
                Scene {
                    name,
                    geometry,
                    domain: Domain::planar((0.0, 1.0), (0.0, 1.0)),
                    grid: GridSpec::planar(nx, ny),
                    time: TimeSpec {
                        end,
                        cfl,
                        dt_max,
                        dt_min,
                        fixed_dt: fixed_dt.filter(|_| dt_max.is_none()),
                        steady: None,
                    },
                    fluid: Fluid { density, viscosity },
                    gravity: if gravity {
                        Vector(0.0, -9.81, None)
                    } else {
                        Vector::default()
                    },
                    initial_velocity: Default::default(),
                    solid: solid.map(|s| Section::of(&s).expect("a solid serialises to RON")),
                    solids: None,
                    boundaries: {
                        // A periodic side mostly gets a periodic partner.
                        let mut b = b;
                        for (a, c) in [(0, 1), (2, 3)] {
                            if (b[a] == Boundary::Periodic) != (b[c] == Boundary::Periodic)
                                && !(nx + ny).is_multiple_of(5)
                            {
                                b[a] = Boundary::Periodic;
                                b[c] = Boundary::Periodic;
                            }
                        }
                        Boundaries::planar(
                            if axi { Boundary::Axis } else { b[0].clone() },
                            b[1].clone(),
                            b[2].clone(),
                            b[3].clone(),
                        )
                    },
                    physics: Default::default(),
                    numerics: Default::default(),
                    output: Section::of(&OutputSpec {
                        folder: None,
                        vtk_every,
                        vtk: Default::default(),
                        probe_every,
                        probes,
                        profiles,
                        slices: Vec::new(),
                    })
                    .unwrap(),
                    source_dir: None,
                    overrides: Vec::new(),
                }
            },
        )
}

#[derive(Debug, Default)]
struct Tally {
    cases: usize,
    refused_by_loader: usize,
    refused_by_simulation: usize,
    refused_by_run: usize,
    reached_a_step: usize,
    failed_numerically: usize,
    stopped: usize,
    resumed: usize,
}

/// Files under `dir`, recursively.
fn files(dir: &Path) -> Vec<PathBuf> {
    let mut out = Vec::new();
    for e in std::fs::read_dir(dir).into_iter().flatten().flatten() {
        let p = e.path();
        if p.is_dir() {
            out.extend(files(&p));
        } else {
            out.push(p);
        }
    }
    out
}

/// Every row of `probes.csv` in `out` has the header's column count.
fn check_csv(out: &Path, text: &str) -> Result<(), TestCaseError> {
    let Ok(csv) = std::fs::read_to_string(out.join("probes.csv")) else {
        return Ok(());
    };
    let mut lines = csv.lines();
    let columns = lines.next().map_or(0, |h| h.split(',').count());
    for l in lines {
        prop_assert_eq!(l.split(',').count(), columns, "row {} of\n{}", l, text);
    }
    prop_assert!(csv.ends_with('\n'));
    Ok(())
}

/// A run stopped by the flag after `stop_at` steps (total, counting from step 0).
fn options(stop_at: u64) -> (RunOptions, Arc<AtomicUsize>) {
    let flag = Arc::new(AtomicUsize::new(0));
    let opts = RunOptions {
        stop: Some(flag.clone()),
        ..RunOptions::default()
    };
    let _ = stop_at;
    (opts, flag)
}

fn one_case(
    scene: &Scene,
    overrides: &[Override],
    stop_at: u64,
    more: u64,
    root: &Path,
    tally: &RefCell<Tally>,
) -> Result<(), TestCaseError> {
    let mut t = tally.borrow_mut();
    t.cases += 1;
    let case = root.join(format!("case{}", t.cases));
    drop(t);
    let _ = std::fs::remove_dir_all(&case);
    std::fs::create_dir_all(&case).unwrap();
    let text = scene.to_ron();
    let path = case.join("scene.ron");
    std::fs::write(&path, &text).unwrap();
    let shown = path.display().to_string();
    let loaded = match Scene::load_with(&path, overrides) {
        Ok(s) => s,
        Err(e) => {
            let m = e.to_string();
            prop_assert!(
                m.starts_with(&shown),
                "refusal without the file: {}\n{}",
                m,
                text
            );
            // An override's error names the override (cut short when long), and no message
            // runs to thousands of characters or prints a number in hundreds of digits.
            if let efsi_core::SceneError::Override { setting, .. } = &e {
                prop_assert!(
                    overrides.iter().any(|o| o.brief() == *setting),
                    "{} names no override of {:?}",
                    m,
                    overrides
                );
            }
            prop_assert!(m.len() < 2_000, "a message of {} bytes", m.len());
            prop_assert!(!has_long_number(&m), "a long number in: {}", m);
            if std::env::var_os("EFSI_RUN_FUZZ_SHOW").is_some() {
                eprintln!("refused: {m}");
            }
            tally.borrow_mut().refused_by_loader += 1;
            let _ = std::fs::remove_dir_all(&case);
            return Ok(());
        }
    };
    let plugins = efsi_stages::builtin();
    let mut sim = match efsi_run::simulation(loaded, &path, &plugins) {
        Ok(s) => s,
        Err(e) => {
            prop_assert!(e.exit_code() == 2 || e.exit_code() == 3, "{}\n{}", e, text);
            if std::env::var_os("EFSI_RUN_FUZZ_SHOW").is_some() {
                eprintln!("not built: {e}");
            }
            tally.borrow_mut().refused_by_simulation += 1;
            let _ = std::fs::remove_dir_all(&case);
            return Ok(());
        }
    };
    // A run stopped after `stop_at` steps, then resumed to `stop_at + more`; and one run to
    // `stop_at + more`.
    let out = case.join("out");
    let (opts, flag) = options(stop_at);
    let result = run_with(&mut sim, &out, &opts, &mut |p| {
        if p.step >= stop_at {
            flag.store(2, Ordering::SeqCst);
        }
    });
    let outcome = match result {
        Ok(o) => o,
        Err(e) => {
            prop_assert!(e.exit_code() != 1, "an I/O error: {}\n{}", e, text);
            if std::env::var_os("EFSI_RUN_FUZZ_SHOW").is_some() {
                eprintln!("run failed: {e}\n{text}");
            }
            let mut t = tally.borrow_mut();
            if e.exit_code() == 3 {
                t.failed_numerically += 1;
            } else {
                t.refused_by_run += 1;
            }
            drop(t);
            for f in files(&case) {
                prop_assert!(
                    f.starts_with(&out) || f == path,
                    "{} outside the output folder",
                    f.display()
                );
            }
            let _ = std::fs::remove_dir_all(&case);
            return Ok(());
        }
    };
    if outcome.steps_this_run > 0 {
        tally.borrow_mut().reached_a_step += 1;
    }
    for f in files(&case) {
        prop_assert!(
            f.starts_with(&out) || f == path,
            "{} outside the output folder\n{}",
            f.display(),
            text
        );
    }
    check_csv(&out, &text)?;
    if let StopReason::Interrupted { .. } = outcome.stop {
        tally.borrow_mut().stopped += 1;
        // The stop is honoured at the first step boundary after the flag is set.
        prop_assert_eq!(outcome.steps, stop_at, "{}", text);
        let target = stop_at + more;
        let (opts, flag) = options(target);
        let resumed = resume(&out, &plugins, &opts, &mut |p| {
            if p.step >= target {
                flag.store(2, Ordering::SeqCst);
            }
        });
        let whole = case.join("whole");
        let mut sim =
            efsi_run::simulation(Scene::load_with(&path, overrides).unwrap(), &path, &plugins)
                .unwrap();
        let (opts, flag) = options(target);
        let straight = run_with(&mut sim, &whole, &opts, &mut |p| {
            if p.step >= target {
                flag.store(2, Ordering::SeqCst);
            }
        });
        match (resumed, straight) {
            (Ok((_, a)), Ok(b)) => {
                tally.borrow_mut().resumed += 1;
                prop_assert_eq!(a.steps, b.steps, "{}", text);
                check_csv(&out, &text)?;
                let mut names: Vec<PathBuf> = files(&whole)
                    .into_iter()
                    .filter(|f| {
                        let n = f.to_string_lossy();
                        n.ends_with(".csv") || n.ends_with(".vtr") || n.ends_with(".pvd")
                    })
                    .collect();
                names.sort();
                for f in names {
                    let rel = f.strip_prefix(&whole).unwrap();
                    let (x, y) = (
                        std::fs::read(&f).unwrap(),
                        std::fs::read(out.join(rel)).ok(),
                    );
                    prop_assert!(
                        Some(x) == y,
                        "{} differs after resume\n{}",
                        rel.display(),
                        text
                    );
                }
            }
            (Err(a), Err(b)) => {
                prop_assert_eq!(a.exit_code(), b.exit_code(), "{} / {}\n{}", a, b, text)
            }
            (a, b) => prop_assert!(
                false,
                "resume and the straight run disagree: {:?} / {:?}\n{}",
                a.map(|r| r.1.stop),
                b.map(|r| r.stop),
                text
            ),
        }
    }
    let _ = std::fs::remove_dir_all(&case);
    Ok(())
}

fn env(name: &str, default: u64) -> u64 {
    std::env::var(name)
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(default)
}

fn runner(cases: u64) -> TestRunner {
    let seed = env("EFSI_RUN_FUZZ_SEED", 20);
    let config = Config {
        cases: cases as u32,
        failure_persistence: None,
        max_shrink_iters: 256,
        ..Config::default()
    };
    let mut bytes = [0u8; 32];
    bytes[..8].copy_from_slice(&seed.to_le_bytes());
    TestRunner::new_with_rng(config, TestRng::from_seed(RngAlgorithm::ChaCha, &bytes))
}

#[test]
fn generated_scenes_run_stop_and_resume_cleanly() {
    let cases = env("EFSI_RUN_FUZZ_CASES", 200);
    let root = std::env::temp_dir().join(format!("efsi-run-fuzz-{}", std::process::id()));
    let tally = RefCell::new(Tally::default());
    let start = std::time::Instant::now();
    let result = runner(cases).run(&(scene(), 1u64..=3, 1u64..=2), |(s, stop_at, more)| {
        one_case(&s, &[], stop_at, more, &root, &tally)
    });
    let secs = start.elapsed().as_secs_f64();
    let _ = std::fs::remove_dir_all(&root);
    let t = tally.into_inner();
    eprintln!(
        "{} cases (with shrinking) in {secs:.2} s = {:.0} cases/s: {t:?}",
        t.cases,
        t.cases as f64 / secs
    );
    if let Err(e) = result {
        panic!("{e}");
    }
    // The generator must reach both sides: refusals, and runs that take steps and resume.
    assert!(
        t.refused_by_loader > 0 && t.reached_a_step > cases as usize / 8,
        "{t:?}"
    );
    assert!(t.resumed > 0, "{t:?}");
}

/// Whether `m` holds a run of more than 20 digits (a number printed in full, `1e308` as 309
/// digits).
fn has_long_number(m: &str) -> bool {
    let mut run = 0;
    for c in m.chars() {
        run = if c.is_ascii_digit() { run + 1 } else { 0 };
        if run > 20 {
            return true;
        }
    }
    false
}

/// An override's value as the command line gives it (RON text): mostly in range, sometimes
/// hostile — numbers at the ends of `f64`, NaN, nesting 10,000 levels deep, a long string.
fn override_value() -> BoxedStrategy<String> {
    prop_oneof![
        6 => num(0.0, 2.0).prop_map(|x| format!("{x:?}")),
        3 => (1i64..200).prop_map(|n| n.to_string()),
        1 => Just("1e308".to_string()),
        1 => Just("-1e308".to_string()),
        1 => Just("1e-308".to_string()),
        1 => Just("5e-324".to_string()),
        1 => Just("NaN".to_string()),
        1 => Just("(-1e308, 1e308)".to_string()),
        1 => Just("(0.0, 1e-300)".to_string()),
        1 => Just(format!("{}1{}", "(".repeat(10_000), ")".repeat(10_000))),
        1 => Just(format!("{}{}", "[".repeat(129), "]".repeat(129))),
        1 => Just("x".repeat(100_000)),
        1 => Just("[1, 2]".to_string()),
        1 => Just("abc".to_string()),
    ]
    .boxed()
}

/// A `--set PATH=VALUE` on a setting the generated scenes have (or can take), or a
/// `--refine F`.
fn an_override() -> BoxedStrategy<Override> {
    let paths = prop::sample::select(vec![
        "grid.nx",
        "grid.ny",
        "time.end",
        "time.cfl",
        "time.dt_min",
        "time.dt_max",
        "output.probe_every",
        "output.vtk_every",
        "fluid.density",
        "fluid.viscosity",
        "domain.x",
        "domain.y",
        "gravity.1",
        "name",
        "solid.shape.radius",
        "solid.shape.center[1]",
        "solid.law.parameters.G",
    ]);
    // Settings any generated scene takes, so that runs are reached with overrides too.
    let benign = prop::sample::select(vec![
        ("time.cfl", "0.3"),
        ("grid.nx", "6"),
        ("grid.ny", "5"),
        ("fluid.viscosity", "0.05"),
        ("time.dt_max", "0.01"),
        ("gravity.1", "-1.0"),
    ]);
    prop_oneof![
        8 => benign.prop_map(|(p, v)| Override::set(p, OverrideValue::Ron(v.into()))),
        8 => (paths, override_value())
            .prop_map(|(p, v)| Override::set(p, OverrideValue::Ron(v))),
        1 => prop_oneof![Just(1e-308), Just(0.01), Just(0.5), Just(2.0), Just(1e308)]
            .prop_map(Override::Refine),
    ]
    .boxed()
}

/// Generated scenes with generated `--set` / `--refine` overrides (and `time.dt_min` with
/// output intervals as small as 1e-300 among them): each is refused naming the file and the
/// override, with a message of sane length, or runs, stops and resumes as the scenes do.
#[test]
fn generated_overrides_are_refused_by_name_or_run_cleanly() {
    let cases = env("EFSI_RUN_FUZZ_CASES", 200);
    let root = std::env::temp_dir().join(format!("efsi-override-fuzz-{}", std::process::id()));
    let tally = RefCell::new(Tally::default());
    let start = std::time::Instant::now();
    let strategy = (
        scene(),
        prop::collection::vec(an_override(), 1..4),
        1u64..=3,
        1u64..=2,
    );
    let result = runner(cases).run(&strategy, |(s, overrides, stop_at, more)| {
        one_case(&s, &overrides, stop_at, more, &root, &tally)
    });
    let secs = start.elapsed().as_secs_f64();
    let _ = std::fs::remove_dir_all(&root);
    let t = tally.into_inner();
    eprintln!(
        "{} cases with overrides (with shrinking) in {secs:.2} s = {:.0} cases/s: {t:?}",
        t.cases,
        t.cases as f64 / secs
    );
    if let Err(e) = result {
        panic!("{e}");
    }
    assert!(t.refused_by_loader > 0 && t.reached_a_step > 0, "{t:?}");
}

/// How a library is broken: the length it is cut to, and bytes overwritten (offset, value).
type Breakage = (Option<usize>, Vec<(usize, u8)>);

/// A copy of a real law library, broken: cut short, bytes of its ELF header, program headers,
/// dynamic table or section headers (`regions`, as offset and length) overwritten, or both.
fn broken_library(len: usize, regions: Vec<(usize, usize)>) -> BoxedStrategy<Breakage> {
    let pokes = prop::collection::vec(
        (prop::sample::select(regions), any::<usize>(), any::<u8>())
            .prop_map(|((at, n), k, v)| (at + k % n.max(1), v)),
        0..6,
    );
    (
        prop_oneof![1 => Just(None), 2 => (1usize..len).prop_map(Some)],
        pokes,
    )
        .prop_filter("a change", |(cut, pokes)| {
            cut.is_some() || !pokes.is_empty()
        })
        .boxed()
}

/// The byte ranges of `b` (ELF64, little-endian) the loader reads first: the ELF header, the
/// program header table, the dynamic table, the section header table.
fn structure(b: &[u8]) -> Vec<(usize, usize)> {
    let u16_at = |at: usize| u16::from_le_bytes([b[at], b[at + 1]]) as usize;
    let u64_at = |at: usize| u64::from_le_bytes(b[at..at + 8].try_into().unwrap()) as usize;
    let (phoff, phnum, shoff, shnum) = (u64_at(32), u16_at(56), u64_at(40), u16_at(60));
    let mut out = vec![(0, 64), (phoff, phnum * 56), (shoff, shnum * 64)];
    for k in 0..phnum {
        let h = phoff + k * 56;
        if u32::from_le_bytes(b[h..h + 4].try_into().unwrap()) == 2 {
            out.push((u64_at(h + 8), u64_at(h + 32)));
        }
    }
    out
}

/// Law libraries made from a real one — truncated anywhere, structure bytes overwritten, and
/// a library built for another ABI — are refused with the file named, never loaded into a
/// crash (the loader checks a file before the dynamic loader maps it).
#[test]
fn broken_law_libraries_are_refused_with_the_file_named() {
    let cases = env("EFSI_RUN_FUZZ_CASES", 200) * 4;
    let root = std::env::temp_dir().join(format!("efsi-law-fuzz-{}", std::process::id()));
    std::fs::create_dir_all(&root).unwrap();
    let good_path = efsi_laws_host::loader::resolve_law("neo_hookean", Path::new("."))
        .expect("the shipped neo_hookean law is built (cargo build --workspace)");
    let good = std::fs::read(&good_path).unwrap();
    let counts = RefCell::new((0usize, 0usize, 0usize));
    let start = std::time::Instant::now();
    let result = runner(cases).run(
        &broken_library(good.len(), structure(&good)),
        |(cut, pokes)| {
            let mut b = good.clone();
            for (at, v) in pokes {
                if at < b.len() {
                    b[at] = v;
                }
            }
            if let Some(n) = cut {
                b.truncate(n);
            }
            let mut c = counts.borrow_mut();
            c.0 += 1;
            let lib = root.join(format!("libefsi_law_case{}.so", c.0));
            std::fs::write(&lib, &b).unwrap();
            match efsi_laws_host::describe(&lib) {
                Err(e) => {
                    c.1 += 1;
                    let m = e.to_string();
                    prop_assert!(m.contains(&lib.display().to_string()), "{}", m);
                }
                Ok(_) => c.2 += 1,
            }
            let _ = std::fs::remove_file(&lib);
            Ok(())
        },
    );
    let (all, refused, loaded) = counts.into_inner();
    eprintln!(
        "{all} broken law libraries in {:.2} s = {:.0} cases/s: {refused} refused, {loaded} loaded (bytes the loader does not use)",
        start.elapsed().as_secs_f64(),
        all as f64 / start.elapsed().as_secs_f64()
    );
    // Another ABI: the real test library built with a wrong version.
    let bad_abi = efsi_laws_host::loader::search_dirs()
        .iter()
        .map(|d| {
            d.join(format!(
                "{}efsi_test_law_bad_abi{}",
                std::env::consts::DLL_PREFIX,
                std::env::consts::DLL_SUFFIX
            ))
        })
        .find(|p| p.is_file());
    if let Some(p) = bad_abi {
        let e = efsi_laws_host::describe(&p).unwrap_err().to_string();
        assert!(e.contains("ABI"), "{e}");
    }
    let _ = std::fs::remove_dir_all(&root);
    if let Err(e) = result {
        panic!("{e}");
    }
    assert!(refused > all / 2, "{refused} of {all}");
}

/// A valid checkpoint of a small solid scene.
fn checkpoint_bytes() -> Vec<u8> {
    let text = r#"Scene(
    name: "ck",
    domain: (x: (0.0, 1.0), y: (0.0, 1.0)),
    grid: (nx: 12, ny: 12),
    time: (end: 0.1, dt_max: 0.01),
    fluid: (density: 1.0, viscosity: 0.01),
    solid: (shape: Disk(center: (0.5, 0.5), radius: 0.3), density: 2.0,
            law: (name: "neo_hookean", parameters: {"G": 10.0})),
    boundaries: (x_min: NoSlip, x_max: NoSlip, y_min: NoSlip, y_max: MovingWall(speed: 1.0)),
    output: (probes: [KineticEnergy], vtk_every: 0.05),
)"#;
    let scene = Scene::from_str_at(text, Path::new("ck.ron")).unwrap();
    let sim = efsi_run::simulation(scene, Path::new("ck.ron"), &efsi_stages::builtin()).unwrap();
    efsi_run::checkpoint::encode(&efsi_run::Checkpoint {
        efsi_version: "fuzz".into(),
        scene_path: "ck.ron".into(),
        scene_ron: sim.scene.to_ron(),
        overrides: Vec::new(),
        law: None,
        outputs: efsi_run::checkpoint::OutputState {
            pvd: vec![(0.0, "fields/ck_000000.vtr".into())],
            profile_times: vec![vec![0.05]],
            run_id: "0123456789abcdef".into(),
            ..Default::default()
        },
        snapshot: sim.snapshot(),
    })
}

/// Make the header's length and checksum fit the (mutated) payload again.
fn reseal(bytes: &mut [u8]) {
    if bytes.len() < 28 {
        return;
    }
    let len = (bytes.len() - 28) as u64;
    bytes[12..20].copy_from_slice(&len.to_le_bytes());
    let sum = efsi_run::binary::checksum(&bytes[28..]);
    bytes[20..28].copy_from_slice(&sum.to_le_bytes());
}

#[test]
fn the_checkpoint_decoder_refuses_or_decodes_mutated_files() {
    let valid = checkpoint_bytes();
    let scene = Scene::from_str_at(
        &efsi_run::checkpoint::decode(&valid, "ck")
            .unwrap()
            .scene_ron,
        Path::new("ck.ron"),
    )
    .unwrap();
    let template = efsi_run::simulation(scene, Path::new("ck.ron"), &efsi_stages::builtin())
        .unwrap()
        .snapshot();
    let cases = env("EFSI_RUN_FUZZ_CASES", 200) * 8;
    let n = valid.len();
    // Mutations: bytes set (lengths and counts among them: 0, 0xff, small), a range cut out,
    // a range repeated, the file cut short; then resealed (or not).
    let mutation = (
        prop::collection::vec(
            (28..n, prop_oneof![Just(0u8), Just(0xffu8), any::<u8>()]),
            0..6,
        ),
        prop::option::of((28..n, 0usize..64)),
        prop::option::of((28..n, 1usize..64)),
        prop::option::of(28..n),
        prop::bool::weighted(0.9),
    );
    let tally = RefCell::new((0usize, 0usize, 0usize));
    let start = std::time::Instant::now();
    let result = runner(cases).run(&mutation, |(sets, cut, repeat, truncate, seal)| {
        let mut b = valid.clone();
        for (at, v) in sets {
            b[at] = v;
        }
        if let Some((at, len)) = cut {
            let end = (at + len).min(b.len());
            b.drain(at.min(end)..end);
        }
        if let Some((at, len)) = repeat {
            let at = at.min(b.len());
            let piece: Vec<u8> = b[at..(at + len).min(b.len())].to_vec();
            b.splice(at..at, piece);
        }
        if let Some(at) = truncate {
            b.truncate(at);
        }
        if seal {
            reseal(&mut b);
        }
        let mut t = tally.borrow_mut();
        t.0 += 1;
        match efsi_run::checkpoint::decode(&b, "ck") {
            Err(e) => {
                t.1 += 1;
                prop_assert!(
                    e.exit_code() == 2 && e.to_string().starts_with("ck: "),
                    "{e}"
                );
            }
            Ok(file) => {
                t.2 += 1;
                if let Err(e) = file.record.into_snapshot(template.clone(), "ck") {
                    prop_assert!(e.to_string().starts_with("ck: "), "{e}");
                }
            }
        }
        Ok(())
    });
    let (all, refused, decoded) = tally.into_inner();
    eprintln!(
        "{all} mutated checkpoints in {:.2} s: {refused} refused, {decoded} decoded",
        start.elapsed().as_secs_f64()
    );
    if let Err(e) = result {
        panic!("{e}");
    }
    assert!(refused > 0 && decoded > 0);
}

/// Defects the fuzzers found, kept as regression cases: each scene is refused with a message
/// that names what is wrong.
#[test]
fn defects_found_by_the_fuzzers_stay_fixed() {
    let base = |shape: &str| {
        format!(
            r#"Scene(
    name: "r",
    domain: (x: (0.0, 1.0), y: (0.0, 1.0)),
    grid: (nx: 8, ny: 8),
    time: (end: 0.1, dt_max: 0.01),
    fluid: (density: 1.0, viscosity: 0.01),
    solid: (shape: {shape}, density: 2.0),
    boundaries: (x_min: NoSlip, x_max: NoSlip, y_min: NoSlip, y_max: NoSlip),
)"#
        )
    };
    // A disk with a NaN centre was refused as "radius must be finite and > 0, got 0.175".
    let e = Scene::from_str_with(
        &base("Disk(center: (NaN, 0.5), radius: 0.175)"),
        Path::new("r.ron"),
        &[],
    )
    .unwrap_err()
    .to_string();
    assert!(
        e.contains("solid.shape.center: Disk: center must be finite, got (NaN, 0.5)"),
        "{e}"
    );
    // A fluid of viscosity 1e308 ran into a conjugate gradient "not converged in 0 iterations
    // (relative residual NaN)": the viscous coefficients overflowed.
    let text = base("Disk(center: (0.5, 0.5), radius: 0.2)")
        .replace("viscosity: 0.01", "viscosity: 1e308");
    let e = Scene::from_str_at(&text, Path::new("r.ron"))
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("fluid.viscosity: 1e308 makes the diffusion number μ·time.end/(ρh²)"),
        "{e}"
    );
    // Seeds 2 and 3 of the mutation fuzzer gave the same inputs (`Rng(seed | 1)`): covered by
    // scene_fuzz.rs's `different_seeds_give_different_streams`.
}
