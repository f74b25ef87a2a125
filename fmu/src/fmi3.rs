//! The FMI 3.0 Co-Simulation C API, hand-written over the same [`Model`] as FMI 2.0 (every
//! function of the standard is exported, as importers such as fmpy bind them all; those this
//! model does not support log why and return `fmi3Error`).
//!
//! Supported: `fmi3InstantiateCoSimulation` (no event mode, no intermediate update), the
//! Float64 / Int32 / Int64 / String variables, `fmi3DoStep` with any communication step, reset,
//! and FMU states: get, set, free, serialise and deserialise. Model Exchange and Scheduled
//! Execution instances are refused; the other variable types hold no variables; clocks,
//! derivatives and configuration mode are not supported.

use crate::instance::{Instance, slice, slice_mut, state_slot, text, with_instance};
use crate::log::{Fmi3Logger, Logger, Status, c_string, guard};
use crate::machine::Version;
use crate::model::{Fault, Model};
use crate::spec::Kind;
use crate::state::FmuState;
use std::ffi::{c_char, c_int, c_void};

/// `fmi3Instance`.
pub type Fmi3Instance = *mut c_void;
/// `fmi3FMUState`.
pub type FmuStatePtr = *mut c_void;
type ValueReference = u32;

/// `fmi3GetVersion`: `"3.0"`.
#[unsafe(no_mangle)]
pub extern "C" fn fmi3GetVersion() -> *const c_char {
    c"3.0".as_ptr()
}

/// `fmi3SetDebugLogging`: the named log categories (all when none is named) on or off; an
/// unknown category is an error.
///
/// # Safety
/// `categories` `n_categories` C strings.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3SetDebugLogging(
    instance: Fmi3Instance,
    logging_on: bool,
    n_categories: usize,
    categories: *const *const c_char,
) -> c_int {
    with_instance(instance, "fmi3SetDebugLogging", |i| {
        let names = unsafe { slice(categories, n_categories) }?
            .iter()
            .map(|p| unsafe { text(*p) }.map(|t| t.into_owned()))
            .collect::<Option<Vec<_>>>()
            .ok_or("a null category name")?;
        i.log.set_categories(logging_on, &names)?;
        Ok(Status::Ok)
    })
}

/// `fmi3InstantiateCoSimulation`: an instance with the default parameters, or null (logged)
/// for another instantiation token or a request for event mode or intermediate updates.
///
/// # Safety
/// The strings must be null or NUL-terminated; `log_message` null or a valid callback.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3InstantiateCoSimulation(
    instance_name: *const c_char,
    instantiation_token: *const c_char,
    _resource_path: *const c_char,
    _visible: bool,
    logging_on: bool,
    event_mode_used: bool,
    _early_return_allowed: bool,
    _required_intermediate_variables: *const ValueReference,
    _n_required_intermediate_variables: usize,
    instance_environment: *mut c_void,
    log_message: Option<Fmi3Logger>,
    _intermediate_update: *mut c_void,
) -> Fmi3Instance {
    guard(
        || {
            let name = unsafe { text(instance_name) }
                .unwrap_or_default()
                .to_string();
            let mut log = Logger::new(&name, logging_on);
            log.fmi3 = log_message.map(|l| (l, instance_environment));
            let t = unsafe { text(instantiation_token) }.unwrap_or_default();
            if event_mode_used {
                log.error("fmi3InstantiateCoSimulation: this FMU has no event mode (hasEventMode is false)");
                return std::ptr::null_mut();
            }
            match crate::spec::packaged_model(&t) {
                Ok(model) => Instance::new(model, log, Version::Fmi3).register(),
                Err(e) => {
                    log.error(&format!("fmi3InstantiateCoSimulation: {e}"));
                    std::ptr::null_mut()
                }
            }
        },
        |_| std::ptr::null_mut(),
    )
}

