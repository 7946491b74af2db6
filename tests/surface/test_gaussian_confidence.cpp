#include <gtest/gtest.h>

#include <cmath>

#include "lidarsurf/surface/gaussian_confidence.hpp"

using namespace lidarsurf;

namespace {

LocalPlane plane_xy(double l1, double l2) {
    LocalPlane p;
    p.mean = {1.0, 2.0, 3.0};
    p.normal = {0, 0, 1};
    p.e1 = {1, 0, 0};
    p.e2 = {0, 1, 0};
    p.lambda1 = l1;
    p.lambda2 = l2;
    p.lambda3 = 0;
    return p;
}

TEST(GaussianConfidence, HandComputedValues) {
    const LocalPlane p = plane_xy(0.04, 0.01);
    // At the mean: 1 / (2 pi sqrt(0.04 * 0.01)) = 1 / (2 pi 0.02) = 7.957747154594767
    EXPECT_NEAR(gaussian_confidence(p, p.mean), 7.957747154594767, 1e-12);
    // One sigma along e1 (0.2 m): times exp(-1/2) = 4.826617631502695
    EXPECT_NEAR(gaussian_confidence(p, p.mean + Eigen::Vector3d(0.2, 0, 0)), 4.826617631502695, 1e-9);
    // (0.2, 0.1): Mahalanobis^2 = 1 + 1 = 2 -> times exp(-1) = 2.927491576215958
    EXPECT_NEAR(gaussian_confidence(p, p.mean + Eigen::Vector3d(0.2, 0.1, 0)), 2.927491576215958, 1e-9);
    // The vertex is projected onto the plane first: its height above the plane does not matter.
    EXPECT_NEAR(gaussian_confidence(p, p.mean + Eigen::Vector3d(0.2, 0.1, 0.7)), 2.927491576215958, 1e-9);
}

TEST(GaussianConfidence, ThresholdAtPaperTau) {
    // lambda1 = lambda2 = 0.25 (0.5 m spread, a k = 5 neighbourhood): peak 1/(2 pi 0.25) = 0.6366;
    // pdf >= 0.2 where r^2/0.25 <= 2 ln(0.6366/0.2), i.e. r <= 0.7609 m.
    const LocalPlane p = plane_xy(0.25, 0.25);
    EXPECT_GE(gaussian_confidence(p, p.mean + Eigen::Vector3d(0.75, 0, 0)), 0.2);
    EXPECT_LT(gaussian_confidence(p, p.mean + Eigen::Vector3d(0.0, 0.77, 0)), 0.2);
}

}  // namespace
