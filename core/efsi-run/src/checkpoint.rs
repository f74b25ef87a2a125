//! Checkpoint files: a [`Snapshot`] on disk, with what a resumed run must check and continue.
//!
//! A **checkpoint file** ([`Checkpoint`], [`encode`], [`decode`]) is a snapshot (the
//! in-memory copy of a [`Simulation`](efsi_core::Simulation)'s evolving data, see [`efsi_core::snapshot`]) plus the
//! scene (canonical RON) and the overrides applied to its file ([`efsi_core::overrides`], applied
//! again on resume), the law library's identity ([`LawIdentity`]: name, ABI version,
//! parameter table, size and hash of the file), the run loop's output bookkeeping
//! ([`OutputState`]) and the efsi version. `efsi resume` refuses a checkpoint whose scene or law
//! differs from the current ones and says what differs.
//!
//! # File format (version [`FORMAT_VERSION`])
//!
//! A [`crate::binary`] file of magic [`MAGIC`]: the prefix (magic, version, body length,
//! checksum), then the body in postcard. The body is three serde structs, in order: the
//! header (efsi version, scene path, scene RON, the overrides applied to the scene file, law
//! identity), the output bookkeeping ([`OutputState`], ending with the run's identity) and the
//! snapshot (t, step, Δt_prev, last rate of change, velocity scale, then named arrays, named
//! scalars (the frame acceleration and the elastic energy), named stage data and the energy
//! guard's record, [`crate::guard`]). A change to any of them is a new [`FORMAT_VERSION`]; a
//! file of another version (versions 1–4 are the hand-written little-endian layout of earlier
//! efsi) is refused naming its version, never misread.
//!
//! Files are written atomically ([`crate::output::atomic`]): a reader or a resumed run sees
//! the previous complete checkpoint or the new complete one, never a torn one; a truncated or
//! corrupted file fails its length or checksum test with a clear message.

use crate::binary::{self, Format};
use efsi_core::Snapshot;
use efsi_core::error::EfsiError;
use efsi_core::overrides::Override;
use efsi_core::plugin_api::Laws;
use efsi_core::scene::Options;
use efsi_core::scene::Scene;
use efsi_core::scene::solid::SceneSolid;
use efsi_core::state::State;
use serde::{Deserialize, Serialize};
use std::borrow::Cow;
use std::path::{Path, PathBuf};

/// The first eight bytes of every checkpoint file.
pub const MAGIC: &[u8; 8] = b"EFSICKPT";
/// The version of the file layout this efsi reads and writes.
pub const FORMAT_VERSION: u32 = 5;
/// Where a run keeps its latest checkpoint, relative to its output folder.
pub const LATEST: &str = "checkpoint/latest.efsick";

/// What identifies the law library a scene uses, to refuse resuming with another one.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct LawIdentity {
    /// The name the scene gives (a shipped law's name or a library path).
    pub spec: String,
    /// The name the library declares (equal to `spec` for a built-in law).
    pub name: String,
    /// The ABI version the library was built for (0 for a built-in law).
    pub abi_version: u32,
    /// The library file resolved from `spec` (empty for a built-in law).
    pub library: String,
    /// Its size in bytes.
    pub bytes: u64,
    /// Its content hash ([`content_hash`]).
    pub hash: u64,
    /// Its parameter table, one line per parameter: name, unit, default, range.
    pub parameters: Vec<String>,
}

/// The identity of the law `scene` names (None without a solid law), by the law loader the
/// plugins put in the checked scene's `options` ([`Laws`]). The library is resolved as the
/// elastic stage resolves it (relative to the scene's folder, else the search path).
pub fn law_identity(scene: &Scene, options: &Options) -> Result<Option<LawIdentity>, EfsiError> {
    let dir = scene
        .source_dir
        .clone()
        .unwrap_or_else(|| PathBuf::from("."));
    let solid = scene
        .solid_spec()
        .map_err(|(field, message)| EfsiError::Config {
            path: dir.clone(),
            field,
            message,
        })?;
    let Some(spec) = solid.and_then(|s| s.law) else {
        return Ok(None);
    };
    let refuse = |message: String| EfsiError::Config {
        path: dir.clone(),
        field: "solid.law".into(),
        message,
    };
    let loader = Laws::of(options).ok_or_else(|| {
        refuse(format!(
            "the scene names the law `{}`, and no plugin of this simulation loads laws",
            spec.name
        ))
    })?;
    let info = loader.describe(&spec.name, &dir).map_err(refuse)?;
    let path = info.library;
    let bytes = std::fs::read(&path).map_err(|e| EfsiError::io(&path, e))?;
    Ok(Some(LawIdentity {
        spec: spec.name.clone(),
        name: info.name,
        abi_version: info.abi_version,
        library: path.display().to_string(),
        bytes: bytes.len() as u64,
        hash: content_hash(&bytes),
        parameters: info.parameters,
    }))
}

