//! Volume-of-fluid PLIC transport of the solid fraction φ_s (seed Fig. 1, step 5).
//!
//! - [`advect`]: geometric, direction-split, mass-conserving advection (Weymouth & Yue 2010) on a
//!   prescribed MAC velocity, planar and axisymmetric ([`VofAdvector`]).
//! - [`stage`]: the stage plugin ([`Vof`]): φ_s transport and the two-material ρ, μ.
//!
//! The interface geometry (PLIC lines, Youngs normals, exact shape fractions) is in
//! [`efsi_core::interface`], shared with scenes and probes.

pub mod advect;
pub mod stage;

pub use advect::{AdvectStats, VofAdvector, VofBoundaries, VofSide, phase_volume};
pub use efsi_core::interface::{Shape, fill_fraction};
pub use stage::Vof;
