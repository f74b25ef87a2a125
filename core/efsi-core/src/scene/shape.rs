//! The shapes a scene's solid is made of ([`Shape`]): their parameters, checks and
//! point membership. Their exact cell fractions are the VOF stage's (crate `efsi-stages`).
//!
//! A shape is two-dimensional (`Disk`, `Rectangle`, `HalfPlane`: regions of the x–y plane, or
//! of the r–z half-plane in axisymmetric geometry) or three-dimensional (`Sphere`,
//! `Ellipsoid`, `Box`, `Cylinder`, `HalfSpace`: regions of x–y–z space); the combinations
//! (`Union`, `Intersection`, `Difference`) take the dimension of their parts, which must agree
//! ([`Shape::dims`]).

use serde::{Deserialize, Serialize};

/// A region of the plane (x–y, or r–z in axisymmetric geometry) or of space, as written in
/// scenes.
///
/// ```ron
/// Difference(
///     Disk(center: (0.5, 0.75), radius: 0.15),
///     Rectangle(min: (0.475, 0.5), max: (0.525, 0.85)),
/// )
/// Difference(
///     Sphere(center: (0.5, 0.75, 0.5), radius: 0.15),
///     Box(min: (0.475, 0.5, 0.0), max: (0.525, 0.725, 1.0)),
/// )
/// Cylinder(axis: Z, center: (0.5, 0.5, 0.5), radius: 0.1, length: 0.4)
/// ```
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub enum Shape {
    /// The open disk `|x − center| < radius` (a sphere when centred on the axis, a torus off it).
    Disk {
        /// Centre `(x, y)` (or `(r, z)`).
        center: (f64, f64),
        /// Radius, > 0.
        radius: f64,
    },
    /// The axis-aligned rectangle `min < x < max` (a cylinder or annulus when axisymmetric).
    Rectangle {
        /// Lower-left corner.
        min: (f64, f64),
        /// Upper-right corner.
        max: (f64, f64),
    },
    /// The half-plane `normal · x < offset` (`normal` need not be unit, must be non-zero).
    HalfPlane {
        /// Outward normal.
        normal: (f64, f64),
        /// Offset `c` in `normal · x < c`.
        offset: f64,
    },
    /// The open ball `|x − center| < radius` (three dimensions).
    Sphere {
        /// Centre `(x, y, z)`.
        center: (f64, f64, f64),
        /// Radius, > 0.
        radius: f64,
    },
    /// The open axis-aligned ellipsoid `Σ ((x_i − center_i)/semi_axes_i)² < 1` (three
    /// dimensions).
    Ellipsoid {
        /// Centre `(x, y, z)`.
        center: (f64, f64, f64),
        /// Semi-axes along x, y and z, each > 0.
        semi_axes: (f64, f64, f64),
    },
    /// The open axis-aligned box `min < x < max` (three dimensions).
    Box {
        /// Lowest corner.
        min: (f64, f64, f64),
        /// Highest corner.
        max: (f64, f64, f64),
    },
    /// The open circular cylinder of `radius` around the line through `center` along `axis`,
    /// `length` long and centred on `center` (three dimensions).
    Cylinder {
        /// The axis the cylinder's own axis is parallel to.
        axis: Axis,
        /// Centre `(x, y, z)`.
        center: (f64, f64, f64),
        /// Radius, > 0.
        radius: f64,
        /// Length along the axis, > 0.
        length: f64,
    },
    /// The half-space `normal · x < offset` (three dimensions; `normal` non-zero).
    HalfSpace {
        /// Outward normal.
        normal: (f64, f64, f64),
        /// Offset `c` in `normal · x < c`.
        offset: f64,
    },
    /// Points in any of the shapes.
    Union(Vec<Shape>),
    /// Points in all of the shapes.
    Intersection(Vec<Shape>),
    /// Points in the first shape and not in the second.
    Difference(Box<Shape>, Box<Shape>),
}

/// A coordinate axis (a [`Shape::Cylinder`]'s direction).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum Axis {
    /// Along x.
    X,
    /// Along y.
    Y,
    /// Along z.
    Z,
}

impl Axis {
    /// The axis' index: 0, 1 or 2.
    pub fn index(self) -> usize {
        match self {
            Axis::X => 0,
            Axis::Y => 1,
            Axis::Z => 2,
        }
    }
}

