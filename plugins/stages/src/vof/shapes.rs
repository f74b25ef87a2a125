//! Initial solid fractions of simple shapes, exact to round-off where one boundary crosses a cell.
//!
//! # What is computed
//!
//! For a shape `S` (a region of the x–y plane, or of the r–z half-plane in axisymmetric
//! geometry) [`fill_fraction`] sets in every cell
//!
//! ```text
//!     φ = ∫_{cell ∩ S} w dA / ∫_{cell} w dA,     w = 1 (planar),  w = r (axisymmetric),
//! ```
//!
//! so that `Σ φ V` is the exact volume of the shape (per radian: a disk centred on the axis is a
//! sphere, of volume `(2/3)R³` per radian).
//!
//! # How
//!
//! Each primitive classifies a rectangle as inside, outside or cut, and integrates itself over a
//! cut rectangle in closed form:
//! - **disk** `|x − c| < R`: `∫_{x_a}^{x_b} w(x) ℓ(x) dx` with `ℓ(x)` the length of the vertical
//!   chord clipped to `[y_a, y_b]`; the integrand is piecewise `(a + b x)(c + k√(R² − x²))`
//!   between the abscissae where the circle crosses `y_a`, `y_b`, and is integrated with the
//!   antiderivatives `∫√(R²−X²) = ½(X√(R²−X²) + R² asin(X/R))`, `∫X√(R²−X²) = −⅓(R²−X²)^{3/2}`;
//! - **rectangle**: the overlap rectangle, `∫ w dA` exactly;
//! - **half-plane** `n·x < c`: the PLIC formulas of [`super::plic`] (Scardovelli & Zaleski's
//!   closed form planar, polygon clipping with exact `∫ r dA` axisymmetric).
//!
//! Unions, intersections and differences are exact where at most one of their primitives
//! crosses the rectangle (the others are wholly in or out). Where two or more boundaries cross
//! (corners such as the mouth of Zalesak's slot), the rectangle is split in four, recursively, to
//! sub-cells of `h/2^18`; an unresolved sub-cell is decided by its centre. The per-cell error is
//! then of order the area of a few such sub-cells, ≲ 1e-10 of the cell. A budget of
//! [`MAX_SPLITS`] splits per cell bounds the work for pathological shapes (coincident
//! boundaries), where the error is then larger.
//!
//! There is no stability condition (a one-off geometric integration). References: the disk
//! integrals are elementary; the half-plane uses Scardovelli & Zaleski (2000, J. Comput. Phys.
//! 164:228); the shapes are those of Zalesak (1979, J. Comput. Phys. 31:335) and Rider & Kothe
//! (1998, J. Comput. Phys. 141:112).

use super::plic::{half_plane_moments, rect_fraction};
use crate::solid::Shape;
use efsi_core::{Field, Grid};

/// Deepest recursive split of a cell crossed by two or more boundaries.
pub const MAX_DEPTH: u32 = 18;
/// Most splits spent on one cell before the remaining sub-cells are decided by their centre.
pub const MAX_SPLITS: u32 = 20_000;

/// The exact volume of a [`Shape`] in a rectangle.
pub trait ShapeVolume {
    /// The exact volume `∫_{S ∩ [x0,x1]×[y0,y1]} w dA` (`w = r` if `axi`), up to the resolution
    /// limits stated in the module docs.
    fn volume_in(&self, x: (f64, f64), y: (f64, f64), axi: bool) -> f64;
}

impl ShapeVolume for Shape {
    fn volume_in(&self, x: (f64, f64), y: (f64, f64), axi: bool) -> f64 {
        let r = Rect {
            x0: x.0,
            x1: x.1,
            y0: y.0,
            y1: y.1,
        };
        let mut budget = MAX_SPLITS;
        volume(self, r, axi, MAX_DEPTH, &mut budget)
    }
}

/// An axis-aligned rectangle `[x0,x1] × [y0,y1]`.
#[derive(Clone, Copy, Debug)]
struct Rect {
    x0: f64,
    y0: f64,
    x1: f64,
    y1: f64,
}

