//! `cargo xtask ghia DIR RE`: a cavity run's centreline profiles against Ghia et al. (1982),
//! Tables I and II (`tests/references/ghia1982/`: Re = 100, 400, 1000, 3200, 5000, 7500 and
//! 10000). The largest deviation leaves out the entries the paper misprints ([`MISPRINTS`]).

use crate::csv::{column, read_csv};
use crate::root;
use std::path::{Path, PathBuf};

/// The Reynolds number `ρ U L / μ` of a cavity run, from the effective scene its `run.json`
/// records: `U` the speed of its moving wall, `L` the domain's length along that wall.
fn run_reynolds(run_json: &serde_json::Value) -> Result<f64, String> {
    let scene = &run_json["scene"];
    let num = |v: &serde_json::Value, what: &str| {
        v.as_f64()
            .ok_or_else(|| format!("run.json has no number at scene.{what}"))
    };
    let rho = num(&scene["fluid"]["density"], "fluid.density")?;
    let mu = num(&scene["fluid"]["viscosity"], "fluid.viscosity")?;
    let mut lids = Vec::new();
    for (side, axis) in [
        ("x_min", "y"),
        ("x_max", "y"),
        ("y_min", "x"),
        ("y_max", "x"),
    ] {
        if let Some(w) = scene["boundaries"][side].get("MovingWall") {
            let speed = num(&w["speed"], &format!("boundaries.{side}.speed"))?;
            let d = &scene["domain"][axis];
            let length = num(&d[1], &format!("domain.{axis}[1]"))?
                - num(&d[0], &format!("domain.{axis}[0]"))?;
            lids.push((side, speed, length));
        }
    }
    match lids.as_slice() {
        [(_, speed, length)] => Ok(rho * speed.abs() * length / mu),
        [] => Err("the run's scene has no moving wall: not a lid-driven cavity".into()),
        _ => Err(format!(
            "the run's scene has {} moving walls ({}): not a lid-driven cavity",
            lids.len(),
            lids.iter().map(|l| l.0).collect::<Vec<_>>().join(", ")
        )),
    }
}

/// Check that the run in `dir` is at the Reynolds number `re` (within 1e-6 relative).
fn check_reynolds(dir: &Path, re: f64) -> Result<(), String> {
    let path = dir.join("run.json");
    let text = std::fs::read_to_string(&path).map_err(|e| format!("{}: {e}", path.display()))?;
    let json: serde_json::Value =
        serde_json::from_str(&text).map_err(|e| format!("{}: {e}", path.display()))?;
    let run_re = run_reynolds(&json).map_err(|e| format!("{}: {e}", path.display()))?;
    if (run_re - re).abs() > 1e-6 * re.abs() {
        return Err(format!(
            "{}: the run is at Re = ρ U L / μ = {run_re} (from its scene), not {re}",
            path.display()
        ));
    }
    Ok(())
}

/// The profile with the latest time among `DIR/profiles/<stem>_t*.csv`.
fn last_profile(dir: &Path, stem: &str) -> Result<PathBuf, String> {
    let prefix = format!("{stem}_t");
    let mut best: Option<(f64, PathBuf)> = None;
    for e in std::fs::read_dir(dir.join("profiles"))
        .map_err(|e| format!("{}: {e}", dir.join("profiles").display()))?
    {
        let p = e.map_err(|e| e.to_string())?.path();
        let name = p
            .file_name()
            .and_then(|n| n.to_str())
            .unwrap_or_default()
            .to_string();
        if let Some(t) = name
            .strip_prefix(&prefix)
            .and_then(|r| r.strip_suffix(".csv"))
            .and_then(|t| t.parse::<f64>().ok())
            && best.as_ref().is_none_or(|(b, _)| t > *b)
        {
            best = Some((t, p));
        }
    }
    best.map(|(_, p)| p)
        .ok_or_else(|| format!("no {prefix}*.csv in {}", dir.join("profiles").display()))
}

