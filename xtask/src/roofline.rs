//! `cargo xtask bench --roofline`: how close each stage comes to the machine's memory bandwidth.
//!
//! **The limit** is measured in the same run: the STREAM triad `a = b + s·c` over arrays far
//! larger than the caches (3 × 128 MiB: main memory) and over arrays that fit in the last-level
//! cache (3 × 512 KiB), on one thread and on the bench's thread count, best of 10 passes, counting
//! 24 bytes per element as STREAM does (the write-allocate read not counted). The threads are
//! started once and a pass repeats the cache-sized triad up to 32 MiB, between two barriers (a
//! thread start per pass would be timed with the cache figure). The triad is compiled at
//! opt-level 3 like efsi's kernels (`[profile.dev.package.xtask]` in the workspace's
//! `Cargo.toml`: `cargo xtask` builds in the dev profile, whose opt-level 1 leaves the loop
//! unvectorised and the limits too low).
//!
//! **The traffic** of a stage is a model of its *compulsory* memory traffic per cell and step:
//! each array the stage's kernels must stream counted once per pass, 8 bytes per value, a
//! velocity-like vector counted as one value per component and cell (u-, v- and, in three
//! dimensions, w-faces), a symmetric tensor's edge components likewise. A stage's bytes
//! per cell-step are `8 (F + I·k)` with `F` the values streamed once per step, `I` those streamed
//! per solver iteration and `k` the measured iterations per step ([`MODELS`] states `F` and `I`
//! for each stage, with the passes they count; the viscous and elastic stages have a second
//! model for the block-multigrid preconditioner, which the bench picks for the cases that use
//! it; a three-dimensional scene's stages have their own models, which count the third
//! velocity component, the six-coefficient operators, the seven-point pressure stencil with
//! its coarsening by eight and the full-grid flux arrays of the third axis). Anything a kernel
//! reads twice from memory, or
//! stencils whose neighbours miss the cache, is traffic the model does not count: the achieved
//! bandwidth `bytes / time` is a lower bound, and its fraction of the triad bandwidth says how
//! far the stage is from being limited by memory traffic alone (near 1: only fewer passes or
//! fewer bytes can make it faster; far below 1: latency, arithmetic, reductions or serial parts
//! dominate).

use std::time::Instant;

/// The traffic model of one stage: values per cell streamed once per step and per iteration.
pub struct Model {
    /// The stage's name as in `run.json`.
    pub stage: &'static str,
    /// Values per cell streamed once per step.
    pub fixed: f64,
    /// Values per cell streamed per solver iteration.
    pub per_iteration: f64,
    /// Whether this is the stage's model with the block-multigrid preconditioner
    /// (`numerics.*.preconditioner: Multigrid`) rather than Jacobi.
    pub block_multigrid: bool,
    /// Whether this is the stage's model on a three-dimensional grid.
    pub three_d: bool,
    /// What the counts are.
    pub passes: &'static str,
}

/// One block-multigrid application, both blocks (u–u and v–v, one unknown per cell each), in
/// values per cell: per block a V(1,1)-cycle on the finest level streams the right-hand side in
/// and the correction out (4), two red–black sweeps and one residual (each: diagonal, two
/// couplings, x, b read and one written: 6 × 3 = 18), restriction (1.25) and prolongation
/// (2.25), ≈ 25.5; the coarse levels add a third (factor-2 coarsening in 2-D): ≈ 34 per block.
const BLOCK_MG_APPLICATION: f64 = 68.0;

/// The same in three dimensions, all three blocks (u–u, v–v, w–w): per block the finest level's
/// right-hand side in and correction out (4), two red–black sweeps and one residual of the
/// seven-point stencil (diagonal, three couplings, x, b read and one written: 7 × 3 = 21),
/// restriction (1.125) and prolongation (2.125), ≈ 28; the coarse levels add a seventh
/// (factor-8 coarsening): ≈ 32 per block.
const BLOCK_MG_APPLICATION_3D: f64 = 96.0;

