//! Sugiyama's oscillating Couette flow with a neo-Hookean layer (`cases/oscillating_couette.ron`)
//! against the start-up reference (`tests/references/oscillating_couette/from_rest/`).

use super::case::{Case, Done, Harness, Plan, Verdict, deviation, trade};
use super::plot::Scale;
use super::{Check, Options, Run, load_case};
use efsi_core::{Scene, Simulation};
use efsi_run::{ProfileSpec, SceneOutput};
use std::path::PathBuf;

const TIMES: [f64; 4] = [2.0, 2.8, 4.0, 4.8];

/// What the Couette cases share: grids across the channel with Δt ∝ h (the combined series),
/// a time series (one grid, Δt halved twice) and a space series (the grids at the smallest Δt),
/// each run's max error of the u profile at `times` against the profiles of
/// `tests/references/<reference>/`.
pub(super) struct Profiles {
    /// Cells across the channel, per run of the combined series (Δt ∝ h).
    pub grids: &'static [usize],
    /// The times of the profiles.
    pub times: &'static [f64],
    /// The reference's folder under `tests/references/`.
    pub reference: &'static str,
    /// Δt at 64 cells; a grid of n cells runs at `dt64 · 64/n` in the combined series.
    pub dt64: f64,
}

/// The Couette cases' viscous step: Crank–Nicolson (`numerics.viscous.theta` ½) instead of the
/// default backward Euler, whose `O(Δt)` error in the fluid layer is what a second-order
/// elastic step would otherwise leave (with the elastic step's stress and the interface
/// corners' relaxation at θ → ½, the 64-cell error moves by 2 % from Δt = 1e-3 to 2.5e-4 with
/// it and by 2× with backward Euler). Only the benchmark's scenes take it: the default stays
/// the seed's (fluid-only scenes are unchanged). And the `Strict` preset's solver tolerances: at
/// 256 cells the default ones (viscous 1e-3, elastic 1e-6) are the larger part of the error
/// (neo-Hookean, Δt = 2.5e-4: 1.15e-4 at the default, 5.4e-5 strict).
pub(super) fn couette_numerics(scene: &mut Scene) {
    scene.numerics.preset = efsi_core::scene::Preset::Strict;
    scene.numerics.set(&efsi_stages::viscous::ViscousOptions {
        theta: 0.5,
        ..Default::default()
    });
}

/// One run of a Couette case: cells across and Δt.
pub type Setting = (usize, f64);

/// What one run shows: the max error at each time, and the profile u at each time (at the
/// grid's u points).
pub struct Measured {
    /// Max abs(u − u_ref) at each time.
    pub errors: Vec<f64>,
    /// u at the grid's u points, at each time.
    pub u: Vec<Vec<f64>>,
}

/// The orders of a Couette case, from its three series.
struct Orders {
    /// Combined (Δt ∝ h): (cells, Δt, error) per grid, and the order between successive grids.
    combined: Vec<(usize, f64, f64)>,
    combined_orders: Vec<f64>,
    /// Time: the grid, its Δt's and `max |u(Δt) − u(Δt/2)|` for the two pairs; the order.
    time: Option<(usize, [f64; 3], [f64; 2], f64)>,
    /// Space (at the smallest Δt): (cells, error) per grid and the order between successive ones.
    space_dt: f64,
    space: Vec<(usize, f64)>,
    space_orders: Vec<f64>,
}

impl Profiles {
    /// Δt of the combined series at `n` cells.
    fn dt(&self, n: usize) -> f64 {
        self.dt64 * 64.0 / n as f64
    }

    /// The grid of the time series: the combined series' coarsest (the self-differences of its
    /// runs hold no space error, and it is the cheapest).
    fn time_grid(&self) -> usize {
        self.grids[0]
    }

    /// The smallest Δt of the combined series (its finest grid's): the space series' Δt.
    fn space_dt(&self) -> f64 {
        self.grids
            .iter()
            .map(|&n| self.dt(n))
            .fold(f64::MAX, f64::min)
    }

    /// The runs: the combined series ("32 cells", Δt ∝ h), then the time series' extra runs
    /// ("32 cells, Δt/2", "…/4") and the space series' ("32 cells, Δt = …"), each (n, Δt) once.
    pub fn plan(&self) -> Vec<(String, Setting)> {
        let mut plan: Vec<(String, Setting)> = self
            .grids
            .iter()
            .map(|&n| (format!("{n} cells"), (n, self.dt(n))))
            .collect();
        let same = |a: f64, b: f64| (a - b).abs() <= 1e-9 * b;
        let mut add = |label: String, n: usize, dt: f64| {
            if !plan.iter().any(|(_, (m, d))| *m == n && same(*d, dt)) {
                plan.push((label, (n, dt)));
            }
        };
        let g = self.time_grid();
        for k in [2, 4] {
            add(format!("{g} cells, Δt/{k}"), g, self.dt(g) / k as f64);
        }
        let dts = self.space_dt();
        for &n in self.grids {
            add(format!("{n} cells, Δt = {dts:e}"), n, dts);
        }
        plan
    }

