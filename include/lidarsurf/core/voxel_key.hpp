#pragma once
// Integer lattice coordinates shared by voxels and grid vertices, with a hash for sparse maps.
#include <cstdint>
#include <functional>
#include <vector>

#include <Eigen/Core>

namespace lidarsurf {

using VoxelKey = Eigen::Vector3i;

/// Whether two keys are equal, without a branch per coordinate (Eigen's == and != test the
/// coordinates one by one and stop at the first that differs: on the hot paths' block comparisons,
/// which are unpredictable, those branches were ~9 % of a KITTI frame's mispredictions).
inline bool same_key(const VoxelKey& a, const VoxelKey& b) { return ((a.x() ^ b.x()) | (a.y() ^ b.y()) | (a.z() ^ b.z())) == 0; }

/// Lattice indices must stay within +-2^20 so that three of them pack into 64 bits.
inline constexpr std::int32_t kMaxLatticeIndex = (1 << 20) - 1;

/// Packs a key (each component within +-kMaxLatticeIndex) into one 64-bit word.
inline std::uint64_t pack_key(const VoxelKey& k) {
    constexpr std::uint64_t mask = (std::uint64_t{1} << 21) - 1;
    return (static_cast<std::uint64_t>(k.x()) & mask) |
           ((static_cast<std::uint64_t>(k.y()) & mask) << 21) |
           ((static_cast<std::uint64_t>(k.z()) & mask) << 42);
}

/// The key pack_key packed.
inline VoxelKey unpack_key(std::uint64_t packed) {
    auto field = [&](int shift) {
        const auto v = static_cast<std::int32_t>((packed >> shift) & ((std::uint64_t{1} << 21) - 1));
        return v > kMaxLatticeIndex ? v - (1 << 21) : v;
    };
    return {field(0), field(21), field(42)};
}

/// splitmix64 finaliser: spreads packed keys over the hash table.
inline std::uint64_t mix64(std::uint64_t x) {
    x ^= x >> 30;
    x *= 0xbf58476d1ce4e5b9ULL;
    x ^= x >> 27;
    x *= 0x94d049bb133111ebULL;
    x ^= x >> 31;
    return x;
}

struct VoxelKeyHash {
    std::size_t operator()(const VoxelKey& k) const noexcept {
        return static_cast<std::size_t>(mix64(pack_key(k)));
    }
};

/// Sorts keys by z, then y, then x (radix sort; comparisons when the keys span more than 64 bits).
void sort_zyx(std::vector<VoxelKey>& keys);

/// Floor division for negative lattice indices (C++ '/' truncates toward zero).
inline std::int32_t floor_div(std::int32_t a, std::int32_t b) {
    std::int32_t q = a / b;
    return (a % b != 0 && ((a < 0) != (b < 0))) ? q - 1 : q;
}

}  // namespace lidarsurf
