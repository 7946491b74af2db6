#include "lidarsurf/surface/neighbourhood.hpp"

#include <cmath>

#include "lidarsurf/core/errors.hpp"

namespace lidarsurf {

VoxelStats merge_box(const VoxelGrid& grid, const VoxelBox& box) {
    VoxelStats acc;
    grid.for_each_in_box(box.lo, box.hi, [&](const VoxelKey&, const VoxelStats& s) { acc.merge(s); });
    return acc;
}

VoxelStats merge_neighbourhood(const VoxelGrid& grid, const VoxelKey& v, int k) {
    if (k < 1) throw InvalidArgument("neighbourhood level must be >= 1");
    return merge_box(grid, {v.array() - k, v.array() + (k - 1)});  // [v-k, v+k-1]^3
}

SlabExtension radial_extension(const Eigen::Vector3d& position, const Eigen::Vector3d& sensor, int voxels) {
    const Eigen::Vector3d r = position - sensor;
    if (std::abs(r.x()) >= std::abs(r.y())) return {voxels, 0};
    return {0, voxels};
}

VoxelBox slab_box(const VoxelKey& v, int k, SlabExtension e) {
    if (k < 1) throw InvalidArgument("neighbourhood level must be >= 1");
    if (e.x < 0 || e.y < 0) throw InvalidArgument("slab extension must be >= 0");
    return {{v.x() - k - e.x, v.y() - k - e.y, v.z() - 1}, {v.x() + k - 1 + e.x, v.y() + k - 1 + e.y, v.z()}};
}

std::array<VoxelBox, 2> bridge_boxes(const VoxelKey& v, int k, int reach, const Eigen::Vector3d& position, const Eigen::Vector3d& sensor) {
    if (k < 1 || reach < 0) throw InvalidArgument("bridge boxes need k >= 1 and reach >= 0");
    const int axis = radial_extension(position, sensor, 1).x ? 0 : 1, across = 1 - axis;  // the radial slabs' axis
    VoxelBox lower{v, v}, upper{v, v};
    for (VoxelBox* b : {&lower, &upper}) {
        b->lo[across] = v[across] - k;
        b->hi[across] = v[across] + k - 1;
        b->lo.z() = v.z() - 2;
        b->hi.z() = v.z() + 1;
    }
    lower.lo[axis] = v[axis] - k - reach;
    lower.hi[axis] = v[axis] - 1;
    upper.lo[axis] = v[axis];
    upper.hi[axis] = v[axis] + k - 1 + reach;
    if (position[axis] >= sensor[axis]) return {lower, upper};  // the sensor is on the lower side
    return {upper, lower};
}

std::array<VoxelBox, 6> shell_boxes(const VoxelKey& v, int k) {
    const VoxelKey lo = v.array() - k, hi = v.array() + (k - 1);
    const int ilo = -k + 1, ihi = k - 2;  // inner range offsets [v-k+1, v+k-2]
    return {{
        {{lo.x(), lo.y(), lo.z()}, {hi.x(), hi.y(), lo.z()}},
        {{lo.x(), lo.y(), hi.z()}, {hi.x(), hi.y(), hi.z()}},
        {{lo.x(), lo.y(), v.z() + ilo}, {hi.x(), lo.y(), v.z() + ihi}},
        {{lo.x(), hi.y(), v.z() + ilo}, {hi.x(), hi.y(), v.z() + ihi}},
        {{lo.x(), v.y() + ilo, v.z() + ilo}, {lo.x(), v.y() + ihi, v.z() + ihi}},
        {{hi.x(), v.y() + ilo, v.z() + ilo}, {hi.x(), v.y() + ihi, v.z() + ihi}},
    }};
}

void grow_neighbourhood(const VoxelGrid& grid, const VoxelKey& v, int k, VoxelStats& acc) {
    if (k < 1) throw InvalidArgument("neighbourhood level must be >= 1");
    auto merge = [&](const VoxelKey&, const VoxelStats& s) { acc.merge(s); };
    if (k == 1) {
        grid.for_each_in_box(v.array() - 1, v, merge);
        return;
    }
    for (const VoxelBox& b : shell_boxes(v, k)) grid.for_each_in_box(b.lo, b.hi, merge);
}

}  // namespace lidarsurf
