//! VTK XML RectilinearGrid (`.vtr`) and ParaView collection (`.pvd`) writers.
//!
//! One `.vtr` file holds the cell data of one output time; a [`PvdCollection`] lists the files
//! with their times so ParaView plays them as a time series. Both are written with
//! [`write_atomically`], so a reader polling the output folder never sees a half-written file.
//!
//! # File layout
//!
//! The `.vtr` files use the XML format version 1.0 with `header_type="UInt64"` and *appended
//! raw* binary data: the XML header names every array with its byte `offset` into the appended
//! section, which follows the `_` marker as a sequence of blocks, each a little-endian `UInt64`
//! byte count followed by the little-endian `Float64` payload. Coordinates and cell data are
//! `Float64`, so values read back bit-exact.
//!
//! * Planar grids ([`Geometry::Planar`]) lie in the X–Y plane: extent `0 nx 0 ny 0 0`, X and Y
//!   the node coordinates, Z = `[0]`.
//! * Axisymmetric grids put the r–z slice in the X–Z plane: extent `0 nx 0 0 0 ny`, X the radial
//!   nodes, Y = `[0]`, Z the axial nodes, so ParaView's *Rotational Extrusion* (about Z) revolves
//!   it directly.
//!
//! * Three-dimensional grids ([`Geometry::Cartesian3D`]): extent `0 nx 0 ny 0 nz`, X, Y and Z
//!   the node coordinates; vectors have their three components.
//! * A plane slice of a three-dimensional grid ([`write_rectilinear`], any rectilinear mesh):
//!   flat along its normal, whose one coordinate is the plane's position (extent
//!   `0 nx 0 ny 0 0` and Z = `[at]` for a plane normal to Z).
//!
//! VTK orders cells with i fastest, then the next non-flat axis, which in every case is efsi's
//! row-major `(i, j)` order, planes of `k` outermost in three dimensions: cell `(i, j, k)`,
//! component `c` is at `((k·ny + j)·nx + i)·components + c` (`k = 0` in two dimensions).
//!
//! [`write_vtr_with`] writes the same layout with options ([`VtrFormat`]): the arrays as
//! `Float32` instead of `Float64`; the appended data compressed with zlib — VTK's
//! `vtkZLibDataCompressor`: the `VTKFile` element names the compressor and every block becomes a
//! header of `UInt64`s (number of blocks, uncompressed block size, size of the last partial
//! block or 0, each block's compressed size) followed by the deflated blocks of at most
//! [`ZLIB_BLOCK`] bytes; each cell array also written as point data, at the nodes, each node
//! the mean of the (up to four, eight in three dimensions) cells around it; and text field data (one-tuple `String`
//! arrays, ASCII) such as the geometry and the units. Coordinates and the time stay `Float64`.
//!
//! The simulation time is stored twice as one-value `Float64` field data: `TIME` (the name VisIt
//! and many scripts look for, shown in ParaView's spreadsheet and information panels) and
//! `TimeValue` (the name VTK ≥ 8.2 XML readers recognise as the time step of a lone file, so a
//! `.vtr` opened without its `.pvd` still carries its time).

use crate::output::atomic::{write_atomically, write_bytes_atomically};
pub use crate::output::spec::{VtkCompression, VtkPrecision};
use efsi_core::grid::{Geometry, Grid};
use std::fmt::Write as _;
use std::io::{self, Write};
use std::path::{Path, PathBuf};

/// One cell-data array.
///
/// `values.len()` must be `nx · ny · nz · components` (`nz` = 1 in two dimensions); cell
/// `(i, j, k)`, component `c` is at `((k·ny + j)·nx + i)·components + c`. Scalars have 1 component, vectors 3 (pad the third with zero in
/// 2-D), symmetric tensors 6 in VTK's order XX, YY, ZZ, XY, YZ, XZ (in axisymmetric output
/// X is r, Y is θ and Z is z, so the r–z component goes in XZ). The writer only records
/// `NumberOfComponents`; arranging the components is the caller's job.
#[derive(Clone, Copy, Debug)]
pub struct CellArray<'a> {
    /// Array name as ParaView shows it (`pressure`, `velocity`, `B`, …).
    pub name: &'a str,
    /// Number of components per cell (≥ 1).
    pub components: usize,
    /// The values, cell-major: all components of cell 0, then of cell 1, …
    pub values: &'a [f64],
}

/// The uncompressed size of a zlib block (VTK's default, 32 KiB).
pub const ZLIB_BLOCK: usize = 1 << 15;

/// How [`write_vtr_with`] stores the arrays; the default is [`write_vtr`]'s: `Float64` cell
/// data, raw.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct VtrFormat {
    /// The type of the cell (and point) arrays.
    pub precision: VtkPrecision,
    /// Compression of every appended block.
    pub compression: VtkCompression,
    /// Also write every cell array as point data (node values: the mean of adjacent cells).
    pub point_data: bool,
}

/// The cell values of `values` (`components` per cell) averaged to the nodes: node `(i, j)`,
/// `i` fastest, is the mean of the cells `(i − 1 … i, j − 1 … j)` inside the grid; in three
/// dimensions node `(i, j, k)` the mean of the cells `(i − 1 … i, j − 1 … j, k − 1 … k)`.
pub fn cells_to_points(grid: &Grid, values: &[f64], components: usize) -> Vec<f64> {
    let nodes = node_coordinates(grid).each_ref().map(Vec::len);
    average_to_nodes(nodes, values, components)
}

