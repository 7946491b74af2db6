// The cube's faces and crossed-face table against their geometric definitions: each face holds
// the four corners on its side (bit f / 2 of the corner index equal to f % 2), listed
// counter-clockwise seen from outside (consecutive corners adjacent, and the cross product of two
// consecutive edges along the outward normal); a face is crossed exactly when its corners' signs
// differ, counted corner by corner.
#include <gtest/gtest.h>

#include <set>

#include <Eigen/Geometry>

#include "lidarsurf/core/cube.hpp"

using namespace lidarsurf;

TEST(Cube, FacesAreTheCornersOfEachSideCounterClockwiseFromOutside) {
    for (int f = 0; f < 6; ++f) {
        const int axis = f / 2, side = f % 2;
        const auto& face = kCubeFaces[static_cast<std::size_t>(f)];
        std::set<int> corners(face.begin(), face.end());
        EXPECT_EQ(corners.size(), 4u) << f;
        for (int c : face) EXPECT_EQ((c >> axis) & 1, side) << f;
        Eigen::Vector3d outward = Eigen::Vector3d::Zero();
        outward[axis] = side ? 1.0 : -1.0;
        for (int i = 0; i < 4; ++i) {
            const Eigen::Vector3d a = corner_offset(face[static_cast<std::size_t>(i)]).cast<double>();
            const Eigen::Vector3d b = corner_offset(face[static_cast<std::size_t>((i + 1) % 4)]).cast<double>();
            const Eigen::Vector3d c = corner_offset(face[static_cast<std::size_t>((i + 2) % 4)]).cast<double>();
            EXPECT_DOUBLE_EQ((b - a).norm(), 1.0) << f;                 // adjacent corners
            EXPECT_GT((b - a).cross(c - b).dot(outward), 0.0) << f;     // counter-clockwise from outside
        }
    }
    for (int c = 0; c < 8; ++c) EXPECT_EQ(corner_offset(c), VoxelKey(c % 2, (c / 2) % 2, c / 4));
}

TEST(Cube, CrossedFacesAreTheFacesWithBothSigns) {
    for (int config = 0; config < 256; ++config)
        for (int f = 0; f < 6; ++f) {
            bool negative = false, positive = false;
            for (int c = 0; c < 8; ++c) {
                if (((c >> (f / 2)) & 1) != f % 2) continue;  // not on face f
                ((config >> c) & 1 ? negative : positive) = true;
            }
            EXPECT_EQ(((kCrossedFaces[static_cast<std::size_t>(config)] >> f) & 1) != 0, negative && positive) << config << " " << f;
        }
}
