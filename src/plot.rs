//! `efsi plot DIR`: a run looked at without ParaView — PNGs of the probe time series
//! (`probes.png`, one panel per column) and of a field at an output time
//! (`<field>_t<time>.png`, a colour map with the solid's φ = ½ contour drawn over it in red;
//! in a run of several bodies, which writes the array `body_id`, each body's contour in a
//! colour of its own: [`BODY_COLOURS`], body 1 red).
//!
//! **What is drawn by default:** the velocity magnitude with arrows of the velocity (white, on
//! a coarse lattice, the longest as long as the lattice's spacing), the solid's φ = ½ contour
//! over it when there is a solid — what a person looks at a flow for. The colour range is the
//! 1st to 99th percentile of the field's finite values (a corner singularity of the pressure,
//! a few interface cells, do not make the rest one colour); values beyond it take the end
//! colours, and the colour bar says so (`≤`, `≥`). Axis and colour-bar labels are plain
//! decimals where they fit in a few digits (`0.02`, `1500`), scientific otherwise.
//!
//! Text uses a TrueType font found on the system (DejaVu Sans or Liberation Sans); without
//! one the plots are drawn without text and a warning says so.

use efsi_run::output::read::{VtrData, read_pvd, read_vtr};
use efsi_run::output::slice::axis_name;
use plotters::prelude::*;
use std::path::{Path, PathBuf};
use std::sync::OnceLock;

/// The font family plot text uses.
const FAMILY: &str = "sans-serif";

/// Width of `probes.png`; each row of two panels is [`PANEL_HEIGHT`] high.
pub const PROBES_WIDTH: u32 = 1200;
/// Height of one row of panels in `probes.png`.
pub const PANEL_HEIGHT: u32 = 300;
/// Size of a field plot.
pub const FIELD_SIZE: (u32, u32) = (900, 900);

/// Register a system TrueType font for plot text, once; `false` if none was found.
fn font() -> bool {
    static FONT: OnceLock<bool> = OnceLock::new();
    *FONT.get_or_init(|| {
        for c in [
            "/usr/share/fonts/truetype/dejavu/DejaVuSans.ttf",
            "/usr/share/fonts/dejavu/DejaVuSans.ttf",
            "/usr/share/fonts/TTF/DejaVuSans.ttf",
            "/usr/share/fonts/truetype/liberation/LiberationSans-Regular.ttf",
        ] {
            if let Ok(bytes) = std::fs::read(c) {
                let bytes: &'static [u8] = Box::leak(bytes.into_boxed_slice());
                if plotters::style::register_font(FAMILY, FontStyle::Normal, bytes).is_ok() {
                    return true;
                }
            }
        }
        false
    })
}

/// What `efsi plot` draws besides the probes.
pub struct FieldRequest {
    /// The cell array (default: `velocity`, its magnitude with arrows).
    pub field: Option<String>,
    /// Its component (default: see [`scalar`]).
    pub component: Option<usize>,
    /// The output time (default: the last); the nearest written one is used.
    pub time: Option<f64>,
    /// The plane drawn of a three-dimensional run (which has to name one).
    pub slice: Option<SliceAt>,
}

/// A plane of a three-dimensional run to draw (`--slice z=0.5`): normal to axis `axis` (0, 1,
/// 2 for x, y, z) at `at`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SliceAt {
    /// The axis the plane is normal to.
    pub axis: usize,
    /// Its position along that axis.
    pub at: f64,
}

impl SliceAt {
    /// `x=V`, `y=V` or `z=V` (the command line's `--slice`).
    pub fn parse(s: &str) -> Result<SliceAt, String> {
        let how = "expected AXIS=POSITION with AXIS x, y or z, e.g. z=0.5";
        let (axis, at) = s.split_once('=').ok_or_else(|| format!("`{s}`: {how}"))?;
        let axis = match axis.trim() {
            "x" | "X" => 0,
            "y" | "Y" => 1,
            "z" | "Z" => 2,
            a => return Err(format!("`{a}` is not an axis: {how}")),
        };
        let at: f64 = at
            .trim()
            .parse()
            .map_err(|e| format!("`{at}` is not a position ({e}): {how}"))?;
        if !at.is_finite() {
            return Err(format!("`{at}` is not a finite position: {how}"));
        }
        Ok(SliceAt { axis, at })
    }
}

impl std::fmt::Display for SliceAt {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}={}", axis_name(self.axis), self.at)
    }
}

