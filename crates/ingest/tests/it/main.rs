//! Integration tests of cablab-ingest (one test binary: see BUILD_NOTES on link time).

mod bad_input;
mod classes;
mod fixtures;
mod fuzz;
mod real_logs;
mod sniff;

/// Counts the heap bytes each thread holds, and their peak, so that tests can bound a read's
/// memory (threads run tests in parallel: the counts are per thread).
pub mod mem {
    use std::alloc::{GlobalAlloc, Layout, System};
    use std::cell::Cell;

    struct Counting;

    thread_local! {
        static NOW: Cell<usize> = const { Cell::new(0) };
        static PEAK: Cell<usize> = const { Cell::new(0) };
    }

    fn add(n: usize) {
        let _ = NOW.try_with(|c| {
            let v = c.get() + n;
            c.set(v);
            let _ = PEAK.try_with(|p| p.set(p.get().max(v)));
        });
    }

    fn sub(n: usize) {
        let _ = NOW.try_with(|c| c.set(c.get().saturating_sub(n)));
    }

    unsafe impl GlobalAlloc for Counting {
        unsafe fn alloc(&self, l: Layout) -> *mut u8 {
            add(l.size());
            unsafe { System.alloc(l) }
        }
        unsafe fn dealloc(&self, p: *mut u8, l: Layout) {
            sub(l.size());
            unsafe { System.dealloc(p, l) }
        }
        unsafe fn realloc(&self, p: *mut u8, l: Layout, new: usize) -> *mut u8 {
            add(new);
            sub(l.size());
            unsafe { System.realloc(p, l, new) }
        }
    }

    #[global_allocator]
    static A: Counting = Counting;

    /// Runs `f` and returns its result with the peak heap bytes it added on this thread.
    pub fn peak<T>(f: impl FnOnce() -> T) -> (T, usize) {
        let base = NOW.with(|c| c.get());
        PEAK.with(|p| p.set(base));
        let out = f();
        (out, PEAK.with(|p| p.get()) - base)
    }
}
