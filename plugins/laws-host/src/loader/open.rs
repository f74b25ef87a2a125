//! Opening a law library and checking it before anything else runs: its file's structure
//! ([`super::elf`], before the dynamic loader sees it), the entry symbol, the ABI version and
//! descriptor size, the strings and the parameter table of its descriptor. A version-2 library
//! (the current ABI) and a version-1 library (the frozen [`efsi_law_abi::v1`] layout, in-plane
//! tensors only) are read; any other version is refused.

use super::LawInfo;
use super::params::ParamInfo;
use crate::LawError;
use efsi_law_abi::{
    ABI_VERSION, CRATE_VERSION, CreateFn, DESCRIPTOR_SIZE, DestroyFn, ENTRY_SYMBOL,
    ENTRY_SYMBOL_NAME, EntryFn, EvaluateFn, LawDescriptor, PARAM_MAX_EXCLUSIVE,
    PARAM_MIN_EXCLUSIVE, ParamDesc, v1,
};
use libloading::Library;
use std::ffi::{CStr, c_char};
use std::path::Path;

/// An opened, checked library.
pub(super) struct Opened {
    pub(super) library: Library,
    pub(super) info: LawInfo,
    pub(super) create: CreateFn,
    pub(super) destroy: DestroyFn,
    pub(super) evaluate_in_plane: EvaluateFn,
    /// `None` for a version-1 library.
    pub(super) evaluate_full: Option<EvaluateFn>,
}

/// The fields of a descriptor of either version that the loader uses (pointers into the
/// library, valid while it stays loaded).
struct Fields {
    name: *const c_char,
    description: *const c_char,
    param_count: usize,
    params: *const ParamDesc,
    param_desc_size: usize,
    create: Option<CreateFn>,
    destroy: Option<DestroyFn>,
    evaluate_in_plane: Option<EvaluateFn>,
    /// `Some(_)` for version 2 (present or not), `None` for version 1 (no such field).
    evaluate_full: Option<Option<EvaluateFn>>,
}

impl From<&LawDescriptor> for Fields {
    fn from(d: &LawDescriptor) -> Self {
        Fields {
            name: d.name,
            description: d.description,
            param_count: d.param_count,
            params: d.params,
            param_desc_size: d.param_desc_size,
            create: d.create,
            destroy: d.destroy,
            evaluate_in_plane: d.evaluate_in_plane,
            evaluate_full: Some(d.evaluate_full),
        }
    }
}

impl From<&v1::LawDescriptor> for Fields {
    fn from(d: &v1::LawDescriptor) -> Self {
        Fields {
            name: d.name,
            description: d.description,
            param_count: d.param_count,
            params: d.params,
            param_desc_size: d.param_desc_size,
            create: d.create,
            destroy: d.destroy,
            evaluate_in_plane: d.evaluate,
            evaluate_full: None,
        }
    }
}

/// Opens `path` and checks its descriptor; `label` names the law until the descriptor does.
pub(super) fn open(path: &Path, label: &str) -> Result<Opened, LawError> {
    let library = load(path, label)?;
    let (d, version) = descriptor(&library, path, label)?;
    // SAFETY: descriptor strings are NUL-terminated, live as long as the library (ABI rule).
    let text = |p: *const c_char, what: &str, law: &str| unsafe { c_text(p, what, law, path) };
    let name = text(d.name, "name", label)?;
    let description = text(d.description, "description", &name)?;
    let parameters = parameters(&d, path, &name)?;
    let missing = || {
        fail(
            &name,
            format!(
                "{}: the descriptor lacks a create, destroy or evaluate function",
                path.display()
            ),
        )
    };
    let (Some(create), Some(destroy), Some(evaluate_in_plane)) =
        (d.create, d.destroy, d.evaluate_in_plane)
    else {
        return Err(missing());
    };
    let evaluate_full = match d.evaluate_full {
        None => None,
        Some(None) => return Err(missing()),
        Some(Some(f)) => Some(f),
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
        evaluate_in_plane,
        evaluate_full,
        library,
    })
}

/// A law error of `law` (no cell).
fn fail(law: &str, message: String) -> LawError {
    LawError {
        law: law.to_string(),
        message,
        cell: None,
    }
}

