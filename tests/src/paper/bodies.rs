//! Issue 42's cases: scenes of several bodies (`solids: [ … ]`), each body with its own
//! fraction and deformation, kept apart by the resolved film and the contact stage.
//!
//! - [`TwoSoftDisks`] (case 1, `cases/two_soft_disks.ron`): two identical neo-Hookean disks in
//!   head-on approach; the mirror symmetry about x = 1, no overlap, each body's volume and one
//!   piece at every output, the bodies part again, and the restitution over three grids.
//! - [`ContactMap`] (case 1's contact model): the same two disks over the repulsion's range ×
//!   stiffness, its effect on the restitution, with the same checks and no energy gained.
//! - [`SpheresOnAxis`] (case 2, `cases/spheres_on_axis.ron`): a soft sphere falls onto
//!   another resting on the floor, axisymmetric; the same checks, the rebound over three grids.
//! - [`TwentyDisks`] (case 3, `cases/twenty_disks.ron`): twenty disks of two materials settle
//!   in a closed box; every body's volume, no overlap, one piece each, and the kinetic energy
//!   decays to rest.
//! - [`DisksInCavity`] (case 4, `cases/disks_in_cavity.ron`): three disks carried round the
//!   lid-driven cavity; their centroid paths converge over three grids.
//!
//! Every figure is read from the runs' probes (`<body>.solid_x`, …, `max_solid_fraction_sum`,
//! `<a>.<b>.shared_cells`, `kinetic_energy`), sampled at the scenes' `probe_every`.

use super::case::{
    Case, Done, Harness, Plan, Verdict, drift, drift_check, grid_study, largest_ratio, xy,
};
use super::plot::Scale;
use super::{Check, Options, Probes, Run, load_case, probes};
use efsi_core::{Scene, Simulation};
use efsi_run::{SceneOutput, SceneOverrides};
use std::path::PathBuf;

/// Largest `Σ_k φ_k` of a cell allowed at any output (the no-overlap bound).
const OVERLAP: f64 = 1.0 + 1e-12;
/// Least share of a body's volume in its largest piece, at every output.
const ONE_PIECE: f64 = 0.9999;

/// What one run's probes show of its bodies.
#[derive(Clone, Debug, Default)]
pub struct Bodies {
    /// Sample times.
    pub t: Vec<f64>,
    /// The bodies' names, in the scene's order.
    pub names: Vec<String>,
    /// Per body: centroid x and y, velocity u and v, per sample.
    pub x: Vec<Vec<f64>>,
    /// See [`Bodies::x`].
    pub y: Vec<Vec<f64>>,
    /// See [`Bodies::x`].
    pub u: Vec<Vec<f64>>,
    /// See [`Bodies::x`].
    pub v: Vec<Vec<f64>>,
    /// Largest relative change of a body's volume, over the bodies.
    pub volume_drift: f64,
    /// Most pieces of a body, and least share of a body's volume in its largest piece.
    pub pieces: f64,
    /// See [`Bodies::pieces`].
    pub largest_piece: f64,
    /// Largest `Σ_k φ_k` of a cell.
    pub overlap: f64,
    /// Most cells two bodies share.
    pub shared_cells: f64,
    /// The scene's kinetic energy per sample.
    pub kinetic: Vec<f64>,
    /// Per body, its spin per sample (rad/s), where the scene probes `SolidSpin`; else empty.
    pub spin: Vec<Vec<f64>>,
    /// Per body, its strain energy per sample, where the scene probes `ElasticEnergy`; else
    /// empty.
    pub strain: Vec<Vec<f64>>,
}

/// The largest of a column over its samples.
fn most(p: &Probes, col: &str) -> Result<f64, String> {
    Ok(p.col(col)?
        .iter()
        .copied()
        .fold(f64::NEG_INFINITY, f64::max))
}

