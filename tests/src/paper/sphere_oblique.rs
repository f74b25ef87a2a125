//! Issue 41, case 3: the seed's sphere striking the substrate at 30° from its normal
//! (`cases/sphere_oblique_3d.ron`: half of the box, the Symmetry plane z = 0 holding the plane
//! of motion, y vertical), over three grids with the observed order of each figure.
//!
//! # What is measured
//! From the probes (every 0.1 ms): the contact is the span where the normal force on the
//! substrate exceeds 2 % of its peak, its duration between the threshold's crossings
//! interpolated linearly between samples (as [`super::sphere`] measures the normal impact).
//! "Before" and "after" are the samples either side of that span: the normal restitution
//! `e_n = −v_after / v_before`, the tangential restitution `e_t = u_after / u_before`, the spin
//! after the rebound `ω_z` (the rigid rotation's, `SolidSpin`) and the rolling ratio
//! `ω_z R / u_after` (−1 for rolling without slip, 0 for sliding).
//!
//! # The grid study
//! The box is whole cells with x = 0 on a face at every multiple of 2.5 cells per radius, so
//! the full version runs the scene's box at 5, 7.5 and 10 cells per radius (28 × 16 × 12,
//! 42 × 24 × 18 and 56 × 32 × 24 cells) to its end time. For each figure `f` with values
//! `f₁, f₂, f₃` on spacings `h₁ > h₂ > h₃`, the observed order `p` solves
//! `(h₁ᵖ − h₂ᵖ)/(h₂ᵖ − h₃ᵖ) = (f₁ − f₂)/(f₂ − f₃)` ([`observed_order`]; none when the
//! differences change sign: the figure does not converge monotonically over these grids), and
//! Richardson's extrapolation `f* = f₃ − (f₂ − f₃) h₃ᵖ/(h₂ᵖ − h₃ᵖ)` estimates the grid-converged
//! value. The quick version runs 5 cells per radius to [`QUICK_END`].
//!
//! # What is required
//! At every grid: `e_n ∈ [0.8, 1]`, `e_t ∈ [0.95, 1]`, the spin in the sense the substrate's
//! drag turns the sphere (`ω_z < 0`) with `|ω_z R / u| ≤ 0.2` (it mostly slides on the air
//! film), one piece throughout and the solid's volume kept to 1e-10.

use super::case::observed_order;
use super::case::{Case, Done, Harness, Plan, Verdict, drift, drift_check};
use super::plot::Scale;
use super::sphere::solid_of;
use super::{Check, Options, Run, format_num, load_case, probes};
use efsi_core::{Scene, Simulation};
use efsi_run::SceneOutput;
use efsi_stages::solid::Shape;
use std::path::PathBuf;

/// The quick version's end time (s): the contact ends near 10.5 ms at 5 cells per radius.
pub const QUICK_END: f64 = 0.014;

/// The force level, as a fraction of its peak, above which the sphere counts as in contact.
const CONTACT: f64 = 0.02;

/// What one run shows.
#[derive(Clone, Debug, Default)]
pub struct Oblique {
    t: Vec<f64>,
    x: Vec<f64>,
    y: Vec<f64>,
    /// The force above [`CONTACT`] of its peak, for this long (s).
    contact_time: f64,
    /// `−v_after / v_before`.
    e_n: f64,
    /// `u_after / u_before`.
    e_t: f64,
    /// `ω_z` after the contact (rad/s).
    spin: f64,
    /// `ω_z R / u_after`.
    roll: f64,
    volume_drift: f64,
    /// The least share of the volume in the largest piece, and the most pieces.
    largest_piece: f64,
    pieces: f64,
}

/// A figure of the study: its name, the scale and format of its value in the table, and its
/// value.
type Figure = (&'static str, f64, &'static str, fn(&Oblique) -> f64);

/// The figures whose convergence is studied.
const FIGURES: [Figure; 5] = [
    ("contact time (ms)", 1e3, "3", |o| o.contact_time),
    ("normal restitution e_n", 1.0, "4", |o| o.e_n),
    ("tangential restitution e_t", 1.0, "5", |o| o.e_t),
    ("spin after rebound ω_z (rad/s)", 1.0, "3", |o| o.spin),
    ("rolling ratio ω_z R / u", 1.0, "4", |o| o.roll),
];

