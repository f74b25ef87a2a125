//! The library through its C API, loaded with `libloading` from an extracted-FMU folder the way
//! an importer loads it (not through the `fmi` crate: its `fmi-sys` runs bindgen, which needs
//! libclang on every machine that builds the tests). FMI 3.0 is used where messages matter (its
//! logger is not variadic, so a Rust test can receive them); FMI 2.0 for its own life cycle.
//!
//! Each test copies the built library and the laws it needs into a fresh folder laid out as an
//! extracted FMU (`binaries/x86_64-linux/`): the library looks for laws there and nowhere else.
//! Calls that would have crashed the importer before (freeing foreign or freed handles) run in
//! a child process (this test binary, re-run on one test), so that a crash fails the test
//! instead of ending the test run.

use efsi_core::overrides::Override;
use efsi_core::{Advance, Scene};
use efsi_fmu::spec::{SPHERE, Spec};
use efsi_run::SceneOverrides;
use libloading::{Library, Symbol};
use std::ffi::{CStr, CString, c_char, c_int, c_void};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::{Mutex, OnceLock};

const H: f64 = 1.0 / 1024.0;
const OK: c_int = 0;
const DISCARD: c_int = 2;
const ERROR: c_int = 3;

/// The sphere FMU's scene file.
fn sphere_scene() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("sphere_impact.ron")
}

/// The sphere FMU's spec (what `cargo xtask fmu` packages).
fn spec() -> &'static Spec {
    static SPEC: OnceLock<Spec> = OnceLock::new();
    SPEC.get_or_init(|| {
        let flags: Vec<String> = SPHERE.iter().map(|s| s.to_string()).collect();
        Spec::from_args(&sphere_scene(), &flags).unwrap()
    })
}

/// The value reference of the variable `name`.
fn vr(name: &str) -> u32 {
    spec()
        .variables()
        .unwrap()
        .iter()
        .find(|v| v.name == name)
        .unwrap_or_else(|| panic!("no variable {name}"))
        .vr
}

/// A library built next to this test (`target/<profile>/deps`, or its parent).
fn built(file: &str) -> PathBuf {
    let exe = std::env::current_exe().unwrap();
    let deps = exe.parent().unwrap().to_path_buf();
    [deps.clone(), deps.parent().unwrap().to_path_buf()]
        .iter()
        .map(|d| d.join(file))
        .find(|p| p.is_file())
        .unwrap_or_else(|| panic!("no {file} next to {}", deps.display()))
}

/// An FMU extracted into a folder of its own, its library loaded.
struct Extracted {
    dir: PathBuf,
    lib: Option<Library>,
}

static FOLDERS: AtomicUsize = AtomicUsize::new(0);

impl Extracted {
    /// A folder with the FMU library and these laws (`(built library stem, law name)`).
    fn with_laws(laws: &[(&str, &str)]) -> Self {
        let dir = std::env::temp_dir().join(format!(
            "efsi-fmu-c-api-{}-{}",
            std::process::id(),
            FOLDERS.fetch_add(1, Ordering::Relaxed)
        ));
        let bin = dir.join("binaries/x86_64-linux");
        std::fs::create_dir_all(&bin).unwrap();
        std::fs::create_dir_all(dir.join("resources")).unwrap();
        std::fs::write(dir.join("resources/fmu.ron"), spec().to_ron()).unwrap();
        std::fs::copy(built("libefsi_fmu.so"), bin.join("sphere_impact.so")).unwrap();
        for (stem, name) in laws {
            std::fs::copy(
                built(&format!("lib{stem}.so")),
                bin.join(format!("libefsi_law_{name}.so")),
            )
            .unwrap();
        }
        // SAFETY: our own library; its initialisers are Rust's.
        let lib = unsafe { Library::new(bin.join("sphere_impact.so")) }.unwrap();
        Extracted {
            dir,
            lib: Some(lib),
        }
    }

    /// The usual one: the neo-Hookean law only.
    fn new() -> Self {
        Self::with_laws(&[("efsi_law_neo_hookean", "neo_hookean")])
    }

    fn lib(&self) -> &Library {
        self.lib.as_ref().unwrap()
    }
}

impl Drop for Extracted {
    fn drop(&mut self) {
        drop(self.lib.take());
        let _ = std::fs::remove_dir_all(&self.dir);
    }
}

type Messages = Mutex<Vec<String>>;

unsafe extern "C" fn collect(
    env: *mut c_void,
    _status: c_int,
    _cat: *const c_char,
    msg: *const c_char,
) {
    // SAFETY: `env` is the `Messages` the test passed; `msg` is NUL-terminated.
    let (messages, text) = unsafe { (&*(env as *const Messages), CStr::from_ptr(msg)) };
    messages
        .lock()
        .unwrap()
        .push(text.to_string_lossy().into_owned());
}

