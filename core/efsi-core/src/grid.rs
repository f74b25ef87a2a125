//! The fixed Cartesian MAC grid and its metric.
//!
//! One uniform grid of `nx × ny` cells covers the box `[x0, x0 + nx·dx] × [y0, y0 + ny·dy]`.
//! Unknowns are staggered (Harlow & Welch's MAC arrangement):
//!
//! | location      | index range (interior)       | position                          | holds            |
//! |---------------|------------------------------|-----------------------------------|------------------|
//! | cell centre   | `i ∈ [0,nx)`, `j ∈ [0,ny)`   | `(x0+(i+½)dx, y0+(j+½)dy)`        | p, ρ, μ, φ_s, B̃ |
//! | x-face        | `i ∈ [0,nx]`, `j ∈ [0,ny)`   | `(x0+i·dx,     y0+(j+½)dy)`       | u                |
//! | y-face        | `i ∈ [0,nx)`, `j ∈ [0,ny]`   | `(x0+(i+½)dx,  y0+j·dy)`          | v                |
//! | corner        | `i ∈ [0,nx]`, `j ∈ [0,ny]`   | `(x0+i·dx,     y0+j·dy)`          | τ_xy             |
//!
//! Every field carries [`GHOST`] layers of ghost cells on each side.
//!
//! # Axisymmetry as metric factors
//!
//! In axisymmetric geometry `x` is the radius `r` and `y` is the axial coordinate `z`. A finite
//! volume then has volume `r·dr·dz` and a face normal to `r` has area `r·dz`: every operator in
//! efsi multiplies fluxes by the radius factor at the flux location and divides by the radius
//! factor at the control-volume centre. In planar geometry those factors are all 1, so the two
//! geometries share one code path (STYLE.md §6). The hoop terms of the axisymmetric equations
//! (`−2μu_r/r²`, `−τ_θθ/r`, `2(u_r/r)B̃_θθ`) carry the factor [`Metric::hoop_x`] or
//! [`Metric::hoop_c`], which is `1/r` in axisymmetric geometry and `0` in planar geometry.

use serde::{Deserialize, Serialize};

/// Number of ghost layers around every field.
pub const GHOST: usize = 2;
/// [`GHOST`] as a signed index offset.
pub const G: isize = GHOST as isize;

/// Planar (x, y) or axisymmetric (r, z) geometry.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum Geometry {
    /// Two-dimensional planar flow in the x–y plane (plane strain for solids).
    Planar,
    /// Axisymmetric flow without swirl; `x` is the radius `r`, `y` the axis `z`.
    Axisymmetric,
}

/// Radius factors of the axisymmetric metric (all ones in planar geometry).
///
/// Indexed by the signed column index `i` (ghosts included) through the accessor methods.
#[derive(Clone, Debug)]
pub struct Metric {
    rc: Vec<f64>,
    rx: Vec<f64>,
    hoop_c: Vec<f64>,
    hoop_x: Vec<f64>,
}

impl Metric {
    /// Radius factor at cell centres of column `i` (`r_c`, or 1 in planar geometry).
    #[inline(always)]
    pub fn rc(&self, i: isize) -> f64 {
        self.rc[(i + G) as usize]
    }
    /// Radius factor at x-faces of column `i` (`r_f`, or 1 in planar geometry); zero on the axis.
    #[inline(always)]
    pub fn rx(&self, i: isize) -> f64 {
        self.rx[(i + G) as usize]
    }
    /// [`rc`](Self::rc) of columns `0..n`, as a slice (for loops that vectorise).
    #[inline(always)]
    pub fn rc_row(&self, n: usize) -> &[f64] {
        &self.rc[GHOST..GHOST + n]
    }
    /// [`rx`](Self::rx) of columns `0..n`, as a slice (for loops that vectorise).
    #[inline(always)]
    pub fn rx_row(&self, n: usize) -> &[f64] {
        &self.rx[GHOST..GHOST + n]
    }
    /// `r_c` at the columns of `line` shifted by `di` (a slice of the line's length).
    #[inline(always)]
    pub fn rc_on(&self, line: &crate::loops::Line, di: isize) -> &[f64] {
        Self::on(&self.rc, line, di)
    }
    /// `r_f` at the columns of `line` shifted by `di`.
    #[inline(always)]
    pub fn rx_on(&self, line: &crate::loops::Line, di: isize) -> &[f64] {
        Self::on(&self.rx, line, di)
    }
    /// The hoop factor at cell centres on the columns of `line` shifted by `di`.
    #[inline(always)]
    pub fn hoop_c_on(&self, line: &crate::loops::Line, di: isize) -> &[f64] {
        Self::on(&self.hoop_c, line, di)
    }
    /// The hoop factor at x-faces on the columns of `line` shifted by `di`.
    #[inline(always)]
    pub fn hoop_x_on(&self, line: &crate::loops::Line, di: isize) -> &[f64] {
        Self::on(&self.hoop_x, line, di)
    }
    #[inline(always)]
    fn on<'a>(v: &'a [f64], line: &crate::loops::Line, di: isize) -> &'a [f64] {
        let o = (line.start[0] + di + G) as usize;
        &v[o..o + line.len]
    }
    /// Hoop factor at cell centres: `1/r_c` (axisymmetric) or 0 (planar).
    #[inline(always)]
    pub fn hoop_c(&self, i: isize) -> f64 {
        self.hoop_c[(i + G) as usize]
    }
    /// Hoop factor at x-faces: `1/r_f` (axisymmetric, 0 on the axis itself) or 0 (planar).
    #[inline(always)]
    pub fn hoop_x(&self, i: isize) -> f64 {
        self.hoop_x[(i + G) as usize]
    }
}