impl Rect {
    /// `∫ w dA` over the rectangle.
    fn volume(&self, axi: bool) -> f64 {
        let a = (self.x1 - self.x0) * (self.y1 - self.y0);
        if axi {
            0.5 * (self.x0 + self.x1) * a
        } else {
            a
        }
    }
    fn quarters(&self) -> [Rect; 4] {
        let xm = 0.5 * (self.x0 + self.x1);
        let ym = 0.5 * (self.y0 + self.y1);
        [
            Rect {
                x1: xm,
                y1: ym,
                ..*self
            },
            Rect {
                x0: xm,
                y1: ym,
                ..*self
            },
            Rect {
                x1: xm,
                y0: ym,
                ..*self
            },
            Rect {
                x0: xm,
                y0: ym,
                ..*self
            },
        ]
    }
}

/// What a cell's cover by a shape can be, whatever else a cut cover carries: what
/// [`combine`] needs of the two-dimensional and the three-dimensional covers.
pub(super) trait Coverage: Sized {
    /// Wholly inside.
    const IN: Self;
    /// Wholly outside.
    const OUT: Self;
    /// Crossed by several boundaries.
    const MIXED: Self;
    /// Whether this is [`Self::IN`] (`inside`) or [`Self::OUT`] (not `inside`).
    fn is(&self, inside: bool) -> bool;
}

/// The cover of a union (`union`) or an intersection of parts whose covers are `parts`: a part
/// wholly in (union) or out (intersection) decides; parts wholly out (union) or in
/// (intersection) do not count; one part crossed by its boundary is the cover; two or more are
/// [`Coverage::MIXED`].
pub(super) fn combine<C: Coverage>(parts: impl Iterator<Item = C>, union: bool) -> C {
    let mut only = None;
    for c in parts {
        if c.is(union) {
            return c;
        }
        if c.is(!union) {
            continue;
        }
        if only.is_some() {
            return C::MIXED;
        }
        only = Some(c);
    }
    only.unwrap_or(if union { C::OUT } else { C::IN })
}

impl Coverage for Cover {
    const IN: Self = Cover::In;
    const OUT: Self = Cover::Out;
    const MIXED: Self = Cover::Mixed;
    fn is(&self, inside: bool) -> bool {
        matches!((self, inside), (Cover::In, true) | (Cover::Out, false))
    }
}

/// How a shape covers a rectangle.
#[derive(Clone, Copy, Debug)]
enum Cover {
    /// Wholly inside.
    In,
    /// Wholly outside.
    Out,
    /// Crossed by one boundary; the exact `∫ w dA` of the covered part.
    Exact(f64),
    /// Crossed by several boundaries.
    Mixed,
}

fn volume(this: &Shape, r: Rect, axi: bool, depth: u32, budget: &mut u32) -> f64 {
    match cover(this, r, axi) {
        Cover::In => r.volume(axi),
        Cover::Out => 0.0,
        Cover::Exact(v) => v,
        Cover::Mixed => {
            if depth == 0 || *budget == 0 {
                let (xm, ym) = (0.5 * (r.x0 + r.x1), 0.5 * (r.y0 + r.y1));
                if this.contains(xm, ym) {
                    r.volume(axi)
                } else {
                    0.0
                }
            } else {
                *budget -= 1;
                r.quarters()
                    .iter()
                    .map(|q| volume(this, *q, axi, depth - 1, budget))
                    .sum()
            }
        }
    }
}

