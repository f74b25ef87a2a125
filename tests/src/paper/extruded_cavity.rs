//! Issue 40, case 3: planar invariance. The Re = 100 lid-driven cavity
//! (`cases/lid_driven_cavity_re100.ron`) run planar and extruded along z — `Cartesian3D`, the
//! same x–y grid, `nz = 4` cells over a depth of ¼, `Periodic` on both z sides — to its steady
//! state (`time.steady`). A flow with no z motion and no z dependence is a solution of the
//! three-dimensional equations, and the three-dimensional stages reduce to the planar ones on
//! it: the extruded run must reproduce the planar one on every z plane to the solvers'
//! tolerance, with w zero to round-off.
//!
//! Both runs take the projection at a relative tolerance of [`PROJECTION_TOLERANCE`] (the
//! scene's default is looser), so what is compared is the discretisation, not where two
//! iterative solves happened to stop. Measured per pair of runs: the largest difference of u on
//! the vertical centreline x = ½ and of v on the horizontal one y = ½ (129 points each, on three
//! z planes), the largest |w| over every cell, and the cost per cell-step of each.

use super::case::{Case, Done, Harness, Plan, Verdict};
use super::{Check, Options, Run, load_case};
use efsi_core::{Geometry as SceneGeometry, Override, Region, Scene, Simulation, Stagger};
use efsi_run::probes::{sample, sample3};
use efsi_run::{SceneOutput, SceneOverrides};
use std::path::PathBuf;

/// The projection's relative tolerance in both runs.
const PROJECTION_TOLERANCE: &str = "1e-10";
/// The largest difference of u and v between the two runs (velocities scale with the lid's
/// speed 1): the solvers' tolerance, with margin for the steady-state test stopping both runs
/// at nearly the same time.
const VELOCITY_BOUND: f64 = 1e-7;
/// The largest |w| of the extruded run: ten times the projection's relative tolerance. Nothing
/// drives w but what the pressure solves leave, which accumulates over the steps to the steady
/// state (measured 2e-12 at 16² × 4 in 445 steps, 6.7e-11 at 32² and 64² in 669 and 1542).
const W_BOUND: f64 = 1e-9;
/// The depth of the extruded box and its cells.
const DEPTH: f64 = 0.25;
const NZ: usize = 4;
/// Points along each centreline.
const POINTS: usize = 129;
/// The z planes the extruded run is sampled on (cell centres and between them).
const PLANES: [f64; 3] = [0.03125, 0.1, 0.21875];

/// The geometry of a run.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Geometry {
    /// The planar cavity as shipped.
    Planar,
    /// The same extruded along a periodic z.
    Extruded,
}

/// What one run shows: the two centrelines on each plane sampled (one plane when planar), the
/// largest |w|, when it stopped and its cost.
pub struct Centrelines {
    /// u(y) on x = ½, then v(x) on y = ½, per plane.
    planes: Vec<Vec<f64>>,
    /// max |w| over the cells (0 when planar).
    w_max: f64,
    /// The time at which the run stopped, and whether it was steady.
    t_end: f64,
    steady: bool,
    /// Wall seconds per million cell-steps.
    cost: f64,
}

/// The case: 16² (quick) or 32² and 64², each planar and extruded.
pub struct ExtrudedCavity;

impl Case for ExtrudedCavity {
    const NAME: &'static str = "extruded_cavity";
    type Setting = (Geometry, usize);
    type Measured = Centrelines;

    fn plan(opts: &Options) -> Plan<Self> {
        let grids: &[usize] = if opts.quick { &[16] } else { &[32, 64] };
        let mut plan = Vec::new();
        for &n in grids {
            plan.push((format!("planar {n}²"), (Geometry::Planar, n)));
            plan.push((format!("extruded {n}² × {NZ}"), (Geometry::Extruded, n)));
        }
        Ok((ExtrudedCavity, plan))
    }

    fn scene(&self, &(geometry, n): &(Geometry, usize)) -> Result<(Scene, PathBuf), String> {
        let (mut scene, path) = load_case("lid_driven_cavity_re100.ron")?;
        scene.grid.nx = n;
        scene.grid.ny = n;
        let tolerance = format!("numerics.projection.tolerance={PROJECTION_TOLERANCE}");
        scene
            .apply(&[Override::parse(&tolerance).map_err(|e| e.to_string())?])
            .map_err(|e| e.to_string())?;
        if geometry == Geometry::Extruded {
            scene.geometry = SceneGeometry::Cartesian3D;
            scene.domain.z = Some((0.0, DEPTH));
            scene.grid.nz = Some(NZ);
            scene.boundaries.z_min = Some(efsi_core::scene::Boundary::Periodic);
            scene.boundaries.z_max = Some(efsi_core::scene::Boundary::Periodic);
            // The planar probes' and profiles' points have no z.
            scene.update_output(|o| {
                o.probes.clear();
                o.profiles.clear();
            })?;
        }
        scene.update_output(|o| o.vtk_every = None)?;
        Ok((scene, path))
    }

