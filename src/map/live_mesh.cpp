#include "lidarsurf/map/live_mesh.hpp"

#include <algorithm>
#include <chrono>
#include <cstring>
#include <tuple>

#include "lidarsurf/core/errors.hpp"
#include "lidarsurf/core/stopwatch.hpp"
#include "lidarsurf/mesh/marching_cubes.hpp"
#include "lidarsurf/mesh/vertex_intensity.hpp"
#include "lidarsurf/surface/seeded_surface.hpp"

namespace lidarsurf {
namespace {

using Clock = std::chrono::steady_clock;

const SurfaceConfig& checked(const SurfaceConfig& surface, const LiveMeshConfig& live) {
    LiveMesh::check(surface, live);
    return surface;
}

bool less_zyx(const VoxelKey& a, const VoxelKey& b) { return std::tie(a.z(), a.y(), a.x()) < std::tie(b.z(), b.y(), b.x()); }

bool same_mesh(const Mesh& a, const Mesh& b) {
    if (a.vertices.size() != b.vertices.size() || a.triangles.size() != b.triangles.size()) return false;
    return std::equal(a.vertices.begin(), a.vertices.end(), b.vertices.begin()) &&
           std::equal(a.triangles.begin(), a.triangles.end(), b.triangles.begin());
}

// Batches of due blocks: at least kMinBatch (one batch of a few blocks costs about as much as a
// few more: the margin and the threads' start), at most kMaxBatch.
constexpr std::size_t kMinBatch = 16, kMaxBatch = 1024;

}  // namespace

std::size_t MeshDelta::triangles() const {
    std::size_t n = 0;
    for (const MeshBlock& b : changed) n += b.mesh.triangles.size();
    return n;
}

void LiveMesh::check(const SurfaceConfig& surface, const LiveMeshConfig& live) {
    surface.validate();
    live.validate();
    if (!surface.seeded_surface)
        throw InvalidArgument("the live mesh needs the seeded surface (the paper's method as written meshes every defined cube of the map)");
}

LiveMesh::LiveMesh(const SurfaceConfig& surface, const LiveMeshConfig& live)
    : config_(checked(surface, live)), live_(live), changes_(live.live_growth, live.live_reach_blocks) {}

MeshDelta LiveMesh::update(VoxelGrid& grid, const Eigen::Vector3d& sensor, const Eigen::Vector3d& position, double budget_seconds) {
    const auto t0 = Clock::now();
    if (!started_) {
        started_ = true;
        grid.track_changes();
        changes_.record_all(grid);
    } else {
        changes_.record(grid, grid.take_changes());
    }
    MeshDelta delta;
    if (!grid.has_origin()) return delta;
    // The urgent blocks (never meshed, or one of their voxels removed) first, then those whose
    // points changed; each group nearest `position` first.
    std::vector<BlockChanges::Due> due = changes_.due_near(grid.to_local(position), grid.voxel_size(), live_.live_range);
    std::sort(due.begin(), due.end(), [](const BlockChanges::Due& a, const BlockChanges::Due& b) {
        if (a.urgent != b.urgent) return a.urgent;
        if (a.distance2 != b.distance2) return a.distance2 < b.distance2;
        return less_zyx(a.key, b.key);
    });

    const VertexPlacement placement = config_.snap_to_plane ? VertexPlacement::SnappedToPlane : VertexPlacement::Interpolated;
    std::size_t next = 0;
    while (next < due.size()) {
        const double spent = seconds_since(t0);
        if (budget_seconds > 0 && next > 0 && spent >= budget_seconds) break;
        std::size_t count = kMaxBatch;
        if (budget_seconds > 0 && seconds_per_block_ > 0)
            count = std::clamp(static_cast<std::size_t>((budget_seconds - spent) / seconds_per_block_), kMinBatch, kMaxBatch);
        count = std::min(count, due.size() - next);
        const auto tb = Clock::now();
        std::vector<VoxelKey> core(count);
        for (std::size_t i = 0; i < count; ++i) core[i] = due[next + i].key;
        const SearchRegion region = SearchRegion::around(core, live_.live_halo_cubes);
        const SeededTsdf seeded = compute_seeded_tsdf(grid, config_, sensor, EigenSolver::ClosedForm, nullptr, &region);
        // The active cubes of each core block (the cubes come sorted (z, y, x), so each block's too).
        BlockIndex position_of;
        for (std::size_t i = 0; i < count; ++i) position_of.try_emplace(core[i], static_cast<std::uint32_t>(i));
        std::vector<std::size_t> starts(count + 1, 0);
        for (const VoxelKey& cube : seeded.cubes)
            if (const std::uint32_t i = position_of.find(BlockMap<std::int32_t>::block_of(cube)); i != BlockIndex::kAbsent) ++starts[i + 1];
        for (std::size_t i = 0; i < count; ++i) starts[i + 1] += starts[i];
        std::vector<VoxelKey> cubes(starts[count]);
        {
            std::vector<std::size_t> at(starts.begin(), starts.end() - 1);
            for (const VoxelKey& cube : seeded.cubes)
                if (const std::uint32_t i = position_of.find(BlockMap<std::int32_t>::block_of(cube)); i != BlockIndex::kAbsent) cubes[at[i]++] = cube;
        }
        std::vector<Mesh> meshes = extract_meshes(seeded.field, cubes, starts, placement);
        for (Mesh& m : meshes) attach_intensity(m, grid, config_.max_reach());
        for (std::size_t i = 0; i < count; ++i) {
            const VoxelKey& key = core[i];
            changes_.mark_meshed(grid, key);
            const auto [slot, added] = index_.try_emplace(key, static_cast<std::uint32_t>(blocks_.size()));
            if (added) blocks_.push_back({key, Mesh{}});
            Mesh& old = blocks_[slot].mesh;
            if (meshes[i].triangles.empty()) meshes[i] = Mesh{};  // vertices whose triangles all had no area
            if (same_mesh(old, meshes[i])) continue;
            triangles_ = triangles_ - old.triangles.size() + meshes[i].triangles.size();
            if (meshes[i].triangles.empty()) {
                delta.removed.push_back(key);
                old = Mesh{};
            } else {
                old = meshes[i];
                delta.changed.push_back({key, std::move(meshes[i])});
            }
        }
        // A running mean of the time per block, for the next batch's size.
        const double per_block = seconds_since(tb) / static_cast<double>(count);
        seconds_per_block_ = seconds_per_block_ > 0 ? 0.7 * seconds_per_block_ + 0.3 * per_block : per_block;
        delta.meshed_blocks += count;
        next += count;
    }
    delta.pending = changes_.due_count();
    delta.seconds = seconds_since(t0);
    return delta;
}

std::vector<MeshBlock> LiveMesh::blocks() const {
    std::vector<MeshBlock> out;
    for (const MeshBlock& b : blocks_)
        if (!b.mesh.triangles.empty()) out.push_back(b);
    std::sort(out.begin(), out.end(), [](const MeshBlock& a, const MeshBlock& b) { return less_zyx(a.key, b.key); });
    return out;
}

Mesh LiveMesh::mesh() const { return concatenate(blocks()); }

std::size_t LiveMesh::memory_bytes() const {
    std::size_t bytes = changes_.memory_bytes() + index_.memory_bytes() + blocks_.capacity() * sizeof(MeshBlock);
    for (const MeshBlock& b : blocks_) {
        const Mesh& m = b.mesh;
        bytes += m.vertices.capacity() * sizeof(Eigen::Vector3d) + m.triangles.capacity() * sizeof(m.triangles[0]) +
                 m.normals.capacity() * sizeof(Eigen::Vector3f) + m.levels.capacity() + (m.confidence.capacity() + m.intensity.capacity()) * sizeof(float);
    }
    return bytes;
}

void apply(const MeshDelta& delta, std::vector<MeshBlock>& blocks) { apply(delta.removed, delta.changed, blocks); }

void apply(std::span<const VoxelKey> removed, std::span<const MeshBlock> changed, std::vector<MeshBlock>& blocks) {
    auto find = [&](const VoxelKey& key) {
        return std::lower_bound(blocks.begin(), blocks.end(), key, [](const MeshBlock& b, const VoxelKey& k) { return less_zyx(b.key, k); });
    };
    for (const VoxelKey& key : removed)
        if (auto it = find(key); it != blocks.end() && same_key(it->key, key)) blocks.erase(it);
    for (const MeshBlock& block : changed) {
        auto it = find(block.key);
        if (it != blocks.end() && same_key(it->key, block.key)) it->mesh = block.mesh;
        else blocks.insert(it, block);
    }
}

Mesh concatenate(const std::vector<MeshBlock>& blocks) {
    Mesh out;
    for (const MeshBlock& b : blocks) out.append(b.mesh);
    return out;
}

std::vector<MeshBlock> split_into_blocks(const Mesh& mesh, const Eigen::Vector3d& origin, double voxel_size) {
    if (!(voxel_size > 0)) throw InvalidArgument("split_into_blocks: voxel_size must be > 0");
    mesh.check();
    // Each triangle's block, then the triangles grouped by block in (z, y, x) order.
    std::vector<std::pair<VoxelKey, std::uint32_t>> owner(mesh.triangles.size());
    for (std::size_t t = 0; t < mesh.triangles.size(); ++t) {
        const auto& tri = mesh.triangles[t];
        const Eigen::Vector3d centroid = (mesh.vertices[tri[0]] + mesh.vertices[tri[1]] + mesh.vertices[tri[2]]) / 3.0;
        const Eigen::Vector3d lattice = ((centroid - origin) / voxel_size).array().floor();
        owner[t] = {BlockMap<std::int32_t>::block_of(lattice.cast<std::int32_t>()), static_cast<std::uint32_t>(t)};
    }
    std::stable_sort(owner.begin(), owner.end(), [](const auto& a, const auto& b) { return less_zyx(a.first, b.first); });
    std::vector<MeshBlock> blocks;
    std::vector<std::uint32_t> local(mesh.vertices.size()), stamp(mesh.vertices.size(), 0);
    const bool normals = mesh.normals.size() == mesh.vertices.size(), levels = mesh.levels.size() == mesh.vertices.size(),
               confidence = mesh.confidence.size() == mesh.vertices.size(), intensity = mesh.intensity.size() == mesh.vertices.size();
    for (std::size_t begin = 0; begin < owner.size();) {
        std::size_t end = begin;
        while (end < owner.size() && same_key(owner[end].first, owner[begin].first)) ++end;
        MeshBlock& block = blocks.emplace_back();
        block.key = owner[begin].first;
        Mesh& m = block.mesh;
        const auto mark = static_cast<std::uint32_t>(blocks.size());  // this block's stamp (never 0)
        for (std::size_t i = begin; i < end; ++i) {
            std::array<std::uint32_t, 3> tri{};
            for (int c = 0; c < 3; ++c) {
                const std::uint32_t v = mesh.triangles[owner[i].second][static_cast<std::size_t>(c)];
                if (stamp[v] != mark) {
                    stamp[v] = mark;
                    local[v] = static_cast<std::uint32_t>(m.vertices.size());
                    m.vertices.push_back(mesh.vertices[v]);
                    if (normals) m.normals.push_back(mesh.normals[v]);
                    if (levels) m.levels.push_back(mesh.levels[v]);
                    if (confidence) m.confidence.push_back(mesh.confidence[v]);
                    if (intensity) m.intensity.push_back(mesh.intensity[v]);
                }
                tri[static_cast<std::size_t>(c)] = local[v];
            }
            m.triangles.push_back(tri);
        }
        begin = end;
    }
    return blocks;
}

}  // namespace lidarsurf
