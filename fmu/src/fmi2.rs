//! The FMI 2.0 Co-Simulation C API (all 34 functions an importer such as fmpy binds; those
//! this model does not support log why and return `fmi2Error`).
//!
//! Supported: instantiation (Co-Simulation only), parameters and the input before and during
//! initialisation, the input between steps, outputs at any time, `fmi2DoStep` with any
//! communication step, `fmi2GetRealStatus(fmi2LastSuccessfulTime)`, reset, and FMU states:
//! get, set, free, serialise and deserialise. Not supported: input or output derivatives,
//! directional derivatives, asynchronous steps (`fmi2CancelStep`, the other status queries).

use crate::description::token;
use crate::instance::{Instance, slice, slice_mut, text, with_instance};
use crate::log::{Fmi2Logger, Logger, Status, c_string, guard};
use crate::model::{FmuState, Model};
use std::ffi::{c_char, c_int, c_void};

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

/// `fmi2SetDebugLogging`: informational messages on or off (categories are not filtered).
///
/// # Safety
/// `c` must be an instance of this library.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2SetDebugLogging(
    c: Component,
    logging_on: c_int,
    _n_categories: usize,
    _categories: *const *const c_char,
) -> c_int {
    unsafe {
        with_instance(c, "fmi2SetDebugLogging", |i| {
            i.log.debug = logging_on == FMI2_TRUE;
            Ok(Status::Ok)
        })
    }
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
            let log = Logger {
                instance_name: c_string(&name),
                fmi2: callbacks.and_then(|f| f.logger.map(|l| (l, f.component_environment))),
                fmi3: None,
                debug: logging_on == FMI2_TRUE,
            };
            if fmu_type != FMI2_CO_SIMULATION {
                log.error("fmi2Instantiate: this FMU supports Co-Simulation only");
                return std::ptr::null_mut();
            }
            let guid = unsafe { text(fmu_guid) }.unwrap_or_default();
            if guid != token() {
                log.error(&format!(
                    "fmi2Instantiate: the GUID {guid} is not this library's {} (a modelDescription.xml of another build?)",
                    token()
                ));
                return std::ptr::null_mut();
            }
            Instance {
                model: Model::new(),
                log,
                strings: Vec::new(),
            }
            .into_raw()
        },
        |_| std::ptr::null_mut(),
    )
}

/// `fmi2FreeInstance`.
///
/// # Safety
/// `c` must be null or an instance of this library, not used afterwards.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2FreeInstance(c: Component) {
    if c.is_null() {
        return;
    }
    // SAFETY: the instance was made by Box::into_raw in fmi2Instantiate.
    guard(
        || drop(unsafe { Box::from_raw(c as *mut Instance) }),
        |_| (),
    );
}

/// `fmi2SetupExperiment`: start and optional stop time (the tolerance is not used).
///
/// # Safety
/// `c` must be an instance of this library.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2SetupExperiment(
    c: Component,
    _tolerance_defined: c_int,
    _tolerance: f64,
    start_time: f64,
    stop_time_defined: c_int,
    stop_time: f64,
) -> c_int {
    unsafe {
        with_instance(c, "fmi2SetupExperiment", |i| {
            let stop = (stop_time_defined == FMI2_TRUE).then_some(stop_time);
            i.model
                .setup_experiment(start_time, stop)
                .map(|_| Status::Ok)
        })
    }
}

/// `fmi2EnterInitializationMode`.
///
/// # Safety
/// `c` must be an instance of this library.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2EnterInitializationMode(c: Component) -> c_int {
    unsafe {
        with_instance(c, "fmi2EnterInitializationMode", |i| {
            i.model.enter_initialization().map(|_| Status::Ok)
        })
    }
}

/// `fmi2ExitInitializationMode`: checks the parameters (a bad one is named in the log) and
/// builds the simulation.
///
/// # Safety
/// `c` must be an instance of this library.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2ExitInitializationMode(c: Component) -> c_int {
    unsafe {
        with_instance(c, "fmi2ExitInitializationMode", |i| {
            i.model.exit_initialization().map(|_| Status::Ok)
        })
    }
}

/// `fmi2Terminate`.
///
/// # Safety
/// `c` must be an instance of this library.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2Terminate(c: Component) -> c_int {
    unsafe {
        with_instance(c, "fmi2Terminate", |i| {
            i.model.terminate().map(|_| Status::Ok)
        })
    }
}