/// The models of the shipped stages (see the module docs).
pub const MODELS: &[Model] = &[
    Model {
        stage: "advection",
        fixed: 10.0,
        per_iteration: 0.0,
        block_multigrid: false,
        three_d: false,
        passes: "SSP-RK2, two stages, each reading u, v, ρ and writing u, v",
    },
    Model {
        stage: "body_force",
        fixed: 4.0,
        per_iteration: 0.0,
        block_multigrid: false,
        three_d: false,
        passes: "u, v read and written",
    },
    Model {
        stage: "viscous",
        fixed: 24.0,
        per_iteration: 25.0,
        block_multigrid: false,
        three_d: false,
        passes: "step: ρ, μ read; coefficients cxx, cyy, g, corner μ written; mass, dm, diagonal \
                 (2 each) written; right-hand side (u, v, 3 coefficients, hoop 2, rhs 2); warm \
                 start and update (δ history 4, u, v); per CG iteration: the product (x 2, \
                 coefficients 3, dm 2, y 2) and the fused vector updates (x, p, q, r, diagonal \
                 read, x, r, p written: 16)",
    },
    Model {
        stage: "elastic",
        fixed: 30.0,
        per_iteration: 50.0,
        block_multigrid: false,
        three_d: false,
        passes: "step: u, v, ρ, μ, φ, B̃ (4) read, u, v, B̃ (4) written, right-hand side, mass, \
                 diagonal, viscous coefficients (2 + 2 + 2 + 5); per BiCGSTAB iteration: two \
                 products (x 2, viscous coefficients 3, dm 2, y 2, fields scattered 2: 11 each; \
                 the tangent inside the solid not counted), two Jacobi applications (r, d, z: \
                 6 each) and the vector updates (r, r₀, p, v, s, t, x: 16)",
    },
    Model {
        stage: "viscous",
        fixed: 24.0 + 20.0,
        per_iteration: 9.0 + BLOCK_MG_APPLICATION + 16.0,
        block_multigrid: true,
        three_d: false,
        passes: "as Jacobi's, plus the set-up of the blocks (coefficients of both blocks and \
                 their coarse levels: ≈ 20); per CG iteration: the product (9), one \
                 block-multigrid application (both blocks, V(1,1): ≈ 68) and the vector \
                 updates (16)",
    },
    Model {
        stage: "elastic",
        fixed: 30.0 + 20.0,
        per_iteration: 50.0 - 12.0 + 2.0 * BLOCK_MG_APPLICATION,
        block_multigrid: true,
        three_d: false,
        passes: "as Jacobi's, plus the set-up of the blocks (≈ 20); per BiCGSTAB iteration \
                 the two Jacobi applications (12) replaced by two block-multigrid applications \
                 (both blocks, V(1,1): ≈ 68 each)",
    },
    Model {
        stage: "projection",
        fixed: 18.0,
        per_iteration: 53.0,
        block_multigrid: false,
        three_d: false,
        passes: "step: u, v, ρ, p read, u, v, p written, divergence, five-point coefficients \
                 (3) and the coarse levels' (≈ 3 more); per CG iteration: the product (3 \
                 coefficients, x, y), the vector updates (8) and one multigrid W-cycle ≈ 2 × \
                 the finest level's smoothing (2 sweeps × 6), residual (5), transfers (3)",
    },
    Model {
        stage: "deformation",
        fixed: 11.0,
        per_iteration: 0.0,
        block_multigrid: false,
        three_d: false,
        passes: "u, v, φ, B̃ (4) read, B̃ (4) written",
    },
    Model {
        stage: "vof",
        fixed: 12.0,
        per_iteration: 0.0,
        block_multigrid: false,
        three_d: false,
        passes: "u, v, φ read; the interface normal (2) and two directional sweeps of φ (read, \
                 written: 4); φ, ρ, μ written",
    },
    Model {
        stage: "pressure_predictor",
        fixed: 6.0,
        per_iteration: 0.0,
        block_multigrid: false,
        three_d: false,
        passes: "p, ρ, u, v read, u, v written",
    },
    Model {
        stage: "pressure_predictor",
        fixed: 8.0,
        per_iteration: 0.0,
        block_multigrid: false,
        three_d: true,
        passes: "p, ρ, u, v, w read, u, v, w written",
    },
    Model {
        stage: "advection",
        fixed: 14.0 + 24.0,
        per_iteration: 0.0,
        block_multigrid: false,
        three_d: true,
        passes: "SSP-RK2, two stages, each reading u, v, w, ρ and writing u, v, w (14); per stage \
                 and component the mass and momentum fluxes along z, which the kernels keep in \
                 two full-grid arrays, written and read (4 × 3 × 2 = 24)",
    },
    Model {
        stage: "body_force",
        fixed: 6.0,
        per_iteration: 0.0,
        block_multigrid: false,
        three_d: true,
        passes: "u, v, w read and written",
    },
    Model {
        stage: "viscous",
        fixed: 41.0,
        per_iteration: 39.0,
        block_multigrid: false,
        three_d: true,
        passes: "step: ρ, μ read; coefficients c_x, c_y, c_z, the edge weights g_xy, g_yz, g_xz \
                 and the three edge viscosities written (9); mass, dm, diagonal (3 each) \
                 written; right-hand side (u, v, w, 6 coefficients, rhs 3 written); warm start \
                 and update (δ history 6, u, v, w); per CG iteration: the product (x 3, \
                 coefficients 6, dm 3, y 3) and the fused vector updates (x, p, q, r, diagonal \
                 read, x, r, p written: 8 × 3 = 24)",
    },
    Model {
        stage: "projection",
        fixed: 15.0,
        per_iteration: 46.0,
        block_multigrid: false,
        three_d: true,
        passes: "step: u, v, w, ρ, p read, u, v, w, p written, divergence, seven-point \
                 coefficients (4) and the coarse levels' (≈ 1: each level an eighth); per CG \
                 iteration: the product (4 coefficients, x, y), the vector updates (8) and one \
                 multigrid W-cycle ≈ 4/3 × the finest level's smoothing (2 sweeps × 7), \
                 residual (7), transfers (3): ≈ 32",
    },
    Model {
        stage: "elastic",
        fixed: 45.0,
        per_iteration: 78.0,
        block_multigrid: false,
        three_d: true,
        passes: "step: u, v, w, ρ, μ, φ, B̃ (6) read, u, v, w, B̃ (6) written, right-hand side, \
                 mass, diagonal (3 each), viscous coefficients (3 + 6 edge weights); per \
                 BiCGSTAB iteration: two products (x 3, viscous coefficients 6, dm 3, y 3, \
                 fields scattered 3: 18 each; the tangent inside the solid not counted), two \
                 Jacobi applications (r, d, z: 9 each) and the vector updates (r, r₀, p, v, s, \
                 t, x: 24)",
    },
    Model {
        stage: "elastic",
        fixed: 45.0 + 30.0,
        per_iteration: 78.0 - 18.0 + 2.0 * BLOCK_MG_APPLICATION_3D,
        block_multigrid: true,
        three_d: true,
        passes: "as Jacobi's, plus the set-up of the three blocks (coefficients and coarse \
                 levels: ≈ 30); per BiCGSTAB iteration the two Jacobi applications (18) replaced \
                 by two block-multigrid applications (three blocks, V(1,1): ≈ 96 each)",
    },
    Model {
        stage: "deformation",
        fixed: 16.0,
        per_iteration: 0.0,
        block_multigrid: false,
        three_d: true,
        passes: "u, v, w, φ, B̃ (6) read, B̃ (6) written",
    },
    Model {
        stage: "vof",
        fixed: 16.0,
        per_iteration: 0.0,
        block_multigrid: false,
        three_d: true,
        passes: "u, v, w, φ read; the interface normal (3) and three directional sweeps of φ \
                 (read, written: 6); φ, ρ, μ written",
    },
];

