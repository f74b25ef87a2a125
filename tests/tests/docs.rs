//! The documentation cannot drift silently from the repository: every repository path the
//! Markdown pages (README, CHANGELOG, `docs/`, the cases' and the law template's READMEs) name
//! in backticks exists — the architecture page, the map of the code, names most of them — and
//! every relative link of those pages resolves; and the figures of `docs/benchmarks.md` are
//! what its committed snapshots `docs/bench/*.json` render (`cargo xtask docs`).

use efsi_tests::workspace_root;
use std::path::{Path, PathBuf};

/// The top-level entries a repository path starts with (the layout DESIGN.md fixes, with the
/// workspace's own files).
const TOP: [&str; 13] = [
    "core/",
    "plugins/",
    "fmu/",
    "cases/",
    "tests/",
    "xtask/",
    "python/",
    "docs/",
    "tools/",
    ".ci/",
    "Cargo.toml",
    "README.md",
    "CHANGELOG.md",
];

/// The backticked spans of `text` that name a repository path: no whitespace, no placeholder
/// (`<name>`, `*`, `{a,b}`), starting with a top-level entry. A trailing `::item` (a test or a
/// function inside the file) and a `#anchor` are dropped.
fn named_paths(text: &str) -> Vec<String> {
    let mut out = Vec::new();
    for (k, span) in text.split('`').enumerate() {
        if k % 2 == 0 || span.is_empty() {
            continue;
        }
        if span
            .chars()
            .any(|c| c.is_whitespace() || "<>*{}()|,".contains(c))
        {
            continue;
        }
        if !TOP.iter().any(|t| span.starts_with(t)) {
            continue;
        }
        let path = span.split("::").next().unwrap_or(span);
        let path = path.split('#').next().unwrap_or(path);
        out.push(path.to_string());
    }
    out
}

/// The targets of the Markdown links `[text](target)` of `text` that are relative paths (not a
/// URL, not an anchor of the same page), without their `#anchor`.
fn relative_links(text: &str) -> Vec<String> {
    let mut out = Vec::new();
    let mut rest = text;
    while let Some(at) = rest.find("](") {
        rest = &rest[at + 2..];
        let Some(end) = rest.find(')') else { break };
        let target = rest[..end].trim();
        let target = target.split_whitespace().next().unwrap_or("");
        if target.is_empty()
            || target.starts_with('#')
            || target.contains("://")
            || target.starts_with("mailto:")
        {
            continue;
        }
        out.push(target.split('#').next().unwrap_or(target).to_string());
    }
    out
}

/// The Markdown pages whose links are checked.
fn pages(root: &Path) -> Vec<PathBuf> {
    let mut pages = vec![
        root.join("README.md"),
        root.join("CHANGELOG.md"),
        root.join("cases/README.md"),
        root.join("plugins/law-template/README.md"),
    ];
    let mut dirs = vec![root.join("docs")];
    while let Some(dir) = dirs.pop() {
        for e in std::fs::read_dir(&dir)
            .unwrap_or_else(|e| panic!("{}: {e}", dir.display()))
            .flatten()
        {
            let p = e.path();
            if p.is_dir() {
                dirs.push(p);
            } else if p.extension().is_some_and(|x| x == "md") {
                pages.push(p);
            }
        }
    }
    pages
}

#[test]
fn every_path_the_architecture_page_names_exists() {
    let root = workspace_root();
    let page = root.join("docs/architecture.md");
    let text = std::fs::read_to_string(&page).unwrap_or_else(|e| panic!("{}: {e}", page.display()));
    let paths = named_paths(&text);
    // The page walks every crate and the stages' modules: far more than a handful of paths.
    assert!(
        paths.len() >= 60,
        "docs/architecture.md names only {} repository paths in backticks",
        paths.len()
    );
    let missing: Vec<&String> = paths.iter().filter(|p| !root.join(p).exists()).collect();
    assert!(
        missing.is_empty(),
        "docs/architecture.md names paths that do not exist: {missing:?}"
    );
}

