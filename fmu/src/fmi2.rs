//! The FMI 2.0 Co-Simulation C API (all 34 functions an importer such as fmpy binds; those
//! this model does not support log why and return `fmi2Error`), with the bodies and macros it
//! shares with FMI 3.0 ([`crate::shim`]).
//!
//! Supported: instantiation (Co-Simulation only), parameters and the input before and during
//! initialisation, the input between steps, outputs at any time, `fmi2DoStep` with any
//! communication step, `fmi2GetRealStatus(fmi2LastSuccessfulTime)`, reset, and FMU states:
//! get, set, free, serialise and deserialise. Not supported: input or output derivatives,
//! directional derivatives, asynchronous steps (`fmi2CancelStep`, the other status queries).

use crate::instance::{Instance, slice, slice_mut, text, with_instance};
use crate::log::{Fmi2Logger, Logger, Status, guard};
use crate::machine::Version;
use crate::model::Fault;
use crate::shim;
use std::ffi::{c_char, c_int, c_void};

/// FMI 2.0 defines `fmi2Discard` for steps only: a setter's refusal is an `fmi2Error`.
fn as_error(f: Fault) -> Fault {
    Fault::error(f.message)
}

/// `fmi2Component`.
pub type Component = *mut c_void;
/// `fmi2FMUstate`.
pub type FmuStatePtr = *mut c_void;

const FMI2_TRUE: c_int = 1;
const FMI2_CO_SIMULATION: c_int = 1;
const FMI2_LAST_SUCCESSFUL_TIME: c_int = 2;
const FMI2_TERMINATED: c_int = 3;

/// `fmi2CallbackFunctions`.
#[repr(C)]
pub struct CallbackFunctions {
    /// The logger.
    pub logger: Option<Fmi2Logger>,
    /// Memory allocation (unused: this FMU allocates with Rust's allocator).
    pub allocate_memory: Option<unsafe extern "C" fn(usize, usize) -> *mut c_void>,
    /// Memory release (unused).
    pub free_memory: Option<unsafe extern "C" fn(*mut c_void)>,
    /// Asynchronous step completion (unused).
    pub step_finished: Option<unsafe extern "C" fn(*mut c_void, c_int)>,
    /// Passed back with every log message.
    pub component_environment: *mut c_void,
}

/// `fmi2GetTypesPlatform`: `"default"`.
#[unsafe(no_mangle)]
pub extern "C" fn fmi2GetTypesPlatform() -> *const c_char {
    c"default".as_ptr()
}

/// `fmi2GetVersion`: `"2.0"`.
#[unsafe(no_mangle)]
pub extern "C" fn fmi2GetVersion() -> *const c_char {
    c"2.0".as_ptr()
}

/// `fmi2SetDebugLogging`: the named log categories (all when none is named) on or off; an
/// unknown category is an error.
///
/// # Safety
/// `c` must be an instance of this library; `categories` `n_categories` C strings.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2SetDebugLogging(
    c: Component,
    logging_on: c_int,
    n_categories: usize,
    categories: *const *const c_char,
) -> c_int {
    with_instance(c, "fmi2SetDebugLogging", |i| unsafe {
        shim::set_debug_logging(i, logging_on == FMI2_TRUE, n_categories, categories)
    })
}

/// `fmi2Instantiate`: a Co-Simulation instance with the default parameters, or null (logged)
/// for Model Exchange or a GUID of another build.
///
/// # Safety
/// The strings must be null or NUL-terminated; `functions` null or a valid callback struct.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2Instantiate(
    instance_name: *const c_char,
    fmu_type: c_int,
    fmu_guid: *const c_char,
    _fmu_resource_location: *const c_char,
    functions: *const CallbackFunctions,
    _visible: c_int,
    logging_on: c_int,
) -> Component {
    guard(
        || {
            // SAFETY: the importer passes a valid struct or null.
            let callbacks = unsafe { functions.as_ref() };
            let name = unsafe { text(instance_name) }
                .unwrap_or_default()
                .to_string();
            let mut log = Logger::new(&name, logging_on == FMI2_TRUE);
            log.fmi2 = callbacks.and_then(|f| f.logger.map(|l| (l, f.component_environment)));
            if fmu_type != FMI2_CO_SIMULATION {
                log.error("fmi2Instantiate: this FMU supports Co-Simulation only");
                return std::ptr::null_mut();
            }
            let guid = unsafe { text(fmu_guid) }.unwrap_or_default();
            match crate::spec::packaged_model(&guid) {
                Ok(model) => Instance::new(model, log, Version::Fmi2).register(),
                Err(e) => {
                    log.error(&format!("fmi2Instantiate: {e}"));
                    std::ptr::null_mut()
                }
            }
        },
        |_| std::ptr::null_mut(),
    )
}

