//! Issue 40, case 4: a drop falling from rest in three dimensions against the same drop in
//! axisymmetric geometry, at the same cells per diameter (`cases/falling_drop_3d.ron`,
//! `cases/falling_drop_axi.ron`).
//!
//! The drop is Basilisk's `axidrop_nt` (the peer yardstick): diameter 1, centre 3 above the
//! floor of a box 4 high, density 1 in 1e-3, viscosity 1e-2 in 2e-4, gravity 1, no surface
//! tension, t ∈ [0, 1], Δt = h/8. The axisymmetric run has the box 4 × 4 in r–z; the
//! three-dimensional one a quarter of the box, 2 × 4 × 2 with `Symmetry` planes x = 0 and z = 0
//! through the drop's axis and no-slip walls elsewhere. The drop is 1000 times denser than the
//! fluid around it, so it falls nearly freely (½gt² = 0.5 at t = 1); what differs between the
//! two is the discretisation of the same body — a sphere on a Cartesian grid against a disk
//! revolved about the axis — and the side walls (a cylinder of radius 4 against a square
//! 2 from the axis), which slow the three-dimensional drop by a few 1e-5 of its fall.
//!
//! Measured per run from `probes.csv`: the fall of the centroid at t = 1, the drift of the
//! drop's volume over the run, and the bounds 0 ≤ φ ≤ 1 at the end; per resolution, the
//! difference of the two falls.

use super::case::{Case, Done, Harness, Plan, Verdict, drift, drift_check};
use super::plot::Scale;
use super::{Check, Options, Run, Series, load_case, probes};
use efsi_core::{Region, Scene, Simulation, Stagger};
use efsi_run::SceneOutput;
use std::path::PathBuf;

/// Free fall at t = 1: ½gt² with g = 1.
const FREE_FALL: f64 = 0.5;
/// The end time.
const END: f64 = 1.0;

/// The largest difference between the falls of the three-dimensional and the axisymmetric
/// drop at t = 1 at the finest grid: quick, 8 cells per diameter (measured 2.9e-4), and full,
/// 32 (measured 6.9e-5; 6.4e-5 at 16).
const QUICK_DIFFERENCE: f64 = 5e-4;
const FULL_DIFFERENCE: f64 = 2e-4;
/// The range of the three-dimensional drop's fall at t = 1 at the finest grid: quick (8 cells
/// per diameter, measured 0.50014) and full (32, measured 0.49739; efsi's axisymmetric drop at
/// 128 cells per diameter falls 0.49730).
const QUICK_FALL: (f64, f64) = (0.4995, 0.5005);
const FULL_FALL: (f64, f64) = (0.4965, 0.4985);

/// The geometry of a run.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Geometry {
    /// The r–z half-plane, `cases/falling_drop_axi.ron`.
    Axisymmetric,
    /// The quarter box, `cases/falling_drop_3d.ron`.
    ThreeD,
}

/// What one run shows.
pub struct Fall {
    /// The centroid's fall `y(0) − y(t)` against t.
    series: Vec<(f64, f64)>,
    /// Its fall at the end.
    fall: f64,
    /// The largest relative change of the drop's volume from its start.
    drift: f64,
    /// The smallest and largest φ at the end.
    phi_range: (f64, f64),
}

/// The case: 8 cells per diameter (quick) or 8, 16 and 32, each in both geometries.
pub struct FallingDrop;

impl Case for FallingDrop {
    const NAME: &'static str = "falling_drop_3d";
    type Setting = (Geometry, usize);
    type Measured = Fall;

    fn plan(opts: &Options) -> Plan<Self> {
        let cpd: &[usize] = if opts.quick { &[8] } else { &[8, 16, 32] };
        let mut plan = Vec::new();
        for &c in cpd {
            plan.push((format!("axisymmetric {c} CPD"), (Geometry::Axisymmetric, c)));
            plan.push((format!("3-D {c} CPD"), (Geometry::ThreeD, c)));
        }
        Ok((FallingDrop, plan))
    }

    fn scene(&self, &(geometry, c): &(Geometry, usize)) -> Result<(Scene, PathBuf), String> {
        let (mut scene, path) = match geometry {
            Geometry::Axisymmetric => load_case("falling_drop_axi.ron")?,
            Geometry::ThreeD => load_case("falling_drop_3d.ron")?,
        };
        // Cells per unit length = cells per diameter (the diameter is 1).
        match geometry {
            Geometry::Axisymmetric => {
                scene.grid.nx = 4 * c;
                scene.grid.ny = 4 * c;
            }
            Geometry::ThreeD => {
                scene.grid.nx = 2 * c;
                scene.grid.ny = 4 * c;
                scene.grid.nz = Some(2 * c);
            }
        }
        scene.time.end = END;
        scene.time.fixed_dt = Some(1.0 / (8.0 * c as f64));
        scene.update_output(|o| o.vtk_every = None)?;
        Ok((scene, path))
    }

