//! `cargo xtask docs [--check]`: render the generated section of `docs/benchmarks.md` from the
//! committed benchmark snapshots, or only check that it is what they render
//! ([`xtask::bench_page`]); and the `--write-docs` of `cargo xtask bench` and `bench-paper`,
//! which replace a snapshot by a fresh run's JSON before rendering.

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
        _ => Err("usage: cargo xtask docs [--check]".into()),
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