/// `fmi2SetupExperiment`: start and optional stop time (the tolerance is not used). A
/// `fmi2DoStep` past the stop time is refused.
#[unsafe(no_mangle)]
pub extern "C" fn fmi2SetupExperiment(
    c: Component,
    _tolerance_defined: c_int,
    _tolerance: f64,
    start_time: f64,
    stop_time_defined: c_int,
    stop_time: f64,
) -> c_int {
    with_instance(c, "fmi2SetupExperiment", |i| {
        let stop = (stop_time_defined == FMI2_TRUE).then_some(stop_time);
        i.model.setup_experiment(start_time, stop)?;
        Ok(Status::Ok)
    })
}

/// `fmi2EnterInitializationMode`.
#[unsafe(no_mangle)]
pub extern "C" fn fmi2EnterInitializationMode(c: Component) -> c_int {
    with_instance(c, "fmi2EnterInitializationMode", |i| {
        i.model.enter_initialization();
        Ok(Status::Ok)
    })
}

shim::life_cycle!(Component; free: fmi2FreeInstance, exit: fmi2ExitInitializationMode,
    terminate: fmi2Terminate, reset: fmi2Reset);

/// `fmi2GetReal`.
///
/// # Safety
/// `vr` and `value` arrays of `nvr` elements.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2GetReal(
    c: Component,
    vr: *const u32,
    nvr: usize,
    value: *mut f64,
) -> c_int {
    with_instance(c, "fmi2GetReal", |i| {
        let (vr, out) = unsafe { (slice(vr, nvr)?, slice_mut(value, nvr)?) };
        shim::get_reals(i, vr, out)
    })
}

/// `fmi2GetInteger` (`steps` saturates at the 32-bit maximum).
///
/// # Safety
/// `vr` and `value` arrays of `nvr` elements.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2GetInteger(
    c: Component,
    vr: *const u32,
    nvr: usize,
    value: *mut c_int,
) -> c_int {
    with_instance(c, "fmi2GetInteger", |i| {
        let (vr, out) = unsafe { (slice(vr, nvr)?, slice_mut(value, nvr)?) };
        for (r, o) in vr.iter().zip(out) {
            *o = i
                .model
                .get_integer(*r)?
                .clamp(c_int::MIN as i64, c_int::MAX as i64) as c_int;
        }
        Ok(Status::Ok)
    })
}

shim::no_variables! { Component;
    "Boolean": fmi2GetBoolean(value: *mut c_int), fmi2SetBoolean(value: *const c_int);
}

/// `fmi2GetString`: the pointers stay valid until the next call on this instance.
///
/// # Safety
/// `vr` and `value` arrays of `nvr` elements.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2GetString(
    c: Component,
    vr: *const u32,
    nvr: usize,
    value: *mut *const c_char,
) -> c_int {
    with_instance(c, "fmi2GetString", |i| {
        let (vr, out) = unsafe { (slice(vr, nvr)?, slice_mut(value, nvr)?) };
        shim::get_strings(i, vr, out)
    })
}

/// `fmi2SetReal`: parameters before initialisation ends, the input at any time; a value
/// outside the variable's range is refused.
///
/// # Safety
/// `vr` and `value` arrays of `nvr` elements.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2SetReal(
    c: Component,
    vr: *const u32,
    nvr: usize,
    value: *const f64,
) -> c_int {
    with_instance(c, "fmi2SetReal", |i| {
        let (vr, value) = unsafe { (slice(vr, nvr)?, slice(value, nvr)?) };
        shim::set_reals(i, vr, value, as_error)
    })
}

/// `fmi2SetInteger`.
///
/// # Safety
/// `vr` and `value` arrays of `nvr` elements.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2SetInteger(
    c: Component,
    vr: *const u32,
    nvr: usize,
    value: *const c_int,
) -> c_int {
    with_instance(c, "fmi2SetInteger", |i| {
        let (vr, value) = unsafe { (slice(vr, nvr)?, slice(value, nvr)?) };
        for (r, v) in vr.iter().zip(value) {
            i.model.set_integer(*r, *v as i64).map_err(as_error)?;
        }
        Ok(Status::Ok)
    })
}

