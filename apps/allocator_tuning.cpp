#include "allocator_tuning.hpp"

#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <string>

// Sanitizers replace malloc: glibc's settings would do nothing there.
#if defined(__GLIBC__) && defined(__linux__) && !defined(__SANITIZE_ADDRESS__) && !defined(__SANITIZE_THREAD__)
#include <malloc.h>
#include <sys/mman.h>
#include <unistd.h>
#define LIDARSURF_GLIBC_MALLOC 1
#endif

namespace lidarsurf::cli {

#if defined(LIDARSURF_GLIBC_MALLOC)
namespace {

constexpr std::size_t kMmapThreshold = std::size_t{64} << 20;

// The lowest address of the main heap (the mappings /proc/self/maps names "[heap]"), or 0 when
// there is none or it cannot be read. (Not sbrk(0) minus mallinfo2's arena: that sums every
// arena, the worker threads' too, and reached below the heap into other mappings.)
std::uintptr_t main_heap_start() {
    std::ifstream maps("/proc/self/maps");
    std::uintptr_t lowest = 0;
    for (std::string line; std::getline(maps, line);) {
        if (line.size() < 6 || line.compare(line.size() - 6, 6, "[heap]") != 0) continue;
        const std::uintptr_t lo = std::strtoull(line.c_str(), nullptr, 16);
        if (lo > 0 && (lowest == 0 || lo < lowest)) lowest = lo;
    }
    return lowest;
}

}  // namespace
#endif

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
    // unchanged.
    mallopt(M_MMAP_THRESHOLD, static_cast<int>(kMmapThreshold));
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
    // Make the heap grow now, unless its free top (mallinfo2's keepcost) holds half the padding
    // already: the growth then brings the padding. The block asked for is larger than all the free
    // memory glibc holds (fordblks, the top and the other arenas included), so that no free chunk
    // inside the heap can serve it (a fragmented heap did: it then grew later, unadvised), and
    // below the mmap threshold, so that it comes from the heap; with more free memory than that,
    // the heap is left as it is.
    const struct mallinfo2 before = mallinfo2();
    const std::size_t grow_by = before.fordblks + (std::size_t{1} << 20);
    if (before.keepcost < kTopPad / 2 && grow_by < kMmapThreshold) {
        // (volatile: a compiler may drop a malloc whose block is only freed)
        void* volatile grow = std::malloc(grow_by);
        std::free(grow);  // kept: below the trim threshold
    }
    // Advise the main heap, from its first 2 MiB boundary to its end: pages not touched yet are
    // then faulted in as 2 MiB pages (those touched already stay 4 KiB ones).
    const std::uintptr_t first = main_heap_start();
    const auto end = reinterpret_cast<std::uintptr_t>(sbrk(0));
    constexpr std::uintptr_t kHuge = std::uintptr_t{2} << 20;
    const std::uintptr_t start = (first + kHuge - 1) & ~(kHuge - 1);
    if (first > 0 && end > start && madvise(reinterpret_cast<void*>(start), end - start, MADV_HUGEPAGE) == 0) done.huge_pages = true;
#endif
    return done;
}

AllocatorTuning release_free_memory() {
#if defined(LIDARSURF_GLIBC_MALLOC)
    malloc_trim(0);
#endif
    return tune_allocator();
}

}  // namespace lidarsurf::cli