type Logger3 = unsafe extern "C" fn(*mut c_void, c_int, *const c_char, *const c_char);
type Instantiate3 = unsafe extern "C" fn(
    *const c_char,
    *const c_char,
    *const c_char,
    bool,
    bool,
    bool,
    bool,
    *const u32,
    usize,
    *mut c_void,
    Option<Logger3>,
    *mut c_void,
) -> *mut c_void;
type Unary = unsafe extern "C" fn(*mut c_void) -> c_int;
type EnterInit3 = unsafe extern "C" fn(*mut c_void, bool, f64, f64, bool, f64) -> c_int;
type SetF64 = unsafe extern "C" fn(*mut c_void, *const u32, usize, *const f64, usize) -> c_int;
type GetF64 = unsafe extern "C" fn(*mut c_void, *const u32, usize, *mut f64, usize) -> c_int;
type SetI32 = unsafe extern "C" fn(*mut c_void, *const u32, usize, *const i32, usize) -> c_int;
type GetI64 = unsafe extern "C" fn(*mut c_void, *const u32, usize, *mut i64, usize) -> c_int;
type SetStr =
    unsafe extern "C" fn(*mut c_void, *const u32, usize, *const *const c_char, usize) -> c_int;
type DoStep3 = unsafe extern "C" fn(
    *mut c_void,
    f64,
    f64,
    bool,
    *mut bool,
    *mut bool,
    *mut bool,
    *mut f64,
) -> c_int;
type StateFn = unsafe extern "C" fn(*mut c_void, *mut *mut c_void) -> c_int;
type SetStateFn = unsafe extern "C" fn(*mut c_void, *mut c_void) -> c_int;
type SizeFn = unsafe extern "C" fn(*mut c_void, *mut c_void, *mut usize) -> c_int;
type SerializeFn = unsafe extern "C" fn(*mut c_void, *mut c_void, *mut u8, usize) -> c_int;
type DeserializeFn = unsafe extern "C" fn(*mut c_void, *const u8, usize, *mut *mut c_void) -> c_int;
type Logging = unsafe extern "C" fn(*mut c_void, bool, usize, *const *const c_char) -> c_int;

/// An FMI 3.0 instance whose messages are collected.
struct Fmi3<'l> {
    lib: &'l Library,
    instance: *mut c_void,
    messages: Box<Messages>,
}

impl<'l> Fmi3<'l> {
    fn new(fmu: &'l Extracted) -> Self {
        let lib = fmu.lib();
        let token = CString::new(spec().token()).unwrap();
        let messages = Box::new(Messages::default());
        let instance = unsafe {
            lib.get::<Instantiate3>(b"fmi3InstantiateCoSimulation")
                .unwrap()(
                c"test".as_ptr(),
                token.as_ptr(),
                std::ptr::null(),
                false,
                false,
                false,
                false,
                std::ptr::null(),
                0,
                &*messages as *const Messages as *mut c_void,
                Some(collect),
                std::ptr::null_mut(),
            )
        };
        assert!(!instance.is_null(), "{:?}", messages.lock().unwrap());
        Fmi3 {
            lib,
            instance,
            messages,
        }
    }

    /// The last message, or "".
    fn last(&self) -> String {
        self.messages
            .lock()
            .unwrap()
            .last()
            .cloned()
            .unwrap_or_default()
    }

    fn call(&self, name: &str) -> c_int {
        unsafe { self.lib.get::<Unary>(name.as_bytes()).unwrap()(self.instance) }
    }

    fn set_real(&self, vr: u32, v: f64) -> c_int {
        unsafe { self.lib.get::<SetF64>(b"fmi3SetFloat64").unwrap()(self.instance, &vr, 1, &v, 1) }
    }

    fn set_int(&self, vr: u32, v: i32) -> c_int {
        unsafe { self.lib.get::<SetI32>(b"fmi3SetInt32").unwrap()(self.instance, &vr, 1, &v, 1) }
    }

    fn set_string(&self, vr: u32, v: &str) -> c_int {
        let s = CString::new(v).unwrap();
        let p = s.as_ptr();
        unsafe { self.lib.get::<SetStr>(b"fmi3SetString").unwrap()(self.instance, &vr, 1, &p, 1) }
    }

    fn real(&self, vr: u32) -> f64 {
        let mut v = f64::NAN;
        let s = unsafe {
            self.lib.get::<GetF64>(b"fmi3GetFloat64").unwrap()(self.instance, &vr, 1, &mut v, 1)
        };
        assert_eq!(s, OK, "{}", self.last());
        v
    }

    fn reals(&self, vrs: &[u32]) -> Vec<f64> {
        vrs.iter().map(|&r| self.real(r)).collect()
    }

    fn steps(&self) -> i64 {
        let mut v = -1;
        let r = vr("steps");
        let s = unsafe {
            self.lib.get::<GetI64>(b"fmi3GetInt64").unwrap()(self.instance, &r, 1, &mut v, 1)
        };
        assert_eq!(s, OK, "{}", self.last());
        v
    }

    fn enter_init(&self, stop: Option<f64>) -> c_int {
        unsafe {
            self.lib
                .get::<EnterInit3>(b"fmi3EnterInitializationMode")
                .unwrap()(
                self.instance,
                false,
                0.0,
                0.0,
                stop.is_some(),
                stop.unwrap_or(0.0),
            )
        }
    }

    /// A 14 x 28 grid (6 cells per radius), the sphere 6 mm above the substrate, `radius`;
    /// through initialisation (returns the status of `fmi3ExitInitializationMode`).
    fn setup(&self, stop: Option<f64>, radius: f64) -> c_int {
        assert_eq!(self.set_int(vr("grid.nr"), 14), OK);
        assert_eq!(self.set_int(vr("grid.nz"), 28), OK);
        assert_eq!(self.set_real(vr("solid.shape.center[1]"), 0.025), OK);
        assert_eq!(self.set_real(vr("solid.shape.radius"), radius), OK);
        assert_eq!(self.enter_init(stop), OK);
        self.call("fmi3ExitInitializationMode")
    }

