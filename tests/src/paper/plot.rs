//! PNG line plots for the report (plotters, bitmap backend; text with a TrueType font found on
//! the system — DejaVu Sans where present — registered once).

use plotters::prelude::*;
use std::path::Path;
use std::sync::OnceLock;

/// The font family name the plots use.
const FAMILY: &str = "sans-serif";

/// Register a system TrueType font for plot text, once; `false` if none was found (plots are
/// then skipped and the report says so).
fn font() -> bool {
    static FONT: OnceLock<bool> = OnceLock::new();
    *FONT.get_or_init(|| {
        let candidates = [
            "/usr/share/fonts/truetype/dejavu/DejaVuSans.ttf",
            "/usr/share/fonts/dejavu/DejaVuSans.ttf",
            "/usr/share/fonts/TTF/DejaVuSans.ttf",
            "/usr/share/fonts/truetype/liberation/LiberationSans-Regular.ttf",
        ];
        for c in candidates {
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

/// Axis scaling of a plot.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Scale {
    /// Linear axes.
    Linear,
    /// Logarithmic axes (both), points marked.
    LogLog,
}

/// Plot `series` (label, points) as lines into `path` (PNG, 900×600). Returns an error message
/// if the plot could not be drawn (no font, empty data, I/O).
pub fn lines(
    path: &Path,
    title: &str,
    x_label: &str,
    y_label: &str,
    series: &[(String, Vec<(f64, f64)>)],
    scale: Scale,
) -> Result<(), String> {
    if !font() {
        return Err("no TrueType font found for plot text (install fonts-dejavu-core)".into());
    }
    let tf = |v: f64| if scale == Scale::LogLog { v.log10() } else { v };
    let pts: Vec<(f64, f64)> = series
        .iter()
        .flat_map(|(_, p)| p.iter().copied())
        .filter(|(x, y)| {
            x.is_finite() && y.is_finite() && (scale == Scale::Linear || (*x > 0.0 && *y > 0.0))
        })
        .map(|(x, y)| (tf(x), tf(y)))
        .collect();
    if pts.is_empty() {
        return Err(format!("{title}: nothing to plot"));
    }
    let (mut x0, mut x1, mut y0, mut y1) = pts.iter().fold(
        (f64::MAX, f64::MIN, f64::MAX, f64::MIN),
        |(a, b, c, d), (x, y)| (a.min(*x), b.max(*x), c.min(*y), d.max(*y)),
    );
    let pad = |lo: &mut f64, hi: &mut f64| {
        let w = (*hi - *lo).max(1e-12 * hi.abs().max(1.0));
        *lo -= 0.05 * w;
        *hi += 0.05 * w;
    };
    pad(&mut x0, &mut x1);
    pad(&mut y0, &mut y1);
    let draw = || -> Result<(), Box<dyn std::error::Error>> {
        let root = BitMapBackend::new(path, (900, 600)).into_drawing_area();
        root.fill(&WHITE)?;
        let mut chart = ChartBuilder::on(&root)
            .caption(title, (FAMILY, 22))
            .margin(12)
            .x_label_area_size(48)
            .y_label_area_size(78)
            .build_cartesian_2d(x0..x1, y0..y1)?;
        let log = scale == Scale::LogLog;
        let fmt = move |v: &f64| {
            if log {
                format!("{:.2e}", 10f64.powf(*v))
            } else {
                format!("{v:.3}")
            }
        };
        chart
            .configure_mesh()
            .x_desc(if log {
                format!("{x_label} (log)")
            } else {
                x_label.to_string()
            })
            .y_desc(if log {
                format!("{y_label} (log)")
            } else {
                y_label.to_string()
            })
            .x_label_formatter(&fmt)
            .y_label_formatter(&fmt)
            .label_style((FAMILY, 14))
            .draw()?;
        for (k, (label, p)) in series.iter().enumerate() {
            let color = Palette99::pick(k).to_rgba();
            let data: Vec<(f64, f64)> = p
                .iter()
                .filter(|(x, y)| x.is_finite() && y.is_finite() && (!log || (*x > 0.0 && *y > 0.0)))
                .map(|(x, y)| (tf(*x), tf(*y)))
                .collect();
            chart
                .draw_series(LineSeries::new(data.clone(), color.stroke_width(2)))?
                .label(label.clone())
                .legend(move |(x, y)| {
                    PathElement::new(vec![(x, y), (x + 18, y)], color.stroke_width(2))
                });
            if log || data.len() < 12 {
                chart.draw_series(
                    data.iter()
                        .map(|&(x, y)| Circle::new((x, y), 4, color.filled())),
                )?;
            }
        }
        chart
            .configure_series_labels()
            .background_style(WHITE.mix(0.85))
            .border_style(BLACK)
            .label_font((FAMILY, 14))
            .draw()?;
        root.present()?;
        Ok(())
    };
    draw().map_err(|e| format!("{}: {e}", path.display()))
}

/// Draw a cell field (row-major, `nx × ny`, `values[j * nx + i]` in [0, 1]) over the box
/// `x ∈ [x0, x1]`, `y ∈ [y0, y1]` as a grey-scale image (1 black) into `path`.
pub fn field(
    path: &Path,
    title: &str,
    (nx, ny): (usize, usize),
    (x0, x1, y0, y1): (f64, f64, f64, f64),
    values: &[f64],
) -> Result<(), String> {
    if !font() {
        return Err("no TrueType font found for plot text (install fonts-dejavu-core)".into());
    }
    let width = 900u32;
    let height =
        ((width as f64 - 90.0) * (y1 - y0) / (x1 - x0) + 110.0).clamp(200.0, 1200.0) as u32;
    let draw =
        || -> Result<(), Box<dyn std::error::Error>> {
            let root = BitMapBackend::new(path, (width, height)).into_drawing_area();
            root.fill(&WHITE)?;
            let mut chart = ChartBuilder::on(&root)
                .caption(title, (FAMILY, 20))
                .margin(10)
                .x_label_area_size(36)
                .y_label_area_size(50)
                .build_cartesian_2d(x0..x1, y0..y1)?;
            chart
                .configure_mesh()
                .disable_mesh()
                .label_style((FAMILY, 13))
                .draw()?;
            let (dx, dy) = ((x1 - x0) / nx as f64, (y1 - y0) / ny as f64);
            chart.draw_series((0..ny).flat_map(|j| (0..nx).map(move |i| (i, j))).map(
                |(i, j)| {
                    let v = values[j * nx + i].clamp(0.0, 1.0);
                    let c = (255.0 * (1.0 - v)) as u8;
                    let (xa, ya) = (x0 + i as f64 * dx, y0 + j as f64 * dy);
                    Rectangle::new([(xa, ya), (xa + dx, ya + dy)], RGBColor(c, c, c).filled())
                },
            ))?;
            root.present()?;
            Ok(())
        };
    draw().map_err(|e| format!("{}: {e}", path.display()))
}

/// How a cell of a [`map`] is coloured.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Tone {
    /// A run that finished stable (green).
    Good,
    /// A run refused before it started (amber).
    Refused,
    /// Anything else: a failure (red).
    Bad,
}

/// One panel of a [`map`]: a grid of coloured, labelled cells.
#[derive(Clone, Debug)]
pub struct Panel {
    /// The panel's title.
    pub title: String,
    /// Column labels, left to right.
    pub cols: Vec<String>,
    /// Row labels, bottom to top.
    pub rows: Vec<String>,
    /// The cells, row by row from the bottom: tone and a short text.
    pub cells: Vec<(Tone, String)>,
}

/// Draw categorical maps side by side (`x_label` under the columns, `y_label` beside the rows)
/// into `path` (PNG).
pub fn map(
    path: &Path,
    title: &str,
    (x_label, y_label): (&str, &str),
    panels: &[Panel],
) -> Result<(), String> {
    use plotters::style::text_anchor::{HPos, Pos, VPos};
    if !font() {
        return Err("no TrueType font found for plot text (install fonts-dejavu-core)".into());
    }
    if panels
        .iter()
        .any(|p| p.cells.len() != p.cols.len() * p.rows.len() || p.cells.is_empty())
    {
        return Err("a panel's cells do not fill its rows × columns".into());
    }
    // At most three panels to a row.
    let per_row = panels.len().min(3);
    let rows = panels.len().div_ceil(per_row);
    let (width, height) = (430 * per_row as u32 + 20, 420 * rows as u32 + 50);
    let draw = || -> Result<(), Box<dyn std::error::Error>> {
        let root = BitMapBackend::new(path, (width, height)).into_drawing_area();
        root.fill(&WHITE)?;
        let root = root.titled(title, (FAMILY, 22))?;
        let centred = |size: u32| {
            TextStyle::from((FAMILY, size).into_font()).pos(Pos::new(HPos::Center, VPos::Center))
        };
        for (area, p) in root.split_evenly((rows, per_row)).iter().zip(panels) {
            let (nc, nr) = (p.cols.len() as f64, p.rows.len() as f64);
            let mut chart = ChartBuilder::on(area)
                .caption(&p.title, (FAMILY, 17))
                .margin(8)
                .build_cartesian_2d(-1.3..nc, -1.0..nr)?;
            chart.draw_series(p.cells.iter().enumerate().map(|(k, (tone, _))| {
                let (c, r) = ((k % p.cols.len()) as f64, (k / p.cols.len()) as f64);
                let colour = match tone {
                    Tone::Good => RGBColor(150, 215, 150),
                    Tone::Refused => RGBColor(245, 200, 110),
                    Tone::Bad => RGBColor(235, 110, 100),
                };
                Rectangle::new(
                    [(c + 0.03, r + 0.03), (c + 0.97, r + 0.97)],
                    colour.filled(),
                )
            }))?;
            chart.draw_series(p.cells.iter().enumerate().map(|(k, (_, text))| {
                let (c, r) = ((k % p.cols.len()) as f64, (k / p.cols.len()) as f64);
                Text::new(text.clone(), (c + 0.5, r + 0.5), centred(12))
            }))?;
            chart.draw_series(
                p.cols
                    .iter()
                    .enumerate()
                    .map(|(c, l)| Text::new(l.clone(), (c as f64 + 0.5, -0.25), centred(13))),
            )?;
            chart.draw_series(std::iter::once(Text::new(
                x_label.to_string(),
                (nc / 2.0, -0.7),
                centred(14),
            )))?;
            chart.draw_series(
                p.rows
                    .iter()
                    .enumerate()
                    .map(|(r, l)| Text::new(l.clone(), (-0.45, r as f64 + 0.5), centred(13))),
            )?;
            chart.draw_series(std::iter::once(Text::new(
                y_label.to_string(),
                (-1.0, nr + 0.0 - 0.15),
                centred(13),
            )))?;
        }
        root.present()?;
        Ok(())
    };
    draw().map_err(|e| format!("{}: {e}", path.display()))
}