/// Draw the plots of the run in `dir` into `out`; returns the files written.
pub fn plot(dir: &Path, out: &Path, request: &FieldRequest) -> Result<Vec<PathBuf>, String> {
    if let Some(t) = request.time
        && !t.is_finite()
    {
        return Err(format!(
            "--time must be a finite time (the nearest output time is plotted), got {t}"
        ));
    }
    std::fs::create_dir_all(out).map_err(|e| format!("{}: {e}", out.display()))?;
    if !font() {
        eprintln!(
            "warning: no TrueType font found (install fonts-dejavu-core): plots without text"
        );
    }
    // The field first: a request it cannot serve writes nothing.
    let field = field_to_plot(dir, out, request)?;
    let mut written = Vec::new();
    let probes = dir.join("probes.csv");
    if probes.is_file() {
        let p = out.join("probes.png");
        plot_probes(&probes, &p)?;
        written.push(p);
    }
    if let Some((data, name, p)) = field {
        plot_field(&data, &name, request.component, request.slice, &p)?;
        written.push(p);
    }
    if written.is_empty() {
        return Err(format!(
            "{}: neither probes.csv nor fields.pvd: not an efsi output folder",
            dir.display()
        ));
    }
    Ok(written)
}

/// The field plot `request` asks for of the run in `dir`: the file's data (the plane of a
/// three-dimensional one), the array's name and the PNG it goes to in `out`; None without VTK
/// output (and no field or time asked for).
fn field_to_plot(
    dir: &Path,
    out: &Path,
    request: &FieldRequest,
) -> Result<Option<(VtrData, String, PathBuf)>, String> {
    let pvd = dir.join("fields.pvd");
    if !pvd.is_file() {
        if request.field.is_some() || request.time.is_some() || request.slice.is_some() {
            return Err(format!(
                "{}: no VTK output to plot a field from (the scene writes none without output.vtk_every)",
                pvd.display()
            ));
        }
        return Ok(None);
    }
    let entries = read_pvd(&pvd).map_err(|e| e.to_string())?;
    let Some((t, file)) = (match request.time {
        None => entries.last().cloned(),
        Some(want) => entries
            .iter()
            .min_by(|a, b| (a.0 - want).abs().total_cmp(&(b.0 - want).abs()))
            .cloned(),
    }) else {
        return Err(format!("{}: no output times", pvd.display()));
    };
    let data = read_vtr(&file).map_err(|e| e.to_string())?;
    let data = match request.slice {
        Some(s) => data
            .plane(s.axis, s.at)
            .map_err(|e| format!("--slice {s}: {}: {e}", file.display()))?,
        None if data.is_3d() => return Err(three_dimensional(&file, &data)),
        None => data,
    };
    let name = request.field.clone().unwrap_or_else(|| "velocity".into());
    let plane = request
        .slice
        .map_or_else(String::new, |s| format!("_{}{}", axis_name(s.axis), s.at));
    let png = format!("{name}_t{}{plane}.png", efsi_run::run::time_label(t));
    Ok(Some((data, name, out.join(png))))
}

/// Why a three-dimensional file is not drawn without a plane, and how to choose one.
fn three_dimensional(file: &Path, data: &VtrData) -> String {
    let [nx, ny, nz] = data.cells3();
    let z = &data.coordinates[2];
    let (lo, hi) = (z[0], z[z.len() - 1]);
    format!(
        "{} is three-dimensional ({nx}×{ny}×{nz} cells): a plot is of a plane; choose one with \
         --slice x=…, y=… or z=… (e.g. --slice z={}, the middle of z ∈ [{lo}, {hi}])",
        file.display(),
        0.5 * (lo + hi)
    )
}

/// `probes.csv` as column names and columns (the first is `t`).
fn read_probes(path: &Path) -> Result<(Vec<String>, Vec<Vec<f64>>), String> {
    let text =
        efsi_run::output::read::read_regular_text(path, efsi_run::output::read::MAX_PROBES_BYTES)
            .map_err(|e| format!("{}: {e}", path.display()))?;
    let mut lines = text.lines();
    let header: Vec<String> = lines
        .next()
        .unwrap_or_default()
        .split(',')
        .map(str::to_string)
        .collect();
    let mut cols = vec![Vec::new(); header.len()];
    for (k, l) in lines.enumerate() {
        for (c, v) in l.split(',').enumerate().take(header.len()) {
            cols[c].push(
                v.parse::<f64>()
                    .map_err(|e| format!("{}: line {}: {e}", path.display(), k + 2))?,
            );
        }
    }
    Ok((header, cols))
}

