#include "lidarsurf/mesh/mesh_filter.hpp"

#include <cstdint>
#include <numeric>
#include <vector>

namespace lidarsurf {
namespace {

// Union-find over vertices, with path halving and union by size.
class DisjointSets {
public:
    explicit DisjointSets(std::size_t n) : parent_(n), size_(n, 1) { std::iota(parent_.begin(), parent_.end(), std::uint32_t{0}); }
    std::uint32_t find(std::uint32_t x) {
        while (parent_[x] != x) x = parent_[x] = parent_[parent_[x]];
        return x;
    }
    void unite(std::uint32_t a, std::uint32_t b) {
        a = find(a);
        b = find(b);
        if (a == b) return;
        if (size_[a] < size_[b]) std::swap(a, b);
        parent_[b] = a;
        size_[a] += size_[b];
    }

private:
    std::vector<std::uint32_t> parent_, size_;
};

}  // namespace

std::size_t remove_small_components(Mesh& mesh, std::size_t min_triangles) {
    if (min_triangles <= 1 || mesh.triangles.empty()) return 0;
    mesh.check();
    DisjointSets sets(mesh.vertices.size());
    for (const auto& t : mesh.triangles) {
        sets.unite(t[0], t[1]);
        sets.unite(t[1], t[2]);
    }
    std::vector<std::uint32_t> triangles_of(mesh.vertices.size(), 0);
    for (const auto& t : mesh.triangles) ++triangles_of[sets.find(t[0])];
    std::vector<std::array<std::uint32_t, 3>> kept;
    kept.reserve(mesh.triangles.size());
    for (const auto& t : mesh.triangles)
        if (triangles_of[sets.find(t[0])] >= min_triangles) kept.push_back(t);
    const std::size_t removed = mesh.triangles.size() - kept.size();
    if (removed == 0) return 0;

    // Compact the vertices (and their attributes) that a kept triangle uses.
    constexpr std::uint32_t kUnused = UINT32_MAX;
    std::vector<std::uint32_t> remap(mesh.vertices.size(), kUnused);
    for (const auto& t : kept)
        for (std::uint32_t v : t) remap[v] = 0;
    std::uint32_t next = 0;
    for (std::size_t v = 0; v < remap.size(); ++v) {
        if (remap[v] == kUnused) continue;
        remap[v] = next;
        mesh.vertices[next] = mesh.vertices[v];
        if (!mesh.normals.empty()) mesh.normals[next] = mesh.normals[v];
        if (!mesh.levels.empty()) mesh.levels[next] = mesh.levels[v];
        if (!mesh.confidence.empty()) mesh.confidence[next] = mesh.confidence[v];
        ++next;
    }
    mesh.vertices.resize(next);
    if (!mesh.normals.empty()) mesh.normals.resize(next);
    if (!mesh.levels.empty()) mesh.levels.resize(next);
    if (!mesh.confidence.empty()) mesh.confidence.resize(next);
    for (auto& t : kept)
        for (std::uint32_t& v : t) v = remap[v];
    mesh.triangles = std::move(kept);
    return removed;
}

}  // namespace lidarsurf
