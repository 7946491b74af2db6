#include "lidarsurf/surface/gaussian_confidence.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace lidarsurf {

double gaussian_confidence(const LocalPlane& plane, const Eigen::Vector3d& v) {
    // w = v - n n.(v - mu) lies on the plane; its coordinates in the (e1, e2) frame centred on mu
    // are a = e1.d and b = e2.d, d = v - mu, since e1, e2 are orthogonal to n. With d = a e1 +
    // b e2 + (n.d) n and H_sigma = sum_i lambda_i e_i e_i^T:
    //   q0 = a^2 + b^2             = |d|^2 - (n.d)^2,
    //   q1 = lambda1 a^2 + lambda2 b^2 = d^T H_sigma d - lambda3 (n.d)^2,
    // and a^2 / lambda1 + b^2 / lambda2 = (lambda2 a^2 + lambda1 b^2) / (lambda1 lambda2)
    //                                  = ((lambda1 + lambda2) q0 - q1) / (lambda1 lambda2),
    // so e1 and e2 are not needed (the difference is >= lambda2 q0: no cancellation unless the
    // plane is a line, which the planarity guard rejects).
    const Eigen::Vector3d d = v - plane.mean;
    const double nd = plane.normal.dot(d);
    const double q0 = d.squaredNorm() - nd * nd;
    const double q1 = d.dot(plane.covariance * d) - plane.lambda3 * nd * nd;
    const double mahalanobis2 = std::max(((plane.lambda1 + plane.lambda2) * q0 - q1) / (plane.lambda1 * plane.lambda2), 0.0);
    // Eq. (3): N_PDF(w | mu, diag(lambda1, lambda2)) = exp(-m^2/2) / (2 pi sqrt(lambda1 lambda2)).
    return std::exp(-0.5 * mahalanobis2) / (2.0 * std::numbers::pi * std::sqrt(plane.lambda1 * plane.lambda2));
}

}  // namespace lidarsurf
