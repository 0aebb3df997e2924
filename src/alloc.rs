//! Process-wide allocator tuning for the `vvgen` binary and the benchmarks.
//!
//! A render allocates tens of megabytes of short-lived buffers per view (splat bins, sample layers, images). With
//! glibc's defaults, blocks that large are mmap'ed and unmapped on free, or trimmed off the heap top, so every view
//! faults the same memory in again: measured on an 800k-point frame, 400 k page faults and ~10 % of the time. A
//! batch tool can instead keep what it freed for the next view.

/// Serves blocks up to 256 MiB from the heap and never trims it, so freed buffers are reused rather than returned
/// to the kernel and faulted in again. No effect off glibc. Call once, first thing in `main`.
pub fn retain_freed_memory() {
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    // SAFETY: mallopt only sets allocator parameters; it is called before any other thread exists.
    unsafe {
        libc::mallopt(libc::M_MMAP_THRESHOLD, 256 << 20);
        libc::mallopt(libc::M_TRIM_THRESHOLD, i32::MAX);
    }
}
