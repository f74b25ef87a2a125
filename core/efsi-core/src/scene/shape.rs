//! The shapes a scene's solid is made of ([`Shape`]): their parameters, checks and
//! point membership. Their exact cell fractions are the VOF stage's (crate `efsi-stages`).

use serde::{Deserialize, Serialize};

/// A region of the plane (x–y, or r–z in axisymmetric geometry), as written in scenes.
///
/// ```ron
/// Difference(
///     Disk(center: (0.5, 0.75), radius: 0.15),
///     Rectangle(min: (0.475, 0.5), max: (0.525, 0.85)),
/// )
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
    /// Points in any of the shapes.
    Union(Vec<Shape>),
    /// Points in all of the shapes.
    Intersection(Vec<Shape>),
    /// Points in the first shape and not in the second.
    Difference(Box<Shape>, Box<Shape>),
}

impl Shape {
    /// Check the parameters: positive radius, non-empty rectangle, non-zero normal, finite
    /// numbers, non-empty unions and intersections.
    pub fn validate(&self) -> Result<(), String> {
        self.check().map_err(|(_, m)| m)
    }

    /// [`Shape::validate`], with where the fault is below the shape as a path suffix
    /// (`.radius`, `[1].center`, empty for the shape itself): the setting to name, and to
    /// blame an override for.
    pub fn check(&self) -> Result<(), (String, String)> {
        use crate::scene::num;
        let fin = |v: &[f64]| v.iter().all(|x| x.is_finite());
        let at = |field: &str, m: String| Err((field.to_string(), m));
        match self {
            Shape::Disk { center, radius } => {
                if !fin(&[center.0, center.1]) {
                    return at(
                        ".center",
                        format!("Disk: center must be finite, got {center:?}"),
                    );
                }
                if !radius.is_finite() || *radius <= 0.0 {
                    return at(
                        ".radius",
                        format!("Disk: radius must be finite and > 0, got {}", num(*radius)),
                    );
                }
            }
            Shape::Rectangle { min, max } => {
                if !fin(&[min.0, min.1, max.0, max.1]) || min.0 >= max.0 || min.1 >= max.1 {
                    let field = if fin(&[min.0, min.1]) { ".max" } else { ".min" };
                    return at(
                        field,
                        format!("Rectangle: need min < max, got {min:?}, {max:?}"),
                    );
                }
            }
            Shape::HalfPlane { normal, offset } => {
                if !fin(&[*offset]) {
                    return at(
                        ".offset",
                        format!("HalfPlane: offset must be finite, got {}", num(*offset)),
                    );
                }
                if !fin(&[normal.0, normal.1]) || (normal.0 == 0.0 && normal.1 == 0.0) {
                    return at(
                        ".normal",
                        format!("HalfPlane: normal must be finite and non-zero, got {normal:?}"),
                    );
                }
            }
            Shape::Union(v) | Shape::Intersection(v) => {
                if v.is_empty() {
                    return at("", "Union/Intersection: needs at least one shape".into());
                }
                for (k, s) in v.iter().enumerate() {
                    s.check().map_err(|(f, m)| (format!("[{k}]{f}"), m))?;
                }
            }
            Shape::Difference(a, b) => {
                a.check().map_err(|(f, m)| (format!("[0]{f}"), m))?;
                b.check().map_err(|(f, m)| (format!("[1]{f}"), m))?;
            }
        }
        Ok(())
    }

    /// Whether the point `(x, y)` is inside the shape.
    pub fn contains(&self, x: f64, y: f64) -> bool {
        match self {
            Shape::Disk { center, radius } => {
                let (a, b) = (x - center.0, y - center.1);
                a * a + b * b < radius * radius
            }
            Shape::Rectangle { min, max } => min.0 < x && x < max.0 && min.1 < y && y < max.1,
            Shape::HalfPlane { normal, offset } => normal.0 * x + normal.1 * y < *offset,
            Shape::Union(v) => v.iter().any(|s| s.contains(x, y)),
            Shape::Intersection(v) => v.iter().all(|s| s.contains(x, y)),
            Shape::Difference(a, b) => a.contains(x, y) && !b.contains(x, y),
        }
    }
}
