#pragma once
// The CLI's memory allocator, set for meshing frame after frame (measured in docs/benchmarks.md:
// 1-5 % of a frame). A frame allocates and frees some 50 MB: with glibc's defaults
// that memory goes back to the system after each frame and is faulted in again, zeroed, for the
// next, in 4 KiB pages whose translations no longer fit the TLB. tune_allocator() keeps freed
// memory for reuse and, where the kernel offers transparent huge pages on request (its mode
// "madvise"), backs the heap with 2 MiB pages: what GLIBC_TUNABLES=glibc.malloc.hugetlb=1 does,
// which a process cannot set for itself once started. It changes the whole process, so it lives in
// the CLI, not in the library: a program embedding the library gets the same from the environment,
// GLIBC_TUNABLES=glibc.malloc.mmap_threshold=67108864:glibc.malloc.trim_threshold=134217728:glibc.malloc.hugetlb=1.
// The price: up to 64 MiB of freed memory stays resident for reuse (release_free_memory() gives it back).
#include <string>

namespace lidarsurf::cli {

struct AllocatorTuning {
    /// Freed blocks below 64 MiB are kept for reuse, the heap's top trimmed only beyond 128 MiB.
    bool keeps_freed_memory = false;
    /// The main heap (and its next 64 MiB) is advised for transparent huge pages, by
    /// tune_allocator() or by glibc itself (GLIBC_TUNABLES=glibc.malloc.hugetlb=1).
    bool huge_pages = false;
    /// What was done, in words (for logs and benchmark headers).
    std::string describe() const;
};

/// Sets glibc's allocator as above and returns what it did; all false without glibc (nothing is
/// changed) and huge_pages false when the kernel's THP mode (transparent_huge_pages_mode()) is
/// "never" or unknown. Calling it again advises the heap grown since. Call it while no other
/// thread allocates (at start, or between frames): the heap's bounds are read, then advised.
AllocatorTuning tune_allocator();

/// Gives the free memory of glibc's heaps back to the system (malloc_trim), then tunes the
/// allocator again (the trimmed heap is advised anew): for a program that has just freed a lot
/// (after a much larger input) and wants its resident memory back to what it uses. `bench` calls
/// it before each row, so that a row's peak memory is its own. Same condition as tune_allocator().
AllocatorTuning release_free_memory();

/// The kernel's transparent huge page mode: "always", "madvise", "never", or "" when unknown
/// (not Linux, or /sys not mounted).
std::string transparent_huge_pages_mode();

}  // namespace lidarsurf::cli
