#include "lidarsurf/mesh/mesh.hpp"

#include <cstdint>
#include <string>
#include <utility>

#include <Eigen/Geometry>

#include "lidarsurf/core/errors.hpp"

namespace lidarsurf {

void Mesh::check() const {
    const std::size_t n = vertices.size();
    auto attr = [n](std::size_t size, const char* name) {
        if (size != 0 && size != n)
            throw InvalidInput(std::string("mesh attribute '") + name + "' has " + std::to_string(size) +
                               " entries for " + std::to_string(n) + " vertices");
    };
    attr(normals.size(), "normals");
    attr(levels.size(), "levels");
    attr(confidence.size(), "confidence");
    attr(intensity.size(), "intensity");
    for (const auto& t : triangles)
        for (std::uint32_t i : t)
            if (i >= n) throw InvalidInput("mesh triangle refers to vertex " + std::to_string(i) + " of " + std::to_string(n));
}

double Mesh::triangle_area(std::size_t i) const {
    const auto& t = triangles[i];
    const Eigen::Vector3d& a = vertices[t[0]];
    return 0.5 * (vertices[t[1]] - a).cross(vertices[t[2]] - a).norm();
}

void Mesh::append(const Mesh& part) {
    const auto base = static_cast<std::uint32_t>(vertices.size());
    vertices.insert(vertices.end(), part.vertices.begin(), part.vertices.end());
    normals.insert(normals.end(), part.normals.begin(), part.normals.end());
    levels.insert(levels.end(), part.levels.begin(), part.levels.end());
    confidence.insert(confidence.end(), part.confidence.begin(), part.confidence.end());
    intensity.insert(intensity.end(), part.intensity.begin(), part.intensity.end());
    for (const auto& t : part.triangles) triangles.push_back({t[0] + base, t[1] + base, t[2] + base});
}

void Mesh::append(const Mesh& part, std::span<const std::int64_t> existing) {
    if (existing.size() != part.vertices.size()) throw InvalidArgument("Mesh::append: one entry of `existing` per vertex of the part");
    std::vector<std::uint32_t> index(part.vertices.size());
    for (std::size_t i = 0; i < part.vertices.size(); ++i) {
        if (existing[i] >= 0) {
            if (static_cast<std::size_t>(existing[i]) >= vertices.size()) throw InvalidArgument("Mesh::append: an existing vertex out of range");
            index[i] = static_cast<std::uint32_t>(existing[i]);
            continue;
        }
        index[i] = static_cast<std::uint32_t>(vertices.size());
        vertices.push_back(part.vertices[i]);
        if (!part.normals.empty()) normals.push_back(part.normals[i]);
        if (!part.levels.empty()) levels.push_back(part.levels[i]);
        if (!part.confidence.empty()) confidence.push_back(part.confidence[i]);
        if (!part.intensity.empty()) intensity.push_back(part.intensity[i]);
    }
    for (const auto& t : part.triangles) triangles.push_back({index[t[0]], index[t[1]], index[t[2]]});
}

void Mesh::keep_triangles(std::vector<std::array<std::uint32_t, 3>> kept) {
    constexpr std::uint32_t kUnused = UINT32_MAX;
    std::vector<std::uint32_t> remap(vertices.size(), kUnused);
    for (const auto& t : kept)
        for (std::uint32_t v : t) remap[v] = 0;
    std::uint32_t next = 0;
    for (std::size_t v = 0; v < remap.size(); ++v) {
        if (remap[v] == kUnused) continue;
        remap[v] = next;
        vertices[next] = vertices[v];
        if (!normals.empty()) normals[next] = normals[v];
        if (!levels.empty()) levels[next] = levels[v];
        if (!confidence.empty()) confidence[next] = confidence[v];
        if (!intensity.empty()) intensity[next] = intensity[v];
        ++next;
    }
    vertices.resize(next);
    if (!normals.empty()) normals.resize(next);
    if (!levels.empty()) levels.resize(next);
    if (!confidence.empty()) confidence.resize(next);
    if (!intensity.empty()) intensity.resize(next);
    for (auto& t : kept)
        for (std::uint32_t& v : t) v = remap[v];
    triangles = std::move(kept);
}

}  // namespace lidarsurf