    /// Max |u − u_ref| at the grid's u points at each of the times, from the run's profiles
    /// (`profiles/u_t{t}.csv`) against the reference's `u_profile_t_{t}.csv` (columns `y`,
    /// `u`), the reference interpolated linearly; and the run's profiles.
    pub fn measure(&self, run: &Run) -> Result<Measured, String> {
        let col = |h: &[String], n: &str| {
            h.iter()
                .position(|x| x == n)
                .ok_or(format!("no column {n}"))
        };
        let mut out = Measured {
            errors: Vec::new(),
            u: Vec::new(),
        };
        for &t in self.times {
            let label = efsi_run::run::time_label(t);
            let (rh, rc) = crate::read_csv(&crate::reference(&format!(
                "{}/u_profile_t_{label}.csv",
                self.reference
            )));
            let (ry, ru) = (&rc[col(&rh, "y")?], &rc[col(&rh, "u")?]);
            let (h, c) = crate::read_csv(&run.dir.join(format!("profiles/u_t{label}.csv")));
            let (y, u) = (&c[col(&h, "y")?], &c[col(&h, "u")?]);
            out.errors.push(deviation(y, u, (ry, ru)));
            out.u.push(u.clone());
        }
        Ok(out)
    }

    /// The times as the report lists them ("2, 2.8, 4, 4.8").
    pub fn at(&self) -> String {
        let t: Vec<String> = self.times.iter().map(|t| t.to_string()).collect();
        t.join(", ")
    }

    /// The three series' errors and observed orders from the runs.
    fn orders(&self, measured: &[(Setting, Measured)]) -> Orders {
        let err = |m: &Measured| m.errors.iter().copied().fold(0.0, f64::max);
        let same = |a: f64, b: f64| (a - b).abs() <= 1e-9 * b;
        let find = |n: usize, dt: f64| {
            measured
                .iter()
                .find(|((m, d), _)| *m == n && same(*d, dt))
                .map(|(_, x)| x)
        };
        let log2 = |w: &[f64]| (w[0] / w[1]).log2();
        let combined: Vec<(usize, f64, f64)> = self
            .grids
            .iter()
            .filter_map(|&n| find(n, self.dt(n)).map(|m| (n, self.dt(n), err(m))))
            .collect();
        let e: Vec<f64> = combined.iter().map(|c| c.2).collect();
        let combined_orders = e.windows(2).map(log2).collect();
        let g = self.time_grid();
        let dts = [self.dt(g), self.dt(g) / 2.0, self.dt(g) / 4.0];
        let time = match dts.map(|dt| find(g, dt)) {
            [Some(a), Some(b), Some(c)] => {
                let diff = |p: &Measured, q: &Measured| {
                    p.u.iter()
                        .zip(&q.u)
                        .flat_map(|(x, y)| x.iter().zip(y).map(|(a, b)| (a - b).abs()))
                        .fold(0.0, f64::max)
                };
                let d = [diff(a, b), diff(b, c)];
                Some((g, dts, d, log2(&d)))
            }
            _ => None,
        };
        let space_dt = self.space_dt();
        let space: Vec<(usize, f64)> = self
            .grids
            .iter()
            .filter_map(|&n| find(n, space_dt).map(|m| (n, err(m))))
            .collect();
        let es: Vec<f64> = space.iter().map(|s| s.1).collect();
        let space_orders = es.windows(2).map(log2).collect();
        Orders {
            combined,
            combined_orders,
            time,
            space_dt,
            space,
            space_orders,
        }
    }

