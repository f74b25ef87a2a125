//! Loading constitutive laws from plugin libraries.
//!
//! A law plugin is a dynamic library speaking the C ABI of `efsi-law-abi` (version
//! [`ABI_VERSION`]): it exports `efsi_law_descriptor`, which returns the law's name, parameter
//! table (name, unit, default, allowed range) and `create` / `destroy` / `evaluate` functions.
//! Laws written in Rust use `efsi-law-sdk`; the shipped ones live in `plugins/laws/`.
//!
//! [`load_law`] turns the law a scene names (its name and parameter values) into a
//! [`LoadedLaw`] (a [`ConstitutiveLaw`]):
//!
//! 1. **Resolve** the name: a name with a path separator or ending in `.so`/`.dylib`/`.dll` is a
//!    library path (relative to the scene's folder); any other name `X` is a shipped law, the file
//!    `libefsi_law_X.so` looked up in [`search_dirs`]: `$EFSI_LAW_PATH` (a `:`-separated list),
//!    the running executable's folder, its parent and its `deps` subfolder, then `target/release`
//!    and `target/debug` of the workspace efsi was built from.
//! 2. **Open** it and check it: a library, with the entry symbol, built for this ABI version, with
//!    the descriptor size this efsi expects, and a well-formed parameter table.
//! 3. **Parameters**: every scene parameter must be declared (else the known ones are listed),
//!    finite and in its range (name, value, range and unit in the message); the others take their
//!    defaults.
//! 4. **Create** the instance; a failure or panic inside the plugin comes back with its message.
//! 5. **Check the tangent** against central finite differences of the stress ([`check_tangent`],
//!    tolerance [`FD_TANGENT_TOLERANCE`]) and refuse a law whose tangent is wrong.
//!
//! Evaluation is one plugin call per batch of cells; a status other than success, a panic in the
//! plugin, or a non-finite output becomes a [`LawError`] naming the law (and the first bad cell).

use crate::{ConstitutiveLaw, LawError, Sym, Tangent};
use efsi_law_abi::{
    ABI_VERSION, CRATE_VERSION, DESCRIPTOR_SIZE, DestroyFn, ENTRY_SYMBOL, ENTRY_SYMBOL_NAME,
    EntryFn, ErrBuf, EvaluateFn, LawDescriptor, PARAM_MAX_EXCLUSIVE, PARAM_MIN_EXCLUSIVE,
    ParamDesc, STATUS_ERROR, STATUS_INVALID_ARGUMENT, STATUS_NON_FINITE, STATUS_OK, STATUS_PANIC,
};
use libloading::Library;
use std::collections::BTreeMap;
use std::ffi::{CStr, c_char, c_void};
use std::fmt;
use std::path::{Path, PathBuf};
use std::ptr::NonNull;

/// Relative tolerance of the load-time tangent check: at every test state,
/// `max_ab |J_ab − J_fd,ab| ≤ FD_TANGENT_TOLERANCE · max(max|J|, max|J_fd|)`, with `J_fd` the
/// central difference of the stress, step `h = 1e-6 · max(1, max|B̃|)`. Central differences
/// of a smooth law at that step err by ~1e-10 relative (round-off `ε/h`, truncation `h²`), so
/// the tolerance leaves a wide margin while a wrong term or factor fails it by orders of
/// magnitude.
pub const FD_TANGENT_TOLERANCE: f64 = 1e-5;

/// Environment variable with extra folders (`:`-separated) to look for shipped-law libraries in,
/// searched first.
pub const LAW_PATH_ENV: &str = "EFSI_LAW_PATH";

const COMPONENTS: [&str; 4] = ["11", "22", "33", "12"];

/// A number for people: plain between 1e-3 and 1e6, else in exponent form.
fn number(x: f64) -> String {
    if x == 0.0 || (1e-3..1e6).contains(&x.abs()) || !x.is_finite() {
        format!("{x}")
    } else {
        format!("{x:e}")
    }
}

/// One declared parameter of a law.
#[derive(Clone, Debug, PartialEq)]
pub struct ParamInfo {
    /// Name used in scenes.
    pub name: String,
    /// Unit (empty when dimensionless).
    pub unit: String,
    /// One-line description.
    pub description: String,
    /// Value used when the scene gives none.
    pub default: f64,
    /// Lower bound (`-∞` when unbounded).
    pub min: f64,
    /// Upper bound (`+∞` when unbounded).
    pub max: f64,
    /// Whether `min` is excluded.
    pub min_exclusive: bool,
    /// Whether `max` is excluded.
    pub max_exclusive: bool,
}

