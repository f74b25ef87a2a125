//! Issue 40, case 1: the lid-driven cube at Re = U L/ν = 1000 (`cases/lid_driven_cube_re1000.ron`)
//! against the Chebyshev-collocation steady state of Albensoeder & Kuhlmann (2005), their
//! Tables 5–6 (`tests/references/lid_driven_cube_re1000/`): u(y) on the vertical centreline
//! x = z = ½ and v(x) on the horizontal one y = z = ½, each sampled (trilinearly) at the tables'
//! interior points. The walls' points are the boundary conditions, not computed, and are left
//! out. Each grid runs to the scene's steady state (`time.steady`) or its end time.

use super::case::{Case, Done, Harness, Plan, Verdict, largest_ratio, steady_check, trade, xy};
use super::plot::Scale;
use super::{Check, Options, Run, load_case};
use efsi_core::{Scene, Simulation};
use efsi_run::SceneOutput;
use efsi_run::probes::{max_divergence, sample3};
use std::path::PathBuf;

/// The reference folder, relative to `tests/references/`.
const REFERENCE: &str = "lid_driven_cube_re1000";
/// The largest deviation of either centreline from the tables in quick mode (16³ measured
/// 0.114 in u, 0.167 in v).
const QUICK_BOUND: f64 = 0.18;
/// The same on the finest grid of the full mode: no worse than 32³ (measured 0.064 in u,
/// 0.087 in v); the full mode also checks that both fall with every refinement.
const FULL_BOUND: f64 = 0.09;
/// max |∇·V|·Δt at the end of a run: the projection's tolerance in a scene of one fluid.
const DIVERGENCE_BOUND: f64 = 1e-4;
/// Points of the plotted profiles.
const PLOT_POINTS: usize = 65;

/// A reference table: positions along the line and the velocity there, walls left out.
struct Table {
    s: Vec<f64>,
    vel: Vec<f64>,
}

/// Read `file` of the reference folder (two columns: position, velocity), its end points (the
/// walls) left out.
fn table(file: &str) -> Result<Table, String> {
    let path = crate::try_reference(&format!("{REFERENCE}/{file}"))?;
    let (_, cols) = crate::try_read_csv(&path)?;
    if cols.len() < 2 || cols[0].len() < 3 {
        return Err(format!("{}: expected two columns", path.display()));
    }
    let n = cols[0].len();
    Ok(Table {
        s: cols[0][1..n - 1].to_vec(),
        vel: cols[1][1..n - 1].to_vec(),
    })
}

/// What one run shows.
pub struct Profiles {
    /// u(y) on x = z = ½ and v(x) on y = z = ½, at [`PLOT_POINTS`] points.
    u: Vec<(f64, f64)>,
    v: Vec<(f64, f64)>,
    /// Largest deviations from the tables.
    dev_u: f64,
    dev_v: f64,
    /// max |∇·V|·Δt at the end.
    divergence: f64,
    /// Whether the run stopped at the steady state (not at the end time).
    steady: bool,
}

/// The case: 16³ (quick) or 32³, 64³, 96³.
pub struct LidDrivenCube {
    u_ref: Table,
    v_ref: Table,
}

impl Case for LidDrivenCube {
    const NAME: &'static str = "lid_driven_cube";
    type Setting = usize;
    type Measured = Profiles;

    fn plan(opts: &Options) -> Plan<Self> {
        let grids: &[usize] = if opts.quick { &[16] } else { &[32, 64, 96] };
        let case = LidDrivenCube {
            u_ref: table("u_vertical_centerline.csv")?,
            v_ref: table("v_horizontal_centerline.csv")?,
        };
        let plan = grids.iter().map(|&n| (format!("{n}³"), n)).collect();
        Ok((case, plan))
    }

    fn scene(&self, &n: &usize) -> Result<(Scene, PathBuf), String> {
        let (mut scene, path) = load_case("lid_driven_cube_re1000.ron")?;
        scene.grid.nx = n;
        scene.grid.ny = n;
        scene.grid.nz = Some(n);
        scene.update_output(|o| o.vtk_every = None)?;
        Ok((scene, path))
    }

    fn measure(&self, _n: &usize, sim: &Simulation, run: &mut Run) -> Result<Profiles, String> {
        let (g, st) = (&sim.grid, &sim.state);
        let on_u = |y: f64| sample3(g, st, "u", [0.5, y, 0.5]);
        let on_v = |x: f64| sample3(g, st, "v", [x, 0.5, 0.5]);
        let dev = |t: &Table, f: &dyn Fn(f64) -> f64| {
            t.s.iter()
                .zip(&t.vel)
                .map(|(&s, &r)| (f(s) - r).abs())
                .fold(0.0, f64::max)
        };
        let line = |f: &dyn Fn(f64) -> f64| {
            (0..PLOT_POINTS)
                .map(|k| {
                    let s = k as f64 / (PLOT_POINTS - 1) as f64;
                    (s, f(s))
                })
                .collect::<Vec<_>>()
        };
        let m = Profiles {
            u: line(&on_u),
            v: line(&on_v),
            dev_u: dev(&self.u_ref, &on_u),
            dev_v: dev(&self.v_ref, &on_v),
            divergence: max_divergence(g, st) * st.dt_prev,
            steady: sim.is_steady(),
        };
        if m.dev_u.is_nan() || m.dev_v.is_nan() {
            return Err(format!("{}: NaN on a centreline", run.label));
        }
        run.error = Some(m.dev_u.max(m.dev_v));
        run.metrics = vec![
            ("dev_u".into(), m.dev_u),
            ("dev_v".into(), m.dev_v),
            ("max_div_dt".into(), m.divergence),
            ("t_end".into(), st.t),
        ];
        Ok(m)
    }

