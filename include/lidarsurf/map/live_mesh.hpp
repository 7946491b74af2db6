#pragma once
// The live mesh of a fused map (docs/method.md, "Live mesh"): the map's surface kept per block
// (the grid's 8^3 blocks of cubes) and brought up to date scan by scan, at a cost that follows
// what the scan changed, not the map:
//  - BlockChanges says which blocks are due (one of their voxels removed, or the points near
//    them changed by a fraction since they were meshed);
//  - the due blocks nearest the sensor are meshed first, in batches, until the time budget is
//    spent; the others wait for the next updates, and those beyond live_range until the sensor
//    comes back near them (the exact extraction has them all);
//  - a batch is meshed as the exact extraction meshes the whole map (the same vertex values, the
//    same marching cubes), with the surface search kept to the batch's blocks and a margin of
//    cubes around them (SearchRegion): a surface that reaches a block only through cubes farther
//    out is missing from the live mesh until the final extraction;
//  - each update returns a MeshDelta: the blocks whose triangles changed, with their new mesh,
//    and the blocks left without a triangle. Applying the deltas in order gives mesh().
// The live mesh keeps every piece (the final extraction's min_component_triangles filter needs
// the whole map). The exact mesh stays Reconstructor::extract_mesh().
#include <cstddef>
#include <span>
#include <vector>

#include <Eigen/Core>

#include "lidarsurf/core/block_map.hpp"
#include "lidarsurf/core/setting.hpp"
#include "lidarsurf/core/voxel_grid.hpp"
#include "lidarsurf/map/block_changes.hpp"
#include "lidarsurf/mesh/mesh.hpp"
#include "lidarsurf/surface/config.hpp"

namespace lidarsurf {

/// The live mesh's settings, one line each (core/setting.hpp).
// clang-format off
#define LIDARSURF_LIVE_MESH_SETTINGS(X) \
    X(double, live_growth, 0.25, 0, 1e3, kClosed, kKeep, "live growth", "", "", "Live mesh: re-mesh a block when the points within live_reach_blocks of it changed (inserted or carved) by this fraction since it was meshed, at once when one of its own voxels was carved") \
    X(double, live_range, 50.0, 0, 1e4, kAboveLow, kKeep, "live range", "m", "", "Live mesh: blocks farther than this from the sensor (metres) wait until it comes back near them") \
    X(int, live_reach_blocks, 1, 0, 4, kClosed, kKeep, "live reach blocks", "", "", "Live mesh: a block depends on the changes (points, removed voxels) within this many blocks (8 voxels) of it") \
    X(int, live_halo_cubes, 0, 0, 64, kClosed, kKeep, "live halo cubes", "", "", "Live mesh: the surface search of the blocks being meshed reaches this many cubes beyond them")
// clang-format on

struct LiveMeshConfig {
    LIDARSURF_SETTINGS(LiveMeshConfig, LIDARSURF_LIVE_MESH_SETTINGS)
};

/// One block of the live mesh: the grid block `key` (cubes 8 key to 8 key + 7) and the triangles
/// of its cubes, in world coordinates, vertices welded within the block.
struct MeshBlock {
    VoxelKey key = VoxelKey::Zero();
    Mesh mesh;
};

/// What one update changed.
struct MeshDelta {
    std::vector<MeshBlock> changed;  ///< blocks whose triangles changed, each with its whole new mesh
    std::vector<VoxelKey> removed;   ///< blocks left without a triangle
    std::size_t meshed_blocks = 0;   ///< blocks meshed by this update (their mesh changed or not)
    std::size_t pending = 0;         ///< blocks due and left for later updates
    double seconds = 0;              ///< the update's wall time
    /// Triangles in `changed`.
    std::size_t triangles() const;
};

class LiveMesh {
public:
    /// Throws InvalidArgument if a configuration is invalid or `surface` meshes without the seeded
    /// surface (the paper as written meshes every defined cube of the map: there is no
    /// block-local form of it).
    LiveMesh(const SurfaceConfig& surface, const LiveMeshConfig& live);
    /// The constructor's check alone, for a caller that refuses a configuration before any work.
    static void check(const SurfaceConfig& surface, const LiveMeshConfig& live);

    /// Reads what changed in `grid` since the last call (takes the grid's journal; the first call
    /// starts it and takes every block the grid holds as changed), then meshes the due blocks
    /// within live_range of `position` (world), urgent first, nearest first, in batches, until
    /// `budget_seconds` is spent, the reading included (a batch is begun while some budget is
    /// left, so the first always runs; <= 0: every due block). `sensor` orients the normals as in
    /// extract_mesh.
    MeshDelta update(VoxelGrid& grid, const Eigen::Vector3d& sensor, const Eigen::Vector3d& position, double budget_seconds);

    /// The live mesh: the blocks' meshes one after the other, blocks in (z, y, x) order of their
    /// keys. Walks the whole map (for a viewer's first frame, a file, tests), unlike update().
    Mesh mesh() const;
    /// The blocks that have a triangle, with their meshes, in the order of mesh().
    std::vector<MeshBlock> blocks() const;
    std::size_t triangle_count() const { return triangles_; }
    /// Blocks due and not meshed yet.
    std::size_t pending() const { return changes_.due_count(); }
    std::size_t memory_bytes() const;

private:
    SurfaceConfig config_;
    LiveMeshConfig live_;
    BlockChanges changes_;
    bool started_ = false;
    BlockIndex index_;              // block key -> blocks_
    std::vector<MeshBlock> blocks_; // every block meshed so far (an empty mesh once it has none)
    std::size_t triangles_ = 0;
    double seconds_per_block_ = 0;  // a running mean, for the size of the next batch
};

/// Applies `delta` to a live mesh kept as blocks (key -> mesh): what a client of the updates
/// (a viewer, a planner) does. Blocks in (z, y, x) key order.
void apply(const MeshDelta& delta, std::vector<MeshBlock>& blocks);
/// The same for removed keys and changed blocks held elsewhere (a decoded stream message).
void apply(std::span<const VoxelKey> removed, std::span<const MeshBlock> changed, std::vector<MeshBlock>& blocks);
/// The blocks' meshes one after the other (as LiveMesh::mesh()).
Mesh concatenate(const std::vector<MeshBlock>& blocks);
/// A mesh cut into the live mesh's blocks: each triangle goes to the block of the cube holding
/// its centroid, on the lattice whose vertex (0, 0, 0) is at `origin` (world) with spacing
/// `voxel_size` (the grid's: VoxelGrid::origin(), SurfaceConfig::voxel_size). Vertices
/// and their attributes are copied into each block that uses them; blocks in (z, y, x) key order.
/// What a viewer of the live mesh is given of the exact mesh, block for block.
std::vector<MeshBlock> split_into_blocks(const Mesh& mesh, const Eigen::Vector3d& origin, double voxel_size);

}  // namespace lidarsurf
