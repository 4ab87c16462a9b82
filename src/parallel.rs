//! Work shared over the cores, on a pool of one thread per core (rayon's,
//! built here, so that neither `RAYON_NUM_THREADS` nor another library
//! sizes it): loading cuts one large job into parts (ranges of vertices,
//! halves of a mesh) that need no coordination; a culler's frame runs a
//! few jobs, each taking its share of the work as it goes. The pool's
//! threads outlive the jobs: a thread started and joined for each job
//! costs about 40 µs on a 2-core machine here (a job handed to the pool,
//! about 12 µs), which `swr` paid three times a frame (some 3 % of a 3 ms
//! frame on the default city).

use std::num::NonZero;
use std::sync::OnceLock;

use rayon::iter::{IntoParallelIterator, ParallelIterator};
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

/// The pool, made on first use; none where the system would not start its
/// threads (then the work runs on the calling thread, in order).
fn pool() -> Option<&'static ThreadPool> {
    static POOL: OnceLock<Option<ThreadPool>> = OnceLock::new();
    POOL.get_or_init(|| {
        ThreadPoolBuilder::new()
            .num_threads(cores())
            .thread_name(|k| format!("occlu-{k}"))
            .build()
            .ok()
    })
    .as_ref()
}

/// `work` applied to every part, the parts in parallel, the results in the
/// parts' order. A panic in any part is raised again here.
pub fn map<P: Send, R: Send>(parts: Vec<P>, work: impl Fn(P) -> R + Sync + Send) -> Vec<R> {
    match pool() {
        Some(pool) => pool.install(|| parts.into_par_iter().map(work).collect()),
        None => parts.into_iter().map(work).collect(),
    }
}

/// `work` run on each of `jobs`, the first on the calling thread and the
/// others on the pool, waiting for them all; it collects no results (a
/// culler's frame calls it, its jobs writing into scratch they own). A
/// panic in any job is raised again here once every job has ended.
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
        assert!(parts_for(1 << 30, 1) >= 1);
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
        assert_eq!(on_caller, [true, false, false, false, false]);
        each(std::iter::empty::<u8>(), |_| unreachable!("no job"));
    }
}