/// [`cells_to_points`] of a rectilinear mesh of `nodes` nodes along X, Y and Z (1 along a flat
/// axis, which has one cell layer): each node the mean of the cells around it, summed with the
/// outermost axis' cell first.
fn average_to_nodes(nodes: [usize; 3], values: &[f64], components: usize) -> Vec<f64> {
    let [m0, m1, m2] = nodes;
    let [n0, n1, n2] = nodes.map(|m| m.saturating_sub(1).max(1));
    let mut out = vec![0.0; m0 * m1 * m2 * components];
    let around = |i: usize, n: usize| i.saturating_sub(1)..(i + 1).min(n);
    for k in 0..m2 {
        for j in 0..m1 {
            for i in 0..m0 {
                let o = ((k * m1 + j) * m0 + i) * components;
                let mut n = 0.0;
                for ck in around(k, n2) {
                    for cj in around(j, n1) {
                        for ci in around(i, n0) {
                            let c = ((ck * n1 + cj) * n0 + ci) * components;
                            for q in 0..components {
                                out[o + q] += values[c + q];
                            }
                            n += 1.0;
                        }
                    }
                }
                for q in 0..components {
                    out[o + q] /= n;
                }
            }
        }
    }
    out
}

/// A producer of an array's values: it hands them to its sink in consecutive pieces, in the
/// file's order (all of them, each once), stopping at the sink's first error.
pub type Produce<'a> =
    dyn Fn(&mut dyn FnMut(&[f64]) -> io::Result<()>) -> io::Result<()> + Sync + 'a;

/// One cell-data array made piece by piece as it is written ([`write_rectilinear_from`]): the
/// file is then written without holding its arrays (a raw file holds none of them; with
/// point data an array is gathered whole while its nodes are averaged, with zlib each block
/// is held compressed until the header, which needs the sizes, is written).
#[derive(Clone, Copy)]
pub struct CellSource<'a> {
    /// Array name as ParaView shows it.
    pub name: &'a str,
    /// Number of components per cell (≥ 1).
    pub components: usize,
    /// Its values, cell-major, in pieces ([`Produce`]).
    pub values: &'a Produce<'a>,
}

/// Values encoded per piece: at most this many at a time go through a stack buffer.
const PIECE: usize = 512;

/// The little-endian bytes of `values`, as `Float64` or, if `float32`, rounded to `Float32`,
/// handed to `out` a stack buffer at a time.
fn encode_values(
    values: &[f64],
    float32: bool,
    out: &mut dyn FnMut(&[u8]) -> io::Result<()>,
) -> io::Result<()> {
    let mut bytes = [0u8; 8 * PIECE];
    for piece in values.chunks(PIECE) {
        let n = if float32 {
            for (b, v) in bytes.chunks_exact_mut(4).zip(piece) {
                b.copy_from_slice(&(*v as f32).to_le_bytes());
            }
            4 * piece.len()
        } else {
            for (b, v) in bytes.chunks_exact_mut(8).zip(piece) {
                b.copy_from_slice(&v.to_le_bytes());
            }
            8 * piece.len()
        };
        out(&bytes[..n])?;
    }
    Ok(())
}

/// A zlib-compressed appended block (see the module docs) of the payload `produce` hands over,
/// its values as `Float64` or, if `float32`, `Float32`: the payload cut into [`ZLIB_BLOCK`]
/// bytes as it comes, each deflated on its own.
fn compress_block(produce: &Produce, float32: bool) -> io::Result<Vec<u8>> {
    let mut raw: Vec<u8> = Vec::with_capacity(ZLIB_BLOCK);
    let mut compressed: Vec<Vec<u8>> = Vec::new();
    let deflate = |b: &[u8]| -> io::Result<Vec<u8>> {
        let mut z = flate2::write::ZlibEncoder::new(Vec::new(), flate2::Compression::default());
        z.write_all(b)?;
        z.finish()
    };
    produce(&mut |values| {
        encode_values(values, float32, &mut |mut bytes| {
            while !bytes.is_empty() {
                let take = bytes.len().min(ZLIB_BLOCK - raw.len());
                raw.extend_from_slice(&bytes[..take]);
                bytes = &bytes[take..];
                if raw.len() == ZLIB_BLOCK {
                    compressed.push(deflate(&raw)?);
                    raw.clear();
                }
            }
            Ok(())
        })
    })?;
    let last = raw.len();
    if last > 0 {
        compressed.push(deflate(&raw)?);
    }
    let mut out = Vec::new();
    for h in [compressed.len(), ZLIB_BLOCK, last] {
        out.extend_from_slice(&(h as u64).to_le_bytes());
    }
    for c in &compressed {
        out.extend_from_slice(&(c.len() as u64).to_le_bytes());
    }
    for c in &compressed {
        out.extend_from_slice(c);
    }
    Ok(out)
}

/// A VTK XML ASCII `String` value: each byte as a number, then the terminating 0.
fn ascii_string(s: &str) -> String {
    let mut out = String::with_capacity(4 * s.len() + 1);
    for b in s.bytes() {
        let _ = write!(out, "{b} ");
    }
    out.push('0');
    out
}

/// An `InvalidInput` error naming the file.
fn invalid(path: &Path, what: impl std::fmt::Display) -> io::Error {
    io::Error::new(
        io::ErrorKind::InvalidInput,
        format!("cannot write {}: {what}", path.display()),
    )
}

