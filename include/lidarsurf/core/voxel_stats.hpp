#pragma once
// Per-voxel point statistics (Sec. III-A): count |V|, mean V_mu and covariance V_sigma,
// updated incrementally per point (Welford) and mergeable (Chan et al. pairwise formula), so
// that the statistics of a neighbourhood H^k are the merge of its voxels' (Sec. III-B1).
#include <cstdint>

#include <Eigen/Core>

namespace lidarsurf {

/// A symmetric 3x3 matrix by its upper triangle: 48 bytes where an Eigen::Matrix3d takes 72.
struct SymmetricMatrix3 {
    double xx = 0, xy = 0, xz = 0, yy = 0, yz = 0, zz = 0;

    /// The matrix whose upper triangle is `m`'s (the lower one is not read).
    static SymmetricMatrix3 upper_of(const Eigen::Matrix3d& m) { return {m(0, 0), m(0, 1), m(0, 2), m(1, 1), m(1, 2), m(2, 2)}; }
    Eigen::Matrix3d full() const {
        Eigen::Matrix3d m;
        m << xx, xy, xz, xy, yy, yz, xz, yz, zz;
        return m;
    }
    bool operator==(const SymmetricMatrix3&) const = default;
};

struct VoxelStats {
    std::uint64_t count = 0;
    Eigen::Vector3d mean = Eigen::Vector3d::Zero();
    /// Scatter matrix M2 = sum_i (p_i - mean)(p_i - mean)^T.
    SymmetricMatrix3 scatter;

    /// Adds one point (Welford's update; stable far from the origin).
    void add(const Eigen::Vector3d& p);

    /// Merges another set of statistics into this one (Chan's parallel formula).
    void merge(const VoxelStats& other);

    /// Population covariance M2 / N (the maximum-likelihood estimate); zero when empty.
    Eigen::Matrix3d covariance() const;

    bool empty() const { return count == 0; }
};

}  // namespace lidarsurf