fn cover(this: &Shape, r: Rect, axi: bool) -> Cover {
    match this {
        Shape::Disk { center, radius } => disk_cover(*center, *radius, r, axi),
        Shape::Rectangle { min, max } => {
            let (x0, x1) = (r.x0.max(min.0), r.x1.min(max.0));
            let (y0, y1) = (r.y0.max(min.1), r.y1.min(max.1));
            if x0 >= x1 || y0 >= y1 {
                Cover::Out
            } else if x0 == r.x0 && x1 == r.x1 && y0 == r.y0 && y1 == r.y1 {
                Cover::In
            } else {
                Cover::Exact(Rect { x0, y0, x1, y1 }.volume(axi))
            }
        }
        Shape::HalfPlane { normal, offset } => {
            let (nx, ny) = *normal;
            let d = [
                nx * r.x0 + ny * r.y0,
                nx * r.x1 + ny * r.y0,
                nx * r.x0 + ny * r.y1,
                nx * r.x1 + ny * r.y1,
            ];
            if d.iter().all(|&v| v <= *offset) {
                Cover::In
            } else if d.iter().all(|&v| v >= *offset) {
                Cover::Out
            } else {
                let a = offset - d[0];
                let (w, h) = (r.x1 - r.x0, r.y1 - r.y0);
                Cover::Exact(if axi {
                    let (area, m1) = half_plane_moments(nx, ny, a, w, h);
                    r.x0 * area + m1
                } else {
                    w * h * rect_fraction(nx, ny, a, w, h)
                })
            }
        }
        // A three-dimensional shape on a two-dimensional grid (refused by the scene check):
        // its section z = 0, by point membership.
        Shape::Sphere { .. }
        | Shape::Ellipsoid { .. }
        | Shape::Box { .. }
        | Shape::Cylinder { .. }
        | Shape::HalfSpace { .. } => Cover::Mixed,
        Shape::Union(v) => combine(v.iter().map(|s| cover(s, r, axi)), true),
        Shape::Intersection(v) => combine(v.iter().map(|s| cover(s, r, axi)), false),
        Shape::Difference(a, b) => match (cover(a, r, axi), cover(b, r, axi)) {
            (_, Cover::In) | (Cover::Out, _) => Cover::Out,
            (ca, Cover::Out) => ca,
            (Cover::In, Cover::Exact(vb)) => Cover::Exact((r.volume(axi) - vb).max(0.0)),
            _ => Cover::Mixed,
        },
    }
}

/// Cover of the rectangle `r` by the disk `|x − c| < R`.
fn disk_cover(c: (f64, f64), rad: f64, r: Rect, axi: bool) -> Cover {
    let (xa, xb, ya, yb) = (r.x0 - c.0, r.x1 - c.0, r.y0 - c.1, r.y1 - c.1);
    let near_x = xa.max(0.0).max(-xb);
    let near_y = ya.max(0.0).max(-yb);
    let rr = rad * rad;
    if near_x * near_x + near_y * near_y >= rr {
        return Cover::Out;
    }
    let far_x = xa.abs().max(xb.abs());
    let far_y = ya.abs().max(yb.abs());
    if far_x * far_x + far_y * far_y <= rr {
        return Cover::In;
    }
    let v = disk_volume(
        rad,
        xa,
        xb,
        ya,
        yb,
        if axi { (c.0, 1.0) } else { (1.0, 0.0) },
    );
    Cover::Exact(v.clamp(0.0, r.volume(axi)))
}

