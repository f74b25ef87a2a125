//! Sugiyama's oscillating Couette flow with a neo-Hookean layer (`cases/oscillating_couette.ron`)
//! against the start-up reference (`tests/references/oscillating_couette/from_rest/`).

use super::case::{Case, Done, Harness, Plan, Verdict, deviation, trade};
use super::plot::Scale;
use super::{Check, Options, Run, load_case};
use efsi_core::{Scene, Simulation};
use efsi_run::{ProfileSpec, SceneOutput};
use std::path::PathBuf;

const TIMES: [f64; 4] = [2.0, 2.8, 4.0, 4.8];

/// What the Couette cases share: grids across the channel, each run's max error of the u
/// profile at `times` against the profiles of `tests/references/<reference>/`.
pub(super) struct Profiles {
    /// Cells across the channel, per run.
    pub grids: &'static [usize],
    /// The times of the profiles.
    pub times: &'static [f64],
    /// The reference's folder under `tests/references/`.
    pub reference: &'static str,
}

impl Profiles {
    /// The runs: a label ("32 cells") and the grid.
    pub fn plan(&self) -> Vec<(String, usize)> {
        self.grids
            .iter()
            .map(|&n| (format!("{n} cells"), n))
            .collect()
    }

    /// Max |u − u_ref| at the grid's u points at each of the times, from the run's profiles
    /// (`profiles/u_t{t}.csv`) against the reference's `u_profile_t_{t}.csv` (columns `y`,
    /// `u`), the reference interpolated linearly.
    pub fn measure(&self, run: &Run) -> Result<Vec<f64>, String> {
        let col = |h: &[String], n: &str| {
            h.iter()
                .position(|x| x == n)
                .ok_or(format!("no column {n}"))
        };
        let mut out = Vec::new();
        for &t in self.times {
            let label = efsi_run::run::time_label(t);
            let (rh, rc) = crate::read_csv(&crate::reference(&format!(
                "{}/u_profile_t_{label}.csv",
                self.reference
            )));
            let (ry, ru) = (&rc[col(&rh, "y")?], &rc[col(&rh, "u")?]);
            let (h, c) = crate::read_csv(&run.dir.join(format!("profiles/u_t{label}.csv")));
            let (y, u) = (&c[col(&h, "y")?], &c[col(&h, "u")?]);
            out.push(deviation(y, u, (ry, ru)));
        }
        Ok(out)
    }

    /// The times as the report lists them ("2, 2.8, 4, 4.8").
    pub fn at(&self) -> String {
        let t: Vec<String> = self.times.iter().map(|t| t.to_string()).collect();
        t.join(", ")
    }

    /// The resolution study: each run's error the largest of its errors at the times (kept per
    /// time as `error_t{t}` metrics), the observed orders between successive runs (as
    /// `observed_order` from the second on); checked: the error at 64 cells at most `limit`,
    /// the smallest order at least `order`. The note and plot of the convergence: `what` the
    /// series, `title` the plot's subject.
    pub fn conclude<C: Case<Measured = Vec<f64>>>(
        &self,
        h: &mut Harness,
        done: &mut Done<C>,
        (limit, order): (f64, f64),
        (what, title): (&str, &str),
    ) -> Vec<Check> {
        let (grids, runs) = (self.grids, &mut done.runs);
        for (run, (_, e)) in runs.iter_mut().zip(&done.measured) {
            run.error = Some(e.iter().copied().fold(0.0, f64::max));
            let at = self.times.iter().zip(e);
            run.metrics = at.map(|(t, e)| (format!("error_t{t}"), *e)).collect();
        }
        let errs: Vec<f64> = runs.iter().map(|r| r.error.unwrap_or(f64::NAN)).collect();
        let orders: Vec<f64> = errs.windows(2).map(|w| (w[0] / w[1]).log2()).collect();
        for (r, p) in runs.iter_mut().skip(1).zip(&orders) {
            r.metrics.push(("observed_order".into(), *p));
        }
        let e64 = runs.iter().find(|r| r.label == "64 cells");
        let checks = vec![
            Check::at_most(
                format!(
                    "64 cells: max abs(u − u_ref) at t = {} (grid points)",
                    self.at()
                ),
                e64.and_then(|r| r.error).unwrap_or(f64::NAN),
                limit,
                "e",
            ),
            Check::at_least(
                format!("observed order over {grids:?} cells (Δt ∝ h), the smallest"),
                orders.iter().copied().fold(f64::MAX, f64::min),
                order,
                "3",
            ),
        ];
        let list =
            |v: &[f64], f: fn(&f64) -> String| v.iter().map(f).collect::<Vec<_>>().join(", ");
        h.notes.push(format!(
            "max errors {} at {grids:?} cells; observed orders {}",
            list(&errs, |e| format!("{e:.3e}")),
            list(&orders, |p| format!("{p:.3}"))
        ));
        let conv = grids.iter().zip(&errs).map(|(&n, &e)| (n as f64, e));
        let axes = (
            &*format!("{title}: error vs cells"),
            "cells across",
            "max abs(u − u_ref)",
        );
        h.figure(
            "convergence",
            axes,
            &[(what.into(), conv.collect())],
            Scale::LogLog,
        );
        checks
    }
}

