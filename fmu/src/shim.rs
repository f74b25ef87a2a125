//! What the FMI 2.0 ([`crate::fmi2`]) and FMI 3.0 ([`crate::fmi3`]) C APIs share, written
//! once: the bodies of the functions both standards define alike (logging categories, Float64 /
//! Real and String values, the FMU-state functions), and the macros each standard's module
//! instantiates with its own function names and C types — `life_cycle!` (free, exit
//! initialisation, terminate, reset), `fmu_states!` (get, set, free, serialised size,
//! serialise, deserialise) and `unsupported!` (functions this model does not provide).
//!
//! Every exported function keeps its standard's symbol name and C signature and runs its body
//! through [`with_instance`](crate::instance::with_instance): the handle is checked, the call is checked against the life
//! cycle under the function's own name ([`crate::machine`]), a panic is caught, a fault is
//! logged and returned as its status — nothing unwinds into the importer.

use crate::instance::{Instance, slice, slice_mut, state_slot, text};
use crate::log::{Status, c_string};
use crate::model::Fault;
use crate::state::FmuState;
use std::ffi::{c_char, c_void};

/// The body of `fmi2SetDebugLogging` / `fmi3SetDebugLogging`: the named log categories (all
/// when none is named) on or off; an unknown category is an error.
///
/// # Safety
/// `categories` null or `n` pointers, each null or a NUL-terminated string.
pub unsafe fn set_debug_logging(
    i: &mut Instance,
    on: bool,
    n: usize,
    categories: *const *const c_char,
) -> Result<Status, Fault> {
    let names = unsafe { slice(categories, n) }?
        .iter()
        .map(|p| unsafe { text(*p) }.map(|t| t.into_owned()))
        .collect::<Option<Vec<_>>>()
        .ok_or("a null category name")?;
    i.log.set_categories(on, &names)?;
    Ok(Status::Ok)
}

/// The body of `fmi2GetReal` / `fmi3GetFloat64`: each variable's value into `out`.
pub fn get_reals(i: &mut Instance, vr: &[u32], out: &mut [f64]) -> Result<Status, Fault> {
    for (r, o) in vr.iter().zip(out) {
        *o = i.model.get_real(*r)?;
    }
    Ok(Status::Ok)
}

/// The body of `fmi2SetReal` / `fmi3SetFloat64`: parameters before initialisation ends, the
/// input at any time; a refusal (a value outside the variable's range) is mapped by `refusal`
/// to the status the standard gives it.
pub fn set_reals(
    i: &mut Instance,
    vr: &[u32],
    values: &[f64],
    refusal: fn(Fault) -> Fault,
) -> Result<Status, Fault> {
    for (r, v) in vr.iter().zip(values) {
        i.model.set_real(*r, *v).map_err(refusal)?;
    }
    Ok(Status::Ok)
}

/// The body of `fmi2GetString` / `fmi3GetString`: the pointers stay valid until the next call
/// on this instance.
pub fn get_strings(
    i: &mut Instance,
    vr: &[u32],
    out: &mut [*const c_char],
) -> Result<Status, Fault> {
    i.strings = vr
        .iter()
        .map(|r| i.model.get_string(*r).map(|s| c_string(&s)))
        .collect::<Result<_, _>>()?;
    for (s, o) in i.strings.iter().zip(out) {
        *o = s.as_ptr();
    }
    Ok(Status::Ok)
}

/// The body of `fmi2SetString` / `fmi3SetString`, a refusal mapped by `refusal`.
///
/// # Safety
/// Each of `values` null or a NUL-terminated string.
pub unsafe fn set_strings(
    i: &mut Instance,
    vr: &[u32],
    values: &[*const c_char],
    refusal: fn(Fault) -> Fault,
) -> Result<Status, Fault> {
    for (r, v) in vr.iter().zip(values) {
        let s = unsafe { text(*v) }.ok_or("a null string")?;
        i.model.set_string(*r, &s).map_err(refusal)?;
    }
    Ok(Status::Ok)
}

/// The body of a getter or setter of a type the model has no variable of (`what`): nothing to
/// do for no value reference, an error naming the first one otherwise.
pub fn none_of(vr: &[u32], what: &str) -> Result<Status, Fault> {
    match vr.first() {
        None => Ok(Status::Ok),
        Some(r) => Err(Fault::error(format!(
            "no {what} variable has the value reference {r}"
        ))),
    }
}

/// The body of `fmi2GetFMUstate` / `fmi3GetFMUState`: a new state when `*state` is null, else
/// `*state` (one of this instance's states) overwritten.
pub fn get_state(i: &mut Instance, state: *mut *mut c_void) -> Result<Status, Fault> {
    let slot = state_slot(state)?;
    if slot.is_null() {
        let s = i.model.get_state()?;
        *slot = i.add_state(s) as *mut c_void;
    } else {
        i.refresh_state(*slot)?;
    }
    Ok(Status::Ok)
}

/// The body of `fmi2SetFMUstate` / `fmi3SetFMUState`: any state of this instance, in any mode
/// (also before initialisation).
pub fn set_state(i: &mut Instance, state: *mut c_void) -> Result<Status, Fault> {
    let s = i.state(state)?.clone();
    i.model.set_state(&s)?;
    Ok(Status::Ok)
}