    /// `fmi3DoStep`; returns the status and `lastSuccessfulTime`.
    fn step(&self, t: f64, h: f64) -> (c_int, f64) {
        let (mut a, mut b, mut c, mut last) = (true, true, true, f64::NAN);
        let s = unsafe {
            self.lib.get::<DoStep3>(b"fmi3DoStep").unwrap()(
                self.instance,
                t,
                h,
                false,
                &mut a,
                &mut b,
                &mut c,
                &mut last,
            )
        };
        if s == OK || s == DISCARD {
            assert!(!a && !b && !c);
        }
        (s, last)
    }

    /// A successful step (asserted), landing on `t + h`.
    fn do_step(&self, t: f64, h: f64) {
        let (s, last) = self.step(t, h);
        assert_eq!(s, OK, "{}", self.last());
        assert_eq!(last, t + h);
    }

    fn get_state(&self) -> *mut c_void {
        let mut s = std::ptr::null_mut();
        let r =
            unsafe { self.lib.get::<StateFn>(b"fmi3GetFMUState").unwrap()(self.instance, &mut s) };
        assert_eq!(r, OK, "{}", self.last());
        s
    }

    fn set_state(&self, s: *mut c_void) -> c_int {
        unsafe { self.lib.get::<SetStateFn>(b"fmi3SetFMUState").unwrap()(self.instance, s) }
    }

    fn free_state(&self, s: *mut *mut c_void) -> c_int {
        unsafe { self.lib.get::<StateFn>(b"fmi3FreeFMUState").unwrap()(self.instance, s) }
    }

    fn serialize(&self, s: *mut c_void) -> Vec<u8> {
        let mut n = 0;
        unsafe {
            assert_eq!(
                self.lib
                    .get::<SizeFn>(b"fmi3SerializedFMUStateSize")
                    .unwrap()(self.instance, s, &mut n),
                OK
            );
            let mut bytes = vec![0; n];
            assert_eq!(
                self.lib
                    .get::<SerializeFn>(b"fmi3SerializeFMUState")
                    .unwrap()(self.instance, s, bytes.as_mut_ptr(), n),
                OK,
                "{}",
                self.last()
            );
            bytes
        }
    }

    fn deserialize(&self, bytes: &[u8]) -> (c_int, *mut c_void) {
        let mut s = std::ptr::null_mut();
        let r = unsafe {
            self.lib
                .get::<DeserializeFn>(b"fmi3DeserializeFMUState")
                .unwrap()(self.instance, bytes.as_ptr(), bytes.len(), &mut s)
        };
        (r, s)
    }

    fn logging(&self, on: bool, categories: &[&CStr]) -> c_int {
        let p: Vec<*const c_char> = categories.iter().map(|c| c.as_ptr()).collect();
        unsafe {
            self.lib.get::<Logging>(b"fmi3SetDebugLogging").unwrap()(
                self.instance,
                on,
                p.len(),
                p.as_ptr(),
            )
        }
    }
}

impl Drop for Fmi3<'_> {
    fn drop(&mut self) {
        unsafe {
            self.lib
                .get::<unsafe extern "C" fn(*mut c_void)>(b"fmi3FreeInstance")
                .unwrap()(self.instance)
        }
    }
}

const OUTPUT_NAMES: [&str; 6] = [
    "solid_y",
    "solid_v",
    "contact_force",
    "contact_radius",
    "kinetic_energy",
    "elastic_energy",
];

fn outputs() -> Vec<u32> {
    OUTPUT_NAMES.iter().map(|n| vr(n)).collect()
}

/// The FMU's outputs equal the solver driven directly from the scene its parameters make (the
/// scene file with the same overrides), stepped the way `efsi run` steps to its output times,
/// its probes evaluated as `efsi run` evaluates them.
#[test]
fn fmi3_outputs_equal_the_solver_driven_directly() {
    let fmu = Extracted::new();
    let f = Fmi3::new(&fmu);
    let n = 10;
    assert_eq!(f.setup(Some(n as f64 * H), 0.0192), OK, "{}", f.last());
    let overrides = [
        Override::set("grid.nr", 14),
        Override::set("grid.nz", 28),
        Override::set("solid.shape.center[1]", 0.025),
        Override::set("time.end", n as f64 * H),
    ];
    let mut sim = efsi_run::simulation(
        Scene::load_with(sphere_scene(), &overrides).unwrap(),
        &sphere_scene(),
        &efsi_stages::builtin(),
    )
    .unwrap();
    let columns = efsi_fmu::spec::probe_columns(&sim.scene).unwrap();
    let probes = efsi_run::SceneOutput::output_spec(&sim.scene)
        .unwrap()
        .probes;
    let mut peak = 0.0f64;
    for k in 0..n {
        f.do_step(k as f64 * H, H);
        let until = (k + 1) as f64 * H;
        sim.advance_to(until, Advance::default()).unwrap();
        let mut row = Vec::new();
        for p in &probes {
            efsi_run::probes::evaluate(
                p,
                &sim.grid,
                &sim.state,
                sim.scene.gravity,
                sim.pipeline().outputs(),
                &mut row,
            );
        }
        for name in OUTPUT_NAMES {
            let want = row[columns.iter().position(|c| c == name).unwrap()];
            assert_eq!(f.real(vr(name)), want, "{name} at step {k}");
        }
        assert_eq!(f.real(vr("time")), until);
        assert_eq!(f.steps(), sim.state.step as i64);
        peak = peak.max(f.real(vr("contact_force")));
    }
    assert!(
        peak > 0.1,
        "the sphere reaches the substrate: peak force {peak} N per radian"
    );
}