fn refuse_instantiate(
    log_message: Option<Fmi3Logger>,
    env: *mut c_void,
    what: &str,
) -> Fmi3Instance {
    guard(
        || {
            if let Some(l) = log_message {
                let m = c_string(&format!("this FMU supports Co-Simulation only, not {what}"));
                // SAFETY: the importer's callback, with NUL-terminated strings.
                unsafe {
                    l(
                        env,
                        Status::Error as c_int,
                        c"logStatusError".as_ptr(),
                        m.as_ptr(),
                    )
                };
            }
            std::ptr::null_mut()
        },
        |_| std::ptr::null_mut(),
    )
}

/// `fmi3InstantiateModelExchange`: refused (null), the FMU is Co-Simulation only.
#[unsafe(no_mangle)]
pub extern "C" fn fmi3InstantiateModelExchange(
    _instance_name: *const c_char,
    _instantiation_token: *const c_char,
    _resource_path: *const c_char,
    _visible: bool,
    _logging_on: bool,
    instance_environment: *mut c_void,
    log_message: Option<Fmi3Logger>,
) -> Fmi3Instance {
    refuse_instantiate(log_message, instance_environment, "Model Exchange")
}

/// `fmi3InstantiateScheduledExecution`: refused (null), the FMU is Co-Simulation only.
#[unsafe(no_mangle)]
pub extern "C" fn fmi3InstantiateScheduledExecution(
    _instance_name: *const c_char,
    _instantiation_token: *const c_char,
    _resource_path: *const c_char,
    _visible: bool,
    _logging_on: bool,
    instance_environment: *mut c_void,
    log_message: Option<Fmi3Logger>,
    _clock_update: *mut c_void,
    _lock_preemption: *mut c_void,
    _unlock_preemption: *mut c_void,
) -> Fmi3Instance {
    refuse_instantiate(log_message, instance_environment, "Scheduled Execution")
}

/// `fmi3FreeInstance`: frees the instance and its FMU states; an unknown or already freed
/// handle is ignored.
#[unsafe(no_mangle)]
pub extern "C" fn fmi3FreeInstance(instance: Fmi3Instance) {
    guard(|| crate::instance::free(instance), |_| ());
}

/// `fmi3EnterInitializationMode`: start and optional stop time (the tolerance is not used). A
/// `fmi3DoStep` past the stop time is refused.
#[unsafe(no_mangle)]
pub extern "C" fn fmi3EnterInitializationMode(
    instance: Fmi3Instance,
    _tolerance_defined: bool,
    _tolerance: f64,
    start_time: f64,
    stop_time_defined: bool,
    stop_time: f64,
) -> c_int {
    with_instance(instance, "fmi3EnterInitializationMode", |i| {
        i.model
            .setup_experiment(start_time, stop_time_defined.then_some(stop_time))?;
        i.model.enter_initialization();
        Ok(Status::Ok)
    })
}

/// `fmi3ExitInitializationMode`: checks the parameters (a bad one is named in the log) and
/// builds the simulation; the instance is then in step mode.
#[unsafe(no_mangle)]
pub extern "C" fn fmi3ExitInitializationMode(instance: Fmi3Instance) -> c_int {
    with_instance(instance, "fmi3ExitInitializationMode", |i| {
        i.model.exit_initialization()?;
        Ok(Status::Ok)
    })
}

/// `fmi3Terminate`: after initialisation, once.
#[unsafe(no_mangle)]
pub extern "C" fn fmi3Terminate(instance: Fmi3Instance) -> c_int {
    with_instance(instance, "fmi3Terminate", |i| {
        i.model.terminate();
        Ok(Status::Ok)
    })
}

/// `fmi3Reset`: back to the instantiated state with the default parameters (the instance's
/// FMU states stay valid).
#[unsafe(no_mangle)]
pub extern "C" fn fmi3Reset(instance: Fmi3Instance) -> c_int {
    with_instance(instance, "fmi3Reset", |i| {
        i.model.reset();
        Ok(Status::Ok)
    })
}

