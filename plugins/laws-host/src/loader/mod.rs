//! Loading constitutive laws from plugin libraries.
//!
//! A law plugin is a dynamic library speaking the C ABI of `efsi-law-abi` (version
//! [`ABI_VERSION`](efsi_law_abi::ABI_VERSION)): it exports `efsi_law_descriptor`, which returns
//! the law's name, parameter table (name, unit, default, allowed range) and `create` / `destroy`
//! / `evaluate_in_plane` / `evaluate_full` functions.
//! Laws written in Rust use `efsi-law-sdk`; the shipped ones live in `plugins/laws/`.
//!
//! **Version 1.** A library built for ABI version 1 (the frozen layout
//! [`efsi_law_abi::v1`]) has one evaluation, on in-plane tensors `[11, 22, 33, 12]`. It loads
//! and runs in planar and axisymmetric scenes exactly as before ([`load_law`]). A 3-D scene
//! ([`load_law_3d`]) refuses it, naming the version and asking for a rebuild against the
//! current SDK: its stress on a tensor with 13, 23 ≠ 0 is not defined by anything the library
//! exports. (Adapting it would rotate each `B̃` to its principal axes, which is exact only for
//! an isotropic law, and version 1 never required or checked isotropy; a rebuild against
//! `efsi-law-sdk` is the law's own code, evaluated on the full tensor.)
//!
//! [`load_law`] turns the law a scene names (its name and parameter values) into a
//! [`LoadedLaw`] (a [`ConstitutiveLaw`](crate::ConstitutiveLaw)):
//!
//! 1. **Resolve** the name: a name with a path separator or ending in `.so`/`.dylib`/`.dll` is a
//!    library path (relative to the scene's folder); any other name `X` is a shipped law, the file
//!    `libefsi_law_X.so` looked up in [`search_dirs`]: `$EFSI_LAW_PATH` (a `:`-separated list),
//!    the running executable's folder, its parent and its `deps` subfolder, then `target/release`
//!    and `target/debug` of the workspace efsi was built from.
//! 2. **Open** it and check it: its file's ELF structure first ([`elf`]: a truncated or
//!    corrupted file is refused, never handed to the dynamic loader), then a library with the entry symbol, built for this ABI version, with
//!    the descriptor size this efsi expects, and a well-formed parameter table.
//! 3. **Parameters**: every scene parameter must be declared (else the known ones are listed),
//!    finite and in its range (name, value, range and unit in the message); the others take their
//!    defaults.
//! 4. **Create** the instance; a failure or panic inside the plugin comes back with its message.
//! 5. **Check the tangent** against central finite differences of the stress ([`check_tangent`]
//!    on in-plane tensors, and for a version-2 library [`check_tangent_full`] on full 3-D ones;
//!    tolerance [`FD_TANGENT_TOLERANCE`]) and refuse a law whose tangent is wrong in either;
//!    for a version-2 library, also compare its two evaluations on in-plane tensors
//!    ([`check_embedding`], tolerance [`EMBEDDING_TOLERANCE`]) and refuse a library whose
//!    in-plane and 3-D laws differ.
//!
//! Evaluation is one plugin call per batch of cells; a status other than success, a panic in the
//! plugin, or a non-finite output becomes a [`LawError`] naming the law (and the first bad cell).

use crate::LawError;
use std::collections::BTreeMap;
use std::fmt;
use std::path::{Path, PathBuf};

pub mod elf;
mod law;
mod open;
mod params;
mod resolve;
mod tangent;

pub use law::LoadedLaw;
use open::open;
pub use params::ParamInfo;
use params::{describe_values, instantiate};
use resolve::not_a_library_file;
pub use resolve::{library_file_name, resolve_law, search_dirs};
pub use tangent::{
    EMBEDDING_TOLERANCE, EmbeddingCheck, TangentCheck, check_embedding, check_tangent,
    check_tangent_full, tangent_check_states, tangent_check_states_full,
};

