#pragma once
// A map fused in square tiles (docs/method.md, "Tiles"): each tile is fused from the scans that
// can reach what it depends on and meshed alone; the tiles' meshes together are the mesh of the
// map fused whole. Memory follows a group of tiles, not the map; the groups can run one after the
// other (`fuse --tile-size`) or on many machines (the Python module's fuse_tiles, on Dask).
//
// Why a tile's mesh is the whole map's, cube for cube:
//  - every cube belongs to one tile, the one holding its centre (x-y, world frame);
//  - a cube's triangles depend on the values of its corners, which depend on the voxels within
//    max_reach() of them, and on the surface search reaching it: the tile searches its own cubes
//    and `halo_cubes` beyond them. The tile's dependency box (its own cubes, the halo and the
//    reach) holds the statistics of every point of every scan falling in it;
//  - free-space carving removes a voxel by the rays passing through it, tested against each
//    scan's range image (map/range_image.hpp: it depends on the scan alone, so a group of tiles
//    builds it once per scan), and reads the plane of the voxel a ray returned in within
//    carve_plane_reach, and the clusters within CarvedClusters::kReach: a tile integrates every
//    point within its crop (the dependency box grown by those reaches) and carves with every scan
//    whose returns come within its range of that box. The other scans are counted (staleness is
//    counted in scans);
//  - every tile takes the whole map's lattice origin, so the statistics agree to the last bit.
// A voxel beyond the crop whose own carving would have changed what a voxel inside reads is the
// one thing a tile cannot see; tests/tiles/test_tiles.cpp compares the tiles with the whole map
// on drives crossing several tiles.
#include <algorithm>
#include <array>
#include <compare>
#include <cstdint>
#include <functional>
#include <optional>
#include <span>
#include <unordered_map>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "lidarsurf/io/point_cloud.hpp"
#include "lidarsurf/mesh/mesh.hpp"
#include "lidarsurf/reconstruction_config.hpp"

namespace lidarsurf {

class Reconstructor;
struct ReconstructionSummary;

struct TileConfig {
    double tile_size = 100.0;  ///< metres: the side of the square tiles, in the world's x-y plane
    int halo_cubes = 32;       ///< the surface search of a tile reaches this many cubes beyond it
    /// Tiles fused in one pass over the scans (fuse_tiles): squares of group x group tiles, each
    /// scan read and seen as a range image once per group; memory holds a group's tiles.
    int group = 2;
    /// Throws InvalidArgument naming the field: tile_size finite and >= 1 m, halo_cubes in [8, 1024],
    /// group in [1, 64].
    void validate() const;
};

/// What a plan needs of one scan: where it was seen from, how far its returns reach, where its
/// points are (world frame).
struct ScanReach {
    Eigen::Vector3d viewpoint = Eigen::Vector3d::Zero();
    double radius = 0;                         ///< metres from the viewpoint to its farthest finite return
    Eigen::AlignedBox3d box;                   ///< its finite points (empty: none)
    std::optional<Eigen::Vector3d> first_point;  ///< its first finite point: a map's lattice origin comes from it
    bool empty_rays = false;  ///< it says which of its rays returned nothing (carving takes them to carve_empty_range)
};
/// The reach of the scan `points` (world) seen from `viewpoint`; `empty_rays`: whether it comes
/// with the rays that returned nothing.
ScanReach scan_reach(std::span<const Eigen::Vector3d> points, const Eigen::Vector3d& viewpoint, bool empty_rays = false);

struct TileKey {
    int x = 0, y = 0;  ///< the tile covers [x, x + 1) tile_size by [y, y + 1) tile_size (world metres)
    auto operator<=>(const TileKey&) const = default;
};

/// Which tiles a sequence's map has and which scans each one takes.
class TilePlan {
public:
    /// `scans`: every scan of the sequence, in fusion order. Throws InvalidArgument for a bad
    /// config and InvalidInput when no scan has a finite point.
    TilePlan(std::vector<ScanReach> scans, const ReconstructionConfig& config, const TileConfig& tiles);
    /// The constructor's check of `config` alone (InvalidArgument), for a caller that refuses a
    /// configuration before reading any scan.
    static void check(const ReconstructionConfig& config);

    /// The tiles that can own a triangle: those within reach of a point, in (y, x) order.
    const std::vector<TileKey>& tiles() const { return tiles_; }
    /// The tiles in groups of TileConfig::group x group (fuse_tiles' passes), each in (y, x) order,
    /// the groups in the (y, x) order of their squares.
    std::vector<std::vector<TileKey>> groups() const;
    /// The tile whose square holds `world` (x-y).
    TileKey tile_of(const Eigen::Vector3d& world) const;
    /// Whether scan `scan` must be integrated into `tile` (else it is counted only).
    bool reaches(const TileKey& tile, std::size_t scan) const;
    /// How many scans `tile` integrates.
    std::size_t scans_of(const TileKey& tile) const;
    /// The tile's square (z unbounded); the box its cubes depend on; the box of the points it keeps.
    Eigen::AlignedBox3d square(const TileKey& tile) const;
    Eigen::AlignedBox3d dependency(const TileKey& tile) const;
    Eigen::AlignedBox3d crop(const TileKey& tile) const;