fn plot_probes(csv: &Path, png: &Path) -> Result<(), String> {
    let (names, cols) = read_probes(csv)?;
    if names.len() < 2 || cols[0].is_empty() {
        return Err(format!("{}: no probe values to plot", csv.display()));
    }
    let panels = names.len() - 1;
    let rows = panels.div_ceil(2) as u32;
    let text = font();
    let draw = || -> Result<(), Box<dyn std::error::Error>> {
        let root = BitMapBackend::new(png, (PROBES_WIDTH, rows * PANEL_HEIGHT)).into_drawing_area();
        root.fill(&WHITE)?;
        let areas = root.split_evenly((rows as usize, 2));
        for (k, area) in areas.iter().enumerate().take(panels) {
            let (t, y) = (&cols[0], &cols[k + 1]);
            let pts: Vec<(f64, f64)> = t
                .iter()
                .zip(y)
                .filter(|(a, b)| a.is_finite() && b.is_finite())
                .map(|(a, b)| (*a, *b))
                .collect();
            let (x0, x1) = range(pts.iter().map(|p| p.0));
            let (y0, y1) = range(pts.iter().map(|p| p.1));
            let mut b = ChartBuilder::on(area);
            b.margin(10);
            if text {
                b.caption(&names[k + 1], (FAMILY, 18))
                    .x_label_area_size(30)
                    .y_label_area_size(70);
            }
            let mut chart = b.build_cartesian_2d(x0..x1, y0..y1)?;
            let mut mesh = chart.configure_mesh();
            let (fx, fy) = (|v: &f64| tick(*v, x1 - x0), |v: &f64| tick(*v, y1 - y0));
            if text {
                mesh.x_desc("t")
                    .label_style((FAMILY, 12))
                    .x_label_formatter(&fx)
                    .y_label_formatter(&fy);
            }
            mesh.draw()?;
            chart.draw_series(LineSeries::new(pts, BLUE.stroke_width(2)))?;
        }
        root.present()?;
        Ok(())
    };
    draw().map_err(|e| format!("{}: {e}", png.display()))
}

/// The `(min, max)` of finite values, widened by 5 % (and around a constant).
fn range(values: impl Iterator<Item = f64>) -> (f64, f64) {
    let (lo, hi) = values
        .filter(|v| v.is_finite())
        .fold((f64::MAX, f64::MIN), |(a, b), v| (a.min(v), b.max(v)));
    if lo > hi {
        return (0.0, 1.0);
    }
    let w = (hi - lo).max(1e-12 * hi.abs().max(1e-300));
    (lo - 0.05 * w, hi + 0.05 * w)
}

/// A label for the value `v` on an axis spanning `span`: a plain decimal with the digits the
/// span needs (`0.02`, `1500`, `-0.375`) when that takes at most 8 characters, else scientific
/// with 3 significant digits (`2.50e-7`).
pub fn tick(v: f64, span: f64) -> String {
    if !v.is_finite() {
        return v.to_string();
    }
    let span = if span.is_finite() && span > 0.0 {
        span
    } else {
        v.abs().max(1e-300)
    };
    // Enough decimals to tell ticks a tenth of the span apart.
    let decimals = (-(span / 10.0).log10().floor()).max(0.0) as usize;
    if decimals <= 6 {
        let text = format!("{v:.decimals$}");
        let text = if text.contains('.') {
            text.trim_end_matches('0').trim_end_matches('.').to_string()
        } else {
            text
        };
        let text = if text == "-0" { "0".to_string() } else { text };
        if text.len() <= 8 {
            return text;
        }
    }
    format!("{v:.2e}")
}

/// The `p`-quantile (`p` in [0, 1], nearest rank) of the finite values; None if there are none.
pub fn percentile(values: &[f64], p: f64) -> Option<f64> {
    let mut v: Vec<f64> = values.iter().copied().filter(|x| x.is_finite()).collect();
    if v.is_empty() {
        return None;
    }
    v.sort_by(f64::total_cmp);
    let k = ((p * (v.len() - 1) as f64).round() as usize).min(v.len() - 1);
    Some(v[k])
}

