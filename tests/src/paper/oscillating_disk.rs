//! Seed §5.4 (after Robinson-Mosher, Schroeder & Fedkiw 2011): a neo-Hookean disk in a
//! decaying vortex (`cases/oscillating_disk.ron`). The fluid and the disk start from the
//! velocity of ψ = a sin(2πx) sin(2πy); the disk is squeezed, stores the flow's energy as
//! elastic energy (largest near t = 0.2, the seed's "maximum deformation"), gives it back, and
//! the exchange repeats while viscosity drains the total.
//!
//! Checked: the discrete initial kinetic energy against the exact a²(kx² + ky²)/8 (0.0246740)
//! and its order of convergence; the kinetic energy decays and oscillates; the elastic energy
//! peaks near t = 0.2; the solid volume is conserved. The speed/accuracy error is the kinetic
//! energy history against the finest grid's.

use super::case::{
    Case, Done, Harness, Plan, Verdict, deviation, drift, drift_check, largest_ratio, trade, xy,
};
use super::plot::Scale;
use super::{Check, Options, Run, Series, load_case, probes};
use efsi_core::scene::InitialVelocity;
use efsi_core::{Scene, Simulation};
use efsi_run::SceneOutput;
use efsi_stages::solid::SceneSolid;
use std::path::PathBuf;

/// The time the seed gives for the largest deformation.
const T_PEAK_SEED: f64 = 0.2;

/// What one run shows.
#[derive(Clone, Debug, Default)]
pub struct History {
    t: Vec<f64>,
    kinetic: Vec<f64>,
    elastic: Vec<f64>,
    /// Local extrema of the kinetic energy: (time, value, is a maximum).
    extrema: Vec<(f64, f64, bool)>,
    /// When the elastic energy is largest, and its value.
    t_elastic_peak: f64,
    elastic_peak: f64,
    volume_drift: f64,
}

/// Local extrema of `y(t)`: a sample that is the largest (smallest) within ±`w` samples,
/// away from the ends.
fn extrema(t: &[f64], y: &[f64], w: usize) -> Vec<(f64, f64, bool)> {
    let mut out = Vec::new();
    for k in w..y.len().saturating_sub(w) {
        let win = &y[k - w..=k + w];
        if win.iter().all(|&v| v <= y[k]) && win.iter().filter(|&&v| v == y[k]).count() == 1 {
            out.push((t[k], y[k], true));
        } else if win.iter().all(|&v| v >= y[k]) && win.iter().filter(|&&v| v == y[k]).count() == 1
        {
            out.push((t[k], y[k], false));
        }
    }
    out
}

fn analyse(run: &Run) -> Result<History, String> {
    let p = probes(&run.dir)?;
    let t = p.col("t")?.to_vec();
    let kinetic = p.col("kinetic_energy")?.to_vec();
    let elastic = p.col("elastic_energy")?.to_vec();
    let vol = p.col("solid_volume")?;
    if t.len() < 3 {
        return Err(format!("{}: too few probe samples", run.label));
    }
    let k = (0..elastic.len())
        .max_by(|&a, &b| elastic[a].total_cmp(&elastic[b]))
        .unwrap_or(0);
    Ok(History {
        extrema: extrema(&t, &kinetic, 2),
        t_elastic_peak: t[k],
        elastic_peak: elastic[k],
        volume_drift: drift(vol),
        t,
        kinetic,
        elastic,
    })
}

/// The case: 24², 32², 48² to t = 0.5 (quick) or 32² … 192² to t = 1 and 64² with a purely
/// elastic solid.
pub struct OscillatingDisk {
    grids: &'static [usize],
    end: f64,
    quick: bool,
    /// The exact initial kinetic energy.
    ke_exact: f64,
}

impl Case for OscillatingDisk {
    const NAME: &'static str = "oscillating_disk";
    /// The grid, and the solid viscosity if not the scene's.
    type Setting = (usize, Option<f64>);
    type Measured = History;