/// What differs between the law a checkpoint was written with (`old`) and the current one.
pub fn law_differences(old: &Option<LawIdentity>, new: &Option<LawIdentity>) -> Vec<String> {
    match (old, new) {
        (None, None) => Vec::new(),
        (Some(o), None) => vec![format!(
            "the checkpoint used the law `{}`; the scene now has none",
            o.name
        )],
        (None, Some(n)) => vec![format!(
            "the checkpoint used no law; the scene now uses `{}`",
            n.name
        )],
        (Some(o), Some(n)) => {
            let mut d = Vec::new();
            if o.name != n.name {
                d.push(format!("law name `{}` → `{}`", o.name, n.name));
            }
            if o.abi_version != n.abi_version {
                d.push(format!(
                    "law `{}`: ABI version {} → {}",
                    n.name, o.abi_version, n.abi_version
                ));
            }
            if o.parameters != n.parameters {
                d.push(format!(
                    "law `{}`: parameter table [{}] → [{}]",
                    n.name,
                    o.parameters.join("; "),
                    n.parameters.join("; ")
                ));
            }
            if (o.bytes, o.hash) != (n.bytes, n.hash) {
                d.push(format!(
                    "law `{}`: the library changed: {} ({} bytes, hash {:016x}) → {} ({} bytes, hash {:016x})",
                    n.name, o.library, o.bytes, o.hash, n.library, n.bytes, n.hash
                ));
            }
            d
        }
    }
}

/// The settings that differ between two scenes, as `path: old → new` (at most 20).
pub fn scene_differences(old: &Scene, new: &Scene) -> Vec<String> {
    fn walk(path: &str, a: &serde_json::Value, b: &serde_json::Value, out: &mut Vec<String>) {
        use serde_json::Value;
        if out.len() >= 20 || a == b {
            return;
        }
        let join = |k: &str| {
            if path.is_empty() {
                k.to_string()
            } else {
                format!("{path}.{k}")
            }
        };
        match (a, b) {
            (Value::Object(x), Value::Object(y)) => {
                for (k, va) in x {
                    walk(&join(k), va, y.get(k).unwrap_or(&Value::Null), out);
                }
                for (k, vb) in y {
                    if !x.contains_key(k) {
                        walk(&join(k), &Value::Null, vb, out);
                    }
                }
            }
            (Value::Array(x), Value::Array(y)) if x.len() == y.len() => {
                for (k, (va, vb)) in x.iter().zip(y).enumerate() {
                    walk(&format!("{path}[{k}]"), va, vb, out);
                }
            }
            _ => out.push(format!("{path}: {a} → {b}")),
        }
    }
    let mut a = serde_json::to_value(old).unwrap_or_default();
    let mut b = serde_json::to_value(new).unwrap_or_default();
    // The output sections are RON text in the scenes: compared setting by setting.
    a["output"] = crate::output::spec::json(old);
    b["output"] = crate::output::spec::json(new);
    a["solid"] = efsi_core::scene::solid::json(old);
    b["solid"] = efsi_core::scene::solid::json(new);
    // A stage's numerics section is RON text in the scene; where both scenes hold it checked
    // (its settings in force), compare it setting by setting.
    let old_sections: std::collections::BTreeMap<_, _> = old.numerics.sections_json().collect();
    for (name, nb) in new.numerics.sections_json() {
        if let Some(na) = old_sections.get(name) {
            a["numerics"][name] = (*na).clone();
            b["numerics"][name] = nb.clone();
        }
    }
    let mut out = Vec::new();
    walk("", &a, &b, &mut out);
    out
}

