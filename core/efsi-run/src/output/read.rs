//! Reading back what efsi wrote (for `efsi plot`): its `.vtr` files — any [`VtrFormat`]:
//! `Float64` or `Float32`, raw or zlib-compressed — and its `.pvd` collections. This reads
//! efsi's own layout (one piece, appended data, `UInt64` headers), not every VTK file.
//!
//! [`VtrFormat`]: crate::output::vtk::VtrFormat

use std::io::{self, Read};
use std::path::{Path, PathBuf};

/// An array of a `.vtr` file, as `f64` whatever its type in the file.
#[derive(Clone, Debug, PartialEq)]
pub struct ReadArray {
    /// Its name.
    pub name: String,
    /// Components per tuple.
    pub components: usize,
    /// The values, tuple-major.
    pub values: Vec<f64>,
}

/// The content of a `.vtr` file written by efsi.
#[derive(Clone, Debug, PartialEq)]
pub struct VtrData {
    /// The simulation time (`TIME`).
    pub time: f64,
    /// The X, Y and Z node coordinates.
    pub coordinates: [Vec<f64>; 3],
    /// The cell arrays.
    pub cells: Vec<ReadArray>,
    /// The point arrays (empty unless written with point data).
    pub points: Vec<ReadArray>,
}

impl VtrData {
    /// The cell array `name`, if the file has it.
    pub fn cell(&self, name: &str) -> Option<&ReadArray> {
        self.cells.iter().find(|a| a.name == name)
    }

    /// The number of cells along X, Y and Z (1 along a flat axis); cells are stored with X
    /// fastest, then Y, then Z.
    pub fn cells3(&self) -> [usize; 3] {
        self.coordinates
            .each_ref()
            .map(|c| c.len().saturating_sub(1).max(1))
    }

    /// Whether the file holds a three-dimensional grid (no flat axis).
    pub fn is_3d(&self) -> bool {
        self.coordinates.iter().all(|c| c.len() > 1)
    }

    /// The number of cells along the two non-flat axes `(n1, n2)`: X–Y for a planar file, X–Z
    /// for an axisymmetric one (cells are stored with the first fastest); X–Y for a
    /// three-dimensional one, whose `cells3()[2]` planes follow one another.
    pub fn shape(&self) -> (usize, usize) {
        let (a1, a2) = self.plane_axes();
        let n = self.cells3();
        (n[a1], n[a2])
    }

    /// The two axes a two-dimensional file spans, the lower first (its cells are stored with
    /// that one fastest): X–Y planar, X–Z axisymmetric, and those of a slice's plane (Y–Z for a
    /// plane normal to X); X–Y for a three-dimensional file.
    pub fn plane_axes(&self) -> (usize, usize) {
        match self.coordinates.iter().position(|c| c.len() == 1) {
            Some(0) => (1, 2),
            Some(1) => (0, 2),
            _ => (0, 1),
        }
    }

    /// The plane `x_axis = at` (axis 0, 1, 2 for X, Y, Z) of a three-dimensional file: its cell
    /// arrays interpolated to the plane as a run's `output.slices` are
    /// ([`crate::output::slice`]), the coordinates flat along the normal; the point arrays are
    /// left out. Refused (saying why) for a two-dimensional file or a plane outside the box.
    pub fn plane(&self, axis: usize, at: f64) -> Result<VtrData, String> {
        use crate::output::slice::{Layers, axis_name, plane_nodes, plane_values};
        if !self.is_3d() {
            return Err(
                "a slice is a plane of a three-dimensional file, and this one is \
                        two-dimensional already"
                    .into(),
            );
        }
        let nodes = &self.coordinates[axis];
        let (lo, hi) = (nodes[0], nodes[nodes.len() - 1]);
        if !(at.is_finite() && at >= lo && at <= hi) {
            return Err(format!(
                "{} = {at} is outside the box's [{lo}, {hi}]",
                axis_name(axis)
            ));
        }
        let layers = Layers::around(nodes, at);
        let cells = self.cells3();
        Ok(VtrData {
            time: self.time,
            coordinates: plane_nodes(&self.coordinates, axis, at),
            cells: self
                .cells
                .iter()
                .map(|a| ReadArray {
                    name: a.name.clone(),
                    components: a.components,
                    values: plane_values(&a.values, a.components, cells, axis, layers),
                })
                .collect(),
            points: Vec::new(),
        })
    }
}