/// `fmi2Reset`: back to the instantiated state with the default parameters.
///
/// # Safety
/// `c` must be an instance of this library.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2Reset(c: Component) -> c_int {
    unsafe {
        with_instance(c, "fmi2Reset", |i| {
            i.model.reset();
            Ok(Status::Ok)
        })
    }
}

/// `fmi2GetReal`.
///
/// # Safety
/// `c` an instance; `vr` and `value` arrays of `nvr` elements.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2GetReal(
    c: Component,
    vr: *const u32,
    nvr: usize,
    value: *mut f64,
) -> c_int {
    unsafe {
        with_instance(c, "fmi2GetReal", |i| {
            let (vr, out) = (slice(vr, nvr)?, slice_mut(value, nvr)?);
            for (r, o) in vr.iter().zip(out) {
                *o = i.model.get_real(*r)?;
            }
            Ok(Status::Ok)
        })
    }
}

/// `fmi2GetInteger` (`steps` saturates at the 32-bit maximum).
///
/// # Safety
/// `c` an instance; `vr` and `value` arrays of `nvr` elements.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2GetInteger(
    c: Component,
    vr: *const u32,
    nvr: usize,
    value: *mut c_int,
) -> c_int {
    unsafe {
        with_instance(c, "fmi2GetInteger", |i| {
            let (vr, out) = (slice(vr, nvr)?, slice_mut(value, nvr)?);
            for (r, o) in vr.iter().zip(out) {
                *o = i
                    .model
                    .get_integer(*r)?
                    .clamp(c_int::MIN as i64, c_int::MAX as i64) as c_int;
            }
            Ok(Status::Ok)
        })
    }
}

/// `fmi2GetBoolean`: the model has no Boolean variables.
///
/// # Safety
/// `c` an instance; `vr` an array of `nvr` elements.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2GetBoolean(
    c: Component,
    vr: *const u32,
    nvr: usize,
    _value: *mut c_int,
) -> c_int {
    unsafe { with_instance(c, "fmi2GetBoolean", |_| no_booleans(slice(vr, nvr)?)) }
}

fn no_booleans(vr: &[u32]) -> Result<Status, String> {
    match vr.first() {
        None => Ok(Status::Ok),
        Some(r) => Err(format!("no Boolean variable has the value reference {r}")),
    }
}

/// `fmi2GetString`: the pointers stay valid until the next call on this instance.
///
/// # Safety
/// `c` an instance; `vr` and `value` arrays of `nvr` elements.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2GetString(
    c: Component,
    vr: *const u32,
    nvr: usize,
    value: *mut *const c_char,
) -> c_int {
    unsafe {
        with_instance(c, "fmi2GetString", |i| {
            let (vr, out) = (slice(vr, nvr)?, slice_mut(value, nvr)?);
            i.strings = vr
                .iter()
                .map(|r| i.model.get_string(*r).map(c_string))
                .collect::<Result<_, _>>()?;
            for (s, o) in i.strings.iter().zip(out) {
                *o = s.as_ptr();
            }
            Ok(Status::Ok)
        })
    }
}

/// `fmi2SetReal`: parameters before initialisation ends, the input at any time.
///
/// # Safety
/// `c` an instance; `vr` and `value` arrays of `nvr` elements.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2SetReal(
    c: Component,
    vr: *const u32,
    nvr: usize,
    value: *const f64,
) -> c_int {
    unsafe {
        with_instance(c, "fmi2SetReal", |i| {
            for (r, v) in slice(vr, nvr)?.iter().zip(slice(value, nvr)?) {
                i.model.set_real(*r, *v)?;
            }
            Ok(Status::Ok)
        })
    }
}

/// `fmi2SetInteger`.
///
/// # Safety
/// `c` an instance; `vr` and `value` arrays of `nvr` elements.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2SetInteger(
    c: Component,
    vr: *const u32,
    nvr: usize,
    value: *const c_int,
) -> c_int {
    unsafe {
        with_instance(c, "fmi2SetInteger", |i| {
            for (r, v) in slice(vr, nvr)?.iter().zip(slice(value, nvr)?) {
                i.model.set_integer(*r, *v as i64)?;
            }
            Ok(Status::Ok)
        })
    }
}

