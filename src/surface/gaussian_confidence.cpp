#include "lidarsurf/surface/gaussian_confidence.hpp"

#include <cmath>
#include <numbers>

namespace lidarsurf {

double gaussian_confidence(const LocalPlane& plane, const Eigen::Vector3d& v) {
    // w = v - n n.(v - mu) lies on the plane; its coordinates in the (e1, e2) frame centred on mu
    // are e1.(v - mu) and e2.(v - mu) because e1, e2 are orthogonal to n.
    const Eigen::Vector3d d = v - plane.mean;
    const double a = plane.e1.dot(d), b = plane.e2.dot(d);
    const double mahalanobis2 = a * a / plane.lambda1 + b * b / plane.lambda2;
    // Eq. (3): N_PDF(w | mu, diag(lambda1, lambda2)) = exp(-m^2/2) / (2 pi sqrt(lambda1 lambda2)).
    return std::exp(-0.5 * mahalanobis2) / (2.0 * std::numbers::pi * std::sqrt(plane.lambda1 * plane.lambda2));
}

}  // namespace lidarsurf