/// Read the bodies' probes of `run`.
pub fn read(run: &Run) -> Result<Bodies, String> {
    let p = probes(&run.dir)?;
    let t = p.col("t")?.to_vec();
    if t.is_empty() {
        return Err(format!("{}: no probe samples", run.label));
    }
    let names: Vec<String> = p
        .header()
        .iter()
        .filter_map(|h| h.strip_suffix(".solid_x").map(str::to_string))
        .collect();
    if names.len() < 2 {
        return Err(format!("{}: expected two bodies or more", run.label));
    }
    let per = |q: &str| -> Result<Vec<Vec<f64>>, String> {
        names
            .iter()
            .map(|n| Ok(p.col(&format!("{n}.{q}"))?.to_vec()))
            .collect()
    };
    let mut b = Bodies {
        x: per("solid_x")?,
        y: per("solid_y")?,
        u: per("solid_u")?,
        v: per("solid_v")?,
        overlap: most(&p, "max_solid_fraction_sum")?,
        kinetic: p.col("kinetic_energy")?.to_vec(),
        largest_piece: f64::INFINITY,
        ..Bodies::default()
    };
    for n in &names {
        b.volume_drift = b
            .volume_drift
            .max(drift(p.col(&format!("{n}.solid_volume"))?));
        b.pieces = b.pieces.max(most(&p, &format!("{n}.solid_pieces"))?);
        let least = p.col(&format!("{n}.solid_largest_piece"))?;
        b.largest_piece = least.iter().copied().fold(b.largest_piece, f64::min);
    }
    for h in p.header().iter().filter(|h| h.ends_with(".shared_cells")) {
        b.shared_cells = b.shared_cells.max(most(&p, h)?);
    }
    // Columns a scene may not probe: empty where it does not.
    let optional = |q: &str| -> Result<Vec<Vec<f64>>, String> {
        let probed = p.header().iter().any(|h| h.ends_with(&format!(".{q}")));
        if probed { per(q) } else { Ok(Vec::new()) }
    };
    b.spin = optional("solid_spin")?;
    b.strain = optional("elastic_energy")?;
    b.t = t;
    b.names = names;
    Ok(b)
}

/// The checks every scene of several bodies must pass in every run: volumes, no overlap, one
/// piece each.
fn separation_checks(all: &[&Bodies]) -> Vec<Check> {
    let fold = |f: fn(&Bodies) -> f64, init: f64, g: fn(f64, f64) -> f64| {
        all.iter().map(|b| f(b)).fold(init, g)
    };
    vec![
        drift_check(
            "every body's volume drift, every run",
            all.iter().map(|b| b.volume_drift),
        ),
        Check::at_most(
            "largest Σ_k φ_k of a cell, every output of every run",
            fold(|b| b.overlap, 0.0, f64::max),
            OVERLAP,
            "e",
        ),
        Check::at_most(
            "pieces of a body, every output of every run",
            fold(|b| b.pieces, 0.0, f64::max),
            1.0,
            "0",
        ),
        Check::at_least(
            "share of a body's volume in its largest piece, every output of every run",
            fold(|b| b.largest_piece, f64::INFINITY, f64::min),
            ONE_PIECE,
            "6",
        ),
    ]
}

/// Mean distance, over the bodies and the samples of `a`, of each body's centroid to the same
/// body's in `b` at the same time (`b` interpolated linearly in time; samples outside `b`'s
/// times are left out).
pub fn paths_gap(a: &Bodies, b: &Bodies) -> f64 {
    let (Some(&t0), Some(&t1)) = (b.t.first(), b.t.last()) else {
        return f64::NAN;
    };
    if b.t.len() < 2 || a.names != b.names {
        return f64::NAN;
    }
    let mut d = Vec::new();
    for k in 0..a.names.len() {
        for (s, &t) in a.t.iter().enumerate() {
            if (t0..=t1).contains(&t) {
                let x = crate::interp(&b.t, &b.x[k], t);
                let y = crate::interp(&b.t, &b.y[k], t);
                d.push((a.x[k][s] - x).hypot(a.y[k][s] - y));
            }
        }
    }
    if d.is_empty() {
        f64::NAN
    } else {
        d.iter().sum::<f64>() / d.len() as f64
    }
}

/// A scene of `cases/` on an `n × n` grid to `end`, without VTK output.
fn square(file: &str, n: usize, end: Option<f64>) -> Result<(Scene, PathBuf), String> {
    let (mut scene, path) = load_case(file)?;
    scene.grid.nx = n;
    scene.grid.ny = n;
    if let Some(end) = end {
        scene.time.end = end;
    }
    scene.update_output(|o| o.vtk_every = None)?;
    Ok((scene, path))
}

/// The runs and what they showed, paired.
fn paired<C: Case<Measured = Bodies>>(done: &Done<C>) -> Vec<(&Run, &Bodies)> {
    done.runs
        .iter()
        .zip(done.measured.iter().map(|(_, b)| b))
        .collect()
}

/// Case 1: two soft disks head-on, on three grids.
pub struct TwoSoftDisks {
    end: f64,
}