/// `fmi2SetBoolean`: the model has no Boolean variables.
///
/// # Safety
/// `c` an instance; `vr` an array of `nvr` elements.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2SetBoolean(
    c: Component,
    vr: *const u32,
    nvr: usize,
    _value: *const c_int,
) -> c_int {
    unsafe { with_instance(c, "fmi2SetBoolean", |_| no_booleans(slice(vr, nvr)?)) }
}

/// `fmi2SetString`.
///
/// # Safety
/// `c` an instance; `vr` and `value` arrays of `nvr` elements, the strings NUL-terminated.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2SetString(
    c: Component,
    vr: *const u32,
    nvr: usize,
    value: *const *const c_char,
) -> c_int {
    unsafe {
        with_instance(c, "fmi2SetString", |i| {
            for (r, v) in slice(vr, nvr)?.iter().zip(slice(value, nvr)?) {
                let s = text(*v).ok_or("a null string")?;
                i.model.set_string(*r, &s)?;
            }
            Ok(Status::Ok)
        })
    }
}

/// `fmi2GetFMUstate`: a new state, or `*state` overwritten when it is one already.
///
/// # Safety
/// `c` an instance; `state` points to null or to a state of this library.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2GetFMUstate(c: Component, state: *mut FmuStatePtr) -> c_int {
    unsafe {
        with_instance(c, "fmi2GetFMUstate", |i| {
            let slot = state.as_mut().ok_or("a null FMU state pointer")?;
            match (*slot as *mut FmuState).as_mut() {
                Some(s) => i.model.get_state_into(s)?,
                None => *slot = Box::into_raw(Box::new(i.model.get_state()?)) as FmuStatePtr,
            }
            Ok(Status::Ok)
        })
    }
}

/// `fmi2SetFMUstate`.
///
/// # Safety
/// `c` an instance; `state` a state of this library.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2SetFMUstate(c: Component, state: FmuStatePtr) -> c_int {
    unsafe {
        with_instance(c, "fmi2SetFMUstate", |i| {
            let s = (state as *const FmuState)
                .as_ref()
                .ok_or("a null FMU state")?;
            i.model.set_state(s).map(|_| Status::Ok)
        })
    }
}

/// `fmi2FreeFMUstate`: frees `*state` and sets it to null.
///
/// # Safety
/// `c` an instance; `state` points to null or to a state of this library.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2FreeFMUstate(c: Component, state: *mut FmuStatePtr) -> c_int {
    unsafe {
        with_instance(c, "fmi2FreeFMUstate", |_| {
            if let Some(slot) = state.as_mut()
                && !slot.is_null()
            {
                drop(Box::from_raw(*slot as *mut FmuState));
                *slot = std::ptr::null_mut();
            }
            Ok(Status::Ok)
        })
    }
}

/// `fmi2SerializedFMUstateSize`.
///
/// # Safety
/// `c` an instance; `state` a state of this library; `size` writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2SerializedFMUstateSize(
    c: Component,
    state: FmuStatePtr,
    size: *mut usize,
) -> c_int {
    unsafe {
        with_instance(c, "fmi2SerializedFMUstateSize", |i| {
            let s = (state as *mut FmuState)
                .as_mut()
                .ok_or("a null FMU state")?;
            *size.as_mut().ok_or("a null size pointer")? = i.model.serialize(s)?.len();
            Ok(Status::Ok)
        })
    }
}

/// `fmi2SerializeFMUstate`: `size` must be what `fmi2SerializedFMUstateSize` said.
///
/// # Safety
/// `c` an instance; `state` a state of this library; `bytes` `size` writable bytes.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2SerializeFMUstate(
    c: Component,
    state: FmuStatePtr,
    bytes: *mut c_char,
    size: usize,
) -> c_int {
    unsafe {
        with_instance(c, "fmi2SerializeFMUstate", |i| {
            let s = (state as *mut FmuState)
                .as_mut()
                .ok_or("a null FMU state")?;
            let data = i.model.serialize(s)?;
            if data.len() != size {
                return Err(format!(
                    "the buffer has {size} bytes, the state {} (ask fmi2SerializedFMUstateSize)",
                    data.len()
                ));
            }
            slice_mut(bytes as *mut u8, size)?.copy_from_slice(data);
            Ok(Status::Ok)
        })
    }
}