/// The run loop's output bookkeeping at a checkpoint: what has been written, and what is due
/// next, so that a resumed run appends to the same files without duplicating or losing rows.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct OutputState {
    /// VTK outputs due so far (the next is at `vtk_count × vtk_every`).
    pub vtk_count: u64,
    /// Probe samples due so far.
    pub probe_count: u64,
    /// Length of `probes.csv` in bytes (a resumed run truncates it to this).
    pub probe_bytes: u64,
    /// The `.pvd` collections' entries: time and file relative to the output folder — the VTK
    /// series' (`fields/…`), then each plane slice's (`slices/<name>_<step>.vtr`).
    pub pvd: Vec<(f64, String)>,
    /// For each profile of the scene, the output times still to come.
    pub profile_times: Vec<Vec<f64>>,
    /// The checkpoint interval of the run (simulated time), if any.
    pub checkpoint_every: Option<f64>,
    /// Checkpoints due so far.
    pub checkpoint_count: u64,
    /// The identity of the run that wrote the outputs (also in its `run.json`): a resume
    /// refuses a checkpoint whose run is not the one of the folder it is resumed in. Empty
    /// where no output folder belongs to the snapshot (an FMU's state).
    pub run_id: String,
    /// XXH3 (64-bit) of the first `probe_bytes` bytes of `probes.csv`: binds the checkpoint to
    /// the folder's own files, so that a checkpoint put in another run's folder (its `run.json`
    /// edited to match) is refused (0 where there is no folder).
    pub probes_hash: u64,
}

/// A checkpoint: a [`Snapshot`] and what a resumed run checks and continues.
#[derive(Clone, Debug)]
pub struct Checkpoint {
    /// The efsi version that wrote it.
    pub efsi_version: String,
    /// The scene file of the run (absolute when it could be made so).
    pub scene_path: PathBuf,
    /// The scene as run, in canonical RON ([`Scene::to_ron`]).
    pub scene_ron: String,
    /// The overrides applied to the scene file ([`Scene::overrides`]), applied again on resume.
    pub overrides: Vec<Override>,
    /// The law library in use, if the scene has a solid law.
    pub law: Option<LawIdentity>,
    /// Output bookkeeping of the run loop.
    pub outputs: OutputState,
    /// The simulation's evolving data.
    pub snapshot: Snapshot,
}

/// The values recorded under `name` in `arrays`.
fn recorded(arrays: &[(String, Vec<f64>)], name: &str) -> Option<Vec<f64>> {
    let found = arrays.iter().find(|(n, _)| n == name);
    found.map(|(_, d)| d.clone())
}

/// Raw content of a checkpoint file's snapshot section: named arrays, to be fitted into a
/// simulation's own [`Snapshot`] ([`SnapshotRecord::into_snapshot`]).
#[derive(Clone, Debug)]
pub struct SnapshotRecord {
    t: f64,
    step: u64,
    dt_prev: f64,
    last_change: f64,
    velocity_scale: f64,
    arrays: Vec<(String, Vec<f64>)>,
    scalars: Vec<(String, f64)>,
    stages: Vec<(String, Vec<f64>)>,
    guard: Vec<f64>,
}

impl SnapshotRecord {
    /// Simulated time recorded.
    pub fn t(&self) -> f64 {
        self.t
    }

    /// Step count recorded.
    pub fn step(&self) -> u64 {
        self.step
    }

    /// Fill `template` (a snapshot of the simulation it will be restored into, e.g. from
    /// [`Simulation::snapshot`](efsi_core::Simulation::snapshot)) with the recorded values. Every array of the template must be
    /// recorded with the same length, and no other; the error names the first that is not.
    pub fn into_snapshot(self, mut template: Snapshot, what: &str) -> Result<Snapshot, EfsiError> {
        let fail = |message: String| EfsiError::Checkpoint {
            what: what.to_string(),
            message,
        };
        let arrays = &self.arrays;
        template
            .state
            .reshape_resources(&|name| recorded(arrays, name))
            .map_err(fail)?;
        let mut theirs = self.arrays.into_iter();
        for (name, field) in template.state.arrays_mut() {
            let Some((rname, data)) = theirs.next() else {
                return Err(fail(format!("the array `{name}` is missing")));
            };
            if rname != name {
                return Err(fail(format!(
                    "expected the array `{name}`, found `{rname}`"
                )));
            }
            if data.len() != field.data().len() {
                return Err(fail(format!(
                    "the array `{name}` has {} values, this grid needs {}",
                    data.len(),
                    field.data().len()
                )));
            }
            field.data_mut().copy_from_slice(&data);
        }
        if let Some((extra, _)) = theirs.next() {
            return Err(fail(format!(
                "the array `{extra}` is recorded but this simulation has no such field"
            )));
        }
        for (name, v) in template.state.scalars_mut() {
            let recorded = self
                .scalars
                .iter()
                .find(|(n, _)| n == name)
                .map(|(_, x)| *x);
            let Some(x) = recorded.or_else(|| State::scalar_default(name)) else {
                return Err(fail(format!("the value `{name}` is missing")));
            };
            *v = x;
        }
        template.state.t = self.t;
        template.state.step = self.step;
        template.state.dt_prev = self.dt_prev;
        template.last_change = self.last_change;
        template.velocity_scale = self.velocity_scale;
        template.stages = self.stages;
        // The record of the energy guard, the one step check efsi-run adds.
        if let Some((_, record)) = template
            .checks
            .iter_mut()
            .find(|(n, _)| *n == crate::guard::NAME)
        {
            *record = self.guard;
        }
        Ok(template)
    }
}