/// The bytes of the regular file at `path`, at most `limit` of them: a device (`/dev/zero`), a
/// pipe or a folder is refused before it is opened, and a file longer than `limit` is refused
/// without reading past it — what a reader of a run's files must do, since any of them can be
/// replaced by something endless. The error says what is wrong (the caller names the file).
pub fn read_regular(path: &Path, limit: u64) -> io::Result<Vec<u8>> {
    let plain = |what: String| io::Error::new(io::ErrorKind::InvalidData, what);
    let meta = std::fs::metadata(path)?;
    if !meta.is_file() {
        return Err(plain(if meta.is_dir() {
            "a folder, not a file".into()
        } else {
            "not a regular file (a device, a pipe or a socket)".into()
        }));
    }
    let too_long = |n: u64| {
        plain(format!(
            "{n} bytes or more, more than the {limit} a file of its kind may have"
        ))
    };
    if meta.len() > limit {
        return Err(too_long(meta.len()));
    }
    let mut bytes = Vec::with_capacity(meta.len() as usize);
    std::fs::File::open(path)?
        .take(limit + 1)
        .read_to_end(&mut bytes)?;
    if bytes.len() as u64 > limit {
        return Err(too_long(bytes.len() as u64));
    }
    Ok(bytes)
}

/// [`read_regular`] as UTF-8 text.
pub fn read_regular_text(path: &Path, limit: u64) -> io::Result<String> {
    String::from_utf8(read_regular(path, limit)?)
        .map_err(|_| io::Error::new(io::ErrorKind::InvalidData, "not UTF-8 text"))
}

/// The most bytes of a `run.json` read (64 MiB): it holds a scene (at most 4 MiB), its
/// overrides and a few lines per stage.
pub const MAX_RUN_JSON_BYTES: u64 = 64 << 20;
/// The most bytes of a `.pvd` collection read (256 MiB: two million entries).
pub const MAX_PVD_BYTES: u64 = 256 << 20;
/// The most bytes of one `.vtr` file read (16 GiB: a 4096² grid's fields several times over).
pub const MAX_VTR_BYTES: u64 = 16 << 30;
/// The most bytes of a `probes.csv` read for a plot (1 GiB: millions of rows).
pub const MAX_PROBES_BYTES: u64 = 1 << 30;

fn bad(path: &Path, what: impl std::fmt::Display) -> io::Error {
    io::Error::new(
        io::ErrorKind::InvalidData,
        format!("{}: {what}", path.display()),
    )
}

/// Attribute `key="…"` of an XML tag's text.
fn attr<'a>(tag: &'a str, key: &str) -> Option<&'a str> {
    let pat = format!(" {key}=\"");
    let start = tag.find(&pat)? + pat.len();
    let len = tag[start..].find('"')?;
    Some(&tag[start..start + len])
}