/// `fmi2DeSerializeFMUstate`: refuses a state of an instance with other parameters.
///
/// # Safety
/// `c` an instance; `bytes` `size` readable bytes; `state` writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2DeSerializeFMUstate(
    c: Component,
    bytes: *const c_char,
    size: usize,
    state: *mut FmuStatePtr,
) -> c_int {
    unsafe {
        with_instance(c, "fmi2DeSerializeFMUstate", |i| {
            let s = i.model.deserialize(slice(bytes as *const u8, size)?)?;
            let slot = state.as_mut().ok_or("a null FMU state pointer")?;
            if !slot.is_null() {
                drop(Box::from_raw(*slot as *mut FmuState));
            }
            *slot = Box::into_raw(Box::new(s)) as FmuStatePtr;
            Ok(Status::Ok)
        })
    }
}

macro_rules! unsupported {
    ($name:ident, $why:literal, ($($arg:ident : $ty:ty),*)) => {
        #[doc = concat!("`", stringify!($name), "`: not supported (", $why, "); returns `fmi2Error`.")]
        ///
        /// # Safety
        /// `c` must be an instance of this library.
        #[unsafe(no_mangle)]
        pub unsafe extern "C" fn $name(c: Component, $($arg: $ty),*) -> c_int {
            $(let _ = $arg;)*
            unsafe {
                with_instance(c, stringify!($name), |_| Err(concat!("not supported: ", $why).into()))
            }
        }
    };
}

unsupported!(fmi2GetDirectionalDerivative, "providesDirectionalDerivative is false",
    (v_unknown: *const u32, n_unknown: usize, v_known: *const u32, n_known: usize,
     dv_known: *const f64, dv_unknown: *mut f64));
unsupported!(fmi2SetRealInputDerivatives, "canInterpolateInputs is false",
    (vr: *const u32, nvr: usize, order: *const c_int, value: *const f64));
unsupported!(fmi2GetRealOutputDerivatives, "maxOutputDerivativeOrder is 0",
    (vr: *const u32, nvr: usize, order: *const c_int, value: *mut f64));
unsupported!(fmi2CancelStep, "canRunAsynchronuously is false", ());
unsupported!(fmi2GetStatus, "steps are synchronous: no pending status",
    (kind: c_int, value: *mut c_int));
unsupported!(fmi2GetIntegerStatus, "no integer status is defined",
    (kind: c_int, value: *mut c_int));
unsupported!(fmi2GetStringStatus, "steps are synchronous: no pending status",
    (kind: c_int, value: *mut *const c_char));

/// `fmi2DoStep`: advance by `h` with as many solver steps as needed, landing on `t + h`.
///
/// # Safety
/// `c` must be an instance of this library.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2DoStep(
    c: Component,
    current_communication_point: f64,
    communication_step_size: f64,
    _no_set_fmu_state_prior_to_current_point: c_int,
) -> c_int {
    unsafe {
        with_instance(c, "fmi2DoStep", |i| {
            i.model
                .do_step(current_communication_point, communication_step_size)
                .map(|_| Status::Ok)
        })
    }
}

/// `fmi2GetRealStatus`: `fmi2LastSuccessfulTime` is the model's time.
///
/// # Safety
/// `c` an instance; `value` writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2GetRealStatus(c: Component, kind: c_int, value: *mut f64) -> c_int {
    unsafe {
        with_instance(c, "fmi2GetRealStatus", |i| {
            if kind != FMI2_LAST_SUCCESSFUL_TIME {
                return Err(format!(
                    "status kind {kind}: only fmi2LastSuccessfulTime is defined"
                ));
            }
            *value.as_mut().ok_or("a null value pointer")? = i.model.time();
            Ok(Status::Ok)
        })
    }
}

/// `fmi2GetBooleanStatus`: `fmi2Terminated` is always false (the model never ends a run).
///
/// # Safety
/// `c` an instance; `value` writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2GetBooleanStatus(
    c: Component,
    kind: c_int,
    value: *mut c_int,
) -> c_int {
    unsafe {
        with_instance(c, "fmi2GetBooleanStatus", |_| {
            if kind != FMI2_TERMINATED {
                return Err(format!(
                    "status kind {kind}: only fmi2Terminated is defined"
                ));
            }
            *value.as_mut().ok_or("a null value pointer")? = 0;
            Ok(Status::Ok)
        })
    }
}