/// The body of `fmi2FreeFMUstate` / `fmi3FreeFMUState`: frees `*state` (a state of this
/// instance) and sets it to null; null is nothing to free.
pub fn free_state(i: &mut Instance, state: *mut *mut c_void) -> Result<Status, Fault> {
    let slot = state_slot(state)?;
    if !slot.is_null() {
        i.remove_state(*slot)?;
        *slot = std::ptr::null_mut();
    }
    Ok(Status::Ok)
}

/// The body of `fmi2SerializedFMUstateSize` / `fmi3SerializedFMUStateSize`.
///
/// # Safety
/// `size` null or writable.
pub unsafe fn serialized_size(
    i: &mut Instance,
    state: *mut c_void,
    size: *mut usize,
) -> Result<Status, Fault> {
    let token = i.model.spec().token();
    let n = i.state_mut(state)?.serialize(&token).len();
    *unsafe { size.as_mut() }.ok_or("a null size pointer")? = n;
    Ok(Status::Ok)
}

/// The body of `fmi2SerializeFMUstate` / `fmi3SerializeFMUState`: `size` must be what the
/// standard's size function (`size_function`, named in the error) said.
///
/// # Safety
/// `bytes` `size` writable bytes.
pub unsafe fn serialize(
    i: &mut Instance,
    state: *mut c_void,
    bytes: *mut u8,
    size: usize,
    size_function: &str,
) -> Result<Status, Fault> {
    let token = i.model.spec().token();
    let data = i.state_mut(state)?.serialize(&token);
    if data.len() != size {
        return Err(Fault::error(format!(
            "the buffer has {size} bytes, the state {} (ask {size_function})",
            data.len()
        )));
    }
    unsafe { slice_mut(bytes, size) }?.copy_from_slice(data);
    Ok(Status::Ok)
}

/// The body of `fmi2DeSerializeFMUstate` / `fmi3DeserializeFMUState`: a state serialised by
/// any instance of this FMU's build (another process or extraction too); into a new state when
/// `*state` is null, else into `*state`.
///
/// # Safety
/// `bytes` `size` readable bytes.
pub unsafe fn deserialize(
    i: &mut Instance,
    bytes: *const u8,
    size: usize,
    state: *mut *mut c_void,
) -> Result<Status, Fault> {
    let s = FmuState::deserialize(unsafe { slice(bytes, size) }?, &i.model.spec().token())?;
    let slot = state_slot(state)?;
    if slot.is_null() {
        *slot = i.add_state(s) as *mut c_void;
    } else {
        *i.state_mut(*slot)? = s;
    }
    Ok(Status::Ok)
}

/// The instance's life cycle past instantiation, for the handle type `$handle`: free, exit
/// initialisation, terminate, reset.
macro_rules! life_cycle {
    ($handle:ty; free: $free:ident, exit: $exit:ident, terminate: $terminate:ident,
     reset: $reset:ident) => {
        #[doc = concat!("`", stringify!($free), "`: frees the instance and its FMU states; an ",
                        "unknown or already freed handle is ignored.")]
        #[unsafe(no_mangle)]
        pub extern "C" fn $free(instance: $handle) {
            $crate::log::guard(|| $crate::instance::free(instance), |_| ());
        }

        #[doc = concat!("`", stringify!($exit), "`: checks the parameters (a bad one is named ",
                        "in the log) and builds the simulation; the instance can then step.")]
        #[unsafe(no_mangle)]
        pub extern "C" fn $exit(instance: $handle) -> ::std::ffi::c_int {
            $crate::instance::with_instance(instance, stringify!($exit), |i| {
                i.model.exit_initialization()?;
                Ok($crate::log::Status::Ok)
            })
        }

        #[doc = concat!("`", stringify!($terminate), "`: after initialisation, once.")]
        #[unsafe(no_mangle)]
        pub extern "C" fn $terminate(instance: $handle) -> ::std::ffi::c_int {
            $crate::instance::with_instance(instance, stringify!($terminate), |i| {
                i.model.terminate();
                Ok($crate::log::Status::Ok)
            })
        }

        #[doc = concat!("`", stringify!($reset), "`: back to the instantiated state with the ",
                        "default parameters (the instance's FMU states stay valid).")]
        #[unsafe(no_mangle)]
        pub extern "C" fn $reset(instance: $handle) -> ::std::ffi::c_int {
            $crate::instance::with_instance(instance, stringify!($reset), |i| {
                i.model.reset();
                Ok($crate::log::Status::Ok)
            })
        }
    };
}
pub(crate) use life_cycle;