/// `s` escaped for use inside a double-quoted XML attribute.
fn xml_attr(s: &str) -> String {
    let mut out = String::with_capacity(s.len());
    for ch in s.chars() {
        match ch {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '"' => out.push_str("&quot;"),
            '\'' => out.push_str("&apos;"),
            c => out.push(c),
        }
    }
    out
}

/// The `WholeExtent`/`Extent` string of `grid`: `0 nx 0 ny 0 0` planar, `0 nx 0 0 0 ny`
/// axisymmetric, `0 nx 0 ny 0 nz` three-dimensional.
pub fn extent_string(grid: &Grid) -> String {
    match grid.geometry {
        Geometry::Cartesian3D => format!("0 {} 0 {} 0 {}", grid.nx, grid.ny, grid.nz),
        Geometry::Planar => format!("0 {} 0 {} 0 0", grid.nx, grid.ny),
        Geometry::Axisymmetric => format!("0 {} 0 0 0 {}", grid.nx, grid.ny),
    }
}

/// The X, Y and Z node coordinate arrays of `grid` as written to the `.vtr` file.
pub fn node_coordinates(grid: &Grid) -> [Vec<f64>; 3] {
    let xs: Vec<f64> = (0..=grid.nx as isize).map(|i| grid.xf(i)).collect();
    let ys: Vec<f64> = (0..=grid.ny as isize).map(|j| grid.yf(j)).collect();
    match grid.geometry {
        Geometry::Planar => [xs, ys, vec![0.0]],
        Geometry::Cartesian3D => [xs, ys, (0..=grid.nz as isize).map(|k| grid.zf(k)).collect()],
        Geometry::Axisymmetric => [xs, vec![0.0], ys],
    }
}

/// Write the cell data `arrays` of `grid` at simulation time `time` to the `.vtr` file `path`
/// (atomically: see [`write_atomically`]), as `Float64`, raw: [`write_vtr_with`] with the
/// default [`VtrFormat`] and no text field data.
///
/// Fails with `InvalidInput` (and writes nothing) if `time` is not finite, an array name is empty
/// or repeated, an array has zero components, or its length is not `nx · ny · nz · components`.
/// Non-finite cell values are written as they are.
pub fn write_vtr(path: &Path, grid: &Grid, time: f64, arrays: &[CellArray]) -> io::Result<()> {
    write_vtr_with(path, grid, time, arrays, &VtrFormat::default(), &[])
}

/// [`write_vtr`] with the arrays stored as `format` says, and the text field data `notes`
/// (`(name, text)`: one-tuple `String` arrays beside `TIME`, e.g. the geometry and the units).
pub fn write_vtr_with(
    path: &Path,
    grid: &Grid,
    time: f64,
    arrays: &[CellArray],
    format: &VtrFormat,
    notes: &[(&str, &str)],
) -> io::Result<()> {
    let mesh = node_coordinates(grid);
    write_rectilinear(path, &mesh, time, arrays, format, notes)
}

/// [`write_vtr_with`] of any rectilinear mesh: `nodes` are the X, Y and Z node coordinates (one
/// value along a flat axis, which has one cell layer), the extent `0 n_X 0 n_Y 0 n_Z` with
/// `n` the node count less one, and `arrays` hold the cells' values in VTK's order (X fastest).
/// A plane slice of a three-dimensional run is such a mesh, flat along its normal.
pub fn write_rectilinear(
    path: &Path,
    nodes: &[Vec<f64>; 3],
    time: f64,
    arrays: &[CellArray],
    format: &VtrFormat,
    notes: &[(&str, &str)],
) -> io::Result<()> {
    let whole: Vec<Box<Produce>> = arrays
        .iter()
        .map(|a| {
            let values = a.values;
            Box::new(move |sink: &mut dyn FnMut(&[f64]) -> io::Result<()>| sink(values))
                as Box<Produce>
        })
        .collect();
    write_rectilinear_from(path, nodes, time, &sources(arrays, &whole), format, notes)
}

/// The sources of `arrays`, the values of each made by its entry of `produce`.
fn sources<'a>(arrays: &[CellArray<'a>], produce: &'a [Box<Produce<'a>>]) -> Vec<CellSource<'a>> {
    arrays
        .iter()
        .zip(produce)
        .map(|(a, values)| CellSource {
            name: a.name,
            components: a.components,
            values: &**values,
        })
        .collect()
}

/// The cells of a rectilinear mesh of `nodes` (one layer along a flat axis).
fn cell_count(nodes: &[Vec<f64>; 3]) -> usize {
    nodes
        .iter()
        .map(|m| m.len().saturating_sub(1).max(1))
        .product()
}

/// One appended block of a `.vtr` file, in the order of the appended section.
#[derive(Clone, Copy)]
enum Block {
    /// The time (`TIME`, then `TimeValue`).
    Time,
    /// A cell array averaged to the nodes (point data).
    Points(usize),
    /// A cell array.
    Cells(usize),
    /// The node coordinates along an axis.
    Axis(usize),
}