    fn conclude(&self, h: &mut Harness, done: &mut Done<Self>) -> Result<Verdict, String> {
        let (Some(f), Some((_, mf))) = (done.runs.last(), done.measured.last()) else {
            return Err("no run completed".into());
        };
        let full = !h.opts.quick;
        let bound = if full { FULL_BOUND } else { QUICK_BOUND };
        let mut checks = vec![
            Check::at_most(
                format!("max abs(u − u_ref) on x = z = ½ ({})", f.label),
                mf.dev_u,
                bound,
                "4",
            ),
            Check::at_most(
                format!("max abs(v − v_ref) on y = z = ½ ({})", f.label),
                mf.dev_v,
                bound,
                "4",
            ),
            Check::at_most(
                "max abs(∇·V)·Δt at the end, every grid",
                done.measured
                    .iter()
                    .map(|(_, m)| m.divergence)
                    .fold(0.0, f64::max),
                DIVERGENCE_BOUND,
                "e",
            ),
            // The tables are a steady state: a run that stops at its end time is not compared
            // with what they show.
            steady_check(done.measured.iter().map(|(_, m)| m.steady)),
        ];
        if full {
            for (what, pick) in [
                ("u", (|m: &Profiles| m.dev_u) as fn(&Profiles) -> f64),
                ("v", |m: &Profiles| m.dev_v),
            ] {
                checks.push(Check::at_most(
                    format!("the {what} deviation falls with refinement: largest ratio of successive grids'"),
                    largest_ratio(done.measured.iter().map(|(_, m)| pick(m))),
                    0.99,
                    "3",
                ));
            }
        }
        let hs: Vec<f64> = done.measured.iter().map(|(n, _)| 1.0 / *n as f64).collect();
        let order = |pick: fn(&Profiles) -> f64| {
            let e: Vec<f64> = done.measured.iter().map(|(_, m)| pick(m)).collect();
            crate::orders(&hs, &e)
                .iter()
                .map(|o| format!("{o:.2}"))
                .collect::<Vec<_>>()
                .join(", ")
        };
        let per_grid = done
            .runs
            .iter()
            .zip(&done.measured)
            .map(|(r, (_, m))| {
                format!(
                    "{}: u {:.4}, v {:.4}, max abs(∇·V)·Δt {:.1e}, {} at t = {:.1} ({} steps, {:.0} s)",
                    r.label,
                    m.dev_u,
                    m.dev_v,
                    m.divergence,
                    if m.steady { "steady" } else { "end time" },
                    r.metric("t_end").unwrap_or(f64::NAN),
                    r.steps,
                    r.wall_seconds
                )
            })
            .collect::<Vec<_>>()
            .join("; ");
        let orders = if done.measured.len() > 1 {
            format!(
                "; observed orders between successive grids u: {}, v: {}",
                order(|m| m.dev_u),
                order(|m| m.dev_v)
            )
        } else {
            String::new()
        };
        h.notes.push(format!(
            "largest deviations from the tables per grid — {per_grid}{orders}"
        ));
        let profile_series = |pick: fn(&Profiles) -> &Vec<(f64, f64)>, t: &Table| {
            let mut s: Vec<_> = done
                .runs
                .iter()
                .zip(&done.measured)
                .map(|(r, (_, m))| (r.label.clone(), pick(m).clone()))
                .collect();
            s.push(xy("Albensoeder & Kuhlmann 2005", &t.s, &t.vel));
            s
        };
        let u_series = profile_series(|m| &m.u, &self.u_ref);
        let v_series = profile_series(|m| &m.v, &self.v_ref);
        h.figure(
            "u_vertical",
            ("Lid-driven cube Re 1000: u on x = z = ½", "y", "u / U"),
            &u_series,
            Scale::Linear,
        );
        h.figure(
            "v_horizontal",
            ("Lid-driven cube Re 1000: v on y = z = ½", "x", "v / U"),
            &v_series,
            Scale::Linear,
        );
        h.figure(
            "tradeoff",
            (
                "Lid-driven cube Re 1000: centreline deviation vs wall time",
                "wall time (s)",
                "max abs deviation",
            ),
            &[trade("grids", done.runs.iter())],
            Scale::LogLog,
        );
        let recommendation = format!(
            "{}, the finest grid: the largest centreline deviation {:.4} (u {:.4}, v {:.4}); it sits at the profiles' extrema next to the walls, which the coarser grids flatten",
            f.label,
            mf.dev_u.max(mf.dev_v),
            mf.dev_u,
            mf.dev_v
        );
        Ok(Verdict {
            title: "Lid-driven cube, Re = 1000 (issue 40)".into(),
            reference: "Albensoeder & Kuhlmann (2005), J. Comput. Phys. 206:536–558, Tables 5–6: Chebyshev-collocation steady state, centreline profiles at the mid-plane z = ½ (tests/references/lid_driven_cube_re1000/)".into(),
            error_metric: "the larger of max abs(u − u_ref) on x = z = ½ and max abs(v − v_ref) on y = z = ½, at the tables' interior points".into(),
            checks,
            recommendation,
        })
    }
}
