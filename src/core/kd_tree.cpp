#include "lidarsurf/core/kd_tree.hpp"

#include <algorithm>
#include <string>

#include <nanoflann.hpp>

#include "lidarsurf/core/errors.hpp"

namespace lidarsurf {
namespace {

struct Adaptor {
    const std::vector<Eigen::Vector3d>* points;
    std::size_t kdtree_get_point_count() const { return points->size(); }
    double kdtree_get_pt(std::size_t i, std::size_t dim) const { return (*points)[i][static_cast<Eigen::Index>(dim)]; }
    template <class BBox>
    bool kdtree_get_bbox(BBox&) const { return false; }
};

using Tree = nanoflann::KDTreeSingleIndexAdaptor<nanoflann::L2_Simple_Adaptor<double, Adaptor>, Adaptor, 3, std::uint32_t>;

#if NANOFLANN_VERSION >= 0x150
using SearchParams = nanoflann::SearchParameters;
#else
using SearchParams = nanoflann::SearchParams;
#endif

// Collects every point within a squared radius (nanoflann's result-set protocol).
struct RadiusCollector {
    double squared_radius;
    std::vector<Neighbour>* out;
    void init() {}
    void clear() { out->clear(); }
    std::size_t size() const { return out->size(); }
    bool full() const { return true; }
    bool addPoint(double d, std::uint32_t i) {
        if (d <= squared_radius) out->push_back({i, d});
        return true;
    }
    double worstDist() const { return squared_radius; }
};

}  // namespace

struct KdTree::Index {
    Adaptor adaptor;
    Tree tree;
    explicit Index(const std::vector<Eigen::Vector3d>* pts)
        : adaptor{pts}, tree(3, adaptor, nanoflann::KDTreeSingleIndexAdaptorParams(16)) {
        if (!pts->empty()) tree.buildIndex();
    }
};

KdTree::KdTree(std::vector<Eigen::Vector3d> points) : points_(std::move(points)) {
    for (std::size_t i = 0; i < points_.size(); ++i)
        if (!points_[i].allFinite()) throw InvalidInput("kd-tree: point " + std::to_string(i) + " is not finite");
    index_ = std::make_unique<Index>(&points_);
}

KdTree::~KdTree() = default;
// The index points at points_; moving the vector keeps its buffer, but the adaptor holds the
// vector's address, so it is re-pointed after a move.
KdTree::KdTree(KdTree&& o) noexcept : points_(std::move(o.points_)), index_(std::move(o.index_)) {
    if (index_) index_->adaptor.points = &points_;
}
KdTree& KdTree::operator=(KdTree&& o) noexcept {
    points_ = std::move(o.points_);
    index_ = std::move(o.index_);
    if (index_) index_->adaptor.points = &points_;
    return *this;
}

Neighbour KdTree::nearest(const Eigen::Vector3d& q) const {
    if (points_.empty()) throw InvalidInput("kd-tree: nearest neighbour in an empty set");
    std::uint32_t index = 0;
    double d = 0;
    nanoflann::KNNResultSet<double, std::uint32_t> result(1);
    result.init(&index, &d);
    index_->tree.findNeighbors(result, q.data(), SearchParams());
    return {index, d};
}

void KdTree::knn(const Eigen::Vector3d& q, std::size_t k, std::vector<Neighbour>& out) const {
    out.clear();
    k = std::min(k, points_.size());
    if (k == 0) return;
    std::vector<std::uint32_t> idx(k);
    std::vector<double> d(k);
    nanoflann::KNNResultSet<double, std::uint32_t> result(k);
    result.init(idx.data(), d.data());
    index_->tree.findNeighbors(result, q.data(), SearchParams());
    for (std::size_t i = 0; i < result.size(); ++i) out.push_back({idx[i], d[i]});
}

void KdTree::radius(const Eigen::Vector3d& q, double r, std::vector<Neighbour>& out) const {
    out.clear();
    if (points_.empty() || !(r >= 0)) return;
    RadiusCollector collector{r * r, &out};
    index_->tree.findNeighbors(collector, q.data(), SearchParams());
}

}  // namespace lidarsurf