/// The model of `stage` on a grid of two or (`three_d`) three dimensions — the block-multigrid
/// one where `block_multigrid` and the stage has one — if there is one. A two-dimensional model
/// never stands in for a three-dimensional one.
pub fn model(stage: &str, block_multigrid: bool, three_d: bool) -> Option<&'static Model> {
    let of = |m: &&Model| m.stage == stage && m.three_d == three_d;
    MODELS
        .iter()
        .filter(of)
        .find(|m| m.block_multigrid == block_multigrid)
        .or_else(|| MODELS.iter().find(of))
}

/// Bytes per cell-step of `m` at `iterations` solver iterations per step.
pub fn bytes(m: &Model, iterations: f64) -> f64 {
    8.0 * (m.fixed + m.per_iteration * iterations)
}

/// STREAM triad bandwidth (bytes per second, 24 per element) over three arrays of `n` values
/// each on `threads` threads (each thread its own contiguous part, this one the first), best of
/// 10 passes (each repeated up to 32 MiB of traffic). The threads are started once and meet
/// at a barrier before and after each pass, so a pass times the triad, not the start of
/// threads (which cost more than a cache-sized pass).
pub fn triad(n: usize, threads: usize) -> f64 {
    const PASSES: usize = 10;
    let threads = threads.max(1);
    let mut a = vec![0.0f64; n];
    let b: Vec<f64> = (0..n).map(|k| k as f64).collect();
    let c: Vec<f64> = (0..n).map(|k| (n - k) as f64).collect();
    let chunk = n.div_ceil(threads);
    let parts = n.div_ceil(chunk);
    let barrier = std::sync::Barrier::new(parts);
    // Each timed pass repeats the triad until it moves ≥ 32 MiB, so that the barriers' cost
    // (tens of µs on a VM) stays small beside a cache-sized pass.
    let reps = ((32usize << 20) / (24 * n.max(1))).max(1);
    let triad = |a: &mut [f64], b: &[f64], c: &[f64]| {
        for _ in 0..reps {
            for ((a, b), c) in a.iter_mut().zip(b).zip(c) {
                *a = b + 3.0 * c;
            }
            std::hint::black_box(&mut *a);
        }
    };
    let mut best = f64::INFINITY;
    std::thread::scope(|s| {
        let mut pieces = a
            .chunks_mut(chunk)
            .zip(b.chunks(chunk))
            .zip(c.chunks(chunk));
        // This thread does the first part and times the passes; the others do the rest.
        let ((a0, b0), c0) = pieces.next().expect("n > 0");
        for ((a, b), c) in pieces {
            let barrier = &barrier;
            s.spawn(move || {
                for _ in 0..PASSES {
                    barrier.wait();
                    triad(a, b, c);
                    barrier.wait();
                }
            });
        }
        for _ in 0..PASSES {
            barrier.wait();
            let t0 = Instant::now();
            triad(a0, b0, c0);
            barrier.wait();
            best = best.min(t0.elapsed().as_secs_f64());
        }
    });
    // Keep the result alive so the passes are not optimised away.
    assert!(a[n / 2].is_finite());
    24.0 * (n * reps) as f64 / best
}

