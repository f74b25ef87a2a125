//! Seed §5.1: the silicone sphere dropped on a rigid substrate (`cases/sphere_impact*.ron`),
//! against free fall before contact and Hertz's contact estimates
//! (`tests/references/hertz_sphere_impact/`). The measurement of a run (`analyse`) serves the
//! axisymmetric sphere and the three-dimensional one of [`super::sphere_3d`] alike.

use super::case::{
    Case, Done, Harness, Plan, Verdict, deviation, drift, drift_check, stage_names, trade,
};
use super::plot::Scale;
use super::{Check, Options, Run, load_case, probes};
use efsi_core::scene::{Boundary, Side};
use efsi_core::{Geometry, Scene, Simulation};
use efsi_run::{ProbeSpec, SceneOutput};
use efsi_stages::solid::{SceneSolid, Shape, Solid};
use std::f64::consts::PI;

/// The sphere's material and initial condition, read from its scene.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Sphere {
    pub(crate) radius: f64,
    density: f64,
    shear_modulus: f64,
    /// The centre's initial height (y; z when axisymmetric).
    pub(crate) z0: f64,
    v0: f64,
    g: f64,
    /// The whole sphere over the part the domain holds, by which a probe's force is
    /// multiplied: 2π for an axisymmetric scene (its forces are per radian), 2 for each
    /// Symmetry plane through the centre of a Cartesian3D one (4 on a quarter domain).
    whole: f64,
}

/// The solid of `scene`, or why there is none.
pub(crate) fn solid_of(scene: &Scene) -> Result<Solid, String> {
    scene
        .solid_spec()
        .map_err(|(f, m)| format!("{f}: {m}"))?
        .ok_or_else(|| "the scene has no solid".into())
}

/// The sphere of `scene`: a `Disk` centred on the axis of an axisymmetric scene, or a
/// `Sphere` of a Cartesian3D one (y vertical, cut by the Symmetry planes through its centre).
pub(crate) fn sphere_of(scene: &Scene) -> Result<Sphere, String> {
    let solid = solid_of(scene)?;
    let (radius, height, whole) = match solid.shape {
        Shape::Disk { center, radius } if scene.geometry == Geometry::Axisymmetric => {
            (radius, center.1, 2.0 * PI)
        }
        Shape::Sphere { center, radius } => {
            let z = scene
                .domain
                .z
                .ok_or("a Sphere in a scene without a z extent")?;
            let planes = [
                (Side::XMin, center.0, scene.domain.x.0),
                (Side::ZMin, center.2, z.0),
            ]
            .iter()
            .filter(|(side, c, wall)| {
                scene.boundaries.side(*side) == Some(&Boundary::Symmetry) && c == wall
            })
            .count();
            (radius, center.1, 2f64.powi(planes as i32))
        }
        _ => {
            return Err(
                "the solid is not a sphere (a Disk in an axisymmetric scene, or a Sphere)".into(),
            );
        }
    };
    let g = solid
        .law
        .as_ref()
        .and_then(|l| l.parameters.get("G").copied())
        .ok_or("the law has no parameter G")?;
    Ok(Sphere {
        radius,
        density: solid.density,
        shear_modulus: g,
        z0: height,
        v0: solid.velocity.map_or(0.0, |v| v.1),
        g: -scene.gravity.1,
        whole,
    })
}

/// The force level, as a fraction of its peak, above which the sphere counts as in contact.
const CONTACT: f64 = 0.02;

/// Hertz's quasi-static estimates at impact speed `v` (rigid flat, incompressible sphere,
/// E* = 4G): maximum approach δ, contact time, peak force, contact radius. The contact time is
/// the time the force spends above [`CONTACT`] of its peak, as measured in the simulation: with
/// Hertz's F ≈ F_max sin^{3/2}(πt/t_c) that is `t_c (1 − 2 asin(CONTACT^{2/3})/π)` (0.953 t_c).
fn hertz(s: &Sphere, v: f64) -> (f64, f64, f64, f64) {
    let m = 4.0 / 3.0 * PI * s.radius.powi(3) * s.density;
    let e_star = 4.0 * s.shear_modulus;
    let delta = (15.0 * m * v * v / (16.0 * e_star * s.radius.sqrt())).powf(0.4);
    let tc = 2.9433 * delta / v * (1.0 - 2.0 * CONTACT.powf(2.0 / 3.0).asin() / PI);
    let f = 4.0 / 3.0 * e_star * s.radius.sqrt() * delta.powf(1.5);
    (delta, tc, f, (s.radius * delta).sqrt())
}

