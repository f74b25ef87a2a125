//! Initial solid fractions of three-dimensional shapes: `φ = |cell ∩ S| / |cell|`.
//!
//! # How
//!
//! As in two dimensions ([`super::shapes`]), each primitive classifies a cell (an axis-aligned
//! box) as inside, outside or cut, and integrates itself over a cut box:
//! - **box**: the overlap box, exact;
//! - **half-space** `n·x < c`: Scardovelli & Zaleski's plane–cuboid volume
//!   ([`super::plic3d::cuboid_fraction`]), exact to round-off;
//! - **cylinder** along an axis: the exact area of its disk section in the box's face normal to
//!   the axis (the closed form of the two-dimensional disk) times the overlap length, exact to
//!   round-off;
//! - **sphere**: `∫ A(z) dz` over the box's extent in z, `A(z)` the exact area of the slice
//!   disk of radius `ρ(z) = √(R² − z²)` in the box's x–y rectangle. `A` is smooth between the
//!   heights where the slice circle touches an edge line or passes a corner of the rectangle
//!   (and the poles), where it has algebraic singularities (`(z − z*)^{3/2}`, `√`); the
//!   integral is split at those heights and each piece integrated by tanh-sinh quadrature
//!   (Takahasi & Mori 1974), which converges double-exponentially for integrands analytic
//!   inside the interval whatever their endpoint singularities: with the step `h = 1/8` and 53
//!   nodes per piece, the error is below 1e-13 of the cell's volume (tested against the
//!   analytic volume of the ball and against a fine midpoint sum per cell);
//! - **ellipsoid** (axis-aligned): the unit ball in coordinates scaled by the semi-axes, its
//!   volume times their product.
//!
//! Combinations are exact where at most one of their primitives crosses the box (a cut
//! primitive inside a `Difference`'s subtrahend counts as its complement). Where two or more
//! boundaries cross a box (the rim of a slot) it is split in eight, recursively, to sub-boxes
//! of `h/2^10`, an unresolved sub-box decided by its centre; the error there is of order the
//! volume of the unresolved sub-boxes along the crossing curve, ≲ 2^10 · 2^−30 ≈ 1e-6 of the
//! cell (less where the signs of their errors alternate). [`MAX_SPLITS`] splits per cell bound
//! the work.
//!
//! A two-dimensional primitive on a three-dimensional grid (refused by the scene check) is its
//! extrusion along z, classified by point membership.
//!
//! References: R. Scardovelli & S. Zaleski (2000), J. Comput. Phys. 164:228 (the plane–cuboid
//! volume); H. Takahasi & M. Mori (1974), *Double exponential formulas for numerical
//! integration*, Publ. RIMS Kyoto Univ. 9:721–741; the three-dimensional slotted sphere is that
//! of Enright et al. (2002), J. Comput. Phys. 183:83.

use super::plic3d::cuboid_fraction;
use super::shapes::{Coverage, combine, disk_volume};
use crate::solid::Shape;
use efsi_core::{Field, Grid, Region, Stagger};

/// Deepest recursive split of a cell crossed by two or more boundaries.
pub const MAX_DEPTH: u32 = 10;
/// Most splits spent on one cell before the remaining sub-boxes are decided by their centre.
pub const MAX_SPLITS: u32 = 20_000;

/// An axis-aligned box `[lo, hi]`.
#[derive(Clone, Copy, Debug)]
pub struct Cuboid {
    /// Lowest corner.
    pub lo: [f64; 3],
    /// Highest corner.
    pub hi: [f64; 3],
}

impl Cuboid {
    /// Its volume.
    pub fn volume(&self) -> f64 {
        (self.hi[0] - self.lo[0]) * (self.hi[1] - self.lo[1]) * (self.hi[2] - self.lo[2])
    }

    fn centre(&self) -> [f64; 3] {
        std::array::from_fn(|a| 0.5 * (self.lo[a] + self.hi[a]))
    }

