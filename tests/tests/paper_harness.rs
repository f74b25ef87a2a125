//! The paper harness keeps going when a run fails: the run becomes a failed check naming it and
//! its error, the other runs still run and the case's report is still assembled.

use efsi_tests::paper::case::{self, Case, Done, Harness, Plan, RunResult, Verdict};
use efsi_tests::paper::{Check, Options};

/// Three runs, the second of which fails; the verdict checks how many runs it saw.
struct OneFails {
    /// Whether the verdict needs every run (then it cannot conclude without the failed one).
    needs_all: bool,
}

impl Case for OneFails {
    const NAME: &'static str = "one_fails";
    type Setting = usize;
    type Measured = f64;

    fn plan(_: &Options) -> Plan<Self> {
        let plan = (0..3).map(|n| (format!("run {n}"), n)).collect();
        Ok((OneFails { needs_all: false }, plan))
    }

    fn run(&self, _: &mut Harness, _: &str, &n: &usize) -> RunResult<f64> {
        if n == 1 {
            Err("BiCGSTAB diverged: residual NaN".into())
        } else {
            Ok((None, 10.0 * n as f64))
        }
    }

    fn conclude(&self, _: &mut Harness, done: &mut Done<Self>) -> Result<Verdict, String> {
        if self.needs_all && !done.failed.is_empty() {
            return Err("no finest run".into());
        }
        let sum: f64 = done.measured.iter().map(|(_, m)| m).sum();
        Ok(Verdict {
            title: "one fails".into(),
            reference: String::new(),
            error_metric: String::new(),
            checks: vec![Check::at_most("sum of the runs' values", sum, 20.0, "1")],
            recommendation: String::new(),
        })
    }
}

fn options(tag: &str) -> Options {
    Options {
        quick: true,
        out: std::env::temp_dir().join(format!("efsi-paper-harness-{}-{tag}", std::process::id())),
        progress: false,
        overrides: Vec::new(),
    }
}

#[test]
fn a_failed_run_is_a_failed_check_and_the_others_run() {
    let opts = options("runs");
    let report = case::run::<OneFails>(&opts).expect("the report is assembled");
    let _ = std::fs::remove_dir_all(&opts.out);
    assert_eq!(report.checks.len(), 2);
    // The verdict saw runs 0 and 2 (0 + 20).
    assert_eq!(report.checks[0].value, "20.0");
    assert!(report.checks[0].pass);
    let failed = &report.checks[1];
    assert_eq!(failed.what, "run run 1 completes");
    assert!(failed.value.contains("BiCGSTAB diverged: residual NaN"));
    assert!(!failed.pass);
    assert!(!report.passed());
}

#[test]
fn a_verdict_that_needs_the_failed_run_still_reports() {
    let opts = options("verdict");
    let h = &mut Harness {
        opts: &opts,
        dir: opts.out.clone(),
        plots: Vec::new(),
        notes: Vec::new(),
        schedule: Vec::new(),
    };
    let c = OneFails { needs_all: true };
    let (_, plan) = OneFails::plan(&opts).expect("plan");
    let mut done = c.runs(h, plan).expect("runs");
    assert_eq!(done.failed.len(), 1);
    assert_eq!(done.measured.len(), 2);
    assert!(c.conclude(h, &mut done).is_err());
    // Through the harness: the verdict's error and the run's, both failed checks.
    struct Strict;
    impl Case for Strict {
        const NAME: &'static str = "strict";
        type Setting = usize;
        type Measured = f64;
        fn plan(_: &Options) -> Plan<Self> {
            Ok((Strict, vec![("only".into(), 0)]))
        }
        fn run(&self, _: &mut Harness, _: &str, _: &usize) -> RunResult<f64> {
            Err("unstable run".into())
        }
        fn conclude(&self, _: &mut Harness, _: &mut Done<Self>) -> Result<Verdict, String> {
            Err("no finest run".into())
        }
    }
    let report = case::run::<Strict>(&opts).expect("the report is assembled");
    let _ = std::fs::remove_dir_all(&opts.out);
    let whats: Vec<&str> = report.checks.iter().map(|c| c.what.as_str()).collect();
    assert_eq!(whats, ["run verdict completes", "run only completes"]);
    assert!(report.checks[0].value.contains("no finest run"));
    assert!(report.checks[1].value.contains("unstable run"));
    assert!(report.checks.iter().all(|c| !c.pass));
}
