//! A bump allocator over a static buffer: enough for one small file, never
//! frees (the program is short-lived).

use core::alloc::{GlobalAlloc, Layout};
use core::cell::UnsafeCell;
use core::ptr;
use core::sync::atomic::{AtomicUsize, Ordering};

/// Bytes available to the whole program.
const HEAP_BYTES: usize = 1 << 20;

#[repr(C, align(16))]
struct Heap(UnsafeCell<[u8; HEAP_BYTES]>);

// SAFETY: the allocator hands out disjoint ranges of the buffer (the atomic
// offset only grows), so no two owners share a byte.
unsafe impl Sync for Heap {}

static HEAP: Heap = Heap(UnsafeCell::new([0; HEAP_BYTES]));

/// Allocates by moving an offset forward; `dealloc` does nothing.
pub struct Bump {
    /// Bytes of `HEAP` handed out so far (including alignment padding).
    used: AtomicUsize,
}

impl Bump {
    /// An allocator with the whole buffer free.
    pub const fn new() -> Self {
        Self {
            used: AtomicUsize::new(0),
        }
    }
}

// SAFETY: every block returned lies inside `HEAP`, is aligned as asked and
// does not overlap another (see `Heap`); null when the buffer is full.
unsafe impl GlobalAlloc for Bump {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        let base = HEAP.0.get().cast::<u8>();
        let mut used = self.used.load(Ordering::Relaxed);
        loop {
            let start = (base as usize + used).next_multiple_of(layout.align()) - base as usize;
            let end = match start.checked_add(layout.size()) {
                Some(end) if end <= HEAP_BYTES => end,
                _ => return ptr::null_mut(),
            };
            match self
                .used
                .compare_exchange_weak(used, end, Ordering::Relaxed, Ordering::Relaxed)
            {
                // SAFETY: `start + size ≤ HEAP_BYTES`, so the block is inside `HEAP`.
                Ok(_) => return unsafe { base.add(start) },
                Err(now) => used = now,
            }
        }
    }

    unsafe fn dealloc(&self, _ptr: *mut u8, _layout: Layout) {}
}
