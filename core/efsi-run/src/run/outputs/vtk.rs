//! The VTK series as an output: `fields/<name>_<step>.vtr` (VTK XML RectilinearGrid, the
//! arrays of `output.vtk`) every `output.vtk_every` of simulated time and at the end, each
//! added to the collection `fields.pvd` with its time (rewritten after each file, so it is
//! valid at every moment of the run).

use super::{RunAt, Schedule, Writer};
use crate::checkpoint::OutputState;
use crate::output::spec::VtkOptions;
use crate::output::vtk::{
    CellSource, PvdCollection, VtrFormat, node_coordinates, write_rectilinear_from,
};
use efsi_core::error::EfsiError;
use efsi_core::state::State;
use std::path::{Path, PathBuf};

/// The writer of a run's VTK files and their collection.
pub struct VtkSeries {
    dir: PathBuf,
    options: VtkOptions,
    pvd: PvdCollection,
}

impl VtkSeries {
    /// The series of the run in `dir`, written as `options` say, its collection holding
    /// `entries` (time, file relative to `dir`: empty for a new run, the checkpoint's for a
    /// resumed one); writes the collection (a stale one from an earlier run goes).
    pub fn create(
        dir: &Path,
        options: &VtkOptions,
        entries: Vec<(f64, String)>,
    ) -> Result<VtkSeries, EfsiError> {
        let pvd = PvdCollection::with_entries(dir.join("fields.pvd"), entries);
        pvd.write()
            .map_err(|e| EfsiError::io(dir.join("fields.pvd"), e))?;
        Ok(VtkSeries {
            dir: dir.to_path_buf(),
            options: options.clone(),
            pvd,
        })
    }

    /// Write `state` as `fields/<name>_<step><suffix>.vtr` and add it to the collection;
    /// returns the file's path.
    fn write_state(
        &mut self,
        run: &RunAt<'_>,
        state: &State,
        suffix: &str,
    ) -> Result<PathBuf, EfsiError> {
        let (grid, name) = (&run.sim.grid, &run.sim.scene.name);
        let options = &self.options;
        let outputs = run.sim.pipeline().outputs();
        // The arrays made line by line as the file is written: none is held whole.
        let data = crate::output::fields::producers(grid, state, options, outputs);
        let sources: Vec<CellSource> = data
            .iter()
            .map(|(name, components, values)| CellSource {
                name,
                components: *components,
                values: &**values,
            })
            .collect();
        let format = VtrFormat {
            precision: options.precision,
            compression: options.compression,
            point_data: options.point_data,
        };
        let notes = crate::output::fields::notes(grid.geometry);
        let file = format!("{name}_{:06}{suffix}.vtr", state.step);
        let path = self.dir.join("fields").join(&file);
        write_rectilinear_from(
            &path,
            &node_coordinates(grid),
            state.t,
            &sources,
            &format,
            &notes,
        )
        .map_err(|e| EfsiError::io(&path, e))?;
        let rel = format!("fields/{file}");
        self.pvd
            .add(state.t, &rel)
            .map_err(|e| EfsiError::io(self.dir.join("fields.pvd"), e))?;
        Ok(path)
    }
}

impl Writer for VtkSeries {
    fn label(&self) -> String {
        "fields.pvd".to_string()
    }

    fn write(&mut self, run: &mut RunAt<'_>) -> Result<PathBuf, EfsiError> {
        self.write_state(run, &run.sim.state, "")
    }

    fn save(&self, schedule: &Schedule, into: &mut OutputState) {
        into.vtk_count = schedule.count();
        into.pvd.extend_from_slice(self.pvd.entries());
    }

    /// `fields/<name>_<step>_last_good.vtr`, with a `.pvd` entry at its time.
    fn write_last_good(
        &mut self,
        run: &mut RunAt<'_>,
        state: &State,
    ) -> Result<Option<PathBuf>, EfsiError> {
        self.write_state(run, state, "_last_good").map(Some)
    }
}