/// A decoded checkpoint file: everything but the snapshot, which must be fitted into a
/// simulation ([`SnapshotRecord::into_snapshot`]).
#[derive(Clone, Debug)]
pub struct CheckpointFile {
    /// The efsi version that wrote it.
    pub efsi_version: String,
    /// The scene file of the run.
    pub scene_path: PathBuf,
    /// The scene as run, in canonical RON.
    pub scene_ron: String,
    /// The overrides applied to the scene file.
    pub overrides: Vec<Override>,
    /// The law library in use.
    pub law: Option<LawIdentity>,
    /// Output bookkeeping of the run loop.
    pub outputs: OutputState,
    /// The snapshot's raw content.
    pub record: SnapshotRecord,
}

impl Checkpoint {
    /// Write the checkpoint to `path` atomically (temporary name, then rename).
    pub fn write(&self, path: &Path) -> Result<(), EfsiError> {
        let bytes = encode(self);
        if let Some(dir) = path.parent() {
            std::fs::create_dir_all(dir).map_err(|e| EfsiError::io(dir, e))?;
        }
        crate::output::atomic::write_bytes_atomically(path, &bytes)
            .map_err(|e| EfsiError::io(path, e))
    }
}

impl CheckpointFile {
    /// Read and decode the checkpoint file at `path`.
    pub fn read(path: &Path) -> Result<CheckpointFile, EfsiError> {
        let bytes = std::fs::read(path).map_err(|e| EfsiError::io(path, e))?;
        decode(&bytes, &path.display().to_string())
    }

    /// The scene recorded, parsed (with `scene_path` for messages and its folder for laws).
    pub fn scene(&self) -> Result<Scene, EfsiError> {
        let mut scene = Scene::from_str_at(&self.scene_ron, &self.scene_path)?;
        scene.source_dir = self.scene_path.parent().map(Path::to_path_buf);
        Ok(scene)
    }
}

/// The checkpoint file kind of [`crate::binary`]: magic [`MAGIC`], version [`FORMAT_VERSION`].
pub const FORMAT: Format = Format {
    magic: MAGIC,
    version: FORMAT_VERSION,
    kind: "checkpoint",
};

/// The 64-bit content hash identifying a file (XXH3), e.g. a law library in [`LawIdentity`].
pub fn content_hash(bytes: &[u8]) -> u64 {
    xxhash_rust::xxh3::xxh3_64(bytes)
}

/// The body of a checkpoint file (format [`FORMAT_VERSION`]): the one definition of its
/// layout, written from a [`Checkpoint`] by reference and read into a [`CheckpointFile`].
#[derive(Serialize, Deserialize)]
struct Body<'a> {
    header: Header<'a>,
    outputs: Cow<'a, OutputState>,
    snapshot: SnapshotBody<'a>,
}

/// What a resumed run checks before it continues: who wrote the file, the scene and the law.
#[derive(Serialize, Deserialize)]
struct Header<'a> {
    efsi_version: Cow<'a, str>,
    scene_path: Cow<'a, str>,
    scene_ron: Cow<'a, str>,
    overrides: Cow<'a, [Override]>,
    law: Cow<'a, Option<LawIdentity>>,
}