/// [`write_rectilinear`] of arrays made as they are written ([`CellSource`]): the same file,
/// byte for byte, without the arrays or their encoded blocks in memory (raw data streams
/// through the file's buffer). A source that hands over a number of values other than
/// `cells × components` fails the write with `InvalidInput` and leaves no file.
pub fn write_rectilinear_from(
    path: &Path,
    nodes: &[Vec<f64>; 3],
    time: f64,
    sources: &[CellSource],
    format: &VtrFormat,
    notes: &[(&str, &str)],
) -> io::Result<()> {
    if !time.is_finite() {
        return Err(invalid(path, format_args!("the time {time} is not finite")));
    }
    check_sources(path, sources)?;
    check_notes(path, notes)?;
    let appended = Appended::new(path, nodes, time, sources, format);
    let [m0, m1, m2] = appended.counts.map(|m| m.saturating_sub(1));
    let extent = format!("0 {m0} 0 {m1} 0 {m2}");
    let header = |offsets: &[u64]| header(&extent, sources, format, notes, offsets);
    match format.compression {
        VtkCompression::None => appended.write_raw(&header),
        VtkCompression::Zlib => appended.write_zlib(&header),
    }
}

/// The end of a `.vtr` file, after the appended blocks.
const TAIL: &[u8] = b"\n  </AppendedData>\n</VTKFile>\n";

/// The appended blocks of one `.vtr` file and what they are made of: the time, the arrays of
/// `sources` (as point data too with `VtrFormat::point_data`), the node coordinates.
struct Appended<'a> {
    path: &'a Path,
    nodes: &'a [Vec<f64>; 3],
    time: f64,
    sources: &'a [CellSource<'a>],
    /// Nodes along each axis.
    counts: [usize; 3],
    cells: usize,
    /// Whether the arrays go as `Float32`.
    float32: bool,
    /// The blocks in the order of the appended section.
    blocks: Vec<Block>,
}

impl<'a> Appended<'a> {
    fn new(
        path: &'a Path,
        nodes: &'a [Vec<f64>; 3],
        time: f64,
        sources: &'a [CellSource<'a>],
        format: &VtrFormat,
    ) -> Self {
        let arrays = 0..sources.len();
        let point_blocks = arrays.clone().filter(|_| format.point_data);
        let blocks: Vec<Block> = [Block::Time, Block::Time]
            .into_iter()
            .chain(point_blocks.map(Block::Points))
            .chain(arrays.map(Block::Cells))
            .chain((0..3).map(Block::Axis))
            .collect();
        Appended {
            path,
            nodes,
            time,
            sources,
            counts: nodes.each_ref().map(Vec::len),
            cells: cell_count(nodes),
            float32: format.precision == VtkPrecision::Float32,
            blocks,
        }
    }

    /// The values of block `b` handed to `sink` in pieces.
    fn produce(&self, b: Block, sink: &mut dyn FnMut(&[f64]) -> io::Result<()>) -> io::Result<()> {
        match b {
            Block::Time => sink(&[self.time]),
            Block::Axis(a) => sink(&self.nodes[a]),
            Block::Cells(k) => counted(self.path, &self.sources[k], self.cells, sink),
            Block::Points(k) => {
                let s = &self.sources[k];
                let mut whole = Vec::with_capacity(self.cells * s.components);
                counted(self.path, s, self.cells, &mut |v| {
                    whole.extend_from_slice(v);
                    Ok(())
                })?;
                sink(&average_to_nodes(self.counts, &whole, s.components))
            }
        }
    }

    /// Whether block `b` goes as `Float32`.
    fn single(&self, b: Block) -> bool {
        self.float32 && matches!(b, Block::Points(_) | Block::Cells(_))
    }

    /// The bytes of block `b` uncompressed.
    fn payload(&self, b: Block) -> usize {
        let values = match b {
            Block::Time => 1,
            Block::Axis(a) => self.counts[a],
            Block::Cells(k) => self.cells * self.sources[k].components,
            Block::Points(k) => self.counts.iter().product::<usize>() * self.sources[k].components,
        };
        (if self.single(b) { 4 } else { 8 }) * values
    }

    /// The file with raw blocks (each its byte count, then its values), streamed through the
    /// file's buffer.
    fn write_raw(&self, header: &dyn Fn(&[u64]) -> String) -> io::Result<()> {
        let sizes = self.blocks.iter().map(|&b| 8 + self.payload(b) as u64);
        self.write_file(&header(&offsets(sizes)), |w| {
            for &b in &self.blocks {
                w.write_all(&(self.payload(b) as u64).to_le_bytes())?;
                self.produce(b, &mut |v| {
                    encode_values(v, self.single(b), &mut |x| w.write_all(x))
                })?;
            }
            Ok(())
        })
    }

    /// The file with zlib-compressed blocks ([`compress_block`]), each held compressed until
    /// the header, which needs their sizes, is written.
    fn write_zlib(&self, header: &dyn Fn(&[u64]) -> String) -> io::Result<()> {
        let encoded = self
            .blocks
            .iter()
            .map(|&b| compress_block(&|sink| self.produce(b, sink), self.single(b)))
            .collect::<io::Result<Vec<_>>>()?;
        let sizes = encoded.iter().map(|e| e.len() as u64);
        self.write_file(&header(&offsets(sizes)), |w| {
            encoded.iter().try_for_each(|e| w.write_all(e))
        })
    }

    /// The file (atomically: [`write_atomically`]): `header`, the appended blocks `blocks`
    /// writes, the tail.
    fn write_file(
        &self,
        header: &str,
        blocks: impl FnOnce(&mut std::io::BufWriter<std::fs::File>) -> io::Result<()>,
    ) -> io::Result<()> {
        write_atomically(self.path, |w| {
            w.write_all(header.as_bytes())?;
            blocks(w)?;
            w.write_all(TAIL)
        })
    }
}

