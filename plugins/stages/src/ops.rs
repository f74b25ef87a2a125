//! The discrete operators the stages share, defined by the framework ([`efsi_core::ops`]) and
//! re-exported here under the name the stages use.

pub use efsi_core::ops::*;
