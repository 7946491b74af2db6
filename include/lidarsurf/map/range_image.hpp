#pragma once
// A scan seen from its viewpoint as a range image, what free-space carving tests voxels against
// (map/free_space.hpp; docs/method.md, "Free space"): columns of kAzimuthStep degrees, rows of
// kElevationStep degrees from the scan's lowest direction, per pixel the nearest return.
// The rays that returned nothing (when the input says which) mark the pixels no return fell in;
// one with such rays beside it in its row gets a return where the ray stopped seeing free space:
// up to the nearest return around it, `empty_range` at most.
//
// The image depends on the scan alone (and the frame it is computed in): a map fused in tiles
// builds it once per scan and carves every tile's grid with it (tiles/tiles.hpp).
#include <cstdint>
#include <optional>
#include <span>
#include <utility>
#include <vector>

#include <Eigen/Core>

namespace lidarsurf {

class RangeImage {
public:
    static constexpr float kAzimuthStep = 0.2f, kElevationStep = 0.4f;
    static constexpr int kColumns = 1800;
    static constexpr std::uint32_t kNoPixel = 0xffffffffu;

    /// The image of `points` (world frame; non-finite ones are no return) seen from `viewpoint`
    /// (world), computed in the frame whose origin is `origin` (a grid's, VoxelGrid::origin()).
    /// `no_return`: the unit directions (world) of the rays that returned nothing, or empty;
    /// `empty_range` (metres, 0: they say nothing) how far such a ray saw. `points` must outlive
    /// the image's use (return_point reads them).
    void build(const Eigen::Vector3d& origin, std::span<const Eigen::Vector3d> points, const Eigen::Vector3d& viewpoint,
               std::span<const Eigen::Vector3f> no_return, double empty_range);

    /// No finite direction: no pixel.
    bool empty() const { return rows_ == 0; }
    /// The origin of the image's frame (world).
    const Eigen::Vector3d& origin() const { return origin_; }
    /// The viewpoint in the image's frame.
    const Eigen::Vector3d& sensor() const { return s_; }
    std::size_t pixels() const { return static_cast<std::size_t>(rows_) * kColumns; }
    /// The pixel of direction `d` (image frame) at elevation `el` degrees, or kNoPixel.
    std::uint32_t pixel(const Eigen::Vector3d& d, float el) const;
    /// The pixel's nearest return (kNoPixel: none) and its squared range.
    std::uint32_t nearest(std::size_t q) const { return nearest_[q]; }
    float depth2(std::size_t q) const { return depth_[q]; }
    /// Whether return `target` (nearest()) is an empty pixel's: a ray that returned nothing.
    bool no_surface(std::uint32_t target) const { return target >= real_; }
    /// Return `target` in the image's frame.
    Eigen::Vector3d return_point(std::uint32_t target) const {
        return target >= real_ ? empty_points_[target - real_] : Eigen::Vector3d(points_[target] - origin_);
    }
    /// The surface normal at pixel `q`'s return from the returns beside it on the same surface,
    /// when they give one.
    std::optional<Eigen::Vector3d> normal(std::uint32_t q) const;
    /// The distance to the farthest finite return (metres).
    double farthest() const { return farthest_; }
    /// Empty pixels given a return.
    std::size_t empty_pixels() const { return empty_points_.size(); }

    std::size_t memory_bytes() const {
        return (pixel_of_.capacity() + nearest_.capacity() + empty_ray_.capacity()) * sizeof(std::uint32_t) +
               (depth_.capacity() + elevation_.capacity() + range2_.capacity()) * sizeof(float) + empty_.capacity() +
               empty_points_.capacity() * sizeof(Eigen::Vector3d) + empty_seen_.capacity() * sizeof(std::pair<std::size_t, float>);
    }

private:
    void mark_empty(std::span<const Eigen::Vector3f> no_return, double empty_range);

    std::span<const Eigen::Vector3d> points_;
    Eigen::Vector3d origin_ = Eigen::Vector3d::Zero(), s_ = Eigen::Vector3d::Zero();
    int rows_ = 0;
    float el_min_ = 0;      // the elevation of the first row (degrees)
    std::size_t real_ = 0;  // the scan's points: a nearest_ at or above this is an empty pixel's return
    double farthest_ = 0;
    // Kept from scan to scan (no page faults for fresh buffers).
    std::vector<std::uint32_t> pixel_of_, nearest_;
    std::vector<float> depth_, elevation_, range2_;  // per pixel; per point (elevation, squared range)
    // Rays that returned nothing: per pixel, whether one fell in it and the first one that did;
    // the empty pixels kept and how far their rays saw (squared); their returns, indexed by
    // nearest_ - real_.
    std::vector<std::uint8_t> empty_;
    std::vector<std::uint32_t> empty_ray_;
    std::vector<std::pair<std::size_t, float>> empty_seen_;
    std::vector<Eigen::Vector3d> empty_points_;
};

}  // namespace lidarsurf
