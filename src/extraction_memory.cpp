// The memory an extraction will use, from the grid alone, before any of its work: what
// Reconstructor checks against max_memory_mb (docs/reliability.md, "Memory budget").
#include <algorithm>
#include <bit>
#include <cstdint>
#include <limits>

#include "lidarsurf/core/block_mask.hpp"
#include "lidarsurf/core/packed_voxels.hpp"
#include "lidarsurf/pipeline.hpp"
#include "lidarsurf/surface/vertex_evaluator.hpp"

namespace lidarsurf {
namespace {

// The corners v + {0,1}^3 of a block's occupied voxels, among the block's 9^3 vertices: the
// vertices its seed cubes evaluate. An upper bound where a neighbour's voxels share the far faces.
std::size_t seed_corners(const BlockMask& occupancy) {
    constexpr std::uint64_t kLastColumn = 0x8080808080808080ULL;
    std::size_t n = 0;
    for (int z = 0; z <= 8; ++z) {
        const std::uint64_t layer = (z < 8 ? occupancy[z] : 0) | (z > 0 ? occupancy[z - 1] : 0);
        if (!layer) continue;
        const std::uint64_t inner = layer & ~kLastColumn;  // (x, y) -> x + 8 y; x = 7 leaves the block
        // Bit y: voxel (7, y), gathered from bits 8 y by the multiply (bit 8 y lands at 56 + y).
        const auto column = static_cast<std::uint32_t>((((layer >> 7) & 0x0101010101010101ULL) * 0x0102040810204080ULL) >> 56);
        const auto row = static_cast<std::uint32_t>(layer >> 56);  // y = 7
        n += static_cast<std::size_t>(std::popcount(layer | (inner << 1) | (layer << 8) | (inner << 9)) +
                                      std::popcount(column | (column << 1)) + std::popcount((row | (row << 1)) & 0xFFu));
    }
    return n;
}

// Per-item costs of the fast path (seeded_surface.cpp, marching_cubes.cpp), in bytes. Measured on
// a KITTI frame, the demo, 40 planes at 0.1 and 0.2 m and 30 stacked layers (docs/reliability.md).
constexpr double kStoreBytes = 40;                                     // an evaluated vertex (key, sample, TSDF)
constexpr double kFieldBytes = sizeof(VoxelKey) + sizeof(VertexSample);  // a defined vertex in the field
constexpr double kListEntryBytes = 12;                                  // a voxel in a window's list (record, x, y, z, weight)
constexpr double kBlockBytes = 5 * 1024;                                // a block's slots and visited flags
constexpr double kCubeBytes = sizeof(VoxelKey);                         // a cube found
constexpr double kWeldBytes = 32;                                       // marching cubes' welding, per field vertex
constexpr double kVertexBytes = 45;                                     // a mesh vertex: position, normal, level, confidence, intensity
constexpr double kTriangleBytes = 12;
// Evaluated vertices and triangles per seed corner as counted (the far faces counted twice): 0.7-1.8
// and 0.5-1.9 were measured (the most vertices with bridges at 0.05 m, where the sparse figure
// below is the larger; the most triangles between layers 1.5 voxels apart).
constexpr double kEvaluatedPerCorner = 1.0;
constexpr double kTrianglesPerCorner = 1.9;
constexpr double kVerticesPerTriangle = 0.6;
// Where the voxels are few a block, what a block costs: the search's slots and visited flags
// (5 KiB), and, for a block the surface runs through (3+ voxels), the vertices it evaluates
// between the seeds (bridges between rings, slabs), the field, the welding and the mesh (16 KiB:
// 11-17 KiB a block were measured on single scans at 0.05-0.2 m).
constexpr double kSparseBlockBytes = kBlockBytes;
constexpr double kSparseSurfaceBlockBytes = 16 * 1024;

}  // namespace

std::size_t estimate_extraction_bytes(const VoxelGrid& grid, const SurfaceConfig& config, Evaluation evaluation,
                                      std::size_t limit, const SearchRegion* region) {
    // The grid's blocks the extraction can reach: all of them, or those within the region's
    // bounding box grown by the reach of a vertex's neighbourhoods (in blocks, rounded up, plus
    // one for the region's cubes on a block's last layer).
    const std::vector<VoxelKey>& keys = grid.index().block_keys();
    VoxelKey lo = VoxelKey::Constant(std::numeric_limits<int>::min()), hi = VoxelKey::Constant(std::numeric_limits<int>::max());
    if (region) {
        lo = VoxelKey::Constant(std::numeric_limits<int>::max()), hi = VoxelKey::Constant(std::numeric_limits<int>::min());
        for (const VoxelKey& b : region->blocks()) lo = lo.cwiseMin(b), hi = hi.cwiseMax(b);
        const int grow = (config.max_reach() + BlockMap<int>::kSize - 1) / BlockMap<int>::kSize + 1;
        lo.array() -= grow, hi.array() += grow;
    }
    const auto counted = [&](std::size_t b) { return (keys[b].array() >= lo.array()).all() && (keys[b].array() <= hi.array()).all(); };
    std::size_t blocks = 0, surface_blocks = 0, voxels = 0, corners = 0;
    for (std::size_t b = 0; b < keys.size(); ++b) {
        if (!counted(b)) continue;
        const BlockMask& occupancy = grid.occupancy(b);
        const int n = popcount(occupancy);
        ++blocks;
        surface_blocks += n >= 3;
        voxels += static_cast<std::size_t>(n);
        corners += seed_corners(occupancy);
    }
    if (config.seeded_surface && evaluation == Evaluation::Fast) {
        // The search's peak: the packed statistics (PackedVoxels), every vertex block's voxel list
        // (each voxel is in the lists of the vertex blocks whose region [8b - K, 8b + 6 + K]^3
        // holds it, K = max_level: (7 + 2K)^3 / 8^3 of them on average, all neighbours present),
        // the blocks' slots, the evaluated vertices and the field they are compacted into.
        const double packed = static_cast<double>(voxels * sizeof(PackedVoxels::Voxel) + blocks * sizeof(PackedVoxels::Block));
        const double side = 7.0 + 2.0 * config.max_level();
        const double evaluated = kEvaluatedPerCorner * static_cast<double>(corners);
        const double field = kFieldBytes * evaluated + kCubeBytes * static_cast<double>(corners);
        const double search = packed + kListEntryBytes * static_cast<double>(voxels) * side * side * side / 512.0 +
                              kBlockBytes * static_cast<double>(blocks) + kStoreBytes * evaluated + field;
        // Then marching cubes, beside the field and the cubes: the mesh and its welding table. The
        // evaluated vertices' store, freed by then, stays counted: glibc keeps its chunks, and the
        // mesh's large arrays do not fit in them (measured).
        const double triangles = kTrianglesPerCorner * static_cast<double>(corners);
        const double mesh = field + kStoreBytes * evaluated + kWeldBytes * evaluated +
                            triangles * (kTriangleBytes + kVerticesPerTriangle * kVertexBytes);
        // Where blocks hold few voxels (single scans: a surface block of a KITTI frame holds ~20),
        // the per-block costs dominate; where they are dense (stacked layers: ~360), the per-voxel ones.
        const double sparse = packed + kSparseBlockBytes * static_cast<double>(blocks) + kSparseSurfaceBlockBytes * static_cast<double>(surface_blocks);
        return static_cast<std::size_t>(std::max({search, mesh, sparse}));
    }
    // Every vertex within the largest level L of a voxel is a candidate, each costing its key, its
    // sample and its share of the field (measured ~43 B; 48 B here). Candidates are bounded by the
    // vertex blocks within ceil(L / 8) blocks of a voxel block, counted until `limit` is passed.
    // The output mesh: at most 96 vertices per block with 3 or more voxels (measured 40-64), each
    // 41 B with about two triangles' share (24 B): 6 KiB.
    const std::size_t mesh = surface_blocks * 6 * 1024;
    constexpr std::size_t kPerBlock = BlockMap<int>::kVolume * 48;
    const int r = (config.max_level() + BlockMap<int>::kSize - 1) / BlockMap<int>::kSize;
    BlockIndex dilated;
    std::size_t count = 0;
    for (std::size_t b = 0; b < keys.size(); ++b) {
        if (!counted(b)) continue;
        for (int z = -r; z <= r; ++z)
            for (int y = -r; y <= r; ++y)
                for (int x = -r; x <= r; ++x) {
                    if (!dilated.try_emplace(VoxelKey(keys[b].x() + x, keys[b].y() + y, keys[b].z() + z), 0).second) continue;
                    if (mesh + ++count * kPerBlock > limit) return mesh + count * kPerBlock;
                }
    }
    return mesh + count * kPerBlock;
}

}  // namespace lidarsurf