/// `∫∫ (a + bX) dX dY` over `{X² + Y² < R²} ∩ [xa,xb] × [ya,yb]` (coordinates relative to the
/// centre), with the weight `w = (a, b)`; piecewise closed form.
pub(crate) fn disk_volume(rad: f64, xa: f64, xb: f64, ya: f64, yb: f64, w: (f64, f64)) -> f64 {
    let (x0, x1) = (xa.max(-rad), xb.min(rad));
    if x0 >= x1 {
        return 0.0;
    }
    let rr = rad * rad;
    // √(R² − X²) as √((R − |X|)(R + |X|)): accurate near X = ±R, where R² − X² cancels.
    let s = |x: f64| ((rad - x.abs()).max(0.0) * (rad + x.abs())).sqrt();
    // ∫ s = ½(X s + R² θ) with θ = atan2(X, s) (not asin(X/R), whose slope is infinite at ±R,
    // so that rounding X/R would cost 1e-8 in θ); and ∫ X s = −s³/3.
    let s0 = |x: f64| {
        let x = x.clamp(-rad, rad);
        let q = s(x);
        0.5 * (x * q + rr * x.atan2(q))
    };
    let s1 = |x: f64| {
        let q = s(x);
        -q * q * q / 3.0
    };
    // Break points where the circle crosses y = ya or y = yb.
    let mut pts = [0.0f64; 6];
    let mut n = 0;
    pts[n] = x0;
    n += 1;
    for yy in [ya, yb] {
        if yy.abs() < rad {
            let q = s(yy);
            for p in [-q, q] {
                if p > x0 && p < x1 {
                    pts[n] = p;
                    n += 1;
                }
            }
        }
    }
    pts[n] = x1;
    n += 1;
    pts[..n].sort_by(|a, b| a.partial_cmp(b).unwrap());
    let (wa, wb) = w;
    let mut total = 0.0;
    for k in 0..n - 1 {
        let (p, q) = (pts[k], pts[k + 1]);
        if q <= p {
            continue;
        }
        let sm = s(0.5 * (p + q));
        let upper_is_s = sm < yb;
        let lower_is_s = -sm > ya;
        let up = if upper_is_s { sm } else { yb };
        let lo = if lower_is_s { -sm } else { ya };
        if up <= lo {
            continue;
        }
        // Integrand (wa + wb X)(cst + k s(X)).
        let cst = if upper_is_s { 0.0 } else { yb } - if lower_is_s { 0.0 } else { ya };
        let kk = upper_is_s as u8 as f64 + lower_is_s as u8 as f64;
        let mut v = wa * cst * (q - p);
        if wb != 0.0 {
            v += wb * cst * 0.5 * (q * q - p * p);
        }
        if kk != 0.0 {
            v += wa * kk * (s0(q) - s0(p));
            if wb != 0.0 {
                v += wb * kk * (s1(q) - s1(p));
            }
        }
        total += v;
    }
    total
}

/// Set the interior of `phi` to the fraction of each cell covered by `shape` (r-weighted in
/// axisymmetric geometry; on a three-dimensional grid the volume fraction of
/// [`super::shapes3d`]). Ghost cells are left untouched.
pub fn fill_fraction(grid: &Grid, shape: &Shape, phi: &mut Field) {
    if grid.is_3d() {
        return super::shapes3d::fill_fraction(grid, shape, phi);
    }
    fill_cells(
        grid,
        shape,
        [0, grid.nx as isize],
        [0, grid.ny as isize],
        phi,
    );
}

/// [`fill_fraction`] on the cells `i0 ≤ i < i1`, `j0 ≤ j < j1` (`is`, `js`): zero at once where
/// the shape's [`cover`] of their box is wholly out — then it is of every cell in it, each
/// cover test being monotone as a box shrinks — else the box split in two across its longer
/// side, down to single cells (so the work follows the shape's boundary, not the grid).
fn fill_cells(grid: &Grid, shape: &Shape, is: [isize; 2], js: [isize; 2], phi: &mut Field) {
    let axi = grid.is_axisymmetric();
    let (ni, nj) = (is[1] - is[0], js[1] - js[0]);
    if ni <= 0 || nj <= 0 {
        return;
    }
    let r = Rect {
        x0: grid.xf(is[0]),
        x1: grid.xf(is[1]),
        y0: grid.yf(js[0]),
        y1: grid.yf(js[1]),
    };
    if ni == 1 && nj == 1 {
        let mut budget = MAX_SPLITS;
        let v = volume(shape, r, axi, MAX_DEPTH, &mut budget);
        phi[(is[0], js[0])] = (v / r.volume(axi)).clamp(0.0, 1.0);
    } else if matches!(cover(shape, r, axi), Cover::Out) {
        for j in js[0]..js[1] {
            for i in is[0]..is[1] {
                phi[(i, j)] = 0.0;
            }
        }
    } else if ni >= nj {
        let m = is[0] + ni / 2;
        fill_cells(grid, shape, [is[0], m], js, phi);
        fill_cells(grid, shape, [m, is[1]], js, phi);
    } else {
        let m = js[0] + nj / 2;
        fill_cells(grid, shape, is, [js[0], m], phi);
        fill_cells(grid, shape, is, [m, js[1]], phi);
    }
}

