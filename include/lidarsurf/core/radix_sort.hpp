#pragma once
// Stable LSD radix sort by an unsigned integer key (11-bit digits: a counting sort per digit), for
// serial steps of a frame: sorting the surface search's cubes (sort_zyx) and, for batches that
// touch voxels of many earlier batches, grouping points by voxel (VoxelGrid::insert). O(items * key_bits / 11).
#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <utility>
#include <vector>

namespace lidarsurf {

/// Sorts `items` by key(item) (an unsigned integer below 2^key_bits), keeping the order of equal
/// keys. `scratch` is working storage (resized to items.size()).
template <typename T, typename Key>
void radix_sort(std::vector<T>& items, std::vector<T>& scratch, int key_bits, Key&& key) {
    constexpr int kDigit = 11;
    constexpr std::uint64_t kMask = (std::uint64_t{1} << kDigit) - 1;
    scratch.resize(items.size());
    std::vector<std::size_t> count(std::size_t{1} << kDigit);
    for (int shift = 0; shift < key_bits; shift += kDigit) {
        std::fill(count.begin(), count.end(), 0);
        for (const T& item : items) ++count[(static_cast<std::uint64_t>(key(item)) >> shift) & kMask];
        std::size_t at = 0;
        for (std::size_t& c : count) at += std::exchange(c, at);
        for (const T& item : items) scratch[count[(static_cast<std::uint64_t>(key(item)) >> shift) & kMask]++] = item;
        items.swap(scratch);
    }
}

}  // namespace lidarsurf
