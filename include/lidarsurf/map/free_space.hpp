#pragma once
// Free-space carving for fused sequences (docs/method.md, "Free space"). The paper meshes one
// scan; a drive fused into one grid also holds every moving object at every place it was seen,
// and those voxels' statistics make surfaces (ghosts) where the street is empty. A ray says more
// than where its return is: the space between the sensor and the return was empty at that time.
//
// Each voxel keeps evidence counted in scans: the scans that put a point in it (hits) and the
// scans that saw through it without hitting it (passes). A voxel with at least `min_scans` passes
// and more passes than hits (or hit by one scan only) is removed from the grid (VoxelGrid::remove):
// its block counts as touched, so an incremental extraction redoes the vertices it reached, as for
// a new point. A voxel no scan has hit for `stale_scans` scans goes after `stale_passes` passes
// since its last hit, however many came before: a car parked long, gone, is not outweighed by
// its past.
//
// "Saw through": the scan is a range image from its viewpoint (the nearest return per 0.2 x 0.4
// degree pixel). Each occupied voxel within `range`, not hit by the scan, is tested against the
// returns of its pixel and of the pixels above and below; beyond `range` only the young voxels
// (hit by at most kYoungHits scans: a car seen from afar) are. The voxel's points are a Gaussian
// (mean, covariance + sigma0^2 I, sigma0 = alpha / 8, alpha / 4 for fewer than kMinPoints):
//  - planar voxel: the return's ray crosses the voxel's plane inside the points' in-plane ellipse
//    (two sigmas) and the return lies at least `margin` behind that plane. A grazing ray over the
//    ground returns on the same plane and never counts;
//  - any voxel (a planar one only while young: the rays grazing a static edge pass through its
//    ellipsoid): the ray passes within two sigmas of the mean (Mahalanobis) and returns at least
//    `margin` beyond it, and the voxel lies at least `margin` off the surface the ray returned
//    on: the plane of the return's voxel (for a voxel within `plane_reach` of the return: a
//    plane says little far from where it was fitted, and a part of the map fused alone holds
//    the voxels near it only), else the normal of the range image at the return, else the
//    horizontal plane through the return. A far ring on the ground lies on the ground the
//    ray returned on; a car's trail does not.
//
// A ray that returned nothing (the sensor says which: a recording's empty pixels, a simulated
// drive's sensor pattern) saw free space up to the nearest return around it, `empty_range` at most:
// the pixels it falls in, when no return does, get a return at that distance, with no surface
// there. The guards: a pixel is empty only with the rays beside it in its row (a random dropout is
// one ray); a dark surface that absorbs rays is framed by what returns around it, which ends the
// free space in front of whatever stands behind it; and emptiness alone passes only a young or
// stale voxel (a surface hit from many places and lately is not carved on emptiness).
//
// What no ray reaches stays when the rest of its object is carved (a car's roof at the sensor's
// height): the remnant of a cluster mostly carved goes with it (map/carved_clusters.hpp,
// `cluster_share`).
#include <cstdint>
#include <span>
#include <vector>

#include <Eigen/Core>

#include "lidarsurf/core/setting.hpp"
#include "lidarsurf/core/voxel_grid.hpp"
#include "lidarsurf/map/carved_clusters.hpp"
#include "lidarsurf/map/range_image.hpp"

namespace lidarsurf {

/// Free-space carving's settings, one line each (core/setting.hpp). Carving acts only on scans
/// integrated with a viewpoint (Reconstructor::integrate(points, viewpoint)): a single scan is
/// never carved.
// clang-format off
#define LIDARSURF_CARVING_SETTINGS(X) \
    X(bool, carve, true, 0, 1, kClosed, 0, "carve", "", "", "Sequences: remove voxels that later rays went through, the trails of moving objects (0 = keep every point; a single scan is never carved)") \
    X(double, carve_margin_voxels, 2.0, 0.5, 1e3, kClosed, kKeep, "carve margin", "voxels", "", "Carving: a ray counts only if it returned this many voxels behind the voxel's surface") \
    X(int, carve_min_scans, 1, 1, 65535, kClosed, kKeep, "carve min scans", "", "", "Carving: scans that must see through a voxel before it is removed (and more than hit it, when more than one did)") \
    X(double, carve_range, 40.0, 0, 1e4, kAboveLow, kKeep, "carve range", "m", "", "Carving: the voxels within this distance of each scan's sensor are tested against it (metres)") \
    X(int, carve_stale_scans, 6, 0, 65535, kClosed, kKeep, "carve stale scans", "", "", "Carving: a planar voxel no scan has hit for this many scans is tested by the returns near it, not only by its plane, as a surface that stood and is gone (0 = never)") \
    X(int, carve_stale_passes, 6, 0, 65535, kClosed, kKeep, "carve stale passes", "", "", "Carving: a voxel no scan has hit for carve_stale_scans scans is removed after this many passes since its last hit, however many hits came before (0 = never)") \
    X(double, carve_empty_range, 40.0, 0, 1e4, kClosed, kKeep, "carve empty range", "m", "", "Carving: a ray that returned nothing saw free space up to this distance (metres; 0 = rays that return nothing say nothing), when the input says which rays those were") \
    X(double, carve_cluster_share, 0.5, 0, 1, kAboveLow, kKeep, "carve cluster share", "", "", "Carving: a cluster above the ground goes whole when at least this share of it was carved (1 = never)") \
    X(double, carve_plane_reach, 8.0, 0, 1e4, kClosed, kKeep, "carve plane reach", "m", "", "Carving: the plane of the voxel a ray returned in places that surface for the voxels within this distance of the return (metres); farther, the range image's normal does")
// clang-format on

struct CarvingConfig {
    LIDARSURF_SETTINGS(CarvingConfig, LIDARSURF_CARVING_SETTINGS)
};

struct CarvingStats {
    std::size_t rays = 0;       ///< pixels of the range image
    std::size_t crossings = 0;  ///< voxel-return pairs tested (the return far enough behind the voxel)
    std::size_t empty = 0;      ///< pixels empty of returns where the sensor fired (rays that returned nothing)
    std::size_t passes = 0;     ///< voxels given a pass this scan
    std::size_t removed = 0;    ///< voxels removed this scan
    std::size_t clustered = 0;  ///< of them, the rest of mostly carved clusters
};

class FreeSpaceCarver {
public:
    static constexpr int kMinPoints = 5;
    /// Voxels hit by at most this many scans are tested beyond `range` too.
    static constexpr int kYoungHits = 2;