/// The figures of the run in `run.dir` of a sphere of radius `radius`.
fn analyse(run: &Run, radius: f64) -> Result<Oblique, String> {
    let p = probes(&run.dir)?;
    let t = p.col("t")?;
    let (f, u, v, spin) = (
        p.col("contact_force")?,
        p.col("solid_u")?,
        p.col("solid_v")?,
        p.col("solid_spin_z")?,
    );
    let peak = f.iter().copied().fold(0.0, f64::max);
    let threshold = CONTACT * peak;
    let first = (0..t.len())
        .find(|&k| f[k] > threshold)
        .filter(|_| peak > 0.0)
        .ok_or_else(|| format!("{}: the sphere never touched the substrate", run.label))?;
    let mut last = first;
    while last + 1 < t.len() && f[last + 1] > threshold {
        last += 1;
    }
    if first == 0 || last + 1 >= t.len() {
        return Err(format!(
            "{}: the contact is not within the record (t = {:.2e} … {:.2e} s)",
            run.label, t[first], t[last]
        ));
    }
    let (before, after) = (first - 1, last + 1);
    let crossing = |a: usize, b: usize| t[a] + (threshold - f[a]) / (f[b] - f[a]) * (t[b] - t[a]);
    let fold = |v: &[f64], init: f64, g: fn(f64, f64) -> f64| v.iter().copied().fold(init, g);
    Ok(Oblique {
        contact_time: crossing(last, after) - crossing(before, first),
        e_n: -v[after] / v[before],
        e_t: u[after] / u[before],
        spin: spin[after],
        roll: spin[after] * radius / u[after],
        volume_drift: drift(p.col("solid_volume")?),
        largest_piece: fold(p.col("solid_largest_piece")?, f64::INFINITY, f64::min),
        pieces: fold(p.col("solid_pieces")?, 0.0, f64::max),
        t: t.to_vec(),
        x: p.col("solid_x")?.to_vec(),
        y: p.col("solid_y")?.to_vec(),
    })
}

/// The observed order `p` of a figure's values `f` on spacings `h` (coarse to fine), and
/// Richardson's extrapolation of it; NaN for both if the successive differences change sign
/// or the order is outside (0, 8].
pub fn order_and_limit(h: [f64; 3], f: [f64; 3]) -> (f64, f64) {
    let p = observed_order(h, [f[0] - f[1], f[1] - f[2]]);
    let (a, b) = (h[1].powf(p), h[2].powf(p));
    (p, f[2] - (f[1] - f[2]) * b / (a - b))
}

/// The case: 5, 7.5 and 10 cells per radius to the scene's end (quick: 5, to [`QUICK_END`]).
pub struct SphereOblique3d {
    quick: bool,
}

impl SphereOblique3d {
    /// The sphere's radius in the scene.
    fn radius() -> Result<f64, String> {
        let (scene, _) = load_case("sphere_oblique_3d.ron")?;
        match solid_of(&scene)?.shape {
            Shape::Sphere { radius, .. } => Ok(radius),
            _ => Err("sphere_oblique_3d.ron: the solid is not a Sphere".into()),
        }
    }
}

impl Case for SphereOblique3d {
    const NAME: &'static str = "sphere_oblique_3d";
    type Setting = f64;
    type Measured = Oblique;

    fn plan(opts: &Options) -> Plan<Self> {
        let cprs: &[f64] = if opts.quick {
            &[5.0]
        } else {
            &[5.0, 7.5, 10.0]
        };
        let plan = cprs.iter().map(|&c| (format!("{c} CPR"), c)).collect();
        Ok((SphereOblique3d { quick: opts.quick }, plan))
    }