#[test]
fn every_path_the_markdown_pages_name_exists() {
    let root = workspace_root();
    let mut missing = Vec::new();
    for page in pages(&root) {
        let text =
            std::fs::read_to_string(&page).unwrap_or_else(|e| panic!("{}: {e}", page.display()));
        for path in named_paths(&text) {
            if !root.join(&path).exists() {
                missing.push(format!("{}: {path}", page.display()));
            }
        }
    }
    assert!(missing.is_empty(), "paths that do not exist: {missing:#?}");
}

#[test]
fn every_relative_link_of_the_markdown_pages_resolves() {
    let root = workspace_root();
    let pages = pages(&root);
    assert!(
        pages.len() >= 9,
        "found only {} Markdown pages",
        pages.len()
    );
    let mut checked = 0;
    let mut broken = Vec::new();
    for page in &pages {
        let text =
            std::fs::read_to_string(page).unwrap_or_else(|e| panic!("{}: {e}", page.display()));
        let dir = page.parent().expect("a page lies in a folder");
        for link in relative_links(&text) {
            checked += 1;
            if !dir.join(&link).exists() {
                broken.push(format!("{}: {link}", page.display()));
            }
        }
    }
    assert!(checked >= 20, "only {checked} relative links found");
    assert!(broken.is_empty(), "links that do not resolve: {broken:#?}");
}

#[test]
fn the_benchmarks_page_is_what_its_json_snapshots_render() {
    let root = workspace_root();
    xtask::bench_page::check(&root).unwrap_or_else(|e| panic!("{e}"));
    // The generated section shows both benchmarks, with where and when they ran.
    let page = std::fs::read_to_string(root.join(xtask::bench_page::PAGE)).expect("the page");
    let start = page
        .find(xtask::bench_page::BEGIN)
        .expect("a generated section");
    let section = &page[start..];
    for heading in [
        "## Speed per stage: measured",
        "## The paper's cases: measured",
    ] {
        assert!(section.contains(heading), "no `{heading}` in the section");
    }
    // Where and when: once for the speed table, once for every paper case.
    let cases = section.matches("\n### ").count();
    assert!(cases >= 1, "{section}");
    assert_eq!(
        section.matches(" at commit ").count(),
        1 + cases,
        "{section}"
    );
    // A page whose figures differ from the snapshots' is refused.
    let edited = page.replacen("| case | threads |", "| case | thread |", 1);
    assert_ne!(
        edited, page,
        "the speed table's header is where the test expects it"
    );
    let dir = std::env::temp_dir().join(format!("efsi-docs-check-{}", std::process::id()));
    std::fs::create_dir_all(dir.join("docs/bench")).expect("a scratch folder");
    std::fs::write(dir.join(xtask::bench_page::PAGE), &edited).expect("the edited page");
    for snapshot in [xtask::bench_page::BENCH_JSON, xtask::bench_page::PAPER_JSON] {
        std::fs::copy(root.join(snapshot), dir.join(snapshot)).expect("a snapshot");
    }
    let refused = xtask::bench_page::check(&dir);
    std::fs::remove_dir_all(&dir).ok();
    let message = refused.expect_err("an edited figure is refused");
    assert!(message.contains("cargo xtask docs"), "{message}");
}

#[test]
fn the_path_and_link_scanners_find_what_they_should() {
    let text = "`core/efsi-core/src/grid.rs` `efsi run SCENE` `fields/<name>.vtr` \
                `Stage::save` `tests/tests/contact.rs::name` `cases/`";
    assert_eq!(
        named_paths(text),
        [
            "core/efsi-core/src/grid.rs",
            "tests/tests/contact.rs",
            "cases/"
        ]
    );
    let md = "[a](docs/scenes.md#overrides) [b](https://example.org) [c](#top) [d](../README.md)";
    assert_eq!(relative_links(md), ["docs/scenes.md", "../README.md"]);
}
