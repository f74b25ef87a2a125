//! The layers of the workspace, read from `cargo metadata`: no crate of the framework (`core/`)
//! depends on a crate under `plugins/` (as a dependency of any kind), and the front ends are
//! the crates that compose the two.

use serde_json::Value;
use std::path::{Path, PathBuf};
use std::process::Command;

/// The workspace's packages as `cargo metadata --no-deps` lists them (each with its declared
/// dependencies, a path dependency with its folder).
fn packages() -> (PathBuf, Vec<Value>) {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"))
        .parent()
        .unwrap()
        .to_path_buf();
    let cargo = std::env::var("CARGO").unwrap_or_else(|_| "cargo".into());
    let out = Command::new(cargo)
        .args([
            "metadata",
            "--format-version",
            "1",
            "--no-deps",
            "--offline",
        ])
        .current_dir(&root)
        .output()
        .expect("cargo metadata runs");
    assert!(
        out.status.success(),
        "cargo metadata: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    let meta: Value = serde_json::from_slice(&out.stdout).unwrap();
    (root, meta["packages"].as_array().unwrap().clone())
}

/// The folder of the workspace (relative to `root`) that `path` is in: `core`, `plugins`, …
fn layer(root: &Path, path: &str) -> String {
    Path::new(path)
        .strip_prefix(root)
        .ok()
        .and_then(|p| p.components().next())
        .map(|c| c.as_os_str().to_string_lossy().into_owned())
        .unwrap_or_default()
}

/// Each package's layer and the layers of its path dependencies: (package, layer, dependency,
/// its layer).
fn edges() -> Vec<(String, String, String, String)> {
    let (root, packages) = packages();
    let mut edges = Vec::new();
    for p in &packages {
        let name = p["name"].as_str().unwrap().to_string();
        let dir = Path::new(p["manifest_path"].as_str().unwrap())
            .parent()
            .unwrap();
        let from = layer(&root, &dir.to_string_lossy());
        for d in p["dependencies"].as_array().unwrap() {
            if let Some(path) = d["path"].as_str() {
                let to = layer(&root, path);
                edges.push((
                    name.clone(),
                    from.clone(),
                    d["name"].as_str().unwrap().into(),
                    to,
                ));
            }
        }
    }
    edges
}

#[test]
fn no_crate_of_the_framework_depends_on_a_plugin_crate() {
    let edges = edges();
    // The graph was read: the framework's crates depend on one another.
    assert!(
        edges
            .iter()
            .any(|(p, from, d, _)| p == "efsi-run" && from == "core" && d == "efsi-core"),
        "{edges:?}"
    );
    let wrong: Vec<String> = edges
        .iter()
        .filter(|(_, from, _, to)| from == "core" && to == "plugins")
        .map(|(p, _, d, _)| format!("{p} (core/) → {d} (plugins/)"))
        .collect();
    assert!(
        wrong.is_empty(),
        "the framework (core/) may not depend on a plugin crate (plugins/); a front end (the \
         root package `efsi`, fmu/, python/) composes them: {wrong:?}"
    );
}

#[test]
fn the_front_ends_compose_the_framework_with_the_shipped_plugins() {
    let edges = edges();
    for front in ["efsi", "efsi-fmu", "efsi-python"] {
        for dep in ["efsi-core", "efsi-run", "efsi-stages"] {
            assert!(
                edges.iter().any(|(p, _, d, _)| p == front && d == dep),
                "{front} should depend on {dep}: {edges:?}"
            );
        }
    }
    // The CLI is the workspace's root package.
    assert!(
        edges
            .iter()
            .any(|(p, from, _, _)| p == "efsi" && from.is_empty()),
        "{edges:?}"
    );
}