/// A uniform staggered grid with its metric.
#[derive(Clone, Debug)]
pub struct Grid {
    /// Planar or axisymmetric.
    pub geometry: Geometry,
    /// Number of cells along x (r).
    pub nx: usize,
    /// Number of cells along y (z).
    pub ny: usize,
    /// Lower-left corner x (r) of the domain.
    pub x0: f64,
    /// Lower-left corner y (z) of the domain.
    pub y0: f64,
    /// Cell width.
    pub dx: f64,
    /// Cell height.
    pub dy: f64,
    /// The radius factors.
    pub metric: Metric,
}

impl Grid {
    /// A grid of `nx × ny` cells over `[x0,x1] × [y0,y1]`.
    ///
    /// Callers validate the arguments (the scene loader does); this only asserts them.
    pub fn new(geometry: Geometry, nx: usize, ny: usize, x: (f64, f64), y: (f64, f64)) -> Self {
        assert!(nx >= 1 && ny >= 1 && x.1 > x.0 && y.1 > y.0);
        let dx = (x.1 - x.0) / nx as f64;
        let dy = (y.1 - y.0) / ny as f64;
        let n = nx + 1 + 2 * GHOST;
        let axi = geometry == Geometry::Axisymmetric;
        let mut rc = vec![1.0; n];
        let mut rx = vec![1.0; n];
        let mut hoop_c = vec![0.0; n];
        let mut hoop_x = vec![0.0; n];
        if axi {
            for k in 0..n {
                let i = k as isize - G;
                // Ghost columns left of the axis mirror it, so even reflections stay consistent.
                let c = (x.0 + (i as f64 + 0.5) * dx).abs();
                let f = (x.0 + i as f64 * dx).abs();
                rc[k] = c;
                rx[k] = f;
                hoop_c[k] = if c > 0.0 { 1.0 / c } else { 0.0 };
                hoop_x[k] = if f > 1e-14 * dx { 1.0 / f } else { 0.0 };
                if f <= 1e-14 * dx {
                    rx[k] = 0.0;
                }
            }
        }
        Grid {
            geometry,
            nx,
            ny,
            x0: x.0,
            y0: y.0,
            dx,
            dy,
            metric: Metric {
                rc,
                rx,
                hoop_c,
                hoop_x,
            },
        }
    }

    /// Whether this grid is axisymmetric.
    pub fn is_axisymmetric(&self) -> bool {
        self.geometry == Geometry::Axisymmetric
    }

    /// Total number of cells.
    pub fn cells(&self) -> usize {
        self.nx * self.ny
    }

    /// x of the centre of column `i`.
    #[inline]
    pub fn xc(&self, i: isize) -> f64 {
        self.x0 + (i as f64 + 0.5) * self.dx
    }
    /// y of the centre of row `j`.
    #[inline]
    pub fn yc(&self, j: isize) -> f64 {
        self.y0 + (j as f64 + 0.5) * self.dy
    }
    /// x of the x-face `i` (left edge of column `i`).
    #[inline]
    pub fn xf(&self, i: isize) -> f64 {
        self.x0 + i as f64 * self.dx
    }
    /// y of the y-face `j` (bottom edge of row `j`).
    #[inline]
    pub fn yf(&self, j: isize) -> f64 {
        self.y0 + j as f64 * self.dy
    }
    /// Upper x bound of the domain.
    pub fn x1(&self) -> f64 {
        self.x0 + self.nx as f64 * self.dx
    }
    /// Upper y bound of the domain.
    pub fn y1(&self) -> f64 {
        self.y0 + self.ny as f64 * self.dy
    }

    /// Volume of cell column `i` (per radian in axisymmetric geometry: `r_c·dx·dy`).
    #[inline]
    pub fn cell_volume(&self, i: isize) -> f64 {
        self.metric.rc(i) * self.dx * self.dy
    }

    /// Total domain volume (per radian in axisymmetric geometry).
    pub fn domain_volume(&self) -> f64 {
        (0..self.nx as isize)
            .map(|i| self.cell_volume(i))
            .sum::<f64>()
            * self.ny as f64
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn planar_metric_is_unity() {
        let g = Grid::new(Geometry::Planar, 4, 3, (0.0, 1.0), (0.0, 1.0));
        for i in -G..(g.nx as isize + 1 + G) {
            assert_eq!(g.metric.rc(i), 1.0);
            assert_eq!(g.metric.rx(i), 1.0);
            assert_eq!(g.metric.hoop_x(i), 0.0);
        }
        assert!((g.domain_volume() - 1.0).abs() < 1e-15);
    }

    #[test]
    fn axisymmetric_volume_is_r_weighted() {
        // ∫_0^R r dr · H = R²H/2 per radian; the midpoint rule is exact for r.
        let g = Grid::new(Geometry::Axisymmetric, 8, 2, (0.0, 2.0), (0.0, 3.0));
        assert!((g.domain_volume() - 2.0 * 2.0 * 3.0 / 2.0).abs() < 1e-13);
        assert_eq!(g.metric.rx(0), 0.0);
        assert_eq!(g.metric.hoop_x(0), 0.0);
        assert!(
            (g.metric.rc(-1) - g.metric.rc(0)).abs() < 1e-15,
            "ghost mirrors the axis"
        );
        assert!((g.metric.hoop_x(2) - 1.0 / 0.5).abs() < 1e-15);
    }
}
