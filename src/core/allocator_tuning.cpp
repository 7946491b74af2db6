#include "lidarsurf/core/allocator_tuning.hpp"

#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <fstream>

// Sanitizers replace malloc: glibc's settings would do nothing there.
#if defined(__GLIBC__) && defined(__linux__) && !defined(__SANITIZE_ADDRESS__) && !defined(__SANITIZE_THREAD__)
#include <malloc.h>
#include <sys/mman.h>
#include <unistd.h>
#define LIDARSURF_GLIBC_MALLOC 1
#endif

namespace lidarsurf {

std::string AllocatorTuning::describe() const {
    if (!keeps_freed_memory && !huge_pages) return "default allocator";
    std::string text = keeps_freed_memory ? "freed memory kept" : "";
    if (huge_pages) text += std::string(text.empty() ? "" : ", ") + "heap in huge pages";
    return text;
}

std::string transparent_huge_pages_mode() {
    std::ifstream in("/sys/kernel/mm/transparent_hugepage/enabled");
    std::string line;
    if (!in || !std::getline(in, line)) return "";
    // e.g. "always [madvise] never": the mode in force is bracketed.
    const auto open = line.find('['), close = line.find(']');
    if (open == std::string::npos || close == std::string::npos || close < open) return "";
    return line.substr(open + 1, close - open - 1);
}

AllocatorTuning tune_allocator() {
    AllocatorTuning done;
#if defined(LIDARSURF_GLIBC_MALLOC)
    // Blocks below 64 MiB come from the heap (not mapped and unmapped one by one), and the heap's
    // top is given back only beyond 128 MiB: ~300 -> ~36 page faults per KITTI frame, peak memory
    // unchanged (docs/benchmarks.md, session 23).
    mallopt(M_MMAP_THRESHOLD, 64 << 20);
    mallopt(M_TRIM_THRESHOLD, 128 << 20);
    done.keeps_freed_memory = true;

    const char* tunables = std::getenv("GLIBC_TUNABLES");
    if (tunables && std::strstr(tunables, "glibc.malloc.hugetlb=1")) {  // glibc advises its heaps itself
        done.huge_pages = true;
        return done;
    }
    const std::string mode = transparent_huge_pages_mode();
    if (mode != "madvise" && mode != "always") return done;
    // The heap grows by 64 MiB of address space at a time (only what is touched is memory), so
    // the region advised below holds a frame to come (a KITTI frame's peak is ~50 MB): memory the
    // heap gains beyond lies in a new mapping without the advice (until the next call). glibc
    // also keeps that much free at the heap's top when it trims it.
    constexpr std::size_t kTopPad = std::size_t{64} << 20;
    mallopt(M_TOP_PAD, static_cast<int>(kTopPad));
    // Make the heap grow now, by more than its free top (mallinfo2's keepcost) unless that holds
    // half the padding already: the growth then brings the padding.
    const std::size_t top = mallinfo2().keepcost;
    if (top < kTopPad / 2) {
        // (volatile: a compiler may drop a malloc whose block is only freed)
        void* volatile grow = std::malloc(top + (std::size_t{1} << 20));
        std::free(grow);  // kept: below the trim threshold
    }
    // Advise the main heap, [end - arena, end), from its first 2 MiB boundary: pages not touched
    // yet are then faulted in as 2 MiB pages (those touched already stay 4 KiB ones).
    const auto end = reinterpret_cast<std::uintptr_t>(sbrk(0));
    const std::uintptr_t arena = mallinfo2().arena;
    constexpr std::uintptr_t kHuge = std::uintptr_t{2} << 20;
    const std::uintptr_t start = (end - arena + kHuge - 1) & ~(kHuge - 1);
    if (arena > 0 && end > start && madvise(reinterpret_cast<void*>(start), end - start, MADV_HUGEPAGE) == 0) done.huge_pages = true;
#endif
    return done;
}

AllocatorTuning release_free_memory() {
#if defined(LIDARSURF_GLIBC_MALLOC)
    malloc_trim(0);
#endif
    return tune_allocator();
}

}  // namespace lidarsurf
