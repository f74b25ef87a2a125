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

/// A handle on the pipeline's pool: one block of values that a running stage cuts into its
/// work vectors ([`take`]).
#[derive(Clone)]
pub(crate) struct Scratch(Arc<Mutex<Vec<f64>>>);

impl Scratch {
    /// The pipeline's pool (the first stage built creates it), grown to at least `len` values.
    pub(crate) fn reserve(shared: &mut Resources, len: usize) -> Self {
        let pool = shared
            .get_or_try_insert_with(|| Ok::<_, ()>(Scratch(Arc::default())))
            .expect("infallible")
            .clone();
        {
            let mut v = pool.lock();
            if v.len() < len {
                // Exactly `len`: the pool is sized by the largest need, not grown by doubling.
                let more = len - v.len();
                v.reserve_exact(more);
                v.resize(len, 0.0);
            }
        }
        pool
    }

    /// The pool, for one stage's run (a panic in another stage does not make it unusable:
    /// its contents carry nothing).
    pub(crate) fn lock(&self) -> MutexGuard<'_, Vec<f64>> {
        self.0.lock().unwrap_or_else(|e| e.into_inner())
    }
}

/// `N` consecutive vectors of `len` values from the start of the pool (reserved at build with
/// at least `N × len` values).
pub(crate) fn take<const N: usize>(pool: &mut [f64], len: usize) -> [&mut [f64]; N] {
    let mut rest = &mut pool[..N * len];
    std::array::from_fn(|_| {
        let (head, tail) = std::mem::take(&mut rest).split_at_mut(len);
        rest = tail;
        head
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_pool_holds_the_largest_need_once() {
        let mut shared = Resources::default();
        let a = Scratch::reserve(&mut shared, 30);
        let b = Scratch::reserve(&mut shared, 50);
        let _ = Scratch::reserve(&mut shared, 20);
        assert_eq!(a.lock().len(), 50);
        let mut pool = b.lock();
        let [x, y] = take::<2>(&mut pool, 7);
        x[6] = 1.0;
        y[0] = 2.0;
        assert_eq!(&pool[6..8], [1.0, 2.0]);
    }
}