/// Case 1's figures of one run: the approach speed, the rebound and the mirror symmetry.
#[derive(Clone, Debug)]
pub struct Rebound {
    /// Speed of the left disk at t = 0.1 (before contact).
    pub approach: f64,
    /// Its most negative velocity after contact (the rebound).
    pub rebound: f64,
    /// `−rebound / approach`.
    pub restitution: f64,
    /// Largest |x_l + x_r − 2|, |y_l − y_r|, |u_l + u_r| over the samples.
    pub mirror: f64,
}

fn rebound(b: &Bodies) -> Rebound {
    let (ul, ur) = (&b.u[0], &b.u[1]);
    let k01 = (0..b.t.len())
        .min_by(|&i, &j| (b.t[i] - 0.1).abs().total_cmp(&(b.t[j] - 0.1).abs()))
        .unwrap_or(0);
    let approach = ul[k01];
    let rebound = ul.iter().copied().fold(f64::INFINITY, f64::min);
    let mirror = (0..b.t.len())
        .map(|s| {
            (b.x[0][s] + b.x[1][s] - 2.0)
                .abs()
                .max((b.y[0][s] - b.y[1][s]).abs())
                .max((ul[s] + ur[s]).abs())
        })
        .fold(0.0, f64::max);
    Rebound {
        approach,
        rebound,
        restitution: -rebound / approach,
        mirror,
    }
}

/// Each run's [`Rebound`] and the checks of two disks head-on in every run: the separation
/// checks, the mirror symmetry about x = 1 and that the disks part again.
fn head_on_checks(all: &[&Bodies]) -> (Vec<Rebound>, Vec<Check>) {
    let reb: Vec<Rebound> = all.iter().map(|b| rebound(b)).collect();
    let mut checks = separation_checks(all);
    checks.push(Check::at_most(
        "mirror symmetry about x = 1: largest |x_l + x_r − 2|, |y_l − y_r|, |u_l + u_r|",
        reb.iter().map(|r| r.mirror).fold(0.0, f64::max),
        1e-10,
        "e",
    ));
    checks.push(Check::at_least(
        "the disks part again: least rebound speed −u_l after contact, every run",
        reb.iter().map(|r| -r.rebound).fold(f64::INFINITY, f64::min),
        0.1,
        "3",
    ));
    (reb, checks)
}

impl Case for TwoSoftDisks {
    const NAME: &'static str = "two_soft_disks";
    type Setting = usize;
    type Measured = Bodies;

    fn plan(opts: &Options) -> Plan<Self> {
        // The coarser grids (32², 48²: 3 and 5 cells per radius) are not yet in the range where
        // the restitution converges monotonically.
        let (grids, end): (&[usize], f64) = if opts.quick {
            (&[64, 96, 128], 0.7)
        } else {
            (&[64, 128, 256], 1.0)
        };
        let plan = grids.iter().map(|&n| (format!("{n}²"), n)).collect();
        Ok((TwoSoftDisks { end }, plan))
    }

    fn folder(&self, _: &str, n: &usize) -> String {
        format!("N{n}")
    }

    fn scene(&self, &n: &usize) -> Result<(Scene, PathBuf), String> {
        square("two_soft_disks.ron", n, Some(self.end))
    }

    fn measure(&self, _: &usize, _: &Simulation, run: &mut Run) -> Result<Bodies, String> {
        let b = read(run)?;
        let r = rebound(&b);
        run.metrics = vec![
            ("approach".into(), r.approach),
            ("rebound".into(), r.rebound),
            ("restitution".into(), r.restitution),
            ("mirror".into(), r.mirror),
            ("overlap".into(), b.overlap),
            ("volume_drift".into(), b.volume_drift),
        ];
        Ok(b)
    }