impl ParamInfo {
    /// Whether `value` is finite and in the allowed range.
    pub fn contains(&self, value: f64) -> bool {
        efsi_law_abi::range_contains(
            value,
            self.min,
            self.max,
            self.min_exclusive,
            self.max_exclusive,
        )
    }

    /// The allowed range in interval notation, e.g. `(0, ∞)`.
    pub fn range_text(&self) -> String {
        efsi_law_abi::range_text(self.min, self.max, self.min_exclusive, self.max_exclusive)
    }

    /// `value` followed by the unit, if any.
    fn with_unit(&self, value: impl fmt::Display) -> String {
        if self.unit.is_empty() {
            value.to_string()
        } else {
            format!("{value} {}", self.unit)
        }
    }
}

/// What a law library says about itself (for `efsi laws` and error messages).
#[derive(Clone, Debug, PartialEq)]
pub struct LawInfo {
    /// The law's name.
    pub name: String,
    /// One line describing it.
    pub description: String,
    /// The library it was read from.
    pub path: PathBuf,
    /// The ABI version the library was built for.
    pub abi_version: u32,
    /// Its declared parameters, in the order `create` receives them.
    pub parameters: Vec<ParamInfo>,
}

impl fmt::Display for LawInfo {
    /// The law's name and description, its library, then one line per parameter: name, unit,
    /// default, range, description.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        writeln!(f, "{} — {}", self.name, self.description)?;
        writeln!(f, "  library: {}", self.path.display())?;
        if self.parameters.is_empty() {
            writeln!(f, "  no parameters")?;
        }
        for p in &self.parameters {
            let unit = if p.unit.is_empty() { "-" } else { &p.unit };
            writeln!(
                f,
                "  {:<10} {:<4} default {:<10} range {:<12} {}",
                p.name,
                unit,
                number(p.default),
                p.range_text(),
                p.description
            )?;
        }
        Ok(())
    }
}

/// The outcome of the finite-difference tangent check ([`check_tangent`]): the worst entry.
#[derive(Clone, Debug, PartialEq)]
pub struct TangentCheck {
    /// Number of deformed states tested.
    pub states: usize,
    /// Number of states skipped because the law could not evaluate them (outside its domain,
    /// e.g. past a locking stretch); at most half.
    pub skipped: usize,
    /// The worst `max|J − J_fd| / max(max|J|, max|J_fd|)` over the states.
    pub worst_relative_error: f64,
    /// The state where it occurred.
    pub worst_state: Sym,
    /// The worst entry there: row `a` (stress component) and column `b` (B̃ component).
    pub worst_entry: (usize, usize),
    /// The law's tangent entry there.
    pub tangent: f64,
    /// The finite-difference value there.
    pub finite_difference: f64,
}

impl TangentCheck {
    /// Whether the check passed ([`FD_TANGENT_TOLERANCE`]).
    pub fn passed(&self) -> bool {
        self.worst_relative_error <= FD_TANGENT_TOLERANCE
    }
}

impl fmt::Display for TangentCheck {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let (a, b) = self.worst_entry;
        write!(
            f,
            "worst relative error {:.3e} (tolerance {FD_TANGENT_TOLERANCE:e}) over {} states ({} skipped), at ∂τ{}/∂B̃{} = {:.6e} vs finite difference {:.6e}, B̃ = {:?}",
            self.worst_relative_error,
            self.states,
            self.skipped,
            COMPONENTS[a],
            COMPONENTS[b],
            self.tangent,
            self.finite_difference,
            self.worst_state
        )
    }
}

/// A law loaded from a plugin library: a [`ConstitutiveLaw`] holding the library and one
/// instance of the law (destroyed on drop, before the library is closed).
pub struct LoadedLaw {
    info: LawInfo,
    values: Vec<f64>,
    handle: NonNull<c_void>,
    evaluate_fn: EvaluateFn,
    destroy_fn: DestroyFn,
    check: Option<TangentCheck>,
    // Declared last: dropped after `Drop::drop` destroyed the handle.
    _library: Library,
}

// SAFETY: the ABI requires `evaluate` to be callable concurrently on one handle and
// `create`/`destroy` from any thread (the SDK enforces `Send + Sync` on the law type).
unsafe impl Send for LoadedLaw {}
// SAFETY: as above.
unsafe impl Sync for LoadedLaw {}

impl fmt::Debug for LoadedLaw {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("LoadedLaw")
            .field("info", &self.info)
            .field("values", &self.values)
            .finish_non_exhaustive()
    }
}

impl LoadedLaw {
    /// What the library says about the law.
    pub fn info(&self) -> &LawInfo {
        &self.info
    }