    /// The scene's box at `cpr` cells per radius on every axis; the box must be whole cells.
    fn scene(&self, &cpr: &f64) -> Result<(Scene, PathBuf), String> {
        let (mut scene, path) = load_case("sphere_oblique_3d.ron")?;
        let h = Self::radius()? / cpr;
        let cells = |(a, b): (f64, f64)| -> Result<usize, String> {
            let n = (b - a) / h;
            if (n - n.round()).abs() > 1e-6 || (a / h - (a / h).round()).abs() > 1e-6 {
                return Err(format!(
                    "the box [{a}, {b}] is not whole cells of {h:e} m with 0 on a face at {cpr} \
                     cells per radius"
                ));
            }
            Ok(n.round() as usize)
        };
        scene.grid.nx = cells(scene.domain.x)?;
        scene.grid.ny = cells(scene.domain.y)?;
        let z = scene.domain.z.ok_or("the scene has no z extent")?;
        scene.grid.nz = Some(cells(z)?);
        if self.quick {
            scene.time.end = QUICK_END;
        }
        scene.update_output(|o| o.vtk_every = None)?;
        Ok((scene, path))
    }

    fn measure(&self, _: &f64, _: &Simulation, run: &mut Run) -> Result<Oblique, String> {
        let o = analyse(run, Self::radius()?)?;
        run.metrics = vec![
            ("contact_time_s".into(), o.contact_time),
            ("e_n".into(), o.e_n),
            ("e_t".into(), o.e_t),
            ("spin_z".into(), o.spin),
            ("roll".into(), o.roll),
            ("volume_drift".into(), o.volume_drift),
            ("largest_piece_min".into(), o.largest_piece),
            ("pieces_max".into(), o.pieces),
        ];
        Ok(o)
    }

