#pragma once
// The TSDF over the grid vertices near the data (Sec. III-C). Evaluated vertices are those whose
// largest neighbourhood H^{k_max}(v) contains at least one occupied voxel; every other vertex stays
// undefined (see docs/method.md for the reason).
#include <array>
#include <cstdint>
#include <vector>

#include "lidarsurf/core/block_map.hpp"
#include "lidarsurf/core/cube.hpp"
#include "lidarsurf/core/voxel_grid.hpp"
#include "lidarsurf/surface/config.hpp"
#include "lidarsurf/surface/vertex_evaluator.hpp"

namespace lidarsurf {

class TsdfField {
public:
    TsdfField() = default;
    /// Adopts a field built elsewhere: `index` maps each vertex to its position in `keys` and
    /// `samples`, or to kUnevaluated / kUndefined; every sample must be defined.
    TsdfField(BlockMap<std::int32_t>&& index, std::vector<VoxelKey>&& keys, std::vector<VertexSample>&& samples,
              double voxel_size_, const Eigen::Vector3d& origin_)
        : voxel_size(voxel_size_), origin(origin_), index_(std::move(index)), keys_(std::move(keys)), samples_(std::move(samples)) {}

    /// Sample at lattice vertex v, or nullptr if v is undefined.
    const VertexSample* find(const VoxelKey& v) const { return sample_at(index_.find(v)); }

    /// What the field knows of v: whether it was evaluated, and its sample if it is defined. A
    /// field of the fast path (compute_seeded_tsdf) records the vertices it evaluated and found
    /// undefined (or beyond the truncation); other fields know only their defined vertices.
    struct Known {
        bool evaluated = false;
        const VertexSample* sample = nullptr;
    };
    Known known(const VoxelKey& v) const { return known_at(index_.find(v)); }
    /// Index values of a vertex with no sample: never evaluated, or evaluated and undefined.
    static constexpr std::int32_t kUnevaluated = -1, kUndefined = -2;

    /// find() remembering the last block: for coherent sequences of lookups (one per thread).
    class Accessor {
    public:
        explicit Accessor(const TsdfField& field) : field_(field), index_(field.index_) {}
        const VertexSample* find(const VoxelKey& v) { return field_.sample_at(index_.find(v)); }
        Known known(const VoxelKey& v) { return field_.known_at(index_.find(v)); }
        /// The samples of the corners of the cube with minimum corner `base` (corner c at base +
        /// (c & 1, c >> 1 & 1, c >> 2)); false, `s` partly set, at the first undefined one. A cube
        /// whose corners share its block (7 in 8 per axis) costs one block lookup, not eight; one
        /// on its block's last layer along some axes, one lookup per block its corners are in.
        bool corners(const VoxelKey& base, std::array<const VertexSample*, 8>& s) {
            using Index = BlockMap<std::int32_t>;
            const std::int32_t* slot = index_.find(base);
            if (!slot) return false;
            const int last = Index::last_axes(base);
            if (!last) {
                for (int c = 0; c < 8; ++c)
                    if (!(s[static_cast<std::size_t>(c)] = field_.sample_at(slot + Index::corner_step(c)))) return false;
                return true;
            }
            // Corner c lies in the block of base + (c & last), at its own offset there (the
            // offsets wrap): the blocks first, each looked up once (the accessor remembers one).
            std::array<const std::int32_t*, 8> block{};
            block[0] = slot - Index::offset_of(base);
            const VoxelKey base_block = Index::block_of(base);
            for (int n = 1; n < 8; ++n) {
                if (n & ~last) continue;
                const Index::Block* b = field_.index_.find_block(base_block + corner_offset(n));
                if (!b) return false;  // its corners are undefined
                block[static_cast<std::size_t>(n)] = b->data();
            }
            for (int c = 0; c < 8; ++c)
                if (!(s[static_cast<std::size_t>(c)] =
                          field_.sample_at(block[static_cast<std::size_t>(c & last)] + Index::offset_of(base + corner_offset(c)))))
                    return false;
            return true;
        }

    private:
        const TsdfField& field_;
        BlockMap<std::int32_t>::Accessor index_;
    };

    void insert(const VoxelKey& v, const VertexSample& s);
    std::size_t size() const { return keys_.size(); }
    /// Bytes held: the index blocks, the keys and the samples (capacities).
    std::size_t memory_bytes() const {
        return index_.memory_bytes() + keys_.capacity() * sizeof(VoxelKey) + samples_.capacity() * sizeof(VertexSample);
    }
    const std::vector<VoxelKey>& keys() const { return keys_; }
    const std::vector<VertexSample>& samples() const { return samples_; }

    double voxel_size = 0.2;
    Eigen::Vector3d origin = Eigen::Vector3d::Zero();  ///< world position of vertex (0,0,0)

private:
    Known known_at(const std::int32_t* slot) const {
        if (!slot || *slot == kUnevaluated) return {};
        return {true, sample_at(slot)};
    }
    // The sample an index slot points to; nullptr for an absent block or an undefined vertex.
    const VertexSample* sample_at(const std::int32_t* slot) const {
        return slot && *slot >= 0 ? &samples_[static_cast<std::size_t>(*slot)] : nullptr;
    }

    BlockMap<std::int32_t> index_{kUnevaluated};
    std::vector<VoxelKey> keys_;
    std::vector<VertexSample> samples_;
};

/// Vertices v whose H^{level}(v) contains an occupied voxel, sorted (z, y, x).
std::vector<VoxelKey> candidate_vertices(const VoxelGrid& grid, int level);

struct TsdfStats {
    std::size_t candidates = 0;  ///< vertices evaluated
    std::size_t defined = 0;     ///< vertices that received a TSDF value within the truncation
};

/// Builds the field from evaluated candidates: keeps the samples the truncation keeps (distance
/// infinity keeps every defined one). Shared by every method that produces a TSDF on the lattice.
TsdfField assemble_field(const VoxelGrid& grid, const std::vector<VoxelKey>& candidates,
                         const std::vector<VertexSample>& samples, const Truncation& truncation, TsdfStats* stats = nullptr);

/// Evaluates every candidate vertex (in parallel) and keeps the defined ones.
TsdfField compute_tsdf(const VoxelGrid& grid, const SurfaceConfig& config,
                       const Eigen::Vector3d& sensor_world, TsdfStats* stats = nullptr);

}  // namespace lidarsurf