    /// The parameter values in use (scene values, or defaults), by name, in declaration order.
    pub fn parameter_values(&self) -> Vec<(String, f64)> {
        self.info
            .parameters
            .iter()
            .map(|p| p.name.clone())
            .zip(self.values.iter().copied())
            .collect()
    }

    /// The load-time tangent check's result.
    pub fn tangent_check(&self) -> &TangentCheck {
        self.check
            .as_ref()
            .expect("a loaded law has passed its tangent check")
    }

    fn error(&self, message: String) -> LawError {
        LawError {
            law: self.info.name.clone(),
            message,
            cell: None,
        }
    }
}

impl Drop for LoadedLaw {
    fn drop(&mut self) {
        // SAFETY: the handle came from this library's `create` and is not used again.
        unsafe { (self.destroy_fn)(self.handle.as_ptr()) }
    }
}

impl ConstitutiveLaw for LoadedLaw {
    fn name(&self) -> &str {
        &self.info.name
    }

    fn evaluate(
        &self,
        b: &[Sym],
        tau: &mut [Sym],
        mut tangent: Option<&mut [Tangent]>,
    ) -> Result<(), LawError> {
        let n = b.len();
        if tau.len() != n || tangent.as_ref().is_some_and(|j| j.len() != n) {
            return Err(self.error(format!(
                "evaluate called with {n} B̃, {} τ and {} tangent slots",
                tau.len(),
                tangent.as_ref().map_or(0, |j| j.len())
            )));
        }
        if n == 0 {
            return Ok(());
        }
        let mut err = ErrBuf::new();
        let tangent_ptr = tangent
            .as_deref_mut()
            .map_or(std::ptr::null_mut(), |j| j.as_mut_ptr().cast::<f64>());
        // SAFETY: `b`, `tau` and `tangent` hold `n` cells of 4, 4 and 16 contiguous f64
        // (cell-major, as the ABI lays them out) and do not overlap (distinct borrows); the
        // handle is alive.
        let status = unsafe {
            (self.evaluate_fn)(
                self.handle.as_ptr(),
                n,
                b.as_ptr().cast::<f64>(),
                tau.as_mut_ptr().cast::<f64>(),
                tangent_ptr,
                &mut err,
            )
        };
        if status != STATUS_OK {
            let text = err.text();
            if status == STATUS_NON_FINITE {
                // The SDK says "non-finite stress at cell k (…)": keep k as the batch index.
                if let Some(at) = text.find(" at cell ") {
                    let rest = &text[at + 9..];
                    let digits = rest
                        .find(|c: char| !c.is_ascii_digit())
                        .unwrap_or(rest.len());
                    if let Ok(k) = rest[..digits].parse() {
                        let message = format!("{}{}", &text[..at], &rest[digits..]);
                        return Err(LawError {
                            cell: Some(k),
                            ..self.error(message)
                        });
                    }
                }
            }
            return Err(self.error(match status {
                STATUS_ERROR => format!("evaluate failed: {text}"),
                STATUS_PANIC => format!("panicked in evaluate: {text}"),
                STATUS_NON_FINITE => text,
                STATUS_INVALID_ARGUMENT => format!("evaluate refused its arguments: {text}"),
                s => format!("evaluate returned unknown status {s}: {text}"),
            }));
        }
        // The plugin promises finite outputs; check anyway (a C plugin may not).
        let bad_tau = tau.iter().position(|t| !t.iter().all(|x| x.is_finite()));
        let bad_j = tangent
            .as_deref()
            .and_then(|j| j.iter().position(|j| !j.iter().all(|x| x.is_finite())));
        match (bad_tau, bad_j) {
            (None, None) => Ok(()),
            (Some(k), j) if j.is_none_or(|j| k <= j) => Err(LawError {
                cell: Some(k),
                ..self.error(format!("non-finite stress (B̃ = {:?})", b[k]))
            }),
            (_, Some(k)) => Err(LawError {
                cell: Some(k),
                ..self.error(format!("non-finite tangent (B̃ = {:?})", b[k]))
            }),
            (Some(_), None) => unreachable!("covered by the guard above"),
        }
    }
}

