//! Volume-of-fluid PLIC transport of the solid fraction φ_s (seed Fig. 1, step 5).
//!
//! - [`advect`]: geometric, direction-split, mass-conserving advection (Weymouth & Yue 2010) on a
//!   prescribed MAC velocity, planar and axisymmetric ([`VofAdvector`]).
//! - [`stage`]: the stage plugin ([`Vof`]): φ_s transport and the two-material ρ, μ.
//!
//! - [`plic`]: PLIC lines in cells, Youngs normals (also used by the elastic stage's interface
//!   corners); [`shapes`]: the exact cell fractions of a scene's [`Shape`] (the initial φ_s).
//! - [`plic3d`]: the same geometry in three dimensions: the plane–cuboid volume and its
//!   inverse, the fluxed volume of a split sweep, Youngs / centred / mixed normals;
//!   [`shapes3d`]: the cell fractions of the three-dimensional shapes.

pub mod advect;
pub mod plic;
pub mod plic3d;
pub mod shapes;
pub mod shapes3d;
pub mod stage;

pub use crate::solid::Shape;
pub use advect::{AdvectStats, VofAdvector, VofBoundaries, VofSide, phase_volume};
pub use efsi_core::scene::solid::Axis;
pub use shapes::{ShapeVolume, fill_fraction, section_width};
pub use stage::Vof;
