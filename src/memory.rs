//! Heap accounting: a global allocator that counts the bytes in use and their peak, so that a
//! render can report its peak memory and the benchmark can measure two modes in one process
//! (the resident size cannot: the allocator keeps freed pages).
//!
//! Underneath is mimalloc, not the C library's allocator. Every pass allocates and frees buffers
//! of megabytes (eye results, photons, the photon grid); glibc serves those with fresh `mmap`s,
//! so each pass paid page faults and zeroed pages (a tenth of a render's CPU time in the kernel).
//! mimalloc keeps the pages for the next pass: 160 passes of the caustic box took 14% less
//! wall time, for about 45 MB more resident memory at 256x192.
//!
//! The `caustic` program installs [`CountingAllocator`]; elsewhere (tests, other programs using
//! the library) nothing is counted and [`peak_mib`] is `None`.

use std::alloc::{GlobalAlloc, Layout};
use std::sync::atomic::{AtomicUsize, Ordering::Relaxed};

use mimalloc::MiMalloc;

static IN_USE: AtomicUsize = AtomicUsize::new(0);
static PEAK: AtomicUsize = AtomicUsize::new(0);

/// Turns transparent huge pages off for this process (Linux; elsewhere nothing happens).
///
/// mimalloc asks for huge pages where the system leaves it to programs (`madvise`, as on this
/// machine), and the kernel then zeroes 2 MiB at each first touch of a page, used or not: 4-7% of
/// a render of the demo (480x360) went to zeroing pages, and mimalloc returns freed pages to the
/// system within milliseconds, so every pass faulted them in again. With small pages the demo's
/// first 16 passes on 2 threads took 0.08-0.12 s of system time instead of 0.22-0.35 s, and 4%
/// less wall time (4 interleaved runs each); the TLB misses huge pages would save did not show.
/// Call it before the first large allocation; failure only costs speed.
pub fn prefer_small_pages() {
    #[cfg(target_os = "linux")]
    let _ = nix::sys::prctl::set_thp_disable(true);
}

/// mimalloc, counting.
pub struct CountingAllocator;

fn grew(bytes: usize) {
    let now = IN_USE.fetch_add(bytes, Relaxed) + bytes;
    PEAK.fetch_max(now, Relaxed);
}

// SAFETY: every call goes to mimalloc unchanged; only counters are added.
unsafe impl GlobalAlloc for CountingAllocator {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        // SAFETY: the caller's contract is passed on unchanged.
        let p = unsafe { MiMalloc.alloc(layout) };
        if !p.is_null() {
            grew(layout.size());
        }
        p
    }

    unsafe fn alloc_zeroed(&self, layout: Layout) -> *mut u8 {
        // SAFETY: as above.
        let p = unsafe { MiMalloc.alloc_zeroed(layout) };
        if !p.is_null() {
            grew(layout.size());
        }
        p
    }

    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        // SAFETY: as above.
        unsafe { MiMalloc.dealloc(ptr, layout) };
        IN_USE.fetch_sub(layout.size(), Relaxed);
    }

    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        // SAFETY: as above.
        let p = unsafe { MiMalloc.realloc(ptr, layout, new_size) };
        if !p.is_null() {
            IN_USE.fetch_sub(layout.size(), Relaxed);
            grew(new_size);
        }
        p
    }
}

/// The most heap memory in use at once since the start (or the last [`reset_peak`]), in MiB;
/// `None` when the counting allocator is not installed.
pub fn peak_mib() -> Option<f64> {
    let peak = PEAK.load(Relaxed);
    (peak > 0).then(|| peak as f64 / (1 << 20) as f64)
}

/// Starts a new peak from what is in use now.
pub fn reset_peak() {
    PEAK.store(IN_USE.load(Relaxed), Relaxed);
}