/// The offset of each block of the appended section from the blocks' `sizes` in bytes.
fn offsets(sizes: impl Iterator<Item = u64>) -> Vec<u64> {
    sizes
        .scan(0u64, |at, size| {
            let here = *at;
            *at += size;
            Some(here)
        })
        .collect()
}

/// The values of `source` handed to `sink`, failing with `InvalidInput` if they are not
/// `cells × components`.
fn counted(
    path: &Path,
    source: &CellSource,
    cells: usize,
    sink: &mut dyn FnMut(&[f64]) -> io::Result<()>,
) -> io::Result<()> {
    let mut n = 0;
    (source.values)(&mut |v| {
        n += v.len();
        sink(v)
    })?;
    let expected = cells * source.components;
    if n != expected {
        return Err(invalid(
            path,
            format_args!(
                "cell array `{}` has {n} values, expected {cells} cells × {} components = {expected}",
                source.name, source.components
            ),
        ));
    }
    Ok(())
}

/// The sources' names (non-empty, each once) and component counts (≥ 1), or the
/// `InvalidInput` error naming the file and the array.
fn check_sources(path: &Path, sources: &[CellSource]) -> io::Result<()> {
    for (k, a) in sources.iter().enumerate() {
        if a.name.is_empty() {
            return Err(invalid(
                path,
                format_args!("cell array #{k} has an empty name"),
            ));
        }
        if sources[..k].iter().any(|b| b.name == a.name) {
            return Err(invalid(
                path,
                format_args!("cell array name `{}` is used twice", a.name),
            ));
        }
        if a.components == 0 {
            return Err(invalid(
                path,
                format_args!("cell array `{}` has 0 components", a.name),
            ));
        }
    }
    Ok(())
}

/// The text field data's names: non-empty, each once, neither `TIME` nor `TimeValue`.
fn check_notes(path: &Path, notes: &[(&str, &str)]) -> io::Result<()> {
    for (k, (name, _)) in notes.iter().enumerate() {
        if name.is_empty()
            || notes[..k].iter().any(|n| n.0 == *name)
            || *name == "TIME"
            || *name == "TimeValue"
        {
            return Err(invalid(
                path,
                format_args!("field data name `{name}` is empty, repeated or reserved"),
            ));
        }
    }
    Ok(())
}

