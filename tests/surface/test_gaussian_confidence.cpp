#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <random>

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>

#include "lidarsurf/surface/gaussian_confidence.hpp"

using namespace lidarsurf;

namespace {

LocalPlane plane_xy(double l1, double l2) {
    LocalPlane p;
    p.mean = {1.0, 2.0, 3.0};
    p.normal = {0, 0, 1};
    p.lambda1 = l1;
    p.lambda2 = l2;
    p.lambda3 = 0;
    p.covariance = Eigen::Vector3d(l1, l2, 0).asDiagonal();  // e1 = x, e2 = y
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

// Eq. (3) by its definition, with the in-plane axes e1, e2 from Eigen's iterative solver, is the
// oracle for the identity gaussian_confidence uses, on random tilted planes and vertices, from
// isotropic discs to strips (lambda2 = lambda1 / 20, the planarity guard's limit) and beyond.
TEST(GaussianConfidence, EqualsTheDefinitionThroughTheInPlaneAxes) {
    std::mt19937 rng(3);
    std::normal_distribution<double> g;
    std::uniform_real_distribution<double> u(0.0, 1.0);
    for (int trial = 0; trial < 2000; ++trial) {
        const Eigen::Matrix3d r = Eigen::Quaterniond(g(rng), g(rng), g(rng), g(rng)).normalized().toRotationMatrix();
        const double l1 = 0.01 + 0.5 * u(rng), l2 = l1 * std::pow(10.0, -3.0 * u(rng)), l3 = l2 * 0.1 * u(rng);
        const Eigen::Matrix3d c = r * Eigen::Vector3d(l1, l2, l3).asDiagonal() * r.transpose();
        Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(c);
        LocalPlane p;
        p.mean = Eigen::Vector3d(g(rng), g(rng), g(rng));
        p.normal = eig.eigenvectors().col(0);
        p.lambda1 = eig.eigenvalues()[2];
        p.lambda2 = eig.eigenvalues()[1];
        p.lambda3 = eig.eigenvalues()[0];
        p.covariance = c;
        const Eigen::Vector3d e1 = eig.eigenvectors().col(2), e2 = eig.eigenvectors().col(1);
        const Eigen::Vector3d v = p.mean + 1.5 * std::sqrt(l1) * Eigen::Vector3d(g(rng), g(rng), g(rng));
        const double a = e1.dot(v - p.mean), b = e2.dot(v - p.mean);
        const double expected = std::exp(-0.5 * (a * a / p.lambda1 + b * b / p.lambda2)) /
                                (2.0 * std::numbers::pi * std::sqrt(p.lambda1 * p.lambda2));
        EXPECT_NEAR(gaussian_confidence(p, v), expected, 1e-9 * expected + 1e-300) << trial;
    }
}

}  // namespace