/// `fmi2SetString`.
///
/// # Safety
/// `vr` and `value` arrays of `nvr` elements, the strings NUL-terminated.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2SetString(
    c: Component,
    vr: *const u32,
    nvr: usize,
    value: *const *const c_char,
) -> c_int {
    with_instance(c, "fmi2SetString", |i| unsafe {
        let (vr, value) = (slice(vr, nvr)?, slice(value, nvr)?);
        shim::set_strings(i, vr, value, as_error)
    })
}

shim::fmu_states!(Component, FmuStatePtr, c_char; get: fmi2GetFMUstate,
    set: fmi2SetFMUstate, free: fmi2FreeFMUstate, size: fmi2SerializedFMUstateSize,
    serialize: fmi2SerializeFMUstate, deserialize: fmi2DeSerializeFMUstate);

shim::unsupported! { Component, "fmi2Error";
    fmi2GetDirectionalDerivative, "providesDirectionalDerivative is false",
        (v_unknown: *const u32, n_unknown: usize, v_known: *const u32, n_known: usize,
         dv_known: *const f64, dv_unknown: *mut f64);
    fmi2SetRealInputDerivatives, "canInterpolateInputs is false",
        (vr: *const u32, nvr: usize, order: *const c_int, value: *const f64);
    fmi2GetRealOutputDerivatives, "maxOutputDerivativeOrder is 0",
        (vr: *const u32, nvr: usize, order: *const c_int, value: *mut f64);
    fmi2CancelStep, "canRunAsynchronuously is false", ();
    fmi2GetStatus, "steps are synchronous: no pending status", (kind: c_int, value: *mut c_int);
    fmi2GetIntegerStatus, "no integer status is defined", (kind: c_int, value: *mut c_int);
    fmi2GetStringStatus, "steps are synchronous: no pending status",
        (kind: c_int, value: *mut *const c_char);
}

/// `fmi2DoStep`: advance by `h` with as many solver steps as needed (at most
/// `max_solver_steps_per_step`), landing on `t + h`. A step refused or failed with the
/// instance put back at `t` returns `fmi2Discard` (the instance is then in *stepFailed*:
/// `fmi2GetRealStatus(fmi2LastSuccessfulTime)` says `t`; set an FMU state to go on, or
/// terminate).
#[unsafe(no_mangle)]
pub extern "C" fn fmi2DoStep(
    c: Component,
    current_communication_point: f64,
    communication_step_size: f64,
    _no_set_fmu_state_prior_to_current_point: c_int,
) -> c_int {
    with_instance(c, "fmi2DoStep", |i| {
        let r = i
            .model
            .do_step(current_communication_point, communication_step_size);
        if matches!(&r, Err(f) if f.status == Status::Discard) {
            i.model.enter_step_discarded();
        }
        r.map(|_| Status::Ok)
    })
}

/// `fmi2GetRealStatus`: `fmi2LastSuccessfulTime` is the model's time.
///
/// # Safety
/// `value` writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2GetRealStatus(c: Component, kind: c_int, value: *mut f64) -> c_int {
    with_instance(c, "fmi2GetRealStatus", |i| {
        if kind != FMI2_LAST_SUCCESSFUL_TIME {
            return Err(Fault::error(format!(
                "status kind {kind}: only fmi2LastSuccessfulTime is defined"
            )));
        }
        *unsafe { value.as_mut() }.ok_or("a null value pointer")? = i.model.time();
        Ok(Status::Ok)
    })
}

/// `fmi2GetBooleanStatus`: `fmi2Terminated` is always false (the model never ends a run).
///
/// # Safety
/// `value` writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2GetBooleanStatus(
    c: Component,
    kind: c_int,
    value: *mut c_int,
) -> c_int {
    with_instance(c, "fmi2GetBooleanStatus", |_| {
        if kind != FMI2_TERMINATED {
            return Err(Fault::error(format!(
                "status kind {kind}: only fmi2Terminated is defined"
            )));
        }
        *unsafe { value.as_mut() }.ok_or("a null value pointer")? = 0;
        Ok(Status::Ok)
    })
}
