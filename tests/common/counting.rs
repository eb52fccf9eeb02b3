//! A counting allocator for the tests that measure memory (tests/memory.rs,
//! tests/bop_memory.rs). Each such binary installs it:
//! `#[global_allocator] static ALLOCATOR: Counting = Counting;`. It counts the bytes live and
//! their peak on each thread, and over every thread; signed, since a block one thread made may
//! be freed by another.

use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;
use std::sync::atomic::{AtomicIsize, Ordering};

pub struct Counting;

thread_local! {
    static THREAD_LIVE: Cell<isize> = const { Cell::new(0) };
    static THREAD_PEAK: Cell<isize> = const { Cell::new(0) };
}

static LIVE: AtomicIsize = AtomicIsize::new(0);
static PEAK: AtomicIsize = AtomicIsize::new(0);

fn note(delta: isize) {
    let _ = THREAD_LIVE.try_with(|live| {
        let now = live.get().wrapping_add(delta);
        live.set(now);
        let _ = THREAD_PEAK.try_with(|peak| peak.set(peak.get().max(now)));
    });
    let now = LIVE.fetch_add(delta, Ordering::Relaxed).wrapping_add(delta);
    PEAK.fetch_max(now, Ordering::Relaxed);
}

// SAFETY: every call is passed on to the system allocator unchanged; the counting only reads
// the sizes.
unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        note(layout.size() as isize);
        // SAFETY: the caller's contract is the system allocator's.
        unsafe { System.alloc(layout) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        note(-(layout.size() as isize));
        // SAFETY: as above.
        unsafe { System.dealloc(ptr, layout) }
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        // Counted as the allocation of the new block before the old one is freed.
        note(new_size as isize);
        note(-(layout.size() as isize));
        // SAFETY: as above.
        unsafe { System.realloc(ptr, layout, new_size) }
    }
}

/// The most bytes this thread held at once while `work` ran, beyond what it held before: for
/// work on the calling thread, in a binary whose other tests run beside it.
pub fn thread_peak_during(work: impl FnOnce()) -> usize {
    let before = THREAD_LIVE.with(Cell::get);
    THREAD_PEAK.with(|peak| peak.set(before));
    work();
    (THREAD_PEAK.with(Cell::get) - before).max(0) as usize
}

/// The most bytes every thread together held at once while `work` ran, beyond what they held
/// before: for work spread over threads, in a binary of one test.
pub fn process_peak_during(work: impl FnOnce()) -> usize {
    let before = LIVE.load(Ordering::Relaxed);
    PEAK.store(before, Ordering::Relaxed);
    work();
    (PEAK.load(Ordering::Relaxed) - before).max(0) as usize
}