/// The six FMU-state functions for the handle type `$handle`, the state type `$state` and
/// the byte type `$byte` of serialised states (their bodies: [`get_state`], [`set_state`],
/// [`free_state`], [`serialized_size`], [`serialize`], [`deserialize`]).
macro_rules! fmu_states {
    ($handle:ty, $state:ty, $byte:ty; get: $get:ident, set: $set:ident, free: $free:ident,
     size: $size:ident, serialize: $serialize:ident, deserialize: $deserialize:ident) => {
        #[doc = concat!("`", stringify!($get), "`: a new state when `*state` is null, else ",
                        "`*state` (one of this instance's states) overwritten.")]
        #[unsafe(no_mangle)]
        pub extern "C" fn $get(instance: $handle, state: *mut $state) -> ::std::ffi::c_int {
            $crate::instance::with_instance(instance, stringify!($get), |i| {
                $crate::shim::get_state(i, state)
            })
        }

        #[doc = concat!("`", stringify!($set), "`: any state of this instance, in any mode ",
                        "(also before initialisation).")]
        #[unsafe(no_mangle)]
        pub extern "C" fn $set(instance: $handle, state: $state) -> ::std::ffi::c_int {
            $crate::instance::with_instance(instance, stringify!($set), |i| {
                $crate::shim::set_state(i, state)
            })
        }

        #[doc = concat!("`", stringify!($free), "`: frees `*state` (a state of this instance) ",
                        "and sets it to null; null is nothing to free.")]
        #[unsafe(no_mangle)]
        pub extern "C" fn $free(instance: $handle, state: *mut $state) -> ::std::ffi::c_int {
            $crate::instance::with_instance(instance, stringify!($free), |i| {
                $crate::shim::free_state(i, state)
            })
        }

        #[doc = concat!("`", stringify!($size), "`.")]
        ///
        /// # Safety
        /// `size` writable.
        #[unsafe(no_mangle)]
        pub unsafe extern "C" fn $size(
            instance: $handle,
            state: $state,
            size: *mut usize,
        ) -> ::std::ffi::c_int {
            $crate::instance::with_instance(instance, stringify!($size), |i| unsafe {
                $crate::shim::serialized_size(i, state, size)
            })
        }

        #[doc = concat!("`", stringify!($serialize), "`: `size` must be what `",
                        stringify!($size), "` said.")]
        ///
        /// # Safety
        /// `bytes` `size` writable bytes.
        #[unsafe(no_mangle)]
        pub unsafe extern "C" fn $serialize(
            instance: $handle,
            state: $state,
            bytes: *mut $byte,
            size: usize,
        ) -> ::std::ffi::c_int {
            $crate::instance::with_instance(instance, stringify!($serialize), |i| unsafe {
                $crate::shim::serialize(i, state, bytes as *mut u8, size, stringify!($size))
            })
        }

        #[doc = concat!("`", stringify!($deserialize), "`: a state serialised by any instance ",
                        "of this FMU's build (another process or extraction too); into a new ",
                        "state when `*state` is null, else into `*state`.")]
        ///
        /// # Safety
        /// `bytes` `size` readable bytes.
        #[unsafe(no_mangle)]
        pub unsafe extern "C" fn $deserialize(
            instance: $handle,
            bytes: *const $byte,
            size: usize,
            state: *mut $state,
        ) -> ::std::ffi::c_int {
            $crate::instance::with_instance(instance, stringify!($deserialize), |i| unsafe {
                $crate::shim::deserialize(i, bytes as *const u8, size, state)
            })
        }
    };
}
pub(crate) use fmu_states;

/// Functions this model does not provide, for the handle type `$handle`: each logs
/// `not supported: <why>` and returns `$error` (the standard's `…Error` status, named in its
/// docs). Its arguments are not read.
macro_rules! unsupported {
    ($handle:ty, $error:literal;
     $($name:ident, $why:literal, ($($arg:ident : $ty:ty),* $(,)?);)*) => {
        $(
            #[doc = concat!("`", stringify!($name), "`: not supported (", $why, "); returns `",
                            $error, "`.")]
            #[unsafe(no_mangle)]
            pub extern "C" fn $name(instance: $handle, $($arg: $ty),*) -> ::std::ffi::c_int {
                $(let _ = $arg;)*
                $crate::instance::with_instance(instance, stringify!($name), |_| {
                    Err($crate::model::Fault::error(concat!("not supported: ", $why)))
                })
            }
        )*
    };
}
pub(crate) use unsupported;

/// Getters and setters of types the model has no variable of, for the handle type `$handle`:
/// each takes the value references (`vr`, `nvr`) and then its own arguments, which it does not
/// read; no value reference is `OK`, any is an error naming it ([`none_of`]).
macro_rules! no_variables {
    ($handle:ty; $($what:literal: $($name:ident($($arg:ident: $ty:ty),*)),+;)*) => {
        $($(
            #[doc = concat!("`", stringify!($name), "`: the model has no ", $what, " variables.")]
            ///
            /// # Safety
            /// `vr` `nvr` values.
            #[unsafe(no_mangle)]
            pub unsafe extern "C" fn $name(
                instance: $handle,
                vr: *const u32,
                nvr: usize,
                $($arg: $ty),*
            ) -> ::std::ffi::c_int {
                $(let _ = $arg;)*
                $crate::instance::with_instance(instance, stringify!($name), |_| {
                    $crate::shim::none_of(unsafe { $crate::instance::slice(vr, nvr) }?, $what)
                })
            }
        )+)*
    };
}
pub(crate) use no_variables;