#[test]
fn fmi3_refuses_a_bad_parameter_and_names_it_then_is_in_the_error_state() {
    let fmu = Extracted::new();
    let f = Fmi3::new(&fmu);
    assert_eq!(f.set_real(vr("solid.shape.radius"), -1.0), DISCARD);
    assert!(
        f.last()
            .contains("parameter `solid.shape.radius` = -1 m: outside its range [5e-324, 0.045] m"),
        "{}",
        f.last()
    );
    // In range but refused by the scene: a sphere 3 cells across.
    assert_eq!(f.set_int(vr("grid.nr"), 4), OK);
    assert_eq!(f.set_int(vr("grid.nz"), 8), OK);
    assert_eq!(f.enter_init(None), OK);
    assert_eq!(f.call("fmi3ExitInitializationMode"), ERROR);
    assert!(f.last().contains("refine the grid"), "{}", f.last());
    // After an Error only an FMU state or a reset goes on: other calls are refused, never crash.
    assert_eq!(f.step(0.0, H).0, ERROR);
    assert!(
        f.last()
            .contains("fmi3DoStep: not allowed in the Error state"),
        "{}",
        f.last()
    );
    assert_eq!(f.call("fmi3EnterEventMode"), ERROR);
    assert_eq!(f.call("fmi3Reset"), OK);
    assert_eq!(f.setup(None, 0.0192), OK, "{}", f.last());
    f.do_step(0.0, H);
}

/// `refine` is `efsi run --refine`: refine = 0.6 on the default 23 × 47 grid is the 14 × 28
/// grid (rounded), bit for bit; outside its range it is refused by name.
#[test]
fn the_refine_parameter_scales_the_grid_as_efsi_run_refine() {
    let fmu = Extracted::new();
    let by_grid = Fmi3::new(&fmu);
    assert_eq!(by_grid.setup(None, 0.0192), OK, "{}", by_grid.last());
    let by_refine = Fmi3::new(&fmu);
    assert_eq!(by_refine.set_real(vr("refine"), 20.0), DISCARD);
    assert!(
        by_refine
            .last()
            .contains("parameter `refine` = 20: outside its range [0.1, 10]"),
        "{}",
        by_refine.last()
    );
    assert_eq!(by_refine.set_real(vr("refine"), 0.6), OK);
    assert_eq!(by_refine.set_real(vr("solid.shape.center[1]"), 0.025), OK);
    assert_eq!(by_refine.enter_init(None), OK);
    assert_eq!(
        by_refine.call("fmi3ExitInitializationMode"),
        OK,
        "{}",
        by_refine.last()
    );
    for k in 0..3 {
        by_grid.do_step(k as f64 * H, H);
        by_refine.do_step(k as f64 * H, H);
        assert_eq!(by_refine.reals(&outputs()), by_grid.reals(&outputs()));
        assert_eq!(by_refine.steps(), by_grid.steps());
    }
    assert!(by_grid.steps() > 0);
}

#[test]
fn a_null_or_unknown_instance_is_an_error_not_a_crash() {
    let fmu = Extracted::new();
    for name in [&b"fmi2DoStep"[..], b"fmi3DoStep"] {
        let f: Symbol<DoStep3> = unsafe { fmu.lib().get(name) }.unwrap();
        for instance in [std::ptr::null_mut(), 0x1234_5678usize as *mut c_void] {
            let (mut a, mut b, mut c, mut t) = (false, false, false, 0.0);
            let s = unsafe { f(instance, 0.0, H, false, &mut a, &mut b, &mut c, &mut t) };
            assert_eq!(s, ERROR);
        }
    }
}

