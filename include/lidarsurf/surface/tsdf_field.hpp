#pragma once
// The TSDF over the grid vertices near the data (Sec. III-C). Evaluated vertices are those whose
// largest neighbourhood H^{k_max}(v) contains at least one occupied voxel; every other vertex stays
// undefined (see docs/method.md for the reason).
#include <cstdint>
#include <unordered_map>
#include <vector>

#include "lidarsurf/core/voxel_grid.hpp"
#include "lidarsurf/surface/config.hpp"
#include "lidarsurf/surface/vertex_evaluator.hpp"

namespace lidarsurf {

class TsdfField {
public:
    /// Sample at lattice vertex v, or nullptr if v is undefined.
    const VertexSample* find(const VoxelKey& v) const;

    void insert(const VoxelKey& v, const VertexSample& s);
    std::size_t size() const { return keys_.size(); }
    const std::vector<VoxelKey>& keys() const { return keys_; }
    const std::vector<VertexSample>& samples() const { return samples_; }

    double voxel_size = 0.2;
    Eigen::Vector3d origin = Eigen::Vector3d::Zero();  ///< world position of vertex (0,0,0)

private:
    std::unordered_map<VoxelKey, std::uint32_t, VoxelKeyHash> index_;
    std::vector<VoxelKey> keys_;
    std::vector<VertexSample> samples_;
};

/// Vertices v whose H^{level}(v) contains an occupied voxel, sorted (z, y, x).
std::vector<VoxelKey> candidate_vertices(const VoxelGrid& grid, int level);

struct TsdfStats {
    std::size_t candidates = 0;  ///< vertices evaluated
    std::size_t defined = 0;     ///< vertices that received a TSDF value within the truncation
};

/// Builds the field from evaluated candidates: keeps the defined samples with |tsdf| <= truncation
/// (metres; infinity keeps all). Shared by every method that produces a TSDF on the lattice.
TsdfField assemble_field(const VoxelGrid& grid, const std::vector<VoxelKey>& candidates,
                         const std::vector<VertexSample>& samples, double truncation, TsdfStats* stats = nullptr);

/// Evaluates every candidate vertex (in parallel) and keeps the defined ones.
TsdfField compute_tsdf(const VoxelGrid& grid, const ReconstructionConfig& config,
                       const Eigen::Vector3d& sensor_world, TsdfStats* stats = nullptr);

}  // namespace lidarsurf