/// Relative tolerance of the load-time tangent check: at every test state,
/// `max_ab |J_ab − J_fd,ab| ≤ FD_TANGENT_TOLERANCE · max(max|J|, max|J_fd|, max|J(I)|)`, with
/// `J_fd` the central difference of the stress, step `h = 1e-6 · max(1, max|B̃|)`, and `J(I)` the
/// law's tangent at rest. Central differences of a smooth law at that step err by ~1e-10 of the
/// stress scale (round-off `ε|τ|/h`, truncation `h²`), so the tolerance leaves a wide margin
/// while a wrong term or factor fails it by orders of magnitude. The floor `max|J(I)|` is the
/// law's own stiffness: at a state where the tangent vanishes or nearly does (Saint
/// Venant–Kirchhoff with λ = 0 has `J = 0` at `B̃ = 0.5 I`, and `J ≈ λ` with a small λ) the
/// round-off of the differences is judged against it, not against that zero.
pub const FD_TANGENT_TOLERANCE: f64 = 1e-5;

/// Environment variable with extra folders (`:`-separated) to look for shipped-law libraries in,
/// searched first.
pub const LAW_PATH_ENV: &str = "EFSI_LAW_PATH";

/// Component names, in the order of the full representation (the in-plane one is its first
/// four).
const COMPONENTS: [&str; 6] = ["11", "22", "33", "12", "23", "13"];

