//! Finding a law's library: a path (relative to the scene's folder) or the name of a shipped law
//! looked up in [`search_dirs`].

use super::LAW_PATH_ENV;
use crate::LawError;
use std::path::{Path, PathBuf};

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
pub(super) fn is_path(name: &str) -> bool {
    name.contains('/')
        || name.contains('\\')
        || [".so", ".dylib", ".dll"].iter().any(|e| name.ends_with(e))
}

/// Why `path` cannot be a law library file, if it cannot: absent, a folder, a device.
pub(super) fn not_a_library_file(path: &Path) -> Option<String> {
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
