//! The binary's allocator in a build with the `bots` feature (for `load`): mimalloc, as in every build
//! (`main.rs`), counting the net bytes allocated while a thread is flagged as doing the server's work, so
//! `load` can tell the server's heap from its bots' in one process.

use std::alloc::{GlobalAlloc, Layout};
use std::cell::Cell;
use std::sync::atomic::{AtomicI64, Ordering};

use mimalloc::MiMalloc;

/// mimalloc, counting flagged work.
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

// SAFETY: every call goes to mimalloc unchanged; counting touches only an atomic and a
// const thread-local.
unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        count(layout.size() as i64);
        // SAFETY: the caller's layout, as GlobalAlloc requires.
        unsafe { MiMalloc.alloc(layout) }
    }

    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        count(-(layout.size() as i64));
        // SAFETY: `ptr` came from this allocator (mimalloc) with `layout`.
        unsafe { MiMalloc.dealloc(ptr, layout) }
    }

    unsafe fn alloc_zeroed(&self, layout: Layout) -> *mut u8 {
        count(layout.size() as i64);
        // SAFETY: as `alloc`.
        unsafe { MiMalloc.alloc_zeroed(layout) }
    }

    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        count(new_size as i64 - layout.size() as i64);
        // SAFETY: as `dealloc` and `alloc`.
        unsafe { MiMalloc.realloc(ptr, layout, new_size) }
    }
}

#[global_allocator]
static ALLOCATOR: Counting = Counting;

/// The probe `load` uses.
pub const PROBE: heist_server::load::HeapProbe = heist_server::load::HeapProbe {
    flag: |on| SERVER_WORK.with(|w| w.set(on)),
    bytes: || SERVER_BYTES.load(Ordering::Relaxed),
};