/// `fmi3DoStep`: advance by `h` with as many solver steps as needed (at most
/// `max_solver_steps_per_step`), landing on `t + h`; never returns early, never asks for event
/// handling or termination. A step refused or failed with the instance put back at `t` returns
/// `fmi3Discard` with `lastSuccessfulTime = t`: the instance stays in step mode and may step
/// again (with a shorter step or other inputs) or set an FMU state.
///
/// # Safety
/// The four out-pointers writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3DoStep(
    instance: Fmi3Instance,
    current_communication_point: f64,
    communication_step_size: f64,
    _no_set_fmu_state_prior_to_current_point: bool,
    event_handling_needed: *mut bool,
    terminate_simulation: *mut bool,
    early_return: *mut bool,
    last_successful_time: *mut f64,
) -> c_int {
    with_instance(instance, "fmi3DoStep", |i| {
        let (Some(e), Some(t), Some(r), Some(last)) = (unsafe {
            (
                event_handling_needed.as_mut(),
                terminate_simulation.as_mut(),
                early_return.as_mut(),
                last_successful_time.as_mut(),
            )
        }) else {
            return Err(Fault::error(
                "a null pointer among eventHandlingNeeded, terminateSimulation, earlyReturn, lastSuccessfulTime",
            ));
        };
        let result = i
            .model
            .do_step(current_communication_point, communication_step_size);
        (*e, *t, *r) = (false, false, false);
        *last = i.model.time();
        result.map(|_| Status::Ok)
    })
}

/// `fmi3GetFloat64`.
///
/// # Safety
/// `vr` `nvr` values, `values` `n_values` writable values.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3GetFloat64(
    instance: Fmi3Instance,
    vr: *const ValueReference,
    nvr: usize,
    values: *mut f64,
    n_values: usize,
) -> c_int {
    with_instance(instance, "fmi3GetFloat64", |i| {
        check_counts(nvr, n_values)?;
        let (vr, out) = unsafe { (slice(vr, nvr)?, slice_mut(values, n_values)?) };
        for (r, o) in vr.iter().zip(out) {
            *o = i.model.get_real(*r)?;
        }
        Ok(Status::Ok)
    })
}

/// `fmi3SetFloat64`: parameters before initialisation ends, the input at any time; a value
/// outside the variable's range is refused with `fmi3Discard` (nothing changes).
///
/// # Safety
/// `vr` `nvr` values, `values` `n_values` values.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3SetFloat64(
    instance: Fmi3Instance,
    vr: *const ValueReference,
    nvr: usize,
    values: *const f64,
    n_values: usize,
) -> c_int {
    with_instance(instance, "fmi3SetFloat64", |i| {
        check_counts(nvr, n_values)?;
        let (vr, values) = unsafe { (slice(vr, nvr)?, slice(values, n_values)?) };
        for (r, v) in vr.iter().zip(values) {
            i.model.set_real(*r, *v)?;
        }
        Ok(Status::Ok)
    })
}

fn check_counts(nvr: usize, n_values: usize) -> Result<(), Fault> {
    if nvr == n_values {
        Ok(())
    } else {
        Err(Fault::error(format!(
            "{nvr} value references but {n_values} values (the model has scalar variables only)"
        )))
    }
}

macro_rules! integers {
    ($get:ident, $set:ident, $ty:ty, $kind:expr) => {
        #[doc = concat!("`", stringify!($get), "`.")]
        ///
        /// # Safety
        /// `vr` `nvr` values, `values` `n_values` writable values.
        #[unsafe(no_mangle)]
        pub unsafe extern "C" fn $get(
            instance: Fmi3Instance,
            vr: *const ValueReference,
            nvr: usize,
            values: *mut $ty,
            n_values: usize,
        ) -> c_int {
            with_instance(instance, stringify!($get), |i| {
                check_counts(nvr, n_values)?;
                let (vr, out) = unsafe { (slice(vr, nvr)?, slice_mut(values, n_values)?) };
                for (r, o) in vr.iter().zip(out) {
                    check_kind(&i.model, *r, $kind)?;
                    let v = i.model.get_integer(*r)?;
                    *o = <$ty>::try_from(v).map_err(|_| format!("{v} does not fit"))?;
                }
                Ok(Status::Ok)
            })
        }

        #[doc = concat!("`", stringify!($set), "`: out of the variable's range: `fmi3Discard`.")]
        ///
        /// # Safety
        /// `vr` `nvr` values, `values` `n_values` values.
        #[unsafe(no_mangle)]
        pub unsafe extern "C" fn $set(
            instance: Fmi3Instance,
            vr: *const ValueReference,
            nvr: usize,
            values: *const $ty,
            n_values: usize,
        ) -> c_int {
            with_instance(instance, stringify!($set), |i| {
                check_counts(nvr, n_values)?;
                let (vr, values) = unsafe { (slice(vr, nvr)?, slice(values, n_values)?) };
                for (r, v) in vr.iter().zip(values) {
                    check_kind(&i.model, *r, $kind)?;
                    i.model.set_integer(*r, *v as i64)?;
                }
                Ok(Status::Ok)
            })
        }
    };
}

