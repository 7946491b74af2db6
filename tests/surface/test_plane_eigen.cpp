// plane_eigen against Eigen's iterative solver (the oracle) on random symmetric covariances of
// the shapes planes meet: flat patches, strips, isotropic discs, lines (refused), scaled over
// twelve decades; and the matrices it must refuse. plane_eigen4 against plane_eigen, bit for bit.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <functional>
#include <limits>
#include <random>

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>

#include "lidarsurf/surface/plane_eigen.hpp"
#include "test_util.hpp"

using namespace lidarsurf;

namespace {

// R diag(l1, l2, l3) R^T for a rotation R; R's columns are the true eigenvectors.
Eigen::Matrix3d with_eigen(double l1, double l2, double l3, const Eigen::Matrix3d& r) {
    return r * Eigen::Vector3d(l1, l2, l3).asDiagonal() * r.transpose();
}

Eigen::Matrix3d random_rotation(std::mt19937& rng) {
    std::normal_distribution<double> g;
    return Eigen::Quaterniond(g(rng), g(rng), g(rng), g(rng)).normalized().toRotationMatrix();
}

// Eigenvalues spread over 8 decades below the largest, times a scale from 1e-6 to 1e6, sorted
// (l1 >= l2 >= l3), in a random frame r.
struct RandomEigen {
    std::array<double, 3> l;
    Eigen::Matrix3d r;
    Eigen::Matrix3d covariance() const { return with_eigen(l[0], l[1], l[2], r); }
};
RandomEigen random_eigen(std::mt19937& rng) {
    std::uniform_real_distribution<double> u(0.0, 1.0);
    RandomEigen e;
    const double scale = std::pow(10.0, 12.0 * u(rng) - 6.0);
    for (double& x : e.l) x = scale * std::pow(10.0, -8.0 * u(rng));
    std::sort(e.l.begin(), e.l.end(), std::greater<>());
    e.r = random_rotation(rng);
    return e;
}

TEST(PlaneEigen, MatchesTheIterativeSolverOnRandomCovariances) {
    std::mt19937 rng(7);
    int solved = 0;
    for (int trial = 0; trial < 20000; ++trial) {
        const RandomEigen e = random_eigen(rng);
        const std::array<double, 3>& l = e.l;
        const Eigen::Matrix3d& r = e.r;
        const Eigen::Matrix3d c = e.covariance();
        const auto eig = plane_eigen(c);
        const double spread = l[0] - l[2], gap3 = l[1] - l[2];
        // Refused exactly when lambda2 - lambda3 is within 1e-3 of the spread (up to rounding).
        if (gap3 < 0.99e-3 * spread) {
            EXPECT_FALSE(eig) << trial;
            continue;
        }
        if (gap3 > 1.01e-3 * spread) {
            ASSERT_TRUE(eig) << trial;
        }
        if (!eig) continue;
        ++solved;
        Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> oracle(c);
        const Eigen::Vector3d ev = oracle.eigenvalues();
        // lambda3 to rounding; lambda1 and lambda2 come from a quadratic, whose roots carry
        // eps s^2 / (lambda1 - lambda2) of error (sqrt(eps) when they coincide) while their sum and
        // product, which the planarity guard and Eq. (3) use, stay exact.
        const double tol = 1e-12 * l[0];
        const double tol12 = std::min(tol + 1e-15 * l[0] * l[0] / (l[0] - l[1]), 3e-8 * l[0]);
        EXPECT_NEAR(eig->lambda1, ev[2], tol12) << trial;
        EXPECT_NEAR(eig->lambda2, ev[1], tol12) << trial;
        EXPECT_NEAR(eig->lambda1 + eig->lambda2, ev[2] + ev[1], tol) << trial;
        EXPECT_NEAR(eig->lambda1 * eig->lambda2, ev[2] * ev[1], tol * l[0]) << trial;
        EXPECT_NEAR(eig->lambda3, ev[0], tol) << trial;
        EXPECT_NEAR(eig->e3.norm(), 1.0, 1e-12);
        // The normal: parallel to the true one, to ~eps * spread / gap (the problem's conditioning).
        EXPECT_LT(eig->e3.cross(r.col(2)).norm(), 1e-12 * spread / gap3 + 1e-13) << trial;
    }
    EXPECT_GT(solved, 10000);  // log-uniform eigenvalues: a quarter of the draws are lines (lambda2 << lambda1)
}

// Newton's stop (a step <= 1e-13 T, or an estimated error after the step <= 1e-17 T) against the
// smallest root of the same matrix's characteristic polynomial solved in long double (64-bit
// mantissa) until its steps stop shrinking: on planar covariances (lambda3 from 1e-7.5 to 0.3 of
// lambda2, the shapes the evaluation fits), lambda3 must be the root to the rounding of the
// double coefficients, which a stop one step early would miss by far.
TEST(PlaneEigen, StopsAtTheRootToRounding) {
    std::mt19937 rng(31);
    std::uniform_real_distribution<double> u(0.0, 1.0);
    for (int trial = 0; trial < 5000; ++trial) {
        const double scale = std::pow(10.0, 6.0 * u(rng) - 5.0);  // 1e-5 .. 10 m^2
        const double l1 = scale, l2 = scale * (0.05 + 0.95 * u(rng)), l3 = l2 * std::pow(10.0, -7.0 * u(rng) - 0.5);
        const Eigen::Matrix3d c = with_eigen(l1, l2, l3, random_rotation(rng));
        const auto eig = plane_eigen(c);
        ASSERT_TRUE(eig) << trial;
        using Long = long double;
        const Long t = Long(c(0, 0)) + c(1, 1) + c(2, 2), shift = t / 3;
        const Long xx = c(0, 0) - shift, xy = c(0, 1), xz = c(0, 2), yy = c(1, 1) - shift, yz = c(1, 2), zz = c(2, 2) - shift;
        const Long m = xx * yy - xy * xy + xx * zz - xz * xz + yy * zz - yz * yz;
        const Long d = xx * (yy * zz - yz * yz) - xy * (xy * zz - yz * xz) + xz * (xy * yz - yy * xz);
        Long l = -shift, last = HUGE_VALL;  // left of the root: Newton rises to it
        for (int i = 0; i < 200; ++i) {
            const Long step = ((l * l + m) * l - d) / (3 * l * l + m);
            if (!(std::fabs(step) < last)) break;
            last = std::fabs(step);
            l -= step;
        }
        const double root = static_cast<double>(shift + l);
        // The double coefficients carry ~eps T^3 of rounding, which moves the root by that over
        // p'(lambda3) = (l1 - l3)(l2 - l3).
        const double conditioning = std::numeric_limits<double>::epsilon() * std::pow(static_cast<double>(t), 3) / ((l1 - l3) * (l2 - l3));
        const double error = std::fabs(eig->lambda3 - root) / conditioning;
        EXPECT_LT(error, 4.0) << trial << " l3 / l2 " << l3 / l2;  // 0.19 at worst; 1e-11 for 1e-17 in the stop fails it
    }
}

// Nearly isotropic covariances (all eigenvalues within a small spread s of each other, gaps s / 2):
// Newton's early stop (a step <= 1e-13 T) leaves an error of order 1e-23 T^3 / s^2 there, the
// case its bound is weakest for; the eigenvalues must still be right to rounding of T.
TEST(PlaneEigen, NearlyIsotropicCovariancesToRounding) {
    std::mt19937 rng(23);
    for (const double spread : {1e-1, 1e-2, 1e-3, 1e-4}) {
        for (int trial = 0; trial < 500; ++trial) {
            const Eigen::Matrix3d r = random_rotation(rng);
            const double l1 = 1.0, l2 = 1.0 - spread / 2, l3 = 1.0 - spread;
            const auto eig = plane_eigen(with_eigen(l1, l2, l3, r));
            ASSERT_TRUE(eig) << spread;
            EXPECT_NEAR(eig->lambda3, l3, 1e-13) << spread;
            EXPECT_NEAR(eig->lambda1 + eig->lambda2, l1 + l2, 1e-13) << spread;
            EXPECT_LT(eig->e3.cross(r.col(2)).norm(), 1e-13 / spread) << spread;  // conditioning eps T / gap
        }
    }
}

TEST(PlaneEigen, DiscsStripsAndLines) {
    std::mt19937 rng(11);
    for (int trial = 0; trial < 200; ++trial) {
        const Eigen::Matrix3d r = random_rotation(rng);
        // An isotropic disc (lambda1 = lambda2) and a strip at the planarity guard's limit.
        for (const double l2 : {0.04, 0.002}) {
            const auto plane = plane_eigen(with_eigen(0.04, l2, 1e-6, r));
            ASSERT_TRUE(plane);
            EXPECT_LT(plane->e3.cross(r.col(2)).norm(), 1e-12);
            EXPECT_NEAR(plane->lambda1, 0.04, 3e-8 * 0.04);  // sqrt(eps) for the disc (above)
            EXPECT_NEAR(plane->lambda2, l2, 3e-8 * 0.04);
            EXPECT_NEAR(plane->lambda1 + plane->lambda2, 0.04 + l2, 1e-15);
            EXPECT_NEAR(plane->lambda1 * plane->lambda2, 0.04 * l2, 1e-16);
            EXPECT_NEAR(plane->lambda3, 1e-6, 1e-15);
        }
        // Exactly flat (lambda3 = 0) and a line (lambda2 = lambda3): the first solved, the second refused.
        const auto flat = plane_eigen(with_eigen(0.04, 0.01, 0.0, r));
        ASSERT_TRUE(flat);
        EXPECT_NEAR(flat->lambda3, 0.0, 1e-16);
        EXPECT_LT(flat->e3.cross(r.col(2)).norm(), 1e-12);
        EXPECT_FALSE(plane_eigen(with_eigen(0.04, 1e-6, 1e-6, r)));
    }
    EXPECT_FALSE(plane_eigen(0.3 * Eigen::Matrix3d::Identity()));  // every direction a normal
    EXPECT_FALSE(plane_eigen(Eigen::Matrix3d::Zero()));
    EXPECT_FALSE(plane_eigen(with_eigen(0.04, 0.01, -1e-3, Eigen::Matrix3d::Identity())));  // not PSD
    Eigen::Matrix3d nan = Eigen::Matrix3d::Identity();
    nan(0, 1) = nan(1, 0) = std::nan("");
    EXPECT_FALSE(plane_eigen(nan));
}

// plane_eigen4's lanes give plane_eigen's bits at every SIMD level: random covariances over
// twelve decades (flat, strips, lines, nearly isotropic), grouped four by four with the matrices
// plane_eigen refuses (zero, not positive semi-definite, NaN, infinite), so that lanes that fail
// early sit beside lanes that take many Newton steps.
TEST(PlaneEigen, FourLanesGiveTheScalarBits) {
    std::mt19937 rng(23);
    std::uniform_real_distribution<double> u(0.0, 1.0);
    std::vector<Eigen::Matrix3d> pool;
    for (int trial = 0; trial < 4000; ++trial) {
        const RandomEigen e = random_eigen(rng);
        const Eigen::Matrix3d& r = e.r;
        pool.push_back(e.covariance());
        pool.push_back(with_eigen(0.04, 0.04 * (1.0 - 1e-3 * u(rng)), 0.04 * (1.0 - 2e-3 * u(rng)), r));  // nearly isotropic
        pool.push_back(with_eigen(0.04, 0.01 * u(rng), 1e-6 * u(rng), r));                                  // a lidar patch
    }
    Eigen::Matrix3d nan = Eigen::Matrix3d::Identity(), inf = Eigen::Matrix3d::Identity();
    nan(0, 1) = nan(1, 0) = std::nan("");
    inf(2, 2) = HUGE_VAL;
    for (const Eigen::Matrix3d& refused : {Eigen::Matrix3d(Eigen::Matrix3d::Zero()), Eigen::Matrix3d(0.3 * Eigen::Matrix3d::Identity()),
                                           with_eigen(0.04, 0.01, -1e-3, Eigen::Matrix3d::Identity()), nan, inf})
        for (int i = 0; i < 40; ++i) pool.insert(pool.begin() + static_cast<std::ptrdiff_t>(rng() % pool.size()), refused);
    pool.resize(pool.size() / 4 * 4);
    for (SimdLevel level : test::simd_levels()) {
        test::ScopedSimdLevel scoped(level);
        int solved = 0, refused = 0;
        for (std::size_t i = 0; i < pool.size(); i += 4) {
            const std::array<Eigen::Matrix3d, 4> four{pool[i], pool[i + 1], pool[i + 2], pool[i + 3]};
            const auto lanes = plane_eigen4(four);
            for (std::size_t j = 0; j < 4; ++j) {
                const auto one = plane_eigen(four[j]);
                ASSERT_EQ(lanes[j].has_value(), one.has_value()) << to_string(level) << " " << i + j;
                if (!one) {
                    ++refused;
                    continue;
                }
                ++solved;
                EXPECT_EQ(lanes[j]->lambda1, one->lambda1) << to_string(level) << " " << i + j;
                EXPECT_EQ(lanes[j]->lambda2, one->lambda2) << to_string(level) << " " << i + j;
                EXPECT_EQ(lanes[j]->lambda3, one->lambda3) << to_string(level) << " " << i + j;
                EXPECT_EQ(lanes[j]->e3, one->e3) << to_string(level) << " " << i + j;
            }
        }
        EXPECT_GT(solved, 4000) << to_string(level);
        EXPECT_GT(refused, 200) << to_string(level);  // the refused matrices and the lines
    }
}

}  // namespace