/// What one run of the sphere shows.
#[derive(Clone, Debug, Default)]
pub struct Impact {
    pub(crate) t: Vec<f64>,
    pub(crate) z: Vec<f64>,
    v: Vec<f64>,
    force: Vec<f64>,
    /// Max |z − z_free|/z_free before contact.
    free_fall: f64,
    t_contact: f64,
    /// How long the force stays above [`CONTACT`] of its peak.
    pub(crate) contact_time: f64,
    pub(crate) impact_speed: f64,
    /// 2R minus the least axial height of the solid.
    pub(crate) compression: f64,
    /// R minus the lowest centroid height.
    centroid_drop: f64,
    peak_force: f64,
    contact_radius: f64,
    pub(crate) rebound_speed: f64,
    pub(crate) volume_drift: f64,
    /// The smallest share of the solid volume in its largest connected piece, over the outputs.
    pub(crate) largest_piece: f64,
    /// The most pieces at any output.
    pub(crate) pieces: f64,
    /// The run's pipeline.
    stages: Vec<String>,
}

/// What the probes of `run` show of the sphere `s`: the force on the whole sphere, the first
/// contiguous contact (force above [`CONTACT`] of its peak; its duration between the
/// threshold's crossings, interpolated between probe samples), the impact and rebound speeds
/// (the largest upward speed within 5 ms after the contact), the compression (2R minus the
/// least height along the axis), the volume drift and the pieces.
pub(crate) fn analyse(run: &Run, s: &Sphere) -> Result<Impact, String> {
    let p = probes(&run.dir)?;
    let t = p.col("t")?.to_vec();
    let z = p.col("solid_y")?.to_vec();
    let v = p.col("solid_v")?.to_vec();
    // The force on the domain's part of the sphere, times the whole over that part.
    let force: Vec<f64> = p
        .col("contact_force")?
        .iter()
        .map(|f| s.whole * f)
        .collect();
    let radius = p.col("contact_radius")?;
    let (bottom, top) = (p.col("solid_bottom")?, p.col("solid_top")?);
    let vol = p.col("solid_volume")?;
    let largest_piece = p
        .col("solid_largest_piece")?
        .iter()
        .copied()
        .fold(f64::MAX, f64::min);
    let pieces = p.col("solid_pieces")?.iter().copied().fold(0.0, f64::max);
    let peak = force.iter().copied().fold(0.0, f64::max);
    let on: Vec<usize> = (0..t.len())
        .filter(|&k| force[k] > CONTACT * peak)
        .collect();
    let (first, last) = match (on.first(), on.last()) {
        (Some(&a), Some(_)) if peak > 0.0 => {
            // The first contiguous contact.
            let mut b = a;
            while b + 1 < t.len() && force[b + 1] > CONTACT * peak {
                b += 1;
            }
            (a, b)
        }
        _ => {
            return Err(format!(
                "{}: the sphere never touched the substrate",
                run.label
            ));
        }
    };
    let free_fall = (0..first)
        .map(|k| {
            let za = s.z0 + s.v0 * t[k] - 0.5 * s.g * t[k] * t[k];
            ((z[k] - za) / za).abs()
        })
        .fold(0.0, f64::max);
    let impact_speed = -v[first];
    let height = (first..=last)
        .map(|k| top[k] - bottom[k])
        .fold(f64::MAX, f64::min);
    let zmin = (first..=last).map(|k| z[k]).fold(f64::MAX, f64::min);
    let after = last + 1
        ..t.len()
            .min(last + 1 + (0.005 / (t[1] - t[0])).ceil() as usize);
    let rebound_speed = after.map(|k| v[k]).fold(f64::MIN, f64::max);
    let volume_drift = drift(vol);
    // The times the force crosses the threshold, each interpolated linearly between the
    // samples either side of it (the sample itself at the ends of the record), so that the
    // contact time resolves less than a probe interval.
    let threshold = CONTACT * peak;
    let crossing = |a: usize, b: usize| {
        if a == b || force[a] == force[b] {
            t[b]
        } else {
            t[a] + (threshold - force[a]) / (force[b] - force[a]) * (t[b] - t[a])
        }
    };
    let start = crossing(first.saturating_sub(1), first);
    let end = crossing(last, (last + 1).min(t.len() - 1));
    Ok(Impact {
        free_fall,
        t_contact: t[first],
        contact_time: end - start,
        impact_speed,
        compression: 2.0 * s.radius - height,
        centroid_drop: s.radius - zmin,
        peak_force: peak,
        contact_radius: (first..=last).map(|k| radius[k]).fold(0.0, f64::max),
        rebound_speed,
        volume_drift,
        largest_piece,
        pieces,
        stages: Vec::new(),
        t,
        z,
        v,
        force,
    })
}