/// Loads the law a scene names, `name` with the parameter values `parameters` (see the module
/// docs for the resolution and the checks). `scene_dir` is the scene file's folder: relative
/// library paths are relative to it.
pub fn load_law(
    name: &str,
    parameters: &BTreeMap<String, f64>,
    scene_dir: &Path,
) -> Result<LoadedLaw, LawError> {
    let path = resolve_law(name, scene_dir)?;
    let mut law = instantiate(&path, name, parameters)?;
    let check = check_tangent(&law).map_err(|e| {
        law.error(format!(
            "tangent check at load failed ({}): {}",
            describe_values(&law.info, &law.values),
            e.message
        ))
    })?;
    if !check.passed() {
        let (a, b) = check.worst_entry;
        return Err(law.error(format!(
            "refused: its tangent disagrees with finite differences of its stress ({}): at B̃ = {:?}, ∂τ{}/∂B̃{} is {:.6e} but the stress gives {:.6e} — relative error {:.3e} > tolerance {FD_TANGENT_TOLERANCE:e}; fix the law's tangent (or its stress)",
            describe_values(&law.info, &law.values),
            check.worst_state,
            COMPONENTS[a],
            COMPONENTS[b],
            check.tangent,
            check.finite_difference,
            check.worst_relative_error,
        )));
    }
    law.check = Some(check);
    Ok(law)
}

/// The tangent check of the law in the library at `path`, created with its default parameters
/// (`efsi laws --check`): the law's description and the check's outcome, passed or not
/// ([`TangentCheck::passed`]). An error if the library cannot be loaded, the law cannot be
/// created or cannot evaluate the check's states.
pub fn check_library(path: &Path) -> Result<(LawInfo, TangentCheck), LawError> {
    let label = path.display().to_string();
    if !path.is_file() {
        return Err(LawError {
            law: label,
            message: format!("library not found: {}", path.display()),
            cell: None,
        });
    }
    let law = instantiate(path, &label, &BTreeMap::new())?;
    let check = check_tangent(&law).map_err(|e| {
        law.error(format!(
            "tangent check failed ({}): {}",
            describe_values(&law.info, &law.values),
            e.message
        ))
    })?;
    Ok((law.info.clone(), check))
}

/// Open the library at `path` (named `name` in errors) and create its law with `parameters`
/// (by name, checked against the declared ranges; defaults for the others), without the
/// tangent check.
fn instantiate(
    path: &Path,
    name: &str,
    parameters: &BTreeMap<String, f64>,
) -> Result<LoadedLaw, LawError> {
    let opened = open(path, name)?;
    let info = opened.info;
    let fail = |message: String| LawError {
        law: info.name.clone(),
        message,
        cell: None,
    };

    let mut values: Vec<f64> = info.parameters.iter().map(|p| p.default).collect();
    for (name, &value) in parameters {
        let Some(k) = info.parameters.iter().position(|p| &p.name == name) else {
            let known = info
                .parameters
                .iter()
                .map(|p| {
                    if p.unit.is_empty() {
                        format!("`{}`", p.name)
                    } else {
                        format!("`{}` ({})", p.name, p.unit)
                    }
                })
                .collect::<Vec<_>>();
            return Err(fail(format!(
                "unknown parameter `{name}`; the law's parameters are: {}",
                if known.is_empty() {
                    "none".to_string()
                } else {
                    known.join(", ")
                }
            )));
        };
        let p = &info.parameters[k];
        if !p.contains(value) {
            return Err(fail(
                format!(
                    "parameter `{name}` = {} is out of range: allowed {} {}",
                    p.with_unit(value),
                    p.range_text(),
                    p.unit
                )
                .trim_end()
                .to_string(),
            ));
        }
        values[k] = value;
    }

    let mut err = ErrBuf::new();
    // SAFETY: `values` holds `len` readable f64; `err` is writable.
    let handle = unsafe { (opened.create)(values.as_ptr(), values.len(), &mut err) };
    let Some(handle) = NonNull::new(handle) else {
        return Err(fail(format!(
            "could not be created with {}: {}",
            describe_values(&info, &values),
            err.text()
        )));
    };
    Ok(LoadedLaw {
        info,
        values,
        handle,
        evaluate_fn: opened.evaluate,
        destroy_fn: opened.destroy,
        check: None,
        _library: opened.library,
    })
}

/// Reads a law library's name and parameter table without creating the law (`efsi laws`).
pub fn describe(path: &Path) -> Result<LawInfo, LawError> {
    let label = path.display().to_string();
    if let Some(message) = not_a_library_file(path) {
        return Err(LawError {
            law: label,
            message,
            cell: None,
        });
    }
    open(path, &label).map(|o| o.info)
}

/// Describes every shipped law found on the search path (the first of each name, in
/// [`search_dirs`] order), then each library in `extra`.
pub fn list_laws(extra: &[PathBuf]) -> Vec<Result<LawInfo, LawError>> {
    let prefix = format!("{}efsi_law_", std::env::consts::DLL_PREFIX);
    let suffix = std::env::consts::DLL_SUFFIX;
    let mut seen = std::collections::BTreeSet::new();
    let mut out = Vec::new();
    for dir in search_dirs() {
        let Ok(entries) = std::fs::read_dir(&dir) else {
            continue;
        };
        let mut found: Vec<(String, PathBuf)> = entries
            .filter_map(|e| e.ok())
            .filter_map(|e| {
                let file = e.file_name().into_string().ok()?;
                let name = file
                    .strip_prefix(&prefix)?
                    .strip_suffix(suffix)?
                    .to_string();
                e.path().is_file().then_some((name, e.path()))
            })
            .collect();
        found.sort();
        for (name, path) in found {
            if seen.insert(name) {
                out.push(describe(&path));
            }
        }
    }
    out.extend(extra.iter().map(|p| describe(p)));
    out
}