/// The width of `shape` on `grid` as the hydraulic diameter `4A/P` of its section (x–y, or
/// r–z): `A = Σ φ dx dy`, `P = Σ |∇φ| dx dy` with φ the cell fractions and central differences
/// (a boundary of the domain — a wall the solid touches, the axis — is not counted as
/// perimeter). `2R` for a disk, ≈ `2w` for a long strip of width `w`. `None` if the shape has
/// no interface on the grid (empty, or filling the domain).
pub fn section_width(grid: &Grid, shape: &Shape) -> Option<f64> {
    let mut phi = Field::zeros(grid);
    fill_fraction(grid, shape, &mut phi);
    let (nx, ny) = (grid.nx as isize, grid.ny as isize);
    let at = |i: isize, j: isize| phi[(i.clamp(0, nx - 1), j.clamp(0, ny - 1))];
    // The cells within one of a cell holding the shape: elsewhere both terms are zero, and
    // adding a zero leaves the sums (taken in the same order) as they are.
    let (mut lo, mut hi) = ((nx, ny), (-1, -1));
    for j in 0..ny {
        for i in 0..nx {
            if phi[(i, j)] != 0.0 {
                (lo, hi) = ((lo.0.min(i), lo.1.min(j)), (hi.0.max(i), hi.1.max(j)));
            }
        }
    }
    let (mut area, mut perimeter) = (0.0, 0.0);
    for j in (lo.1 - 1).max(0)..(hi.1 + 2).min(ny) {
        for i in (lo.0 - 1).max(0)..(hi.0 + 2).min(nx) {
            area += phi[(i, j)];
            let gx = (at(i + 1, j) - at(i - 1, j)) / (2.0 * grid.dx);
            let gy = (at(i, j + 1) - at(i, j - 1)) / (2.0 * grid.dy);
            perimeter += gx.hypot(gy);
        }
    }
    (perimeter > 0.0).then(|| 4.0 * area / perimeter)
}

#[cfg(test)]
mod tests {
    use super::*;
    use efsi_core::Geometry;
    use std::f64::consts::PI;

    #[test]
    fn section_width_is_the_diameter_of_a_disk_and_twice_a_strip() {
        for (n, cells) in [(64, 3.0), (64, 4.0), (64, 16.0), (128, 40.0)] {
            let grid = Grid::new(Geometry::Planar, n, n, (0.0, 1.0), (0.0, 1.0));
            let h = 1.0 / n as f64;
            let d = cells * h;
            let s = Shape::Disk {
                center: (0.5 + 0.3 * h, 0.5 - 0.2 * h),
                radius: d / 2.0,
            };
            let w = section_width(&grid, &s).unwrap();
            assert!((w / d - 1.0).abs() < 0.08, "{cells} cells: width {}", w / h);
            let axi = Grid::new(Geometry::Axisymmetric, n / 2, n, (0.0, 0.5), (0.0, 1.0));
            let s = Shape::Disk {
                center: (0.0, 0.5 - 0.2 * h),
                radius: d / 2.0,
            };
            let w = section_width(&axi, &s).unwrap();
            assert!(
                (w / d - 1.0).abs() < 0.1,
                "axisymmetric {cells} cells: width {}",
                w / h
            );
        }
        let grid = Grid::new(Geometry::Planar, 64, 64, (0.0, 1.0), (0.0, 1.0));
        let strip = Shape::Rectangle {
            min: (-1.0, 0.4),
            max: (2.0, 0.5),
        };
        let w = section_width(&grid, &strip).unwrap();
        assert!((w / 0.2 - 1.0).abs() < 1e-9, "strip: {w}");
        let all = Shape::HalfPlane {
            normal: (0.0, 1.0),
            offset: 5.0,
        };
        assert_eq!(section_width(&grid, &all), None);
    }