    fn measure(
        &self,
        _s: &(Geometry, usize),
        sim: &Simulation,
        run: &mut Run,
    ) -> Result<Fall, String> {
        let p = probes(&run.dir)?;
        let (t, y, volume) = (p.col("t")?, p.col("solid_y")?, p.col("solid_volume")?);
        let start = y.first().copied().unwrap_or(f64::NAN);
        let series: Vec<(f64, f64)> = t.iter().zip(y).map(|(&t, &y)| (t, start - y)).collect();
        let fall = series.last().map_or(f64::NAN, |&(_, f)| f);
        let phi = sim.state.phi.as_ref().ok_or("the run has no drop")?;
        let cells = Region::of(&sim.grid, Stagger::Cell);
        let lo = cells.fold(
            f64::INFINITY,
            |l| {
                phi.at(&l, [0; 3])
                    .iter()
                    .fold(f64::INFINITY, |m, &f| m.min(f))
            },
            f64::min,
        );
        let hi = cells.max(f64::NEG_INFINITY, |l| {
            phi.at(&l, [0; 3])
                .iter()
                .fold(f64::NEG_INFINITY, |m, &f| m.max(f))
        });
        let m = Fall {
            series,
            fall,
            drift: drift(volume),
            phi_range: (lo, hi),
        };
        if !m.fall.is_finite() {
            return Err(format!("{}: no fall measured", run.label));
        }
        run.metrics = vec![
            ("fall".into(), m.fall),
            ("volume_drift".into(), m.drift),
            ("phi_min".into(), lo),
            ("phi_max".into(), hi),
            ("t_end".into(), sim.state.t),
        ];
        Ok(m)
    }

    fn conclude(&self, h: &mut Harness, done: &mut Done<Self>) -> Result<Verdict, String> {
        // The pairs (axisymmetric, 3-D) at each resolution, in the plan's order.
        let fall_of = |g: Geometry, c: usize| {
            done.measured
                .iter()
                .find(|((gg, cc), _)| *gg == g && *cc == c)
                .map(|(_, m)| m.fall)
        };
        let mut pairs = Vec::new();
        for ((g, c), m) in &done.measured {
            if *g == Geometry::ThreeD
                && let Some(axi) = fall_of(Geometry::Axisymmetric, *c)
            {
                pairs.push((*c, m.fall, axi));
            }
        }
        let Some(&(finest, fall_3d, fall_axi)) = pairs.last() else {
            return Err("no pair of runs (axisymmetric and 3-D) completed".into());
        };
        for (run, ((g, c), _)) in done.runs.iter_mut().zip(&done.measured) {
            if *g == Geometry::ThreeD
                && let Some(&(_, f3, fa)) = pairs.iter().find(|(cc, _, _)| cc == c)
            {
                run.error = Some((f3 - fa).abs());
            }
        }
        let full = !h.opts.quick;
        let (bound, range) = if full {
            (FULL_DIFFERENCE, FULL_FALL)
        } else {
            (QUICK_DIFFERENCE, QUICK_FALL)
        };
        let lo = done
            .measured
            .iter()
            .map(|(_, m)| m.phi_range.0)
            .fold(f64::INFINITY, f64::min);
        let hi = done
            .measured
            .iter()
            .map(|(_, m)| m.phi_range.1)
            .fold(f64::NEG_INFINITY, f64::max);
        let checks = vec![
            Check::at_most(
                format!("abs(fall 3-D − fall axisymmetric) at t = 1, {finest} cells per diameter"),
                (fall_3d - fall_axi).abs(),
                bound,
                "e",
            ),
            Check::within(
                format!("fall of the 3-D drop at t = 1, {finest} cells per diameter"),
                fall_3d,
                range.0,
                range.1,
                "5",
            ),
            drift_check(
                "relative drift of the drop's volume, every run",
                done.measured.iter().map(|(_, m)| m.drift),
            ),
            Check::at_least("smallest φ at the end, every run", lo, 0.0, "e"),
            Check::at_most("largest φ at the end, every run", hi, 1.0, "e"),
        ];
        let per_grid = pairs
            .iter()
            .map(|(c, f3, fa)| {
                format!(
                    "{c} CPD: 3-D {f3:.5}, axisymmetric {fa:.5}, difference {:.2e}",
                    f3 - fa
                )
            })
            .collect::<Vec<_>>()
            .join("; ");
        let drifts = done
            .runs
            .iter()
            .zip(&done.measured)
            .map(|(r, (_, m))| format!("{} {:.1e}", r.label, m.drift))
            .collect::<Vec<_>>()
            .join(", ");
        h.notes.push(format!(
            "fall of the centroid at t = 1 (free fall {FREE_FALL}) — {per_grid}; volume drift: {drifts}"
        ));
        let mut series: Vec<Series> = done
            .runs
            .iter()
            .zip(&done.measured)
            .map(|(r, (_, m))| (r.label.clone(), m.series.clone()))
            .collect();
        let free = (0..=32)
            .map(|k| {
                let t = END * k as f64 / 32.0;
                (t, 0.5 * t * t)
            })
            .collect();
        series.push(("free fall ½gt²".into(), free));
        h.figure(
            "fall",
            ("Falling drop: fall of the centroid", "t", "y(0) − y(t)"),
            &series,
            Scale::Linear,
        );
        Ok(Verdict {
            title: "Falling drop, 3-D against axisymmetric (issue 40, case 4)".into(),
            reference: "the same drop in axisymmetric geometry at the same cells per diameter (Basilisk's axidrop_nt set-up; free fall ½gt² = 0.5 at t = 1)".into(),
            error_metric: "abs(fall of the 3-D drop − fall of the axisymmetric drop) at t = 1, same cells per diameter".into(),
            checks,
            recommendation: format!(
                "{finest} cells per diameter: the 3-D drop falls {fall_3d:.4}, the axisymmetric one {fall_axi:.4}; the axisymmetric run is the cheaper way to the same figure for a drop on the axis"
            ),
        })
    }
}
