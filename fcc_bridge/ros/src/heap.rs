//! Give the allocator's free pages back to the OS, periodically (glibc only).
//!
//! A node's live heap is flat in steady state (heaptrack over a 14-min soak: the mission node
//! 3.8–4.7 MB, no call site growing), yet its RSS crept up by 0.6–1.8 MB/h: glibc keeps freed
//! memory in its arenas (one per thread that allocates: tokio workers, the DDS event loop, the
//! recorder) and only returns the top of the main heap by itself. `malloc_trim(0)` releases the
//! free pages of every arena (`madvise(MADV_DONTNEED)`, glibc ≥ 2.8), so the RSS follows the live
//! heap. One call walks the arenas' free lists under each arena's lock (its duration was not
//! measured here; the IMU latency of `tests/ros2` with it on: max 7.7–10.2 ms), once every
//! [`TRIM_PERIOD`] on a thread of its own.
//! On other C libraries this does nothing.

use std::time::Duration;

/// How often the free pages are returned.
pub const TRIM_PERIOD: Duration = Duration::from_secs(30);

/// Start the trimming thread (once per process; a second call starts a second thread, harmless).
pub fn spawn_trimmer() {
    let _ = std::thread::Builder::new()
        .name("heap-trim".into())
        .spawn(|| loop {
            std::thread::sleep(TRIM_PERIOD);
            trim();
        });
}

/// Return the free pages now.
pub fn trim() {
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    // SAFETY: malloc_trim only reads and updates the allocator's own state, under its locks.
    unsafe {
        libc::malloc_trim(0);
    }
}
