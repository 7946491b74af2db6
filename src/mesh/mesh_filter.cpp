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
    mesh.keep_triangles(std::move(kept));
    return removed;
}

}  // namespace lidarsurf