/// The file name of shipped law `name`: `libefsi_law_<name>.so` (`.dylib` on macOS,
/// `efsi_law_<name>.dll` on Windows).
pub fn library_file_name(name: &str) -> String {
    format!(
        "{}efsi_law_{name}{}",
        std::env::consts::DLL_PREFIX,
        std::env::consts::DLL_SUFFIX
    )
}

/// Where shipped laws are looked for, in order: each folder of `$EFSI_LAW_PATH`, the running
/// executable's folder, its parent (test binaries live in `target/<profile>/deps`) and its
/// `deps` subfolder (where `cargo test`, unlike `cargo build`, leaves the law libraries), then
/// `target/release` and `target/debug` of the workspace this efsi was compiled from.
pub fn search_dirs() -> Vec<PathBuf> {
    let mut dirs = Vec::new();
    if let Some(paths) = std::env::var_os(LAW_PATH_ENV) {
        dirs.extend(std::env::split_paths(&paths).filter(|p| !p.as_os_str().is_empty()));
    }
    if let Ok(exe) = std::env::current_exe()
        && let Some(dir) = exe.parent()
    {
        dirs.push(dir.to_path_buf());
        if let Some(parent) = dir.parent() {
            dirs.push(parent.to_path_buf());
        }
        // `cargo test` builds the law libraries into `target/<profile>/deps` only.
        dirs.push(dir.join("deps"));
    }
    let root = Path::new(env!("CARGO_MANIFEST_DIR"))
        .parent()
        .and_then(Path::parent)
        .unwrap_or(Path::new(env!("CARGO_MANIFEST_DIR")));
    dirs.push(root.join("target").join("release"));
    dirs.push(root.join("target").join("debug"));
    let mut unique = Vec::new();
    for d in dirs {
        if !unique.contains(&d) {
            unique.push(d);
        }
    }
    unique
}

/// Whether a law name is a library path rather than a shipped law's name.
fn is_path(name: &str) -> bool {
    name.contains('/')
        || name.contains('\\')
        || [".so", ".dylib", ".dll"].iter().any(|e| name.ends_with(e))
}

/// Why `path` cannot be a law library file, if it cannot: absent, a folder, a device.
fn not_a_library_file(path: &Path) -> Option<String> {
    match std::fs::metadata(path) {
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => {
            Some(format!("library not found: {}", path.display()))
        }
        Err(e) => Some(format!("cannot read the library {}: {e}", path.display())),
        Ok(m) if m.is_dir() => Some(format!(
            "{} is a folder, not a law library file",
            path.display()
        )),
        Ok(m) if !m.is_file() => Some(format!(
            "{} is not a regular file (a device or a pipe), not a law library",
            path.display()
        )),
        Ok(_) => None,
    }
}

/// The library file a scene's law name refers to (see the module docs).
pub fn resolve_law(name: &str, scene_dir: &Path) -> Result<PathBuf, LawError> {
    let fail = |message: String| LawError {
        law: name.to_string(),
        message,
        cell: None,
    };
    if name.trim().is_empty() {
        return Err(fail("the law's name is empty".to_string()));
    }
    if is_path(name) {
        let path = scene_dir.join(name);
        // An absolute path, so that the dynamic loader does not search its own paths.
        let path = std::path::absolute(&path).unwrap_or(path);
        return match not_a_library_file(&path) {
            None => Ok(path),
            Some(m) => Err(fail(format!(
                "{m} (a relative law path is relative to the scene's folder {})",
                scene_dir.display()
            ))),
        };
    }
    let file = library_file_name(name);
    let dirs = search_dirs();
    for dir in &dirs {
        let candidate = dir.join(&file);
        if candidate.is_file() {
            return Ok(candidate);
        }
    }
    Err(fail(format!(
        "no shipped law of that name: {file} is in none of {}; build the laws with `cargo build --workspace` (add `--release` for a release efsi), add their folder to ${LAW_PATH_ENV}, or give the library's path",
        dirs.iter()
            .map(|d| d.display().to_string())
            .collect::<Vec<_>>()
            .join(", ")
    )))
}

