#include "lidarsurf/core/voxel_key.hpp"

#include <atomic>

#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>

namespace lidarsurf {

// As 64-bit words whose order is (z, y, x) (each coordinate biased to be non-negative in 21 bits,
// z highest), which compare in one instruction. Vertex and cube keys may lie a few steps beyond
// the voxels' +-kMaxLatticeIndex, outside 21 bits: such a list is sorted by comparisons instead.
void sort_zyx(std::vector<VoxelKey>& keys) {
    constexpr std::int32_t bias = std::int32_t{1} << 20;
    auto fits = [](int c) { return c >= -bias && c < bias; };
    std::vector<std::uint64_t> packed(keys.size());
    std::atomic<bool> all_fit{true};
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, keys.size(), 4096), [&](const auto& r) {
        for (std::size_t i = r.begin(); i != r.end(); ++i) {
            const VoxelKey& k = keys[i];
            if (!fits(k.x()) || !fits(k.y()) || !fits(k.z())) all_fit.store(false, std::memory_order_relaxed);
            packed[i] = static_cast<std::uint64_t>(k.z() + bias) << 42 | static_cast<std::uint64_t>(k.y() + bias) << 21 |
                        static_cast<std::uint64_t>(k.x() + bias);
        }
    });
    if (!all_fit.load()) {
        tbb::parallel_sort(keys.begin(), keys.end(), [](const VoxelKey& a, const VoxelKey& b) {
            if (a.z() != b.z()) return a.z() < b.z();
            if (a.y() != b.y()) return a.y() < b.y();
            return a.x() < b.x();
        });
        return;
    }
    tbb::parallel_sort(packed.begin(), packed.end());
    constexpr std::uint64_t mask = (std::uint64_t{1} << 21) - 1;
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, keys.size(), 4096), [&](const auto& r) {
        for (std::size_t i = r.begin(); i != r.end(); ++i)
            keys[i] = VoxelKey(static_cast<int>(static_cast<std::int64_t>(packed[i] & mask) - bias),
                               static_cast<int>(static_cast<std::int64_t>(packed[i] >> 21 & mask) - bias),
                               static_cast<int>(static_cast<std::int64_t>(packed[i] >> 42) - bias));
    });
}

}  // namespace lidarsurf