/// Read the `.vtr` file at `path`.
pub fn read_vtr(path: &Path) -> io::Result<VtrData> {
    let bytes = read_regular(path, MAX_VTR_BYTES).map_err(|e| bad(path, e))?;
    let (head, data, zlib) = split_appended(path, &bytes)?;
    let (mut time, mut coordinates, mut cells, mut points) = (
        f64::NAN,
        [Vec::new(), Vec::new(), Vec::new()],
        Vec::new(),
        Vec::new(),
    );
    let mut section = "";
    for line in head.lines() {
        let l = line.trim_start();
        for s in ["<FieldData", "<PointData", "<CellData", "<Coordinates"] {
            if l.starts_with(s) {
                section = s;
            }
        }
        if !l.starts_with("<DataArray") || attr(l, "format") != Some("appended") {
            continue;
        }
        let array = appended_array(path, l, data, zlib)?;
        match section {
            "<FieldData" if array.name == "TIME" => {
                time = array.values.first().copied().unwrap_or(f64::NAN)
            }
            "<PointData" => points.push(array),
            "<CellData" => cells.push(array),
            "<Coordinates" => {
                let k = match array.name.as_str() {
                    "x" => 0,
                    "y" => 1,
                    _ => 2,
                };
                coordinates[k] = array.values;
            }
            _ => {}
        }
    }
    Ok(VtrData {
        time,
        coordinates,
        cells,
        points,
    })
}

/// A `.vtr` file's bytes split at its appended data: the XML header before it, the appended
/// section after the `_` marker, and whether the blocks are zlib-compressed.
fn split_appended<'a>(path: &Path, bytes: &'a [u8]) -> io::Result<(&'a str, &'a [u8], bool)> {
    let marker = b"<AppendedData encoding=\"raw\">";
    let at = bytes
        .windows(marker.len())
        .position(|w| w == marker)
        .ok_or_else(|| bad(path, "no appended data (not a file efsi wrote)"))?;
    let underscore = at
        + bytes[at..]
            .iter()
            .position(|&b| b == b'_')
            .ok_or_else(|| bad(path, "no `_` marker"))?;
    let head = std::str::from_utf8(&bytes[..at]).map_err(|_| bad(path, "header not UTF-8"))?;
    let data = &bytes[underscore + 1..];
    let zlib = head.contains("compressor=\"vtkZLibDataCompressor\"");
    if !head.contains("header_type=\"UInt64\"") {
        return Err(bad(path, "only UInt64 block headers are read"));
    }
    Ok((head, data, zlib))
}

/// The appended array the `<DataArray …/>` tag `l` declares, read from the appended section
/// `data`.
fn appended_array(path: &Path, l: &str, data: &[u8], zlib: bool) -> io::Result<ReadArray> {
    let name = attr(l, "Name").ok_or_else(|| bad(path, "an array without a name"))?;
    let width = match attr(l, "type") {
        Some("Float64") => 8,
        Some("Float32") => 4,
        t => {
            return Err(bad(
                path,
                format_args!("array `{name}`: type {t:?} not read"),
            ));
        }
    };
    let offset: usize = attr(l, "offset")
        .and_then(|o| o.parse().ok())
        .ok_or_else(|| bad(path, format_args!("array `{name}`: no offset")))?;
    let components: usize = attr(l, "NumberOfComponents")
        .map_or(Some(1), |c| c.parse().ok())
        .ok_or_else(|| bad(path, format_args!("array `{name}`: bad component count")))?;
    let raw =
        block(data, offset, zlib).map_err(|e| bad(path, format_args!("array `{name}`: {e}")))?;
    let values: Vec<f64> = if width == 8 {
        raw.chunks_exact(8)
            .map(|c| f64::from_le_bytes(c.try_into().unwrap()))
            .collect()
    } else {
        raw.chunks_exact(4)
            .map(|c| f32::from_le_bytes(c.try_into().unwrap()) as f64)
            .collect()
    };
    Ok(ReadArray {
        name: name.to_string(),
        components,
        values,
    })
}