    fn octants(&self) -> [Cuboid; 8] {
        let m = self.centre();
        std::array::from_fn(|k| {
            let mut b = *self;
            for a in 0..3 {
                if k >> a & 1 == 0 {
                    b.hi[a] = m[a];
                } else {
                    b.lo[a] = m[a];
                }
            }
            b
        })
    }
}

/// How a shape covers a box.
#[derive(Clone, Copy, Debug)]
enum Cover<'a> {
    In,
    Out,
    /// Crossed by the boundary of one primitive only: the covered part is that primitive's
    /// part of the box, or (`true`) its complement.
    Cut(&'a Shape, bool),
    /// Crossed by several boundaries.
    Mixed,
}

impl Coverage for Cover<'_> {
    const IN: Self = Cover::In;
    const OUT: Self = Cover::Out;
    const MIXED: Self = Cover::Mixed;
    fn is(&self, inside: bool) -> bool {
        matches!((self, inside), (Cover::In, true) | (Cover::Out, false))
    }
}

/// The exact volume `|S ∩ b|` of `shape` in the box `b`, up to the limits in the module docs.
pub fn volume_in(shape: &Shape, b: Cuboid) -> f64 {
    let mut budget = MAX_SPLITS;
    volume(shape, b, MAX_DEPTH, &mut budget)
}

fn volume(shape: &Shape, b: Cuboid, depth: u32, budget: &mut u32) -> f64 {
    match cover(shape, &b) {
        Cover::In => b.volume(),
        Cover::Out => 0.0,
        Cover::Cut(p, complement) => {
            let all = b.volume();
            let v = primitive_volume(p, &b).clamp(0.0, all);
            if complement { all - v } else { v }
        }
        Cover::Mixed => {
            if depth == 0 || *budget == 0 {
                let [x, y, z] = b.centre();
                if shape.contains3(x, y, z) {
                    b.volume()
                } else {
                    0.0
                }
            } else {
                *budget -= 1;
                b.octants()
                    .iter()
                    .map(|o| volume(shape, *o, depth - 1, budget))
                    .sum()
            }
        }
    }
}

/// Nearest and farthest squared distances from the origin to the points of `[lo, hi]`.
fn near_far(lo: &[f64], hi: &[f64]) -> (f64, f64) {
    let (mut near, mut far) = (0.0, 0.0);
    for (l, h) in lo.iter().zip(hi) {
        let n = l.max(0.0).max(-h);
        let f = l.abs().max(h.abs());
        near += n * n;
        far += f * f;
    }
    (near, far)
}

/// `box` relative to `c` and scaled by `1/s` per axis.
fn relative(b: &Cuboid, c: [f64; 3], s: [f64; 3]) -> ([f64; 3], [f64; 3]) {
    (
        std::array::from_fn(|a| (b.lo[a] - c[a]) / s[a]),
        std::array::from_fn(|a| (b.hi[a] - c[a]) / s[a]),
    )
}

/// In, out or cut for a ball of radius `r` about the origin.
fn ball_cover(lo: &[f64], hi: &[f64], r: f64) -> Option<bool> {
    let (near, far) = near_far(lo, hi);
    if near >= r * r {
        Some(false)
    } else if far <= r * r {
        Some(true)
    } else {
        None
    }
}