/// A number for people: plain between 1e-3 and 1e6, else in exponent form.
fn number(x: f64) -> String {
    if x == 0.0 || (1e-3..1e6).contains(&x.abs()) || !x.is_finite() {
        format!("{x}")
    } else {
        format!("{x:e}")
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
        if self.abi_version == efsi_law_abi::v1::ABI_VERSION {
            writeln!(
                f,
                "  ABI v{}: in-plane tensors only (planar and axisymmetric scenes; refused in 3-D scenes)",
                self.abi_version
            )?;
        } else {
            writeln!(
                f,
                "  ABI v{}: full and in-plane tensors (all geometries)",
                self.abi_version
            )?;
        }
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

/// Loads the law a scene names, `name` with the parameter values `parameters`, for a planar or
/// axisymmetric scene (see the module docs for the resolution and the checks). `scene_dir` is
/// the scene file's folder: relative library paths are relative to it. A version-1 library
/// loads (in-plane tensors); a version-2 library must pass the tangent check on both its
/// evaluations.
pub fn load_law(
    name: &str,
    parameters: &BTreeMap<String, f64>,
    scene_dir: &Path,
) -> Result<LoadedLaw, LawError> {
    load(name, parameters, scene_dir, false)
}

/// [`load_law`] for a 3-D scene: refuses a version-1 library, naming the version (it carries
/// in-plane tensors only; see the module docs).
pub fn load_law_3d(
    name: &str,
    parameters: &BTreeMap<String, f64>,
    scene_dir: &Path,
) -> Result<LoadedLaw, LawError> {
    load(name, parameters, scene_dir, true)
}

/// [`load_law`] (`three_d` false) or [`load_law_3d`] (true).
fn load(
    name: &str,
    parameters: &BTreeMap<String, f64>,
    scene_dir: &Path,
    three_d: bool,
) -> Result<LoadedLaw, LawError> {
    let path = resolve_law(name, scene_dir)?;
    let mut law = instantiate(&path, name, parameters)?;
    if three_d && !law.evaluates_full() {
        return Err(law.in_plane_only());
    }
    law.check = Some(checked(&law, check_tangent(&law), "")?);
    if law.evaluates_full() {
        law.check_full = Some(checked(&law, check_tangent_full(&law), "3-D ")?);
        let embedding = check_embedding(&law).map_err(|e| {
            law.error(format!(
                "embedding check at load failed ({}): {}",
                describe_values(&law.info, &law.values),
                e.message
            ))
        })?;
        if !embedding.passed() {
            return Err(law.error(format!(
                "refused: its in-plane and full evaluations disagree on in-plane tensors ({}): {embedding}; the library's evaluate_in_plane and evaluate_full must be one law",
                describe_values(&law.info, &law.values)
            )));
        }
    }
    Ok(law)
}

/// The outcome of a load-time tangent check, or the refusal of `law` when it failed or could
/// not run; `which` is `""` (in-plane) or `"3-D "`.
fn checked(
    law: &LoadedLaw,
    check: Result<TangentCheck, LawError>,
    which: &str,
) -> Result<TangentCheck, LawError> {
    let check = check.map_err(|e| {
        law.error(format!(
            "{which}tangent check at load failed ({}): {}",
            describe_values(&law.info, &law.values),
            e.message
        ))
    })?;
    if !check.passed() {
        let (a, b) = check.worst_entry_names();
        return Err(law.error(format!(
            "refused: its {which}tangent disagrees with finite differences of its stress ({}): at B̃ = {:?}, ∂τ{a}/∂B̃{b} is {:.6e} but the stress gives {:.6e} — relative error {:.3e} > tolerance {FD_TANGENT_TOLERANCE:e}; fix the law's tangent (or its stress)",
            describe_values(&law.info, &law.values),
            check.worst_state,
            check.tangent,
            check.finite_difference,
            check.worst_relative_error,
        )));
    }
    Ok(check)
}

/// What `efsi laws --check` reports of one library ([`check_library`]).
#[derive(Clone, Debug, PartialEq)]
pub struct LibraryCheck {
    /// What the library says about its law.
    pub info: LawInfo,
    /// The tangent check on in-plane tensors (planar and axisymmetric scenes).
    pub in_plane: TangentCheck,
    /// The tangent check on full 3-D tensors; `None` for a version-1 library.
    pub full: Option<TangentCheck>,
    /// The comparison of the in-plane and full evaluations on in-plane tensors; `None` for a
    /// version-1 library.
    pub embedding: Option<EmbeddingCheck>,
}

impl LibraryCheck {
    /// Whether every check run passed.
    pub fn passed(&self) -> bool {
        self.in_plane.passed()
            && self.full.as_ref().is_none_or(TangentCheck::passed)
            && self.embedding.as_ref().is_none_or(EmbeddingCheck::passed)
    }
}

/// The tangent checks of the law in the library at `path`, created with its default parameters
/// (`efsi laws --check`): on in-plane tensors, and for a version-2 library on full 3-D ones
/// with the embedding check, passed or not ([`LibraryCheck::passed`]). An error if the library cannot be loaded, the law
/// cannot be created or cannot evaluate the checks' states.
pub fn check_library(path: &Path) -> Result<LibraryCheck, LawError> {
    let label = path.display().to_string();
    if !path.is_file() {
        return Err(LawError {
            law: label,
            message: format!("library not found: {}", path.display()),
            cell: None,
        });
    }
    let law = instantiate(path, &label, &BTreeMap::new())?;
    let failed = |e: LawError, which: &str| {
        law.error(format!(
            "{which}tangent check failed ({}): {}",
            describe_values(&law.info, &law.values),
            e.message
        ))
    };
    let in_plane = check_tangent(&law).map_err(|e| failed(e, ""))?;
    let (full, embedding) = if law.evaluates_full() {
        (
            Some(check_tangent_full(&law).map_err(|e| failed(e, "3-D "))?),
            Some(check_embedding(&law).map_err(|e| failed(e, "embedding or "))?),
        )
    } else {
        (None, None)
    };
    Ok(LibraryCheck {
        info: law.info.clone(),
        in_plane,
        full,
        embedding,
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

/// One entry of a listing of laws ([`list_laws`]).
#[derive(Clone, Debug, PartialEq)]
pub enum Listed {
    /// A law library, described.
    Law(LawInfo),
    /// A file on the search path that looks like a shipped law (by its name) but cannot be
    /// trusted or read — truncated, corrupted, another ABI: skipped, and why (a listing warns
    /// and goes on; naming the law in a scene is refused with the same error).
    Skipped(LawError),
    /// A library given by path that could not be described: an error.
    Failed(LawError),
}

/// Describes every shipped law found on the search path (the first of each name, in
/// [`search_dirs`] order), then each library in `extra`. A file on the search path that cannot
/// be described is [`Listed::Skipped`]; a library in `extra` that cannot is
/// [`Listed::Failed`]. No file is handed to the dynamic loader before its structure is checked
/// ([`elf`]), so a broken file on the path cannot end the listing.
pub fn list_laws(extra: &[PathBuf]) -> Vec<Listed> {
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
                out.push(describe(&path).map_or_else(Listed::Skipped, Listed::Law));
            }
        }
    }
    out.extend(
        extra
            .iter()
            .map(|p| describe(p).map_or_else(Listed::Failed, Listed::Law)),
    );
    out
}

#[cfg(test)]
mod tests;