    fn plan(opts: &Options) -> Plan<Self> {
        let (grids, end): (&[usize], f64) = if opts.quick {
            (&[24, 32, 48], 0.5)
        } else {
            (&[32, 64, 128, 192], 1.0)
        };
        let (base, _) = load_case("oscillating_disk.ron")?;
        let InitialVelocity::SinSinStream {
            amplitude,
            wavenumbers: (kx, ky),
        } = base.initial_velocity
        else {
            return Err("the scene's initial velocity is not a SinSinStream".into());
        };
        // ½∫(u² + v²) over [0, 1]² with u = a ky sin(kx x) cos(ky y), v = −a kx cos(kx x) sin(ky y)
        // (kx, ky multiples of 2π).
        let ke_exact = amplitude * amplitude * (kx * kx + ky * ky) / 8.0;
        let quick = opts.quick;
        let mut plan: Vec<_> = grids
            .iter()
            .map(|&n| (format!("{n}²"), (n, None)))
            .collect();
        if !quick {
            // Sensitivity to the solid viscosity: the purely elastic solid of Robinson-Mosher et al.
            let mu_s = 0.0;
            plan.push((format!("64², μ_s = {mu_s}"), (64, Some(mu_s))));
        }
        let case = OscillatingDisk {
            grids,
            end,
            quick,
            ke_exact,
        };
        Ok((case, plan))
    }

    fn folder(&self, label: &str, _: &(usize, Option<f64>)) -> String {
        super::slug(&label.replace('²', ""))
    }

    fn scene(&self, &(n, mu_s): &(usize, Option<f64>)) -> Result<(Scene, PathBuf), String> {
        let (mut scene, path) = load_case("oscillating_disk.ron")?;
        scene.grid.nx = n;
        scene.grid.ny = n;
        scene.time.end = self.end;
        scene.update_output(|o| o.probe_every = Some(0.005))?;
        if self.quick || n != self.grids[self.grids.len() - 1] {
            scene.update_output(|o| o.vtk_every = None)?;
        }
        if let Some(m) = mu_s {
            scene.update_solid(|solid| solid.viscosity = Some(m))?;
        }
        Ok((scene, path))
    }

    fn measure(
        &self,
        _: &(usize, Option<f64>),
        _: &Simulation,
        run: &mut Run,
    ) -> Result<History, String> {
        analyse(run)
    }

