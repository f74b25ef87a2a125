//! When an output is written: its [`Schedule`], the half of a `(schedule, writer)` pair that
//! the run loop lands Δt on.
//!
//! Every kind of output of a run (the VTK series, `probes.csv`, each line profile, the
//! periodic checkpoint) is a schedule and a writer ([`crate::run::Writer`]). A schedule says
//! whether its writer is due at a time, advances past the events it consumed and names the
//! next time the run must land on; it counts events by computing them, not one period at a
//! time, so that a period tiny against the time costs nothing.

use efsi_core::due;

/// When an output is written.
#[derive(Clone, Debug, PartialEq)]
pub enum Schedule {
    /// After every step, and at the end of the run.
    EveryStep,
    /// At the multiples `n·every` of simulated time (`count` is the next `n`), landing Δt on
    /// each, and at the end of the run.
    Every {
        /// The period (s of simulated time).
        every: f64,
        /// The number of events due so far: the next is at `count·every`.
        count: u64,
    },
    /// At the multiples `n·every` of simulated time (`count` is the next `n`) at the end of
    /// the first step that reaches each, without changing Δt, and not at the end of the run:
    /// the periodic checkpoint, so that a run with checkpoints is bit-identical to one without.
    Reached {
        /// The period (s of simulated time).
        every: f64,
        /// The number of events due so far: the next is at `count·every`.
        count: u64,
    },
    /// At the given times still to come (ascending), landing Δt on each; at the end of the
    /// run if none is left. A time the run ends before (at its end time or a steady state) is
    /// written at the end instead ([`Due::missed`]).
    Times(Vec<f64>),
}

/// What a [`Schedule`] says at a time ([`Schedule::take`]).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Due {
    /// Whether the writer writes now.
    pub write: bool,
    /// The times of a [`Schedule::Times`] that the run ended before: written now instead.
    pub missed: Vec<f64>,
}

impl Schedule {
    /// The schedule of period `every` ([`Schedule::Every`]), or after every step without one.
    pub fn every(every: Option<f64>) -> Schedule {
        match every {
            Some(every) => Schedule::Every { every, count: 0 },
            None => Schedule::EveryStep,
        }
    }

    /// The schedule of `times` in any order ([`Schedule::Times`]).
    pub fn times(times: &[f64]) -> Schedule {
        let mut times = times.to_vec();
        times.sort_by(f64::total_cmp);
        Schedule::Times(times)
    }

    /// The next time after the events consumed that the run must land on, if any.
    pub fn next(&self) -> Option<f64> {
        match self {
            Schedule::Every { every, count } => Some(*count as f64 * every),
            Schedule::Times(times) => times.first().copied(),
            Schedule::EveryStep | Schedule::Reached { .. } => None,
        }
    }

    /// The number of events consumed so far (0 for a schedule that does not count them).
    pub fn count(&self) -> u64 {
        match self {
            Schedule::Every { count, .. } | Schedule::Reached { count, .. } => *count,
            _ => 0,
        }
    }

    /// The times still to come (empty for a schedule that has none).
    pub fn remaining(&self) -> &[f64] {
        match self {
            Schedule::Times(times) => times,
            _ => &[],
        }
    }

    /// Whether the writer is due at time `t` (`last`: the run's final state), consuming the
    /// events due by `t`.
    pub fn take(&mut self, t: f64, last: bool) -> Due {
        match self {
            Schedule::EveryStep => Due {
                write: true,
                missed: Vec::new(),
            },
            Schedule::Every { every, count } => {
                let write = due(t, *count as f64 * *every) || last;
                if write {
                    *count = events_due(t, *every, *count);
                }
                Due {
                    write,
                    missed: Vec::new(),
                }
            }
            Schedule::Reached { every, count } => {
                let write = due(t, *count as f64 * *every);
                if write {
                    *count = events_due(t, *every, *count);
                }
                Due {
                    write,
                    missed: Vec::new(),
                }
            }
            Schedule::Times(times) => {
                let is_due = times.first().is_some_and(|&tt| due(t, tt));
                let at_end = last && times.is_empty();
                let reached = times.iter().take_while(|&&tt| due(t, tt)).count();
                times.drain(..reached);
                let missed = if last {
                    std::mem::take(times)
                } else {
                    Vec::new()
                };
                Due {
                    write: is_due || at_end || !missed.is_empty(),
                    missed,
                }
            }
        }
    }
}

