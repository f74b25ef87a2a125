//! FMU states: what `fmi2GetFMUstate` / `fmi3GetFMUState` copy and `…SetFMUState` puts back,
//! and their serialised form.
//!
//! A state is everything the instance's future depends on: the life-cycle mode, the start and
//! stop time, the parameters and the inputs, and — after initialisation — the simulation's
//! snapshot. Setting a state therefore
//! works in any mode, also before initialisation (FMI allows it in Instantiated mode): when the
//! instance has no simulation for the state's parameters, one is built from them first.
//!
//! **Serialised form** (little-endian): the magic `EFSIFMU2`, a `u32` layout version, the
//! instantiation token (a state of another FMU or build is refused), the mode, start and
//! stop time, the step bound, each parameter and input, then — after
//! initialisation — the snapshot in efsi's checkpoint format with the scene and the law's
//! identity. Nothing in it depends on where the FMU was extracted: the scene names the law by
//! its library's file name and the law is identified by name, ABI version, parameter table,
//! size and content hash, so a state serialised by one extraction (or process, or machine)
//! sets into another, whatever its stop time (the stop time is not part of the scene); any
//! difference of scene or law is refused, naming it.

use crate::machine::Mode;
use crate::model::Values;
use crate::stepping::{Run, RunIdentity, SCENE_LABEL};
use efsi_core::Snapshot;
use efsi_core::overrides::OverrideValue;
use efsi_run::checkpoint::{self, Checkpoint, CheckpointFile, OutputState};
use std::sync::Arc;

const MAGIC: &[u8; 8] = b"EFSIFMU2";
const LAYOUT: u32 = 1;

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

fn mode_code(m: Mode) -> u8 {
    match m {
        Mode::Instantiated => 0,
        Mode::Initialization => 1,
        Mode::Step => 2,
        Mode::StepDiscarded => 3,
        Mode::Terminated => 4,
        Mode::Error => 5,
    }
}

fn mode_of(c: u8) -> Option<Mode> {
    Some(match c {
        0 => Mode::Instantiated,
        1 => Mode::Initialization,
        2 => Mode::Step,
        3 => Mode::StepDiscarded,
        4 => Mode::Terminated,
        5 => Mode::Error,
        _ => return None,
    })
}

struct Writer(Vec<u8>);

impl Writer {
    fn bytes(&mut self, b: &[u8]) {
        self.0.extend_from_slice(&(b.len() as u64).to_le_bytes());
        self.0.extend_from_slice(b);
    }
    fn f64(&mut self, x: f64) {
        self.0.extend_from_slice(&x.to_le_bytes());
    }
}

struct Reader<'a> {
    bytes: &'a [u8],
    at: usize,
}

impl Reader<'_> {
    fn take(&mut self, n: usize) -> Result<&[u8], String> {
        if n > self.bytes.len() - self.at {
            return Err(format!(
                "the serialised FMU state ends early (wanted {n} bytes at offset {} of {})",
                self.at,
                self.bytes.len()
            ));
        }
        let s = &self.bytes[self.at..self.at + n];
        self.at += n;
        Ok(s)
    }
    fn u8(&mut self) -> Result<u8, String> {
        Ok(self.take(1)?[0])
    }
    fn u32(&mut self) -> Result<u32, String> {
        Ok(u32::from_le_bytes(
            self.take(4)?.try_into().unwrap_or([0; 4]),
        ))
    }
    fn f64(&mut self) -> Result<f64, String> {
        Ok(f64::from_le_bytes(
            self.take(8)?.try_into().unwrap_or([0; 8]),
        ))
    }
    fn bytes(&mut self) -> Result<&[u8], String> {
        let n = u64::from_le_bytes(self.take(8)?.try_into().unwrap_or([0; 8]));
        let n = usize::try_from(n).map_err(|_| "a length beyond memory".to_string())?;
        self.take(n)
    }
    fn str(&mut self) -> Result<String, String> {
        String::from_utf8(self.bytes()?.to_vec()).map_err(|_| "a string is not UTF-8".into())
    }
}