fn cover<'a>(shape: &'a Shape, b: &Cuboid) -> Cover<'a> {
    let of = |inside: Option<bool>| match inside {
        Some(true) => Cover::In,
        Some(false) => Cover::Out,
        None => Cover::Cut(shape, false),
    };
    match shape {
        Shape::Sphere { center, radius } => {
            let (lo, hi) = relative(b, (*center).into(), [1.0; 3]);
            of(ball_cover(&lo, &hi, *radius))
        }
        Shape::Ellipsoid { center, semi_axes } => {
            let (lo, hi) = relative(b, (*center).into(), (*semi_axes).into());
            of(ball_cover(&lo, &hi, 1.0))
        }
        Shape::Box { min, max } => {
            let (min, max): ([f64; 3], [f64; 3]) = ((*min).into(), (*max).into());
            if (0..3).any(|a| b.lo[a].max(min[a]) >= b.hi[a].min(max[a])) {
                Cover::Out
            } else if (0..3).all(|a| min[a] <= b.lo[a] && b.hi[a] <= max[a]) {
                Cover::In
            } else {
                Cover::Cut(shape, false)
            }
        }
        Shape::Cylinder {
            axis,
            center,
            radius,
            length,
        } => {
            let (lo, hi) = relative(b, (*center).into(), [1.0; 3]);
            let a = axis.index();
            let half = 0.5 * length;
            if lo[a] >= half || hi[a] <= -half {
                return Cover::Out;
            }
            let (e, f) = ((a + 1) % 3, (a + 2) % 3);
            match ball_cover(&[lo[e], lo[f]], &[hi[e], hi[f]], *radius) {
                Some(false) => Cover::Out,
                Some(true) if -half <= lo[a] && hi[a] <= half => Cover::In,
                _ => Cover::Cut(shape, false),
            }
        }
        Shape::HalfSpace { normal, offset } => {
            let n: [f64; 3] = (*normal).into();
            // The lowest and highest values of n·x over the box's corners.
            let (mut lo, mut hi) = (0.0, 0.0);
            for a in 0..3 {
                let (p, q) = (n[a] * b.lo[a], n[a] * b.hi[a]);
                lo += p.min(q);
                hi += p.max(q);
            }
            if hi <= *offset {
                Cover::In
            } else if lo >= *offset {
                Cover::Out
            } else {
                Cover::Cut(shape, false)
            }
        }
        Shape::Disk { .. } | Shape::Rectangle { .. } | Shape::HalfPlane { .. } => Cover::Mixed,
        Shape::Union(v) => combine(v.iter().map(|s| cover(s, b)), true),
        Shape::Intersection(v) => combine(v.iter().map(|s| cover(s, b)), false),
        Shape::Difference(p, q) => match (cover(p, b), cover(q, b)) {
            (_, Cover::In) | (Cover::Out, _) => Cover::Out,
            (c, Cover::Out) => c,
            (Cover::In, Cover::Cut(s, complement)) => Cover::Cut(s, !complement),
            _ => Cover::Mixed,
        },
    }
}

/// The exact volume of a three-dimensional primitive in the box `b`.
fn primitive_volume(shape: &Shape, b: &Cuboid) -> f64 {
    match shape {
        Shape::Sphere { center, radius } => {
            let (lo, hi) = relative(b, (*center).into(), [1.0; 3]);
            ball_volume(*radius, lo, hi)
        }
        Shape::Ellipsoid { center, semi_axes } => {
            let s: [f64; 3] = (*semi_axes).into();
            let (lo, hi) = relative(b, (*center).into(), s);
            ball_volume(1.0, lo, hi) * s[0] * s[1] * s[2]
        }
        Shape::Box { min, max } => {
            let (min, max): ([f64; 3], [f64; 3]) = ((*min).into(), (*max).into());
            (0..3)
                .map(|a| (b.hi[a].min(max[a]) - b.lo[a].max(min[a])).max(0.0))
                .product()
        }
        Shape::Cylinder {
            axis,
            center,
            radius,
            length,
        } => {
            let (lo, hi) = relative(b, (*center).into(), [1.0; 3]);
            let a = axis.index();
            let (e, f) = ((a + 1) % 3, (a + 2) % 3);
            let half = 0.5 * length;
            let along = (hi[a].min(half) - lo[a].max(-half)).max(0.0);
            along * disk_volume(*radius, lo[e], hi[e], lo[f], hi[f], (1.0, 0.0))
        }
        Shape::HalfSpace { normal, offset } => {
            let n: [f64; 3] = (*normal).into();
            let alpha = offset - (n[0] * b.lo[0] + n[1] * b.lo[1] + n[2] * b.lo[2]);
            let d = std::array::from_fn(|a| b.hi[a] - b.lo[a]);
            cuboid_fraction(n, alpha, d) * b.volume()
        }
        _ => unreachable!("cover() cuts three-dimensional primitives only"),
    }
}

/// Step of the tanh-sinh rule on `[−1, 1]`.
const TS_H: f64 = 0.125;
/// Nodes `k = −TS_N..=TS_N`: `k h = 3.25`, where the weights are below 1e-30.
const TS_N: i32 = 26;