    fn conclude(&self, h: &mut Harness, done: &mut Done<Self>) -> Result<Verdict, String> {
        let (diffs, order) = grid_study(done, |a, b| {
            (rebound(a).restitution - rebound(b).restitution).abs()
        });
        let runs = paired(done);
        let all: Vec<&Bodies> = runs.iter().map(|(_, b)| *b).collect();
        let (reb, mut checks) = head_on_checks(&all);
        let e: Vec<f64> = reb.iter().map(|r| r.restitution).collect();
        checks.push(Check::at_most(
            "restitution converges: ratio of successive grids' differences",
            if diffs.len() >= 2 {
                largest_ratio(diffs.iter().copied())
            } else {
                f64::NAN
            },
            1.0,
            "3",
        ));
        let series: Vec<_> = runs
            .iter()
            .map(|(r, b)| xy(&r.label, &b.t, &b.u[0]))
            .collect();
        h.figure(
            "left_disk_velocity",
            ("Left disk's velocity u_l(t)", "t", "u_l"),
            &series,
            Scale::Linear,
        );
        for ((r, _), rb) in runs.iter().zip(&reb) {
            h.notes.push(format!(
                "{}: approach {:.4} at t = 0.1, rebound {:.4}, restitution {:.4}; mirror {:.1e}; \
                 {} steps in {:.1} s",
                r.label,
                rb.approach,
                rb.rebound,
                rb.restitution,
                rb.mirror,
                r.steps,
                r.wall_seconds
            ));
        }
        h.notes.push(format!(
            "restitution differences between successive grids {}; observed order {order:.2}",
            diffs
                .iter()
                .map(|d| format!("{d:.4}"))
                .collect::<Vec<_>>()
                .join(", ")
        ));
        Ok(Verdict {
            title: "two soft disks in head-on approach".into(),
            reference: "self-convergence and the mirror symmetry about x = 1".into(),
            error_metric: "difference of the restitution −u_rebound/u(0.1) from the finest \
                           grid's"
                .into(),
            checks,
            recommendation: format!(
                "the finest grid: restitution {}",
                e.last().map_or("—".into(), |e| format!("{e:.4}"))
            ),
        })
    }
}

/// The contact model's map on case 1: the two soft disks of [`TwoSoftDisks`] at the scene's
/// grid (and, in the full version, twice as fine) over the repulsion's `range` (cells) ×
/// `stiffness` κ (`numerics.contact`, `efsi_stages::contact`), κ from 0 (the resolved film
/// alone) through the scene's default `10 ρ_max U²` = 50 to ten times it. Each run must keep the
/// bodies apart and whole, mirror-symmetric, and never gain energy: its kinetic plus strain
/// energy stays at most its start's (the repulsion stores `E_c ≥ 0` and gives it back; the
/// energy guard, which counts `E_c`, would stop a run that gained).
pub struct ContactMap {
    end: f64,
}

/// One run of the map: grid cells across, the halo's range (cells) and κ (Pa).
#[derive(Clone, Copy, Debug)]
pub struct MapRun {
    /// Cells across the box.
    pub n: usize,
    /// `numerics.contact.range`.
    pub range: f64,
    /// `numerics.contact.stiffness`.
    pub stiffness: f64,
}

/// What a run of the map shows: its bodies and the largest kinetic plus strain energy over its
/// start's.
pub struct MapMeasured {
    /// The bodies' probes.
    pub bodies: Bodies,
    /// Largest `(E_k + Σ_k W_k) / E_k(0)` over the samples.
    pub energy_ratio: f64,
}

/// A line of the map: the grid's cells across and the range, and each of its runs' κ,
/// restitution and most shared cells.
type MapLine = ((usize, f64), Vec<(f64, f64, f64)>);

/// The map's stiffnesses (Pa): 0, a tenth of, equal to and ten times the scene's default 50.
const MAP_STIFFNESS: [f64; 4] = [0.0, 5.0, 50.0, 500.0];

impl Case for ContactMap {
    const NAME: &'static str = "contact_map";
    type Setting = MapRun;
    type Measured = MapMeasured;

    fn plan(opts: &Options) -> Plan<Self> {
        let (grids, ranges, kappas, end): (&[usize], &[f64], &[f64], f64) = if opts.quick {
            (&[64], &[1.0, 2.0], &[0.0, 50.0], 0.7)
        } else {
            (&[64, 128], &[0.5, 1.0, 2.0], &MAP_STIFFNESS, 1.0)
        };
        let mut plan = Vec::new();
        for &n in grids {
            for &range in ranges {
                for &stiffness in kappas {
                    plan.push((
                        format!("{n}², range {range}, κ {stiffness}"),
                        MapRun {
                            n,
                            range,
                            stiffness,
                        },
                    ));
                }
            }
        }
        Ok((ContactMap { end }, plan))
    }

    fn folder(&self, _: &str, r: &MapRun) -> String {
        format!("N{}_range{}_k{}", r.n, r.range, r.stiffness)
    }

    fn scene(&self, r: &MapRun) -> Result<(Scene, PathBuf), String> {
        let (mut scene, path) = square("two_soft_disks.ron", r.n, Some(self.end))?;
        scene
            .set("numerics.contact.range", r.range)
            .and_then(|()| scene.set("numerics.contact.stiffness", r.stiffness))
            .map_err(|e| e.to_string())?;
        Ok((scene, path))
    }