    /// Carves as `config` says (validated: InvalidArgument) on a grid of `voxel_size` metres:
    /// the margin is carve_margin_voxels voxels; voxels farther than carve_range from a scan's
    /// viewpoint are not tested against it; a planar voxel not hit for carve_stale_scans scans
    /// (> 0) is tested as a thick one is.
    FreeSpaceCarver(const CarvingConfig& config, double voxel_size);

    /// After `grid.insert(points, viewpoint, &hits)` of one scan: counts the hits, tests the
    /// voxels within range against the scan's returns seen from `viewpoint` (world), counts the
    /// passes and removes the voxels carved. `points` are the scan's points in world coordinates;
    /// `no_return` the unit directions (world) of the scan's rays that returned nothing, or empty
    /// when the input does not say.
    CarvingStats carve(VoxelGrid& grid, std::span<const Eigen::Vector3d> points, std::span<const VoxelGrid::Hit> hits,
                       const Eigen::Vector3d& viewpoint, std::span<const Eigen::Vector3f> no_return = {});
    /// The same with the scan's range image built already (RangeImage::build with this grid's
    /// origin, carve_empty_range and the scan's points, which must still be alive): what a map
    /// fused in tiles does, one image per scan for all its tiles.
    CarvingStats carve(VoxelGrid& grid, const RangeImage& image, std::span<const VoxelGrid::Hit> hits);

    /// Counts `scans` scans that reach none of the grid's voxels (none of their returns, and
    /// so no ray, comes within their range of one): what carve() would do with them, without the
    /// range image. A part of a map fused alone (tiles/tiles.hpp) keeps the drive's scan count,
    /// which staleness is measured in, and drops the young voxels such a scan leaves behind.
    void skip(std::uint32_t scans = 1) {
        scan_ += scans;
        if (scans > 0) young_.clear();
    }

    /// Scans counted so far.
    std::uint32_t scans() const { return scan_; }
    std::size_t memory_bytes() const {
        return image_.memory_bytes() + evidence_.capacity() * sizeof(Evidence) + young_.capacity() * sizeof(VoxelKey) +
               young_slots_.capacity() * sizeof(std::uint32_t) + clusters_.memory_bytes();
    }
    /// carve_empty_range, the range a RangeImage built for this carver takes.
    double empty_range() const { return empty_range_; }

    /// The evidence of voxel `voxel` (an index into the grid's stats()).
    std::uint16_t hit_scans(std::size_t voxel) const { return evidence_.at(voxel).hits; }
    std::uint16_t pass_scans(std::size_t voxel) const { return evidence_.at(voxel).passes; }
    /// 0: no surface (too few points), 1: planar, 2: thick, 3: a line (one ring).
    int shape(std::size_t voxel) const { return static_cast<int>(evidence_.at(voxel).shape); }

private:
    enum class Shape : std::uint8_t { None, Planar, Thick, Line, Sparse };
    struct Evidence {
        std::uint16_t hits = 0, passes = 0;
        std::uint32_t last_hit = 0;   // scan number + 1 of the last hit (0: none)
        std::uint32_t last_pass = 0;  // scan number + 1 of the last pass (written atomically)
        Shape shape = Shape::None;
        std::uint16_t since_hit = 0;  // passes since the last hit
        // Planar: the unit normal and the in-plane eigenvalues (regularised). Thick: unused.
        float normal[3] = {0, 0, 0};
        float lambda1 = 0, lambda2 = 0;
        float mean[3] = {0, 0, 0};  // the voxel's mean (local frame), read without its statistics
    };
    void fit(const VoxelStats& stats, Evidence& e) const;
    Eigen::Matrix3d covariance(const VoxelStats& stats, const Evidence& e) const;
    bool crosses_plane(const VoxelStats& stats, const Evidence& e, const Eigen::Vector3d& s, const Eigen::Vector3d& p) const;
    bool passes_near(const VoxelStats& stats, const Evidence& e, const Eigen::Vector3d& s, const Eigen::Vector3d& p) const;
    /// `p`: the return of pixel `q` of `image`, local frame.
    bool off_surface(const VoxelGrid& grid, const RangeImage& image, const Eigen::Vector3d& mu, const Eigen::Vector3d& p,
                     std::uint32_t q) const;

    double margin_;
    int min_scans_;
    double range_;
    int stale_scans_;
    int stale_passes_;
    double empty_range_;
    double plane_reach2_;  // carve_plane_reach squared
    double sigma2_;  // sigma0^2, set from the grid's voxel size
    std::uint32_t scan_ = 0;
    std::vector<Evidence> evidence_;  // per voxel of the grid, by its index
    std::vector<VoxelKey> young_;            // the voxels hit by at most kYoungHits scans (keys: removals move indices)
    std::vector<std::uint32_t> young_slots_;  // their indices in this scan
    RangeImage image_;  // the scan being carved (kept from scan to scan: no page faults for fresh buffers)
    CarvedClusters clusters_;
};

}  // namespace lidarsurf