impl Shape {
    /// The shape's dimension: 2 for `Disk`, `Rectangle` and `HalfPlane`, 3 for `Sphere`,
    /// `Ellipsoid`, `Box`, `Cylinder` and `HalfSpace`, that of their parts for the
    /// combinations (a combination of parts of both dimensions is refused by [`Shape::check`];
    /// here it counts as three-dimensional).
    pub fn dims(&self) -> usize {
        match self {
            Shape::Disk { .. } | Shape::Rectangle { .. } | Shape::HalfPlane { .. } => 2,
            Shape::Sphere { .. }
            | Shape::Ellipsoid { .. }
            | Shape::Box { .. }
            | Shape::Cylinder { .. }
            | Shape::HalfSpace { .. } => 3,
            Shape::Union(v) | Shape::Intersection(v) => {
                v.iter().map(Shape::dims).max().unwrap_or(2)
            }
            Shape::Difference(a, b) => a.dims().max(b.dims()),
        }
    }

    /// Check the parameters: positive radii, semi-axes and lengths, non-empty rectangles and
    /// boxes, non-zero normals, finite numbers, non-empty unions and intersections whose parts
    /// all have the same dimension.
    pub fn validate(&self) -> Result<(), String> {
        self.check().map_err(|(_, m)| m)
    }

    /// [`Shape::validate`], with where the fault is below the shape as a path suffix
    /// (`.radius`, `[1].center`, empty for the shape itself): the setting to name, and to
    /// blame an override for.
    pub fn check(&self) -> Result<(), (String, String)> {
        let at = |field: &str, m: String| Err((field.to_string(), m));
        match self {
            Shape::Disk { center, radius } => {
                centre("Disk", &[center.0, center.1], format!("{center:?}"))?;
                positive("Disk", "radius", *radius)?;
            }
            Shape::Rectangle { min, max } => {
                let shown = format!("{min:?}, {max:?}");
                ordered("Rectangle", &[min.0, min.1], &[max.0, max.1], shown)?;
            }
            Shape::HalfPlane { normal, offset } => {
                plane(
                    "HalfPlane",
                    &[normal.0, normal.1],
                    *offset,
                    format!("{normal:?}"),
                )?;
            }
            Shape::Sphere { center, radius } => {
                centre(
                    "Sphere",
                    &[center.0, center.1, center.2],
                    format!("{center:?}"),
                )?;
                positive("Sphere", "radius", *radius)?;
            }
            Shape::Ellipsoid { center, semi_axes } => {
                centre(
                    "Ellipsoid",
                    &[center.0, center.1, center.2],
                    format!("{center:?}"),
                )?;
                let a = [semi_axes.0, semi_axes.1, semi_axes.2];
                if !a.iter().all(|&a| a.is_finite() && a > 0.0) {
                    return at(
                        ".semi_axes",
                        format!("Ellipsoid: semi_axes must be finite and > 0, got {semi_axes:?}"),
                    );
                }
            }
            Shape::Box { min, max } => {
                let shown = format!("{min:?}, {max:?}");
                ordered("Box", &[min.0, min.1, min.2], &[max.0, max.1, max.2], shown)?;
            }
            Shape::Cylinder {
                center,
                radius,
                length,
                ..
            } => {
                centre(
                    "Cylinder",
                    &[center.0, center.1, center.2],
                    format!("{center:?}"),
                )?;
                positive("Cylinder", "radius", *radius)?;
                positive("Cylinder", "length", *length)?;
            }
            Shape::HalfSpace { normal, offset } => {
                let n = [normal.0, normal.1, normal.2];
                plane("HalfSpace", &n, *offset, format!("{normal:?}"))?;
            }
            Shape::Union(v) | Shape::Intersection(v) => {
                if v.is_empty() {
                    return at("", "Union/Intersection: needs at least one shape".into());
                }
                for (k, s) in v.iter().enumerate() {
                    s.check().map_err(|(f, m)| (format!("[{k}]{f}"), m))?;
                }
                Self::same_dims(v.iter())?;
            }
            Shape::Difference(a, b) => {
                a.check().map_err(|(f, m)| (format!("[0]{f}"), m))?;
                b.check().map_err(|(f, m)| (format!("[1]{f}"), m))?;
                Self::same_dims([&**a, &**b].into_iter())?;
            }
        }
        Ok(())
    }

