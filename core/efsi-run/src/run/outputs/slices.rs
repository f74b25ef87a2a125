//! A plane slice of a three-dimensional run as an output: `slices/<name>_<step>.vtr`, the plane
//! normal to one axis (a VTK RectilinearGrid flat along the normal, at its place in the box)
//! holding the arrays of `output.vtk` interpolated to it ([`crate::output::slice`]), each file
//! added to the collection `slices/<name>.pvd` with its time; written in the VTK files' format
//! (`output.vtk`: precision, compression, point data).
//!
//! A checkpoint records the collection's entries with the VTK series' (in
//! [`OutputState::pvd`], as `slices/<file>`); a resumed run takes its own back by their names
//! and counts its schedule's events from the last one's time, as the schedule counted them.

use super::{RunAt, Schedule, Writer};
use crate::checkpoint::OutputState;
use crate::output::fields::{arrays, slice_notes};
use crate::output::schedule::events_due;
use crate::output::slice::{Layers, plane_nodes, plane_values};
use crate::output::spec::{SliceSpec, VtkOptions};
use crate::output::vtk::{
    CellArray, PvdCollection, VtrFormat, node_coordinates, write_rectilinear,
};
use efsi_core::error::EfsiError;
use std::path::{Path, PathBuf};

/// The writer of one plane slice's files and their collection.
pub struct SliceSeries {
    dir: PathBuf,
    spec: SliceSpec,
    name: String,
    options: VtkOptions,
    pvd: PvdCollection,
}

impl SliceSeries {
    /// The slice `spec` of the run in `dir`, in the VTK files' format `vtk`, its collection
    /// holding `entries` (time, file relative to `dir`, of every collection: a resumed run's
    /// checkpoint's; this slice's are its own); makes `dir/slices` and writes the collection.
    pub fn create(
        dir: &Path,
        spec: &SliceSpec,
        vtk: &VtkOptions,
        entries: &[(f64, String)],
    ) -> Result<SliceSeries, EfsiError> {
        let name = spec.stem();
        let folder = dir.join("slices");
        std::fs::create_dir_all(&folder).map_err(|e| EfsiError::io(&folder, e))?;
        let own = entries
            .iter()
            .filter_map(|(t, f)| Some((*t, own_file(&name, f)?.to_string())))
            .collect();
        let pvd = PvdCollection::with_entries(folder.join(format!("{name}.pvd")), own);
        pvd.write().map_err(|e| EfsiError::io(pvd.path(), e))?;
        Ok(SliceSeries {
            dir: dir.to_path_buf(),
            spec: spec.clone(),
            name,
            options: VtkOptions {
                fields: spec.fields.clone(),
                ..vtk.clone()
            },
            pvd,
        })
    }

    /// The schedule of the slice's writes (its `every`, resolved: else at the start and the
    /// end), continuing after the files its collection lists: an interval's events counted by
    /// the last one's time, the start done once it is written.
    pub fn schedule(&self) -> Schedule {
        let last = self.pvd.entries().last().map(|e| e.0);
        match self.spec.every {
            Some(every) => Schedule::Every {
                every,
                count: last.map_or(0, |t| events_due(t, every, 0)),
            },
            None if last.is_some() => Schedule::Times(Vec::new()),
            None => Schedule::times(&[0.0]),
        }
    }
}

/// The file of the slice `name` that `entry` (relative to the output folder) names —
/// `slices/<name>_<digits>.vtr` — relative to `slices/`; None for another collection's.
fn own_file<'a>(name: &str, entry: &'a str) -> Option<&'a str> {
    let file = entry.strip_prefix("slices/")?;
    let step = file
        .strip_prefix(name)?
        .strip_prefix('_')?
        .strip_suffix(".vtr")?;
    (!step.is_empty() && step.bytes().all(|b| b.is_ascii_digit())).then_some(file)
}

impl Writer for SliceSeries {
    fn label(&self) -> String {
        format!("slice `{}`", self.name)
    }

    fn write(&mut self, run: &mut RunAt<'_>) -> Result<PathBuf, EfsiError> {
        let (sim, state) = (run.sim, &run.sim.state);
        let grid = &sim.grid;
        let axis = self.spec.normal.index();
        let nodes = node_coordinates(grid);
        let layers = Layers::around(&nodes[axis], self.spec.at);
        let cells = grid.n();
        let data: Vec<(&str, usize, Vec<f64>)> =
            arrays(grid, state, &self.options, sim.pipeline().outputs())
                .into_iter()
                .map(|(name, c, values)| (name, c, plane_values(&values, c, cells, axis, layers)))
                .collect();
        let cell_arrays: Vec<CellArray> = data
            .iter()
            .map(|(name, components, values)| CellArray {
                name,
                components: *components,
                values,
            })
            .collect();
        let format = VtrFormat {
            precision: self.options.precision,
            compression: self.options.compression,
            point_data: self.options.point_data,
        };
        let notes = slice_notes(axis, self.spec.at);
        let notes: Vec<(&str, &str)> = notes.iter().map(|(k, v)| (*k, v.as_str())).collect();
        let file = format!("{}_{:06}.vtr", self.name, state.step);
        let path = self.dir.join("slices").join(&file);
        let mesh = plane_nodes(&nodes, axis, self.spec.at);
        write_rectilinear(&path, &mesh, state.t, &cell_arrays, &format, &notes)
            .map_err(|e| EfsiError::io(&path, e))?;
        self.pvd
            .add(state.t, &file)
            .map_err(|e| EfsiError::io(self.pvd.path(), e))?;
        Ok(path)
    }

    /// The collection's entries, as `slices/<file>` beside the VTK series'.
    fn save(&self, _schedule: &Schedule, into: &mut OutputState) {
        into.pvd.extend(
            self.pvd
                .entries()
                .iter()
                .map(|(t, f)| (*t, format!("slices/{f}"))),
        );
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A slice's files are told from the VTK series' and from another slice's whose name
    /// begins with its own.
    #[test]
    fn a_slice_takes_back_its_own_entries() {
        assert_eq!(own_file("z", "slices/z_000012.vtr"), Some("z_000012.vtr"));
        assert_eq!(own_file("z", "slices/z_1_000012.vtr"), None);
        assert_eq!(
            own_file("z_1", "slices/z_1_000012.vtr"),
            Some("z_1_000012.vtr")
        );
        assert_eq!(own_file("z", "fields/z_000012.vtr"), None);
        assert_eq!(own_file("z", "slices/z_.vtr"), None);
    }

    /// The count a resumed slice takes from its last file's time is the one its schedule had
    /// reached after writing it, at every output of an interval, the end's included.
    #[test]
    fn the_schedule_resumes_where_it_was() {
        for every in [0.1, 0.3, 1.0 / 3.0, 0.07] {
            let mut schedule = Schedule::every(Some(every));
            let mut t = 0.0;
            loop {
                let last = t >= 2.0;
                if schedule.take(t, last).write {
                    assert_eq!(schedule.count(), events_due(t, every, 0), "{every} {t}");
                }
                if last {
                    break;
                }
                // The run lands on each output time and ends at 2.0.
                t = schedule.next().unwrap().min(2.0);
            }
        }
    }
}
