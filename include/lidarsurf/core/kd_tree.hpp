#pragma once
// Static 3-D kd-tree over a point set (nanoflann behind a small interface, so no nanoflann type
// leaks into the public headers). Used by the IMLS baseline and by the evaluation metrics.
#include <cstdint>
#include <memory>
#include <vector>

#include <Eigen/Core>

namespace lidarsurf {

struct Neighbour {
    std::uint32_t index = 0;    ///< index into KdTree::points()
    double squared_distance = 0;
};

class KdTree {
public:
    /// Builds the tree over a copy of `points` (all must be finite; throws InvalidInput otherwise).
    explicit KdTree(std::vector<Eigen::Vector3d> points);
    ~KdTree();
    KdTree(KdTree&&) noexcept;
    KdTree& operator=(KdTree&&) noexcept;

    const std::vector<Eigen::Vector3d>& points() const { return points_; }
    std::size_t size() const { return points_.size(); }
    bool empty() const { return points_.empty(); }

    /// Nearest point to q. Precondition: !empty() (throws InvalidInput otherwise).
    Neighbour nearest(const Eigen::Vector3d& q) const;

    /// The min(k, size()) nearest points, closest first.
    void knn(const Eigen::Vector3d& q, std::size_t k, std::vector<Neighbour>& out) const;

    /// Every point with ||p - q|| <= radius, in no particular order.
    void radius(const Eigen::Vector3d& q, double radius, std::vector<Neighbour>& out) const;

private:
    struct Index;
    std::vector<Eigen::Vector3d> points_;
    std::unique_ptr<Index> index_;
};

}  // namespace lidarsurf
