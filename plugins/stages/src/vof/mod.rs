//! Volume-of-fluid PLIC transport of the solid fraction φ_s (seed Fig. 1, step 5).
//!
//! - [`plic`]: the interface line in a cell — Youngs normals, the analytic fraction ↔ line
//!   relations (Scardovelli & Zaleski 2000), fractions of sub-rectangles, and their exact
//!   r-weighted (axisymmetric) counterparts.
//! - [`advect`]: geometric, direction-split, mass-conserving advection (Weymouth & Yue 2010) on a
//!   prescribed MAC velocity, planar and axisymmetric ([`VofAdvector`]).
//! - [`shapes`]: initial fractions of disks/spheres, rectangles, half-planes and their
//!   combinations ([`Shape`], [`fill_fraction`]).

pub mod advect;
pub mod plic;
pub mod shapes;

pub use advect::{AdvectStats, VofAdvector, VofBoundaries, VofSide, phase_volume};
pub use shapes::{Shape, fill_fraction};
