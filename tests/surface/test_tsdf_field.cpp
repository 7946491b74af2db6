// TsdfField's accessor against the field's own lookups: the corners of a cube, whether they share
// the cube's block (one lookup) or not (eight), are the samples find() gives.
#include <gtest/gtest.h>

#include <array>
#include <random>

#include "lidarsurf/surface/tsdf_field.hpp"

using namespace lidarsurf;

TEST(TsdfField, AccessorCornersAreTheEightLookups) {
    // Random defined vertices, three in four, over blocks -2..1 on each axis (vertices -13..12).
    TsdfField field;
    std::mt19937 rng(23);
    std::uniform_real_distribution<float> u(-1.0f, 1.0f);
    for (int z = -13; z <= 12; ++z)
        for (int y = -13; y <= 12; ++y)
            for (int x = -13; x <= 12; ++x) {
                if (rng() % 4 == 0) continue;
                VertexSample s;
                s.defined = true;
                s.tsdf = u(rng);
                field.insert({x, y, z}, s);
            }
    TsdfField::Accessor accessor(field);
    std::size_t complete = 0, boundary = 0, checked = 0;
    for (int z = -14; z <= 12; ++z)
        for (int y = -14; y <= 12; ++y)
            for (int x = -14; x <= 12; ++x) {
                const VoxelKey base(x, y, z);
                std::array<const VertexSample*, 8> expected{}, got{};
                bool all = true;
                for (int c = 0; c < 8; ++c) all = (expected[c] = field.find(base + VoxelKey(c & 1, (c >> 1) & 1, c >> 2))) && all;
                ASSERT_EQ(accessor.corners(base, got), all) << base.transpose();
                ++checked;
                if (!all) continue;
                ++complete;
                boundary += (x & 7) == 7 || (y & 7) == 7 || (z & 7) == 7;
                for (int c = 0; c < 8; ++c) ASSERT_EQ(got[c], expected[c]) << base.transpose() << " corner " << c;
            }
    EXPECT_GT(complete, 500u);   // a tenth of the cubes have 8 defined corners
    EXPECT_GT(boundary, 100u);   // and some of those cross a block border (the eight-lookup path)
    EXPECT_EQ(checked, 27u * 27u * 27u);
}
