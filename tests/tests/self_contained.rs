//! The repository carries everything its build, tests and xtask read: no source file names a
//! path that leaves the checkout (a clone of the repository alone must test itself), and the
//! reference data resolves inside it.

use efsi_tests::{reference, references_dir, try_reference, workspace_root};
use std::path::{Path, PathBuf};

/// The source-like files of the workspace (code, scenes, manifests, scripts), outside `target/`,
/// `.git/` and the reference data itself.
fn sources(dir: &Path, out: &mut Vec<PathBuf>) {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return;
    };
    for e in entries.flatten() {
        let p = e.path();
        let name = e.file_name().to_string_lossy().into_owned();
        if p.is_dir() {
            if !matches!(
                name.as_str(),
                "target" | ".git" | "out" | "references" | "__pycache__"
            ) && !name.starts_with("wt-")
            {
                sources(&p, out);
            }
        } else if [".rs", ".toml", ".ron", ".py", ".sh", ".cfg", ".ini", ".txt"]
            .iter()
            .any(|ext| name.ends_with(ext))
            || name == "run"
        {
            out.push(p);
        }
    }
}

/// Fragments that would reach outside the repository: the workplace's shared folder beside the
/// checkout, and absolute paths of this machine. Assembled here, so that this file names none of
/// them and is scanned like every other.
fn outside() -> [String; 4] {
    [
        ["..", "shared"].join("/"),
        ["shared", "references"].join("/"),
        ["", "work", ""].join("/"),
        ["EFSI", "REFERENCES"].join("_"),
    ]
}

#[test]
fn no_source_file_names_a_path_outside_the_repository() {
    let root = workspace_root();
    let mut files = Vec::new();
    sources(&root, &mut files);
    assert!(
        files.len() > 50,
        "found only {} source files under {}",
        files.len(),
        root.display()
    );
    let outside = outside();
    let mut found = Vec::new();
    for f in files {
        let Ok(text) = std::fs::read_to_string(&f) else {
            continue;
        };
        for (k, line) in text.lines().enumerate() {
            for frag in &outside {
                if line.contains(frag.as_str()) {
                    found.push(format!("{}:{}: {}", f.display(), k + 1, line.trim()));
                }
            }
        }
    }
    assert!(
        found.is_empty(),
        "paths outside the repository:\n{}",
        found.join("\n")
    );
}

#[test]
fn every_reference_folder_has_its_readme_and_resolves_inside() {
    let dir = references_dir();
    let mut folders = 0;
    for e in std::fs::read_dir(&dir).unwrap().flatten() {
        if e.path().is_dir() {
            folders += 1;
            let name = e.file_name().to_string_lossy().into_owned();
            let readme = reference(&format!("{name}/README.md"));
            let text = std::fs::read_to_string(&readme).unwrap();
            assert!(text.len() > 200, "{} says too little", readme.display());
        }
    }
    assert!(
        folders >= 6,
        "{folders} reference folders in {}",
        dir.display()
    );
}

#[test]
fn a_reference_outside_the_repository_is_refused() {
    let err = try_reference("../../..").unwrap_err();
    assert!(err.contains("outside the repository"), "{err}");
    let err = try_reference("ghia1982/missing.csv").unwrap_err();
    assert!(err.contains("missing.csv"), "{err}");
}