fn check_kind(model: &Model, vr: ValueReference, kind: Kind) -> Result<(), Fault> {
    match model.variable(vr) {
        Some(v) if v.kind == kind => Ok(()),
        Some(v) => Err(Fault::error(format!(
            "`{}` (value reference {vr}) is a {:?} variable, not {kind:?}",
            v.name, v.kind
        ))),
        None => Err(Fault::error(format!(
            "no {kind:?} variable has the value reference {vr}"
        ))),
    }
}

integers!(fmi3GetInt32, fmi3SetInt32, i32, Kind::Int32);
integers!(fmi3GetInt64, fmi3SetInt64, i64, Kind::Int64);

macro_rules! no_variables {
    ($get:ident, $set:ident, $ty:ty, $what:literal) => {
        #[doc = concat!("`", stringify!($get), "`: the model has no ", $what, " variables.")]
        ///
        /// # Safety
        /// `vr` `nvr` values.
        #[unsafe(no_mangle)]
        pub unsafe extern "C" fn $get(
            instance: Fmi3Instance,
            vr: *const ValueReference,
            nvr: usize,
            _values: *mut $ty,
            _n_values: usize,
        ) -> c_int {
            with_instance(instance, stringify!($get), |_| {
                none_of(unsafe { slice(vr, nvr) }?, $what)
            })
        }

        #[doc = concat!("`", stringify!($set), "`: the model has no ", $what, " variables.")]
        ///
        /// # Safety
        /// `vr` `nvr` values.
        #[unsafe(no_mangle)]
        pub unsafe extern "C" fn $set(
            instance: Fmi3Instance,
            vr: *const ValueReference,
            nvr: usize,
            _values: *const $ty,
            _n_values: usize,
        ) -> c_int {
            with_instance(instance, stringify!($set), |_| {
                none_of(unsafe { slice(vr, nvr) }?, $what)
            })
        }
    };
}

fn none_of(vr: &[ValueReference], what: &str) -> Result<Status, Fault> {
    match vr.first() {
        None => Ok(Status::Ok),
        Some(r) => Err(Fault::error(format!(
            "no {what} variable has the value reference {r}"
        ))),
    }
}

no_variables!(fmi3GetFloat32, fmi3SetFloat32, f32, "Float32");
no_variables!(fmi3GetInt8, fmi3SetInt8, i8, "Int8");
no_variables!(fmi3GetUInt8, fmi3SetUInt8, u8, "UInt8");
no_variables!(fmi3GetInt16, fmi3SetInt16, i16, "Int16");
no_variables!(fmi3GetUInt16, fmi3SetUInt16, u16, "UInt16");
no_variables!(fmi3GetUInt32, fmi3SetUInt32, u32, "UInt32");
no_variables!(fmi3GetUInt64, fmi3SetUInt64, u64, "UInt64");
no_variables!(fmi3GetBoolean, fmi3SetBoolean, bool, "Boolean");

/// `fmi3GetString`: the pointers stay valid until the next call on this instance.
///
/// # Safety
/// `vr` `nvr` values, `values` `n_values` writable pointers.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3GetString(
    instance: Fmi3Instance,
    vr: *const ValueReference,
    nvr: usize,
    values: *mut *const c_char,
    n_values: usize,
) -> c_int {
    with_instance(instance, "fmi3GetString", |i| {
        check_counts(nvr, n_values)?;
        let (vr, out) = unsafe { (slice(vr, nvr)?, slice_mut(values, n_values)?) };
        i.strings = vr
            .iter()
            .map(|r| i.model.get_string(*r).map(|s| c_string(&s)))
            .collect::<Result<_, _>>()?;
        for (s, o) in i.strings.iter().zip(out) {
            *o = s.as_ptr();
        }
        Ok(Status::Ok)
    })
}