    /// The whole map's lattice origin (the first finite point of the first scan that has one).
    const Eigen::Vector3d& grid_origin() const { return origin_; }
    /// Where the first scan was seen from (orients what has no viewpoint).
    const Eigen::Vector3d& sensor() const { return scans_.front().viewpoint; }
    /// Where scan `scan` was seen from.
    const Eigen::Vector3d& viewpoint(std::size_t scan) const { return scans_.at(scan).viewpoint; }
    /// The sequence's longest ray, metres (a scan reaches the tiles within its own farthest return).
    double ray_reach() const { return ray_reach_; }
    /// The box of every scan's points.
    const Eigen::AlignedBox3d& bounds() const { return bounds_; }
    std::size_t scan_count() const { return scans_.size(); }
    const ReconstructionConfig& config() const { return config_; }
    const TileConfig& tile_config() const { return tile_config_; }

private:
    std::vector<ScanReach> scans_;
    ReconstructionConfig config_;
    TileConfig tile_config_;
    Eigen::Vector3d origin_ = Eigen::Vector3d::Zero();
    double ray_reach_ = 0;
    double dependency_margin_ = 0;  // metres around the square
    double crop_margin_ = 0;        // metres around the dependency box
    Eigen::AlignedBox3d bounds_;
    std::vector<TileKey> tiles_;
};

/// A scan of a plan's sequence: `scan(i, no_return)` gives scan i as a cloud in the world frame
/// (its intensities, when it has them, reach the mesh) and fills the directions (world) of its
/// rays that returned nothing (Reconstructor::integrate), when carving takes them. fuse_tiles
/// calls it in increasing order of i, one call at a time, on a thread of its own (the next scan
/// is read while one is fused).
using TileScans = std::function<PointCloud(std::size_t, std::vector<Eigen::Vector3f>&)>;
/// What fuse_tiles hands over of each tile: its key, its mesh (world frame) and its summary.
using TileDone = std::function<void(const TileKey&, Mesh&&, const ReconstructionSummary&)>;

/// What a pass over the scans for several tiles cost besides the tiles' own work.
struct TilePassStats {
    std::size_t scans_read = 0;  ///< scans read (those that reach one of the tiles), each once
    std::size_t most_open = 0;   ///< the most tiles fused at the same time
    double seconds_read = 0;     ///< reading the scans (`scan`)
    double seconds_image = 0;    ///< their range images, one per scan for all the tiles it reaches
    /// Bytes: the most the pass held at once by the estimates (kProcessBaselineBytes, the open
    /// tiles' maps, the scans in hand and their image; a tile's extraction beside the others).
    std::size_t memory_estimate = 0;

    /// Another pass's figures: counts and times summed, the most open and the estimate the larger.
    void add(const TilePassStats& o) {
        scans_read += o.scans_read;
        most_open = std::max(most_open, o.most_open);
        seconds_read += o.seconds_read;
        seconds_image += o.seconds_image;
        memory_estimate = std::max(memory_estimate, o.memory_estimate);
    }
};

/// Fuses and meshes `tiles` of `plan` in one pass over the scans, in order: a scan is read once
/// (the next one while this one is fused) and seen as one range image (map/range_image.hpp) for
/// every tile it reaches, integrated into each (the points within the tile's crop) or counted
/// (TilePlan::reaches). A tile is opened at the first scan that reaches it and, after its last
/// one, meshed (mesh_tile), handed to `done` and freed; a tile no scan reaches is handed over
/// empty first. Memory holds the tiles open at once,
/// those whose scans interleave. Each tile's mesh is the one it has in the map fused whole.
/// Throws ResourceLimit when the open tiles' maps together outgrow config.max_memory_mb.
TilePassStats fuse_tiles(const TilePlan& plan, std::span<const TileKey> tiles, const TileScans& scan, const TileDone& done);

/// Fuses and meshes one tile of `plan` (fuse_tiles of that tile alone): `scan(i)` gives scan i's
/// points in the world frame (read by the caller: files, memory). `summary`, when given, gets
/// the tile's counts and times.
Mesh fuse_tile(const TilePlan& plan, const TileKey& tile, const std::function<std::vector<Eigen::Vector3d>(std::size_t)>& scan,
               ReconstructionSummary* summary = nullptr);
/// The same with a TileScans source.
Mesh fuse_tile(const TilePlan& plan, const TileKey& tile, const TileScans& scan, ReconstructionSummary* summary = nullptr);

/// The mesh of the cubes `tile` owns, from `rec`'s grid (world frame), which must hold every point
/// of the tile's dependency box that `plan`'s scans have: the tile's own Reconstructor
/// (fuse_tile), or one map fused whole and then meshed tile by tile, so that its mesh is written
/// piece by piece. Empty when the grid has nothing within reach of the tile.
Mesh mesh_tile(Reconstructor& rec, const TilePlan& plan, const TileKey& tile);

/// Joins tile meshes written one after the other into one mesh: a vertex on a tile's border that
/// an earlier tile wrote (the same position and attributes, to the bit) is not written again.
class SeamWelder {
public:
    explicit SeamWelder(const TilePlan& plan) : plan_(&plan) {}
    /// For each vertex of `part` (a mesh of `tile`): the index an earlier part wrote it with, or -1
    /// (new). The new vertices are taken to be written next, in order, from index `written`.
    std::vector<std::int64_t> weld(const TileKey& tile, const Mesh& part, std::uint64_t written);
    /// Border vertices remembered.
    std::size_t size() const { return seam_.size(); }

private:
    struct Key {
        std::array<std::uint64_t, 3> position;    // the coordinates' bits
        std::array<std::uint32_t, 6> attributes;  // the normal's, the confidence's bits, the level, the intensity's bits
        bool operator==(const Key&) const = default;
    };
    struct KeyHash {
        std::size_t operator()(const Key& k) const noexcept;
    };
    const TilePlan* plan_;
    std::unordered_map<Key, std::uint64_t, KeyHash> seam_;
};

}  // namespace lidarsurf
