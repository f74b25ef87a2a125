//! Volume-of-fluid PLIC advection of the solid fraction φ_s.
