#include <gtest/gtest.h>

#include "lidarsurf/core/errors.hpp"
#include "lidarsurf/sim/mesh_builder.hpp"
#include "lidarsurf/viz/render.hpp"

using namespace lidarsurf;

namespace {

bool is_sky(const Image& img, int x, int y) {
    const auto* p = &img.rgb[(static_cast<std::size_t>(y) * img.width + x) * 3];
    return p[2] > 200 && p[1] > 200 && p[0] > 180;  // the pale sky gradient
}

// A 64 x 48 picture from 10 m above the origin, looking down (the camera's right is +x).
viz::RenderConfig from_above(viz::Colouring colouring) {
    viz::RenderConfig cfg;
    cfg.width = 64;
    cfg.height = 48;
    cfg.colouring = colouring;
    cfg.eye = Eigen::Vector3d(0, -1, 10);
    cfg.target = Eigen::Vector3d(0, 0, 0);
    return cfg;
}

// A camera above a large plane looking down sees it in every pixel; looking up, only sky.
TEST(Render, PlaneFillsTheViewFromAboveAndSkyFromBelow) {
    sim::MeshBuilder b;
    b.height_field(-100, 100, -100, 100, 20, [](double, double) { return 0.0; });
    viz::RenderConfig cfg = from_above(viz::Colouring::Grey);
    const Image down = viz::render(b.mesh(), cfg);
    ASSERT_EQ(down.rgb.size(), 64u * 48 * 3);
    for (int y = 0; y < 48; ++y)
        for (int x = 0; x < 64; ++x) ASSERT_FALSE(is_sky(down, x, y)) << x << "," << y;
    cfg.target = Eigen::Vector3d(0, 0, 20);
    const Image up = viz::render(b.mesh(), cfg);
    for (int y = 0; y < 48; ++y)
        for (int x = 0; x < 64; ++x) ASSERT_TRUE(is_sky(up, x, y)) << x << "," << y;
}

// A plane of two halves seen from above, coloured by intensity: the brighter half (x > 0) is the
// lighter grey, every pixel grey (r = g = b).
TEST(Render, IntensityIsAGreyRampBrighterWhereTheReturnsWere) {
    sim::MeshBuilder b;
    b.set_reflectivity(0.1f);
    b.height_field(-100, 0, -100, 100, 20, [](double, double) { return 0.0; });
    b.set_reflectivity(0.7f);
    b.height_field(0, 100, -100, 100, 20, [](double, double) { return 0.0; });
    const viz::RenderConfig cfg = from_above(viz::Colouring::Intensity);
    const Image img = viz::render(b.mesh(), cfg);
    const auto at = [&](int x, int y) { return &img.rgb[(static_cast<std::size_t>(y) * img.width + x) * 3]; };
    for (int y = 0; y < 48; y += 5)
        for (int x = 0; x < 64; x += 5) {
            const auto* p = at(x, y);
            ASSERT_EQ(p[0], p[1]);
            ASSERT_EQ(p[1], p[2]);
        }
    EXPECT_GT(at(56, 24)[0], at(8, 24)[0] + 100);  // the camera's right is +x
    Mesh plain;
    plain.vertices = b.mesh().vertices, plain.triangles = b.mesh().triangles;
    EXPECT_THROW(viz::render(plain, cfg), InvalidInput);  // no intensity
    EXPECT_EQ(viz::parse_colouring("intensity"), viz::Colouring::Intensity);
}

TEST(Render, RejectsWhatItCannotDraw) {
    viz::RenderConfig cfg;
    EXPECT_THROW(viz::render(Mesh{}, cfg), InvalidInput);
    sim::MeshBuilder b;
    b.box({0, 0, 0}, {1, 1, 1});
    cfg.colouring = viz::Colouring::Level;  // the box has no levels
    EXPECT_THROW(viz::render(b.mesh(), cfg), InvalidInput);
    cfg.colouring = viz::Colouring::Height;
    cfg.width = 0;
    EXPECT_THROW(viz::render(b.mesh(), cfg), InvalidArgument);
    EXPECT_THROW(viz::parse_colouring("rainbow"), InvalidArgument);
}

}  // namespace
