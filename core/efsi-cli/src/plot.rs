//! `efsi plot DIR`: a run looked at without ParaView — PNGs of the probe time series
//! (`probes.png`, one panel per column) and of a field at an output time
//! (`<field>_t<time>.png`, a colour map with the solid's φ = ½ contour drawn over it).
//!
//! Text uses a TrueType font found on the system (DejaVu Sans or Liberation Sans); without
//! one the plots are drawn without text and a warning says so.

use efsi_run::output::read::{VtrData, read_pvd, read_vtr};
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
    /// The cell array (default: `solid_fraction` if the run has a solid, else `pressure`).
    pub field: Option<String>,
    /// Its component (default: see [`scalar`]).
    pub component: Option<usize>,
    /// The output time (default: the last); the nearest written one is used.
    pub time: Option<f64>,
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
    let mut written = Vec::new();
    let probes = dir.join("probes.csv");
    if probes.is_file() {
        let p = out.join("probes.png");
        plot_probes(&probes, &p)?;
        written.push(p);
    }
    let pvd = dir.join("fields.pvd");
    if pvd.is_file() {
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
        let name = match &request.field {
            Some(f) => f.clone(),
            None if data.cell("solid_fraction").is_some() => "solid_fraction".into(),
            None => "pressure".into(),
        };
        let p = out.join(format!("{name}_t{}.png", efsi_run::run::time_label(t)));
        plot_field(&data, &name, request.component, &p)?;
        written.push(p);
    } else if request.field.is_some() || request.time.is_some() {
        return Err(format!(
            "{}: no VTK output to plot a field from (the scene writes none without output.vtk_every)",
            pvd.display()
        ));
    }
    if written.is_empty() {
        return Err(format!(
            "{}: neither probes.csv nor fields.pvd: not an efsi output folder",
            dir.display()
        ));
    }
    Ok(written)
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
            if text {
                mesh.x_desc("t")
                    .label_style((FAMILY, 12))
                    .x_label_formatter(&|v| format!("{v:.3e}"))
                    .y_label_formatter(&|v| format!("{v:.3e}"));
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

/// The segments of the `level` contour of the cell-centred `values` (`n1 × n2`, first index
/// fastest; centres at `c1`, `c2`), by marching squares over the squares between centres.
pub fn contour(
    values: &[f64],
    (n1, n2): (usize, usize),
    c1: &[f64],
    c2: &[f64],
    level: f64,
) -> Vec<((f64, f64), (f64, f64))> {
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

fn plot_field(
    data: &VtrData,
    name: &str,
    component: Option<usize>,
    png: &Path,
) -> Result<(), String> {
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
    let values = scalar(&array.values, array.components, component);
    let (n1, n2) = data.shape();
    let [x, y, z] = &data.coordinates;
    let (e1, e2) = if y.len() == 1 { (x, z) } else { (x, y) };
    let axes = if y.len() == 1 { ("r", "z") } else { ("x", "y") };
    let (lo, hi) = values
        .iter()
        .filter(|v| v.is_finite())
        .fold((f64::MAX, f64::MIN), |(a, b), v| (a.min(*v), b.max(*v)));
    let span = if hi > lo { hi - lo } else { 1.0 };
    let text = font();
    let label = match component {
        Some(k) => format!("{name}[{k}]"),
        None if array.components == 3 => format!("|{name}|"),
        None if array.components > 1 => format!("{name}[0]"),
        None => name.to_string(),
    };
    let draw = || -> Result<(), Box<dyn std::error::Error>> {
        let root = BitMapBackend::new(png, FIELD_SIZE).into_drawing_area();
        root.fill(&WHITE)?;
        let (main, bar) = root.split_horizontally(FIELD_SIZE.0 - 110);
        // Keep the domain's aspect ratio inside the main area.
        let (w, h) = (e1[n1] - e1[0], e2[n2] - e2[0]);
        let (x0, x1, y0, y1) = if w >= h {
            let pad = 0.5 * (w - h);
            (e1[0], e1[n1], e2[0] - pad, e2[n2] + pad)
        } else {
            let pad = 0.5 * (h - w);
            (e1[0] - pad, e1[n1] + pad, e2[0], e2[n2])
        };
        let mut b = ChartBuilder::on(&main);
        b.margin(12);
        if text {
            b.caption(
                format!("{label} at t = {}", efsi_run::run::time_label(data.time)),
                (FAMILY, 22),
            )
            .x_label_area_size(40)
            .y_label_area_size(70);
        }
        let mut chart = b.build_cartesian_2d(x0..x1, y0..y1)?;
        let mut mesh = chart.configure_mesh();
        mesh.disable_mesh();
        if text {
            mesh.x_desc(axes.0).y_desc(axes.1).label_style((FAMILY, 13));
        }
        mesh.draw()?;
        chart.draw_series((0..n2).flat_map(|j| {
            let values = &values;
            (0..n1).map(move |i| {
                let c = colour((values[j * n1 + i] - lo) / span);
                Rectangle::new([(e1[i], e2[j]), (e1[i + 1], e2[j + 1])], c.filled())
            })
        }))?;
        if let Some(phi) = data.cell("solid_fraction") {
            let centre = |e: &[f64]| {
                e.windows(2)
                    .map(|p| 0.5 * (p[0] + p[1]))
                    .collect::<Vec<_>>()
            };
            let segments = contour(&phi.values, (n1, n2), &centre(e1), &centre(e2), 0.5);
            chart.draw_series(
                segments
                    .into_iter()
                    .map(|(a, b)| PathElement::new(vec![a, b], WHITE.stroke_width(2))),
            )?;
        }
        // The colour bar: its range top to bottom.
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
            bar.draw_text(&format!("{hi:.3e}"), &style, (0, -18))?;
            bar.draw_text(&format!("{lo:.3e}"), &style, (0, bh as i32 + 4))?;
        }
        root.present()?;
        Ok(())
    };
    draw().map_err(|e| format!("{}: {e}", png.display()))
}
