#include "lidarsurf/core/voxel_stats.hpp"

namespace lidarsurf {

void VoxelStats::add(const Eigen::Vector3d& p) {
    // Welford: mean_n = mean_{n-1} + (p - mean_{n-1}) / n ; M2 += (p - mean_{n-1})(p - mean_n)^T,
    // whose upper triangle is kept (the product is symmetric up to rounding).
    ++count;
    const Eigen::Vector3d delta = p - mean;
    mean += delta / static_cast<double>(count);
    const Eigen::Vector3d e = p - mean;
    SymmetricMatrix3& s = scatter;
    s.xx += delta.x() * e.x(), s.xy += delta.x() * e.y(), s.xz += delta.x() * e.z();
    s.yy += delta.y() * e.y(), s.yz += delta.y() * e.z(), s.zz += delta.z() * e.z();
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
    const Eigen::Vector3d d = other.mean - mean;
    mean += d * (nb / n);
    const double w = na * nb / n;
    const SymmetricMatrix3& o = other.scatter;
    SymmetricMatrix3& s = scatter;
    s.xx += o.xx + d.x() * d.x() * w, s.xy += o.xy + d.x() * d.y() * w, s.xz += o.xz + d.x() * d.z() * w;
    s.yy += o.yy + d.y() * d.y() * w, s.yz += o.yz + d.y() * d.z() * w, s.zz += o.zz + d.z() * d.z() * w;
    count += other.count;
}

Eigen::Matrix3d VoxelStats::covariance() const {
    if (count == 0) return Eigen::Matrix3d::Zero();
    return scatter.full() / static_cast<double>(count);
}

}  // namespace lidarsurf
