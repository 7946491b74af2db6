#include "lidarsurf/mesh/mesh.hpp"

#include <string>

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
    for (const auto& t : part.triangles) triangles.push_back({t[0] + base, t[1] + base, t[2] + base});
}

}  // namespace lidarsurf