/// The colour range of a field plot: the 1st and 99th percentiles of its finite values (from 0
/// for a field that is never negative, such as a magnitude, when the 1st percentile is within
/// 5 % of the range from it), the full range if those coincide (e.g. a field that is one value
/// almost everywhere); (0, 1) without finite values.
pub fn colour_range(values: &[f64]) -> (f64, f64) {
    let (Some(lo), Some(hi)) = (percentile(values, 0.01), percentile(values, 0.99)) else {
        return (0.0, 1.0);
    };
    if hi > lo {
        let never_negative = percentile(values, 0.0).is_some_and(|m| m >= 0.0);
        if never_negative && lo <= 0.05 * (hi - lo) {
            return (0.0, hi);
        }
        return (lo, hi);
    }
    let (a, b) = (percentile(values, 0.0), percentile(values, 1.0));
    match (a, b) {
        (Some(a), Some(b)) if b > a => (a, b),
        _ => (lo, lo + 1.0),
    }
}

/// The scalar plotted for a cell array: component `component` if given, else the value of a
/// scalar, the magnitude of a vector, the first (XX) component of a tensor.
pub fn scalar(values: &[f64], components: usize, component: Option<usize>) -> Vec<f64> {
    values
        .chunks_exact(components)
        .map(|c| match component {
            Some(k) => c[k],
            None if components == 3 => c.iter().map(|v| v * v).sum::<f64>().sqrt(),
            None => c[0],
        })
        .collect()
}

/// A perceptually ordered colour map (viridis, interpolated from 5 stops), `s` in [0, 1].
fn colour(s: f64) -> RGBColor {
    const STOPS: [(f64, f64, f64); 5] = [
        (68.0, 1.0, 84.0),
        (59.0, 82.0, 139.0),
        (33.0, 145.0, 140.0),
        (94.0, 201.0, 98.0),
        (253.0, 231.0, 37.0),
    ];
    let s = if s.is_finite() {
        s.clamp(0.0, 1.0)
    } else {
        0.0
    } * 4.0;
    let k = (s.floor() as usize).min(3);
    let f = s - k as f64;
    let (a, b) = (STOPS[k], STOPS[k + 1]);
    let l = |x: f64, y: f64| (x + f * (y - x)).round() as u8;
    RGBColor(l(a.0, b.0), l(a.1, b.1), l(a.2, b.2))
}

/// A line segment from one point to another.
type Segment = ((f64, f64), (f64, f64));

/// The segments of the `level` contour of the cell-centred `values` (`n1 × n2`, first index
/// fastest; centres at `c1`, `c2`), by marching squares over the squares between centres.
pub fn contour(
    values: &[f64],
    (n1, n2): (usize, usize),
    c1: &[f64],
    c2: &[f64],
    level: f64,
) -> Vec<Segment> {
    let mut segments = Vec::new();
    let at = |i: usize, j: usize| values[j * n1 + i] - level;
    for j in 0..n2.saturating_sub(1) {
        for i in 0..n1.saturating_sub(1) {
            // Corners counter-clockwise: (i, j), (i+1, j), (i+1, j+1), (i, j+1).
            let corners = [(i, j), (i + 1, j), (i + 1, j + 1), (i, j + 1)];
            let v: Vec<f64> = corners.iter().map(|&(a, b)| at(a, b)).collect();
            let mut cuts = Vec::with_capacity(4);
            for e in 0..4 {
                let (a, b) = (e, (e + 1) % 4);
                if (v[a] < 0.0) != (v[b] < 0.0) {
                    let f = v[a] / (v[a] - v[b]);
                    let (pa, pb) = (corners[a], corners[b]);
                    let x = c1[pa.0] + f * (c1[pb.0] - c1[pa.0]);
                    let y = c2[pa.1] + f * (c2[pb.1] - c2[pa.1]);
                    cuts.push((x, y));
                }
            }
            match cuts.len() {
                2 => segments.push((cuts[0], cuts[1])),
                // A saddle: pair the cuts by the centre's sign.
                4 => {
                    let centre = v.iter().sum::<f64>() / 4.0;
                    if (centre < 0.0) == (v[0] < 0.0) {
                        segments.push((cuts[0], cuts[3]));
                        segments.push((cuts[1], cuts[2]));
                    } else {
                        segments.push((cuts[0], cuts[1]));
                        segments.push((cuts[2], cuts[3]));
                    }
                }
                _ => {}
            }
        }
    }
    segments
}

/// The colour of the solid's φ = ½ contour.
const CONTOUR: RGBColor = RGBColor(230, 30, 30);