    fn measure(&self, _: &MapRun, _: &Simulation, run: &mut Run) -> Result<MapMeasured, String> {
        let bodies = read(run)?;
        if bodies.strain.is_empty() {
            return Err(format!(
                "{}: the scene does not probe ElasticEnergy",
                run.label
            ));
        }
        let mut energy = bodies.kinetic.clone();
        for w in &bodies.strain {
            for (e, w) in energy.iter_mut().zip(w) {
                *e += w;
            }
        }
        let start = energy.first().copied().unwrap_or(f64::NAN);
        let energy_ratio = energy.iter().map(|e| e / start).fold(0.0, f64::max);
        let r = rebound(&bodies);
        run.metrics = vec![
            ("restitution".into(), r.restitution),
            ("mirror".into(), r.mirror),
            ("overlap".into(), bodies.overlap),
            ("shared_cells".into(), bodies.shared_cells),
            ("energy_ratio".into(), energy_ratio),
        ];
        Ok(MapMeasured {
            bodies,
            energy_ratio,
        })
    }

    fn conclude(&self, h: &mut Harness, done: &mut Done<Self>) -> Result<Verdict, String> {
        let all: Vec<&Bodies> = done.measured.iter().map(|(_, m)| &m.bodies).collect();
        let (reb, mut checks) = head_on_checks(&all);
        checks.push(Check::at_most(
            "no energy gained: largest (kinetic + strain energy) ÷ its start, every run",
            done.measured
                .iter()
                .map(|(_, m)| m.energy_ratio)
                .fold(0.0, f64::max),
            1.0,
            "6",
        ));
        // The map, one line per grid and range: each run's κ, restitution and shared cells.
        let mut lines: Vec<MapLine> = Vec::new();
        for ((r, m), rb) in done.measured.iter().zip(&reb) {
            let point = (r.stiffness, rb.restitution, m.bodies.shared_cells);
            match lines.iter_mut().find(|(key, _)| *key == (r.n, r.range)) {
                Some((_, points)) => points.push(point),
                None => lines.push(((r.n, r.range), vec![point])),
            }
        }
        let mut series = Vec::new();
        for ((n, range), points) in &lines {
            let cells: Vec<String> = points
                .iter()
                .map(|(k, e, shared)| format!("κ {k} → {e:.4} (shared cells {shared})"))
                .collect();
            h.notes.push(format!(
                "{n}², range {range} (cells): restitution {}",
                cells.join(", ")
            ));
            let pts = points.iter().map(|&(k, e, _)| (k, e)).collect();
            series.push((format!("{n}², range {range}"), pts));
        }
        h.figure(
            "restitution_map",
            ("Restitution over the contact stiffness κ", "κ (Pa)", "e"),
            &series,
            Scale::Linear,
        );
        Ok(Verdict {
            title: "the contact model's range × stiffness on two soft disks head-on".into(),
            reference: "the film alone (κ = 0) and the mirror symmetry; no energy gained".into(),
            error_metric: "none".into(),
            checks,
            recommendation: "the defaults: range 1 cell, κ = 10 ρ_max U² (50 here)".into(),
        })
    }
}

/// Case 3: twenty disks settling in a closed box.
pub struct TwentyDisks {
    end: Option<f64>,
}

impl Case for TwentyDisks {
    const NAME: &'static str = "twenty_disks";
    type Setting = usize;
    type Measured = Bodies;

    fn plan(opts: &Options) -> Plan<Self> {
        let (grid, end) = if opts.quick {
            (64, Some(0.5))
        } else {
            (128, None)
        };
        Ok((TwentyDisks { end }, vec![(format!("{grid}²"), grid)]))
    }

    fn folder(&self, _: &str, n: &usize) -> String {
        format!("N{n}")
    }

    fn scene(&self, &n: &usize) -> Result<(Scene, PathBuf), String> {
        square("twenty_disks.ron", n, self.end)
    }

    fn measure(&self, _: &usize, _: &Simulation, run: &mut Run) -> Result<Bodies, String> {
        let b = read(run)?;
        let peak = b.kinetic.iter().copied().fold(0.0, f64::max);
        run.metrics = vec![
            ("peak_kinetic_energy".into(), peak),
            (
                "final_kinetic_energy".into(),
                b.kinetic.last().copied().unwrap_or(f64::NAN),
            ),
            ("overlap".into(), b.overlap),
            ("shared_cells".into(), b.shared_cells),
            ("volume_drift".into(), b.volume_drift),
        ];
        Ok(b)
    }

