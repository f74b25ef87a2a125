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
//! # The third axis
//!
//! A grid is three-dimensional in its data model: indices are `[i, j, k]` and every location
//! above has a z extent as well — `k ∈ [0, nz)` for cell centres, x- and y-faces and corners
//! (which in three dimensions are the edges along z, where `τ_xy` lives), `k ∈ [0, nz]` for the
//! z-faces ([`crate::Stagger::ZFace`], `w`) and for the edges along x and y
//! ([`crate::Stagger::XEdge`], [`crate::Stagger::YEdge`]). The ghost policy:
//!
//! - a **two-dimensional** grid ([`Grid::new`]) has `nz = 1`, `dz = 1` (a planar grid is per unit
//!   depth) and **no ghost layers along z** ([`Grid::gz`] is 0): its fields are one plane, laid
//!   out exactly as a 2-D array, so 2-D results do not depend on the third axis existing;
//! - a **three-dimensional** grid ([`Grid::new_3d`], Cartesian, metric all ones) has `nz ≥ 1`
//!   cells along z and [`GHOST`] ghost layers on each side along z as along x and y.
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

/// Planar (x, y), axisymmetric (r, z) or three-dimensional Cartesian (x, y, z) geometry.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum Geometry {
    /// Two-dimensional planar flow in the x–y plane (plane strain for solids).
    Planar,
    /// Axisymmetric flow without swirl; `x` is the radius `r`, `y` the axis `z`.
    Axisymmetric,
    /// Three-dimensional flow in an x–y–z box ([`Grid::new_3d`]).
    Cartesian3D,
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
    /// Number of cells along z (1 on a two-dimensional grid).
    pub nz: usize,
    /// Lower z bound of the domain (0 on a two-dimensional grid).
    pub z0: f64,
    /// Cell depth (1 on a two-dimensional grid: a planar grid is per unit depth).
    pub dz: f64,
    /// Ghost layers along z: 0 on a two-dimensional grid, [`GHOST`] on a three-dimensional one.
    gz: usize,
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
            nz: 1,
            z0: 0.0,
            dz: 1.0,
            gz: 0,
            metric: Metric {
                rc,
                rx,
                hoop_c,
                hoop_x,
            },
        }
    }

    /// A three-dimensional Cartesian grid of `nx × ny × nz` cells over `[x0,x1] × [y0,y1] ×
    /// [z0,z1]`, with [`GHOST`] ghost layers along every axis and the planar (unit) metric.
    pub fn new_3d(n: [usize; 3], x: (f64, f64), y: (f64, f64), z: (f64, f64)) -> Self {
        assert!(n[2] >= 1 && z.1 > z.0);
        Grid {
            geometry: Geometry::Cartesian3D,
            nz: n[2],
            z0: z.0,
            dz: (z.1 - z.0) / n[2] as f64,
            gz: GHOST,
            ..Grid::new(Geometry::Planar, n[0], n[1], x, y)
        }
    }

    /// The sub-grid of the `n` cells whose first cell is this grid's cell `lo` (per axis; `n[2]`
    /// and `lo[2]` ignored on a two-dimensional grid): the same cell sizes and, column by
    /// column, the same radius factors (ghost columns included), so an operator on the window
    /// computes what it computes on the same cells of this grid, bit for bit. Panics if the
    /// window does not fit.
    pub fn window(&self, lo: [usize; 3], n: [usize; 3]) -> Grid {
        let dims = self.dims();
        let pn = self.n();
        assert!(
            (0..dims).all(|a| n[a] >= 1 && lo[a] + n[a] <= pn[a]),
            "a window of {n:?} cells at {lo:?} does not fit the grid of {pn:?} cells"
        );
        let cols = n[0] + 1 + 2 * GHOST;
        let slice = |v: &[f64]| v[lo[0]..lo[0] + cols].to_vec();
        let m = &self.metric;
        Grid {
            geometry: self.geometry,
            nx: n[0],
            ny: n[1],
            x0: self.xf(lo[0] as isize),
            y0: self.yf(lo[1] as isize),
            dx: self.dx,
            dy: self.dy,
            nz: if self.is_3d() { n[2] } else { 1 },
            z0: if self.is_3d() {
                self.zf(lo[2] as isize)
            } else {
                self.z0
            },
            dz: self.dz,
            gz: self.gz,
            metric: Metric {
                rc: slice(&m.rc),
                rx: slice(&m.rx),
                hoop_c: slice(&m.hoop_c),
                hoop_x: slice(&m.hoop_x),
            },
        }
    }

    /// Whether the grid has a third axis with ghost layers (see the ghost policy above).
    pub fn is_3d(&self) -> bool {
        self.gz > 0
    }

    /// Number of axes: 2, or 3 on a three-dimensional grid.
    pub fn dims(&self) -> usize {
        if self.is_3d() { 3 } else { 2 }
    }

    /// Number of ghost layers along z: 0 in two dimensions, [`GHOST`] in three.
    pub fn gz(&self) -> usize {
        self.gz
    }

    /// Number of cells along each axis, `[nx, ny, nz]`.
    pub fn n(&self) -> [usize; 3] {
        [self.nx, self.ny, self.nz]
    }

    /// Cell size along each axis, `[dx, dy, dz]`.
    pub fn h(&self) -> [f64; 3] {
        [self.dx, self.dy, self.dz]
    }

    /// The padded layout every field of this grid shares: `[row stride, rows per plane,
    /// planes]`, i.e. `nx + 1 + 2G`, `ny + 1 + 2G` and `nz + 1 + 2G` (3-D) or 1 (2-D).
    pub fn padded(&self) -> [usize; 3] {
        let planes = if self.is_3d() {
            self.nz + 1 + 2 * GHOST
        } else {
            1
        };
        [self.nx + 1 + 2 * GHOST, self.ny + 1 + 2 * GHOST, planes]
    }

    /// z of the centre of layer `k`.
    #[inline]
    pub fn zc(&self, k: isize) -> f64 {
        self.z0 + (k as f64 + 0.5) * self.dz
    }
    /// z of the z-face `k` (bottom of layer `k`).
    #[inline]
    pub fn zf(&self, k: isize) -> f64 {
        self.z0 + k as f64 * self.dz
    }

    /// Whether this grid is axisymmetric.
    pub fn is_axisymmetric(&self) -> bool {
        self.geometry == Geometry::Axisymmetric
    }

    /// Total number of cells.
    pub fn cells(&self) -> usize {
        self.nx * self.ny * self.nz
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

    /// Total domain volume (per radian in axisymmetric geometry, per unit depth in planar).
    pub fn domain_volume(&self) -> f64 {
        let a = (0..self.nx as isize)
            .map(|i| self.cell_volume(i))
            .sum::<f64>()
            * self.ny as f64;
        if self.is_3d() {
            a * self.nz as f64 * self.dz
        } else {
            a
        }
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

    #[test]
    fn two_dimensional_grids_have_one_plane_and_three_dimensional_ones_z_ghosts() {
        let g = Grid::new(Geometry::Planar, 4, 3, (0.0, 1.0), (0.0, 1.0));
        assert_eq!((g.nz, g.gz(), g.dz, g.is_3d()), (1, 0, 1.0, false));
        assert_eq!(g.padded(), [4 + 5, 3 + 5, 1]);
        let g = Grid::new_3d([4, 3, 6], (0.0, 1.0), (0.0, 1.5), (-1.0, 2.0));
        assert_eq!((g.n(), g.gz(), g.is_3d()), ([4, 3, 6], GHOST, true));
        assert_eq!(g.padded(), [9, 8, 11]);
        assert_eq!(g.h(), [0.25, 0.5, 0.5]);
        assert_eq!((g.zc(0), g.zf(6), g.cells()), (-0.75, 2.0, 72));
        assert!((g.domain_volume() - 4.5).abs() < 1e-14);
    }
}
