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
//! Little-endian throughout: the 8-byte magic [`MAGIC`], `u32` format version, `u64` payload
//! length, `u64` checksum of the payload (64-bit FNV-1a over 8-byte words), then the payload.
//! In the payload a string is a `u64` byte length and UTF-8 bytes, an array of `f64` a `u64`
//! count and the raw values, an optional `f64` is NaN when absent. Sections, in order: header
//! (efsi version, scene path, scene RON, the overrides applied to the scene file as RON, law
//! identity), output bookkeeping (ending with the run's identity and the hash of the
//! `probes.csv` it continues), the snapshot
//! (t, step, Δt_prev, last rate of change, velocity scale, then named arrays, named scalars (the
//! frame acceleration and the elastic energy), then named stage
//! data, then the energy guard's record, [`crate::guard`]). A 128² cavity checkpoints in ≈ 0.7 MB.
//!
//! Files are written atomically ([`crate::output::atomic`]): a reader or a resumed run sees
//! the previous complete checkpoint or the new complete one, never a torn one; a truncated or
//! corrupted file fails its length or checksum test with a clear message.

use efsi_core::Snapshot;
use efsi_core::error::EfsiError;
use efsi_core::overrides::Override;
use efsi_core::scene::Scene;
use efsi_core::state::State;
use efsi_laws_host::loader::{describe, resolve_law};
use efsi_stages::solid::SceneSolid;
use std::path::{Path, PathBuf};

/// The first eight bytes of every checkpoint file.
pub const MAGIC: &[u8; 8] = b"EFSICKPT";
/// The version of the file layout this efsi reads and writes.
pub const FORMAT_VERSION: u32 = 5;
/// Where a run keeps its latest checkpoint, relative to its output folder.
pub const LATEST: &str = "checkpoint/latest.efsick";

/// What identifies the law library a scene uses, to refuse resuming with another one.
#[derive(Clone, Debug, PartialEq)]
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
    /// 64-bit FNV-1a hash of its content.
    pub hash: u64,
    /// Its parameter table, one line per parameter: name, unit, default, range.
    pub parameters: Vec<String>,
}

