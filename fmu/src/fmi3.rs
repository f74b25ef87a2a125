//! The FMI 3.0 Co-Simulation C API over the same [`Model`] as FMI 2.0, with the bodies and
//! macros both share ([`crate::shim`]). Every function of the standard is exported, as
//! importers such as fmpy bind them all; those this model does not support log why and return
//! `fmi3Error`.
//!
//! Supported: `fmi3InstantiateCoSimulation` (no event mode, no intermediate update), the
//! Float64 / Int32 / Int64 / String variables, `fmi3DoStep` with any communication step, reset,
//! and FMU states: get, set, free, serialise and deserialise. Model Exchange and Scheduled
//! Execution instances are refused; the other variable types hold no variables; clocks,
//! derivatives and configuration mode are not supported.

use crate::instance::{Instance, slice, slice_mut, text, with_instance};
use crate::log::{Fmi3Logger, Logger, Status, c_string, guard};
use crate::machine::Version;
use crate::model::{Fault, Model};
use crate::shim;
use crate::spec::Kind;
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
    with_instance(instance, "fmi3SetDebugLogging", |i| unsafe {
        shim::set_debug_logging(i, logging_on, n_categories, categories)
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

shim::life_cycle!(Fmi3Instance; free: fmi3FreeInstance, exit: fmi3ExitInitializationMode,
    terminate: fmi3Terminate, reset: fmi3Reset);

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

fn check_counts(nvr: usize, n_values: usize) -> Result<(), Fault> {
    if nvr == n_values {
        Ok(())
    } else {
        Err(Fault::error(format!(
            "{nvr} value references but {n_values} values (the model has scalar variables only)"
        )))
    }
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

/// The body of `fmi3GetInt32` / `fmi3GetInt64`: each variable must be of `kind`.
fn get_integers<T: TryFrom<i64>>(
    i: &mut Instance,
    vr: &[ValueReference],
    out: &mut [T],
    kind: Kind,
) -> Result<Status, Fault> {
    for (r, o) in vr.iter().zip(out) {
        check_kind(&i.model, *r, kind)?;
        let v = i.model.get_integer(*r)?;
        *o = T::try_from(v).map_err(|_| format!("{v} does not fit"))?;
    }
    Ok(Status::Ok)
}

/// The body of `fmi3SetInt32` / `fmi3SetInt64`: each variable must be of `kind`; out of the
/// variable's range is `fmi3Discard`.
fn set_integers<T: Copy + Into<i64>>(
    i: &mut Instance,
    vr: &[ValueReference],
    values: &[T],
    kind: Kind,
) -> Result<Status, Fault> {
    for (r, v) in vr.iter().zip(values) {
        check_kind(&i.model, *r, kind)?;
        i.model.set_integer(*r, (*v).into())?;
    }
    Ok(Status::Ok)
}

/// The getter and the setter of one variable type: the counts checked equal (the model has
/// scalar variables only), the arrays taken from the importer's pointers, then the bodies
/// `$getter(instance, vrs, out)` and `$setter(instance, vrs, values)`.
macro_rules! values {
    ($($get:ident, $set:ident, $ty:ty, $get_doc:literal, $set_doc:literal,
       $getter:expr, $setter:expr;)*) => {
        $(
            #[doc = concat!("`", stringify!($get), "`", $get_doc)]
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
                    $getter(i, vr, out)
                })
            }

            #[doc = concat!("`", stringify!($set), "`", $set_doc)]
            ///
            /// # Safety
            /// `vr` `nvr` values, `values` `n_values` values (strings NUL-terminated).
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
                    $setter(i, vr, values)
                })
            }
        )*
    };
}

values! {
    fmi3GetFloat64, fmi3SetFloat64, f64, ".",
    ": parameters before initialisation ends, the input at any time; a value outside the \
     variable's range is refused with `fmi3Discard` (nothing changes).",
    shim::get_reals, |i, vr, v| shim::set_reals(i, vr, v, |f| f);
    fmi3GetInt32, fmi3SetInt32, i32, ".", ": out of the variable's range: `fmi3Discard`.",
    |i, vr, o| get_integers(i, vr, o, Kind::Int32),
    |i, vr, v| set_integers::<i32>(i, vr, v, Kind::Int32);
    fmi3GetInt64, fmi3SetInt64, i64, ".", ": out of the variable's range: `fmi3Discard`.",
    |i, vr, o| get_integers(i, vr, o, Kind::Int64),
    |i, vr, v| set_integers::<i64>(i, vr, v, Kind::Int64);
    fmi3GetString, fmi3SetString, *const c_char,
    ": the pointers stay valid until the next call on this instance.", ".",
    shim::get_strings,
    |i, vr, v| unsafe { shim::set_strings(i, vr, v, |f| f) };
}

/// Types without variables whose getter and setter have the common signature (`values`,
/// `n_values` after the value references): one row each.
macro_rules! no_scalars {
    ($($what:literal: $get:ident, $set:ident, $ty:ty;)*) => {
        shim::no_variables! { Fmi3Instance;
            $($what: $get(values: *mut $ty, n_values: usize),
                $set(values: *const $ty, n_values: usize);)*
        }
    };
}

no_scalars! {
    "Float32": fmi3GetFloat32, fmi3SetFloat32, f32;
    "Int8": fmi3GetInt8, fmi3SetInt8, i8;
    "UInt8": fmi3GetUInt8, fmi3SetUInt8, u8;
    "Int16": fmi3GetInt16, fmi3SetInt16, i16;
    "UInt16": fmi3GetUInt16, fmi3SetUInt16, u16;
    "UInt32": fmi3GetUInt32, fmi3SetUInt32, u32;
    "UInt64": fmi3GetUInt64, fmi3SetUInt64, u64;
    "Boolean": fmi3GetBoolean, fmi3SetBoolean, bool;
}