    fn measure(
        &self,
        &(geometry, _): &(Geometry, usize),
        sim: &Simulation,
        run: &mut Run,
    ) -> Result<Centrelines, String> {
        let (g, st) = (&sim.grid, &sim.state);
        let at = |k: usize| k as f64 / (POINTS - 1) as f64;
        let line = |f: &dyn Fn(&str, f64, f64) -> f64| {
            let mut l: Vec<f64> = (0..POINTS).map(|k| f("u", 0.5, at(k))).collect();
            l.extend((0..POINTS).map(|k| f("v", at(k), 0.5)));
            l
        };
        let planes = match geometry {
            Geometry::Planar => vec![line(&|name, x, y| sample(g, st, name, (x, y)))],
            Geometry::Extruded => PLANES
                .iter()
                .map(|&z| line(&|name, x, y| sample3(g, st, name, [x, y, z])))
                .collect(),
        };
        let w_max = st.w.as_ref().map_or(0.0, |w| {
            Region::of(g, Stagger::ZFace).max(0.0, |l| {
                w.at(&l, [0; 3])
                    .iter()
                    .fold(0.0, |m: f64, &x| m.max(x.abs()))
            })
        });
        if planes.iter().flatten().any(|x| !x.is_finite()) {
            return Err(format!("{}: NaN on a centreline", run.label));
        }
        let cells = (g.nx * g.ny * g.nz) as f64;
        let m = Centrelines {
            planes,
            w_max,
            t_end: st.t,
            steady: sim.is_steady(),
            cost: run.wall_seconds / (cells * run.steps.max(1) as f64) * 1e6,
        };
        run.metrics = vec![("w_max".into(), m.w_max), ("t_end".into(), m.t_end)];
        Ok(m)
    }

    fn conclude(&self, _h: &mut Harness, done: &mut Done<Self>) -> Result<Verdict, String> {
        let mut pairs = Vec::new();
        for ((g, n), m) in &done.measured {
            let planar = done
                .measured
                .iter()
                .find(|((gg, nn), _)| *gg == Geometry::Planar && nn == n);
            if let (Geometry::Extruded, Some((_, p))) = (g, planar) {
                pairs.push(Pair {
                    n: *n,
                    difference: difference(&p.planes[0], &m.planes),
                    extruded: m,
                    planar: p,
                });
            }
        }
        let Some(last) = pairs.last() else {
            return Err("no pair of runs (planar and extruded) completed".into());
        };
        let (finest, d, m, p) = (last.n, last.difference, last.extruded, last.planar);
        let largest = |f: &dyn Fn(&Pair) -> f64| pairs.iter().map(f).fold(0.0, f64::max);
        let (d_max, w_max) = (largest(&|p| p.difference), largest(&|p| p.extruded.w_max));
        let differences: Vec<(usize, f64)> = pairs.iter().map(|p| (p.n, p.difference)).collect();
        for (run, ((g, n), _)) in done.runs.iter_mut().zip(&done.measured) {
            if let (Geometry::Extruded, Some(&(_, d))) =
                (g, differences.iter().find(|(nn, _)| nn == n))
            {
                run.error = Some(d);
                run.metrics.push(("max_velocity_difference".into(), d));
            }
        }
        let checks = vec![
            Check::at_most(
                "max abs(extruded − planar) of u on x = ½ and v on y = ½, three z planes, every grid",
                d_max,
                VELOCITY_BOUND,
                "e",
            ),
            Check::at_most("max abs(w) of the extruded runs", w_max, W_BOUND, "e"),
            Check::at_least(
                format!(
                    "runs stopped at the steady state (time.steady), of {}",
                    done.measured.len()
                ),
                done.measured.iter().filter(|(_, m)| m.steady).count() as f64,
                done.measured.len() as f64,
                "0",
            ),
        ];
        Ok(Verdict {
            title: "Planar invariance: the Re = 100 cavity extruded along z (issue 40, case 3)"
                .into(),
            reference: format!(
                "the planar run of the same cavity at the same grid (both with the projection at relative tolerance {PROJECTION_TOLERANCE})"
            ),
            error_metric: "max abs(extruded − planar) of u on x = ½ and v on y = ½, three z planes"
                .into(),
            checks,
            recommendation: format!(
                "{finest}²: the extruded run (steady at t = {:.2}) departs from the planar one (t = {:.2}) by {d:.1e}; it costs {:.2} µs per cell-step against the planar {:.2} — run a flow without z dependence planar",
                m.t_end, p.t_end, m.cost, p.cost
            ),
        })
    }
}

/// A planar run and the extruded one at the same grid.
struct Pair<'a> {
    /// Cells along x and y.
    n: usize,
    /// The largest difference of the centrelines ([`difference`]).
    difference: f64,
    extruded: &'a Centrelines,
    planar: &'a Centrelines,
}

/// The largest difference between the planar centrelines and each plane's of the extruded run.
fn difference(planar: &[f64], planes: &[Vec<f64>]) -> f64 {
    planes
        .iter()
        .flat_map(|l| l.iter().zip(planar).map(|(a, b)| (a - b).abs()))
        .fold(0.0, f64::max)
}
