#include "lidarsurf/core/voxel_grid.hpp"

#include <cmath>
#include <sstream>

#include "lidarsurf/core/errors.hpp"

namespace lidarsurf {

VoxelGrid::VoxelGrid(double alpha, const std::optional<Eigen::Vector3d>& origin) : alpha_(alpha) {
    if (!std::isfinite(alpha) || alpha <= 0) throw InvalidArgument("voxel size must be finite and > 0");
    if (origin) {
        if (!origin->allFinite()) throw InvalidArgument("grid origin must be finite");
        origin_ = (*origin / alpha_).array().round().matrix() * alpha_;
        origin_set_ = true;
    }
}

VoxelKey VoxelGrid::key_of_local(const Eigen::Vector3d& local) const {
    VoxelKey key;
    for (int i = 0; i < 3; ++i) {
        const double f = std::floor(local[i] / alpha_);
        if (!(std::fabs(f) <= kMaxLatticeIndex)) {
            std::ostringstream msg;
            msg << "point " << to_world(local).transpose() << " is more than " << kMaxLatticeIndex
                << " voxels (" << kMaxLatticeIndex * alpha_ << " m) from the first point; "
                << "split the cloud or use a larger voxel size";
            throw InvalidInput(msg.str());
        }
        key[i] = static_cast<std::int32_t>(f);
    }
    return key;
}

void VoxelGrid::insert(const Eigen::Vector3d& world) {
    if (!world.allFinite()) throw InvalidInput("point coordinates must be finite");
    if (!origin_set_) {
        // Local origin: the lattice point nearest to the first point, so the world lattice is kept.
        origin_ = (world / alpha_).array().round().matrix() * alpha_;
        origin_set_ = true;
    }
    const Eigen::Vector3d local = world - origin_;
    const VoxelKey key = key_of_local(local);
    const VoxelKey block_key = BlockMap<std::int32_t>::block_of(key);
    if (!last_block_ || block_key != last_block_key_) {
        const std::uint32_t b = index_.block_index(block_key);
        if (b >= occupancy_.size()) occupancy_.resize(b + 1, Occupancy{});
        last_block_ = &index_.block_at(b);
        last_occupancy_ = &occupancy_[b];
        last_block_key_ = block_key;
    }
    const int offset = BlockMap<std::int32_t>::offset_of(key);
    std::int32_t& slot = (*last_block_)[static_cast<std::size_t>(offset)];
    if (slot < 0) {
        (*last_occupancy_)[static_cast<std::size_t>(offset >> 6)] |= std::uint64_t{1} << (offset & 63);
        slot = static_cast<std::int32_t>(stats_.size());
        stats_.emplace_back();
        keys_.push_back(key);
    }
    stats_[static_cast<std::size_t>(slot)].add(local);
    ++points_;
}

std::size_t VoxelGrid::memory_bytes() const {
    return index_.memory_bytes() + occupancy_.capacity() * sizeof(Occupancy) + stats_.capacity() * sizeof(VoxelStats) +
           keys_.capacity() * sizeof(VoxelKey);
}

const VoxelStats* VoxelGrid::find(const VoxelKey& key) const {
    const std::int32_t* slot = index_.find(key);
    return slot && *slot >= 0 ? &stats_[static_cast<std::size_t>(*slot)] : nullptr;
}

}  // namespace lidarsurf