/// The payload of the block at `offset` of the appended section.
fn block(data: &[u8], offset: usize, zlib: bool) -> Result<Vec<u8>, String> {
    let word = |k: usize| -> Result<usize, String> {
        let s = offset + 8 * k;
        data.get(s..s + 8)
            .map(|b| u64::from_le_bytes(b.try_into().unwrap()) as usize)
            .ok_or_else(|| "truncated block header".to_string())
    };
    if !zlib {
        let n = word(0)?;
        return data
            .get(offset + 8..offset + 8 + n)
            .map(<[u8]>::to_vec)
            .ok_or_else(|| "truncated block".into());
    }
    let (blocks, size, last) = (word(0)?, word(1)?, word(2)?);
    let mut at = offset + 8 * (3 + blocks);
    let mut out = Vec::with_capacity(blocks * size);
    for k in 0..blocks {
        let c = word(3 + k)?;
        let chunk = data.get(at..at + c).ok_or("truncated compressed block")?;
        let before = out.len();
        flate2::read::ZlibDecoder::new(chunk)
            .read_to_end(&mut out)
            .map_err(|e| format!("zlib: {e}"))?;
        let want = if k + 1 == blocks && last != 0 {
            last
        } else {
            size
        };
        if out.len() - before != want {
            return Err(format!(
                "block {k} inflates to {} bytes, not {want}",
                out.len() - before
            ));
        }
        at += c;
    }
    Ok(out)
}