    /// An error naming the first part whose dimension differs from the first part's.
    fn same_dims<'a>(parts: impl Iterator<Item = &'a Shape>) -> Result<(), (String, String)> {
        let mut first = None;
        for (k, s) in parts.enumerate() {
            let d = s.dims();
            match first {
                None => first = Some(d),
                Some(f) if f != d => {
                    return Err((
                        format!("[{k}]"),
                        format!(
                            "a {d}-D shape combined with a {f}-D one: the parts of a combination \
                             are all two-dimensional or all three-dimensional"
                        ),
                    ));
                }
                _ => {}
            }
        }
        Ok(())
    }

    /// Whether the point `(x, y)` is inside the two-dimensional shape (a three-dimensional
    /// shape: its section `z = 0`).
    pub fn contains(&self, x: f64, y: f64) -> bool {
        self.contains3(x, y, 0.0)
    }

    /// Whether the point `(x, y, z)` is inside the shape (a two-dimensional shape: its
    /// extrusion along z).
    pub fn contains3(&self, x: f64, y: f64, z: f64) -> bool {
        match self {
            Shape::Sphere { center, radius } => {
                let (a, b, c) = (x - center.0, y - center.1, z - center.2);
                a * a + b * b + c * c < radius * radius
            }
            Shape::Ellipsoid { center, semi_axes } => {
                let a = (x - center.0) / semi_axes.0;
                let b = (y - center.1) / semi_axes.1;
                let c = (z - center.2) / semi_axes.2;
                a * a + b * b + c * c < 1.0
            }
            Shape::Box { min, max } => {
                min.0 < x && x < max.0 && min.1 < y && y < max.1 && min.2 < z && z < max.2
            }
            Shape::Cylinder {
                axis,
                center,
                radius,
                length,
            } => {
                let p = [x - center.0, y - center.1, z - center.2];
                let a = axis.index();
                let (e, f) = (p[(a + 1) % 3], p[(a + 2) % 3]);
                e * e + f * f < radius * radius && p[a].abs() < 0.5 * length
            }
            Shape::HalfSpace { normal, offset } => {
                normal.0 * x + normal.1 * y + normal.2 * z < *offset
            }
            Shape::Disk { center, radius } => {
                let (a, b) = (x - center.0, y - center.1);
                a * a + b * b < radius * radius
            }
            Shape::Rectangle { min, max } => min.0 < x && x < max.0 && min.1 < y && y < max.1,
            Shape::HalfPlane { normal, offset } => normal.0 * x + normal.1 * y < *offset,
            Shape::Union(v) => v.iter().any(|s| s.contains3(x, y, z)),
            Shape::Intersection(v) => v.iter().all(|s| s.contains3(x, y, z)),
            Shape::Difference(a, b) => a.contains3(x, y, z) && !b.contains3(x, y, z),
        }
    }
}

/// A shape's centre `c` (written as `shown`) must be finite; `kind` names the shape.
fn centre(kind: &str, c: &[f64], shown: String) -> Result<(), (String, String)> {
    if c.iter().all(|x| x.is_finite()) {
        Ok(())
    } else {
        Err((
            ".center".into(),
            format!("{kind}: center must be finite, got {shown}"),
        ))
    }
}

/// A box's corners `lo` < `hi` (written as `shown`), all finite; the fault is the max corner's
/// unless the min corner is not finite.
fn ordered(kind: &str, lo: &[f64], hi: &[f64], shown: String) -> Result<(), (String, String)> {
    let fin = |v: &[f64]| v.iter().all(|x| x.is_finite());
    if fin(lo) && fin(hi) && lo.iter().zip(hi).all(|(a, b)| a < b) {
        return Ok(());
    }
    let field = if fin(lo) { ".max" } else { ".min" };
    Err((field.into(), format!("{kind}: need min < max, got {shown}")))
}

/// A shape's length `name` must be finite and positive.
fn positive(kind: &str, name: &str, v: f64) -> Result<(), (String, String)> {
    if v.is_finite() && v > 0.0 {
        Ok(())
    } else {
        Err((
            format!(".{name}"),
            format!(
                "{kind}: {name} must be finite and > 0, got {}",
                crate::scene::num(v)
            ),
        ))
    }
}

/// A half-plane's or half-space's offset must be finite and its normal `n` (written as
/// `shown`) finite and non-zero.
fn plane(kind: &str, n: &[f64], offset: f64, shown: String) -> Result<(), (String, String)> {
    if !offset.is_finite() {
        return Err((
            ".offset".into(),
            format!(
                "{kind}: offset must be finite, got {}",
                crate::scene::num(offset)
            ),
        ));
    }
    if !n.iter().all(|x| x.is_finite()) || n.iter().all(|&c| c == 0.0) {
        return Err((
            ".normal".into(),
            format!("{kind}: normal must be finite and non-zero, got {shown}"),
        ));
    }
    Ok(())
}
