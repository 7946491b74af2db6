#pragma once
// Accuracy of a fused map (a drive's world mesh) against the exact static scene, with the protocol
// of lidar mapping papers (SHINE-Mapping, Mai City; docs/evaluation.md, "Maps"):
//  - the map and the ground truth are cut to what lies within max_distance of the drive (the
//    sensor positions), horizontally;
//  - ground truth = noise-free GT sensor points on the static scene (what the sensor saw), one per
//    gt_spacing cell;
//  - accuracy: mesh surface samples -> true static scene (exact, clipped to truncation_accuracy);
//    completeness: GT points -> mesh surface (exact, clipped to truncation_completeness);
//    Chamfer-L1 their mean; precision / recall / F-score at `threshold`;
//  - ghost area: mesh area farther than ghost_distance from the static scene (moving objects'
//    trails, spurious surfaces), in m^2 and as a share of the mesh area; the part of it on the
//    movers' paths: within the volume the moving objects took at the scans' times (SweptVolume);
//  - boundary edges by height above the ground: the share of mesh edges with one triangle
//    (holes, perforated surfaces) in each height band.
#include <cstdint>
#include <memory>
#include <unordered_map>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "lidarsurf/core/kd_tree.hpp"
#include "lidarsurf/mesh/mesh.hpp"
#include "lidarsurf/mesh/mesh_distance.hpp"

namespace lidarsurf {

struct MapEvaluationConfig {
    double max_distance = 30.0;            ///< metres from the drive (horizontal); 0 = everything
    double threshold = 0.1;                ///< precision / recall / F-score (metres)
    double ghost_distance = 0.3;           ///< mesh farther than this from the static scene is ghost (metres)
    double truncation_accuracy = 0.2;      ///< metres
    double truncation_completeness = 2.0;  ///< metres
    double sample_spacing = 0.05;          ///< one mesh sample per sample_spacing^2 of area ...
    std::size_t max_samples = 3'000'000;   ///< ... at most this many
    double gt_spacing = 0.1;               ///< one GT point per cell of this size
    double ground_z = 0;                   ///< height reference of the boundary-edge bands
    std::vector<double> height_bands = {0.5, 2.0, 4.5};  ///< band limits above ground_z (metres)
    std::uint64_t seed = 1;
    int threads = 0;

    /// Throws InvalidArgument naming the first bad field.
    void validate() const;
};

struct HeightBand {
    double lo = 0, hi = 0;  ///< metres above ground_z (-inf / +inf at the ends)
    std::size_t edges = 0, boundary_edges = 0;
    double boundary_share() const { return edges ? static_cast<double>(boundary_edges) / static_cast<double>(edges) : 0.0; }
};

struct MapMetrics {
    std::size_t samples = 0, gt_points = 0;
    double accuracy = 0, completeness = 0, chamfer_l1 = 0;
    double precision = 0, recall = 0, fscore = 0;
    double mesh_area = 0;   ///< m^2, within the crop
    double ghost_area = 0;  ///< m^2
    double path_ghost_area = 0;  ///< m^2 of the ghost area within the movers' swept volume (0 without one)
    double ghost_share() const { return mesh_area > 0 ? ghost_area / mesh_area : 0.0; }
    std::vector<HeightBand> boundary_by_height;
};

/// The part of the world within `max_distance` (horizontal) of a drive's sensor positions.
class DriveCrop {
public:
    /// `max_distance` 0: everything. Throws InvalidInput when `drive` is empty or not finite.
    DriveCrop(const std::vector<Eigen::Vector3d>& drive, double max_distance);
    ~DriveCrop();
    DriveCrop(DriveCrop&&) noexcept;
    bool contains(const Eigen::Vector3d& p) const;

private:
    std::unique_ptr<KdTree> tree_;  // the positions at z = 0
    double max_distance_;
};

/// A map's ground truth: the GT scans' points (world frame) that lie on the static scene (within
/// `on_surface` of `truth`: not on a moving object), one per gt_spacing cell, within the crop.
/// Feed it scan by scan (add), then take the points.
class MapGroundTruth {
public:
    MapGroundTruth(const MeshDistance& truth, const DriveCrop& crop, double gt_spacing, double on_surface = 0.02);
    /// Adds one GT scan (world frame; non-finite points are skipped).
    void add(const std::vector<Eigen::Vector3d>& points);
    /// The points kept so far, ordered by cell.
    std::vector<Eigen::Vector3d> points() const;

private:
    const MeshDistance& truth_;
    const DriveCrop& crop_;
    double spacing_, on_surface_;
    std::unordered_map<std::uint64_t, Eigen::Vector3d> cells_;
};

/// Where a drive's moving objects were at its scans' times: the boxes of their parts (the
/// connected components of each frame's movers mesh), grown by `pad` metres. A box stands for its
/// part: the simulator's parts are boxes and cylinders.
class SweptVolume {
public:
    explicit SweptVolume(double pad = 0.2);
    /// Adds one frame's moving objects (world frame; an empty mesh adds nothing).
    void add(const Mesh& movers);
    bool contains(const Eigen::Vector3d& p) const;
    std::size_t boxes() const { return boxes_.size(); }

private:
    static constexpr double kCell = 2.0;  // metres: the x-y cells boxes are listed in
    std::uint64_t cell_key(long x, long y) const;
    double pad_;
    std::vector<Eigen::AlignedBox3d> boxes_;
    std::unordered_map<std::uint64_t, std::vector<std::uint32_t>> cells_;
};

/// Evaluates a fused map. `gt` from MapGroundTruth, `crop` the same as config.max_distance's;
/// `swept`, when given, the movers' volume (MapMetrics::path_ghost_area). Throws InvalidInput when
/// the mesh has no triangle or nothing of it or of the GT remains in the crop.
MapMetrics evaluate_map(const Mesh& mesh, const MeshDistance& truth, const std::vector<Eigen::Vector3d>& gt, const DriveCrop& crop,
                        const MapEvaluationConfig& config, const SweptVolume* swept = nullptr);

}  // namespace lidarsurf