/// An opened, checked library.
struct Opened {
    library: Library,
    info: LawInfo,
    create: efsi_law_abi::CreateFn,
    destroy: DestroyFn,
    evaluate: EvaluateFn,
}

/// Opens `path` and checks its descriptor; `label` names the law until the descriptor does.
fn open(path: &Path, label: &str) -> Result<Opened, LawError> {
    let mut law = label.to_string();
    let fail = |law: &str, message: String| LawError {
        law: law.to_string(),
        message,
        cell: None,
    };
    // SAFETY: loading a library runs its initialisers; a law library is trusted code by design
    // (the user named it), and the checks below guard the ABI.
    let library = unsafe { Library::new(path) }.map_err(|e| {
        // The loader's own words (`dlerror`) are the error's source, not its summary.
        let why = std::error::Error::source(&e).map_or_else(|| e.to_string(), |s| s.to_string());
        fail(
            &law,
            format!("{} is not a loadable library: {why}", path.display()),
        )
    })?;
    // SAFETY: the symbol's type is fixed by the ABI (`EntryFn`), for every version.
    let entry: EntryFn = unsafe { library.get::<EntryFn>(ENTRY_SYMBOL) }
        .map(|s| *s)
        .map_err(|_| {
            fail(
                &law,
                format!(
                    "{} is not an efsi law library: it has no `{ENTRY_SYMBOL_NAME}` symbol (build it with efsi-law-sdk's `export_law!`)",
                    path.display()
                ),
            )
        })?;
    // SAFETY: `entry` has the ABI's signature; it takes no arguments.
    let ptr = unsafe { entry() };
    if ptr.is_null() {
        return Err(fail(
            &law,
            format!(
                "{}: `{ENTRY_SYMBOL_NAME}` returned no descriptor (the library could not describe its law)",
                path.display()
            ),
        ));
    }
    // The first two u32 fields are frozen across ABI versions: read them before anything else.
    // SAFETY: every version's descriptor starts with these two fields.
    let [version, size] = unsafe { ptr.cast::<[u32; 2]>().read() };
    if version != ABI_VERSION {
        return Err(fail(
            &law,
            format!(
                "{} was built for ABI v{version}, efsi expects v{ABI_VERSION}: rebuild the law against efsi-law-sdk {CRATE_VERSION}",
                path.display()
            ),
        ));
    }
    if size != DESCRIPTOR_SIZE {
        return Err(fail(
            &law,
            format!(
                "{}: descriptor size {size} bytes, efsi expects {DESCRIPTOR_SIZE} for ABI v{ABI_VERSION}: the library's layout does not match its version; rebuild it against efsi-law-sdk {CRATE_VERSION}",
                path.display()
            ),
        ));
    }
    // SAFETY: version and size match this crate's definition; it lives as long as `library`.
    let d: &LawDescriptor = unsafe { &*ptr };
    // SAFETY: descriptor strings are NUL-terminated, live as long as the library (ABI rule).
    let text = |p: *const c_char, what: &str, law: &str| unsafe { c_text(p, what, law, path) };
    let name = text(d.name, "name", &law)?;
    law = name.clone();
    let description = text(d.description, "description", &law)?;
    if d.param_desc_size != std::mem::size_of::<ParamDesc>() {
        return Err(fail(
            &law,
            format!(
                "{}: parameter entries of {} bytes, efsi expects {}: rebuild the law against efsi-law-sdk {CRATE_VERSION}",
                path.display(),
                d.param_desc_size,
                std::mem::size_of::<ParamDesc>()
            ),
        ));
    }
    let table: &[ParamDesc] = match (d.param_count, d.params.is_null()) {
        (0, _) => &[],
        (_, true) => {
            return Err(fail(
                &law,
                format!(
                    "{}: declares {} parameters but no table",
                    path.display(),
                    d.param_count
                ),
            ));
        }
        // SAFETY: non-null, `param_count` entries of the checked size (ABI rule).
        (n, false) => unsafe { std::slice::from_raw_parts(d.params, n) },
    };
    let mut parameters: Vec<ParamInfo> = Vec::with_capacity(table.len());
    for (k, p) in table.iter().enumerate() {
        let what = format!("parameter {k}'s name");
        let info = ParamInfo {
            name: text(p.name, &what, &law)?,
            unit: text(p.unit, "parameter unit", &law)?,
            description: text(p.description, "parameter description", &law)?,
            default: p.default,
            min: p.min,
            max: p.max,
            min_exclusive: p.flags & PARAM_MIN_EXCLUSIVE != 0,
            max_exclusive: p.flags & PARAM_MAX_EXCLUSIVE != 0,
        };
        if parameters.iter().any(|q| q.name == info.name) {
            return Err(fail(
                &law,
                format!("declares parameter `{}` twice", info.name),
            ));
        }
        if !info.contains(info.default) {
            return Err(fail(
                &law,
                format!(
                    "parameter `{}`'s declared default {} is outside its declared range {}",
                    info.name,
                    info.default,
                    info.range_text()
                ),
            ));
        }
        parameters.push(info);
    }
    let (Some(create), Some(destroy), Some(evaluate)) = (d.create, d.destroy, d.evaluate) else {
        return Err(fail(
            &law,
            format!(
                "{}: the descriptor lacks a create, destroy or evaluate function",
                path.display()
            ),
        ));
    };
    Ok(Opened {
        info: LawInfo {
            name,
            description,
            path: path.to_path_buf(),
            abi_version: version,
            parameters,
        },
        create,
        destroy,
        evaluate,
        library,
    })
}

