#pragma once
// The two scans of a window's voxel list (NeighbourhoodWindow::levels and add_listed), one kernel
// per SimdLevel (core/simd.hpp): every level gives the same bits (integer compares; the sums are
// RawSums' additions in list order, without fused multiply-adds). Internal to src/surface/;
// list_kernels.cpp is compiled with -ffp-contract=off (CMakeLists.txt).
#include <cstddef>
#include <cstdint>

#include <Eigen/Core>

#include "lidarsurf/core/packed_voxels.hpp"
#include "lidarsurf/core/simd.hpp"
#include "lidarsurf/core/voxel_key.hpp"
#include "lidarsurf/surface/neighbourhood_window.hpp"
#include "raw_sums.hpp"

namespace lidarsurf::window {

// Entries of a voxel list are padded to a multiple of this (one SSE2 compare).
inline constexpr std::size_t kLanes = 16;

// A list's arrays as local pointers: a byte store may alias anything, so through the vectors the
// compiler would reload every data pointer in each iteration.
struct ListArrays {
    const std::uint8_t *x, *y, *z, *weight;
    const PackedVoxels::Voxel* const* records;
    std::size_t count;  // a multiple of kLanes
};
inline ListArrays arrays_of(const NeighbourhoodWindow::VoxelList& l) { return {l.x, l.y, l.z, l.weight, l.records, l.size}; }
// The points (weights saturated at 255) of the entries with level 1 and with level <= 2.
struct LevelCounts {
    int in1 = 0, in2 = 0;
};

// levels_*: the level of each entry about the vertex r into `out`, and the points at levels 1
// and <= 2. add_listed_*: the entries with lo <= level <= k added to `acc` about p, in list order.
#if defined(LIDARSURF_SSE2)
LevelCounts levels_sse2(const ListArrays& l, const VoxelKey& r, std::uint8_t* out);
void add_listed_sse2(const ListArrays& l, const std::uint8_t* levels, int lo, int k, const Eigen::Vector3d& p, Moments& acc);
[[gnu::target(LIDARSURF_AVX2_TARGET)]] LevelCounts levels_avx2(const ListArrays& l, const VoxelKey& r, std::uint8_t* out);
[[gnu::target(LIDARSURF_AVX2_TARGET)]] void add_listed_avx2(const ListArrays& l, const std::uint8_t* levels, int lo, int k, const Eigen::Vector3d& p,
                                                            Moments& acc);
[[gnu::target(LIDARSURF_AVX512_TARGET)]] LevelCounts levels_avx512(const ListArrays& l, const VoxelKey& r, std::uint8_t* out);
[[gnu::target(LIDARSURF_AVX512_TARGET)]] void add_listed_avx512(const ListArrays& l, const std::uint8_t* levels, int lo, int k,
                                                                const Eigen::Vector3d& p, Moments& acc);
#else
LevelCounts levels_portable(const ListArrays& l, const VoxelKey& r, std::uint8_t* out);
void add_listed_portable(const ListArrays& l, const std::uint8_t* levels, int lo, int k, const Eigen::Vector3d& p, Moments& acc);
#endif

}  // namespace lidarsurf::window
