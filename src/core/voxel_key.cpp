#include "lidarsurf/core/voxel_key.hpp"

#include <algorithm>
#include <array>
#include <bit>
#include <cstdint>

#include <tbb/parallel_sort.h>

#include "lidarsurf/core/radix_sort.hpp"

namespace lidarsurf {

// As 64-bit words whose order is (z, y, x): each coordinate less its minimum, in as many bits as
// its range needs, z highest; the words are then sorted by LSD radix (11-bit digits, a stable
// counting sort per digit: 2-3 passes for a lidar frame's cubes, whose coordinates span a few
// hundred voxels). A list whose ranges need more than 64 bits together (keys far apart on every
// axis, e.g. a few steps beyond +-kMaxLatticeIndex) is sorted by comparisons instead.
void sort_zyx(std::vector<VoxelKey>& keys) {
    const std::size_t n = keys.size();
    if (n < 2) return;
    Eigen::Array3i lo = keys[0].array(), hi = lo;
    for (const VoxelKey& k : keys) {
        lo = lo.min(k.array());
        hi = hi.max(k.array());
    }
    std::array<int, 3> bits{};  // x, y, z
    for (int a = 0; a < 3; ++a)
        bits[static_cast<std::size_t>(a)] = static_cast<int>(std::bit_width(static_cast<std::uint64_t>(static_cast<std::int64_t>(hi[a]) - lo[a])));
    const int total = bits[0] + bits[1] + bits[2];
    if (total > 64) {
        tbb::parallel_sort(keys.begin(), keys.end(), [](const VoxelKey& a, const VoxelKey& b) {
            if (a.z() != b.z()) return a.z() < b.z();
            if (a.y() != b.y()) return a.y() < b.y();
            return a.x() < b.x();
        });
        return;
    }
    auto field = [](std::int32_t c, std::int32_t min) { return static_cast<std::uint64_t>(static_cast<std::int64_t>(c) - min); };
    std::vector<std::uint64_t> words(n), scratch(n);
    for (std::size_t i = 0; i < n; ++i) {
        const VoxelKey& k = keys[i];
        words[i] = (field(k.z(), lo.z()) << bits[1] | field(k.y(), lo.y())) << bits[0] | field(k.x(), lo.x());
    }
    radix_sort(words, scratch, total, [](std::uint64_t w) { return w; });
    const std::uint64_t mx = (std::uint64_t{1} << bits[0]) - 1, my = (std::uint64_t{1} << bits[1]) - 1;
    for (std::size_t i = 0; i < n; ++i) {
        const std::uint64_t w = words[i];
        keys[i] = VoxelKey(static_cast<int>(static_cast<std::int64_t>(w & mx) + lo.x()),
                           static_cast<int>(static_cast<std::int64_t>(w >> bits[0] & my) + lo.y()),
                           static_cast<int>(static_cast<std::int64_t>(total == bits[0] + bits[1] ? 0 : w >> (bits[0] + bits[1])) + lo.z()));
    }
}

}  // namespace lidarsurf