/// A state serialised by one extraction of the FMU sets into an instance of another extraction
/// (a fresh folder, as every importer makes), before that instance is initialised and with
/// another stop time, and the run continues bit for bit.
#[test]
fn serialised_states_move_between_extractions_and_set_before_initialisation() {
    let a_fmu = Extracted::new();
    let a = Fmi3::new(&a_fmu);
    assert_eq!(a.setup(Some(0.1), 0.0192), OK, "{}", a.last());
    for k in 0..4 {
        assert_eq!(
            a.set_real(vr("base_acceleration"), 3.0 * (k as f64).sin()),
            OK
        );
        a.do_step(k as f64 * H, H);
    }
    let state = a.get_state();
    let bytes = a.serialize(state);
    let folder = a_fmu.dir.display().to_string();
    assert!(
        !bytes.windows(folder.len()).any(|w| w == folder.as_bytes()),
        "the serialised state holds the extraction folder {folder}"
    );
    let run = |f: &Fmi3| -> Vec<f64> {
        let mut out = Vec::new();
        for k in 4..10 {
            assert_eq!(
                f.set_real(vr("base_acceleration"), 3.0 * (k as f64).sin()),
                OK
            );
            f.do_step(k as f64 * H, H);
            out.extend(f.reals(&outputs()));
            out.push(f.steps() as f64);
        }
        out
    };
    let first = run(&a);

    let b_fmu = Extracted::new();
    let b = Fmi3::new(&b_fmu);
    // Instantiated mode, default parameters (10 cells per radius), no stop time: the state
    // brings its parameters.
    let (r, copy) = b.deserialize(&bytes);
    assert_eq!(r, OK, "{}", b.last());
    assert_eq!(b.set_state(copy), OK, "{}", b.last());
    assert_eq!(b.real(vr("time")), 4.0 * H);
    assert_eq!(run(&b), first);
    // With another stop time set up first: accepted too.
    let c = Fmi3::new(&b_fmu);
    assert_eq!(c.enter_init(Some(0.05)), OK);
    let (r, copy) = c.deserialize(&bytes);
    assert_eq!(r, OK, "{}", c.last());
    assert_eq!(c.set_state(copy), OK, "{}", c.last());
    assert_eq!(run(&c), first);
    // A damaged state is refused by name, and leaves the Error state to a good one.
    let mut bad = bytes.clone();
    bad.truncate(bytes.len() - 10);
    assert_eq!(c.deserialize(&bad).0, ERROR);
    assert!(c.last().contains("serialised FMU state"), "{}", c.last());
}

/// A step whose solver fails inside the elastic stage (a law returning NaN past a stretch):
/// `Discard`, the instance exactly at the step's start (same outputs, same serialised state),
/// able to try again and to set a state taken before — the failure that used to leave it with
/// B̃ missing and the restore ignored.
#[test]
fn a_step_failing_in_the_elastic_stage_keeps_the_last_good_state() {
    // Soft: the sphere flattens until b11 passes the law's limit (1.7) and its stress is NaN.
    a_failing_law_leaves_the_last_good_state(
        ("efsi_test_law_nan", "test_nan"),
        2000.0,
        "stage `elastic`: law `test_nan`: non-finite stress",
    );
}

/// The same with a law that panics (past b11 = 10, which a very soft sphere reaches at
/// t ≈ 40 ms): the panic is caught in the law's library, the step is `Discard`, the model time
/// stays at the step's start and retries and states work — the failure that used to advance
/// the time past the failed step and refuse every retry.
#[test]
fn a_step_whose_law_panics_keeps_the_last_good_state() {
    a_failing_law_leaves_the_last_good_state(
        ("efsi_test_law_panic", "test_panic"),
        50.0,
        "stage `elastic`: law `test_panic`: panicked in evaluate: b11 = ",
    );
}

/// Step the sphere with the law `(library stem, name)` of shear modulus `g` until a step
/// fails with `expected` in its message, then check the instance is at its last good state.
fn a_failing_law_leaves_the_last_good_state(law: (&str, &str), g: f64, expected: &str) {
    let fmu = Extracted::with_laws(&[law]);
    let f = Fmi3::new(&fmu);
    assert_eq!(f.set_string(vr("solid.law.name"), law.1), OK);
    assert_eq!(f.set_real(vr("solid.law.parameters.G"), g), OK);
    assert_eq!(f.setup(None, 0.0192), OK, "{}", f.last());
    let mut t = 0.0;
    let mut good = std::ptr::null_mut();
    let (before, bytes) = loop {
        assert!(t < 0.05, "the law never failed");
        let s = unsafe { f.lib.get::<StateFn>(b"fmi3GetFMUState").unwrap()(f.instance, &mut good) };
        assert_eq!(s, OK);
        let before = (f.reals(&outputs()), f.steps());
        let (s, last) = f.step(t, H);
        if s == OK {
            t += H;
            continue;
        }
        assert_eq!(s, DISCARD, "{}", f.last());
        assert_eq!(last, t);
        break (before, f.serialize(good));
    };
    let message = f.last();
    assert!(
        message.contains("the solver failed between t = ")
            && message.contains(expected)
            && message.contains(&format!("the instance is back at t = {t} exactly")),
        "{message}"
    );
    assert_eq!((f.reals(&outputs()), f.steps()), before);
    assert_eq!(f.real(vr("time")), t);
    // The state now is the state before the call, byte for byte.
    let now = f.get_state();
    assert_eq!(f.serialize(now), bytes);
    // It may try again (FMI 3.0: Discard leaves it in step mode): the same failure.
    assert_eq!(f.step(t, H).0, DISCARD);
    assert_eq!(f.last(), message);
    // A shorter step gets further before the law fails, or through.
    let (s, _) = f.step(t, H / 8.0);
    assert!(s == OK || s == DISCARD, "{}", f.last());
    assert_eq!(f.set_state(good), OK, "{}", f.last());
    assert_eq!((f.reals(&outputs()), f.steps()), before);
}