/// The case: 16, 32, 64 (quick) or 32 … 256 cells across, Δt ∝ h.
pub struct Couette(Profiles);

impl Case for Couette {
    const NAME: &'static str = "oscillating_couette";
    type Setting = usize;
    /// The max error at each of the times.
    type Measured = Vec<f64>;

    fn plan(opts: &Options) -> Plan<Self> {
        let grids: &[usize] = if opts.quick {
            &[16, 32, 64]
        } else {
            &[32, 64, 128, 256]
        };
        let reference = "oscillating_couette/from_rest";
        let case = Couette(Profiles {
            grids,
            times: &TIMES,
            reference,
        });
        let plan = case.0.plan();
        Ok((case, plan))
    }

    fn scene(&self, &n: &usize) -> Result<(Scene, PathBuf), String> {
        let (mut scene, path) = load_case("oscillating_couette.ron")?;
        scene.grid.ny = n;
        // Δt ∝ h (the scene's 0.001 at 64 cells): the elastic step is first order in time.
        scene.time.dt_max = Some(0.001 * 64.0 / n as f64);
        scene.update_output(|o| o.vtk_every = None)?;
        let x = 0.5 * (scene.domain.x.0 + scene.domain.x.1);
        let h = 1.0 / n as f64;
        // The profile at the cell centres, where u lives: no interpolation.
        scene.update_output(|o| {
            o.profiles = vec![ProfileSpec::Line {
                name: "u".into(),
                from: (x, 0.5 * h),
                to: (x, 1.0 - 0.5 * h),
                points: n,
                fields: vec!["u".into()],
                at: TIMES.to_vec(),
            }];
        })?;
        Ok((scene, path))
    }

    fn measure(&self, _: &usize, _: &Simulation, run: &mut Run) -> Result<Vec<f64>, String> {
        self.0.measure(run)
    }

    fn conclude(&self, h: &mut Harness, done: &mut Done<Self>) -> Result<Verdict, String> {
        let what = ("max error over the four times", "Couette");
        let checks = self.0.conclude(h, done, (0.005, 1.0), what);
        let axes = (
            "Couette: error vs wall time",
            "wall time (s)",
            "max abs(u − u_ref)",
        );
        h.figure(
            "tradeoff",
            axes,
            &[trade("grids (Δt ∝ h)", &done.runs)],
            Scale::LogLog,
        );
        Ok(Verdict {
            title: "Sugiyama's oscillating Couette flow, neo-Hookean layer, μ_s = 0".into(),
            reference: "the start-up-from-rest solution of `tests/references/oscillating_couette/from_rest/` (1D FE, 801 nodes), at the grid's u points".into(),
            error_metric: format!("max abs(u − u_ref), t = {}", self.0.at()),
            checks,
            recommendation: "64 cells (Δt = 0.001): 1.5e-3, a third of the target, in a few seconds; the error halves with each doubling (first order: the interface and the elastic step)".into(),
        })
    }
}
