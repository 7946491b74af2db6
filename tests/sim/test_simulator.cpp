// The procedural worlds and the simulator, checked against the scene they scan: every noise-free
// return lies on the scene's triangles, every noisy one within a few sigma.
#include <gtest/gtest.h>

#include <cmath>
#include <optional>
#include <utility>

#include "lidarsurf/core/errors.hpp"
#include "lidarsurf/mesh/mesh_distance.hpp"
#include "lidarsurf/sim/mesh_scene.hpp"
#include "lidarsurf/sim/procedural_scene.hpp"
#include "lidarsurf/sim/simulator.hpp"

using namespace lidarsurf;
using namespace lidarsurf::sim;

namespace {

SceneConfig small(SceneKind kind, std::uint64_t seed = 1) {
    SceneConfig c;
    c.kind = kind;
    c.seed = seed;
    c.length = 120;
    return c;
}

TEST(ProceduralScene, SameSeedSameTrianglesOtherSeedOtherTown) {
    for (SceneKind kind : {SceneKind::Town, SceneKind::Offroad}) {
        const World a = make_world(small(kind, 4)), b = make_world(small(kind, 4)), c = make_world(small(kind, 5));
        ASSERT_EQ(a.static_mesh.vertices.size(), b.static_mesh.vertices.size());
        EXPECT_EQ(a.static_mesh.vertices, b.static_mesh.vertices);
        EXPECT_EQ(a.static_mesh.triangles, b.static_mesh.triangles);
        EXPECT_NE(a.static_mesh.vertices, c.static_mesh.vertices);
        EXPECT_NO_THROW(a.static_mesh.check());
    }
    EXPECT_THROW(parse_scene_kind("city"), InvalidArgument);
    SceneConfig bad;
    bad.length = 10;
    EXPECT_THROW(make_world(bad), InvalidArgument);
}

// The rig rides at its mount height above the ground with nothing within a metre of the sensor.
// The town's carriageway, probed from above: paint at each marking's centre, asphalt just outside
// each of its edges; every surface of the worlds has a reflectivity in [0, 1], the movers too.
TEST(ProceduralScene, TheCarriagewayIsAsphaltWithPaintedMarkings) {
    SceneConfig config = small(SceneKind::Town, 3);
    config.pedestrians = 2;
    const World w = make_world(config);
    const MeshScene scene(w.static_mesh);
    const auto marks = town_markings(config.length);
    ASSERT_GT(marks.size(), 20u);
    auto inside_any = [&](double x, double y) {
        for (const auto& m : marks)
            if (x > m.x0 && x < m.x1 && y > m.y0 && y < m.y1) return true;
        return false;
    };
    // Probed from 0.25 m up, below the cars' hulls: only a wheel can stand in the way.
    std::size_t probes = 0, blocked = 0;
    auto read = [&](double x, double y) -> std::optional<float> {
        ++probes;
        const auto hit = scene.first_return({x, y, 0.25}, {0, 0, -1}, 1.0);
        EXPECT_TRUE(hit) << x << " " << y;
        if (!hit || std::fabs(hit->range - 0.25) > 1e-4) return ++blocked, std::nullopt;
        return hit->reflectivity;
    };
    std::size_t outside = 0;
    for (const auto& m : marks) {
        const double cx = 0.5 * (m.x0 + m.x1), cy = 0.5 * (m.y0 + m.y1);
        if (const auto r = read(cx, cy)) {
            EXPECT_EQ(*r, Material::kRoadPaint) << cx << " " << cy;
        }
        for (const auto& [x, y] : {std::pair{m.x0 - 0.05, cy}, std::pair{m.x1 + 0.05, cy}, std::pair{cx, m.y0 - 0.05}, std::pair{cx, m.y1 + 0.05}}) {
            if (std::fabs(y) > 4.95 || std::fabs(x) > config.length / 2 || inside_any(x, y)) continue;
            if (const auto r = read(x, y)) {
                EXPECT_EQ(*r, Material::kAsphalt) << x << " " << y;
            }
            ++outside;
        }
    }
    EXPECT_LE(blocked, probes / 20);
    EXPECT_GT(outside, 40u);
    for (SceneKind kind : {SceneKind::Town, SceneKind::Offroad}) {
        const World world = make_world(small(kind, 3));
        ASSERT_EQ(world.static_mesh.intensity.size(), world.static_mesh.vertices.size());
        for (float r : world.static_mesh.intensity) ASSERT_TRUE(r >= 0 && r <= 1) << r;
    }
    const Mesh movers = w.movers_at(1.0);
    ASSERT_FALSE(movers.empty());
    EXPECT_EQ(movers.intensity.size(), movers.vertices.size());
}

TEST(ProceduralScene, TheDriveIsClear) {
    for (SceneKind kind : {SceneKind::Town, SceneKind::Offroad}) {
        const World w = make_world(small(kind));
        for (double s : {0.0, 0.25, 0.5, 0.75, 1.0}) {
            const double t = w.time_at(s);
            const MeshScene scene(w.scene_at(t));
            const Eigen::Isometry3d pose = w.pose_at(s, 1.73);
            const auto down = scene.intersect(pose.translation(), -Eigen::Vector3d::UnitZ(), 10);
            ASSERT_TRUE(down) << to_string(kind) << " s=" << s;
            EXPECT_NEAR(*down, 1.73, kind == SceneKind::Town ? 1e-4 : 0.05) << to_string(kind) << " s=" << s;
            for (int a = 0; a < 16; ++a) {
                const Eigen::Vector3d d(std::cos(a * M_PI / 8), std::sin(a * M_PI / 8), 0);
                const auto h = scene.intersect(pose.translation(), pose.linear() * d, 1.0);
                EXPECT_FALSE(h) << to_string(kind) << " s=" << s << " azimuth " << a;
            }
        }
    }
}

TEST(ProceduralScene, MoversDriveAlongTheStreetAndWrap) {
    const World w = make_world(small(SceneKind::Town));
    ASSERT_EQ(w.movers.size(), 3u);
    for (const Mover& m : w.movers) {
        for (double t : {0.0, 1.0, 10.0, 100.0}) {
            const Eigen::Vector3d p = m.position_at(t);
            EXPECT_GE(p.x(), m.x_min);
            EXPECT_LE(p.x(), m.x_max);
            EXPECT_EQ(p.y(), m.start.y());
        }
        EXPECT_NEAR(m.position_at(0.5).x() - m.position_at(0.0).x(), 0.5 * m.speed, 1e-9);  // away from the wrap
    }
}

TEST(ProceduralScene, PedestriansWalkTheSidewalksAndCyclistsRideTheRoadClearOfEverything) {
    SceneConfig c = small(SceneKind::Town);
    c.pedestrians = 12;
    c.cyclists = 4;
    const World w = make_world(c);
    ASSERT_EQ(w.movers.size(), 3u + 12u + 4u);
    // The same street as without them (they are drawn after it).
    SceneConfig plain = small(SceneKind::Town);
    EXPECT_EQ(make_world(plain).static_mesh.vertices, w.static_mesh.vertices);
    const MeshScene scene(w.static_mesh);
    for (std::size_t i = 3; i < w.movers.size(); ++i) {
        const Mover& m = w.movers[i];
        const bool walker = i < 15;
        for (double t : {0.0, 7.0, 31.0}) {
            const Eigen::Vector3d p = m.position_at(t);
            // Standing on the sidewalk (z = 0.15 from |y| = 5 to 9) or riding on the road (z = 0).
            const auto down = scene.intersect(p + Eigen::Vector3d(0, 0, 1.0), -Eigen::Vector3d::UnitZ(), 5.0);
            ASSERT_TRUE(down);
            EXPECT_NEAR(p.z() + 1.0 - *down, walker ? 0.15 : 0.0, 1e-6) << "mover " << i << " t " << t;  // the ground under it
            EXPECT_NEAR(p.z(), walker ? 0.15 : 0.0, 1e-12);  // feet and wheels on that ground
            EXPECT_EQ(std::abs(p.y()) > 5.0, walker);
            // Nothing static within its body's reach (0.6 m around, up to 1.5 m high): no pole, tree,
            // sign or parked car in the way.
            for (double z : {0.3, 1.0, 1.5})
                for (int a = 0; a < 16; ++a) {
                    const Eigen::Vector3d d(std::cos(a * M_PI / 8), std::sin(a * M_PI / 8), 0);
                    EXPECT_FALSE(scene.intersect(p + Eigen::Vector3d(0, 0, z), d, 0.6)) << "mover " << i << " t " << t << " z " << z;
                }
        }
        EXPECT_LE(std::abs(m.speed), walker ? 1.7 : 6.5);
    }
}

TEST(ProceduralScene, LeavingCarsDriveOffAndParkingCarsStayWhatStandsAtTheEnd) {
    SceneConfig c = small(SceneKind::Town);
    c.leaving_cars = 2;
    c.parking_cars = 2;
    const World w = make_world(c);
    ASSERT_EQ(w.movers.size(), 3u + 4u);
    // The same street and moving cars as without them (drawn after everything else).
    const World plain = make_world(small(SceneKind::Town));
    EXPECT_EQ(plain.static_mesh.vertices, w.static_mesh.vertices);
    for (std::size_t i = 0; i < 3; ++i) EXPECT_EQ(plain.movers[i].start, w.movers[i].start);
    const double end = w.time_at(1.0);
    const MeshScene scene(w.static_mesh);
    for (std::size_t i = 3; i < w.movers.size(); ++i) {
        const Mover& m = w.movers[i];
        const bool leaving = i < 5;
        EXPECT_EQ(m.motion, leaving ? Mover::Motion::Leaving : Mover::Motion::Parking);
        EXPECT_GT(m.when, 0.25 * end - 1e-9);
        EXPECT_LT(m.when, 0.75 * end + 1e-9);
        // At its spot (the curb, |y| = 3.9) while parked, in its lane 1.5 s away from it, then
        // moving at its speed; the spot is free of the static parked cars.
        EXPECT_EQ(m.position_at(leaving ? m.when - 5 : m.when + 5), m.start);
        EXPECT_NEAR(std::abs(m.start.y()), 3.9, 1e-12);
        EXPECT_FALSE(scene.intersect(m.start + Eigen::Vector3d(0, 0, 1.0), -Eigen::Vector3d::UnitZ(), 0.9)) << "the spot is taken";
        const double away = leaving ? m.when + 2 : m.when - 2;
        EXPECT_NEAR(m.position_at(away).y(), m.lane_y, 1e-12);
        EXPECT_NEAR(std::abs(m.position_at(away).x() - m.start.x()), 2 * std::abs(m.speed), 1e-9);
        EXPECT_EQ(m.parked_at(leaving ? m.when - 1 : m.when + 1), true);
        EXPECT_EQ(m.parked_at(leaving ? m.when + 1 : m.when - 1), false);
        // A leaving car is gone once past the street; a parking car is not there before it came.
        const double far = leaving ? m.when + 1e3 : m.when - 1e3;
        EXPECT_FALSE(m.present_at(far));
    }
    // What stands at the end: the static mesh and the cars that parked (not those that left).
    const Mesh car0 = w.movers[5].body, car1 = w.movers[6].body;
    EXPECT_EQ(w.standing_at(end).triangles.size(), w.static_mesh.triangles.size() + car0.triangles.size() + car1.triangles.size());
    const Mesh start = w.standing_at(0.0);
    EXPECT_EQ(start.triangles.size(), w.static_mesh.triangles.size() + w.movers[3].body.triangles.size() + w.movers[4].body.triangles.size());
    c.leaving_cars = 100;
    EXPECT_THROW(make_world(c), InvalidArgument);
}

TEST(Simulator, ReturnsLieOnTheSceneSurface) {
    for (SceneKind kind : {SceneKind::Town, SceneKind::Offroad}) {
        SimulatorConfig cfg;
        cfg.frames = 3;
        cfg.sensor = SensorModel::vlp16();
        cfg.gt_beams = 32;
        const Simulator sim(make_world(small(kind)), cfg);
        for (std::size_t i = 0; i < sim.frame_count(); ++i) {
            const SimulatedFrame f = sim.frame(i);
            EXPECT_NEAR((f.pose.translation() - sim.world().pose_at(sim.fraction(i), 1.73).translation()).norm(), 0.0, 1e-12);
            const MeshDistance surface(sim.world().scene_at(f.time));
            ASSERT_GT(f.scan.points.size(), 5000u);
            ASSERT_GT(f.ground_truth.points.size(), f.scan.points.size());
            std::size_t far = 0;
            for (const auto& p : f.scan.points)
                if (surface.distance(f.pose * p) > 5 * cfg.sensor.range_noise) ++far;
            EXPECT_LT(far, f.scan.points.size() / 1000 + 1) << to_string(kind) << " frame " << i;  // 5-sigma tail
            double worst = 0;
            for (const auto& p : f.ground_truth.points) worst = std::max(worst, surface.distance(f.pose * p));
            EXPECT_LT(worst, 2e-3) << to_string(kind) << " frame " << i;  // float ray casting at <= 100 m
        }
    }
}

TEST(Simulator, ASweepThatTakesTimeCastsEachRayFromWhereTheRigIsThen) {
    // A weaving drive at 10 m/s: each point, placed by the pose at its own time, lies on the
    // scene; placed by the frame's pose, as without de-skew, the last ones are 0.9 m or more away.
    SceneConfig sc = small(SceneKind::Town);
    sc.weave = 1.5;
    sc.ego_speed = 10;
    SimulatorConfig cfg;
    cfg.frames = 3;  // frame 1: mid-drive
    cfg.sensor = SensorModel::vlp16();
    cfg.sensor.range_noise = 0;
    cfg.gt_beams = 0;
    cfg.sweep_seconds = 0.1;
    const Simulator sim(make_world(sc), cfg);
    const SimulatedFrame f = sim.frame(1);
    const MeshDistance surface(sim.world().scene_at(f.time));
    ASSERT_EQ(f.times.size(), f.scan.points.size());
    ASSERT_GT(f.scan.points.size(), 5000u);
    double worst = 0, late = 0;
    std::size_t late_count = 0;
    for (std::size_t i = 0; i < f.scan.points.size(); ++i) {
        ASSERT_GE(f.times[i], 0.0f);
        ASSERT_LT(f.times[i], 0.1f);
        const Eigen::Vector3d p = sim.pose_at_time(f.time + f.times[i]) * f.scan.points[i];
        worst = std::max(worst, surface.distance(p));
        if (f.times[i] > 0.09f) {
            late += (p - f.pose * f.scan.points[i]).norm();
            ++late_count;
        }
    }
    EXPECT_LT(worst, 2e-3);  // float ray casting at <= 100 m
    ASSERT_GT(late_count, 100u);
    EXPECT_GT(late / static_cast<double>(late_count), 0.85);  // 0.9 m driven (and turned) since the sweep began
    // The first step fires at the frame's instant: the sweep starts where the frame's pose is.
    EXPECT_LT((sim.pose_at_time(f.time).translation() - f.pose.translation()).norm(), 1e-9);
}

TEST(Simulator, FramesAreEquiSampledAlongTheDrive) {
    SimulatorConfig cfg;
    cfg.frames = 5;
    cfg.gt_beams = 0;
    cfg.sensor = SensorModel::vlp16();
    const Simulator sim(make_world(small(SceneKind::Town)), cfg);
    EXPECT_DOUBLE_EQ(sim.fraction(0), 0.0);
    EXPECT_DOUBLE_EQ(sim.fraction(4), 1.0);
    EXPECT_DOUBLE_EQ(sim.fraction(2), 0.5);
    EXPECT_TRUE(sim.frame(1).ground_truth.points.empty());
    EXPECT_THROW(sim.frame(5), InvalidArgument);
    SimulatorConfig bad = cfg;
    bad.frames = 0;
    EXPECT_THROW(Simulator(make_world(small(SceneKind::Town)), bad), InvalidArgument);
}

}  // namespace