/// The XML of a `.vtr` file up to the appended data's `_` marker: the mesh of `extent`, the
/// field data (`TIME`, `TimeValue`, the `notes`), the point data (with `format.point_data`)
/// and cell data of `arrays`, and the coordinates, each appended array at its offset of
/// `offsets` (in that order).
fn header(
    extent: &str,
    arrays: &[CellSource],
    format: &VtrFormat,
    notes: &[(&str, &str)],
    offsets: &[u64],
) -> String {
    let mut off = offsets.iter();
    let array_type = match format.precision {
        VtkPrecision::Float32 => "Float32",
        VtkPrecision::Float64 => "Float64",
    };
    let compressor = match format.compression {
        VtkCompression::None => "",
        VtkCompression::Zlib => r#" compressor="vtkZLibDataCompressor""#,
    };
    let mut h = String::with_capacity(2048 + 320 * arrays.len());
    // Writing to a String cannot fail.
    let _ = (|| -> std::fmt::Result {
        writeln!(h, r#"<?xml version="1.0"?>"#)?;
        writeln!(
            h,
            r#"<VTKFile type="RectilinearGrid" version="1.0" byte_order="LittleEndian" header_type="UInt64"{compressor}>"#
        )?;
        writeln!(h, r#"  <RectilinearGrid WholeExtent="{extent}">"#)?;
        writeln!(h, "    <FieldData>")?;
        for name in ["TIME", "TimeValue"] {
            writeln!(
                h,
                r#"      <DataArray type="Float64" Name="{name}" NumberOfTuples="1" format="appended" offset="{}"/>"#,
                off.next().unwrap()
            )?;
        }
        for (name, text) in notes {
            writeln!(
                h,
                r#"      <DataArray type="String" Name="{}" NumberOfTuples="1" format="ascii">{}</DataArray>"#,
                xml_attr(name),
                ascii_string(text)
            )?;
        }
        writeln!(h, "    </FieldData>")?;
        writeln!(h, r#"    <Piece Extent="{extent}">"#)?;
        // One appended array's declaration; offsets in the order the data follow.
        let mut declare = |h: &mut String, name: &str, components: usize| {
            writeln!(
                h,
                r#"        <DataArray type="{array_type}" Name="{}" NumberOfComponents="{components}" format="appended" offset="{}"/>"#,
                xml_attr(name),
                off.next().unwrap()
            )
        };
        writeln!(h, "      <PointData>")?;
        if format.point_data {
            for a in arrays {
                declare(&mut h, a.name, a.components)?;
            }
        }
        writeln!(h, "      </PointData>")?;
        writeln!(h, "      <CellData>")?;
        for a in arrays {
            declare(&mut h, a.name, a.components)?;
        }
        writeln!(h, "      </CellData>")?;
        writeln!(h, "      <Coordinates>")?;
        for name in ["x", "y", "z"] {
            writeln!(
                h,
                r#"        <DataArray type="Float64" Name="{name}" format="appended" offset="{}"/>"#,
                off.next().unwrap()
            )?;
        }
        writeln!(h, "      </Coordinates>")?;
        writeln!(h, "    </Piece>")?;
        writeln!(h, "  </RectilinearGrid>")?;
        write!(h, r#"  <AppendedData encoding="raw">"#)?;
        write!(h, "\n   _")
    })();
    h
}

/// A ParaView `.pvd` collection: the list of `(time, file)` entries of a time series.
///
/// File names are stored as given and should be relative to the `.pvd` file's folder (ParaView
/// resolves them from there). Every [`add`](Self::add) rewrites the whole `.pvd` atomically, so
/// the collection on disk is always complete and lists every file written so far.
#[derive(Clone, Debug)]
pub struct PvdCollection {
    path: PathBuf,
    entries: Vec<(f64, String)>,
}

impl PvdCollection {
    /// An empty collection to be written at `path` (nothing is written until the first
    /// [`add`](Self::add)).
    pub fn new(path: impl Into<PathBuf>) -> Self {
        PvdCollection {
            path: path.into(),
            entries: Vec::new(),
        }
    }

    /// A collection at `path` with `entries` already recorded (a resumed run's); nothing is
    /// written until [`write`](Self::write) or [`add`](Self::add).
    pub fn with_entries(path: impl Into<PathBuf>, entries: Vec<(f64, String)>) -> Self {
        PvdCollection {
            path: path.into(),
            entries,
        }
    }

    /// The path of the `.pvd` file.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Append the entry `(time, file)` and rewrite the `.pvd` file.
    ///
    /// A non-finite `time` is refused with `InvalidInput` and not recorded. If rewriting the
    /// file fails the entry stays recorded (the next successful `add` writes it) and the error
    /// is returned.
    pub fn add(&mut self, time: f64, file: &str) -> io::Result<()> {
        if !time.is_finite() {
            return Err(invalid(
                &self.path,
                format_args!("the time {time} of `{file}` is not finite"),
            ));
        }
        self.entries.push((time, file.to_owned()));
        self.write()
    }

    /// The entries recorded so far, in the order they were added.
    pub fn entries(&self) -> &[(f64, String)] {
        &self.entries
    }

    /// The `.pvd` XML text for the current entries. Times are written with `{:e}`, the shortest
    /// form that parses back to the same `f64`.
    pub fn to_xml(&self) -> String {
        let mut s = String::with_capacity(256 + 96 * self.entries.len());
        s.push_str("<?xml version=\"1.0\"?>\n");
        s.push_str(
            "<VTKFile type=\"Collection\" version=\"1.0\" byte_order=\"LittleEndian\" header_type=\"UInt64\">\n",
        );
        s.push_str("  <Collection>\n");
        for (t, f) in &self.entries {
            let _ = writeln!(
                s,
                r#"    <DataSet timestep="{t:e}" group="" part="0" file="{}"/>"#,
                xml_attr(f)
            );
        }
        s.push_str("  </Collection>\n</VTKFile>\n");
        s
    }

    /// Rewrite the `.pvd` file from the current entries (atomically).
    pub fn write(&self) -> io::Result<()> {
        let xml = self.to_xml();
        write_bytes_atomically(&self.path, xml.as_bytes())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::output::atomic::temporary_path;
    use std::fs;

    fn scratch(name: &str) -> PathBuf {
        let dir = std::env::temp_dir().join(format!("efsi-vtk-{}-{name}", std::process::id()));
        let _ = fs::remove_dir_all(&dir);
        fs::create_dir_all(&dir).unwrap();
        dir
    }

    /// Attribute `key="…"` of the XML line `line`.
    fn attr<'a>(line: &'a str, key: &str) -> Option<&'a str> {
        let pat = format!(" {key}=\"");
        let start = line.find(&pat)? + pat.len();
        let len = line[start..].find('"')?;
        Some(&line[start..start + len])
    }

    /// Split a `.vtr` file into its XML header (up to and including `_`) and appended bytes.
    fn split(bytes: &[u8]) -> (String, &[u8]) {
        let tag = b"<AppendedData encoding=\"raw\">";
        let at = bytes
            .windows(tag.len())
            .position(|w| w == tag)
            .expect("no AppendedData");
        let us = at + bytes[at..].iter().position(|&b| b == b'_').unwrap();
        (
            String::from_utf8(bytes[..=us].to_vec()).unwrap(),
            &bytes[us + 1..],
        )
    }

    fn read_block(data: &[u8], offset: usize) -> Vec<f64> {
        let n = u64::from_le_bytes(data[offset..offset + 8].try_into().unwrap()) as usize;
        assert_eq!(n % 8, 0);
        data[offset + 8..offset + 8 + n]
            .chunks_exact(8)
            .map(|c| f64::from_le_bytes(c.try_into().unwrap()))
            .collect()
    }

    fn sample(grid: &Grid) -> (Vec<f64>, Vec<f64>, Vec<f64>) {
        let n = grid.cells();
        let p: Vec<f64> = (0..n).map(|k| k as f64 * 0.1 - 1.0 / 3.0).collect();
        let u: Vec<f64> = (0..3 * n).map(|k| (k as f64).sin()).collect();
        let b: Vec<f64> = (0..6 * n).map(|k| 1.0 + k as f64 / 7.0).collect();
        (p, u, b)
    }

    #[test]
    fn planar_blocks_match_header_and_payload() {
        let dir = scratch("planar");
        let grid = Grid::new(Geometry::Planar, 7, 5, (0.0, 1.4), (0.0, 1.0));
        let (p, u, b) = sample(&grid);
        let arrays = [
            CellArray {
                name: "pressure",
                components: 1,
                values: &p,
            },
            CellArray {
                name: "velocity",
                components: 3,
                values: &u,
            },
            CellArray {
                name: "B",
                components: 6,
                values: &b,
            },
        ];
        let path = dir.join("f.vtr");
        write_vtr(&path, &grid, 0.125, &arrays).unwrap();
        let bytes = fs::read(&path).unwrap();
        let (head, data) = split(&bytes);

        assert!(head.starts_with("<?xml version=\"1.0\"?>\n<VTKFile type=\"RectilinearGrid\" version=\"1.0\" byte_order=\"LittleEndian\" header_type=\"UInt64\">"));
        assert!(head.contains(r#"<RectilinearGrid WholeExtent="0 7 0 5 0 0">"#));
        assert!(head.contains(r#"<Piece Extent="0 7 0 5 0 0">"#));
        for tag in [
            "FieldData",
            "CellData",
            "Coordinates",
            "Piece",
            "RectilinearGrid",
        ] {
            let open = head.find(&format!("<{tag}")).unwrap();
            let close = head.find(&format!("</{tag}>")).unwrap();
            assert!(open < close, "{tag}");
        }
        assert!(bytes.ends_with(b"\n  </AppendedData>\n</VTKFile>\n"));

        // Every DataArray's offset points at a block whose byte count matches its payload.
        let expected: Vec<(&str, Vec<f64>)> = vec![
            ("TIME", vec![0.125]),
            ("TimeValue", vec![0.125]),
            ("pressure", p.clone()),
            ("velocity", u.clone()),
            ("B", b.clone()),
            ("x", (0..=7).map(|i| grid.xf(i)).collect()),
            ("y", (0..=5).map(|j| grid.yf(j)).collect()),
            ("z", vec![0.0]),
        ];
        let lines: Vec<&str> = head.lines().filter(|l| l.contains("<DataArray")).collect();
        assert_eq!(lines.len(), expected.len());
        let mut next = 0usize;
        for (line, (name, values)) in lines.iter().zip(&expected) {
            assert_eq!(attr(line, "Name"), Some(*name));
            assert_eq!(attr(line, "type"), Some("Float64"));
            assert_eq!(attr(line, "format"), Some("appended"));
            let offset: usize = attr(line, "offset").unwrap().parse().unwrap();
            assert_eq!(offset, next, "{name}: blocks are contiguous");
            let got = read_block(data, offset);
            assert_eq!(got.len(), values.len(), "{name}");
            assert!(
                got.iter()
                    .zip(values)
                    .all(|(a, b)| a.to_bits() == b.to_bits())
            );
            next = offset + 8 + 8 * values.len();
        }
        for (a, c) in arrays.iter().zip(&lines[2..5]) {
            assert_eq!(
                attr(c, "NumberOfComponents"),
                Some(a.components.to_string().as_str())
            );
        }
        // The appended section is exactly the blocks plus the closing tags.
        assert_eq!(
            data.len(),
            next + b"\n  </AppendedData>\n</VTKFile>\n".len()
        );
        assert!(!dir.join(".f.vtr.tmp").exists());
        fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn axisymmetric_slice_lies_in_xz_plane() {
        let dir = scratch("axi");
        let grid = Grid::new(Geometry::Axisymmetric, 6, 9, (0.0, 0.6), (-0.2, 0.7));
        let (p, _, _) = sample(&grid);
        let path = dir.join("a.vtr");
        let arrays = [CellArray {
            name: "p",
            components: 1,
            values: &p,
        }];
        write_vtr(&path, &grid, 2.0, &arrays).unwrap();
        assert_eq!(extent_string(&grid), "0 6 0 0 0 9");
        let bytes = fs::read(&path).unwrap();
        let (head, data) = split(&bytes);
        assert!(head.contains(r#"WholeExtent="0 6 0 0 0 9""#));
        assert!(head.contains(r#"<Piece Extent="0 6 0 0 0 9">"#));
        let offset = |name: &str| -> usize {
            let line = head
                .lines()
                .find(|l| attr(l, "Name") == Some(name))
                .unwrap();
            attr(line, "offset").unwrap().parse().unwrap()
        };
        assert_eq!(read_block(data, offset("x")), node_coordinates(&grid)[0]);
        assert_eq!(read_block(data, offset("x")).len(), 7);
        assert_eq!(read_block(data, offset("y")), vec![0.0]);
        let z = read_block(data, offset("z"));
        assert_eq!(z.len(), 10);
        assert_eq!(z[0], -0.2);
        assert_eq!(z[9], grid.yf(9));
        fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn bad_input_is_refused_and_writes_nothing() {
        let dir = scratch("bad");
        let grid = Grid::new(Geometry::Planar, 3, 2, (0.0, 1.0), (0.0, 1.0));
        let v = vec![0.0; 6];
        let path = dir.join("bad.vtr");
        let one = |name, components, values| CellArray {
            name,
            components,
            values,
        };
        let cases: Vec<(f64, Vec<CellArray>)> = vec![
            (0.0, vec![one("p", 3, &v)]),
            (0.0, vec![one("p", 0, &v[..0])]),
            (0.0, vec![one("", 1, &v)]),
            (0.0, vec![one("p", 1, &v), one("p", 1, &v)]),
            (f64::NAN, vec![one("p", 1, &v)]),
        ];
        for (t, arrays) in cases {
            let e = write_vtr(&path, &grid, t, &arrays).unwrap_err();
            assert_eq!(e.kind(), io::ErrorKind::InvalidInput);
            assert!(e.to_string().contains("bad.vtr"), "{e}");
        }
        assert_eq!(fs::read_dir(&dir).unwrap().count(), 0);
        fs::remove_dir_all(&dir).unwrap();
    }

    /// Arrays handed over in uneven pieces give the file the whole arrays give, byte for byte,
    /// in every format; a source short of values fails and leaves no file.
    #[test]
    fn arrays_in_pieces_write_the_same_file() {
        let dir = scratch("pieces");
        let grid = Grid::new_3d([5, 4, 3], (0.0, 1.0), (0.0, 0.8), (-0.3, 0.3));
        let n = grid.cells();
        let (p, u, _) = sample(&grid);
        // Longer than a zlib block, so that the compressed form has several.
        let big = Grid::new_3d([40, 30, 20], (0.0, 1.0), (0.0, 1.0), (0.0, 1.0));
        let (q, _, _) = sample(&big);
        for (grid, arrays) in [
            (
                &grid,
                vec![
                    CellArray {
                        name: "p",
                        components: 1,
                        values: &p[..n],
                    },
                    CellArray {
                        name: "velocity",
                        components: 3,
                        values: &u[..3 * n],
                    },
                ],
            ),
            (
                &big,
                vec![CellArray {
                    name: "q",
                    components: 1,
                    values: &q,
                }],
            ),
        ] {
            let pieces: Vec<Box<Produce>> = arrays
                .iter()
                .map(|a| {
                    let v = a.values;
                    Box::new(move |sink: &mut dyn FnMut(&[f64]) -> io::Result<()>| {
                        let (mut at, mut len) = (0, 1);
                        while at < v.len() {
                            let end = (at + len).min(v.len());
                            sink(&v[at..end])?;
                            (at, len) = (end, 2 * len + 1);
                        }
                        Ok(())
                    }) as Box<Produce>
                })
                .collect();
            let sources = sources(&arrays, &pieces);
            for precision in [VtkPrecision::Float64, VtkPrecision::Float32] {
                for compression in [VtkCompression::None, VtkCompression::Zlib] {
                    for point_data in [false, true] {
                        let format = VtrFormat {
                            precision,
                            compression,
                            point_data,
                        };
                        let (a, b) = (dir.join("a.vtr"), dir.join("b.vtr"));
                        let notes = [("units", "SI")];
                        write_vtr_with(&a, grid, 0.5, &arrays, &format, &notes).unwrap();
                        let nodes = node_coordinates(grid);
                        write_rectilinear_from(&b, &nodes, 0.5, &sources, &format, &notes).unwrap();
                        assert!(fs::read(&a).unwrap() == fs::read(&b).unwrap(), "{format:?}");
                    }
                }
            }
        }
        let short = |sink: &mut dyn FnMut(&[f64]) -> io::Result<()>| sink(&p[..n - 1]);
        let source = CellSource {
            name: "p",
            components: 1,
            values: &short,
        };
        let path = dir.join("short.vtr");
        let nodes = node_coordinates(&grid);
        let e = write_rectilinear_from(&path, &nodes, 0.0, &[source], &VtrFormat::default(), &[])
            .unwrap_err();
        assert_eq!(e.kind(), io::ErrorKind::InvalidInput);
        assert!(e.to_string().contains("has 59 values, expected 60"), "{e}");
        assert!(!path.exists() && !temporary_path(&path).unwrap().exists());
        fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn names_are_escaped() {
        assert_eq!(xml_attr(r#"a<b>&"c'"#), "a&lt;b&gt;&amp;&quot;c&apos;");
    }

    #[test]
    fn pvd_lists_entries_in_order_with_exact_times() {
        let dir = scratch("pvd");
        let path = dir.join("run.pvd");
        let mut pvd = PvdCollection::new(&path);
        let times = [0.0, 0.1, 1.0 / 3.0, 2.5e-7, 12345.678901234567];
        for (k, t) in times.iter().enumerate() {
            pvd.add(*t, &format!("run_{k:06}.vtr")).unwrap();
            // The file on disk always lists everything added so far.
            let text = fs::read_to_string(&path).unwrap();
            assert_eq!(text.matches("<DataSet").count(), k + 1);
        }
        assert!(pvd.add(f64::INFINITY, "x.vtr").is_err());
        assert_eq!(pvd.entries().len(), times.len());
        let text = fs::read_to_string(&path).unwrap();
        assert!(text.starts_with("<?xml version=\"1.0\"?>\n<VTKFile type=\"Collection\""));
        assert!(text.ends_with("  </Collection>\n</VTKFile>\n"));
        let sets: Vec<&str> = text.lines().filter(|l| l.contains("<DataSet")).collect();
        assert_eq!(sets.len(), times.len());
        for (k, (line, t)) in sets.iter().zip(&times).enumerate() {
            let written = attr(line, "timestep").unwrap();
            assert_eq!(written, format!("{t:e}"));
            assert_eq!(written.parse::<f64>().unwrap().to_bits(), t.to_bits());
            assert_eq!(attr(line, "file").unwrap(), format!("run_{k:06}.vtr"));
            assert_eq!(pvd.entries()[k], (*t, format!("run_{k:06}.vtr")));
        }
        let names: Vec<_> = fs::read_dir(&dir)
            .unwrap()
            .map(|e| e.unwrap().file_name())
            .collect();
        assert_eq!(names, vec![std::ffi::OsString::from("run.pvd")]);
        fs::remove_dir_all(&dir).unwrap();
    }
}