/// `∫_a^b f` by the tanh-sinh rule: nodes `x_k = tanh(½π sinh(kh))`, weights
/// `½π cosh(kh) / cosh²(½π sinh(kh))`, the node's distances to both ends formed without
/// cancellation.
fn tanh_sinh(a: f64, b: f64, f: impl Fn(f64) -> f64) -> f64 {
    let half = std::f64::consts::FRAC_PI_2;
    let l = b - a;
    let mut s = 0.0;
    for k in -TS_N..=TS_N {
        let t = k as f64 * TS_H;
        let u = half * t.sinh();
        let c = u.cosh();
        let w = half * t.cosh() / (c * c);
        // (1 + x)/2 = 1/(1 + e^{−2u}), (1 − x)/2 = 1/(1 + e^{2u}).
        let (from_a, from_b) = (
            1.0 / (1.0 + (-2.0 * u).exp()),
            1.0 / (1.0 + (2.0 * u).exp()),
        );
        let z = if from_a <= 0.5 {
            a + l * from_a
        } else {
            b - l * from_b
        };
        if z > a && z < b {
            s += w * f(z);
        }
    }
    0.5 * l * TS_H * s
}

/// `|B_r ∩ [lo, hi]|` for the ball of radius `r` about the origin: `∫ A(z) dz`, split where the
/// slice circle touches an edge line or passes a corner of the x–y rectangle (module docs).
fn ball_volume(r: f64, lo: [f64; 3], hi: [f64; 3]) -> f64 {
    let (z0, z1) = (lo[2].max(-r), hi[2].min(r));
    if z0 >= z1 {
        return 0.0;
    }
    // Squared distances from the axis to the rectangle's edge lines and corners.
    let (xs, ys) = ([lo[0], hi[0]], [lo[1], hi[1]]);
    let mut d2 = [0.0f64; 8];
    for k in 0..2 {
        d2[k] = xs[k] * xs[k];
        d2[2 + k] = ys[k] * ys[k];
        for (m, y) in ys.iter().enumerate() {
            d2[4 + 2 * k + m] = xs[k] * xs[k] + y * y;
        }
    }
    let mut pts = [0.0f64; 2 + 2 * 8];
    let mut n = 0;
    for p in [z0, z1] {
        pts[n] = p;
        n += 1;
    }
    for d2 in d2 {
        if d2 < r * r {
            let d = d2.sqrt();
            let z = ((r - d) * (r + d)).sqrt();
            for z in [-z, z] {
                if z > z0 && z < z1 {
                    pts[n] = z;
                    n += 1;
                }
            }
        }
    }
    let pts = &mut pts[..n];
    pts.sort_by(f64::total_cmp);
    // The slice disk's area in the rectangle, ρ(z) = √((r − |z|)(r + |z|)).
    let area = |z: f64| {
        let rho = ((r - z.abs()).max(0.0) * (r + z.abs())).sqrt();
        if rho > 0.0 {
            disk_volume(rho, lo[0], hi[0], lo[1], hi[1], (1.0, 0.0))
        } else {
            0.0
        }
    };
    pts.windows(2)
        .filter(|w| w[1] > w[0])
        .map(|w| tanh_sinh(w[0], w[1], area))
        .sum()
}

/// Set the interior of `phi` on the three-dimensional `grid` to the fraction of each cell
/// covered by `shape`, lines in parallel. Ghost cells are left untouched.
pub fn fill_fraction(grid: &Grid, shape: &Shape, phi: &mut Field) {
    Region::of(grid, Stagger::Cell).for_each(phi, |l, phi| {
        for (f, [i, j, k]) in phi.iter_mut().zip(l.indices()) {
            let b = Cuboid {
                lo: [grid.xf(i), grid.yf(j), grid.zf(k)],
                hi: [grid.xf(i + 1), grid.yf(j + 1), grid.zf(k + 1)],
            };
            *f = (volume_in(shape, b) / b.volume()).clamp(0.0, 1.0);
        }
    });
}