    fn conclude(&self, h: &mut Harness, done: &mut Done<Self>) -> Result<Verdict, String> {
        let m = &done.measured;
        if m.is_empty() {
            return Err("no run completed".into());
        }
        let radius = Self::radius()?;
        let mut checks = Vec::new();
        for (c, o) in m {
            checks.push(Check::within(
                format!("normal restitution e_n, {c} CPR"),
                o.e_n,
                0.8,
                1.0,
                "4",
            ));
            checks.push(Check::within(
                format!("tangential restitution e_t, {c} CPR"),
                o.e_t,
                0.95,
                1.0,
                "4",
            ));
            checks.push(Check::within(
                format!(
                    "rolling ratio ω_z R / u after the rebound, {c} CPR (negative: turned by \
                     the substrate's drag; small: sliding)"
                ),
                o.roll,
                -0.2,
                0.0,
                "4",
            ));
        }
        checks.push(drift_check(
            "solid volume drift, every run",
            m.iter().map(|(_, o)| o.volume_drift),
        ));
        checks.push(Check::at_most(
            "one piece: the most pieces (regions above 1e-3 of the volume) at any sample of any run",
            m.iter().map(|(_, o)| o.pieces).fold(0.0, f64::max),
            1.0,
            "0",
        ));
        // The table: per grid each figure; with three grids its observed order and limit.
        for (c, o) in m {
            let cells = FIGURES
                .iter()
                .map(|(name, scale, fmt, f)| format!("{name} {}", format_num(scale * f(o), fmt)))
                .collect::<Vec<_>>()
                .join(", ");
            h.notes.push(format!(
                "{c} CPR: {cells}; volume drift {:.1e}; least share in the largest piece {:.5}",
                o.volume_drift, o.largest_piece
            ));
        }
        let mut recommendation = format!(
            "{} cells per radius: the coarsest grid that keeps e_n ∈ [0.8, 1]; finer for figures \
             (the quick version has no grid study)",
            m[0].0
        );
        if let [(c1, o1), (c2, o2), (c3, o3)] = m.as_slice() {
            let hs = [radius / c1, radius / c2, radius / c3];
            for (k, (name, scale, fmt, f)) in FIGURES.into_iter().enumerate() {
                let v = [f(o1), f(o2), f(o3)];
                let (p, limit) = order_and_limit(hs, v);
                // Every figure but e_t (unchanged between the grids to 1e-4: its differences
                // are the solvers' tolerance) converges: the finer pair differs less.
                if k != 2 {
                    checks.push(Check::at_most(
                        format!(
                            "{name}: |f({c3}) − f({c2})| / |f({c2}) − f({c1})|, successive \
                             grids' differences fall"
                        ),
                        ((v[2] - v[1]) / (v[1] - v[0])).abs(),
                        1.0,
                        "3",
                    ));
                } else {
                    checks.push(Check::at_most(
                        format!("{name}: largest difference between the grids"),
                        v.iter().fold(f64::MIN, |a, &b| a.max(b))
                            - v.iter().fold(f64::MAX, |a, &b| a.min(b)),
                        1e-3,
                        "e",
                    ));
                }
                if k == 1 && p.is_finite() {
                    recommendation = format!(
                        "{c3} cells per radius: e_n {:.4} is {:.1} % from its extrapolated \
                         value {limit:.4} (observed order {p:.2})",
                        v[2],
                        100.0 * (v[2] - limit).abs() / limit
                    );
                }
                h.notes.push(format!(
                    "{name}: {} → {} → {}; observed order {}; extrapolated {}",
                    format_num(scale * v[0], fmt),
                    format_num(scale * v[1], fmt),
                    format_num(scale * v[2], fmt),
                    if p.is_nan() {
                        "none (the differences change sign)".to_string()
                    } else {
                        format!("{p:.2}")
                    },
                    if p.is_nan() {
                        "—".to_string()
                    } else {
                        format_num(scale * limit, fmt)
                    }
                ));
            }
            // Each run's error: its normal restitution's distance from the finest grid's.
            for (r, (_, o)) in done.runs.iter_mut().zip(m) {
                r.error = Some((o.e_n - o3.e_n).abs());
            }
        }
        let paths: Vec<_> = done
            .runs
            .iter()
            .zip(m)
            .map(|(r, (_, o))| {
                let pts = o.x.iter().zip(&o.y).map(|(x, y)| (1e3 * x, 1e3 * y));
                (r.label.clone(), pts.collect::<Vec<_>>())
            })
            .collect();
        h.figure(
            "centroid_path",
            (
                "Oblique impact at 30°: the centroid's path in the plane of motion",
                "x (mm)",
                "y (mm)",
            ),
            &paths,
            Scale::Linear,
        );
        let spins: Vec<_> = done
            .runs
            .iter()
            .zip(m)
            .map(|(r, (_, o))| {
                let p = probes(&r.dir).ok();
                let w = p.as_ref().and_then(|p| p.col("solid_spin_z").ok());
                let pts = w.map_or(Vec::new(), |w| {
                    o.t.iter().zip(w).map(|(t, w)| (1e3 * t, *w)).collect()
                });
                (r.label.clone(), pts)
            })
            .collect();
        h.figure(
            "spin",
            ("Oblique impact at 30°: spin ω_z", "t (ms)", "ω_z (rad/s)"),
            &spins,
            Scale::Linear,
        );
        let finest = m.last().map_or(0.0, |(c, _)| *c);
        Ok(Verdict {
            title: "Oblique sphere impact at 30° in 3-D, half domain (issue 41, case 3)".into(),
            reference: "self-convergence over 5, 7.5 and 10 cells per radius: no published \
                        figures of this set-up; the observed order of each figure"
                .into(),
            error_metric: format!(
                "abs(e_n − e_n at {finest} cells per radius), the normal restitution's distance \
                 from the finest grid's"
            ),
            checks,
            recommendation,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::order_and_limit;

    /// The order and the limit of exact power-law values are recovered, at the study's
    /// spacings (refinement ratios 1.5 and 4/3).
    #[test]
    fn order_and_limit_of_a_power_law() {
        let h: [f64; 3] = [1.0 / 5.0, 1.0 / 7.5, 1.0 / 10.0];
        for p in [1.0, 1.5, 2.0] {
            let f = h.map(|h| 0.9 - 0.4 * h.powf(p));
            let (q, limit) = order_and_limit(h, f);
            assert!((q - p).abs() < 1e-9, "order {q} for {p}");
            assert!((limit - 0.9).abs() < 1e-9, "limit {limit} for {p}");
        }
        let (q, limit) = order_and_limit(h, [0.9, 0.95, 0.92]);
        assert!(q.is_nan() && limit.is_nan());
    }
}
