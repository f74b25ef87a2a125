//! FMU states: what `fmi2GetFMUstate` / `fmi3GetFMUState` copy and `…SetFMUState` puts back,
//! and their serialised form.
//!
//! A state is everything the instance's future depends on: the life-cycle mode, the start and
//! stop time, the parameters and the inputs, and — after initialisation — the simulation's
//! snapshot. Setting a state therefore
//! works in any mode, also before initialisation (FMI allows it in Instantiated mode): when the
//! instance has no simulation for the state's parameters, one is built from them first.
//!
//! **Serialised form**: a [`efsi_run::binary`] file ([`FORMAT`]) whose body holds the
//! instantiation token (a state of another FMU or build is refused), the mode, start and stop
//! time, the step bound, each parameter and input, then — after initialisation — the
//! simulation as an efsi checkpoint file with the scene and the law's identity. Nothing in it
//! depends on where the FMU was extracted: the scene names the law by its library's file name
//! and the law is identified by name, ABI version, parameter table, size and content hash, so
//! a state serialised by one extraction (or process, or machine)
//! sets into another, whatever its stop time (the stop time is not part of the scene); any
//! difference of scene or law is refused, naming it.

use crate::machine::Mode;
use crate::model::Values;
use crate::stepping::{Run, RunIdentity, SCENE_LABEL};
use efsi_core::Snapshot;
use efsi_core::overrides::OverrideValue;
use efsi_run::binary::{self, Format};
use efsi_run::checkpoint::{self, Checkpoint, CheckpointFile, OutputState};
use serde::{Deserialize, Serialize};
use std::borrow::Cow;
use std::sync::Arc;

/// The simulation part of a state.
#[derive(Clone, Debug)]
pub enum Simulated {
    /// Taken from a running simulation of this process.
    Live {
        /// The snapshot.
        snapshot: Box<Snapshot>,
        /// The scene and law it belongs to.
        identity: Arc<RunIdentity>,
    },
    /// Read from serialised bytes, fitted into a simulation when it is set.
    Recorded {
        /// The decoded checkpoint.
        file: Box<CheckpointFile>,
        /// Its bytes (for serialising it again).
        bytes: Vec<u8>,
    },
}

/// A saved FMU state (see the module docs).
#[derive(Clone, Debug)]
pub struct FmuState {
    /// The life-cycle mode.
    pub mode: Mode,
    /// Start time.
    pub start_time: f64,
    /// Stop time, if the importer gave one.
    pub stop_time: Option<f64>,
    /// The parameters, the step bound and the inputs.
    pub values: Values,
    /// The simulation, after initialisation.
    pub simulated: Option<Simulated>,
    /// The serialised form, computed on demand (FMI asks for the size, then the bytes).
    pub serialized: Option<Vec<u8>>,
}

/// The serialised state kind of [`efsi_run::binary`]: magic `EFSIFMU2`, layout version 2.
pub const FORMAT: Format = Format {
    magic: b"EFSIFMU2",
    version: 2,
    kind: "serialised FMU state",
};

/// The body of a serialised state (layout [`FORMAT`]): the one definition of its layout,
/// written from an [`FmuState`] by reference and read back into one.
#[derive(Serialize, Deserialize)]
struct Body<'a> {
    /// The instantiation token of the FMU that wrote it.
    token: Cow<'a, str>,
    mode: Mode,
    start_time: f64,
    stop_time: Option<f64>,
    max_steps: i64,
    params: Cow<'a, [OverrideValue]>,
    inputs: Cow<'a, [f64]>,
    /// A checkpoint file ([`efsi_run::checkpoint`]) of the simulation, after initialisation.
    simulation: Option<Cow<'a, [u8]>>,
}

impl FmuState {
    /// The serialised form (see the module docs); `token` is the FMU's instantiation token.
    pub fn serialize(&mut self, token: &str) -> &[u8] {
        if self.serialized.is_none() {
            let checkpoint = match &self.simulated {
                None => None,
                Some(Simulated::Live { snapshot, identity }) => {
                    Some(Cow::Owned(checkpoint::encode(&Checkpoint {
                        efsi_version: env!("CARGO_PKG_VERSION").to_string(),
                        scene_path: SCENE_LABEL.into(),
                        scene_ron: identity.scene_ron.clone(),
                        overrides: Vec::new(),
                        law: identity.law.clone(),
                        outputs: OutputState::default(),
                        snapshot: (**snapshot).clone(),
                    })))
                }
                Some(Simulated::Recorded { bytes, .. }) => Some(Cow::Borrowed(bytes.as_slice())),
            };
            let v = &self.values;
            let body = Body {
                token: Cow::Borrowed(token),
                mode: self.mode,
                start_time: self.start_time,
                stop_time: self.stop_time,
                max_steps: v.max_steps,
                params: Cow::Borrowed(&v.params),
                inputs: Cow::Borrowed(&v.inputs),
                simulation: checkpoint,
            };
            self.serialized = Some(binary::encode(&FORMAT, &body));
        }
        self.serialized.as_deref().unwrap_or_default()
    }

