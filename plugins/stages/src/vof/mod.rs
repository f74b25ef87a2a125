//! Volume-of-fluid PLIC transport of the solid fraction φ_s (seed Fig. 1, step 5).
//!
//! - [`advect`]: geometric, direction-split, mass-conserving advection (Weymouth & Yue 2010) on a
//!   prescribed MAC velocity, planar, axisymmetric and three-dimensional ([`VofAdvector`]).
//! - [`stage`]: the stage plugin ([`Vof`]): φ_s transport and the two-material ρ, μ.
//!
//! - [`plic`]: PLIC lines in cells, Youngs normals (also used by the elastic stage's interface
//!   corners); [`shapes`]: the exact cell fractions of a scene's [`Shape`] (the initial φ_s).
//! - [`plic3d`]: the same geometry in three dimensions: the plane–cuboid volume and its
//!   inverse, the fluxed volume of a split sweep, Youngs / centred / mixed normals;
//!   [`shapes3d`]: the cell fractions of the three-dimensional shapes.
//! - [`bodies`]: several bodies, each body's fraction on its own window of the grid, advanced
//!   by the same kernel (bit for bit the full-grid step), for scenes with `solids: [ … ]`.
//! - [`benchmarks`]: the three-dimensional transport benchmarks (deformation, slotted sphere)
//!   the tests and `cargo xtask bench-paper` run.
//!
//! # Three dimensions
//!
//! The transport is the two-dimensional scheme with a third sweep: per step one sweep per
//! axis, `x, y, z` and `z, y, x` on alternate steps, each moving through every face normal to
//! its axis the phase volume of the upwind cell's slab below its PLIC plane (mixed
//! Youngs–centred normal, Aulisa et al. 2007; the analytic plane–cuboid volume, Scardovelli &
//! Zaleski 2000), with Weymouth & Yue's frozen indicator `c_c` correcting the divergence of
//! each one-dimensional sweep. The same code runs every geometry (one sweep over grid lines and
//! axis shifts); only the reconstruction of a cell and the fraction of a slab differ.
//!
//! **What it guarantees**: the phase volume to round-off for a discretely divergence-free
//! velocity (the per-sweep corrections cancel over a step, and the last sweep takes back a
//! projection residual below 1e-8 of a cell), `0 ≤ φ ≤ 1` to round-off (clipped, the clipped
//! volume given back) when every sweep's Courant number is at most ½, and exact transport of a
//! plane interface by a uniform velocity.
//!
//! **Limits.** Splitting error: the scheme is first order in time per step, second order over
//! a pair of steps, and its shape error converges at close to second order in space only while
//! the interface is resolved; sub-cell filaments break up into droplets (the deformation test
//! near its maximum stretch). The Courant limit is per sweep, `max_d |u_d| Δt / Δx_d ≤ ½`,
//! not on the sum of the components as for unsplit schemes. Normals are those of one 3×3×3
//! block; LVIRA/ELVIRA or height functions would be more accurate at several times the cost.
//!
//! **Tests** (`tests/vof_advection3d.rs`, on the face-averaged prescribed velocities of
//! [`benchmarks`]): LeVeque's / Enright's deformation of a sphere (r = 0.15, period 3) at 32³,
//! the slotted sphere's revolution (Enright et al. 2002) at 32³, and exact translation along
//! every axis through periodic sides; each asserts its shape error, conservation to 1e-12 and
//! the bounds. `cargo xtask bench-paper --case vof_transport_3d` runs the first two at up to
//! 128³ with their observed order and a published comparison.
//!
//! **References**: G. D. Weymouth & D. K.-P. Yue (2010), J. Comput. Phys. 229:2853–2865;
//! E. Aulisa, S. Manservisi, R. Scardovelli & S. Zaleski (2007), J. Comput. Phys.
//! 225:2301–2319; R. Scardovelli & S. Zaleski (2000), J. Comput. Phys. 164:228–237;
//! D. Enright, R. Fedkiw, J. Ferziger & I. Mitchell (2002), J. Comput. Phys. 183:83–116;
//! R. J. LeVeque (1996), *High-resolution conservative algorithms for advection in
//! incompressible flow*, SIAM J. Numer. Anal. 33:627–665.

pub mod advect;
pub mod benchmarks;
pub mod bodies;
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