/// The identity of the law `scene` names (None without a solid law). The library is resolved
/// as the elastic stage resolves it (relative to the scene's folder, else the search path).
pub fn law_identity(scene: &Scene) -> Result<Option<LawIdentity>, EfsiError> {
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
    let refuse = |e: efsi_laws_host::LawError| EfsiError::Config {
        path: dir.clone(),
        field: "solid.law".into(),
        message: e.to_string(),
    };
    let path = resolve_law(&spec.name, &dir).map_err(refuse)?;
    let info = describe(&path).map_err(refuse)?;
    let bytes = std::fs::read(&path).map_err(|e| EfsiError::io(&path, e))?;
    Ok(Some(LawIdentity {
        spec: spec.name.clone(),
        name: info.name,
        abi_version: info.abi_version,
        library: path.display().to_string(),
        bytes: bytes.len() as u64,
        hash: fnv1a(&bytes),
        parameters: info
            .parameters
            .iter()
            .map(|p| {
                format!(
                    "{} [{}] default {:e} range {}",
                    p.name,
                    p.unit,
                    p.default,
                    p.range_text()
                )
            })
            .collect(),
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
    a["solid"] = efsi_stages::solid::json(old);
    b["solid"] = efsi_stages::solid::json(new);
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
#[derive(Clone, Debug, Default, PartialEq)]
pub struct OutputState {
    /// VTK outputs due so far (the next is at `vtk_count × vtk_every`).
    pub vtk_count: u64,
    /// Probe samples due so far.
    pub probe_count: u64,
    /// Length of `probes.csv` in bytes (a resumed run truncates it to this).
    pub probe_bytes: u64,
    /// The `.pvd` collection's entries: time and file relative to the output folder.
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
    /// 64-bit FNV-1a ([`fnv1a_bytes`]) of the first `probe_bytes` bytes of `probes.csv`: binds
    /// the checkpoint to the folder's own files, so that a checkpoint put in another run's
    /// folder (its `run.json` edited to match) is refused (0 where there is no folder).
    pub probes_hash: u64,
}

/// 64-bit FNV-1a of `bytes` continued from `h` (start from [`FNV_OFFSET`]), one byte at a time:
/// a hash that can be extended as a file grows ([`OutputState::probes_hash`]).
pub fn fnv1a_bytes(mut h: u64, bytes: &[u8]) -> u64 {
    for &b in bytes {
        h = (h ^ u64::from(b)).wrapping_mul(0x0000_0100_0000_01b3);
    }
    h
}

/// The starting value of [`fnv1a_bytes`].
pub const FNV_OFFSET: u64 = 0xcbf2_9ce4_8422_2325;

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

/// 64-bit FNV-1a over 8-byte little-endian words (the tail zero-padded), then the length.
pub fn fnv1a(bytes: &[u8]) -> u64 {
    const PRIME: u64 = 0x0000_0100_0000_01b3;
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    let mut chunks = bytes.chunks_exact(8);
    for c in &mut chunks {
        h = (h ^ u64::from_le_bytes(c.try_into().unwrap_or([0; 8]))).wrapping_mul(PRIME);
    }
    let rest = chunks.remainder();
    if !rest.is_empty() {
        let mut w = [0u8; 8];
        w[..rest.len()].copy_from_slice(rest);
        h = (h ^ u64::from_le_bytes(w)).wrapping_mul(PRIME);
    }
    (h ^ bytes.len() as u64).wrapping_mul(PRIME)
}

struct Writer(Vec<u8>);

impl Writer {
    fn u32(&mut self, x: u32) {
        self.0.extend_from_slice(&x.to_le_bytes());
    }
    fn u64(&mut self, x: u64) {
        self.0.extend_from_slice(&x.to_le_bytes());
    }
    fn f64(&mut self, x: f64) {
        self.0.extend_from_slice(&x.to_le_bytes());
    }
    fn str(&mut self, s: &str) {
        self.u64(s.len() as u64);
        self.0.extend_from_slice(s.as_bytes());
    }
    fn f64s(&mut self, xs: &[f64]) {
        self.u64(xs.len() as u64);
        self.0.reserve(8 * xs.len());
        for x in xs {
            self.0.extend_from_slice(&x.to_le_bytes());
        }
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
                "the file ends early (wanted {n} bytes at offset {})",
                self.at
            ));
        }
        let s = &self.bytes[self.at..self.at + n];
        self.at += n;
        Ok(s)
    }
    fn u32(&mut self) -> Result<u32, String> {
        Ok(u32::from_le_bytes(
            self.take(4)?.try_into().unwrap_or([0; 4]),
        ))
    }
    fn u64(&mut self) -> Result<u64, String> {
        Ok(u64::from_le_bytes(
            self.take(8)?.try_into().unwrap_or([0; 8]),
        ))
    }
    fn f64(&mut self) -> Result<f64, String> {
        Ok(f64::from_bits(self.u64()?))
    }
    fn len(&mut self, unit: usize) -> Result<usize, String> {
        let n = self.u64()?;
        let left = (self.bytes.len() - self.at) / unit;
        if n > left as u64 {
            return Err(format!(
                "a length of {n} at offset {} exceeds the rest of the file",
                self.at - 8
            ));
        }
        Ok(n as usize)
    }
    fn str(&mut self) -> Result<String, String> {
        let n = self.len(1)?;
        String::from_utf8(self.take(n)?.to_vec())
            .map_err(|_| format!("invalid UTF-8 in a string at offset {}", self.at - n))
    }
    fn f64s(&mut self) -> Result<Vec<f64>, String> {
        let n = self.len(8)?;
        Ok(self
            .take(8 * n)?
            .chunks_exact(8)
            .map(|c| f64::from_le_bytes(c.try_into().unwrap_or([0; 8])))
            .collect())
    }
}

fn opt(x: Option<f64>) -> f64 {
    x.unwrap_or(f64::NAN)
}

fn unopt(x: f64) -> Option<f64> {
    (!x.is_nan()).then_some(x)
}

/// The bytes of a checkpoint file (see the module docs for the layout).
pub fn encode(c: &Checkpoint) -> Vec<u8> {
    let s = &c.snapshot;
    let mut w = Writer(Vec::with_capacity(4096 + s.size_bytes()));
    w.str(&c.efsi_version);
    w.str(&c.scene_path.display().to_string());
    w.str(&c.scene_ron);
    w.str(&ron::to_string(&c.overrides).unwrap_or_default());
    match &c.law {
        None => w.u32(0),
        Some(l) => {
            w.u32(1);
            w.str(&l.spec);
            w.str(&l.name);
            w.u32(l.abi_version);
            w.str(&l.library);
            w.u64(l.bytes);
            w.u64(l.hash);
            w.u64(l.parameters.len() as u64);
            for p in &l.parameters {
                w.str(p);
            }
        }
    }
    let o = &c.outputs;
    w.u64(o.vtk_count);
    w.u64(o.probe_count);
    w.u64(o.probe_bytes);
    w.u64(o.pvd.len() as u64);
    for (t, f) in &o.pvd {
        w.f64(*t);
        w.str(f);
    }
    w.u64(o.profile_times.len() as u64);
    for times in &o.profile_times {
        w.f64s(times);
    }
    w.f64(opt(o.checkpoint_every));
    w.u64(o.checkpoint_count);
    w.str(&o.run_id);
    w.u64(o.probes_hash);
    w.f64(s.state.t);
    w.u64(s.state.step);
    w.f64(s.state.dt_prev);
    w.f64(s.last_change);
    w.f64(s.velocity_scale);
    let arrays = s.state.arrays();
    w.u64(arrays.len() as u64);
    for (name, f) in arrays {
        w.str(&name);
        w.f64s(f.data());
    }
    let scalars = s.state.scalars();
    w.u64(scalars.len() as u64);
    for (name, v) in scalars {
        w.str(name);
        w.f64(v);
    }
    w.u64(s.stages.len() as u64);
    for (name, data) in &s.stages {
        w.str(name);
        w.f64s(data);
    }
    let guard = s.checks.iter().find(|(n, _)| *n == crate::guard::NAME);
    w.f64s(guard.map_or(&[], |(_, r)| r.as_slice()));
    let payload = w.0;
    let mut out = Vec::with_capacity(28 + payload.len());
    out.extend_from_slice(MAGIC);
    out.extend_from_slice(&FORMAT_VERSION.to_le_bytes());
    out.extend_from_slice(&(payload.len() as u64).to_le_bytes());
    out.extend_from_slice(&fnv1a(&payload).to_le_bytes());
    out.extend_from_slice(&payload);
    out
}

/// Decode checkpoint bytes; `what` (the file) names it in errors.
pub fn decode(bytes: &[u8], what: &str) -> Result<CheckpointFile, EfsiError> {
    let fail = |message: String| EfsiError::Checkpoint {
        what: what.to_string(),
        message,
    };
    if bytes.len() < 28 || &bytes[..8] != MAGIC {
        return Err(fail("not an efsi checkpoint (no EFSICKPT header)".into()));
    }
    let version = u32::from_le_bytes(bytes[8..12].try_into().unwrap_or([0; 4]));
    if version != FORMAT_VERSION {
        return Err(fail(format!(
            "checkpoint format version {version}; this efsi reads version {FORMAT_VERSION}"
        )));
    }
    let len = u64::from_le_bytes(bytes[12..20].try_into().unwrap_or([0; 8]));
    let sum = u64::from_le_bytes(bytes[20..28].try_into().unwrap_or([0; 8]));
    let payload = &bytes[28..];
    if payload.len() as u64 != len {
        return Err(fail(format!(
            "truncated or padded: the header announces {len} bytes of data, the file has {}",
            payload.len()
        )));
    }
    if fnv1a(payload) != sum {
        return Err(fail("corrupted: the checksum does not match".into()));
    }
    let mut r = Reader {
        bytes: payload,
        at: 0,
    };
    (|| -> Result<CheckpointFile, String> {
        let efsi_version = r.str()?;
        let scene_path = PathBuf::from(r.str()?);
        let scene_ron = r.str()?;
        let overrides = ron::from_str(&r.str()?)
            .map_err(|e| format!("the recorded overrides cannot be read: {e}"))?;
        let law = match r.u32()? {
            0 => None,
            _ => Some(LawIdentity {
                spec: r.str()?,
                name: r.str()?,
                abi_version: r.u32()?,
                library: r.str()?,
                bytes: r.u64()?,
                hash: r.u64()?,
                parameters: (0..r.len(8)?).map(|_| r.str()).collect::<Result<_, _>>()?,
            }),
        };
        let vtk_count = r.u64()?;
        let probe_count = r.u64()?;
        let probe_bytes = r.u64()?;
        let pvd = (0..r.len(16)?)
            .map(|_| Ok((r.f64()?, r.str()?)))
            .collect::<Result<_, String>>()?;
        let profile_times = (0..r.len(8)?).map(|_| r.f64s()).collect::<Result<_, _>>()?;
        let outputs = OutputState {
            vtk_count,
            probe_count,
            probe_bytes,
            pvd,
            profile_times,
            checkpoint_every: unopt(r.f64()?),
            checkpoint_count: r.u64()?,
            run_id: r.str()?,
            probes_hash: r.u64()?,
        };
        let (t, step, dt_prev, last_change, velocity_scale) =
            (r.f64()?, r.u64()?, r.f64()?, r.f64()?, r.f64()?);
        let arrays = (0..r.len(16)?)
            .map(|_| Ok((r.str()?, r.f64s()?)))
            .collect::<Result<_, String>>()?;
        let scalars = (0..r.len(16)?)
            .map(|_| Ok((r.str()?, r.f64()?)))
            .collect::<Result<_, String>>()?;
        let stages = (0..r.len(16)?)
            .map(|_| Ok((r.str()?, r.f64s()?)))
            .collect::<Result<_, String>>()?;
        let guard = r.f64s()?;
        if r.at != payload.len() {
            return Err(format!(
                "{} unexpected bytes after the data",
                payload.len() - r.at
            ));
        }
        Ok(CheckpointFile {
            efsi_version,
            scene_path,
            scene_ron,
            overrides,
            law,
            outputs,
            record: SnapshotRecord {
                t,
                step,
                dt_prev,
                last_change,
                velocity_scale,
                arrays,
                scalars,
                stages,
                guard,
            },
        })
    })()
    .map_err(fail)
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
    recorded.check_options(&file.scene_path, plugins)?;
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
        diffs.extend(law_differences(&file.law, &law_identity(scene)?));
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