    fn conclude(&self, h: &mut Harness, done: &mut Done<Self>) -> Result<Verdict, String> {
        let runs = paired(done);
        let all: Vec<&Bodies> = runs.iter().map(|(_, b)| *b).collect();
        let mut checks = separation_checks(&all);
        checks.push(Check::at_most(
            "cells two bodies share, every output",
            all.iter().map(|b| b.shared_cells).fold(0.0, f64::max),
            0.0,
            "0",
        ));
        if self.end.is_none() {
            let ratio = all
                .iter()
                .map(|b| {
                    let peak = b.kinetic.iter().copied().fold(0.0, f64::max);
                    b.kinetic.last().copied().unwrap_or(f64::NAN) / peak
                })
                .fold(0.0, f64::max);
            checks.push(Check::at_most(
                "kinetic energy at the end ÷ its peak (settled to rest)",
                ratio,
                REST,
                "e",
            ));
        }
        let series: Vec<_> = runs
            .iter()
            .map(|(r, b)| xy(&r.label, &b.t, &b.kinetic))
            .collect();
        h.figure(
            "kinetic_energy",
            ("Kinetic energy of the scene", "t", "E_k"),
            &series,
            Scale::Linear,
        );
        for (r, b) in &runs {
            let peak = b.kinetic.iter().copied().fold(0.0, f64::max);
            h.notes.push(format!(
                "{}: {} bodies; kinetic energy peak {peak:.3e}, at t = {:.2}: {:.3e}; lowest \
                 centroid y {:.4}; max Σφ {:.15}; shared cells {}; volume drift {:.1e}; {} steps \
                 in {:.1} s",
                r.label,
                b.names.len(),
                b.t.last().copied().unwrap_or(f64::NAN),
                b.kinetic.last().copied().unwrap_or(f64::NAN),
                b.y.iter().flatten().copied().fold(f64::INFINITY, f64::min),
                b.overlap,
                b.shared_cells,
                b.volume_drift,
                r.steps,
                r.wall_seconds
            ));
            h.notes
                .push(format!("{}: at the end, {}", r.label, end_motion(b)));
        }
        Ok(Verdict {
            title: "twenty soft disks of two materials settling in a closed box".into(),
            reference: "conservation and separation of every body; rest at the end".into(),
            error_metric: "none".into(),
            checks,
            recommendation: "the scene's grid (9 cells per radius)".into(),
        })
    }
}

/// How the bodies move at the last sample: the fastest centroid and the fastest turning body
/// (where the scene probes `SolidSpin`), which show whether what is left of the motion is the
/// bodies' drift or their turning in place.
fn end_motion(b: &Bodies) -> String {
    let last = |q: &[f64]| q.last().copied().unwrap_or(f64::NAN);
    let speed = (0..b.names.len())
        .map(|k| last(&b.u[k]).hypot(last(&b.v[k])))
        .fold(0.0, f64::max);
    let turning = b
        .spin
        .iter()
        .map(|w| last(w).abs())
        .zip(&b.names)
        .max_by(|x, y| x.0.total_cmp(&y.0));
    match turning {
        Some((w, name)) => {
            format!("fastest centroid {speed:.2e}; fastest turning {name} at {w:.3} rad/s")
        }
        None => format!("fastest centroid {speed:.2e}"),
    }
}

/// The kinetic energy at the end of the twenty-disk run, as a share of its peak, for the
/// bodies to count as settled.
const REST: f64 = 0.05;

/// The note of a grid study of paths: the differences between successive grids' paths and
/// their observed order.
fn path_note(gaps: &[f64], order: f64) -> String {
    let gaps: Vec<String> = gaps.iter().map(|g| format!("{g:.5}")).collect();
    format!(
        "difference between successive grids' paths: {}; observed order {order:.2}",
        gaps.join(", ")
    )
}

/// Case 4: three disks carried round the lid-driven cavity, on three grids.
pub struct DisksInCavity {
    end: f64,
}

impl Case for DisksInCavity {
    const NAME: &'static str = "disks_in_cavity";
    type Setting = usize;
    type Measured = Bodies;

    fn plan(opts: &Options) -> Plan<Self> {
        let (grids, end): (&[usize], f64) = if opts.quick {
            (&[32, 40, 48], 1.0)
        } else {
            (&[64, 96, 128], 8.0)
        };
        let plan = grids.iter().map(|&n| (format!("{n}²"), n)).collect();
        Ok((DisksInCavity { end }, plan))
    }

    fn folder(&self, _: &str, n: &usize) -> String {
        format!("N{n}")
    }

    fn scene(&self, &n: &usize) -> Result<(Scene, PathBuf), String> {
        square("disks_in_cavity.ron", n, Some(self.end))
    }

