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
    auto& block = blocks_[block_of(key)];
    if (!block) {
        block = std::make_unique<Block>();
        block->fill(-1);
    }
    std::int32_t& slot = (*block)[local_index(key)];
    if (slot < 0) {
        slot = static_cast<std::int32_t>(stats_.size());
        stats_.emplace_back();
        keys_.push_back(key);
    }
    stats_[static_cast<std::size_t>(slot)].add(local);
    ++points_;
}

const VoxelGrid::Block* VoxelGrid::find_block(const VoxelKey& block_key) const {
    auto it = blocks_.find(block_key);
    return it == blocks_.end() ? nullptr : it->second.get();
}

const VoxelStats* VoxelGrid::find(const VoxelKey& key) const {
    const Block* block = find_block(block_of(key));
    if (!block) return nullptr;
    const std::int32_t idx = (*block)[local_index(key)];
    return idx < 0 ? nullptr : &stats_[static_cast<std::size_t>(idx)];
}

}  // namespace lidarsurf
