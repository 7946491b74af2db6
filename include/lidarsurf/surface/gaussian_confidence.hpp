#pragma once
// Gaussian confidence (Sec. III-C1, Eq. 3): the 2-D Gaussian N(H_mu, diag(lambda1, lambda2)) of a
// neighbourhood, expressed in the plane's (e1, e2) frame, evaluated at w, the projection of the
// vertex v onto the plane.
#include <Eigen/Core>

#include "lidarsurf/surface/local_plane.hpp"

namespace lidarsurf {

/// N_PDF(w | H_mu, Sigma) with w = projection of v onto the plane. Units: 1/m^2. Computed from the
/// plane's covariance and eigenvalues, without its in-plane axes (an identity; see the .cpp).
double gaussian_confidence(const LocalPlane& plane, const Eigen::Vector3d& v);

}  // namespace lidarsurf