/// Arrows across the longer side of a field plot.
const ARROWS_ACROSS: usize = 24;

/// Arrows of the cell vectors `v` (3 components a cell; `n1 × n2` cells between the edges `e1`,
/// `e2`; in-plane components `(c1, c2)`: 0 and 2 for an axisymmetric r–z slice, 0 and 1 for a
/// planar run, the plane's axes for a slice of a three-dimensional one) on a lattice
/// of about [`ARROWS_ACROSS`] along the longer side, each the polyline shaft and head; the
/// longest is 0.9 of the lattice spacing. None where the field is zero or not finite.
pub fn arrows(
    v: &[f64],
    (n1, n2): (usize, usize),
    e1: &[f64],
    e2: &[f64],
    (c1, c2): (usize, usize),
) -> Vec<[(f64, f64); 5]> {
    let (w, h) = (e1[n1] - e1[0], e2[n2] - e2[0]);
    let spacing = w.max(h) / ARROWS_ACROSS as f64;
    let (m1, m2) = (
        ((w / spacing).round() as usize).max(1),
        ((h / spacing).round() as usize).max(1),
    );
    let cell = |e: &[f64], n: usize, x: f64| e.partition_point(|&a| a <= x).clamp(1, n) - 1;
    let mut picked = Vec::new();
    for b in 0..m2 {
        for a in 0..m1 {
            let x = e1[0] + (a as f64 + 0.5) * w / m1 as f64;
            let y = e2[0] + (b as f64 + 0.5) * h / m2 as f64;
            let k = cell(e2, n2, y) * n1 + cell(e1, n1, x);
            let (u, vv) = (v[3 * k + c1], v[3 * k + c2]);
            if u.is_finite() && vv.is_finite() {
                picked.push((x, y, u, vv));
            }
        }
    }
    let longest = picked.iter().fold(0.0_f64, |m, p| m.max(p.2.hypot(p.3)));
    if longest <= 0.0 {
        return Vec::new();
    }
    let scale = 0.9 * spacing / longest;
    picked
        .into_iter()
        .filter(|p| p.2 != 0.0 || p.3 != 0.0)
        .map(|(x, y, u, vv)| {
            let (dx, dy) = (u * scale, vv * scale);
            let (tx, ty) = (x + 0.5 * dx, y + 0.5 * dy);
            let (bx, by) = (x - 0.5 * dx, y - 0.5 * dy);
            // The head: two barbs at ±25° back from the tip, a third of the arrow long.
            let (c, s) = (0.906_307_787, 0.422_618_262);
            let (hx, hy) = (-dx / 3.0, -dy / 3.0);
            let left = (tx + c * hx - s * hy, ty + s * hx + c * hy);
            let right = (tx + c * hx + s * hy, ty - s * hx + c * hy);
            [(bx, by), (tx, ty), left, (tx, ty), right]
        })
        .collect()
}

/// The cell array `name` of `data` and the component asked for, checked.
fn field_array<'a>(
    data: &'a VtrData,
    name: &str,
    component: Option<usize>,
) -> Result<&'a efsi_run::output::read::ReadArray, String> {
    let array = data.cell(name).ok_or_else(|| {
        format!(
            "no field `{name}` in the VTK output; it has: {}",
            data.cells
                .iter()
                .map(|a| a.name.as_str())
                .collect::<Vec<_>>()
                .join(", ")
        )
    })?;
    if let Some(k) = component
        && k >= array.components
    {
        return Err(format!(
            "field `{name}` has {} component(s); --component {k} is out of range",
            array.components
        ));
    }
    Ok(array)
}

/// The plotted quantity's label: the component, the magnitude of a vector, or the name.
fn field_label(name: &str, components: usize, component: Option<usize>) -> String {
    match component {
        Some(k) => format!("{name}[{k}]"),
        None if components == 3 => format!("|{name}|"),
        None if components > 1 => format!("{name}[0]"),
        None => name.to_string(),
    }
}

/// The colours of the bodies' interfaces in a run of several bodies, body 1 first (then
/// again from the first for more bodies than colours).
pub const BODY_COLOURS: [RGBColor; 6] = [
    CONTOUR,
    RGBColor(255, 150, 0),
    RGBColor(210, 0, 210),
    RGBColor(0, 0, 0),
    RGBColor(0, 200, 220),
    RGBColor(130, 230, 0),
];

