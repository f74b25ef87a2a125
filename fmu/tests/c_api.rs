//! The FMU library through its C API, loaded with `libloading` as an importer loads it (not
//! through the `fmi` crate: its `fmi-sys` runs bindgen, which needs libclang on every machine
//! that builds the tests). FMI 3.0 is used where messages matter (its logger is not variadic,
//! so a Rust test can receive them); FMI 2.0 for FMU states.

use efsi_core::scene::Side;
use efsi_core::{Advance, Scene, Simulation};
use efsi_run::probes;
use libloading::{Library, Symbol};
use sphere_impact::Params;
use sphere_impact::model::vr;
use std::ffi::{CStr, c_char, c_int, c_void};
use std::path::PathBuf;
use std::sync::Mutex;

const H: f64 = 1.0 / 1024.0;
const OK: c_int = 0;
const ERROR: c_int = 3;

/// The cdylib cargo built next to this test (`target/<profile>/deps`, or its parent).
fn library() -> Library {
    let exe = std::env::current_exe().unwrap();
    let deps = exe.parent().unwrap().to_path_buf();
    let candidates: Vec<PathBuf> = [deps.clone(), deps.parent().unwrap().to_path_buf()]
        .iter()
        .map(|d| d.join("libsphere_impact.so"))
        .collect();
    let path = candidates
        .iter()
        .find(|p| p.is_file())
        .unwrap_or_else(|| panic!("no libsphere_impact.so in {candidates:?}"));
    // SAFETY: our own library; its initialisers are Rust's.
    unsafe { Library::new(path) }.unwrap()
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

/// An FMI 3.0 instance with `cells_per_radius` 6 and the sphere 6 mm above the substrate,
/// `change` applied to the radius (for the bad-parameter test).
struct Fmi3<'l> {
    lib: &'l Library,
    instance: *mut c_void,
}

impl<'l> Fmi3<'l> {
    fn new(lib: &'l Library, messages: &Messages) -> Self {
        let token = std::ffi::CString::new(sphere_impact::description::token()).unwrap();
        unsafe {
            let inst: Symbol<Instantiate3> = lib.get(b"fmi3InstantiateCoSimulation").unwrap();
            let instance = inst(
                c"test".as_ptr(),
                token.as_ptr(),
                std::ptr::null(),
                false,
                false,
                false,
                false,
                std::ptr::null(),
                0,
                messages as *const Messages as *mut c_void,
                Some(collect),
                std::ptr::null_mut(),
            );
            assert!(!instance.is_null(), "{:?}", messages.lock().unwrap());
            Fmi3 { lib, instance }
        }
    }

    fn call(&self, name: &[u8]) -> c_int {
        unsafe { self.lib.get::<Unary>(name).unwrap()(self.instance) }
    }

    fn set_real(&self, vr: u32, v: f64) -> c_int {
        unsafe { self.lib.get::<SetF64>(b"fmi3SetFloat64").unwrap()(self.instance, &vr, 1, &v, 1) }
    }

    fn real(&self, vr: u32) -> f64 {
        let mut v = f64::NAN;
        let s = unsafe {
            self.lib.get::<GetF64>(b"fmi3GetFloat64").unwrap()(self.instance, &vr, 1, &mut v, 1)
        };
        assert_eq!(s, OK);
        v
    }

    fn steps(&self) -> i64 {
        let mut v = -1;
        let r = vr::STEPS;
        let s = unsafe {
            self.lib.get::<GetI64>(b"fmi3GetInt64").unwrap()(self.instance, &r, 1, &mut v, 1)
        };
        assert_eq!(s, OK);
        v
    }

