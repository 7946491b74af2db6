#pragma once
// Per-voxel point statistics (Sec. III-A): count |V|, mean V_mu and covariance V_sigma,
// updated incrementally per point (Welford) and mergeable (Chan et al. pairwise formula), so
// that the statistics of a neighbourhood H^k are the merge of its voxels' (Sec. III-B1).
#include <cstdint>

#include <Eigen/Core>

namespace lidarsurf {

struct VoxelStats {
    std::uint64_t count = 0;
    Eigen::Vector3d mean = Eigen::Vector3d::Zero();
    /// Scatter matrix M2 = sum_i (p_i - mean)(p_i - mean)^T.
    Eigen::Matrix3d scatter = Eigen::Matrix3d::Zero();

    /// Adds one point (Welford's update; stable far from the origin).
    void add(const Eigen::Vector3d& p);

    /// Merges another set of statistics into this one (Chan's parallel formula).
    void merge(const VoxelStats& other);

    /// Population covariance M2 / N (the maximum-likelihood estimate); zero when empty.
    Eigen::Matrix3d covariance() const;

    bool empty() const { return count == 0; }
};

}  // namespace lidarsurf
