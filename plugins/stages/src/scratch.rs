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
//!
//! Work fields — padded like the state's, for stencils that read ghosts — are pooled the same
//! way ([`FieldScratch`]): the viscous solve's search direction and the projection's pressure
//! increment are one stage's work each, so the pipeline holds the larger need once. A stage
//! swaps the fields into its own places for its run and back after it (no copy), and zeroes
//! them before use.

use efsi_core::{Field, Grid, Resources};
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

/// A handle on the pipeline's pool of work fields (module docs).
#[derive(Clone)]
pub(crate) struct FieldScratch(Arc<Mutex<Vec<Field>>>);

impl FieldScratch {
    /// The pipeline's pool of work fields (the first stage that asks creates it), grown to at
    /// least `n` fields of `grid`.
    pub(crate) fn reserve(shared: &mut Resources, grid: &Grid, n: usize) -> Self {
        let pool = shared
            .get_or_try_insert_with(|| Ok::<_, ()>(FieldScratch(Arc::default())))
            .expect("infallible")
            .clone();
        {
            let mut v = pool.lock();
            while v.len() < n {
                v.push(Field::zeros(grid));
            }
        }
        pool
    }

    /// The pool, for one stage's run.
    pub(crate) fn lock(&self) -> MutexGuard<'_, Vec<Field>> {
        self.0.lock().unwrap_or_else(|e| e.into_inner())
    }

    /// Swap the first `mine.len()` fields of the pool with `mine` (into a stage's places for
    /// its run, or back after it), zeroing those that come in when `zero`.
    pub(crate) fn swap(&self, mine: &mut [Field], zero: bool) {
        let mut pool = self.lock();
        for (m, p) in mine.iter_mut().zip(pool.iter_mut()) {
            std::mem::swap(m, p);
            if zero {
                m.fill(0.0);
            }
        }
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

    #[test]
    fn the_field_pool_lends_its_fields_zeroed_and_takes_them_back() {
        let grid = Grid::new_3d([4, 3, 2], (0.0, 1.0), (0.0, 1.0), (0.0, 1.0));
        let mut shared = Resources::default();
        let a = FieldScratch::reserve(&mut shared, &grid, 1);
        let b = FieldScratch::reserve(&mut shared, &grid, 3);
        assert_eq!(a.lock().len(), 3);
        let mut mine = vec![Field::default(), Field::default()];
        b.swap(&mut mine, true);
        assert!(
            mine.iter()
                .all(|f| f.data().len() == Field::zeros(&grid).data().len())
        );
        mine[1].fill(2.0);
        b.swap(&mut mine, false);
        assert!(mine.iter().all(|f| f.data().is_empty()));
        let mut one = [Field::default()];
        a.swap(&mut one, false);
        assert!(one[0].data().iter().all(|&x| x == 0.0));
        a.swap(&mut one, false);
        let mut two = [Field::default(), Field::default()];
        a.swap(&mut two, true);
        assert!(
            two[1].data().iter().all(|&x| x == 0.0),
            "zeroed on the way in"
        );
    }
}