/// Entries of Ghia et al.'s tables that are misprinted in the paper (kept as printed in the
/// reference files, left out of the deviation): `(field, Re, coordinate)`. At Re = 3200, u at
/// y = 0.4531 is printed −0.86636 between −0.24427 and −0.04272 (read −0.08636); at Re = 10000,
/// u at y = 0.5 is printed +0.03111 where its neighbours and the other Reynolds numbers give a
/// negative value.
const MISPRINTS: [(&str, f64, f64); 2] = [("u", 3200.0, 0.4531), ("u", 10000.0, 0.5)];

/// The largest |profile − reference| over the reference's points (the profile interpolated
/// linearly at each; the points [`MISPRINTS`] lists for `field` at `re` left out), and how many
/// points were left out. `profile` and `reference` are (coordinates, values), the profile's
/// coordinates increasing.
fn deviation(
    profile: (&[f64], &[f64]),
    reference: (&[f64], &[f64]),
    field: &str,
    re: f64,
) -> (f64, usize) {
    let (s, f) = profile;
    let mut dev = 0.0f64;
    let mut skipped = 0;
    for (&x, &want) in reference.0.iter().zip(reference.1) {
        if MISPRINTS.contains(&(field, re, x)) {
            skipped += 1;
            continue;
        }
        let k = s.partition_point(|&a| a < x).clamp(1, s.len() - 1);
        let w = (x - s[k - 1]) / (s[k] - s[k - 1]);
        dev = dev.max((f[k - 1] * (1.0 - w) + f[k] * w - want).abs());
    }
    (dev, skipped)
}