    fn total(grid: &Grid, phi: &Field) -> f64 {
        super::super::phase_volume(grid, phi)
    }

    #[test]
    fn disk_area_is_exact() {
        for n in [16, 50, 100] {
            let g = Grid::new(Geometry::Planar, n, n, (0.0, 1.0), (0.0, 1.0));
            let mut phi = Field::zeros(&g);
            let s = Shape::Disk {
                center: (0.5123, 0.4711),
                radius: 0.3,
            };
            fill_fraction(&g, &s, &mut phi);
            let a = total(&g, &phi);
            assert!((a - PI * 0.09).abs() < 1e-14, "n={n}: {a} vs {}", PI * 0.09);
        }
    }

    #[test]
    fn sphere_volume_is_exact() {
        // Disk centred on the axis: ∫ r dA over the half disk = (2/3) R³ per radian.
        for n in [10, 32, 64] {
            let g = Grid::new(Geometry::Axisymmetric, n, 2 * n, (0.0, 0.5), (0.0, 1.0));
            let mut phi = Field::zeros(&g);
            let s = Shape::Disk {
                center: (0.0, 0.5),
                radius: 0.2,
            };
            fill_fraction(&g, &s, &mut phi);
            let v = total(&g, &phi);
            let exact = 2.0 / 3.0 * 0.2f64.powi(3);
            assert!(
                (v - exact).abs() < 1e-14 * exact * 10.0,
                "n={n}: {v} vs {exact}"
            );
        }
    }

    #[test]
    fn torus_and_cylinder_volumes_are_exact() {
        let g = Grid::new(Geometry::Axisymmetric, 37, 41, (0.0, 1.0), (0.0, 1.0));
        let mut phi = Field::zeros(&g);
        // Torus: disk of radius a centred at r = c: Pappus, ∫ r dA = c π a².
        let (c, a) = (0.5, 0.2);
        fill_fraction(
            &g,
            &Shape::Disk {
                center: (c, 0.5),
                radius: a,
            },
            &mut phi,
        );
        assert!((total(&g, &phi) - c * PI * a * a).abs() < 1e-14);
        // Annular cylinder [0.1, 0.4] × [0.2, 0.7]: (0.4² − 0.1²)/2 · 0.5.
        fill_fraction(
            &g,
            &Shape::Rectangle {
                min: (0.1, 0.2),
                max: (0.4, 0.7),
            },
            &mut phi,
        );
        assert!((total(&g, &phi) - (0.16 - 0.01) / 2.0 * 0.5).abs() < 1e-15);
        // Cone-like half-plane z < 0.3 + r: ∫_0^1 r (0.3 + r) dr = 0.15 + 1/3, clipped at z ≤ 1:
        // for r > 0.7 the column is full: ∫_0^0.7 r(0.3+r) dr + ∫_0.7^1 r dr.
        fill_fraction(
            &g,
            &Shape::HalfPlane {
                normal: (-1.0, 1.0),
                offset: 0.3,
            },
            &mut phi,
        );
        let exact = 0.3 * 0.49 / 2.0 + 0.343 / 3.0 + (1.0 - 0.49) / 2.0;
        assert!(
            (total(&g, &phi) - exact).abs() < 1e-15,
            "{} {exact}",
            total(&g, &phi)
        );
    }

    #[test]
    fn zalesak_area_is_exact() {
        let (r, a, top) = (0.15f64, 0.025f64, 0.1f64);
        let exact_slot = 2.0 * a * top + (a * (r * r - a * a).sqrt() + r * r * (a / r).asin());
        let exact = PI * r * r - exact_slot;
        for n in [64, 100, 200] {
            let g = Grid::new(Geometry::Planar, n, n, (0.0, 1.0), (0.0, 1.0));
            let mut phi = Field::zeros(&g);
            let s = Shape::Difference(
                Box::new(Shape::Disk {
                    center: (0.5, 0.75),
                    radius: 0.15,
                }),
                Box::new(Shape::Rectangle {
                    min: (0.475, 0.5),
                    max: (0.525, 0.85),
                }),
            );
            fill_fraction(&g, &s, &mut phi);
            let v = total(&g, &phi);
            assert!(
                (v - exact).abs() < 1e-13,
                "n={n}: {v} vs {exact}, {:e}",
                v - exact
            );
        }
    }

