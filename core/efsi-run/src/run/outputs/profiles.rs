//! A line profile as an output: `profiles/<name>_t<time>.csv`, the fields sampled at evenly
//! spaced points of a segment — `s` (the distance along it), `x`, `y`, then the fields — at
//! each of the profile's times ([`Schedule::Times`]), or at the end if it has none.

use super::{RunAt, Schedule, Writer};
use crate::checkpoint::OutputState;
use crate::output::spec::ProfileSpec;
use crate::probes;
use crate::run::time_label;
use efsi_core::error::EfsiError;
use efsi_core::scene::Vector;
use std::path::{Path, PathBuf};

/// The writer of one line profile.
pub struct Profile {
    dir: PathBuf,
    spec: ProfileSpec,
}

impl Profile {
    /// The profile `spec` of the run in `dir`.
    pub fn new(dir: &Path, spec: &ProfileSpec) -> Profile {
        Profile {
            dir: dir.to_path_buf(),
            spec: spec.clone(),
        }
    }
}

impl Writer for Profile {
    fn label(&self) -> String {
        format!("profile `{}`", self.spec.name())
    }

    fn write(&mut self, run: &mut RunAt<'_>) -> Result<PathBuf, EfsiError> {
        let sim = run.sim;
        let ProfileSpec::Line {
            name,
            from,
            to,
            points,
            fields,
            ..
        } = &self.spec;
        let path = self
            .dir
            .join("profiles")
            .join(format!("{name}_t{}.csv", time_label(sim.state.t)));
        let outputs = sim.pipeline().outputs();
        // In three dimensions the segment has a z, and the file a `z` column.
        let three = sim.grid.is_3d();
        let [fx, fy, fz] = from.xyz();
        let [tx, ty, tz] = to.xyz();
        let len = if three {
            (tx - fx).hypot(ty - fy).hypot(tz - fz)
        } else {
            (tx - fx).hypot(ty - fy)
        };
        let mut text = if three {
            format!("s,x,y,z,{}\n", fields.join(","))
        } else {
            format!("s,x,y,{}\n", fields.join(","))
        };
        for q in 0..*points {
            let f = q as f64 / (*points - 1) as f64;
            let p = (fx + f * (tx - fx), fy + f * (ty - fy));
            text.push_str(&format!("{:.17e},{:.17e},{:.17e}", f * len, p.0, p.1));
            let at = if three {
                let z = fz + f * (tz - fz);
                text.push_str(&format!(",{z:.17e}"));
                Vector(p.0, p.1, Some(z))
            } else {
                Vector(p.0, p.1, None)
            };
            for fl in fields {
                text.push_str(&format!(
                    ",{:.17e}",
                    probes::sample_at(&sim.grid, &sim.state, outputs, fl, at)
                ));
            }
            text.push('\n');
        }
        crate::output::atomic::write_bytes_atomically(&path, text.as_bytes())
            .map_err(|e| EfsiError::io(&path, e))?;
        Ok(path)
    }

    fn save(&self, schedule: &Schedule, into: &mut OutputState) {
        into.profile_times.push(schedule.remaining().to_vec());
    }
}