    /// The resolution study: each run's error the largest of its errors at the times (kept per
    /// time as `error_t{t}` metrics, with the cost per step as `us_per_step`); the observed
    /// orders of the three series (combined with Δt ∝ h, time at one grid, space at the
    /// smallest Δt) in the notes; checked: the error at 64 cells (Δt ∝ h) at most `limit`, the
    /// smallest combined order at least `order`. The note and plot of the convergence: `what`
    /// the series, `title` the plot's subject. Returns the checks and the recommendation,
    /// computed from the figures.
    pub fn conclude<C: Case<Setting = Setting, Measured = Measured>>(
        &self,
        h: &mut Harness,
        done: &mut Done<C>,
        (limit, order): (f64, f64),
        (what, title): (&str, &str),
    ) -> (Vec<Check>, String) {
        let runs = &mut done.runs;
        for (run, (_, m)) in runs.iter_mut().zip(&done.measured) {
            run.error = Some(m.errors.iter().copied().fold(0.0, f64::max));
            let at = self.times.iter().zip(&m.errors);
            run.metrics = at.map(|(t, e)| (format!("error_t{t}"), *e)).collect();
            let per_step = 1e6 * run.wall_seconds / run.steps.max(1) as f64;
            run.metrics.push(("us_per_step".into(), per_step));
        }
        let o = self.orders(&done.measured);
        let grids: Vec<usize> = o.combined.iter().map(|c| c.0).collect();
        let e64 = o
            .combined
            .iter()
            .find(|c| c.0 == 64)
            .map_or(f64::NAN, |c| c.2);
        let smallest = |v: &[f64]| v.iter().copied().fold(f64::MAX, f64::min);
        let checks = vec![
            Check::at_most(
                format!(
                    "64 cells: max abs(u − u_ref) at t = {} (grid points)",
                    self.at()
                ),
                e64,
                limit,
                "e",
            ),
            Check::at_least(
                format!("observed order over {grids:?} cells (Δt ∝ h), the smallest"),
                smallest(&o.combined_orders),
                order,
                "3",
            ),
        ];
        let list =
            |v: &[f64], f: fn(&f64) -> String| v.iter().map(f).collect::<Vec<_>>().join(", ");
        let errs: Vec<f64> = o.combined.iter().map(|c| c.2).collect();
        h.notes.push(format!(
            "combined (Δt ∝ h): max errors {} at {grids:?} cells; observed orders {}",
            list(&errs, |e| format!("{e:.3e}")),
            list(&o.combined_orders, |p| format!("{p:.3}"))
        ));
        if let Some((g, dts, d, p)) = o.time {
            h.notes.push(format!(
                "time ({g} cells, Δt = {:.3e}, {:.3e}, {:.3e}): max abs(u(Δt) − u(Δt/2)) {:.3e}, \
                 {:.3e}; observed time order {p:.3}; time error at Δt ≈ {:.3e}",
                dts[0],
                dts[1],
                dts[2],
                d[0],
                d[1],
                d[0] * 2f64.powf(p) / (2f64.powf(p) - 1.0)
            ));
        }
        let es: Vec<f64> = o.space.iter().map(|s| s.1).collect();
        let sg: Vec<usize> = o.space.iter().map(|s| s.0).collect();
        h.notes.push(format!(
            "space (Δt = {:.3e}): max errors {} at {sg:?} cells; observed space orders {}",
            o.space_dt,
            list(&es, |e| format!("{e:.3e}")),
            list(&o.space_orders, |p| format!("{p:.3}"))
        ));
        let combined_runs = runs
            .iter()
            .filter(|r| grids.iter().any(|n| r.label == format!("{n} cells")));
        let cost: Vec<String> = combined_runs
            .map(|r| {
                format!(
                    "{}: {:.0} µs a step ({} steps)",
                    r.label,
                    1e6 * r.wall_seconds / r.steps.max(1) as f64,
                    r.steps
                )
            })
            .collect();
        h.notes.push(format!("cost per step: {}", cost.join("; ")));
        let conv = o.combined.iter().map(|&(n, _, e)| (n as f64, e));
        let space = o.space.iter().map(|&(n, e)| (n as f64, e));
        let axes = (
            &*format!("{title}: error vs cells"),
            "cells across",
            "max abs(u − u_ref)",
        );
        h.figure(
            "convergence",
            axes,
            &[
                (format!("{what}, Δt ∝ h"), conv.collect()),
                (format!("Δt = {:.3e}", o.space_dt), space.collect()),
            ],
            Scale::LogLog,
        );
        (checks, self.recommend(&o, runs))
    }

    /// The recommendation, from the combined series' figures: the 64-cell run's error and wall
    /// time (the check's grid), the finest grid's, and the grid a target error ε takes at the
    /// last observed order.
    fn recommend(&self, o: &Orders, runs: &[Run]) -> String {
        let wall = |n: usize| {
            runs.iter()
                .find(|r| r.label == format!("{n} cells"))
                .map_or(f64::NAN, |r| r.wall_seconds)
        };
        let Some(&(n, dt, e)) = o.combined.iter().find(|c| c.0 == 64).or(o.combined.first()) else {
            return "no run finished".into();
        };
        let p = o.combined_orders.last().copied().unwrap_or(f64::NAN);
        let finest = o.combined.last().map_or(n, |c| c.0);
        let ef = o.combined.last().map_or(e, |c| c.2);
        let finer = if finest == n {
            String::new()
        } else {
            format!("; {finest} cells: {ef:.2e} in {:.1} s", wall(finest))
        };
        format!(
            "{n} cells (Δt = {dt:.1e}): {e:.2e} in {:.1} s{finer}. Between the two finest grids \
             the error falls by 2^{p:.2} = {:.2}× per halving of h and Δt, so an error ε takes \
             about {finest}·({ef:.2e}/ε)^(1/{p:.2}) cells",
            wall(n),
            2f64.powf(p)
        )
    }
}