impl FmuState {
    /// The serialised form (see the module docs); `token` is the FMU's instantiation token.
    pub fn serialize(&mut self, token: &str) -> &[u8] {
        if self.serialized.is_none() {
            let mut w = Writer(Vec::new());
            w.0.extend_from_slice(MAGIC);
            w.0.extend_from_slice(&LAYOUT.to_le_bytes());
            w.bytes(token.as_bytes());
            w.0.push(mode_code(self.mode));
            w.f64(self.start_time);
            w.f64(self.stop_time.unwrap_or(f64::NAN));
            let v = &self.values;
            w.f64(v.max_steps as f64);
            w.0.extend_from_slice(&(v.params.len() as u64).to_le_bytes());
            for p in &v.params {
                match p {
                    OverrideValue::Str(s) => {
                        w.0.push(1);
                        w.bytes(s.as_bytes());
                    }
                    OverrideValue::Int(i) => {
                        w.0.push(2);
                        w.0.extend_from_slice(&i.to_le_bytes());
                    }
                    OverrideValue::Float(x) => {
                        w.0.push(0);
                        w.f64(*x);
                    }
                    other => {
                        w.0.push(1);
                        w.bytes(other.to_string().as_bytes());
                    }
                }
            }
            w.0.extend_from_slice(&(v.inputs.len() as u64).to_le_bytes());
            for x in &v.inputs {
                w.f64(*x);
            }
            match &self.simulated {
                None => w.0.push(0),
                Some(Simulated::Live { snapshot, identity }) => {
                    w.0.push(1);
                    let c = Checkpoint {
                        efsi_version: env!("CARGO_PKG_VERSION").to_string(),
                        scene_path: SCENE_LABEL.into(),
                        scene_ron: identity.scene_ron.clone(),
                        overrides: Vec::new(),
                        law: identity.law.clone(),
                        outputs: OutputState::default(),
                        snapshot: (**snapshot).clone(),
                    };
                    w.bytes(&checkpoint::encode(&c));
                }
                Some(Simulated::Recorded { bytes, .. }) => {
                    w.0.push(1);
                    w.bytes(bytes);
                }
            }
            self.serialized = Some(w.0);
        }
        self.serialized.as_deref().unwrap_or_default()
    }

    /// A state from [`serialize`](Self::serialize)'s bytes; `token` is this FMU's
    /// instantiation token. The simulation part is decoded but fitted into a simulation only
    /// when the state is set.
    pub fn deserialize(bytes: &[u8], token: &str) -> Result<FmuState, String> {
        let what = "serialised FMU state";
        if bytes.len() < 12 || &bytes[..8] != MAGIC {
            return Err(format!(
                "not a serialised efsi FMU state (no {} header)",
                String::from_utf8_lossy(MAGIC)
            ));
        }
        let mut r = Reader { bytes, at: 8 };
        let layout = r.u32()?;
        if layout != LAYOUT {
            return Err(format!(
                "a {what} of layout {layout}; this FMU reads layout {LAYOUT}"
            ));
        }
        let theirs = r.str()?;
        if theirs != token {
            return Err(format!(
                "the {what} belongs to another build of the FMU (instantiation token {theirs}, this one {token})"
            ));
        }
        let mode = mode_of(r.u8()?).ok_or("an unknown mode in the state")?;
        let start_time = r.f64()?;
        let stop = r.f64()?;
        let stop_time = (!stop.is_nan()).then_some(stop);
        let max_steps = r.f64()? as i64;
        let count = |r: &mut Reader| -> Result<usize, String> {
            let n = u64::from_le_bytes(r.take(8)?.try_into().unwrap_or([0; 8]));
            usize::try_from(n)
                .ok()
                .filter(|&n| n <= bytes.len())
                .ok_or_else(|| format!("the {what} is damaged (a count of {n})"))
        };
        let mut params = Vec::new();
        for _ in 0..count(&mut r)? {
            params.push(match r.u8()? {
                0 => OverrideValue::Float(r.f64()?),
                1 => OverrideValue::Str(r.str()?),
                2 => {
                    OverrideValue::Int(i64::from_le_bytes(r.take(8)?.try_into().unwrap_or([0; 8])))
                }
                _ => return Err(format!("the {what} is damaged (a value tag)")),
            });
        }
        let mut inputs = Vec::new();
        for _ in 0..count(&mut r)? {
            inputs.push(r.f64()?);
        }
        let simulated = match r.u8()? {
            0 => None,
            1 => {
                let bytes = r.bytes()?.to_vec();
                let file = checkpoint::decode(&bytes, what).map_err(|e| e.to_string())?;
                Some(Simulated::Recorded {
                    file: Box::new(file),
                    bytes,
                })
            }
            _ => return Err(format!("the {what} is damaged (simulation tag)")),
        };
        if r.at != bytes.len() {
            return Err(format!(
                "the {what} has {} bytes after its end",
                bytes.len() - r.at
            ));
        }
        Ok(FmuState {
            mode,
            start_time,
            stop_time,
            values: Values {
                params,
                max_steps,
                inputs,
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
