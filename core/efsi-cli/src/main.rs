//! The efsi command.
fn main() {}