/// `fmi3SetString`.
///
/// # Safety
/// `vr` `nvr` values, `values` `n_values` NUL-terminated strings.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3SetString(
    instance: Fmi3Instance,
    vr: *const ValueReference,
    nvr: usize,
    values: *const *const c_char,
    n_values: usize,
) -> c_int {
    with_instance(instance, "fmi3SetString", |i| {
        check_counts(nvr, n_values)?;
        let (vr, values) = unsafe { (slice(vr, nvr)?, slice(values, n_values)?) };
        for (r, v) in vr.iter().zip(values) {
            let s = unsafe { text(*v) }.ok_or("a null string")?;
            i.model.set_string(*r, &s)?;
        }
        Ok(Status::Ok)
    })
}

/// `fmi3GetBinary`: the model has no Binary variables.
///
/// # Safety
/// `vr` `nvr` values.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3GetBinary(
    instance: Fmi3Instance,
    vr: *const ValueReference,
    nvr: usize,
    _value_sizes: *mut usize,
    _values: *mut *const u8,
    _n_values: usize,
) -> c_int {
    with_instance(instance, "fmi3GetBinary", |_| {
        none_of(unsafe { slice(vr, nvr) }?, "Binary")
    })
}

/// `fmi3SetBinary`: the model has no Binary variables.
///
/// # Safety
/// `vr` `nvr` values.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3SetBinary(
    instance: Fmi3Instance,
    vr: *const ValueReference,
    nvr: usize,
    _value_sizes: *const usize,
    _values: *const *const u8,
    _n_values: usize,
) -> c_int {
    with_instance(instance, "fmi3SetBinary", |_| {
        none_of(unsafe { slice(vr, nvr) }?, "Binary")
    })
}

/// `fmi3GetClock`: the model has no clocks.
///
/// # Safety
/// `vr` `nvr` values.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3GetClock(
    instance: Fmi3Instance,
    vr: *const ValueReference,
    nvr: usize,
    _values: *mut bool,
) -> c_int {
    with_instance(instance, "fmi3GetClock", |_| {
        none_of(unsafe { slice(vr, nvr) }?, "Clock")
    })
}

/// `fmi3SetClock`: the model has no clocks.
///
/// # Safety
/// `vr` `nvr` values.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3SetClock(
    instance: Fmi3Instance,
    vr: *const ValueReference,
    nvr: usize,
    _values: *const bool,
) -> c_int {
    with_instance(instance, "fmi3SetClock", |_| {
        none_of(unsafe { slice(vr, nvr) }?, "Clock")
    })
}

/// `fmi3GetFMUState`: a new state when `*state` is null, else `*state` (one of this
/// instance's states) overwritten.
#[unsafe(no_mangle)]
pub extern "C" fn fmi3GetFMUState(instance: Fmi3Instance, state: *mut FmuStatePtr) -> c_int {
    with_instance(instance, "fmi3GetFMUState", |i| {
        let slot = state_slot(state)?;
        if slot.is_null() {
            let s = i.model.get_state()?;
            *slot = i.add_state(s) as FmuStatePtr;
        } else {
            i.refresh_state(*slot)?;
        }
        Ok(Status::Ok)
    })
}

/// `fmi3SetFMUState`: any state of this instance, in any mode (also before initialisation).
#[unsafe(no_mangle)]
pub extern "C" fn fmi3SetFMUState(instance: Fmi3Instance, state: FmuStatePtr) -> c_int {
    with_instance(instance, "fmi3SetFMUState", |i| {
        let s = i.state(state)?.clone();
        i.model.set_state(&s)?;
        Ok(Status::Ok)
    })
}