    fn measure(&self, _: &usize, _: &Simulation, run: &mut Run) -> Result<Bodies, String> {
        let b = read(run)?;
        run.metrics = vec![
            ("overlap".into(), b.overlap),
            ("shared_cells".into(), b.shared_cells),
            ("volume_drift".into(), b.volume_drift),
        ];
        Ok(b)
    }

    fn conclude(&self, h: &mut Harness, done: &mut Done<Self>) -> Result<Verdict, String> {
        let end = self.end;
        let (gaps, order) = grid_study(done, paths_gap);
        let runs = paired(done);
        let all: Vec<&Bodies> = runs.iter().map(|(_, b)| *b).collect();
        let mut checks = separation_checks(&all);
        checks.push(Check::at_most(
            "paths converge: ratio of successive grid pairs' path differences (mean distance \
             at equal times, over the bodies)",
            if gaps.len() >= 2 && gaps.iter().all(|g| g.is_finite()) {
                largest_ratio(gaps.iter().copied())
            } else {
                f64::NAN
            },
            1.0,
            "3",
        ));
        let mut paths = Vec::new();
        for (r, b) in &runs {
            for (k, n) in b.names.iter().enumerate() {
                paths.push(xy(&format!("{} {n}", r.label), &b.x[k], &b.y[k]));
            }
        }
        h.figure(
            "centroid_paths",
            (
                &format!("The disks' centroid paths, 0 ≤ t ≤ {end}"),
                "x_c",
                "y_c",
            ),
            &paths,
            Scale::Linear,
        );
        for (r, b) in &runs {
            let ends: Vec<String> = (0..b.names.len())
                .map(|k| {
                    format!(
                        "{} ({:.4}, {:.4})",
                        b.names[k],
                        b.x[k].last().copied().unwrap_or(f64::NAN),
                        b.y[k].last().copied().unwrap_or(f64::NAN)
                    )
                })
                .collect();
            h.notes.push(format!(
                "{}: centroids at t = {:.2}: {}; max Σφ {:.15}; shared cells {}; volume drift \
                 {:.1e}; {} steps in {:.1} s",
                r.label,
                b.t.last().copied().unwrap_or(f64::NAN),
                ends.join(", "),
                b.overlap,
                b.shared_cells,
                b.volume_drift,
                r.steps,
                r.wall_seconds
            ));
        }
        h.notes.push(path_note(&gaps, order));
        let finest = runs.last().map_or(String::new(), |(r, _)| r.label.clone());
        Ok(Verdict {
            title: "three soft disks in the lid-driven cavity (Re = 100)".into(),
            reference: "self-convergence of the three centroid paths".into(),
            error_metric: format!(
                "mean distance of the centroid samples (every 0.02, t ≤ {end}, over the three \
                 bodies) to the finest grid's ({finest}) paths at equal times"
            ),
            checks,
            recommendation: format!(
                "{finest} or finer: the grids here differ by {} at equal times",
                gaps.last().map_or("—".into(), |g| format!("{g:.4}"))
            ),
        })
    }
}

/// Case 2: a soft sphere falling onto another resting on the floor, on the axis, on three
/// grids.
pub struct SpheresOnAxis {
    end: f64,
}

/// Case 2's figures of one run: the upper sphere's first impact and rebound.
#[derive(Clone, Debug)]
pub struct Impact {
    /// The upper sphere's speed at its first impact (its most negative velocity before it
    /// first moves up).
    pub impact: f64,
    /// Its largest upward velocity after the impact.
    pub rebound: f64,
    /// `−rebound / impact`.
    pub restitution: f64,
    /// The closest approach of the two spheres' surfaces along the axis, from the centroids
    /// (negative: both flattened against the film between them).
    pub closest: f64,
}

fn impact(b: &Bodies, radius: f64) -> Impact {
    let v = &b.v[1];
    // The first impact ends where the upper sphere first moves up.
    let up = v.iter().position(|&v| v > 0.0).unwrap_or(v.len());
    let impact = v[..up].iter().copied().fold(0.0, f64::min);
    // Its rebound: the largest upward velocity before it turns down again.
    let down = v[up..]
        .iter()
        .position(|&v| v < 0.0)
        .map_or(v.len(), |k| up + k);
    let rebound = v[up..down].iter().copied().fold(0.0, f64::max);
    let closest = (0..b.t.len())
        .map(|s| b.y[1][s] - b.y[0][s] - 2.0 * radius)
        .fold(f64::INFINITY, f64::min);
    Impact {
        impact,
        rebound,
        restitution: -rebound / impact,
        closest,
    }
}