    fn setup(&self, stop: f64, radius: f64) -> c_int {
        unsafe {
            let cpr = vr::CELLS_PER_RADIUS;
            assert_eq!(
                self.lib.get::<SetI32>(b"fmi3SetInt32").unwrap()(self.instance, &cpr, 1, &6, 1),
                OK
            );
            assert_eq!(self.set_real(vr::INITIAL_HEIGHT, 0.025), OK);
            assert_eq!(self.set_real(vr::RADIUS, radius), OK);
            let enter: Symbol<EnterInit3> = self.lib.get(b"fmi3EnterInitializationMode").unwrap();
            assert_eq!(enter(self.instance, false, 0.0, 0.0, true, stop), OK);
        }
        self.call(b"fmi3ExitInitializationMode")
    }

    fn do_step(&self, t: f64, h: f64) -> c_int {
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
        if s == OK {
            assert!(!a && !b && !c);
            assert_eq!(last, t + h);
        }
        s
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

/// The FMU's outputs equal the solver driven directly from the scene its parameters make,
/// stepped the way `efsi run` steps to its output times.
#[test]
fn fmi3_outputs_equal_the_solver_driven_directly() {
    let lib = library();
    let messages = Messages::default();
    let fmu = Fmi3::new(&lib, &messages);
    let n = 10;
    assert_eq!(
        fmu.setup(n as f64 * H, 0.0192),
        OK,
        "{:?}",
        messages.lock().unwrap()
    );

    let params = Params {
        cells_per_radius: 6,
        initial_height: 0.025,
        ..Params::default()
    };
    let text = params.scene_ron("neo_hookean", n as f64 * H, H);
    let path = std::path::Path::new("direct.ron");
    let mut sim = Simulation::new(
        Scene::from_str_at(&text, path).unwrap(),
        path,
        &efsi_stages::builtin(),
    )
    .unwrap();
    let mut peak = 0.0f64;
    for k in 0..n {
        assert_eq!(
            fmu.do_step(k as f64 * H, H),
            OK,
            "{:?}",
            messages.lock().unwrap()
        );
        let until = (k + 1) as f64 * H;
        sim.advance_to(until, Advance::default()).unwrap();
        let m = probes::solid_moments(&sim.grid, &sim.state, sim.state.phi.as_ref().unwrap());
        let force =
            std::f64::consts::TAU * probes::contact_force(&sim.grid, &sim.state, Side::YMin);
        assert_eq!(fmu.real(vr::HEIGHT), m.centroid.1, "step {k}");
        assert_eq!(fmu.real(vr::VELOCITY), m.velocity.1, "step {k}");
        assert_eq!(fmu.real(vr::CONTACT_FORCE), force, "step {k}");
        assert_eq!(fmu.real(vr::TIME), until);
        assert_eq!(fmu.steps(), sim.state.step as i64);
        peak = peak.max(force);
    }
    assert!(
        peak > 1.0,
        "the sphere reaches the substrate: peak force {peak} N"
    );
}

#[test]
fn fmi3_refuses_a_bad_parameter_and_names_it() {
    let lib = library();
    let messages = Messages::default();
    let fmu = Fmi3::new(&lib, &messages);
    assert_eq!(fmu.setup(0.01, -1.0), ERROR);
    let log = messages.lock().unwrap().join("\n");
    assert!(
        log.contains("parameter `radius` = -1 m: must be a finite number > 0"),
        "{log}"
    );
    // Refused calls afterwards are errors too, never crashes.
    assert_eq!(fmu.do_step(0.0, H), ERROR);
    assert_eq!(fmu.call(b"fmi3EnterEventMode"), ERROR);
    assert!(
        messages
            .lock()
            .unwrap()
            .last()
            .unwrap()
            .contains("hasEventMode is false")
    );
}

#[test]
fn a_null_instance_is_an_error_not_a_crash() {
    let lib = library();
    for name in [&b"fmi2DoStep"[..], b"fmi3DoStep"] {
        let f: Symbol<DoStep3> = unsafe { lib.get(name) }.unwrap();
        let s = unsafe {
            f(
                std::ptr::null_mut(),
                0.0,
                H,
                false,
                std::ptr::null_mut(),
                std::ptr::null_mut(),
                std::ptr::null_mut(),
                std::ptr::null_mut(),
            )
        };
        assert_eq!(s, ERROR);
    }
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
type State2 = unsafe extern "C" fn(*mut c_void, *mut *mut c_void) -> c_int;
type SetState2 = unsafe extern "C" fn(*mut c_void, *mut c_void) -> c_int;
type Size2 = unsafe extern "C" fn(*mut c_void, *mut c_void, *mut usize) -> c_int;
type Serialize2 = unsafe extern "C" fn(*mut c_void, *mut c_void, *mut c_char, usize) -> c_int;
type Deserialize2 =
    unsafe extern "C" fn(*mut c_void, *const c_char, usize, *mut *mut c_void) -> c_int;

/// FMI 2.0 (no logger): get the state, step with a varying input, set it back and replay —
/// bit for bit, also through the serialised state.
#[test]
fn fmi2_state_get_set_serialize_replays_bit_for_bit() {
    let lib = library();
    let guid = std::ffi::CString::new(sphere_impact::description::token()).unwrap();
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
        let cpr = vr::CELLS_PER_RADIUS;
        assert_eq!(
            lib.get::<SetInt2>(b"fmi2SetInteger").unwrap()(c, &cpr, 1, &6),
            OK
        );
        assert_eq!(set_real(vr::INITIAL_HEIGHT, 0.025), OK);
        assert_eq!(unary(b"fmi2EnterInitializationMode"), OK);
        assert_eq!(unary(b"fmi2ExitInitializationMode"), OK);
        // A fixed parameter cannot change any more.
        assert_eq!(set_real(vr::RADIUS, 0.01), ERROR);
        let outputs = [
            vr::HEIGHT,
            vr::VELOCITY,
            vr::CONTACT_FORCE,
            vr::MAX_COMPRESSION,
            vr::KINETIC_ENERGY,
            vr::ELASTIC_ENERGY,
        ];
        let run = |from: usize, n: usize| -> Vec<f64> {
            let mut out = Vec::new();
            for k in from..from + n {
                assert_eq!(set_real(vr::BASE_ACCELERATION, 4.0 * (k as f64).sin()), OK);
                assert_eq!(
                    lib.get::<DoStep2>(b"fmi2DoStep").unwrap()(c, k as f64 * H, H, 0),
                    OK
                );
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
            lib.get::<State2>(b"fmi2GetFMUstate").unwrap()(c, &mut state),
            OK
        );
        let first = run(3, 6);
        assert_eq!(
            lib.get::<SetState2>(b"fmi2SetFMUstate").unwrap()(c, state),
            OK
        );
        assert_eq!(run(3, 6), first);
        let mut size = 0;
        assert_eq!(
            lib.get::<Size2>(b"fmi2SerializedFMUstateSize").unwrap()(c, state, &mut size),
            OK
        );
        let mut bytes = vec![0 as c_char; size];
        assert_eq!(
            lib.get::<Serialize2>(b"fmi2SerializeFMUstate").unwrap()(
                c,
                state,
                bytes.as_mut_ptr(),
                size
            ),
            OK
        );
        assert_eq!(
            lib.get::<Serialize2>(b"fmi2SerializeFMUstate").unwrap()(
                c,
                state,
                bytes.as_mut_ptr(),
                size - 1
            ),
            ERROR
        );
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
            lib.get::<SetState2>(b"fmi2SetFMUstate").unwrap()(c, copy),
            OK
        );
        assert_eq!(run(3, 6), first);
        // A communication point that is not the model's time is refused.
        assert_eq!(
            lib.get::<DoStep2>(b"fmi2DoStep").unwrap()(c, 0.5, H, 0),
            ERROR
        );
        for s in [&mut state, &mut copy] {
            assert_eq!(lib.get::<State2>(b"fmi2FreeFMUstate").unwrap()(c, s), OK);
            assert!(s.is_null());
        }
        lib.get::<unsafe extern "C" fn(*mut c_void)>(b"fmi2FreeInstance")
            .unwrap()(c);
    }
}