#[test]
fn work_per_step_is_bounded_and_implausible_values_are_refused() {
    let fmu = Extracted::new();
    let f = Fmi3::new(&fmu);
    assert_eq!(f.set_int(vr("max_solver_steps_per_step"), 5), OK);
    assert_eq!(f.set_real(vr("solid.velocity[1]"), -1220.0), DISCARD);
    assert!(
        f.last().contains(
            "parameter `solid.velocity[1]` = -1220 m/s: outside its range [-100, 100] m/s"
        ),
        "{}",
        f.last()
    );
    assert_eq!(f.setup(None, 0.0192), OK, "{}", f.last());
    assert_eq!(f.set_real(vr("base_acceleration"), 1e12), DISCARD);
    assert!(
        f.last().contains(
            "input `base_acceleration` = 1000000000000 m/s2: outside its range [-1000, 1000] m/s2"
        ),
        "{}",
        f.last()
    );
    assert_eq!(f.real(vr("base_acceleration")), 0.0);
    // 20 ms at once needs more than 5 solver steps: refused before any work, time unchanged.
    let t0 = std::time::Instant::now();
    let (s, last) = f.step(0.0, 0.02);
    assert_eq!(s, DISCARD, "{}", f.last());
    assert_eq!(last, 0.0);
    assert!(
        f.last().contains("more than max_solver_steps_per_step = 5"),
        "{}",
        f.last()
    );
    assert!(t0.elapsed().as_secs_f64() < 1.0);
    assert_eq!(f.steps(), 0);
    // Shorter steps go through.
    f.do_step(0.0, H);
    assert!(f.steps() > 0);
}

#[test]
fn the_life_cycle_is_the_standards() {
    let fmu = Extracted::new();
    // Terminate before initialisation: Error, and the instance is in the Error state.
    let f = Fmi3::new(&fmu);
    assert_eq!(f.call("fmi3Terminate"), ERROR);
    assert!(
        f.last().contains(
            "fmi3Terminate: not allowed in the Instantiated state (illegal call sequence)"
        ),
        "{}",
        f.last()
    );
    assert_eq!(f.set_real(vr("solid.shape.radius"), 0.01), ERROR);
    assert_eq!(f.call("fmi3Reset"), OK);
    // An unknown log category: Error; a known one: OK.
    assert_eq!(f.logging(true, &[c"logInfo"]), OK);
    assert_eq!(f.logging(true, &[c"logEverything"]), ERROR);
    assert!(
        f.last()
            .contains("unknown log category `logEverything`; this FMU has: logStatusError, logStatusDiscard, logInfo"),
        "{}",
        f.last()
    );
    assert_eq!(f.call("fmi3Reset"), OK);
    assert_eq!(f.setup(Some(4.0 * H), 0.0192), OK, "{}", f.last());
    // A step too small to resolve: Discard, the time unchanged.
    assert_eq!(f.step(0.0, 1e-20), (DISCARD, 0.0));
    assert!(f.last().contains("too small to resolve"), "{}", f.last());
    f.do_step(0.0, H);
    assert_eq!(f.step(H, 1e-20), (DISCARD, H));
    // Past the stop time: Error.
    assert_eq!(f.step(H, 4.0 * H).0, ERROR);
    assert!(f.last().contains("past the stop time"), "{}", f.last());
    assert_eq!(f.call("fmi3Reset"), OK);
    assert_eq!(f.setup(None, 0.0192), OK);
    f.do_step(0.0, H);
    // A NaN communication point: Error, the time stays; after a state is set, the
    // communication-point check still works.
    let good = f.get_state();
    assert_eq!(f.step(f64::NAN, H).0, ERROR);
    assert!(
        f.last()
            .contains("the communication point NaN is not a finite number"),
        "{}",
        f.last()
    );
    assert_eq!(f.real(vr("time")), H);
    assert_eq!(f.set_state(good), OK);
    assert_eq!(f.step(0.5, H).0, ERROR);
    assert!(f.last().contains("is not the model's time"), "{}", f.last());
    assert_eq!(f.set_state(good), OK);
    f.do_step(H, H);
    // Terminate once; the second is refused.
    assert_eq!(f.call("fmi3Terminate"), OK);
    assert_eq!(f.call("fmi3Terminate"), ERROR);
}

/// A law that is not in the FMU is not found elsewhere (the build machine's target folder, the
/// importer's folder), and a path is not a law name.
#[test]
fn laws_are_looked_up_in_the_fmu_only() {
    let fmu = Extracted::new();
    let f = Fmi3::new(&fmu);
    assert_eq!(f.set_string(vr("solid.law.name"), "mooney_rivlin"), OK);
    assert_eq!(f.setup(None, 0.0192), ERROR);
    assert!(
        f.last().contains(
            "solid.law.name = \"mooney_rivlin\": no such law in the FMU (its binaries folder has: neo_hookean)"
        ),
        "{}",
        f.last()
    );
    let f = Fmi3::new(&fmu);
    let elsewhere = built("libefsi_law_mooney_rivlin.so");
    assert_eq!(
        f.set_string(vr("solid.law.name"), elsewhere.to_str().unwrap()),
        OK
    );
    assert_eq!(f.setup(None, 0.0192), ERROR);
    assert!(
        f.last().contains("must be a plain law name"),
        "{}",
        f.last()
    );
}

/// Run the test `name` of this binary in a child process with `EFSI_CHILD=1`; returns whether
/// it passed and its output.
fn in_child(name: &str) -> (bool, String) {
    let out = std::process::Command::new(std::env::current_exe().unwrap())
        .args(["--exact", name, "--nocapture", "--test-threads=1"])
        .env("EFSI_CHILD", "1")
        .output()
        .unwrap();
    (
        out.status.success(),
        format!(
            "{}\n{}\n{:?}",
            String::from_utf8_lossy(&out.stdout),
            String::from_utf8_lossy(&out.stderr),
            out.status
        ),
    )
}

