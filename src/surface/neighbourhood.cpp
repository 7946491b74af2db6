#include "lidarsurf/surface/neighbourhood.hpp"

#include "lidarsurf/core/errors.hpp"

namespace lidarsurf {

VoxelStats merge_neighbourhood(const VoxelGrid& grid, const VoxelKey& v, int k) {
    if (k < 1) throw InvalidArgument("neighbourhood level must be >= 1");
    VoxelStats acc;
    const VoxelKey lo = v.array() - k, hi = v.array() + (k - 1);  // [v-k, v+k-1]^3
    grid.for_each_in_box(lo, hi, [&](const VoxelKey&, const VoxelStats& s) { acc.merge(s); });
    return acc;
}

void grow_neighbourhood(const VoxelGrid& grid, const VoxelKey& v, int k, VoxelStats& acc) {
    if (k < 1) throw InvalidArgument("neighbourhood level must be >= 1");
    const VoxelKey lo = v.array() - k, hi = v.array() + (k - 1);
    if (k == 1) {
        grid.for_each_in_box(lo, hi, [&](const VoxelKey&, const VoxelStats& s) { acc.merge(s); });
        return;
    }
    // Shell H^k \ H^{k-1}: the two z-slabs, then the two y-slabs of the remaining z range, then
    // the two x-slabs of the remaining y and z range.
    auto add_box = [&](VoxelKey a, VoxelKey b) {
        grid.for_each_in_box(a, b, [&](const VoxelKey&, const VoxelStats& s) { acc.merge(s); });
    };
    const int ilo = -k + 1, ihi = k - 2;  // inner range offsets [v-k+1, v+k-2]
    add_box({lo.x(), lo.y(), lo.z()}, {hi.x(), hi.y(), lo.z()});
    add_box({lo.x(), lo.y(), hi.z()}, {hi.x(), hi.y(), hi.z()});
    add_box({lo.x(), lo.y(), v.z() + ilo}, {hi.x(), lo.y(), v.z() + ihi});
    add_box({lo.x(), hi.y(), v.z() + ilo}, {hi.x(), hi.y(), v.z() + ihi});
    add_box({lo.x(), v.y() + ilo, v.z() + ilo}, {lo.x(), v.y() + ihi, v.z() + ihi});
    add_box({hi.x(), v.y() + ilo, v.z() + ilo}, {hi.x(), v.y() + ihi, v.z() + ihi});
}

}  // namespace lidarsurf