/// The snapshot's content, by name: fitted into a simulation's own snapshot on resume.
#[derive(Serialize, Deserialize)]
struct SnapshotBody<'a> {
    t: f64,
    step: u64,
    dt_prev: f64,
    last_change: f64,
    velocity_scale: f64,
    arrays: Vec<(Cow<'a, str>, Cow<'a, [f64]>)>,
    scalars: Vec<(Cow<'a, str>, f64)>,
    stages: Cow<'a, [(String, Vec<f64>)]>,
    /// The energy guard's record ([`crate::guard`]), empty when the run has none.
    guard: Cow<'a, [f64]>,
}

/// The bytes of a checkpoint file (see the module docs for the layout).
pub fn encode(c: &Checkpoint) -> Vec<u8> {
    with_body(c, |body| binary::encode(&FORMAT, body))
}

/// The length of [`encode`]'s bytes, counted without making them (what the run keeps room on
/// disk for).
pub fn encoded_len(c: &Checkpoint) -> usize {
    with_body(c, |body| binary::encoded_len(body))
}

/// The length of [`encode`]'s bytes for the checkpoint of `sim`'s current state with the
/// law `law` and the output bookkeeping `outputs`, counted from the simulation itself: no
/// snapshot is made (what a run keeps room on disk for). Each stage's data is counted by its
/// length ([`efsi_core::Stage::saved_len`]): postcard writes a list of numbers as its length
/// (a varint) and eight bytes per number.
pub fn encoded_len_of(
    sim: &efsi_core::simulation::Simulation,
    law: &Option<LawIdentity>,
    outputs: &OutputState,
) -> usize {
    let lens = sim.pipeline().saved_lens();
    let stages: Vec<(String, Vec<f64>)> = lens
        .iter()
        .map(|(name, _)| (name.to_string(), Vec::new()))
        .collect();
    let mut guard = Vec::new();
    if let Some(c) = sim.checks().iter().find(|c| c.name() == crate::guard::NAME) {
        c.save_into(&mut guard);
    }
    let header = Header {
        efsi_version: Cow::Borrowed(env!("CARGO_PKG_VERSION")),
        scene_path: Cow::Owned(
            std::path::absolute(&sim.scene_path)
                .unwrap_or(sim.scene_path.clone())
                .display()
                .to_string(),
        ),
        scene_ron: Cow::Owned(sim.scene.to_ron()),
        overrides: Cow::Borrowed(&sim.scene.overrides),
        law: Cow::Borrowed(law),
    };
    // The stepping scalars are fixed-width: any value has their length.
    let view = SnapshotView {
        state: &sim.state,
        last_change: 0.0,
        velocity_scale: 0.0,
        stages: &stages,
        guard: &guard,
    };
    let empty = binary::encoded_len(&body(header, outputs, &view));
    let data: usize = lens.iter().map(|&(_, n)| 8 * n + varint_len(n) - 1).sum();
    empty + data
}

/// The bytes of `n` as a postcard varint (seven bits a byte).
fn varint_len(n: usize) -> usize {
    (usize::BITS - n.leading_zeros()).div_ceil(7).max(1) as usize
}

/// What the snapshot section of a checkpoint is made from, borrowed.
struct SnapshotView<'a> {
    state: &'a State,
    last_change: f64,
    velocity_scale: f64,
    stages: &'a [(String, Vec<f64>)],
    guard: &'a [f64],
}

/// The body of a checkpoint file of `header`, `outputs` and the snapshot `s`, borrowing its
/// arrays.
fn body<'a>(header: Header<'a>, outputs: &'a OutputState, s: &SnapshotView<'a>) -> Body<'a> {
    Body {
        header,
        outputs: Cow::Borrowed(outputs),
        snapshot: SnapshotBody {
            t: s.state.t,
            step: s.state.step,
            dt_prev: s.state.dt_prev,
            last_change: s.last_change,
            velocity_scale: s.velocity_scale,
            arrays: s
                .state
                .arrays()
                .into_iter()
                .map(|(name, f)| (Cow::Owned(name), Cow::Borrowed(f.data())))
                .collect(),
            scalars: s
                .state
                .scalars()
                .into_iter()
                .map(|(name, v)| (Cow::Borrowed(name), v))
                .collect(),
            stages: Cow::Borrowed(s.stages),
            guard: Cow::Borrowed(s.guard),
        },
    }
}

