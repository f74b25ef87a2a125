//! Work vectors shared by the stages of one pipeline.
//!
//! The stages of a step run one after another, so the vectors a stage needs only while it runs
//! — a solver's work vectors, a right-hand side, an initial guess — can live in one pool: the
//! pipeline then holds the largest stage's need instead of the sum of all. What a stage keeps
//! from one step to the next (history, cached coefficients) stays its own.
//!
//! The pool is a pipeline resource ([`efsi_core::Resources`]): each stage reserves what it
//! needs when it is built (the only time the pool grows, so a step allocates nothing) and
//! locks the pool while it runs. Nothing in the pool survives a stage's run: a stage writes
//! every entry it reads before reading it.

use efsi_core::Resources;
use std::sync::{Arc, Mutex, MutexGuard};

/// A handle on the pipeline's pool of work vectors.
#[derive(Clone)]
pub(crate) struct Scratch(Arc<Mutex<Vec<Vec<f64>>>>);

impl Scratch {
    /// The pipeline's pool (the first stage built creates it), grown so that it holds at least
    /// `count` vectors of at least `len` values each.
    pub(crate) fn reserve(shared: &mut Resources, count: usize, len: usize) -> Self {
        let pool = shared
            .get_or_try_insert_with(|| Ok::<_, ()>(Scratch(Arc::default())))
            .expect("infallible")
            .clone();
        {
            let mut v = pool.lock();
            if v.len() < count {
                v.resize_with(count, Vec::new);
            }
            for b in &mut v[..count] {
                if b.len() < len {
                    b.resize(len, 0.0);
                }
            }
        }
        pool
    }

    /// The pool, for one stage's run (a panic in another stage does not make it unusable:
    /// its contents carry nothing).
    pub(crate) fn lock(&self) -> MutexGuard<'_, Vec<Vec<f64>>> {
        self.0.lock().unwrap_or_else(|e| e.into_inner())
    }
}

/// The first `N` vectors of the pool, each cut to `len` values.
pub(crate) fn take<const N: usize>(pool: &mut [Vec<f64>], len: usize) -> [&mut [f64]; N] {
    let mut it = pool.iter_mut();
    std::array::from_fn(|_| &mut it.next().expect("reserved at build")[..len])
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_pool_holds_the_largest_need_once() {
        let mut shared = Resources::default();
        let a = Scratch::reserve(&mut shared, 3, 10);
        let b = Scratch::reserve(&mut shared, 2, 25);
        let pool = a.lock();
        assert_eq!(pool.iter().map(Vec::len).collect::<Vec<_>>(), [25, 25, 10]);
        drop(pool);
        let mut pool = b.lock();
        let [x, y] = take::<2>(&mut pool, 7);
        assert_eq!((x.len(), y.len()), (7, 7));
    }
}