/// A descriptor string.
///
/// # Safety
/// `p` is null or a NUL-terminated string that outlives the call.
unsafe fn c_text(p: *const c_char, what: &str, law: &str, path: &Path) -> Result<String, LawError> {
    if p.is_null() {
        return Err(LawError {
            law: law.to_string(),
            message: format!("{}: the descriptor's {what} is null", path.display()),
            cell: None,
        });
    }
    // SAFETY: by the caller's contract.
    let s = unsafe { CStr::from_ptr(p) };
    s.to_str().map(str::to_string).map_err(|_| LawError {
        law: law.to_string(),
        message: format!("{}: the descriptor's {what} is not UTF-8", path.display()),
        cell: None,
    })
}

/// `G = 1e5 Pa, …` for messages.
fn describe_values(info: &LawInfo, values: &[f64]) -> String {
    if values.is_empty() {
        return "no parameters".to_string();
    }
    info.parameters
        .iter()
        .zip(values)
        .map(|(p, v)| format!("{} = {}", p.name, p.with_unit(v)))
        .collect::<Vec<_>>()
        .join(", ")
}

/// The deformed states of the tangent check: `B̃ = I`, `B̃ = 0.5 I` (φ = 0.25), and 24
/// states `B̃ = φ^{1/2} F Fᵀ` with `F` the identity plus entries uniform in ±0.25 (F11, F12,
/// F21, F22, and F33 out of plane) and `φ` cycling through 1, 0.6, 0.25, 0.05 — a fixed seed,
/// so every law sees the same states.
pub fn tangent_check_states() -> Vec<Sym> {
    let mut rng = XorShift(0x5EED_1A3F_0C0F_FEE5);
    let phis = [1.0, 0.6, 0.25, 0.05_f64];
    let amplitude = 0.25;
    let mut states = vec![[1.0, 1.0, 1.0, 0.0], [0.5, 0.5, 0.5, 0.0]];
    for k in 0..24 {
        let mut r = || amplitude * (2.0 * rng.uniform() - 1.0);
        let (f11, f12, f21, f22, f33) = (1.0 + r(), r(), r(), 1.0 + r(), 1.0 + r());
        let s = phis[k % phis.len()].sqrt();
        states.push([
            s * (f11 * f11 + f12 * f12),
            s * (f21 * f21 + f22 * f22),
            s * f33 * f33,
            s * (f11 * f21 + f12 * f22),
        ]);
    }
    states
}

/// Checks a law's tangent against central finite differences of its stress at
/// [`tangent_check_states`] (two batched calls: the states with tangents, then the ±h
/// perturbations with stresses only). Returns the worst entry; the caller compares it with
/// [`FD_TANGENT_TOLERANCE`] ([`TangentCheck::passed`]). States the law cannot evaluate (outside
/// its domain) are skipped, up to half of them; it fails if the law cannot evaluate `B̃ = I` or
/// more than half the states. Works for any [`ConstitutiveLaw`], built in or loaded.
pub fn check_tangent(law: &dyn ConstitutiveLaw) -> Result<TangentCheck, LawError> {
    let states = tangent_check_states();
    let n = states.len();
    let (pairs, skipped) = match tangents_and_differences(law, &states) {
        Ok(pairs) => (pairs, 0),
        // Some state is outside the law's domain (e.g. past a locking stretch): test the states
        // one by one and skip those the law cannot evaluate. `B̃ = I` must evaluate, and at
        // least half the states.
        Err(first) => {
            let mut pairs = Vec::with_capacity(n);
            for (s, b) in states.iter().enumerate() {
                match tangents_and_differences(law, std::slice::from_ref(b)) {
                    Ok(p) => pairs.extend(p),
                    Err(e) if s == 0 => return Err(e),
                    Err(_) => {}
                }
            }
            if 2 * pairs.len() < n {
                return Err(first);
            }
            let skipped = n - pairs.len();
            (pairs, skipped)
        }
    };
    let mut worst: Option<TangentCheck> = None;
    for (b, j, fd) in &pairs {
        let scale = j.iter().chain(fd).fold(0.0_f64, |m, x| m.max(x.abs()));
        let (i, err) = (0..16)
            .map(|i| (i, (j[i] - fd[i]).abs()))
            .fold((0, 0.0), |best, e| if e.1 > best.1 { e } else { best });
        let relative = if scale > 0.0 { err / scale } else { err };
        if worst
            .as_ref()
            .is_none_or(|w| relative > w.worst_relative_error)
        {
            worst = Some(TangentCheck {
                states: pairs.len(),
                skipped,
                worst_relative_error: relative,
                worst_state: *b,
                worst_entry: (i / 4, i % 4),
                tangent: j[i],
                finite_difference: fd[i],
            });
        }
    }
    Ok(worst.expect("at least one state"))
}