    #[test]
    fn cut_cells_match_brute_force() {
        // Per-cell fractions of a disk, a union with a corner crossing, and an axisymmetric
        // torus, against a 1000² midpoint sub-grid (error ≲ 1e-3·h of the cut length).
        let shapes = [
            Shape::Disk {
                center: (0.43, 0.61),
                radius: 0.27,
            },
            Shape::Union(vec![
                Shape::Disk {
                    center: (0.43, 0.61),
                    radius: 0.27,
                },
                Shape::HalfPlane {
                    normal: (0.3, 1.0),
                    offset: 0.5,
                },
            ]),
        ];
        for axi in [false, true] {
            let geom = if axi {
                Geometry::Axisymmetric
            } else {
                Geometry::Planar
            };
            let g = Grid::new(geom, 8, 8, (0.0, 1.0), (0.0, 1.0));
            for s in &shapes {
                let mut phi = Field::zeros(&g);
                fill_fraction(&g, s, &mut phi);
                for j in 0..8 {
                    for i in 0..8 {
                        let m = 1000;
                        let (mut inside, mut all) = (0.0, 0.0);
                        for b in 0..m {
                            for a in 0..m {
                                let x = g.xf(i) + (a as f64 + 0.5) * g.dx / m as f64;
                                let y = g.yf(j) + (b as f64 + 0.5) * g.dy / m as f64;
                                let w = if axi { x } else { 1.0 };
                                all += w;
                                if s.contains(x, y) {
                                    inside += w;
                                }
                            }
                        }
                        let f = inside / all;
                        assert!(
                            (phi[(i, j)] - f).abs() < 2e-3,
                            "({i},{j}): {} vs {f}",
                            phi[(i, j)]
                        );
                    }
                }
            }
        }
    }

    #[test]
    fn difference_at_a_corner_converges() {
        // A square minus a disk whose boundary crosses the square's corner region: the cell
        // holding the crossing is Mixed and resolved by recursive splitting.
        let s = Shape::Difference(
            Box::new(Shape::Rectangle {
                min: (0.0, 0.0),
                max: (0.55, 0.55),
            }),
            Box::new(Shape::Disk {
                center: (0.6, 0.6),
                radius: 0.1,
            }),
        );
        // Exact: the square minus the disk's corner part [0.5, 0.55]², the latter by the
        // single-primitive closed form (validated on its own above).
        let corner = disk_volume(0.1, -0.2, -0.05, -0.2, -0.05, (1.0, 0.0));
        let v = s.volume_in((0.0, 1.0), (0.0, 1.0), false);
        let exact = 0.55 * 0.55 - corner;
        // One cell covering the whole box: sub-cells of 2^-18, error ≲ their area.
        assert!((v - exact).abs() < 1e-10, "{v} vs {exact}");
        // On a grid of cells the unresolved sub-cells are 400× smaller.
        let g = Grid::new(Geometry::Planar, 20, 20, (0.0, 1.0), (0.0, 1.0));
        let mut phi = Field::zeros(&g);
        fill_fraction(&g, &s, &mut phi);
        let t = total(&g, &phi);
        assert!((t - exact).abs() < 1e-14, "{t} vs {exact}: {:e}", t - exact);
    }

    #[test]
    fn validation_names_the_problem() {
        assert!(
            Shape::Disk {
                center: (0.0, 0.0),
                radius: -1.0
            }
            .validate()
            .unwrap_err()
            .contains("radius")
        );
        assert!(Shape::Union(vec![]).validate().is_err());
        assert!(
            Shape::HalfPlane {
                normal: (0.0, 0.0),
                offset: 1.0
            }
            .validate()
            .is_err()
        );
    }
}