    /// A state from [`serialize`](Self::serialize)'s bytes; `token` is this FMU's
    /// instantiation token. The simulation part is decoded but fitted into a simulation only
    /// when the state is set.
    pub fn deserialize(bytes: &[u8], token: &str) -> Result<FmuState, String> {
        let what = FORMAT.kind;
        let body: Body = binary::decode(bytes, &FORMAT)?;
        if body.token != token {
            return Err(format!(
                "the {what} belongs to another build of the FMU (instantiation token {}, this one {token})",
                body.token
            ));
        }
        let simulated = match body.simulation {
            None => None,
            Some(bytes) => {
                let bytes = bytes.into_owned();
                let file = checkpoint::decode(&bytes, what).map_err(|e| e.to_string())?;
                Some(Simulated::Recorded {
                    file: Box::new(file),
                    bytes,
                })
            }
        };
        Ok(FmuState {
            mode: body.mode,
            start_time: body.start_time,
            stop_time: body.stop_time,
            values: Values {
                params: body.params.into_owned(),
                max_steps: body.max_steps,
                inputs: body.inputs.into_owned(),
            },
            simulated,
            serialized: Some(bytes.to_vec()),
        })
    }
}

/// Fit the state's simulation into `run` (built from the state's parameters): a live snapshot
/// is restored as it is; a recorded one must belong to the same scene (the end time aside) and
/// the same law library, else the differences are listed.
pub fn restore_into(run: &mut Run, simulated: &Simulated) -> Result<(), String> {
    match simulated {
        Simulated::Live { snapshot, .. } => {
            run.sim.restore(snapshot).map_err(|e| e.to_string())?;
        }
        Simulated::Recorded { file, .. } => {
            let what = "serialised FMU state";
            let mut recorded = file.scene().map_err(|e| e.to_string())?;
            recorded.time.end = run.sim.scene.time.end;
            let mut diffs: Vec<String> = checkpoint::scene_differences(&recorded, &run.sim.scene)
                .into_iter()
                .map(|d| format!("scene: {d}"))
                .collect();
            diffs.extend(checkpoint::law_differences(&file.law, &run.identity.law));
            if !diffs.is_empty() {
                return Err(format!(
                    "the {what} does not fit this FMU's simulation of its parameters: {}",
                    diffs.join("; ")
                ));
            }
            let snapshot = file
                .record
                .clone()
                .into_snapshot(run.sim.snapshot(), what)
                .map_err(|e| e.to_string())?;
            run.sim.restore(&snapshot).map_err(|e| e.to_string())?;
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_state_comes_back_as_it_was_and_another_version_or_build_is_refused() {
        let params = vec![
            OverrideValue::Float(1e-3),
            OverrideValue::Int(-7),
            OverrideValue::Str("IncompleteCholesky".into()),
            OverrideValue::Bool(true),
            OverrideValue::Ron("[1.0, 2.0]".into()),
        ];
        let mut state = FmuState {
            mode: Mode::Initialization,
            start_time: 0.5,
            stop_time: None,
            values: Values {
                params: params.clone(),
                max_steps: 123,
                inputs: vec![-0.0, 2.5],
            },
            simulated: None,
            serialized: None,
        };
        let bytes = state.serialize("{a}").to_vec();
        assert_eq!(&bytes[..8], b"EFSIFMU2");
        assert_eq!(binary::version_of(&bytes, &FORMAT), Some(FORMAT.version));
        let back = FmuState::deserialize(&bytes, "{a}").unwrap();
        assert_eq!(back.mode, Mode::Initialization);
        assert_eq!((back.start_time, back.stop_time), (0.5, None));
        assert_eq!(back.values.params, params);
        assert_eq!(back.values.max_steps, 123);
        let bits: Vec<u64> = back.values.inputs.iter().map(|x| x.to_bits()).collect();
        assert_eq!(bits, [(-0.0f64).to_bits(), 2.5f64.to_bits()]);
        assert!(back.simulated.is_none());
        assert_eq!(
            FmuState::deserialize(&bytes, "{b}").unwrap_err(),
            "the serialised FMU state belongs to another build of the FMU (instantiation token \
             {a}, this one {b})"
        );
        let mut old = bytes.clone();
        old[8] = 1;
        assert_eq!(
            FmuState::deserialize(&old, "{a}").unwrap_err(),
            format!(
                "serialised FMU state format version 1 (written by an earlier efsi); this efsi \
                 reads version {} only",
                FORMAT.version
            )
        );
    }
}