/// The library at `path`, its file's structure checked before the dynamic loader maps it.
fn load(path: &Path, law: &str) -> Result<Library, LawError> {
    // The loader maps the file as its headers say: a truncated or corrupted file would kill
    // the process (SIGBUS, SIGSEGV) before any error could be reported.
    super::elf::check_library_file(path).map_err(|why| {
        fail(
            law,
            format!("{} is not a loadable library: {why}", path.display()),
        )
    })?;
    // SAFETY: loading a library runs its initialisers; a law library is trusted code by design
    // (the user named it); its file was checked above, and the checks below guard the ABI.
    unsafe { Library::new(path) }.map_err(|e| {
        // The loader's own words (`dlerror`) are the error's source, not its summary.
        let why = std::error::Error::source(&e).map_or_else(|| e.to_string(), |s| s.to_string());
        fail(
            law,
            format!("{} is not a loadable library: {why}", path.display()),
        )
    })
}

/// The descriptor `library`'s entry symbol returns, after its frozen header (ABI version and
/// descriptor size) matched this build's version or version 1; with the version.
fn descriptor(library: &Library, path: &Path, law: &str) -> Result<(Fields, u32), LawError> {
    // SAFETY: the symbol's type is fixed by the ABI (`EntryFn`), for every version.
    let entry: EntryFn = unsafe { library.get::<EntryFn>(ENTRY_SYMBOL) }
        .map(|s| *s)
        .map_err(|_| {
            fail(
                law,
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
            law,
            format!(
                "{}: `{ENTRY_SYMBOL_NAME}` returned no descriptor (the library could not describe its law)",
                path.display()
            ),
        ));
    }
    // The first two u32 fields are frozen across ABI versions: read them before anything else.
    // SAFETY: every version's descriptor starts with these two fields.
    let [version, size] = unsafe { ptr.cast::<[u32; 2]>().read() };
    let expected = match version {
        ABI_VERSION => DESCRIPTOR_SIZE,
        v1::ABI_VERSION => v1::DESCRIPTOR_SIZE,
        _ => {
            return Err(fail(
                law,
                format!(
                    "{} was built for ABI v{version}, efsi expects v{ABI_VERSION} (or v{}, in-plane tensors only): rebuild the law against efsi-law-sdk {CRATE_VERSION}",
                    path.display(),
                    v1::ABI_VERSION
                ),
            ));
        }
    };
    if size != expected {
        return Err(fail(
            law,
            format!(
                "{}: descriptor size {size} bytes, efsi expects {expected} for ABI v{version}: the library's layout does not match its version; rebuild it against efsi-law-sdk {CRATE_VERSION}",
                path.display()
            ),
        ));
    }
    let fields = if version == ABI_VERSION {
        // SAFETY: version and size match this crate's definition; it lives as long as
        // `library`.
        Fields::from(unsafe { &*ptr })
    } else {
        // SAFETY: version and size match the frozen version-1 definition; it lives as long as
        // `library`.
        Fields::from(unsafe { &*ptr.cast::<v1::LawDescriptor>() })
    };
    Ok((fields, version))
}

/// The parameter table of descriptor `d`, each entry's strings, uniqueness and default checked.
fn parameters(d: &Fields, path: &Path, law: &str) -> Result<Vec<ParamInfo>, LawError> {
    // SAFETY: descriptor strings are NUL-terminated, live as long as the library (ABI rule).
    let text = |p: *const c_char, what: &str| unsafe { c_text(p, what, law, path) };
    if d.param_desc_size != std::mem::size_of::<ParamDesc>() {
        return Err(fail(
            law,
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
                law,
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
        let info = ParamInfo {
            name: text(p.name, &format!("parameter {k}'s name"))?,
            unit: text(p.unit, "parameter unit")?,
            description: text(p.description, "parameter description")?,
            default: p.default,
            min: p.min,
            max: p.max,
            min_exclusive: p.flags & PARAM_MIN_EXCLUSIVE != 0,
            max_exclusive: p.flags & PARAM_MAX_EXCLUSIVE != 0,
        };
        if parameters.iter().any(|q| q.name == info.name) {
            return Err(fail(
                law,
                format!("declares parameter `{}` twice", info.name),
            ));
        }
        if !info.contains(info.default) {
            return Err(fail(
                law,
                format!(
                    "parameter `{}`'s declared default {} is outside its declared range {}",
                    info.name,
                    super::number(info.default),
                    info.range_text()
                ),
            ));
        }
        parameters.push(info);
    }
    Ok(parameters)
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