/// The importer mistakes of issue 18, each of which crashed the importer: a state passed by
/// value where its address was meant, a pointer to something else, a state freed twice, an
/// instance freed twice or used after it was freed. Run in a child process.
#[test]
fn foreign_and_freed_handles_are_errors_not_crashes() {
    if std::env::var_os("EFSI_CHILD").is_none() {
        let (ok, output) = in_child("foreign_and_freed_handles_are_errors_not_crashes");
        assert!(ok, "the child crashed or failed: {output}");
        assert!(output.contains("1 passed"), "{output}");
        return;
    }
    let fmu = Extracted::new();
    let f = Fmi3::new(&fmu);
    assert_eq!(f.setup(None, 0.0192), OK);
    f.do_step(0.0, H);
    let mut state = f.get_state();
    // The handle itself where its address is expected.
    assert_eq!(f.free_state(state as *mut *mut c_void), ERROR);
    assert!(
        f.last().contains(
            "is an FMU state handle, passed where the address of a variable holding one is expected"
        ),
        "{}",
        f.last()
    );
    assert_eq!(f.call("fmi3Reset"), OK);
    assert_eq!(f.set_state(state), OK, "{}", f.last());
    // The address of something that is not a state handle.
    let mut garbage: *mut c_void = 0xdead_beefusize as *mut c_void;
    assert_eq!(f.free_state(&mut garbage), ERROR);
    assert!(
        f.last().contains("is not an FMU state of this instance"),
        "{}",
        f.last()
    );
    assert_eq!(f.set_state(state), OK);
    // An address that is not readable at all.
    assert_eq!(f.free_state(16usize as *mut *mut c_void), ERROR);
    assert!(
        f.last()
            .contains("is not the address of a writable FMU state variable"),
        "{}",
        f.last()
    );
    assert_eq!(f.set_state(state), OK);
    assert_eq!(f.set_state(0x42usize as *mut c_void), ERROR);
    // Freed twice through a copy of the handle.
    let mut copy = state;
    assert_eq!(f.set_state(state), OK);
    assert_eq!(f.free_state(&mut state), OK);
    assert!(state.is_null());
    assert_eq!(f.free_state(&mut copy), ERROR);
    assert!(f.last().contains("already freed"), "{}", f.last());
    // A state of another instance.
    let g = Fmi3::new(&fmu);
    assert_eq!(g.setup(None, 0.0192), OK);
    let theirs = g.get_state();
    assert_eq!(f.call("fmi3Reset"), OK);
    assert_eq!(f.set_state(theirs), ERROR);
    // An instance freed twice, and used after it was freed.
    let free: Symbol<unsafe extern "C" fn(*mut c_void)> =
        unsafe { fmu.lib().get(b"fmi3FreeInstance") }.unwrap();
    let handle = g.instance;
    unsafe {
        free(handle);
        free(handle);
    }
    assert_eq!(
        unsafe { fmu.lib().get::<Unary>(b"fmi3Terminate").unwrap()(handle) },
        ERROR
    );
    std::mem::forget(g);
    let free2: Symbol<unsafe extern "C" fn(*mut c_void)> =
        unsafe { fmu.lib().get(b"fmi2FreeInstance") }.unwrap();
    unsafe { free2(handle) };
}

#[repr(C)]
struct Callbacks2 {
    logger: *mut c_void,
    allocate: *mut c_void,
    free: *mut c_void,
    step_finished: *mut c_void,
    env: *mut c_void,
}

type Instantiate2 = unsafe extern "C" fn(
    *const c_char,
    c_int,
    *const c_char,
    *const c_char,
    *const Callbacks2,
    c_int,
    c_int,
) -> *mut c_void;
type GetReal2 = unsafe extern "C" fn(*mut c_void, *const u32, usize, *mut f64) -> c_int;
type SetInt2 = unsafe extern "C" fn(*mut c_void, *const u32, usize, *const c_int) -> c_int;
type SetReal2 = unsafe extern "C" fn(*mut c_void, *const u32, usize, *const f64) -> c_int;
type DoStep2 = unsafe extern "C" fn(*mut c_void, f64, f64, c_int) -> c_int;
type Status2 = unsafe extern "C" fn(*mut c_void, c_int, *mut f64) -> c_int;
type Serialize2 = unsafe extern "C" fn(*mut c_void, *mut c_void, *mut c_char, usize) -> c_int;
type Deserialize2 =
    unsafe extern "C" fn(*mut c_void, *const c_char, usize, *mut *mut c_void) -> c_int;