/// The case: 16, 32, 64 (quick) or 32 … 256 cells across, Δt ∝ h, and the time and space
/// series of `Profiles::plan`.
pub struct Couette(Profiles);

impl Case for Couette {
    const NAME: &'static str = "oscillating_couette";
    type Setting = Setting;
    /// The max error and the profile at each of the times.
    type Measured = Measured;

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
            dt64: 0.001,
        });
        let plan = case.0.plan();
        Ok((case, plan))
    }

    fn scene(&self, &(n, dt): &Setting) -> Result<(Scene, PathBuf), String> {
        let (mut scene, path) = load_case("oscillating_couette.ron")?;
        scene.grid.ny = n;
        scene.time.dt_max = Some(dt);
        couette_numerics(&mut scene);
        scene.update_output(|o| o.vtk_every = None)?;
        let x = 0.5 * (scene.domain.x.0 + scene.domain.x.1);
        let h = 1.0 / n as f64;
        // The profile at the cell centres, where u lives: no interpolation.
        scene.update_output(|o| {
            o.profiles = vec![ProfileSpec::Line {
                name: "u".into(),
                from: (x, 0.5 * h).into(),
                to: (x, 1.0 - 0.5 * h).into(),
                points: n,
                fields: vec!["u".into()],
                at: TIMES.to_vec(),
            }];
        })?;
        Ok((scene, path))
    }

    fn measure(&self, _: &Setting, _: &Simulation, run: &mut Run) -> Result<Measured, String> {
        self.0.measure(run)
    }

    fn conclude(&self, h: &mut Harness, done: &mut Done<Self>) -> Result<Verdict, String> {
        let what = ("max error over the four times", "Couette");
        // Issue 43's bounds: the 64-cell error no worse than the first-order scheme's 7.1e-4,
        // the smallest combined order at least 1.5.
        let (checks, recommendation) = self.0.conclude(h, done, (7.1e-4, 1.5), what);
        let axes = (
            "Couette: error vs wall time",
            "wall time (s)",
            "max abs(u − u_ref)",
        );
        h.figure(
            "tradeoff",
            axes,
            &[trade("runs", &done.runs)],
            Scale::LogLog,
        );
        Ok(Verdict {
            title: "Sugiyama's oscillating Couette flow, neo-Hookean layer, μ_s = 0".into(),
            reference: "the start-up-from-rest solution of `tests/references/oscillating_couette/from_rest/` (1D FE, 801 nodes), at the grid's u points".into(),
            error_metric: format!("max abs(u − u_ref), t = {}", self.0.at()),
            checks,
            recommendation,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Max abs(u − u_ref) at t = 1 at the cell centres of the Couette case at `n` cells, with
    /// the combined series' Δt (∝ h) and numerics.
    fn error_at_1(n: usize) -> f64 {
        let reference = "oscillating_couette/from_rest";
        let case = Couette(Profiles {
            grids: &[],
            times: &[1.0],
            reference,
            dt64: 0.001,
        });
        let (mut scene, path) = case.scene(&(n, case.0.dt(n))).unwrap();
        scene.output = Default::default();
        let mut sim = efsi_run::simulation(scene, &path, &efsi_stages::builtin())
            .unwrap_or_else(|e| panic!("{e}"));
        crate::run_until(&mut sim, 1.0, |_, _| {});
        let h = 1.0 / n as f64;
        let y: Vec<f64> = (0..n).map(|j| (j as f64 + 0.5) * h).collect();
        let u: Vec<f64> = (0..n as isize).map(|j| sim.state.u[(0, j)]).collect();
        let (rh, rc) =
            crate::read_csv(&crate::reference(&format!("{reference}/u_profile_t_1.csv")));
        let col = |name: &str| &rc[rh.iter().position(|c| c == name).unwrap()];
        deviation(&y, &u, (col("y"), col("u")))
    }

    /// The start-up front the impulsive start sends through the inviscid layer converges at
    /// second order already at 16 and 32 cells: with the two-point shear gradient its
    /// dispersion made the error first order (3.10e-3, 1.58e-3: order 0.97), with the bulk
    /// four-point gradient 2.03e-3, 4.95e-4 (order 2.04).
    #[test]
    fn couette_converges_at_second_order_on_coarse_grids() {
        let e = [error_at_1(16), error_at_1(32)];
        let order = (e[0] / e[1]).log2();
        eprintln!(
            "t = 1: max errors {:.3e}, {:.3e}; order {order:.3}",
            e[0], e[1]
        );
        assert!(e[1] <= 6e-4, "32 cells: {:.3e}", e[1]);
        assert!(order >= 1.8, "order {order:.3}");
    }
}