/// `f` of the body of `c`'s file, which borrows its arrays.
fn with_body<R>(c: &Checkpoint, f: impl FnOnce(&Body) -> R) -> R {
    let s = &c.snapshot;
    let guard = s.checks.iter().find(|(n, _)| *n == crate::guard::NAME);
    let header = Header {
        efsi_version: Cow::Borrowed(&c.efsi_version),
        scene_path: Cow::Owned(c.scene_path.display().to_string()),
        scene_ron: Cow::Borrowed(&c.scene_ron),
        overrides: Cow::Borrowed(&c.overrides),
        law: Cow::Borrowed(&c.law),
    };
    let view = SnapshotView {
        state: &s.state,
        last_change: s.last_change,
        velocity_scale: s.velocity_scale,
        stages: &s.stages,
        guard: guard.map_or(&[], |(_, r)| r.as_slice()),
    };
    f(&body(header, &c.outputs, &view))
}

/// Decode checkpoint bytes; `what` (the file) names it in errors.
pub fn decode(bytes: &[u8], what: &str) -> Result<CheckpointFile, EfsiError> {
    let body: Body = binary::decode(bytes, &FORMAT).map_err(|mut message| {
        if binary::version_of(bytes, &FORMAT).is_some_and(|v| v < FORMAT_VERSION) {
            message.push_str(
                "; finish that run with the efsi that wrote the checkpoint, or start it again",
            );
        }
        EfsiError::Checkpoint {
            what: what.to_string(),
            message,
        }
    })?;
    let (h, s) = (body.header, body.snapshot);
    Ok(CheckpointFile {
        efsi_version: h.efsi_version.into_owned(),
        scene_path: PathBuf::from(h.scene_path.into_owned()),
        scene_ron: h.scene_ron.into_owned(),
        overrides: h.overrides.into_owned(),
        law: h.law.into_owned(),
        outputs: body.outputs.into_owned(),
        record: SnapshotRecord {
            t: s.t,
            step: s.step,
            dt_prev: s.dt_prev,
            last_change: s.last_change,
            velocity_scale: s.velocity_scale,
            arrays: s
                .arrays
                .into_iter()
                .map(|(n, d)| (n.into_owned(), d.into_owned()))
                .collect(),
            scalars: s
                .scalars
                .into_iter()
                .map(|(n, x)| (n.into_owned(), x))
                .collect(),
            stages: s.stages.into_owned(),
            guard: s.guard.into_owned(),
        },
    })
}

/// Check that a checkpoint may resume with `scene` and the law it names now: the scene must
/// equal the recorded one except for a later `time.end`, and the law library must be the
/// same. The error lists what differs.
///
/// `scene`'s stages' sections are compared with the recorded ones setting by setting once both
/// are checked by `plugins` (the recorded scene here; `scene` by its caller).
pub fn check_resumable(
    file: &CheckpointFile,
    scene: &Scene,
    what: &str,
    plugins: &[&dyn efsi_core::StagePlugin],
) -> Result<(), EfsiError> {
    let mut recorded = file.scene()?;
    // The same plugins check both scenes: the recorded one's law loader is `scene`'s too.
    let options = recorded.check_options(&file.scene_path, plugins)?;
    let mut diffs = Vec::new();
    // `time.end` alone may change, to a time after the checkpoint's: a stopped or finished
    // run continues to a later end (no step before the checkpoint depends on it).
    if scene.time.end != recorded.time.end {
        if scene.time.end <= file.record.t {
            diffs.push(format!(
                "scene: time.end: {} is not after the checkpoint's t = {:.6e} (time.end may only \
                 move past it)",
                scene.time.end, file.record.t
            ));
        }
        recorded.time.end = scene.time.end;
    }
    diffs.extend(
        scene_differences(&recorded, scene)
            .into_iter()
            .map(|d| format!("scene: {d}")),
    );
    if diffs.is_empty() {
        diffs.extend(law_differences(&file.law, &law_identity(scene, &options)?));
    }
    if diffs.is_empty() {
        return Ok(());
    }
    Err(EfsiError::Checkpoint {
        what: what.to_string(),
        message: format!(
            "cannot resume: the run has changed since the checkpoint (step {}, t = {:.6e}):\n  {}",
            file.record.step,
            file.record.t,
            diffs.join("\n  ")
        ),
    })
}
