//! Work shared over the cores, on a pool of threads that outlive the work
//! (rayon's, built here, so that neither `RAYON_NUM_THREADS` nor another
//! library sizes it): loading cuts one large job into parts (ranges of
//! vertices, halves of a mesh) that need no coordination; a culler's frame
//! runs a few jobs, each taking its share of the work as it goes. A thread
//! started and joined for each job costs about 40 µs on a 2-core machine
//! here, a job handed to the pool about 12 µs; `swr` hands jobs over at
//! three steps a frame.
//!
//! The calling thread takes the first part of every step, `map`'s too, so
//! the pool holds one thread fewer than the cores: with one per core, swr's
//! frame on the default city took 3.06–3.14 ms against 2.86–2.95 (most
//! likely the spare thread spinning for work on the core the caller's
//! serial steps run on). With the caller waiting instead (rayon's parallel
//! iterator inside the pool), loading's closed-solid test of a 16-block
//! city ran five times slower.

use std::num::NonZero;
use std::sync::OnceLock;

use rayon::{ThreadPool, ThreadPoolBuilder};

/// How many parts to cut `work` units into so that each holds at least
/// `least` of them: one per core at most, and at least one.
pub fn parts_for(work: usize, least: usize) -> usize {
    match work / least.max(1) {
        0 | 1 => 1,
        worth => cores().min(worth),
    }
}

/// The cores this process may use, asked once: the answer costs system
/// calls and file reads (cgroup quotas), and loading asks for every mesh.
fn cores() -> usize {
    static CORES: OnceLock<usize> = OnceLock::new();
    *CORES.get_or_init(|| std::thread::available_parallelism().map_or(1, NonZero::get))
}

/// The pool, made on first use: one thread fewer than the cores; none on
/// one core, or where the system would not start its threads (then the
/// work runs on the calling thread, in order).
fn pool() -> Option<&'static ThreadPool> {
    static POOL: OnceLock<Option<ThreadPool>> = OnceLock::new();
    POOL.get_or_init(|| {
        let threads = cores() - 1;
        let pool = ThreadPoolBuilder::new()
            .num_threads(threads)
            .thread_name(|k| format!("occlu-{k}"));
        // (Rayon takes 0 threads for one per core.)
        (threads > 0).then(|| pool.build().ok()).flatten()
    })
    .as_ref()
}

/// `work` applied to every part, the parts in parallel (the first on the
/// calling thread), the results in the parts' order. A panic in any part
/// is raised again here.
pub fn map<P: Send, R: Send>(parts: Vec<P>, work: impl Fn(P) -> R + Sync) -> Vec<R> {
    let mut results: Vec<Option<R>> = parts.iter().map(|_| None).collect();
    each(parts.into_iter().zip(&mut results), |(part, result)| {
        *result = Some(work(part))
    });
    // Every job ran once (a panic in one is raised by `each`).
    results
        .into_iter()
        .map(|result| result.expect("each ran every part"))
        .collect()
}

/// `work` run on each of `jobs`, the first on the calling thread and the
/// others on the pool, waiting for them all; it collects no results (a
/// culler's frame calls it, its jobs writing into scratch they own). A
/// panic in any job is raised again here: once every job has ended, or,
/// with no pool, at once (the jobs after it do not run).
pub fn each<J: Send>(mut jobs: impl Iterator<Item = J>, work: impl Fn(J) + Sync) {
    let Some(pool) = pool() else {
        return jobs.for_each(work);
    };
    let first = jobs.next();
    let work = &work;
    pool.in_place_scope(|scope| {
        for job in jobs {
            scope.spawn(move |_| work(job));
        }
        if let Some(job) = first {
            work(job);
        }
    });
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parts_hold_at_least_the_least_work_and_results_keep_their_order() {
        assert_eq!(parts_for(10, 100), 1);
        assert_eq!(parts_for(0, 100), 1);
        assert_eq!(parts_for(1 << 30, 1), cores());
        let squares = map((0..9u64).collect(), |k| k * k);
        assert_eq!(squares, [0, 1, 4, 9, 16, 25, 36, 49, 64]);
        assert!(map(Vec::<u8>::new(), |k| k).is_empty());
    }

    #[test]
    fn each_runs_every_job_once_the_first_on_the_calling_thread() {
        let caller = std::thread::current().id();
        let mut slots = [(0u32, None); 5];
        each(slots.iter_mut().enumerate(), |(k, slot)| {
            *slot = (slot.0 + 1, Some(std::thread::current().id() == caller));
            assert!(k < 5);
        });
        assert!(slots.iter().all(|(runs, _)| *runs == 1), "{slots:?}");
        let on_caller: Vec<_> = slots.iter().map(|(_, here)| *here == Some(true)).collect();
        // (On one core there is no pool: the caller runs them all.)
        let pooled = cores() > 1;
        assert_eq!(on_caller, [true, !pooled, !pooled, !pooled, !pooled]);
        each(std::iter::empty::<u8>(), |_| unreachable!("no job"));
    }

    #[test]
    fn a_panic_in_a_job_reaches_the_caller_after_the_jobs_before_it_ran() {
        let mut runs = [0u32; 4];
        let result = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
            each(runs.iter_mut().enumerate(), |(k, runs)| {
                *runs += 1;
                assert!(k < 3, "job {k} fails on purpose");
            })
        }));
        assert!(result.is_err(), "the panic was lost");
        assert_eq!(runs, [1; 4]);
    }

    #[test]
    fn jobs_may_share_work_themselves() {
        let mut sums = [0u64; 3];
        each(sums.iter_mut().enumerate(), |(k, sum)| {
            *sum = map((0..5u64).collect(), |part| part * k as u64).iter().sum();
        });
        assert_eq!(sums, [0, 10, 20]);
    }
}