/// The sphere of `file` at `cpr` cells per radius (every axis, the third of a Cartesian3D
/// scene too) and Courant number `cfl`, with the `SolidPieces` probe, its VTK output only if
/// `vtk`.
pub(crate) fn scene_at(
    file: &str,
    cpr: f64,
    cfl: f64,
    vtk: bool,
) -> Result<(Scene, std::path::PathBuf), String> {
    let (mut scene, path) = load_case(file)?;
    let s = sphere_of(&scene)?;
    let h = s.radius / cpr;
    let cells = |(a, b): (f64, f64)| ((b - a) / h).round() as usize;
    scene.grid.nx = cells(scene.domain.x);
    scene.grid.ny = cells(scene.domain.y);
    scene.grid.nz = scene.domain.z.map(cells);
    scene.time.cfl = cfl;
    scene.update_output(|o| {
        if !o.probes.contains(&ProbeSpec::SolidPieces) {
            o.probes.push(ProbeSpec::SolidPieces);
        }
    })?;
    if !vtk {
        scene.update_output(|o| o.vtk_every = None)?;
    }
    Ok((scene, path))
}

/// One run of the sphere.
#[derive(Clone, Copy, Debug)]
pub enum Drop {
    /// Cells per radius, at CFL 0.4.
    Cpr(f64),
    /// A CFL number, at the middle resolution.
    Cfl(f64),
    /// Another initial condition of the seed (its scene and name), at the conditions'
    /// resolution.
    Condition(&'static str, &'static str),
}

/// The case: 8, 10, 12 cells per radius (quick) or 10 … 50, the CFL numbers at the middle
/// resolution and the seed's two other initial conditions.
pub struct SphereImpact {
    quick: bool,
    reference_cpr: f64,
    conditions_cpr: f64,
    /// The resolution of the CFL study.
    mid: f64,
    sphere: Sphere,
}

impl Case for SphereImpact {
    const NAME: &'static str = "sphere_impact";
    type Setting = Drop;
    type Measured = Impact;

    fn plan(opts: &Options) -> Plan<Self> {
        let (cprs, reference_cpr, conditions_cpr, cfls): (&[f64], f64, f64, &[f64]) = if opts.quick
        {
            (&[8.0, 10.0, 12.0], 12.0, 10.0, &[0.2])
        } else {
            (&[10.0, 15.0, 20.0, 35.0, 50.0], 50.0, 35.0, &[0.2, 0.8])
        };
        let mid = if opts.quick { 10.0 } else { 20.0 };
        let (base, _) = load_case("sphere_impact.ron")?;
        let mut plan: Vec<_> = cprs
            .iter()
            .map(|&c| (format!("{c} CPR"), Drop::Cpr(c)))
            .collect();
        plan.extend(
            cfls.iter()
                .map(|&c| (format!("{mid} CPR, CFL {c}"), Drop::Cfl(c))),
        );
        for (file, name) in [
            ("sphere_impact_case1.ron", "case 1 (61.9 mm, 0.73 m/s)"),
            ("sphere_impact_case2.ron", "case 2 (58.6 mm, 1.06 m/s)"),
        ] {
            plan.push((
                format!("{name} {conditions_cpr} CPR"),
                Drop::Condition(file, name),
            ));
        }
        let case = SphereImpact {
            quick: opts.quick,
            reference_cpr,
            conditions_cpr,
            mid,
            sphere: sphere_of(&base)?,
        };
        Ok((case, plan))
    }

