//! The binary's allocator (a build with the `bots` feature, for `load`): the system's, counting the net bytes allocated while a thread is flagged as
//! doing the server's work, so `load` can tell the server's heap from its bots' in one process.

use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;
use std::sync::atomic::{AtomicI64, Ordering};

/// The system allocator, counting flagged work.
struct Counting;

static SERVER_BYTES: AtomicI64 = AtomicI64::new(0);

thread_local! {
    // Const-initialised and without a destructor: safe to read inside the allocator.
    static SERVER_WORK: Cell<bool> = const { Cell::new(false) };
}

fn count(delta: i64) {
    if SERVER_WORK.with(Cell::get) {
        SERVER_BYTES.fetch_add(delta, Ordering::Relaxed);
    }
}

// SAFETY: every call goes to the system allocator unchanged; counting touches only an atomic and a
// const thread-local.
unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        count(layout.size() as i64);
        // SAFETY: the caller's layout, as GlobalAlloc requires.
        unsafe { System.alloc(layout) }
    }

    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        count(-(layout.size() as i64));
        // SAFETY: `ptr` came from this allocator (the system's) with `layout`.
        unsafe { System.dealloc(ptr, layout) }
    }

    unsafe fn alloc_zeroed(&self, layout: Layout) -> *mut u8 {
        count(layout.size() as i64);
        // SAFETY: as `alloc`.
        unsafe { System.alloc_zeroed(layout) }
    }

    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        count(new_size as i64 - layout.size() as i64);
        // SAFETY: as `dealloc` and `alloc`.
        unsafe { System.realloc(ptr, layout, new_size) }
    }
}

#[global_allocator]
static ALLOCATOR: Counting = Counting;

/// The probe `load` uses.
pub const PROBE: heist_server::load::HeapProbe = heist_server::load::HeapProbe {
    flag: |on| SERVER_WORK.with(|w| w.set(on)),
    bytes: || SERVER_BYTES.load(Ordering::Relaxed),
};
