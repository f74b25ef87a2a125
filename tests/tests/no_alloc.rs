//! No heap allocation inside a time step after the first: a counting global allocator (this
//! test binary only) around steps 2..k of a single-fluid cavity (advection, viscous,
//! projection), of a two-phase axisymmetric drop without a solid law (advection, body force,
//! viscous, projection, VOF), at 128² so that the parallel (rayon) paths run, and of the sphere
//! impact touching down (all of those, and the elastic and deformation stages with the plugin
//! law), and of three soft disks, two of them in contact (each body on its own window, the
//! contact stage, the bodies stepped in parallel), stepped inside a
//! two-thread and a one-thread pool (as `efsi run` does: called from outside a pool, rayon
//! queues each job through its global injector, which allocates a block every 63 jobs). Each
//! step is preceded, as in the run loop, by the snapshot of the last good state (into the
//! same snapshot: it reuses its arrays and the stages' saved data).

use efsi_tests::scenes::{CAVITY, DISKS, DROP, SPHERE};
use efsi_tests::sim;
use std::alloc::{GlobalAlloc, Layout, System};
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};

struct Counting;

static COUNTING: AtomicBool = AtomicBool::new(false);
static ALLOCATIONS: AtomicUsize = AtomicUsize::new(0);

// SAFETY: forwards to the system allocator; only counts.
unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        if COUNTING.load(Ordering::Relaxed) {
            ALLOCATIONS.fetch_add(1, Ordering::Relaxed);
        }
        // SAFETY: same contract as the caller's.
        unsafe { System.alloc(layout) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        // SAFETY: same contract as the caller's.
        unsafe { System.dealloc(ptr, layout) }
    }
    unsafe fn alloc_zeroed(&self, layout: Layout) -> *mut u8 {
        if COUNTING.load(Ordering::Relaxed) {
            ALLOCATIONS.fetch_add(1, Ordering::Relaxed);
        }
        // SAFETY: same contract as the caller's.
        unsafe { System.alloc_zeroed(layout) }
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        if COUNTING.load(Ordering::Relaxed) {
            ALLOCATIONS.fetch_add(1, Ordering::Relaxed);
        }
        // SAFETY: same contract as the caller's.
        unsafe { System.realloc(ptr, layout, new_size) }
    }
}

#[global_allocator]
static GLOBAL: Counting = Counting;

/// Allocations during steps 2..=k, per stage set.
fn allocations_after_first_step(text: &str, k: usize) -> usize {
    let mut s = sim(text);
    let dt = s.next_dt(1.0).unwrap();
    let mut last_good = s.snapshot();
    s.step(dt).unwrap();
    ALLOCATIONS.store(0, Ordering::SeqCst);
    COUNTING.store(true, Ordering::SeqCst);
    for _ in 1..k {
        // As the run loop does: the last good state kept before each step.
        s.snapshot_into(&mut last_good);
        s.step(dt).unwrap();
    }
    COUNTING.store(false, Ordering::SeqCst);
    ALLOCATIONS.load(Ordering::SeqCst)
}

#[test]
fn no_allocation_after_the_first_step() {
    // One test function: the counter is global, tests in parallel would pollute it.
    // The drop also with the block-multigrid viscous preconditioner (default: Jacobi).
    let drop_mg = DROP.replace(
        "boundaries:",
        "numerics: (viscous: (preconditioner: Multigrid)),\n    boundaries:",
    );
    let two_phase = [
        "advection",
        "body_force",
        "pressure_predictor",
        "viscous",
        "projection",
        "vof",
    ];
    let solid = [
        "advection",
        "body_force",
        "viscous",
        "elastic",
        "projection",
        "deformation",
        "vof",
    ];
    let bodies = [
        "advection",
        "body_force",
        "contact",
        "viscous",
        "elastic",
        "projection",
        "deformation",
        "vof",
    ];
    for (name, text, stages) in [
        (
            "cavity",
            CAVITY,
            &["advection", "pressure_predictor", "viscous", "projection"][..],
        ),
        ("drop", DROP, &two_phase[..]),
        ("drop-mg", &drop_mg, &two_phase[..]),
        ("sphere", SPHERE, &solid[..]),
        ("disks", DISKS, &bodies[..]),
    ] {
        assert_eq!(sim(text).pipeline().stage_names(), stages);
        let count = |threads| {
            rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap()
                .install(|| allocations_after_first_step(text, 6))
        };
        assert_eq!(
            (count(2), count(1)),
            (0, 0),
            "{name}: heap allocations in steps 2..6 (two threads, one thread)"
        );
    }
}
