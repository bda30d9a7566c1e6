//! A worker that spins through the world's sub-steps instead of sleeping between them.
//!
//! A world step is 23 sub-steps, each a few parallel regions (the islands' solve, the meters fed
//! beside the next sub-step) between one-thread stages. A rayon worker with nothing to do goes
//! to sleep and takes about a stage to wake; [`with_spinning_helper`] keeps one worker awake for
//! the length of a call: it takes the caller's parallel jobs as soon as they are pushed.
//!
//! It is only safe when the caller is the pool's only work. The helper waits for the caller's
//! flag, so two callers on one pool could each hold the other's helper: deadlock. The runner
//! turns it on for a run of a single job ([`super::Swarm::set_spinning_helper`]). It changes
//! which thread runs a job, never a result: every parallel stage merges in index order.

use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

/// How long the caller waits for a worker to take the helper before going on without it: far
/// beyond a sleeping worker's wake-up, far below a step.
const HELPER_WAIT: Duration = Duration::from_micros(500);

/// Runs `f` on the calling thread while another worker of the current rayon pool spins, taking
/// any job the pool has, until `f` returns. Without a second worker (a one-thread pool, or none
/// free within [`HELPER_WAIT`]) `f` runs as it would alone.
pub(super) fn with_spinning_helper<R: Send>(f: impl FnOnce() -> R + Send) -> R {
    helped(HELPER_WAIT, |_| f()).0
}

/// As [`with_spinning_helper`], waiting up to `wait` for the helper, telling `f` and the caller
/// whether a helper spins.
fn helped<R: Send>(wait: Duration, f: impl FnOnce(bool) -> R + Send) -> (R, bool) {
    if rayon::current_num_threads() < 2 {
        return (f(false), false);
    }
    let done = AtomicBool::new(false);
    let started = AtomicBool::new(false);
    rayon::scope(|sc| {
        sc.spawn(|_| {
            // A helper taken after the caller gave up on it (or finished) has nothing to do.
            if done.load(Ordering::Acquire) {
                return;
            }
            started.store(true, Ordering::Release);
            while !done.load(Ordering::Acquire) {
                if rayon::yield_now() != Some(rayon::Yield::Executed) {
                    // Nothing to take: let the system run another thread on this core if one
                    // waits (a machine with more threads than cores), else go round at once.
                    std::thread::yield_now();
                }
            }
        });
        // The helper sits on this thread's own queue until another worker steals it; were this
        // thread to take it back (a join's wait takes local jobs first) it would spin for
        // itself. So the caller starts only once the helper runs elsewhere, or gives up.
        let t0 = Instant::now();
        while !started.load(Ordering::Acquire) && t0.elapsed() < wait {
            std::hint::spin_loop();
        }
        let helped = started.load(Ordering::Acquire);
        done.store(!helped, Ordering::Release);
        // Set however `f` ends: were it to panic, the scope would otherwise wait for ever for
        // a helper spinning on a flag nobody sets.
        let _release = Release(&done);
        (f(helped), helped)
    })
}

/// Sets its flag when dropped.
struct Release<'a>(&'a AtomicBool);

impl Drop for Release<'_> {
    fn drop(&mut self) {
        self.0.store(true, Ordering::Release);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rayon::prelude::*;

    /// How long the tests wait for a helper where they need one.
    const LONG_WAIT: Duration = Duration::from_secs(10);

    fn sum_of_squares(n: u64) -> u64 {
        (0..n).into_par_iter().map(|k| k * k).sum()
    }

    #[test]
    fn the_result_is_the_callers_on_any_pool() {
        for threads in [1, 2, 3, 8] {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap();
            let (alone, helped) = pool.install(|| {
                (
                    sum_of_squares(100_000),
                    with_spinning_helper(|| {
                        (0..50).map(|k| sum_of_squares(1_000 + k)).sum::<u64>()
                            + sum_of_squares(100_000)
                    }),
                )
            });
            let expect: u64 = (0..50).map(|k| sum_of_squares(1_000 + k)).sum::<u64>() + alone;
            assert_eq!(helped, expect, "{threads} threads");
        }
    }

    #[test]
    fn a_free_worker_spins_and_a_busy_one_is_not_waited_for() {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(2)
            .build()
            .unwrap();
        let one = rayon::ThreadPoolBuilder::new()
            .num_threads(1)
            .build()
            .unwrap();
        // A free worker takes the helper (waited for as long as a loaded machine may need to
        // wake it: the runs wait HELPER_WAIT and go on alone).
        assert_eq!(
            pool.install(|| helped(LONG_WAIT, |_| sum_of_squares(1_000))),
            (332_833_500, true)
        );
        assert_eq!(
            one.install(|| helped(LONG_WAIT, |_| sum_of_squares(1_000))),
            (332_833_500, false)
        );
        // The other worker busy with a job of its own: no helper, and no wait beyond
        // HELPER_WAIT. join runs its first half on the calling worker (busy until released)
        // and its second on the other worker, which steals it and asks for a helper there.
        let busy = AtomicBool::new(false);
        let release = AtomicBool::new(false);
        let (_, (r, spun)) = pool.install(|| {
            rayon::join(
                || {
                    busy.store(true, Ordering::Release);
                    while !release.load(Ordering::Acquire) {
                        std::hint::spin_loop();
                    }
                },
                || {
                    while !busy.load(Ordering::Acquire) {
                        std::hint::spin_loop();
                    }
                    let t0 = Instant::now();
                    let out = helped(HELPER_WAIT, |_| sum_of_squares(1_000));
                    assert!(t0.elapsed() < HELPER_WAIT * 20, "{:?}", t0.elapsed());
                    release.store(true, Ordering::Release);
                    out
                },
            )
        });
        assert_eq!((r, spun), (332_833_500, false));
    }

    #[test]
    fn a_panic_in_f_reaches_the_caller_and_the_helper_stops() {
        let (tx, rx) = std::sync::mpsc::channel();
        // On a thread of its own, so that a helper left spinning fails the test instead of
        // hanging it.
        std::thread::spawn(move || {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(2)
                .build()
                .unwrap();
            // A panic while a helper spins.
            let caught = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
                pool.install(|| {
                    helped(LONG_WAIT, |spins| {
                        assert!(!spins, "a stage failed");
                    })
                })
            }));
            tx.send(caught.is_err()).unwrap();
        });
        assert_eq!(
            rx.recv_timeout(Duration::from_secs(60)),
            Ok(true),
            "the panic did not come back"
        );
    }

    #[test]
    fn called_outside_a_pool_it_returns_f_s_result() {
        // From a thread of no pool rayon::scope runs on the global pool (as many threads as
        // the machine's cores); a helper may or may not be taken, the result is f's either way.
        assert_eq!(with_spinning_helper(|| sum_of_squares(1_000)), 332_833_500);
    }
}