/// The spheres' radius in `cases/spheres_on_axis.ron`.
const SPHERE_RADIUS: f64 = 0.2;

impl Case for SpheresOnAxis {
    const NAME: &'static str = "spheres_on_axis";
    type Setting = usize;
    type Measured = Bodies;

    fn plan(opts: &Options) -> Plan<Self> {
        // The quick version runs one grid (the checks of separation and rebound); the paths'
        // convergence needs the full version's grids.
        let (grids, end): (&[usize], f64) = if opts.quick {
            (&[32], 0.9)
        } else {
            (&[32, 64, 128], 1.0)
        };
        let plan = grids
            .iter()
            .map(|&n| (format!("{n} × {}", 2 * n), n))
            .collect();
        Ok((SpheresOnAxis { end }, plan))
    }

    fn folder(&self, _: &str, n: &usize) -> String {
        format!("N{n}")
    }

    fn scene(&self, &n: &usize) -> Result<(Scene, PathBuf), String> {
        let (mut scene, path) = load_case("spheres_on_axis.ron")?;
        scene.grid.nx = n;
        scene.grid.ny = 2 * n;
        scene.time.end = self.end;
        scene.update_output(|o| o.vtk_every = None)?;
        Ok((scene, path))
    }

    fn measure(&self, _: &usize, _: &Simulation, run: &mut Run) -> Result<Bodies, String> {
        let b = read(run)?;
        let i = impact(&b, SPHERE_RADIUS);
        run.metrics = vec![
            ("impact".into(), i.impact),
            ("rebound".into(), i.rebound),
            ("restitution".into(), i.restitution),
            ("closest".into(), i.closest),
            ("overlap".into(), b.overlap),
            ("volume_drift".into(), b.volume_drift),
        ];
        Ok(b)
    }

    fn conclude(&self, h: &mut Harness, done: &mut Done<Self>) -> Result<Verdict, String> {
        let (gaps, order) = grid_study(done, paths_gap);
        let runs = paired(done);
        let all: Vec<&Bodies> = runs.iter().map(|(_, b)| *b).collect();
        let hits: Vec<Impact> = all.iter().map(|b| impact(b, SPHERE_RADIUS)).collect();
        let e: Vec<f64> = hits.iter().map(|i| i.restitution).collect();
        let mut checks = separation_checks(&all);
        checks.push(Check::at_most(
            "cells the two spheres share, every output",
            all.iter().map(|b| b.shared_cells).fold(0.0, f64::max),
            0.0,
            "0",
        ));
        checks.push(Check::at_least(
            "the spheres part again: least rebound speed of the upper sphere, every run",
            hits.iter().map(|i| i.rebound).fold(f64::INFINITY, f64::min),
            0.1,
            "3",
        ));
        if gaps.len() >= 2 {
            checks.push(Check::at_most(
                "paths converge: ratio of successive grid pairs' path differences (mean \
                 distance of the centroids at equal times, both spheres)",
                largest_ratio(gaps.iter().copied()),
                1.0,
                "3",
            ));
        }
        let series: Vec<_> = runs
            .iter()
            .flat_map(|(r, b)| {
                [
                    xy(&format!("{} lower", r.label), &b.t, &b.v[0]),
                    xy(&format!("{} upper", r.label), &b.t, &b.v[1]),
                ]
            })
            .collect();
        h.figure(
            "velocities",
            ("The spheres' axial velocities", "t", "v"),
            &series,
            Scale::Linear,
        );
        for ((r, b), i) in runs.iter().zip(&hits) {
            h.notes.push(format!(
                "{}: impact {:.4}, rebound {:.4}, restitution {:.4}; closest surfaces {:.4}; max \
                 Σφ {:.15}; volume drift {:.1e}; {} steps in {:.1} s",
                r.label,
                i.impact,
                i.rebound,
                i.restitution,
                i.closest,
                b.overlap,
                b.volume_drift,
                r.steps,
                r.wall_seconds
            ));
        }
        if !gaps.is_empty() {
            h.notes.push(path_note(&gaps, order));
        }
        Ok(Verdict {
            title: "a soft sphere falling onto another resting on the floor (axisymmetric)".into(),
            reference: "self-convergence; each body's volume and separation".into(),
            error_metric: "mean distance of both spheres' centroid samples to the finest grid's \
                           paths at equal times"
                .into(),
            checks,
            recommendation: format!(
                "the finest grid: restitution {}",
                e.last().map_or("—".into(), |e| format!("{e:.4}"))
            ),
        })
    }
}