/// The measured limits on `threads` threads: (main memory, last-level cache) in bytes/s.
pub fn limits(threads: usize) -> (f64, f64) {
    (triad(16 << 20, threads), triad(64 << 10, threads))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_shipped_stage_has_a_model_and_bytes_grow_with_iterations() {
        for s in [
            "advection",
            "body_force",
            "pressure_predictor",
            "viscous",
            "elastic",
            "projection",
            "deformation",
            "vof",
        ] {
            for mg in [false, true] {
                let m = model(s, mg, false).unwrap_or_else(|| panic!("no model for {s}"));
                assert_eq!(m.stage, s);
                assert!(m.fixed > 0.0);
                assert!(bytes(m, 10.0) >= bytes(m, 0.0));
            }
        }
        assert_eq!(
            bytes(model("viscous", false, false).unwrap(), 2.0),
            8.0 * (24.0 + 50.0)
        );
        // The block multigrid's models are their own, and a stage without one falls back.
        for s in ["viscous", "elastic"] {
            let (j, mg) = (
                model(s, false, false).unwrap(),
                model(s, true, false).unwrap(),
            );
            assert!(mg.block_multigrid && !j.block_multigrid);
            assert!(mg.per_iteration > j.per_iteration);
        }
        assert!(!model("projection", true, false).unwrap().block_multigrid);
    }

    #[test]
    fn the_stages_of_a_three_dimensional_scene_have_their_own_models() {
        // Every stage that runs in 3-D has a 3-D model; stages that do not have none, and no
        // 2-D model stands in for one.
        for s in [
            "advection",
            "body_force",
            "pressure_predictor",
            "viscous",
            "projection",
            "vof",
            "elastic",
            "deformation",
        ] {
            let (two, three) = (
                model(s, false, false).unwrap(),
                model(s, false, true).unwrap(),
            );
            assert!(three.three_d && !two.three_d, "{s}");
        }
        let b = |s: &str, it: f64| bytes(model(s, false, true).unwrap(), it);
        assert_eq!(b("body_force", 0.0), 8.0 * 6.0);
        assert_eq!(b("advection", 0.0), 8.0 * 38.0);
        assert_eq!(b("viscous", 2.0), 8.0 * (41.0 + 78.0));
        assert_eq!(b("deformation", 0.0), 8.0 * 16.0);
        let e = model("elastic", true, true).unwrap();
        assert!(e.block_multigrid && e.three_d);
        assert_eq!(bytes(e, 1.0), 8.0 * (75.0 + 252.0));
    }

    #[test]
    fn the_triad_measures_a_plausible_bandwidth() {
        // Anything from an old laptop to a large server: 0.5 GB/s to 2 TB/s; on three threads
        // too (more than some machines' cores: the barriers must still release every pass).
        for threads in [1, 3] {
            let bw = triad(1 << 16, threads);
            assert!(bw > 5e8 && bw < 2e12, "{threads} threads: {bw}");
        }
    }
}
