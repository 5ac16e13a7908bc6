//! The C allocator's policy while a model is loaded, smoothed and given
//! tangent frames.
//!
//! Each stage of a large model allocates arrays of tens of megabytes and
//! frees those of the stage before. By default the C library maps every
//! block above a threshold (128 KiB, raised up to 32 MiB as it sees blocks
//! freed) straight from the system and unmaps it when freed, so every
//! stage's arrays are fresh pages: a page fault and a cleared page per
//! 4 KiB, about 2 to 3 µs each on a virtual machine, which at a million
//! triangles was a sixth of the smoothing and tangent time. While a
//! [`HeapReuse`] is alive, blocks of any size come from the heap and freed
//! memory stays there, so each stage reuses what the one before freed
//! (the file's text, the parser's arrays, smoothing's tables); when the
//! last one ends, the default thresholds come back and the free memory is
//! returned to the system, so the renderer holds no more than before.
//! (On a thread other than the main one the C library's heaps are 64 MiB
//! at most, and a larger block there is mapped whatever the policy: the
//! pipeline's largest arrays reuse memory on the main thread.)

use std::sync::{Mutex, PoisonError};

/// Keeps freed memory in the process for reuse while alive (see the
/// module documentation). Guards nest: the policy ends with the last.
#[must_use = "the policy ends when the guard is dropped"]
pub struct HeapReuse {
    _private: (),
}

/// The number of live guards.
static ACTIVE: Mutex<usize> = Mutex::new(0);

impl HeapReuse {
    /// Starts the policy (or joins a live one).
    pub fn enter() -> HeapReuse {
        let mut active = ACTIVE.lock().unwrap_or_else(PoisonError::into_inner);
        if *active == 0 {
            allocator::keep_freed();
        }
        *active += 1;
        HeapReuse { _private: () }
    }
}

impl Drop for HeapReuse {
    fn drop(&mut self) {
        let mut active = ACTIVE.lock().unwrap_or_else(PoisonError::into_inner);
        *active -= 1;
        if *active == 0 {
            allocator::release_freed();
        }
    }
}

#[cfg(all(target_os = "linux", target_env = "gnu"))]
mod allocator {
    /// Blocks up to this size come from the heap, and up to this much free
    /// memory at its top is kept (a model's largest array is its file's
    /// text: 785 MB at ten million triangles).
    const KEEP: libc::c_int = 1 << 30;
    /// glibc's documented defaults for both thresholds. Once set, the
    /// mapping threshold no longer rises by itself as blocks are freed:
    /// large blocks are mapped from the system, as at start.
    const DEFAULT: libc::c_int = 128 * 1024;

    pub fn keep_freed() {
        // SAFETY: `mallopt` only sets the allocator's thresholds, taking
        // its own lock; a value it refuses leaves them as they were.
        unsafe {
            libc::mallopt(libc::M_MMAP_THRESHOLD, KEEP);
            libc::mallopt(libc::M_TRIM_THRESHOLD, KEEP);
        }
    }

    pub fn release_freed() {
        // SAFETY: as above; `malloc_trim` returns free pages of every
        // arena to the system, under the allocator's locks.
        unsafe {
            libc::mallopt(libc::M_MMAP_THRESHOLD, DEFAULT);
            libc::mallopt(libc::M_TRIM_THRESHOLD, DEFAULT);
            libc::malloc_trim(0);
        }
    }
}

/// Other allocators: nothing to set.
#[cfg(not(all(target_os = "linux", target_env = "gnu")))]
mod allocator {
    pub fn keep_freed() {}
    pub fn release_freed() {}
}