/// The number of events of period `every` due by time `t` ([`due`]), at least `count`: the
/// smallest `n ≥ count` whose event `n·every` is not yet due. Computed, not counted, so that a
/// period tiny against `t` costs nothing: whatever the arguments, a bounded number of steps.
pub fn events_due(t: f64, every: f64, count: u64) -> u64 {
    // `due(t, x)` holds for x ≤ t / (1 − 1e-9) when x ≥ 1e-12, and for x ≤ t + 1e-21 below
    // (its absolute floor): start past the latest such x, then correct the rounding by single
    // steps. The start is capped at 2⁵³, where n·every stops being exact.
    const EXACT: f64 = 9_007_199_254_740_992.0;
    let reach = (t / (1.0 - 1e-9)).max((t + 1e-21).min(1e-12));
    let start = (reach / every).floor() + 1.0;
    let mut n = if start >= 0.0 {
        start.min(EXACT) as u64
    } else {
        0
    }
    .max(count);
    for _ in 0..64 {
        if n > count && !due(t, (n - 1) as f64 * every) {
            n -= 1;
        } else {
            break;
        }
    }
    for _ in 0..64 {
        if due(t, n as f64 * every) {
            n = n.saturating_add(1);
        } else {
            break;
        }
    }
    n
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::time::Instant;

    /// The counter as the loop `while due(t, n·e) { n += 1 }` would leave it.
    fn counted(t: f64, e: f64, mut n: u64) -> u64 {
        while due(t, n as f64 * e) {
            n += 1;
        }
        n
    }

    #[test]
    fn events_due_equals_counting_and_costs_nothing_for_tiny_periods() {
        for (t, e, n) in [
            (0.0, 0.1, 0),
            (0.0, 0.1, 1),
            (0.3, 0.1, 1),
            (0.30000000000000004, 0.1, 2),
            (0.29999999999, 0.1, 1),
            (1.0, 0.25, 3),
            (40.0, 2.0, 0),
            (1e-3, 1e-7, 5),
            (7.0, 3.0, 9),
        ] {
            assert_eq!(
                events_due(t, e, n),
                counted(t, e, n),
                "t = {t}, e = {e}, n = {n}"
            );
        }
        // 1e12 events due at once: computed, not counted.
        let t0 = Instant::now();
        let n = events_due(1.0, 1e-12, 1);
        assert!(t0.elapsed().as_secs_f64() < 0.01);
        assert!(due(1.0, (n - 1) as f64 * 1e-12) && !due(1.0, n as f64 * 1e-12));
        // Periods under `due`'s absolute floor (1e-21) at t = 0, periods of 1e-300 at any time,
        // NaN: a bounded number of steps, at least the count.
        for (t, e) in [(0.0, 1e-300), (1e-12, 1e-300), (1.0, 1e-300)] {
            let n = events_due(t, e, 1);
            assert!(
                n > 1 << 53 && due(t, (n - 1) as f64 * e),
                "t = {t}, e = {e}"
            );
        }
        assert_eq!(events_due(1.0, f64::NAN, 7), 7);
        assert_eq!(events_due(0.0, 1e-22, 0), counted(0.0, 1e-22, 0));
    }

    #[test]
    fn periodic_schedules_land_on_their_multiples_and_the_end() {
        let mut s = Schedule::every(Some(0.25));
        assert_eq!(
            (s.take(0.0, false).write, s.count(), s.next()),
            (true, 1, Some(0.25))
        );
        assert_eq!((s.take(0.1, false).write, s.count()), (false, 1));
        // Three periods passed at once are consumed together; the end writes off period.
        assert_eq!(
            (s.take(0.8, false).write, s.count(), s.next()),
            (true, 4, Some(1.0))
        );
        assert_eq!((s.take(0.9, true).write, s.count()), (true, 4));
        let mut s = Schedule::every(None);
        assert_eq!((s.take(0.1, false).write, s.next()), (true, None));
        // Reached: not at the end, and never a time to land on.
        let mut s = Schedule::Reached {
            every: 0.5,
            count: 1,
        };
        assert_eq!((s.take(0.3, true).write, s.next()), (false, None));
        assert_eq!((s.take(1.2, false).write, s.count()), (true, 3));
    }

    #[test]
    fn a_times_schedule_writes_at_its_times_and_what_the_run_missed_at_the_end() {
        let mut s = Schedule::times(&[0.5, 0.2, 2.0]);
        assert_eq!(s.remaining(), &[0.2, 0.5, 2.0]);
        assert_eq!(s.next(), Some(0.2));
        assert!(!s.take(0.1, false).write);
        // Two times reached by one step: one write.
        assert_eq!(
            s.take(0.6, false),
            Due {
                write: true,
                missed: vec![]
            }
        );
        assert_eq!(s.remaining(), &[2.0]);
        // The run ends at 1.0, before 2.0: written at the end, and the time named.
        assert_eq!(
            s.take(1.0, true),
            Due {
                write: true,
                missed: vec![2.0]
            }
        );
        assert_eq!((s.remaining(), s.next()), (&[][..], None));
        // A profile without times is written at the end only.
        let mut s = Schedule::times(&[]);
        assert!(!s.take(0.5, false).write);
        assert_eq!(
            s.take(1.0, true),
            Due {
                write: true,
                missed: vec![]
            }
        );
    }
}
