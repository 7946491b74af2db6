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

// A camera above a large plane looking down sees it in every pixel; looking up, only sky.
TEST(Render, PlaneFillsTheViewFromAboveAndSkyFromBelow) {
    sim::MeshBuilder b;
    b.height_field(-100, 100, -100, 100, 20, [](double, double) { return 0.0; });
    viz::RenderConfig cfg;
    cfg.width = 64;
    cfg.height = 48;
    cfg.colouring = viz::Colouring::Grey;
    cfg.eye = Eigen::Vector3d(0, -1, 10);
    cfg.target = Eigen::Vector3d(0, 0, 0);
    const Image down = viz::render(b.mesh(), cfg);
    ASSERT_EQ(down.rgb.size(), 64u * 48 * 3);
    for (int y = 0; y < 48; ++y)
        for (int x = 0; x < 64; ++x) ASSERT_FALSE(is_sky(down, x, y)) << x << "," << y;
    cfg.target = Eigen::Vector3d(0, 0, 20);
    const Image up = viz::render(b.mesh(), cfg);
    for (int y = 0; y < 48; ++y)
        for (int x = 0; x < 64; ++x) ASSERT_TRUE(is_sky(up, x, y)) << x << "," << y;
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