/// `fmi3FreeFMUState`: frees `*state` (a state of this instance) and sets it to null; null is
/// nothing to free.
#[unsafe(no_mangle)]
pub extern "C" fn fmi3FreeFMUState(instance: Fmi3Instance, state: *mut FmuStatePtr) -> c_int {
    with_instance(instance, "fmi3FreeFMUState", |i| {
        let slot = state_slot(state)?;
        if !slot.is_null() {
            i.remove_state(*slot)?;
            *slot = std::ptr::null_mut();
        }
        Ok(Status::Ok)
    })
}

/// `fmi3SerializedFMUStateSize`.
///
/// # Safety
/// `size` writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3SerializedFMUStateSize(
    instance: Fmi3Instance,
    state: FmuStatePtr,
    size: *mut usize,
) -> c_int {
    with_instance(instance, "fmi3SerializedFMUStateSize", |i| {
        let token = i.model.spec().token();
        let n = i.state_mut(state)?.serialize(&token).len();
        *unsafe { size.as_mut() }.ok_or("a null size pointer")? = n;
        Ok(Status::Ok)
    })
}

/// `fmi3SerializeFMUState`: `size` must be what `fmi3SerializedFMUStateSize` said.
///
/// # Safety
/// `bytes` `size` writable bytes.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3SerializeFMUState(
    instance: Fmi3Instance,
    state: FmuStatePtr,
    bytes: *mut u8,
    size: usize,
) -> c_int {
    with_instance(instance, "fmi3SerializeFMUState", |i| {
        let token = i.model.spec().token();
        let data = i.state_mut(state)?.serialize(&token);
        if data.len() != size {
            return Err(Fault::error(format!(
                "the buffer has {size} bytes, the state {} (ask fmi3SerializedFMUStateSize)",
                data.len()
            )));
        }
        unsafe { slice_mut(bytes, size) }?.copy_from_slice(data);
        Ok(Status::Ok)
    })
}

/// `fmi3DeserializeFMUState`: a state serialised by any instance of this FMU's build (another
/// process or extraction too); into a new state when `*state` is null, else into `*state`.
///
/// # Safety
/// `bytes` `size` readable bytes.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3DeserializeFMUState(
    instance: Fmi3Instance,
    bytes: *const u8,
    size: usize,
    state: *mut FmuStatePtr,
) -> c_int {
    with_instance(instance, "fmi3DeserializeFMUState", |i| {
        let s = FmuState::deserialize(unsafe { slice(bytes, size) }?, &i.model.spec().token())?;
        let slot = state_slot(state)?;
        if slot.is_null() {
            *slot = i.add_state(s) as FmuStatePtr;
        } else {
            *i.state_mut(*slot)? = s;
        }
        Ok(Status::Ok)
    })
}

macro_rules! unsupported {
    ($name:ident, $why:literal, ($($arg:ident : $ty:ty),*)) => {
        #[doc = concat!("`", stringify!($name), "`: not supported (", $why, "); returns `fmi3Error`.")]
        #[unsafe(no_mangle)]
        pub extern "C" fn $name(instance: Fmi3Instance, $($arg: $ty),*) -> c_int {
            $(let _ = $arg;)*
            with_instance(instance, stringify!($name), |_| {
                Err(Fault::error(concat!("not supported: ", $why)))
            })
        }
    };
}

unsupported!(fmi3GetNumberOfVariableDependencies, "dependencies are not provided",
    (vr: ValueReference, n: *mut usize));
unsupported!(fmi3GetVariableDependencies, "dependencies are not provided",
    (dependent: ValueReference, element_indices_of_dependent: *mut usize,
     independents: *mut ValueReference, element_indices_independents: *mut usize,
     dependency_kinds: *mut c_int, n_dependencies: usize));
unsupported!(fmi3GetDirectionalDerivative, "providesDirectionalDerivatives is false",
    (unknowns: *const ValueReference, n_unknowns: usize, knowns: *const ValueReference,
     n_knowns: usize, seed: *const f64, n_seed: usize, sensitivity: *mut f64,
     n_sensitivity: usize));
unsupported!(fmi3GetAdjointDerivative, "providesAdjointDerivatives is false",
    (unknowns: *const ValueReference, n_unknowns: usize, knowns: *const ValueReference,
     n_knowns: usize, seed: *const f64, n_seed: usize, sensitivity: *mut f64,
     n_sensitivity: usize));
