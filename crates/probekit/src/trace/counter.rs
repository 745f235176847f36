//! A count of the rays a [`super::Tracer`] intersects, cheap from many
//! threads: one cache-line-sized slot per rayon worker (and one for other
//! threads), summed when read. Each ray is counted exactly once whichever
//! thread traces it, so the total is as deterministic as the work.

use std::sync::atomic::{AtomicU64, Ordering};

/// Slots of [`RayCounter`]: more than the worker threads of most machines;
/// threads beyond share slots (still exact, only slower).
const SLOTS: usize = 32;

/// One counter on its own cache line (128 bytes: two lines on x86-64, where
/// the adjacent-line prefetcher pairs them), so threads do not contend.
#[derive(Default)]
#[repr(align(128))]
struct Slot(AtomicU64);

/// Rays traced, counted per thread slot (see the module docs).
pub(crate) struct RayCounter {
    slots: Box<[Slot]>,
}

impl RayCounter {
    /// A counter at zero.
    pub(crate) fn new() -> Self {
        RayCounter {
            slots: (0..SLOTS).map(|_| Slot::default()).collect(),
        }
    }

    /// Counts one ray for the calling thread.
    #[inline]
    pub(crate) fn add_one(&self) {
        let i = rayon::current_thread_index().map_or(0, |i| i + 1) % SLOTS;
        self.slots[i].0.fetch_add(1, Ordering::Relaxed);
    }

    /// Rays counted so far by every thread.
    pub(crate) fn total(&self) -> u64 {
        self.slots.iter().map(|s| s.0.load(Ordering::Relaxed)).sum()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rayon::prelude::*;

    /// Counts from many threads add up exactly.
    #[test]
    fn counts_from_threads_add_up() {
        let c = RayCounter::new();
        (0..10_000).into_par_iter().for_each(|_| c.add_one());
        c.add_one();
        assert_eq!(c.total(), 10_001);
    }
}