/// FMI 2.0 (no logger): get the state, step with a varying input, set it back and replay —
/// bit for bit, also through the serialised state; a discarded step leaves *stepFailed*, from
/// which setting a state goes on.
#[test]
fn fmi2_state_get_set_serialize_replays_bit_for_bit() {
    let fmu = Extracted::new();
    let lib = fmu.lib();
    let guid = CString::new(spec().token()).unwrap();
    let callbacks = Callbacks2 {
        logger: std::ptr::null_mut(),
        allocate: std::ptr::null_mut(),
        free: std::ptr::null_mut(),
        step_finished: std::ptr::null_mut(),
        env: std::ptr::null_mut(),
    };
    unsafe {
        let c = lib.get::<Instantiate2>(b"fmi2Instantiate").unwrap()(
            c"s".as_ptr(),
            1,
            guid.as_ptr(),
            std::ptr::null(),
            &callbacks,
            0,
            0,
        );
        assert!(!c.is_null());
        let unary = |n: &[u8]| lib.get::<Unary>(n).unwrap()(c);
        let set_real = |r: u32, v: f64| lib.get::<SetReal2>(b"fmi2SetReal").unwrap()(c, &r, 1, &v);
        let do_step = |t: f64, h: f64| lib.get::<DoStep2>(b"fmi2DoStep").unwrap()(c, t, h, 0);
        let (nr, nz) = (vr("grid.nr"), vr("grid.nz"));
        let small = || {
            assert_eq!(
                lib.get::<SetInt2>(b"fmi2SetInteger").unwrap()(c, &nr, 1, &14),
                OK
            );
            assert_eq!(
                lib.get::<SetInt2>(b"fmi2SetInteger").unwrap()(c, &nz, 1, &28),
                OK
            );
            assert_eq!(set_real(vr("solid.shape.center[1]"), 0.025), OK);
        };
        small();
        assert_eq!(unary(b"fmi2Terminate"), ERROR);
        assert_eq!(unary(b"fmi2Reset"), OK);
        small();
        // FMI 2.0 has no Discard for setters: an out-of-range value is an Error.
        assert_eq!(set_real(vr("base_acceleration"), 1e12), ERROR);
        assert_eq!(unary(b"fmi2Reset"), OK);
        small();
        assert_eq!(unary(b"fmi2EnterInitializationMode"), OK);
        assert_eq!(unary(b"fmi2ExitInitializationMode"), OK);
        let outputs = outputs();
        let run = |from: usize, n: usize| -> Vec<f64> {
            let mut out = Vec::new();
            for k in from..from + n {
                assert_eq!(
                    set_real(vr("base_acceleration"), 4.0 * (k as f64).sin()),
                    OK
                );
                assert_eq!(do_step(k as f64 * H, H), OK);
                let mut v = [0.0; 6];
                assert_eq!(
                    lib.get::<GetReal2>(b"fmi2GetReal").unwrap()(
                        c,
                        outputs.as_ptr(),
                        6,
                        v.as_mut_ptr()
                    ),
                    OK
                );
                out.extend(v);
            }
            out
        };
        run(0, 3);
        let mut state: *mut c_void = std::ptr::null_mut();
        assert_eq!(
            lib.get::<StateFn>(b"fmi2GetFMUstate").unwrap()(c, &mut state),
            OK
        );
        let first = run(3, 6);
        assert_eq!(
            lib.get::<SetStateFn>(b"fmi2SetFMUstate").unwrap()(c, state),
            OK
        );
        assert_eq!(run(3, 6), first);
        let mut size = 0;
        assert_eq!(
            lib.get::<SizeFn>(b"fmi2SerializedFMUstateSize").unwrap()(c, state, &mut size),
            OK
        );
        let mut bytes = vec![0 as c_char; size];
        let serialize = lib.get::<Serialize2>(b"fmi2SerializeFMUstate").unwrap();
        assert_eq!(serialize(c, state, bytes.as_mut_ptr(), size), OK);
        assert_eq!(serialize(c, state, bytes.as_mut_ptr(), size - 1), ERROR);
        // (an Error: the instance must be given a state back)
        assert_eq!(do_step(9.0 * H, H), ERROR);
        let mut copy: *mut c_void = std::ptr::null_mut();
        assert_eq!(
            lib.get::<Deserialize2>(b"fmi2DeSerializeFMUstate").unwrap()(
                c,
                bytes.as_ptr(),
                size,
                &mut copy
            ),
            OK
        );
        assert_eq!(
            lib.get::<SetStateFn>(b"fmi2SetFMUstate").unwrap()(c, copy),
            OK
        );
        assert_eq!(run(3, 6), first);
        // A discarded step (the step bound): stepFailed, last successful time = t; doStep is
        // refused there; setting a state goes on.
        assert_eq!(
            lib.get::<SetStateFn>(b"fmi2SetFMUstate").unwrap()(c, state),
            OK
        );
        let mut last = f64::NAN;
        assert_eq!(do_step(3.0 * H, 1000.0), DISCARD);
        assert_eq!(
            lib.get::<Status2>(b"fmi2GetRealStatus").unwrap()(c, 2, &mut last),
            OK
        );
        assert_eq!(last, 3.0 * H);
        assert_eq!(
            lib.get::<SetStateFn>(b"fmi2SetFMUstate").unwrap()(c, state),
            OK
        );
        assert_eq!(run(3, 6), first);
        for s in [&mut state, &mut copy] {
            assert_eq!(lib.get::<StateFn>(b"fmi2FreeFMUstate").unwrap()(c, s), OK);
            assert!(s.is_null());
        }
        assert_eq!(unary(b"fmi2Terminate"), OK);
        lib.get::<unsafe extern "C" fn(*mut c_void)>(b"fmi2FreeInstance")
            .unwrap()(c);
    }
}