/// The segments of the solid's interface (the `solid_fraction` = ½ contour) over the cells
/// with edges `e1`, `e2`, when the output has a solid fraction, each group with its colour:
/// one group in [`CONTOUR`]; in a run of several bodies (the array `body_id`), one group per
/// body ([`body_contours`]) in its colour of [`BODY_COLOURS`].
fn interface_segments(
    data: &VtrData,
    e1: &[f64],
    e2: &[f64],
) -> Option<Vec<(RGBColor, Vec<Segment>)>> {
    let phi = data.cell("solid_fraction")?;
    let centre = |e: &[f64]| {
        e.windows(2)
            .map(|p| 0.5 * (p[0] + p[1]))
            .collect::<Vec<_>>()
    };
    let shape = (e1.len() - 1, e2.len() - 1);
    let (c1, c2) = (centre(e1), centre(e2));
    Some(match data.cell("body_id") {
        Some(ids) => body_contours(&phi.values, &ids.values, shape, &c1, &c2)
            .into_iter()
            .map(|(k, s)| (BODY_COLOURS[(k - 1) % BODY_COLOURS.len()], s))
            .collect(),
        None => vec![(CONTOUR, contour(&phi.values, shape, &c1, &c2, 0.5))],
    })
}

/// Each body's interface in a run of several bodies: for body `k` (1, 2, …, the values of
/// `ids`, the `body_id` array), the ½ contour of the solid fraction `phi` kept in the cells
/// `ids` gives to `k` (0 elsewhere), as `(k, segments)` in the order of `k`.
pub fn body_contours(
    phi: &[f64],
    ids: &[f64],
    shape: (usize, usize),
    c1: &[f64],
    c2: &[f64],
) -> Vec<(usize, Vec<Segment>)> {
    let most = ids.iter().fold(0.0f64, |m, v| m.max(*v)) as usize;
    (1..=most)
        .map(|k| {
            let own: Vec<f64> = phi
                .iter()
                .zip(ids)
                .map(|(f, id)| if *id == k as f64 { *f } else { 0.0 })
                .collect();
            (k, contour(&own, shape, c1, c2, 0.5))
        })
        .collect()
}

/// The plot window `(x0, x1, y0, y1)` around edges `e1`, `e2` with the domain's aspect ratio.
fn square_window(e1: &[f64], e2: &[f64]) -> (f64, f64, f64, f64) {
    let (n1, n2) = (e1.len() - 1, e2.len() - 1);
    let (w, h) = (e1[n1] - e1[0], e2[n2] - e2[0]);
    if w >= h {
        let pad = 0.5 * (w - h);
        (e1[0], e1[n1], e2[0] - pad, e2[n2] + pad)
    } else {
        let pad = 0.5 * (h - w);
        (e1[0] - pad, e1[n1] + pad, e2[0], e2[n2])
    }
}

/// The axes of a field plot, named `axes` and ticked for the window's spans, without a grid;
/// without text when no font is available.
fn draw_axes(
    chart: &mut ChartContext<
        '_,
        BitMapBackend<'_>,
        Cartesian2d<plotters::coord::types::RangedCoordf64, plotters::coord::types::RangedCoordf64>,
    >,
    axes: (&str, &str),
    (sx, sy): (f64, f64),
    text: bool,
) -> Result<(), Box<dyn std::error::Error>> {
    let mut mesh = chart.configure_mesh();
    mesh.disable_mesh();
    let (fx, fy) = (move |v: &f64| tick(*v, sx), move |v: &f64| tick(*v, sy));
    if text {
        mesh.x_desc(axes.0)
            .y_desc(axes.1)
            .label_style((FAMILY, 13))
            .x_label_formatter(&fx)
            .y_label_formatter(&fy);
    }
    mesh.draw()?;
    Ok(())
}