/// For each state: `(B̃, J, J_fd)`, in two batched calls (the states with tangents, then the ±h
/// perturbations with stresses only).
fn tangents_and_differences(
    law: &dyn ConstitutiveLaw,
    states: &[Sym],
) -> Result<Vec<(Sym, Tangent, Tangent)>, LawError> {
    let n = states.len();
    let mut tau = vec![[0.0; 4]; n];
    let mut jac = vec![[0.0; 16]; n];
    law.evaluate(states, &mut tau, Some(&mut jac))?;
    let steps: Vec<f64> = states
        .iter()
        .map(|b| 1e-6 * b.iter().fold(1.0_f64, |m, x| m.max(x.abs())))
        .collect();
    let mut perturbed = Vec::with_capacity(8 * n);
    for (b, h) in states.iter().zip(&steps) {
        for c in 0..4 {
            for sign in [1.0, -1.0] {
                let mut p = *b;
                p[c] += sign * h;
                perturbed.push(p);
            }
        }
    }
    let mut tau_p = vec![[0.0; 4]; 8 * n];
    law.evaluate(&perturbed, &mut tau_p, None)?;
    Ok((0..n)
        .map(|s| {
            let mut fd = [0.0; 16];
            for c in 0..4 {
                let (tp, tm) = (tau_p[8 * s + 2 * c], tau_p[8 * s + 2 * c + 1]);
                for a in 0..4 {
                    fd[4 * a + c] = (tp[a] - tm[a]) / (2.0 * steps[s]);
                }
            }
            (states[s], jac[s], fd)
        })
        .collect())
}

/// xorshift64* (seeded, reproducible).
struct XorShift(u64);

impl XorShift {
    fn uniform(&mut self) -> f64 {
        let mut x = self.0;
        x ^= x >> 12;
        x ^= x << 25;
        x ^= x >> 27;
        self.0 = x;
        (x.wrapping_mul(0x2545_F491_4F6C_DD1D) >> 11) as f64 / (1u64 << 53) as f64
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::NeoHookeanReference;

    #[test]
    fn reference_law_passes_the_tangent_check() {
        let c = check_tangent(&NeoHookeanReference { g: 1e6 }).unwrap();
        assert!(c.passed(), "{c}");
        assert!(c.worst_relative_error < 1e-8, "{c}");
    }

    #[test]
    fn check_states_are_symmetric_positive_definite() {
        for b in tangent_check_states() {
            assert!(b[0] > 0.0 && b[2] > 0.0 && b[0] * b[1] - b[3] * b[3] > 0.0);
        }
    }

    #[test]
    fn names_and_paths() {
        assert!(is_path("./libx.so") && is_path("x.dll") && is_path("a/b"));
        assert!(!is_path("neo_hookean"));
        assert_eq!(
            library_file_name("neo_hookean"),
            format!(
                "{}efsi_law_neo_hookean{}",
                std::env::consts::DLL_PREFIX,
                std::env::consts::DLL_SUFFIX
            )
        );
        let e = resolve_law("no_such_law_xyz", Path::new(".")).unwrap_err();
        assert_eq!(e.law, "no_such_law_xyz");
        assert!(e.message.contains("target"), "{e}");
    }

    #[test]
    fn range_text() {
        let p = ParamInfo {
            name: "G".into(),
            unit: "Pa".into(),
            description: String::new(),
            default: 1.0,
            min: 0.0,
            max: f64::INFINITY,
            min_exclusive: true,
            max_exclusive: false,
        };
        assert_eq!(p.range_text(), "(0, ∞)");
        assert!(!p.contains(0.0) && p.contains(1e9) && !p.contains(f64::INFINITY));
    }
}