    fn conclude(&self, h: &mut Harness, done: &mut Done<Self>) -> Result<Verdict, String> {
        let (end, ke_exact) = (self.end, self.ke_exact);
        let finest = self.grids[self.grids.len() - 1];
        // Errors against the finest grid's kinetic energy history, relative to the exact KE(0).
        let reference = done
            .measured
            .iter()
            .find(|((n, mu_s), _)| *n == finest && mu_s.is_none())
            .map(|(_, h)| h.clone())
            .ok_or("no finest run")?;
        for (r, ((n, _), h)) in done.runs.iter_mut().zip(&done.measured) {
            let e = deviation(&h.t, &h.kinetic, (&reference.t, &reference.kinetic)) / ke_exact;
            r.error = (*n != finest && !r.label.contains("μ_s")).then_some(e);
            let ke0 = h.kinetic[0];
            r.metrics = vec![
                ("ke0".into(), ke0),
                ("ke0_error".into(), ke_exact - ke0),
                ("ke_end".into(), h.kinetic[h.kinetic.len() - 1]),
                ("t_elastic_peak".into(), h.t_elastic_peak),
                ("elastic_peak".into(), h.elastic_peak),
                ("volume_drift".into(), h.volume_drift),
            ];
            if !r.label.contains("μ_s") {
                r.metrics.push(("ke_history_error".into(), e));
            }
        }
        let runs: Vec<(&Run, &History, usize)> = done
            .runs
            .iter()
            .zip(&done.measured)
            .map(|(r, ((n, _), h))| (r, h, *n))
            .collect();
        let plain: Vec<&(&Run, &History, usize)> = runs
            .iter()
            .filter(|(r, _, _)| !r.label.contains("μ_s"))
            .collect();
        // Initial kinetic energy: error and observed order over the grids.
        let ke0_err: Vec<f64> = plain
            .iter()
            .map(|(_, h, _)| (ke_exact - h.kinetic[0]).abs())
            .collect();
        let hs: Vec<f64> = plain.iter().map(|(_, _, n)| 1.0 / *n as f64).collect();
        let orders = crate::orders(&hs, &ke0_err);
        let (fr, fh, _) = *plain[plain.len() - 1];
        let mut checks = vec![
            Check::within(
                format!(
                    "initial kinetic energy, observed order ({} vs {})",
                    plain[plain.len() - 2].0.label,
                    fr.label
                ),
                orders[orders.len() - 1],
                1.8,
                2.2,
                "2",
            ),
            Check::at_most(
                format!(
                    "initial kinetic energy, relative error vs 0.0246740 ({})",
                    fr.label
                ),
                ke0_err[ke0_err.len() - 1] / ke_exact,
                if self.quick { 5e-3 } else { 2e-4 },
                "e",
            ),
            Check::at_most(
                format!("KE(t = {end}) / KE(0), largest over the grids (decay)"),
                plain
                    .iter()
                    .map(|(_, h, _)| h.kinetic[h.kinetic.len() - 1] / h.kinetic[0])
                    .fold(0.0, f64::max),
                if self.quick { 0.8 } else { 0.5 },
                "3",
            ),
        ];
        let maxima = fh.extrema.iter().filter(|e| e.2).count();
        let minima = fh.extrema.iter().filter(|e| !e.2).count();
        let first_min = fh.extrema.iter().find(|e| !e.2).map_or(f64::NAN, |e| e.0);
        if self.quick {
            checks.push(Check::within(
                format!(
                    "KE oscillates: local minima + maxima before t = {end} ({})",
                    fr.label
                ),
                (maxima + minima) as f64,
                2.0,
                4.0,
                "0",
            ));
            checks.push(Check::within(
                format!(
                    "time of the elastic energy peak, coarse grid ({})",
                    fr.label
                ),
                fh.t_elastic_peak,
                0.18,
                0.24,
                "4",
            ));
        } else {
            checks.push(Check::within(
                format!(
                    "KE oscillates: local minima + maxima in (0, 1) ({})",
                    fr.label
                ),
                (maxima + minima) as f64,
                4.0,
                6.0,
                "0",
            ));
            checks.push(Check::within(
                format!("time of the elastic energy peak ({}; seed: 0.2)", fr.label),
                fh.t_elastic_peak,
                T_PEAK_SEED - 0.02,
                T_PEAK_SEED + 0.02,
                "4",
            ));
            checks.push(Check::at_most(
                "KE history error vs the finest grid falls with refinement: largest ratio of successive errors",
                largest_ratio(plain.iter().filter_map(|(r, _, _)| r.error)),
                1.0,
                "3",
            ));
        }
        checks.push(drift_check(
            "solid volume drift, every run",
            runs.iter().map(|(_, h, _)| h.volume_drift),
        ));
        // Plots and their series.
        let series = |f: fn(&History) -> &Vec<f64>| -> Vec<Series> {
            runs.iter()
                .map(|(r, h, _)| xy(&r.label, &h.t, f(h)))
                .collect()
        };
        h.figure(
            "kinetic_energy",
            ("Kinetic energy vs time", "t", "kinetic energy"),
            &series(|h| &h.kinetic),
            Scale::Linear,
        );
        h.figure(
            "elastic_energy",
            (
                "Elastic energy vs time (largest deformation at its peak)",
                "t",
                "elastic energy",
            ),
            &series(|h| &h.elastic),
            Scale::Linear,
        );
        h.figure(
            "ke0_convergence",
            (
                "Initial kinetic energy: error vs exact 0.0246740",
                "N",
                "abs(KE(0) − KE_exact)",
            ),
            &[(
                "KE(0) error".into(),
                plain
                    .iter()
                    .zip(&ke0_err)
                    .map(|((_, _, n), e)| (*n as f64, *e))
                    .collect(),
            )],
            Scale::LogLog,
        );
        h.figure(
            "tradeoff",
            (
                "Speed vs accuracy: KE history error vs wall time",
                "wall time (s)",
                "max abs(KE − KE_finest) / KE_exact(0)",
            ),
            &[trade("grids (CFL 0.4)", plain.iter().map(|(r, _, _)| *r))],
            Scale::LogLog,
        );
        let mut table = String::from("Initial kinetic energy (exact 0.0246740): ");
        for (k, ((r, h, _), e)) in plain.iter().copied().zip(&ke0_err).enumerate() {
            table += &format!(
                "{} {:.7} (error {:.2e}{}){}",
                r.label,
                h.kinetic[0],
                e,
                if k > 0 {
                    format!(", order {:.2}", orders[k - 1])
                } else {
                    String::new()
                },
                if k + 1 < plain.len() { "; " } else { "" }
            );
        }
        h.notes.push(table);
        for (r, hi, _) in &runs {
            let ext: Vec<String> = hi
                .extrema
                .iter()
                .map(|(t, _, max)| format!("{} {t:.4}", if *max { "max" } else { "min" }))
                .collect();
            h.notes.push(format!(
                "{}: KE {:.5} → {:.5} at t = {end}; KE extrema at {}; elastic energy peak {:.5} at \
                 t = {:.4}; {} steps in {:.1} s",
                r.label,
                hi.kinetic[0],
                hi.kinetic[hi.kinetic.len() - 1],
                if ext.is_empty() {
                    "—".into()
                } else {
                    ext.join(", ")
                },
                hi.elastic_peak,
                hi.t_elastic_peak,
                r.steps,
                r.wall_seconds
            ));
        }
        h.notes.push(format!(
            "First kinetic energy minimum ({}): t = {first_min:.4}",
            fr.label
        ));
        // The cheapest grid whose kinetic energy history is within 5 % of KE(0) of the finest's
        // and whose elastic energy peaks within 0.01 of the finest's peak time.
        let recommendation = match plain.iter().find(|(r, h, _)| {
            r.error.is_some_and(|e| e <= 0.05)
                && (h.t_elastic_peak - fh.t_elastic_peak).abs() <= 0.01
        }) {
            Some((r, h, _)) => format!(
                "{} at CFL 0.4: the cheapest grid whose KE history is within 5 % of KE(0) of the \
                 finest grid's (error {:.3}) and whose elastic energy peaks within 0.01 of its peak \
                 time (t = {:.4}), in {:.1} s",
                r.label,
                r.error.unwrap_or(f64::NAN),
                h.t_elastic_peak,
                r.wall_seconds
            ),
            None => format!(
                "no grid coarser than {} is within 5 % of it: use the finest",
                fr.label
            ),
        };
        Ok(Verdict {
            title: "elastic disk in a decaying vortex (seed §5.4)".into(),
            reference: "the exact initial kinetic energy a²(kx² + ky²)/8 = 0.0246740; the seed's \
                        time of largest deformation, t ≈ 0.2; the finest grid for the \
                        speed/accuracy trade"
                .into(),
            error_metric: format!(
                "max abs(KE − KE_{finest}²)/KE_exact(0) over 0 ≤ t ≤ {end} (against the finest grid)"
            ),
            checks,
            recommendation: if self.quick {
                format!("quick mode (t ≤ {end}, coarse grids): {recommendation}")
            } else {
                recommendation
            },
        })
    }
}
