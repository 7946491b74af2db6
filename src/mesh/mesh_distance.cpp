#include "lidarsurf/mesh/mesh_distance.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>

#include "lidarsurf/core/errors.hpp"

namespace lidarsurf {

Eigen::Vector3d closest_point_on_triangle(const Eigen::Vector3d& p, const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                                          const Eigen::Vector3d& c) {
    // Voronoi regions of the vertices, then edges, then the face (Ericson 5.1.5).
    const Eigen::Vector3d ab = b - a, ac = c - a, ap = p - a;
    const double d1 = ab.dot(ap), d2 = ac.dot(ap);
    if (d1 <= 0 && d2 <= 0) return a;
    const Eigen::Vector3d bp = p - b;
    const double d3 = ab.dot(bp), d4 = ac.dot(bp);
    if (d3 >= 0 && d4 <= d3) return b;
    const double vc = d1 * d4 - d3 * d2;
    if (vc <= 0 && d1 >= 0 && d3 <= 0) return a + (d1 / (d1 - d3)) * ab;
    const Eigen::Vector3d cp = p - c;
    const double d5 = ab.dot(cp), d6 = ac.dot(cp);
    if (d6 >= 0 && d5 <= d6) return c;
    const double vb = d5 * d2 - d1 * d6;
    if (vb <= 0 && d2 >= 0 && d6 <= 0) return a + (d2 / (d2 - d6)) * ac;
    const double va = d3 * d6 - d5 * d4;
    if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0) return b + ((d4 - d3) / ((d4 - d3) + (d5 - d6))) * (c - b);
    const double sum = va + vb + vc;
    if (!(sum > 0)) {
        // Degenerate (zero-area) triangle: the closest point lies on one of its edges.
        auto on_segment = [&](const Eigen::Vector3d& s, const Eigen::Vector3d& t) {
            const Eigen::Vector3d d = t - s;
            const double len2 = d.squaredNorm();
            const double u = len2 > 0 ? std::clamp((p - s).dot(d) / len2, 0.0, 1.0) : 0.0;
            return Eigen::Vector3d(s + u * d);
        };
        Eigen::Vector3d best = on_segment(a, b);
        for (const Eigen::Vector3d& q : {on_segment(b, c), on_segment(c, a)})
            if ((q - p).squaredNorm() < (best - p).squaredNorm()) best = q;
        return best;
    }
    const double v = vb / sum, w = vc / sum;
    return a + v * ab + w * ac;
}

MeshDistance::MeshDistance(const Mesh& mesh) {
    if (mesh.triangles.empty()) throw InvalidInput("distance to a mesh with no triangle");
    const std::size_t n = mesh.triangles.size();
    for (const auto& t : mesh.triangles)
        for (std::uint32_t i : t)
            if (i >= mesh.vertices.size()) throw InvalidInput("mesh triangle refers to a missing vertex");
    original_.resize(n);
    std::iota(original_.begin(), original_.end(), 0u);
    a_.resize(n);
    b_.resize(n);
    c_.resize(n);
    for (std::size_t i = 0; i < n; ++i) {
        a_[i] = mesh.vertices[mesh.triangles[i][0]];
        b_[i] = mesh.vertices[mesh.triangles[i][1]];
        c_[i] = mesh.vertices[mesh.triangles[i][2]];
    }
    nodes_.reserve(2 * n / 4 + 2);
    build(0, static_cast<std::uint32_t>(n));
}

std::uint32_t MeshDistance::build(std::uint32_t first, std::uint32_t count) {
    constexpr std::uint32_t kLeaf = 4;
    const auto id = static_cast<std::uint32_t>(nodes_.size());
    nodes_.push_back({});
    Eigen::Vector3d lo = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity()), hi = -lo;
    for (std::uint32_t i = first; i < first + count; ++i) {
        lo = lo.cwiseMin(a_[i]).cwiseMin(b_[i]).cwiseMin(c_[i]);
        hi = hi.cwiseMax(a_[i]).cwiseMax(b_[i]).cwiseMax(c_[i]);
    }
    nodes_[id].lo = lo;
    nodes_[id].hi = hi;
    if (count <= kLeaf) {
        nodes_[id].first = first;
        nodes_[id].count = count;
        return id;
    }
    // Median split of the centroids along the longest axis of the box.
    Eigen::Index axis = 0;
    (hi - lo).maxCoeff(&axis);
    std::vector<std::uint32_t> order(count);
    std::iota(order.begin(), order.end(), first);
    const std::uint32_t half = count / 2;
    auto centroid = [&](std::uint32_t i) { return a_[i][axis] + b_[i][axis] + c_[i][axis]; };
    std::nth_element(order.begin(), order.begin() + half, order.end(),
                     [&](std::uint32_t x, std::uint32_t y) { return centroid(x) < centroid(y); });
    auto permute = [&](auto& v) {
        std::vector<std::decay_t<decltype(v[0])>> tmp(count);
        for (std::uint32_t i = 0; i < count; ++i) tmp[i] = v[order[i]];
        std::copy(tmp.begin(), tmp.end(), v.begin() + first);
    };
    permute(a_);
    permute(b_);
    permute(c_);
    permute(original_);
    const std::uint32_t left = build(first, half);
    const std::uint32_t right = build(first + half, count - half);
    nodes_[id].left = left;
    nodes_[id].right = right;
    return id;
}

SurfacePoint MeshDistance::closest(const Eigen::Vector3d& p) const {
    auto box_distance2 = [&](const Node& n) {
        const Eigen::Vector3d d = (n.lo - p).cwiseMax(p - n.hi).cwiseMax(0.0);
        return d.squaredNorm();
    };
    double best2 = std::numeric_limits<double>::infinity();
    SurfacePoint best;
    std::uint32_t stack[64];
    int top = 0;
    stack[top++] = 0;
    while (top > 0) {
        const Node& node = nodes_[stack[--top]];
        if (box_distance2(node) >= best2) continue;
        if (node.count > 0) {
            for (std::uint32_t i = node.first; i < node.first + node.count; ++i) {
                const Eigen::Vector3d q = closest_point_on_triangle(p, a_[i], b_[i], c_[i]);
                const double d2 = (q - p).squaredNorm();
                if (d2 < best2) {
                    best2 = d2;
                    best.point = q;
                    best.triangle = original_[i];
                }
            }
            continue;
        }
        // Visit the nearer child first (pushed last).
        const double dl = box_distance2(nodes_[node.left]), dr = box_distance2(nodes_[node.right]);
        if (dl < dr) {
            stack[top++] = node.right;
            stack[top++] = node.left;
        } else {
            stack[top++] = node.left;
            stack[top++] = node.right;
        }
    }
    best.distance = std::sqrt(best2);
    return best;
}

}  // namespace lidarsurf