/// The colour bar of the range `lo..hi` top to bottom, its ends labelled (`≥`/`≤` when values
/// lie beyond them) when `text`.
fn draw_colour_bar(
    bar: &DrawingArea<BitMapBackend<'_>, plotters::coord::Shift>,
    (lo, hi): (f64, f64),
    (below, above): (bool, bool),
    text: bool,
) -> Result<(), Box<dyn std::error::Error>> {
    let span = hi - lo;
    let bar = bar.margin(60, 60, 20, 40);
    let (bw, bh) = bar.dim_in_pixel();
    for py in 0..bh {
        let s = 1.0 - py as f64 / (bh.max(2) - 1) as f64;
        bar.draw(&Rectangle::new(
            [(0, py as i32), (bw as i32 / 2, py as i32 + 1)],
            colour(s).filled(),
        ))?;
    }
    if text {
        let style = (FAMILY, 13).into_font().color(&BLACK);
        let top = if above { "≥ " } else { "" };
        let bottom = if below { "≤ " } else { "" };
        // One digit more than an axis tick: the ends are values, not steps.
        bar.draw_text(&format!("{top}{}", tick(hi, span / 10.0)), &style, (0, -18))?;
        bar.draw_text(
            &format!("{bottom}{}", tick(lo, span / 10.0)),
            &style,
            (0, bh as i32 + 4),
        )?;
    }
    Ok(())
}

/// A field plot's caption: the plotted quantity's `label`, its direction when drawn with
/// `arrows`, the plane of a `slice`, the `time`.
fn caption(label: &str, arrows: bool, slice: Option<SliceAt>, time: f64) -> String {
    let and_arrows = if arrows { " and its direction" } else { "" };
    let time = efsi_run::run::time_label(time);
    let on = slice.map_or_else(String::new, |s| {
        format!(" on {} = {}", axis_name(s.axis), s.at)
    });
    format!("{label}{and_arrows}{on} at t = {time}")
}

