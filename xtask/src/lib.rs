//! What project automation shares with the test suite and the paper's bench: the provenance a
//! benchmark records in its JSON ([`provenance`]) and the rendering of that JSON into the
//! benchmarks page and the bench-paper report ([`bench_page`]). The commands themselves are the
//! `xtask` binary's (`cargo xtask …`).

pub mod bench_page;
pub mod provenance;
