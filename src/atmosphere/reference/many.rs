//! Many cases on every core: the one place the reference's work is spread over threads.

use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::Mutex;

use super::{Case, Estimate, Reference};
use crate::support::progress::Cancelled;

/// The reference's estimate of every `(reference, case)` job, on every core.
///
/// Jobs are taken one at a time from a shared counter: their costs differ by an order of
/// magnitude (twilight, long horizontal rays, a target standard error met early or late), so
/// fixed chunks would leave cores idle. With fewer jobs than cores, each job's paths are drawn
/// on several threads ([`Reference::estimate_on`]; the same result on any number).
/// `progress(done, total)` is called after each job; an error from it stops the work.
pub fn estimate_many(jobs: &[(&Reference, Case)], progress: &(dyn Fn(usize, usize) -> Result<(), Cancelled> + Sync)) -> Result<Vec<Estimate>, Cancelled> {
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    let workers = cores.min(jobs.len().max(1));
    let threads_per_job = (cores / jobs.len().max(1)).max(1);
    let done = AtomicUsize::new(0);
    let next = AtomicUsize::new(0);
    let stopped = AtomicBool::new(false);
    let results = Mutex::new(vec![None; jobs.len()]);
    std::thread::scope(|scope| {
        for _ in 0..workers {
            scope.spawn(|| loop {
                if stopped.load(Ordering::Relaxed) {
                    break;
                }
                let i = next.fetch_add(1, Ordering::Relaxed);
                let Some((reference, case)) = jobs.get(i) else { break };
                let e = reference.estimate_on(case, threads_per_job);
                results.lock().unwrap_or_else(|p| p.into_inner())[i] = Some(e);
                if progress(done.fetch_add(1, Ordering::Relaxed) + 1, jobs.len()).is_err() {
                    stopped.store(true, Ordering::Relaxed);
                }
            });
        }
    });
    if stopped.into_inner() {
        return Err(Cancelled);
    }
    Ok(results.into_inner().unwrap_or_else(|p| p.into_inner()).into_iter().flatten().collect())
}