/// Draw the cell array `name` (its `component`) of the two-dimensional `data` — a planar or
/// axisymmetric file, or the plane `slice` of a three-dimensional one — into `png`.
fn plot_field(
    data: &VtrData,
    name: &str,
    component: Option<usize>,
    slice: Option<SliceAt>,
    png: &Path,
) -> Result<(), String> {
    let array = field_array(data, name, component)?;
    let values = scalar(&array.values, array.components, component);
    let (n1, n2) = data.shape();
    let (a1, a2) = data.plane_axes();
    let (e1, e2) = (&data.coordinates[a1], &data.coordinates[a2]);
    let axisymmetric = slice.is_none() && (a1, a2) == (0, 2);
    let axes = if axisymmetric {
        ("r", "z")
    } else {
        (axis_name(a1), axis_name(a2))
    };
    let (lo, hi) = colour_range(&values);
    let span = hi - lo;
    let beyond = (
        values.iter().any(|&v| v < lo),
        values.iter().any(|&v| v > hi),
    );
    // Arrows of a vector field plotted as its magnitude.
    let arrows = (component.is_none() && array.components == 3)
        .then(|| arrows(&array.values, (n1, n2), e1, e2, (a1, a2)));
    let interface = interface_segments(data, e1, e2);
    let text = font();
    let label = field_label(name, array.components, component);
    let caption = caption(&label, arrows.is_some(), slice, data.time);
    let draw = || -> Result<(), Box<dyn std::error::Error>> {
        let root = BitMapBackend::new(png, FIELD_SIZE).into_drawing_area();
        root.fill(&WHITE)?;
        let (main, bar) = root.split_horizontally(FIELD_SIZE.0 - 110);
        let (x0, x1, y0, y1) = square_window(e1, e2);
        let mut b = ChartBuilder::on(&main);
        b.margin(12);
        if text {
            b.caption(&caption, (FAMILY, 22))
                .x_label_area_size(40)
                .y_label_area_size(70);
        }
        let mut chart = b.build_cartesian_2d(x0..x1, y0..y1)?;
        draw_axes(&mut chart, axes, (x1 - x0, y1 - y0), text)?;
        chart.draw_series((0..n2).flat_map(|j| {
            let values = &values;
            (0..n1).map(move |i| {
                let c = colour((values[j * n1 + i] - lo) / span);
                Rectangle::new([(e1[i], e2[j]), (e1[i + 1], e2[j + 1])], c.filled())
            })
        }))?;
        for (colour, segments) in interface.iter().flatten() {
            chart.draw_series(
                segments
                    .iter()
                    .map(|&(a, b)| PathElement::new(vec![a, b], colour.stroke_width(3))),
            )?;
        }
        if let Some(arrows) = &arrows {
            chart.draw_series(
                arrows
                    .iter()
                    .map(|a| PathElement::new(a.to_vec(), WHITE.stroke_width(1))),
            )?;
        }
        draw_colour_bar(&bar, (lo, hi), beyond, text)?;
        root.present()?;
        Ok(())
    };
    draw().map_err(|e| format!("{}: {e}", png.display()))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Two bodies side by side: each body's contour lies around its own cells only.
    #[test]
    fn each_body_has_its_own_contour() {
        // 6 × 3 cells: body 1 in column 1, body 2 in column 4 (φ = 1), fluid elsewhere.
        let (n1, n2) = (6, 3);
        let mut phi = vec![0.0; n1 * n2];
        let mut ids = vec![0.0; n1 * n2];
        for j in 0..n2 {
            for (i, k) in [(1, 1.0), (4, 2.0)] {
                phi[j * n1 + i] = 1.0;
                ids[j * n1 + i] = k;
            }
        }
        let c1: Vec<f64> = (0..n1).map(|i| i as f64 + 0.5).collect();
        let c2: Vec<f64> = (0..n2).map(|j| j as f64 + 0.5).collect();
        let got = body_contours(&phi, &ids, (n1, n2), &c1, &c2);
        assert_eq!(got.iter().map(|g| g.0).collect::<Vec<_>>(), [1, 2]);
        for (k, segments) in &got {
            let x = if *k == 1 { 1.5 } else { 4.5 };
            assert!(!segments.is_empty());
            for ((xa, _), (xb, _)) in segments {
                // Halfway between the body's centres and its neighbours'.
                assert!(
                    (xa - x).abs() <= 0.5 && (xb - x).abs() <= 0.5,
                    "{k}: {segments:?}"
                );
            }
        }
        // The whole φ's contour is both bodies' together.
        let all = contour(&phi, (n1, n2), &c1, &c2, 0.5).len();
        assert_eq!(got[0].1.len() + got[1].1.len(), all);
    }

    #[test]
    fn ticks_are_plain_numbers_where_they_fit() {
        assert_eq!(tick(0.02, 0.1), "0.02");
        assert_eq!(tick(0.020000000000000004, 0.1), "0.02");
        assert_eq!(tick(1500.0, 5000.0), "1500");
        assert_eq!(tick(-0.25, 0.5), "-0.25");
        assert_eq!(tick(0.0, 0.5), "0");
        assert_eq!(tick(-1e-17, 0.5), "0");
        assert_eq!(tick(0.045, 0.09), "0.045");
        assert_eq!(tick(2.5e-7, 1e-6), "2.50e-7");
        assert_eq!(tick(3.0e9, 1e10), "3.00e9");
    }

    #[test]
    fn the_colour_range_is_the_1st_to_99th_percentile() {
        // 1000 values in [0, 1) and two spikes, as a lid's corners give the pressure.
        let mut v: Vec<f64> = (0..1000).map(|k| k as f64 / 1000.0).collect();
        v.extend([1e6, -1e6, f64::NAN]);
        let (lo, hi) = colour_range(&v);
        assert!(
            (0.0..0.02).contains(&lo) && (0.97..1.0).contains(&hi),
            "{lo} {hi}"
        );
        // A magnitude starts at 0.
        let speeds: Vec<f64> = (0..1000).map(|k| 0.001 + k as f64 / 1000.0).collect();
        assert_eq!(colour_range(&speeds).0, 0.0);
        // One value almost everywhere: the full range.
        let mut flat = vec![1.0; 1000];
        flat[3] = 2.0;
        assert_eq!(colour_range(&flat), (1.0, 2.0));
        assert_eq!(colour_range(&[f64::NAN]), (0.0, 1.0));
    }

    #[test]
    fn arrows_follow_the_velocity() {
        // A uniform flow along +x on a 10 × 5 grid of unit cells.
        let e1: Vec<f64> = (0..=10).map(|k| k as f64).collect();
        let e2: Vec<f64> = (0..=5).map(|k| k as f64).collect();
        let v: Vec<f64> = (0..50).flat_map(|_| [2.0, 0.0, 0.0]).collect();
        let a = arrows(&v, (10, 5), &e1, &e2, (0, 1));
        assert!(!a.is_empty());
        let spacing = 10.0 / ARROWS_ACROSS as f64;
        for [base, tip, left, _, right] in a {
            assert!((tip.0 - base.0 - 0.9 * spacing).abs() < 1e-12 && tip.1 == base.1);
            // The barbs point back from the tip, one on each side.
            assert!(left.0 < tip.0 && right.0 < tip.0);
            assert!((left.1 - tip.1) * (right.1 - tip.1) < 0.0);
        }
        // No flow, no arrows.
        assert!(arrows(&vec![0.0; 150], (10, 5), &e1, &e2, (0, 1)).is_empty());
    }
}