/// The `(time, file)` entries of the `.pvd` collection at `path`, the files resolved against
/// its folder.
pub fn read_pvd(path: &Path) -> io::Result<Vec<(f64, PathBuf)>> {
    let text = read_regular_text(path, MAX_PVD_BYTES).map_err(|e| bad(path, e))?;
    let dir = path.parent().unwrap_or(Path::new("."));
    let mut out = Vec::new();
    for l in text
        .lines()
        .filter(|l| l.trim_start().starts_with("<DataSet"))
    {
        let t = attr(l, "timestep")
            .and_then(|t| t.parse::<f64>().ok())
            .ok_or_else(|| bad(path, format_args!("a DataSet without a time: {l}")))?;
        let f = attr(l, "file")
            .ok_or_else(|| bad(path, format_args!("a DataSet without a file: {l}")))?;
        out.push((t, dir.join(f)));
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::output::vtk::{CellArray, VtkCompression, VtkPrecision, VtrFormat, write_vtr_with};
    use efsi_core::{Geometry, Grid};

    /// What the writer wrote, the reader reads: every format, both geometries, zlib blocks
    /// full and partial.
    #[test]
    fn reads_back_every_format() {
        let dir = std::env::temp_dir().join(format!("efsi-read-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        for geometry in [Geometry::Planar, Geometry::Axisymmetric] {
            // 96 × 64 cells × 6 components: 147 456 bytes as Float32, 4.5 zlib blocks.
            let grid = Grid::new(geometry, 96, 64, (0.0, 1.5), (-0.5, 0.5));
            let n = grid.cells();
            let p: Vec<f64> = (0..n).map(|k| (k as f64 * 0.37).sin()).collect();
            let b: Vec<f64> = (0..6 * n).map(|k| 1.0 + (k % 7) as f64 / 3.0).collect();
            let arrays = [
                CellArray {
                    name: "pressure",
                    components: 1,
                    values: &p,
                },
                CellArray {
                    name: "B",
                    components: 6,
                    values: &b,
                },
            ];
            for precision in [VtkPrecision::Float64, VtkPrecision::Float32] {
                for compression in [VtkCompression::None, VtkCompression::Zlib] {
                    let format = VtrFormat {
                        precision,
                        compression,
                        point_data: true,
                    };
                    let path = dir.join("f.vtr");
                    write_vtr_with(&path, &grid, 0.25, &arrays, &format, &[("units", "SI")])
                        .unwrap();
                    let r = read_vtr(&path).unwrap();
                    let what = format!("{geometry:?} {format:?}");
                    assert_eq!(r.time, 0.25, "{what}");
                    assert_eq!(r.shape(), (96, 64), "{what}");
                    assert_eq!(r.points.len(), 2, "{what}");
                    for (a, want) in [("pressure", &p), ("B", &b)] {
                        let got = &r.cell(a).unwrap().values;
                        let want: Vec<f64> = if precision == VtkPrecision::Float32 {
                            want.iter().map(|&v| v as f32 as f64).collect()
                        } else {
                            want.clone()
                        };
                        assert_eq!(got, &want, "{what} {a}");
                    }
                }
            }
        }
        std::fs::remove_dir_all(&dir).unwrap();
    }

    /// A three-dimensional state written and read back: the z coordinates, the velocity as a
    /// 3-vector with `w`, the divergence with ∂w/∂z, every value equal.
    #[test]
    fn a_three_dimensional_state_reads_back_equal() {
        use crate::output::fields::arrays;
        use crate::output::spec::VtkOptions;
        let dir = std::env::temp_dir().join(format!("efsi-read3-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let grid = Grid::new_3d([3, 4, 5], (0.0, 3.0), (0.0, 2.0), (-1.0, 1.5));
        let mut state = efsi_core::State::new(&grid, 1.0, 0.1, &Default::default());
        let w = state.w.as_mut().unwrap();
        for n in 0..w.data().len() {
            let [i, j, k] = w.index_of(n);
            w.data_mut()[n] = (i + 3 * j) as f64 + 0.5 * k as f64 * k as f64;
        }
        for n in 0..state.u.data().len() {
            let [i, j, k] = state.u.index_of(n);
            state.u.data_mut()[n] = (i * i) as f64 - (j + k) as f64;
            state.p.data_mut()[n] = (i + 10 * j + 100 * k) as f64;
        }
        let written = arrays(&grid, &state, &VtkOptions::default(), &[]);
        let cells: Vec<CellArray> = written
            .iter()
            .map(|(name, components, values)| CellArray {
                name,
                components: *components,
                values,
            })
            .collect();
        let path = dir.join("f.vtr");
        let format = VtrFormat {
            point_data: true,
            ..VtrFormat::default()
        };
        write_vtr_with(&path, &grid, 1.5, &cells, &format, &[]).unwrap();
        let r = read_vtr(&path).unwrap();
        assert!(r.is_3d());
        assert_eq!(r.cells3(), [3, 4, 5]);
        assert_eq!(r.coordinates[2], vec![-1.0, -0.5, 0.0, 0.5, 1.0, 1.5]);
        for (name, components, values) in &written {
            let a = r.cell(name).unwrap();
            assert_eq!((a.components, &a.values), (*components, values), "{name}");
        }
        // Cell (2, 1, 3) is number (3·4 + 1)·3 + 2 = 41: its velocity is the mean of each
        // component's two faces, w = ((2 + 3) + 4.5 + (2 + 3) + 8) / 2.
        let vel = &r.cell("velocity").unwrap().values;
        assert_eq!(vel[3 * 41 + 2], (5.0 + 4.5 + 5.0 + 8.0) / 2.0);
        assert_eq!(vel[3 * 41], ((4 - 4) as f64 + (9 - 4) as f64) / 2.0);
        assert_eq!(vel[3 * 41 + 1], 0.0);
        assert_eq!(r.cell("pressure").unwrap().values[41], 2.0 + 10.0 + 300.0);
        // ∂u/∂x + ∂w/∂z = (9 − 4)/1 + (8 − 4.5)/0.5.
        assert_eq!(r.cell("divergence").unwrap().values[41], 5.0 + 7.0);
        // Point data: node (0, 0, 0) is cell (0, 0, 0)'s value alone.
        let pp = &r
            .points
            .iter()
            .find(|a| a.name == "pressure")
            .unwrap()
            .values;
        assert_eq!(pp.len(), 4 * 5 * 6);
        assert_eq!(pp[0], 0.0);
        // Node (1, 1, 1): the mean of the eight cells around it.
        let mean = (0..8)
            .map(|c| ((c & 1) + 10 * ((c >> 1) & 1) + 100 * (c >> 2)) as f64)
            .sum::<f64>()
            / 8.0;
        assert_eq!(pp[(5 + 1) * 4 + 1], mean);
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
