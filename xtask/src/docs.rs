//! `cargo xtask docs [--check | --merge SUMMARY_JSON]`: render the generated section of
//! `docs/benchmarks.md` from the committed benchmark snapshots, or only check that it is what
//! they render ([`xtask::bench_page`]), or first merge the cases of a `bench-paper` run's
//! `summary.json` into the paper snapshot (a run made elsewhere, e.g. in another worktree);
//! and the `--write-docs` of `cargo xtask bench`, which replaces its snapshot by a fresh run's
//! JSON, and of `bench-paper`, which merges the run's cases into its snapshot
//! ([`xtask::bench_page::merge_paper`]), before rendering.

use crate::root;
use std::path::Path;
use xtask::bench_page;

pub(crate) fn docs(args: &[String]) -> Result<(), String> {
    match args {
        [] => {
            let changed = bench_page::write(&root())?;
            eprintln!(
                "{}: {}",
                bench_page::PAGE,
                if changed { "rendered" } else { "unchanged" }
            );
            Ok(())
        }
        [a] if a == "--check" => bench_page::check(&root()),
        [a, path] if a == "--merge" => merge_paper_snapshot(Path::new(path)),
        _ => Err("usage: cargo xtask docs [--check | --merge SUMMARY_JSON]".into()),
    }
}

/// Copy a benchmark's JSON `src` to the snapshot `rel` (relative to the workspace root) and
/// render the page again.
pub(crate) fn snapshot(src: &Path, rel: &str) -> Result<(), String> {
    let to = root().join(rel);
    std::fs::copy(src, &to).map_err(|e| format!("{} → {}: {e}", src.display(), to.display()))?;
    bench_page::write(&root())?;
    eprintln!("{rel} and {}: written", bench_page::PAGE);
    Ok(())
}

/// Merge the cases of a `bench-paper` run's `summary.json` `src` into the snapshot
/// [`bench_page::PAPER_JSON`] ([`bench_page::merge_into_snapshot`]) and render the page again.
pub(crate) fn merge_paper_snapshot(src: &Path) -> Result<(), String> {
    bench_page::merge_into_snapshot(&root(), src)?;
    eprintln!(
        "{} and {}: written",
        bench_page::PAPER_JSON,
        bench_page::PAGE
    );
    Ok(())
}