pub(crate) fn ghia(args: &[String]) -> Result<(), String> {
    let [dir, re] = args else {
        return Err("usage: cargo xtask ghia DIR RE".into());
    };
    let dir = PathBuf::from(dir);
    let re_value: f64 = re
        .parse()
        .map_err(|_| format!("RE must be a number, got `{re}`"))?;
    check_reynolds(&dir, re_value)?;
    let refs = root().join("tests/references/ghia1982");
    for (stem, field, coord, file) in [
        (
            "u_x0.5",
            "u",
            "y",
            "ghia1982_u_vertical_centerline_x0.5.csv",
        ),
        (
            "v_y0.5",
            "v",
            "x",
            "ghia1982_v_horizontal_centerline_y0.5.csv",
        ),
    ] {
        let prof = last_profile(&dir, stem)?;
        let (h, c) = read_csv(&prof)?;
        let (s, f) = (column(&h, &c, coord, &prof)?, column(&h, &c, field, &prof)?);
        let rpath = refs.join(file);
        let (rh, rc) = read_csv(&rpath)?;
        let (rs, rf) = (
            column(&rh, &rc, coord, &rpath)?,
            column(&rh, &rc, &format!("{field}_Re{re_value}"), &rpath)?,
        );
        let (dev, skipped) = deviation((s, f), (rs, rf), field, re_value);
        let note = if skipped > 0 {
            format!(" ({skipped} misprinted entry of the table left out)")
        } else {
            String::new()
        };
        println!(
            "{}: max |{field} − Ghia| = {dev:.4} over {} points{note}",
            prof.display(),
            rs.len() - skipped
        );
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cavity_json(viscosity: f64, lid: &str) -> serde_json::Value {
        serde_json::json!({"scene": {
            "fluid": {"density": 1.0, "viscosity": viscosity},
            "domain": {"x": [0.0, 2.0], "y": [0.0, 1.0]},
            "boundaries": {"x_min": "NoSlip", "x_max": "NoSlip", "y_min": "NoSlip",
                           lid: {"MovingWall": {"speed": -0.5, "profile": "Uniform", "motion": "Steady"}}},
        }})
    }

    /// Every Reynolds number of Ghia et al.'s Tables I and II is in the reference files, 17
    /// points each; a profile equal to the table deviates by 0, one off by 0.01 at one point by
    /// 0.01, and the misprinted entries are left out.
    #[test]
    fn ghia_carries_every_reynolds_number_of_the_tables() {
        let refs = root().join("tests/references/ghia1982");
        for (field, coord, file) in [
            ("u", "y", "ghia1982_u_vertical_centerline_x0.5.csv"),
            ("v", "x", "ghia1982_v_horizontal_centerline_y0.5.csv"),
        ] {
            let path = refs.join(file);
            let (h, c) = read_csv(&path).unwrap();
            let mut s = column(&h, &c, coord, &path).unwrap().to_vec();
            s.reverse();
            for re in [100.0, 400.0, 1000.0, 3200.0, 5000.0, 7500.0, 10000.0] {
                let mut f = column(&h, &c, &format!("{field}_Re{re}"), &path)
                    .unwrap()
                    .to_vec();
                f.reverse();
                assert_eq!((s.len(), f.len()), (17, 17));
                // The wall values: no slip, the lid at y = 1.
                let lid = if field == "u" { 1.0 } else { 0.0 };
                assert_eq!((f[0], f[16]), (0.0, lid), "{field} at Re {re}");
                let left_out = MISPRINTS
                    .iter()
                    .filter(|m| m.0 == field && m.1 == re)
                    .count();
                assert_eq!(deviation((&s, &f), (&s, &f), field, re), (0.0, left_out));
                let mut off = f.clone();
                off[3] += 0.01;
                let (dev, _) = deviation((&s, &off), (&s, &f), field, re);
                assert!((dev - 0.01).abs() < 1e-12, "{dev}");
            }
        }
        // The misprints: printed as the paper has them, left out of the deviation.
        let path = refs.join("ghia1982_u_vertical_centerline_x0.5.csv");
        let (h, c) = read_csv(&path).unwrap();
        let y = column(&h, &c, "y", &path).unwrap();
        let at = |name: &str, yy: f64| {
            let k = y.iter().position(|&v| v == yy).unwrap();
            column(&h, &c, name, &path).unwrap()[k]
        };
        assert_eq!(at("u_Re3200", 0.4531), -0.86636);
        assert_eq!(at("u_Re10000", 0.5), 0.03111);
    }

    #[test]
    fn ghia_checks_the_runs_reynolds_number() {
        // ρ |U| L / μ with L the lid's length (x for a lid on y_max).
        assert_eq!(run_reynolds(&cavity_json(0.01, "y_max")), Ok(100.0));
        assert_eq!(run_reynolds(&cavity_json(0.01, "x_max")), Ok(50.0));
        let mut no_lid = cavity_json(0.01, "y_max");
        no_lid["scene"]["boundaries"]["y_max"] = "NoSlip".into();
        assert!(
            run_reynolds(&no_lid)
                .unwrap_err()
                .contains("no moving wall")
        );
        let dir = std::env::temp_dir().join(format!("xtask-ghia-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        std::fs::write(
            dir.join("run.json"),
            cavity_json(0.001, "y_max").to_string(),
        )
        .unwrap();
        assert_eq!(check_reynolds(&dir, 1000.0), Ok(()));
        let e = check_reynolds(&dir, 100.0).unwrap_err();
        assert!(e.contains("the run is at Re = ρ U L / μ = 1000"), "{e}");
        assert!(e.contains("not 100"), "{e}");
        // A Reynolds number the reference has no column for: the columns it has are listed.
        std::fs::write(
            dir.join("run.json"),
            cavity_json(0.0005, "y_max").to_string(),
        )
        .unwrap();
        let e = ghia(&[dir.display().to_string(), "2000".into()]).unwrap_err();
        assert!(e.contains("profiles: No such file"), "{e}");
        let profiles = dir.join("profiles");
        std::fs::create_dir_all(&profiles).unwrap();
        std::fs::write(
            profiles.join("u_x0.5_t1.csv"),
            "s,x,y,u\n0,0.5,0,0\n1,0.5,1,1\n",
        )
        .unwrap();
        let e = ghia(&[dir.display().to_string(), "2000".into()]).unwrap_err();
        assert!(e.contains("no column `u_Re2000`"), "{e}");
        assert!(
            e.contains(
                "the columns are: grid_point, y, u_Re100, u_Re400, u_Re1000, u_Re3200, u_Re5000, u_Re7500, u_Re10000"
            ),
            "{e}"
        );
        let e = ghia(&[dir.display().to_string(), "fast".into()]).unwrap_err();
        assert!(e.contains("RE must be a number, got `fast`"), "{e}");
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
