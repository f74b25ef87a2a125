//! `cargo xtask bench-paper [--quick] [--case NAME…] [--out DIR] [--set KEY=VALUE…]`: the
//! paper's cases, their accuracy against references and their speed/accuracy trade, as
//! `DIR/REPORT.md`, `DIR/summary.json`, PNG plots and CSV series. `--set` applies a setting to
//! every run's scene (as `efsi run --set` does), e.g. to check the cases with another scheme.

use efsi_tests::paper::{CASES, Options, bench};
use std::path::PathBuf;
use std::process::ExitCode;

fn main() -> ExitCode {
    let mut args = std::env::args().skip(1);
    let mut opts = Options {
        quick: false,
        out: PathBuf::from("target/bench-paper"),
        progress: true,
        overrides: Vec::new(),
    };
    let mut cases = Vec::new();
    while let Some(a) = args.next() {
        match a.as_str() {
            "--quick" => opts.quick = true,
            "--case" => match args.next() {
                Some(c) => cases.push(c),
                None => return usage("--case needs a case name"),
            },
            "--out" => match args.next() {
                Some(d) => opts.out = PathBuf::from(d),
                None => return usage("--out needs a folder"),
            },
            "--no-progress" => opts.progress = false,
            "--set" => match args.next().map(|a| efsi_core::Override::parse(&a)) {
                Some(Ok(o)) => opts.overrides.push(o),
                Some(Err(e)) => return usage(&format!("--set: {e}")),
                None => return usage("--set needs KEY=VALUE"),
            },
            "-h" | "--help" => {
                println!("{}", help());
                return ExitCode::SUCCESS;
            }
            other => return usage(&format!("unknown argument `{other}`")),
        }
    }
    match bench(&opts, &cases) {
        Ok(reports) => {
            println!("report: {}", opts.out.join("REPORT.md").display());
            if reports.iter().all(|r| r.passed()) {
                ExitCode::SUCCESS
            } else {
                println!("some checks failed (see the report)");
                ExitCode::from(1)
            }
        }
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::from(2)
        }
    }
}

fn help() -> String {
    format!(
        "usage: cargo xtask bench-paper [--quick] [--case NAME]… [--out DIR] [--no-progress] \
         [--set KEY=VALUE]…\ncases: {}",
        CASES.iter().map(|c| c.name).collect::<Vec<_>>().join(", ")
    )
}

fn usage(msg: &str) -> ExitCode {
    eprintln!("error: {msg}\n{}", help());
    ExitCode::from(2)
}
