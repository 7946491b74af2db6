#include "lidarsurf/core/voxel_stats.hpp"

namespace lidarsurf {

void VoxelStats::add(const Eigen::Vector3d& p) {
    // Welford: mean_n = mean_{n-1} + (p - mean_{n-1}) / n ; M2 += (p - mean_{n-1})(p - mean_n)^T
    ++count;
    const Eigen::Vector3d delta = p - mean;
    mean += delta / static_cast<double>(count);
    scatter += delta * (p - mean).transpose();
}

void VoxelStats::merge(const VoxelStats& other) {
    if (other.count == 0) return;
    if (count == 0) {
        *this = other;
        return;
    }
    // Chan et al.: M2 = M2_a + M2_b + delta delta^T * n_a n_b / n
    const double na = static_cast<double>(count), nb = static_cast<double>(other.count);
    const double n = na + nb;
    const Eigen::Vector3d delta = other.mean - mean;
    mean += delta * (nb / n);
    scatter += other.scatter + (delta * delta.transpose()) * (na * nb / n);
    count += other.count;
}

Eigen::Matrix3d VoxelStats::covariance() const {
    if (count == 0) return Eigen::Matrix3d::Zero();
    return scatter / static_cast<double>(count);
}

}  // namespace lidarsurf
