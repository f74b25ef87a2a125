//! `cargo xtask ghia DIR RE`: a cavity run's centreline profiles against Ghia et al. (1982).

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
        let mut dev = 0.0f64;
        for (&x, &want) in rs.iter().zip(rf) {
            let k = s.partition_point(|&a| a < x).clamp(1, s.len() - 1);
            let w = (x - s[k - 1]) / (s[k] - s[k - 1]);
            dev = dev.max((f[k - 1] * (1.0 - w) + f[k] * w - want).abs());
        }
        println!(
            "{}: max |{field} − Ghia| = {dev:.4} over {} points",
            prof.display(),
            rs.len()
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
            cavity_json(0.0025, "y_max").to_string(),
        )
        .unwrap();
        let e = ghia(&[dir.display().to_string(), "400".into()]).unwrap_err();
        assert!(e.contains("profiles: No such file"), "{e}");
        let profiles = dir.join("profiles");
        std::fs::create_dir_all(&profiles).unwrap();
        std::fs::write(
            profiles.join("u_x0.5_t1.csv"),
            "s,x,y,u\n0,0.5,0,0\n1,0.5,1,1\n",
        )
        .unwrap();
        let e = ghia(&[dir.display().to_string(), "400".into()]).unwrap_err();
        assert!(e.contains("no column `u_Re400`"), "{e}");
        assert!(
            e.contains("the columns are: grid_point, y, u_Re100, u_Re1000"),
            "{e}"
        );
        let e = ghia(&[dir.display().to_string(), "fast".into()]).unwrap_err();
        assert!(e.contains("RE must be a number, got `fast`"), "{e}");
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
