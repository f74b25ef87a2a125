//! The FMI life cycle of an instance, as the standards (FMI 2.0 §4.2.4 and FMI 3.0 §4.2) and
//! the Modelica Association's Reference FMUs define it: which function may be called in which
//! mode. A call outside its modes is an illegal call sequence: it returns `Error` and changes
//! nothing else (FMI: "when detecting … a function call not allowed in the current state …, the
//! FMU must return fmi3Error"), and, as after every `Error`, the instance is then in the
//! [`Mode::Error`] mode until an FMU state is set or it is reset.

/// Which standard an instance was created through.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Version {
    /// FMI 2.0 (`fmi2Instantiate`).
    Fmi2,
    /// FMI 3.0 (`fmi3InstantiateCoSimulation`).
    Fmi3,
}

/// Where an instance is in its life cycle.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub enum Mode {
    /// After instantiation or reset: parameters and inputs may be set.
    Instantiated,
    /// Initialisation mode: parameters may still be set; outputs are computed on request.
    Initialization,
    /// Step mode (FMI 2.0 *stepComplete*): `doStep` may be called.
    Step,
    /// FMI 2.0 *stepFailed*: the last `fmi2DoStep` returned `fmi2Discard` with the instance at
    /// the start of that step; set an FMU state (back to [`Mode::Step`]) or terminate. (FMI 3.0
    /// stays in [`Mode::Step`] after a discarded step.)
    StepDiscarded,
    /// After `terminate`.
    Terminated,
    /// After a call returned `Error`: values may be read for diagnosis; set an FMU state or
    /// reset the instance to go on.
    Error,
}

impl Mode {
    /// The mode's name as the standard of `version` calls it.
    pub fn name(self, version: Version) -> &'static str {
        match (self, version) {
            (Mode::Instantiated, _) => "Instantiated",
            (Mode::Initialization, _) => "Initialization Mode",
            (Mode::Step, Version::Fmi2) => "Step Complete",
            (Mode::Step, Version::Fmi3) => "Step Mode",
            (Mode::StepDiscarded, _) => "Step Failed",
            (Mode::Terminated, _) => "Terminated",
            (Mode::Error, _) => "Error",
        }
    }
}

const INSTANTIATED: u8 = 1;
const INITIALIZATION: u8 = 2;
const STEP: u8 = 4;
const STEP_DISCARDED: u8 = 8;
const TERMINATED: u8 = 16;
const ERROR: u8 = 32;
const ANY: u8 = 63;

fn bit(mode: Mode) -> u8 {
    match mode {
        Mode::Instantiated => INSTANTIATED,
        Mode::Initialization => INITIALIZATION,
        Mode::Step => STEP,
        Mode::StepDiscarded => STEP_DISCARDED,
        Mode::Terminated => TERMINATED,
        Mode::Error => ERROR,
    }
}

/// The modes in which `function` (its name without the `fmi2` / `fmi3` prefix) may be called.
fn modes(version: Version, function: &str) -> u8 {
    let get = match version {
        // FMI 2.0: not before initialisation; in Error "for debugging only" (§4.2.4).
        Version::Fmi2 => INITIALIZATION | STEP | STEP_DISCARDED | TERMINATED | ERROR,
        Version::Fmi3 => INSTANTIATED | INITIALIZATION | STEP | STEP_DISCARDED | TERMINATED | ERROR,
    };
    match function {
        "SetupExperiment" | "EnterInitializationMode" => INSTANTIATED,
        "ExitInitializationMode" => INITIALIZATION,
        "Terminate" => STEP | STEP_DISCARDED,
        "DoStep" => STEP,
        "GetRealStatus" | "GetBooleanStatus" | "GetStatus" | "GetIntegerStatus"
        | "GetStringStatus" => STEP | STEP_DISCARDED | TERMINATED,
        f if f.starts_with("Set") && !f.ends_with("State") && !f.ends_with("state") => match f {
            "SetDebugLogging" => ANY,
            _ => INSTANTIATED | INITIALIZATION | STEP,
        },
        f if f.starts_with("Get") && !f.contains("FMU") => get,
        // Reset, FMU states, logging, everything a function refuses by itself.
        _ => ANY,
    }
}

/// Whether `function` (full name, e.g. `fmi2DoStep`) may be called in `mode`.
pub fn allowed(version: Version, function: &str, mode: Mode) -> bool {
    let bare = function
        .strip_prefix("fmi2")
        .or_else(|| function.strip_prefix("fmi3"))
        .unwrap_or(function);
    modes(version, bare) & bit(mode) != 0
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_reference_fmus_life_cycle() {
        use Mode::*;
        use Version::*;
        // Terminate only after initialisation, once.
        for m in [Instantiated, Initialization, Terminated, Error] {
            assert!(!allowed(Fmi2, "fmi2Terminate", m), "{m:?}");
            assert!(!allowed(Fmi3, "fmi3Terminate", m), "{m:?}");
        }
        assert!(allowed(Fmi2, "fmi2Terminate", StepDiscarded));
        // doStep only in step mode.
        for m in [
            Instantiated,
            Initialization,
            StepDiscarded,
            Terminated,
            Error,
        ] {
            assert!(!allowed(Fmi3, "fmi3DoStep", m), "{m:?}");
        }
        // FMI 2.0 reads no values before initialisation, FMI 3.0 does.
        assert!(!allowed(Fmi2, "fmi2GetReal", Instantiated));
        assert!(allowed(Fmi3, "fmi3GetFloat64", Instantiated));
        // Setting values after termination or an error is refused; FMU states and reset are
        // always allowed.
        assert!(!allowed(Fmi3, "fmi3SetFloat64", Terminated));
        assert!(!allowed(Fmi2, "fmi2SetReal", Error));
        for f in ["fmi2SetFMUstate", "fmi2Reset", "fmi2DeSerializeFMUstate"] {
            assert!(allowed(Fmi2, f, Error), "{f}");
        }
        assert!(allowed(Fmi3, "fmi3SetFMUState", Instantiated));
        assert!(allowed(Fmi3, "fmi3SetDebugLogging", Terminated));
        assert!(!allowed(Fmi3, "fmi3EnterInitializationMode", Step));
    }
}