unsupported!(
    fmi3EnterConfigurationMode,
    "the model has no structural parameters",
    ()
);
unsupported!(
    fmi3ExitConfigurationMode,
    "the model has no structural parameters",
    ()
);
unsupported!(fmi3GetIntervalDecimal, "the model has no clocks",
    (vr: *const ValueReference, nvr: usize, intervals: *mut f64, qualifiers: *mut c_int));
unsupported!(fmi3GetIntervalFraction, "the model has no clocks",
    (vr: *const ValueReference, nvr: usize, counters: *mut u64, resolutions: *mut u64,
     qualifiers: *mut c_int));
unsupported!(fmi3GetShiftDecimal, "the model has no clocks",
    (vr: *const ValueReference, nvr: usize, shifts: *mut f64));
unsupported!(fmi3GetShiftFraction, "the model has no clocks",
    (vr: *const ValueReference, nvr: usize, counters: *mut u64, resolutions: *mut u64));
unsupported!(fmi3SetIntervalDecimal, "the model has no clocks",
    (vr: *const ValueReference, nvr: usize, intervals: *const f64));
unsupported!(fmi3SetIntervalFraction, "the model has no clocks",
    (vr: *const ValueReference, nvr: usize, counters: *const u64, resolutions: *const u64));
unsupported!(fmi3SetShiftDecimal, "the model has no clocks",
    (vr: *const ValueReference, nvr: usize, shifts: *const f64));
unsupported!(fmi3SetShiftFraction, "the model has no clocks",
    (vr: *const ValueReference, nvr: usize, counters: *const u64, resolutions: *const u64));
unsupported!(
    fmi3EvaluateDiscreteStates,
    "the model has no discrete states",
    ()
);
unsupported!(fmi3UpdateDiscreteStates, "hasEventMode is false",
    (discrete_states_need_update: *mut bool, terminate_simulation: *mut bool,
     nominals_of_continuous_states_changed: *mut bool,
     values_of_continuous_states_changed: *mut bool, next_event_time_defined: *mut bool,
     next_event_time: *mut f64));
unsupported!(fmi3EnterEventMode, "hasEventMode is false", ());
unsupported!(
    fmi3EnterStepMode,
    "hasEventMode is false: the instance is in step mode after initialisation",
    ()
);
unsupported!(fmi3GetOutputDerivatives, "maxOutputDerivativeOrder is 0",
    (vr: *const ValueReference, nvr: usize, orders: *const i32, values: *mut f64,
     n_values: usize));
unsupported!(fmi3ActivateModelPartition, "Scheduled Execution is not supported",
    (clock_reference: ValueReference, activation_time: f64));
unsupported!(
    fmi3EnterContinuousTimeMode,
    "Model Exchange is not supported",
    ()
);
unsupported!(fmi3CompletedIntegratorStep, "Model Exchange is not supported",
    (no_set_fmu_state_prior_to_current_point: bool, enter_event_mode: *mut bool,
     terminate_simulation: *mut bool));
unsupported!(fmi3SetTime, "Model Exchange is not supported", (time: f64));
unsupported!(fmi3SetContinuousStates, "Model Exchange is not supported",
    (states: *const f64, n: usize));
unsupported!(fmi3GetContinuousStateDerivatives, "Model Exchange is not supported",
    (derivatives: *mut f64, n: usize));
unsupported!(fmi3GetEventIndicators, "Model Exchange is not supported",
    (indicators: *mut f64, n: usize));
unsupported!(fmi3GetContinuousStates, "Model Exchange is not supported",
    (states: *mut f64, n: usize));
unsupported!(fmi3GetNominalsOfContinuousStates, "Model Exchange is not supported",
    (nominals: *mut f64, n: usize));
unsupported!(fmi3GetNumberOfEventIndicators, "Model Exchange is not supported",
    (n: *mut usize));
unsupported!(fmi3GetNumberOfContinuousStates, "Model Exchange is not supported",
    (n: *mut usize));