shim::no_variables! { Fmi3Instance;
    "Binary": fmi3GetBinary(value_sizes: *mut usize, values: *mut *const u8, n_values: usize),
        fmi3SetBinary(value_sizes: *const usize, values: *const *const u8, n_values: usize);
    "Clock": fmi3GetClock(values: *mut bool), fmi3SetClock(values: *const bool);
}

shim::fmu_states!(Fmi3Instance, FmuStatePtr, u8; get: fmi3GetFMUState,
    set: fmi3SetFMUState, free: fmi3FreeFMUState, size: fmi3SerializedFMUStateSize,
    serialize: fmi3SerializeFMUState, deserialize: fmi3DeserializeFMUState);

shim::unsupported! { Fmi3Instance, "fmi3Error";
    fmi3GetNumberOfVariableDependencies, "dependencies are not provided",
        (vr: ValueReference, n: *mut usize);
    fmi3GetVariableDependencies, "dependencies are not provided",
        (dependent: ValueReference, element_indices_of_dependent: *mut usize,
         independents: *mut ValueReference, element_indices_independents: *mut usize,
         dependency_kinds: *mut c_int, n_dependencies: usize);
    fmi3GetDirectionalDerivative, "providesDirectionalDerivatives is false",
        (unknowns: *const ValueReference, n_unknowns: usize, knowns: *const ValueReference,
         n_knowns: usize, seed: *const f64, n_seed: usize, sensitivity: *mut f64,
         n_sensitivity: usize);
    fmi3GetAdjointDerivative, "providesAdjointDerivatives is false",
        (unknowns: *const ValueReference, n_unknowns: usize, knowns: *const ValueReference,
         n_knowns: usize, seed: *const f64, n_seed: usize, sensitivity: *mut f64,
         n_sensitivity: usize);
    fmi3EnterConfigurationMode, "the model has no structural parameters", ();
    fmi3ExitConfigurationMode, "the model has no structural parameters", ();
    fmi3GetIntervalDecimal, "the model has no clocks",
        (vr: *const ValueReference, nvr: usize, intervals: *mut f64, qualifiers: *mut c_int);
    fmi3GetIntervalFraction, "the model has no clocks",
        (vr: *const ValueReference, nvr: usize, counters: *mut u64, resolutions: *mut u64,
         qualifiers: *mut c_int);
    fmi3GetShiftDecimal, "the model has no clocks",
        (vr: *const ValueReference, nvr: usize, shifts: *mut f64);
    fmi3GetShiftFraction, "the model has no clocks",
        (vr: *const ValueReference, nvr: usize, counters: *mut u64, resolutions: *mut u64);
    fmi3SetIntervalDecimal, "the model has no clocks",
        (vr: *const ValueReference, nvr: usize, intervals: *const f64);
    fmi3SetIntervalFraction, "the model has no clocks",
        (vr: *const ValueReference, nvr: usize, counters: *const u64, resolutions: *const u64);
    fmi3SetShiftDecimal, "the model has no clocks",
        (vr: *const ValueReference, nvr: usize, shifts: *const f64);
    fmi3SetShiftFraction, "the model has no clocks",
        (vr: *const ValueReference, nvr: usize, counters: *const u64, resolutions: *const u64);
    fmi3EvaluateDiscreteStates, "the model has no discrete states", ();
    fmi3UpdateDiscreteStates, "hasEventMode is false",
        (discrete_states_need_update: *mut bool, terminate_simulation: *mut bool,
         nominals_of_continuous_states_changed: *mut bool,
         values_of_continuous_states_changed: *mut bool, next_event_time_defined: *mut bool,
         next_event_time: *mut f64);
    fmi3EnterEventMode, "hasEventMode is false", ();
    fmi3EnterStepMode, "hasEventMode is false: the instance is in step mode after initialisation",
        ();
    fmi3GetOutputDerivatives, "maxOutputDerivativeOrder is 0",
        (vr: *const ValueReference, nvr: usize, orders: *const i32, values: *mut f64,
         n_values: usize);
    fmi3ActivateModelPartition, "Scheduled Execution is not supported",
        (clock_reference: ValueReference, activation_time: f64);
    fmi3EnterContinuousTimeMode, "Model Exchange is not supported", ();
    fmi3CompletedIntegratorStep, "Model Exchange is not supported",
        (no_set_fmu_state_prior_to_current_point: bool, enter_event_mode: *mut bool,
         terminate_simulation: *mut bool);
    fmi3SetTime, "Model Exchange is not supported", (time: f64);
    fmi3SetContinuousStates, "Model Exchange is not supported", (states: *const f64, n: usize);
    fmi3GetContinuousStateDerivatives, "Model Exchange is not supported",
        (derivatives: *mut f64, n: usize);
    fmi3GetEventIndicators, "Model Exchange is not supported", (indicators: *mut f64, n: usize);
    fmi3GetContinuousStates, "Model Exchange is not supported", (states: *mut f64, n: usize);
    fmi3GetNominalsOfContinuousStates, "Model Exchange is not supported",
        (nominals: *mut f64, n: usize);
    fmi3GetNumberOfEventIndicators, "Model Exchange is not supported", (n: *mut usize);
    fmi3GetNumberOfContinuousStates, "Model Exchange is not supported", (n: *mut usize);
}