    fn scene(&self, s: &Drop) -> Result<(Scene, std::path::PathBuf), String> {
        match *s {
            Drop::Cpr(cpr) => scene_at("sphere_impact.ron", cpr, 0.4, cpr == self.conditions_cpr),
            Drop::Cfl(cfl) => scene_at("sphere_impact.ron", self.mid, cfl, false),
            Drop::Condition(file, _) => scene_at(file, self.conditions_cpr, 0.4, false),
        }
    }

    fn measure(&self, s: &Drop, sim: &Simulation, run: &mut Run) -> Result<Impact, String> {
        let (scene, _) = self.scene(s)?;
        let mut i = analyse(run, &sphere_of(&scene)?)?;
        i.stages = stage_names(sim);
        Ok(i)
    }

    fn conclude(&self, h: &mut Harness, done: &mut Done<Self>) -> Result<Verdict, String> {
        let (sphere, reference_cpr, mid) = (&self.sphere, self.reference_cpr, self.mid);
        // The pipeline of the resolution study.
        h.schedule = done
            .measured
            .iter()
            .rev()
            .find(|(s, _)| matches!(s, Drop::Cpr(_)))
            .map(|(_, i)| i.stages.clone())
            .unwrap_or_default();
        let n_main = done
            .measured
            .iter()
            .filter(|(s, _)| !matches!(s, Drop::Condition(..)))
            .count();
        let (main, cond) = done.runs.split_at_mut(n_main);
        let mut runs: Vec<(&mut Run, &Impact)> = main
            .iter_mut()
            .zip(done.measured.iter().map(|(_, i)| i))
            .collect();
        let conditions: Vec<(String, &Run, &Impact)> = cond
            .iter()
            .zip(&done.measured[n_main..])
            .filter_map(|(r, (s, i))| match s {
                Drop::Condition(_, name) => Some((name.to_string(), r, i)),
                _ => None,
            })
            .collect();
        // Error of each run: the largest distance of its centroid path from the finest run's
        // (reference_cpr), relative to R.
        let reference = runs
            .iter()
            .find(|(r, _)| r.label == format!("{reference_cpr} CPR"))
            .map(|(_, i)| (*i).clone())
            .ok_or("no reference run")?;
        for (r, i) in runs.iter_mut() {
            let e = deviation(&i.t, &i.z, (&reference.t, &reference.z)) / sphere.radius;
            r.error = (r.label != format!("{reference_cpr} CPR")).then_some(e);
            let (dh, th, fh, ah) = hertz(sphere, i.impact_speed);
            r.metrics = vec![
                ("free_fall_error".into(), i.free_fall),
                ("impact_time_s".into(), i.t_contact),
                ("impact_speed".into(), i.impact_speed),
                ("contact_time_s".into(), i.contact_time),
                ("hertz_contact_time_s".into(), th),
                ("compression_m".into(), i.compression),
                ("centroid_drop_m".into(), i.centroid_drop),
                ("hertz_compression_m".into(), dh),
                ("peak_force_N".into(), i.peak_force),
                ("hertz_peak_force_N".into(), fh),
                ("contact_radius_m".into(), i.contact_radius),
                ("hertz_contact_radius_m".into(), ah),
                ("rebound_speed".into(), i.rebound_speed),
                ("restitution".into(), i.rebound_speed / i.impact_speed),
                ("volume_drift".into(), i.volume_drift),
                ("largest_piece_min".into(), i.largest_piece),
                ("pieces_max".into(), i.pieces),
            ];
        }
        let runs: Vec<(&Run, &Impact)> = runs.into_iter().map(|(r, i)| (&*r, i)).collect();
        // Checks, on the run the paper's claims are about (35 CPR; the finest in quick mode).
        let judge_cpr = if self.quick { reference_cpr } else { 35.0 };
        let (jr, _) = runs
            .iter()
            .find(|(r, _)| r.label == format!("{judge_cpr} CPR"))
            .ok_or("no judged run")?;
        let m = |n: &str| jr.metric(n).unwrap_or(f64::NAN);
        let mut checks = vec![
            Check::at_most(
                format!(
                    "free fall: max abs(z − z_free)/z_free before contact ({})",
                    jr.label
                ),
                m("free_fall_error"),
                0.005,
                "%",
            ),
            Check::within(
                format!("restitution e = v_rebound / v_impact ({})", jr.label),
                m("restitution"),
                0.5,
                1.0,
                "3",
            ),
            drift_check(
                "solid volume drift, every run",
                runs.iter()
                    .map(|(_, i)| i.volume_drift)
                    .chain(conditions.iter().map(|(_, _, i)| i.volume_drift)),
            ),
            Check::at_least(
                "one piece: the largest connected piece's share of the solid volume, least over every output of every run at 10 CPR or more",
                runs.iter()
                    .filter(|(r, _)| {
                        r.label
                            .split(' ')
                            .next()
                            .and_then(|c| c.parse::<f64>().ok())
                            .is_some_and(|c| c >= 10.0)
                    })
                    .map(|(_, i)| i.largest_piece)
                    .chain(conditions.iter().map(|(_, _, i)| i.largest_piece))
                    .fold(f64::MAX, f64::min),
                0.999,
                "%",
            ),
        ];
        if !self.quick {
            let rel = |a: f64, b: f64| (a - b) / b;
            checks.push(Check::within(
                format!(
                    "contact time (force above 2 % of its peak) vs Hertz {:.2} ms ({})",
                    1e3 * m("hertz_contact_time_s"),
                    jr.label
                ),
                rel(m("contact_time_s"), m("hertz_contact_time_s")),
                -0.15,
                0.15,
                "%",
            ));
            checks.push(Check::within(
                format!(
                    "max compression 2R − height vs Hertz {:.2} mm ({})",
                    1e3 * m("hertz_compression_m"),
                    jr.label
                ),
                rel(m("compression_m"), m("hertz_compression_m")),
                -0.15,
                0.15,
                "%",
            ));
            let r35 = m("rebound_speed");
            let r50 = runs
                .iter()
                .find(|(r, _)| r.label == "50 CPR")
                .and_then(|(r, _)| r.metric("rebound_speed"))
                .unwrap_or(f64::NAN);
            checks.push(Check::at_most(
                "rebound speed, 35 vs 50 CPR, relative difference",
                ((r35 - r50) / r50).abs(),
                0.05,
                "%",
            ));
        }
        // Plots and their series.
        let by_cpr: Vec<(&Run, &Impact)> = runs
            .iter()
            .copied()
            .filter(|(r, _)| !r.label.contains("CFL"))
            .collect();
        // Time histories in ms of one quantity, per labelled run.
        let history = |runs: &[(String, &Impact)], y: fn(&Impact) -> &[f64], scale: f64| {
            runs.iter()
                .map(|(n, i)| {
                    let pts =
                        i.t.iter()
                            .zip(y(i))
                            .map(|(t, v)| (1e3 * t, scale * v))
                            .collect();
                    (n.clone(), pts)
                })
                .collect::<Vec<(String, Vec<(f64, f64)>)>>()
        };
        let cpr: Vec<(String, &Impact)> =
            by_cpr.iter().map(|(r, i)| (r.label.clone(), *i)).collect();
        let base_run = by_cpr
            .iter()
            .find(|(r, _)| r.label == format!("{} CPR", self.conditions_cpr))
            .ok_or("no conditions run")?;
        let mut three = vec![("baseline (57.3 mm, 1.22 m/s)".to_string(), base_run.1)];
        for (n, _, i) in &conditions {
            three.push((n.clone(), *i));
        }
        for (file, title, y, runs, q, scale) in [
            (
                "fig5a_centroid",
                "Centroid height vs time (seed Fig. 5a)",
                "z (mm)",
                &cpr,
                (|i: &Impact| &i.z[..]) as fn(&Impact) -> &[f64],
                1e3,
            ),
            (
                "fig5b_velocity",
                "Axial velocity vs time (seed Fig. 5b)",
                "v (m/s)",
                &cpr,
                |i: &Impact| &i.v[..],
                1.0,
            ),
            (
                "contact_force",
                "Contact force on the substrate",
                "F (N)",
                &cpr,
                |i: &Impact| &i.force[..],
                1.0,
            ),
            (
                "fig7_centroid",
                "Three initial conditions: centroid height (seed Figs. 7–8a)",
                "z (mm)",
                &three,
                |i: &Impact| &i.z[..],
                1e3,
            ),
            (
                "fig8_velocity",
                "Three initial conditions: axial velocity (seed Figs. 7–8b)",
                "v (m/s)",
                &three,
                |i: &Impact| &i.v[..],
                1.0,
            ),
        ] {
            h.figure(
                file,
                (title, "t (ms)", y),
                &history(runs, q, scale),
                Scale::Linear,
            );
        }
        h.figure(
            "tradeoff",
            (
                "Speed vs accuracy: centroid-path error vs wall time",
                "wall time (s)",
                "max abs(z − z_ref) / R",
            ),
            &[
                trade("cells per radius (CFL 0.4)", by_cpr.iter().map(|(r, _)| *r)),
                trade(
                    &format!("CFL at {mid} CPR"),
                    runs.iter()
                        .map(|(r, _)| *r)
                        .filter(|r| r.label.contains("CFL") || r.label == format!("{mid} CPR")),
                ),
            ],
            Scale::LogLog,
        );
        h.notes.push(format!(
            "SolidPieces: least share of the largest piece (most pieces) — {}",
            by_cpr
                .iter()
                .map(|(r, i)| format!(
                    "{}: {:.5} % ({})",
                    r.label,
                    100.0 * i.largest_piece,
                    i.pieces
                ))
                .chain(conditions.iter().map(|(n, _, i)| format!(
                    "{n}: {:.5} % ({})",
                    100.0 * i.largest_piece,
                    i.pieces
                )))
                .collect::<Vec<_>>()
                .join("; ")
        ));
        for (n, r, i) in &conditions {
            h.notes.push(format!(
                "{n}: impact at {:.2} ms at {:.3} m/s, rebound {:.3} m/s (e = {:.3}), contact {:.2} ms, {} steps in {:.1} s",
                1e3 * i.t_contact, i.impact_speed, i.rebound_speed, i.rebound_speed / i.impact_speed,
                1e3 * i.contact_time, r.steps, r.wall_seconds
            ));
        }
        let j = |n: &str| jr.metric(n).unwrap_or(f64::NAN);
        h.notes.insert(0, format!(
            "{}: impact at {:.2} ms at {:.3} m/s; contact {:.2} ms (Hertz {:.2}); compression 2R − height {:.2} mm (Hertz {:.2}; the centroid drops {:.2} mm below R); peak force {:.1} N (Hertz {:.1}); loaded footprint radius {:.1} mm (Hertz {:.1}); rebound {:.3} m/s, e = {:.3}",
            jr.label, 1e3 * j("impact_time_s"), j("impact_speed"), 1e3 * j("contact_time_s"), 1e3 * j("hertz_contact_time_s"),
            1e3 * j("compression_m"), 1e3 * j("hertz_compression_m"), 1e3 * j("centroid_drop_m"), j("peak_force_N"), j("hertz_peak_force_N"),
            1e3 * j("contact_radius_m"), 1e3 * j("hertz_contact_radius_m"), j("rebound_speed"), j("restitution")
        ));
        Ok(Verdict {
            title: "silicone sphere impact on a rigid substrate (seed §5.1)".into(),
            reference: "free fall z₀ + v₀t − gt²/2 before contact; Hertz's quasi-static contact at the measured impact speed (E* = 4G, `tests/references/hertz_sphere_impact/`); the finest grid for the speed/accuracy trade".into(),
            error_metric: format!("max abs(z_c − z_c,ref) / R against {reference_cpr} CPR"),
            checks,
            recommendation: if self.quick {
                "quick mode: see the full report".into()
            } else {
                "35 cells per radius at CFL 0.4: the compression and rebound are within the stated tolerances of 50 CPR at a fraction of its cost; 20 CPR for parameter sweeps".into()
            },
        })
    }
}
