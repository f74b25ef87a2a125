//! Sugiyama's oscillating Couette flow with a neo-Hookean layer (`cases/oscillating_couette.ron`)
//! against the start-up reference (`tests/references/oscillating_couette/from_rest/`).

use super::case::{Case, Done, Harness, Verdict, trade};
use super::plot::Scale;
use super::{Check, Options, Run, load_case};
use efsi_core::Scene;
use efsi_core::scene::ProfileSpec;
use std::path::PathBuf;

const TIMES: [f64; 4] = [2.0, 2.8, 4.0, 4.8];

/// The case: grids of 16, 32, 64 (quick) or 32 … 256 cells across, Δt ∝ h.
pub struct Couette {
    grids: &'static [usize],
}

impl Case for Couette {
    const NAME: &'static str = "oscillating_couette";
    type Setting = usize;
    /// The max error at each of [`TIMES`].
    type Measured = Vec<f64>;

    fn new(opts: &Options) -> Result<Self, String> {
        Ok(Couette {
            grids: if opts.quick {
                &[16, 32, 64]
            } else {
                &[32, 64, 128, 256]
            },
        })
    }

    fn settings(&self) -> Vec<usize> {
        self.grids.to_vec()
    }

    fn label(&self, n: &usize) -> String {
        format!("{n} cells")
    }

    fn scene(&self, &n: &usize) -> Result<(Scene, PathBuf), String> {
        let (mut scene, path) = load_case("oscillating_couette.ron")?;
        scene.grid.ny = n;
        // Δt ∝ h (the scene's 0.001 at 64 cells): the elastic step is first order in time.
        scene.time.dt_max = Some(0.001 * 64.0 / n as f64);
        scene.output.vtk_every = None;
        let x = 0.5 * (scene.domain.x.0 + scene.domain.x.1);
        let h = 1.0 / n as f64;
        // The profile at the cell centres, where u lives: no interpolation.
        scene.output.profiles = vec![ProfileSpec::Line {
            name: "u".into(),
            from: (x, 0.5 * h),
            to: (x, 1.0 - 0.5 * h),
            points: n,
            fields: vec!["u".into()],
            at: TIMES.to_vec(),
        }];
        Ok((scene, path))
    }

    fn measure(
        &self,
        _: &usize,
        _: &efsi_core::Simulation,
        run: &mut Run,
    ) -> Result<Vec<f64>, String> {
        super::profile_errors(run, "oscillating_couette/from_rest", &TIMES)
    }

    fn conclude(&self, h: &mut Harness, done: &mut Done<Self>) -> Result<Verdict, String> {
        let (errs, orders, e64) = profile_study(done, &TIMES);
        let grids = self.grids;
        let checks = vec![
            Check::at_most(
                "64 cells: max abs(u − u_ref) at t = 2, 2.8, 4, 4.8 (grid points)",
                e64,
                0.005,
                "e",
            ),
            Check::at_least(
                format!("observed order over {grids:?} cells (Δt ∝ h), the smallest"),
                orders.iter().copied().fold(f64::MAX, f64::min),
                1.0,
                "3",
            ),
        ];
        let (note, conv) =
            super::convergence("max error over the four times", grids, &errs, &orders);
        h.notes.push(note);
        let tradeoff = vec![trade("grids (Δt ∝ h)", &done.runs)];
        for (file, title, x, series) in [
            (
                "convergence",
                "Couette: error vs cells",
                "cells across",
                conv,
            ),
            (
                "tradeoff",
                "Couette: error vs wall time",
                "wall time (s)",
                tradeoff,
            ),
        ] {
            h.figure(
                file,
                (title, x, "max abs(u − u_ref)"),
                &series,
                Scale::LogLog,
            );
        }
        Ok(Verdict {
            title: "Sugiyama's oscillating Couette flow, neo-Hookean layer, μ_s = 0".into(),
            reference: "the start-up-from-rest solution of `tests/references/oscillating_couette/from_rest/` (1D FE, 801 nodes), at the grid's u points".into(),
            error_metric: "max abs(u − u_ref), t = 2, 2.8, 4, 4.8".into(),
            checks,
            recommendation: "64 cells (Δt = 0.001): 1.5e-3, a third of the target, in a few seconds; the error halves with each doubling (first order: the interface and the elastic step)".into(),
        })
    }
}

/// [`super::study`] over the runs of a Couette case whose measurement is the profile errors at
/// `times`: the errors, the observed orders and the error at 64 cells.
pub(super) fn profile_study<C, T>(done: &mut Done<C>, times: &[T]) -> (Vec<f64>, Vec<f64>, f64)
where
    C: Case<Measured = Vec<f64>>,
    T: std::fmt::Display,
{
    let per_run: Vec<Vec<f64>> = done.measured.iter().map(|(_, e)| e.clone()).collect();
    super::study(&mut done.runs, &per_run, times)
}
