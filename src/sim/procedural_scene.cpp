#include "lidarsurf/sim/procedural_scene.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "lidarsurf/core/errors.hpp"
#include "lidarsurf/sim/mesh_builder.hpp"
#include "splitmix.hpp"

namespace lidarsurf::sim {
namespace {

/// splitmix64 stream: the same numbers on every platform (std distributions are not).
class Rng {
public:
    explicit Rng(std::uint64_t seed) : state_(seed * 0x2545F4914F6CDD1Dull + 0x1234567ull) {}
    std::uint64_t next() {
        const std::uint64_t z = detail::splitmix64(state_);
        state_ += 0x9E3779B97F4A7C15ull;
        return z;
    }
    double uniform(double lo, double hi) { return lo + (hi - lo) * detail::unit_interval(next()); }
    bool chance(double p) { return uniform(0, 1) < p; }

private:
    std::uint64_t state_;
};

using V = Eigen::Vector3d;

// ---- Town -------------------------------------------------------------------------------
constexpr double kRoadHalf = 5.0;      // carriageway |y| <= 5
constexpr double kCurb = 0.15;         // curb height: sidewalks and lots are at z = 0.15
constexpr double kSidewalkOuter = 9.0; // building line starts here
constexpr double kLotBack = 40.0;      // the blocks end at |y| = 40
constexpr double kCrossHalf = 5.0;     // cross streets are 10 m wide

/// A car or a van in its own frame (x forward, on the ground at z = 0): the hull, and the rest
/// (cabin or box body, wheels).
struct CarParts {
    Mesh hull, rest;
};
CarParts car_parts(Rng& rng) {
    MeshBuilder hull, b;
    const bool van = rng.chance(0.2);
    const double len = van ? rng.uniform(4.8, 5.4) : rng.uniform(3.9, 4.7);
    const double wid = rng.uniform(1.7, 1.9), wheel_r = van ? 0.36 : 0.32;
    const double hull_top = van ? 1.1 : rng.uniform(0.95, 1.05);
    hull.set_reflectivity(Material::kCarPaint);
    b.set_reflectivity(Material::kCarPaint);
    hull.box_between({-len / 2, -wid / 2, 0.3}, {len / 2, wid / 2, hull_top});    // hull
    if (van) {
        b.box_between({-len / 2, -wid / 2 + 0.05, hull_top}, {len / 2 - 0.9, wid / 2 - 0.05, 2.1});  // box body
    } else {
        const double cab = rng.uniform(1.9, 2.4), back = rng.uniform(-0.5, 0.0);
        b.box_between({back - cab / 2, -wid / 2 + 0.1, hull_top}, {back + cab / 2, wid / 2 - 0.1, hull_top + rng.uniform(0.4, 0.5)});
    }
    const double ax = len / 2 - 0.85;
    b.set_reflectivity(Material::kRubber);
    for (double x : {-ax, ax})
        for (double s : {-1.0, 1.0})
            b.cylinder({x, s * (wid / 2 - 0.22), wheel_r}, {x, s * (wid / 2 + 0.0), wheel_r}, wheel_r, 14);
    return {hull.take(), b.take()};
}
Mesh car_body(Rng& rng) {
    CarParts parts = car_parts(rng);
    MeshBuilder b;
    b.append(parts.hull);
    b.append(parts.rest);
    return b.take();
}

/// A pedestrian in its own frame (x forward, feet at z = 0): legs, torso, arms and head, 1.6-1.9 m.
Mesh pedestrian_body(Rng& rng) {
    MeshBuilder b;
    b.set_reflectivity(Material::kClothing);
    const double h = rng.uniform(1.6, 1.9), hip = 0.5 * h, shoulder = 0.82 * h;
    for (double s : {-1.0, 1.0}) {
        b.box_between({-0.08, s * 0.11 - 0.07, 0.0}, {0.08, s * 0.11 + 0.07, hip});                   // leg
        b.box_between({-0.06, s * 0.25 - 0.05, hip + 0.05}, {0.06, s * 0.25 + 0.05, shoulder});         // arm
    }
    b.box_between({-0.12, -0.2, hip}, {0.12, 0.2, shoulder + 0.03});                                    // torso
    b.box_between({-0.1, -0.08, shoulder + 0.06}, {0.1, 0.08, h});                                      // head
    return b.take();
}

/// A cyclist in its own frame (x forward, wheels on z = 0): a bicycle (two wheels, frame) and a rider.
Mesh cyclist_body(Rng& rng) {
    MeshBuilder b;
    const double r = 0.34, base = 1.05;
    b.set_reflectivity(Material::kRubber);
    for (double x : {-base / 2, base / 2}) b.cylinder({x, -0.02, r}, {x, 0.02, r}, r, 16);               // wheels
    b.set_reflectivity(Material::kMetal);
    b.box_between({-base / 2, -0.03, r}, {base / 2, 0.03, r + 0.35});                                   // frame
    const double h = rng.uniform(1.6, 1.85);
    b.set_reflectivity(Material::kClothing);
    b.box_between({-0.25, -0.18, r + 0.45}, {0.05, 0.18, r + 0.5 + 0.35 * h});                          // rider's torso
    b.box_between({-0.05, -0.08, r + 0.52 + 0.35 * h}, {0.13, 0.08, r + 0.7 + 0.35 * h});             // head
    for (double s : {-1.0, 1.0}) b.box_between({-0.15, s * 0.12 - 0.05, r}, {0.05, s * 0.12 + 0.05, r + 0.5});  // legs
    return b.take();
}

void place(MeshBuilder& b, const Mesh& body, const V& at, double yaw) {
    const Eigen::Matrix3d r = Eigen::AngleAxisd(yaw, V::UnitZ()).toRotationMatrix();
    Mesh m = body;
    for (auto& p : m.vertices) p = at + r * p;
    b.append(m);
}

void building(MeshBuilder& b, Rng& rng, double x0, double x1, double side) {
    const double setback = rng.uniform(0.0, 3.0), depth = rng.uniform(10.0, 16.0);
    const double front = kSidewalkOuter + setback;  // |y| of the facade's outer line
    const int floors = static_cast<int>(rng.uniform(2.0, 8.99));
    const double floor_h = rng.uniform(2.9, 3.4), height = floors * floor_h + rng.uniform(0.3, 1.5);
    const double recess = rng.uniform(0.2, 0.35), z0 = kCurb;
    auto y_at = [&](double d) { return side * (front + d); };  // d = depth behind the facade line
    b.set_reflectivity(Material::kFacade);
    auto slab = [&](double xa, double xb, double da, double db, double za, double zb) {
        b.box_between({xa, std::min(y_at(da), y_at(db)), za}, {xb, std::max(y_at(da), y_at(db)), zb});
    };
    slab(x0, x1, recess, depth, z0, z0 + height);                                        // main block, recessed facade
    for (int f = 0; f <= floors; ++f) {                                                  // floor bands
        const double z = z0 + f * floor_h;
        slab(x0, x1, 0.0, recess, f == 0 ? z0 : z - 0.15, std::min(z + (f == 0 ? 0.9 : 0.25), z0 + height));
    }
    const int bays = std::max(1, static_cast<int>((x1 - x0) / rng.uniform(2.8, 4.0)));
    const double bay = (x1 - x0) / bays;
    for (int i = 0; i <= bays; ++i) {                                                    // pillars
        const double x = x0 + i * bay;
        slab(std::max(x0, x - 0.25), std::min(x1, x + 0.25), 0.0, recess, z0, z0 + height);
    }
    if (floors >= 2 && rng.chance(0.45)) {                                               // balconies
        for (int f = 1; f < floors; ++f)
            for (int i = 0; i < bays; ++i) {
                if (!rng.chance(0.5)) continue;
                const double xa = x0 + i * bay + 0.4, xb = x0 + (i + 1) * bay - 0.4, z = z0 + f * floor_h;
                if (xb - xa < 1.0) continue;
                slab(xa, xb, -1.1, 0.0, z - 0.05, z + 0.12);                               // slab
                b.set_reflectivity(Material::kMetal);
                slab(xa, xb, -1.1, -1.05, z + 0.12, z + 1.05);                             // railing plate
                b.set_reflectivity(Material::kFacade);
            }
    }
    if (rng.chance(0.3)) slab(x0 + 0.5, x1 - 0.5, -1.6, 0.0, z0 + 2.6, z0 + 2.75);     // shop awning
}

void wall_or_fence(MeshBuilder& b, Rng& rng, double x0, double x1, double side) {
    const double y = side * (kSidewalkOuter + 0.3);
    if (rng.chance(0.5)) {
        const double h = rng.uniform(1.2, 2.2);
        b.set_reflectivity(Material::kConcrete);
        b.box_between({x0, std::min(y, y + side * 0.25), kCurb}, {x1, std::max(y, y + side * 0.25), kCurb + h});
        return;
    }
    const double h = rng.uniform(1.2, 1.8);
    b.set_reflectivity(Material::kMetal);
    for (double x = x0; x <= x1 + 1e-9; x += 2.0) b.box_between({x - 0.04, y - 0.04, kCurb}, {x + 0.04, y + 0.04, kCurb + h});
    for (double z : {0.35, h - 0.15}) b.box_between({x0, y - 0.02, kCurb + z}, {x1, y + 0.02, kCurb + z + 0.1});
}

void tree(MeshBuilder& b, Rng& rng, const V& ground, bool conifer) {
    const double trunk_h = rng.uniform(2.2, 3.6), trunk_r = rng.uniform(0.12, 0.25);
    const V top = ground + V(0, 0, trunk_h);
    b.set_reflectivity(Material::kBark);
    b.cylinder(ground, top, trunk_r, 10);
    b.set_reflectivity(Material::kFoliage);
    if (conifer) {
        const double r = rng.uniform(1.2, 2.2), h = rng.uniform(4.0, 7.0);
        b.cone(top - V(0, 0, 0.8), top + V(0, 0, h), r, 12);
    } else {
        const double rx = rng.uniform(1.4, 2.6), rz = rng.uniform(1.2, 2.2);
        b.ellipsoid(top + V(0, 0, 0.6 * rz), {rx, rx * rng.uniform(0.8, 1.2), rz}, 8);
    }
}

void lamppost(MeshBuilder& b, const V& ground, double toward_road) {
    const V top = ground + V(0, 0, 7.0);
    b.set_reflectivity(Material::kMetal);
    b.cylinder(ground, top, 0.09, 10);
    const V tip = top + V(0, toward_road * 1.8, 0);
    b.cylinder(top - V(0, 0, 0.05), tip - V(0, 0, 0.05), 0.05, 8);
    b.box(tip - V(0, 0, 0.2), {0.3, 0.15, 0.08});
}

void traffic_sign(MeshBuilder& b, Rng& rng, const V& ground) {
    const double h = rng.uniform(2.0, 2.6);
    b.set_reflectivity(Material::kMetal);
    b.cylinder(ground, ground + V(0, 0, h), 0.04, 8);
    const V c = ground + V(0, 0, h + 0.35);
    b.set_reflectivity(Material::kSignFace);
    if (rng.chance(0.5)) b.box(c, {0.015, 0.3, 0.3});                                  // square plate facing x
    else b.cylinder(c - V(0.015, 0, 0), c + V(0.015, 0, 0), 0.32, 16);                 // round plate
}

/// The carriageway |y| <= kRoadHalf as flat cells of asphalt and paint: the cells are cut at the
/// markings' edges (and every 5 m), so each is one material.
void carriageway(MeshBuilder& b, double length) {
    const double half = length / 2;
    const std::vector<Marking> marks = town_markings(length);
    std::vector<double> xs, ys = {-kRoadHalf, kRoadHalf};
    for (double x = -half; x < half; x += 5.0) xs.push_back(x);
    xs.push_back(half);
    for (const Marking& m : marks) {
        xs.insert(xs.end(), {m.x0, m.x1});
        ys.insert(ys.end(), {m.y0, m.y1});
    }
    for (auto* cuts : {&xs, &ys}) {
        std::sort(cuts->begin(), cuts->end());
        cuts->erase(std::unique(cuts->begin(), cuts->end(), [](double a, double c) { return c - a < 1e-9; }), cuts->end());
    }
    auto flat = [](double, double) { return 0.0; };
    for (std::size_t j = 0; j + 1 < ys.size(); ++j)
        for (std::size_t i = 0; i + 1 < xs.size(); ++i) {
            const double cx = 0.5 * (xs[i] + xs[i + 1]), cy = 0.5 * (ys[j] + ys[j + 1]);
            bool paint = false;
            for (const Marking& m : marks) paint = paint || (cx > m.x0 && cx < m.x1 && cy > m.y0 && cy < m.y1);
            b.set_reflectivity(paint ? Material::kRoadPaint : Material::kAsphalt);
            b.height_field(xs[i], xs[i + 1], ys[j], ys[j + 1], std::max(xs[i + 1] - xs[i], ys[j + 1] - ys[j]), flat);
        }
}

void make_town(World& w, Rng& rng) {
    MeshBuilder b;
    std::vector<V> free_spots;  // curb spots with no parked car
    const double half = w.config.length / 2;
    const double cross[2] = {-w.config.length / 4, w.config.length / 4};
    auto flat = [](double, double) { return 0.0; };
    carriageway(b, w.config.length);
    b.set_reflectivity(Material::kAsphalt);
    for (double cx : cross) b.height_field(cx - kCrossHalf, cx + kCrossHalf, -kLotBack, -kRoadHalf, 5.0, flat);
    for (double cx : cross) b.height_field(cx - kCrossHalf, cx + kCrossHalf, kRoadHalf, kLotBack, 5.0, flat);
    // Blocks between the cross streets, each side: a kerbed plateau with lots on it.
    std::vector<std::pair<double, double>> blocks = {{-half, cross[0] - kCrossHalf}, {cross[0] + kCrossHalf, cross[1] - kCrossHalf},
                                                     {cross[1] + kCrossHalf, half}};
    for (double side : {-1.0, 1.0}) {
        for (const auto& [bx0, bx1] : blocks) {
            b.set_reflectivity(Material::kConcrete);
            b.box_between({bx0, side > 0 ? kRoadHalf : -kLotBack, 0.0}, {bx1, side > 0 ? kLotBack : -kRoadHalf, kCurb});
            double x = bx0 + rng.uniform(0.0, 2.0);
            while (x < bx1 - 6.0) {
                const double w_lot = std::min(rng.uniform(8.0, 20.0), bx1 - x);
                if (rng.chance(0.18)) wall_or_fence(b, rng, x, x + w_lot, side);
                else building(b, rng, x, x + w_lot, side);
                x += w_lot + (rng.chance(0.3) ? rng.uniform(1.0, 4.0) : 0.0);
            }
            // Street furniture on the sidewalk.
            for (double lx = bx0 + 6.0; lx < bx1 - 3.0; lx += 25.0) lamppost(b, {lx, side * (kRoadHalf + 0.6), kCurb}, -side);
            for (double tx = bx0 + 12.0; tx < bx1 - 6.0; tx += rng.uniform(9.0, 15.0))
                if (rng.chance(0.6)) tree(b, rng, {tx, side * rng.uniform(7.4, 8.2), kCurb}, false);
            for (double sx = bx0 + 3.0; sx < bx1 - 3.0; sx += rng.uniform(30.0, 50.0))
                traffic_sign(b, rng, {sx, side * (kRoadHalf + 0.45), kCurb});
            // Parked cars along the curb, facing the traffic direction of their side; the free spots
            // are where leaving and parking cars stand.
            for (double px = bx0 + 4.0; px < bx1 - 4.0; px += rng.uniform(5.8, 7.5)) {
                if (rng.chance(0.55)) place(b, car_body(rng), {px, side * 3.9, 0.0}, side > 0 ? std::numbers::pi : 0.0);
                else free_spots.push_back({px, side * 3.9, 0.0});
            }
        }
    }
    w.static_mesh = b.take();
    for (int i = 0; i < w.config.moving_cars; ++i) {
        Mover m;
        m.body = car_body(rng);
        m.start = {-half + (i + 0.5) * w.config.length / w.config.moving_cars + rng.uniform(-10, 10), 1.75, 0.0};
        m.speed = -rng.uniform(7.0, 12.0);
        m.x_min = -half + 3;
        m.x_max = half - 3;
        w.movers.push_back(std::move(m));
    }
    // Pedestrians walk the sidewalk of one block (clear of lampposts, signs and trees) either way,
    // wrapping within it; cyclists ride between the centre line and the opposite lane's cars, in the
    // drive's direction, slower than it.
    for (int i = 0; i < w.config.pedestrians; ++i) {
        Mover m;
        m.body = pedestrian_body(rng);
        const double side = rng.chance(0.5) ? 1.0 : -1.0;
        const auto& [bx0, bx1] = blocks[static_cast<std::size_t>(rng.uniform(0.0, 2.999))];
        m.x_min = bx0 + 1;
        m.x_max = bx1 - 1;
        m.start = {rng.uniform(m.x_min, m.x_max), side * rng.uniform(6.2, 6.8), kCurb};
        m.speed = (rng.chance(0.5) ? 1.0 : -1.0) * rng.uniform(1.1, 1.7);
        w.movers.push_back(std::move(m));
    }
    for (int i = 0; i < w.config.cyclists; ++i) {
        Mover m;
        m.body = cyclist_body(rng);
        m.start = {rng.uniform(-half + 3, half - 3), 0.45, 0.0};
        m.speed = rng.uniform(4.0, 6.5);
        m.x_min = -half + 3;
        m.x_max = half - 3;
        w.movers.push_back(std::move(m));
    }
    const double margin = 35.0;
    if (w.config.weave > 0) {
        // A weaving drive, sampled every 10 cm: its heading turns smoothly, not at 1 m corners.
        for (double x = -half + margin; x <= half - margin + 1e-9; x += 0.1)
            w.path.push_back({x, -1.75 + w.config.weave * std::sin(2 * std::numbers::pi * x / SceneConfig::kWeaveWavelength), 0.0});
    } else {
        for (double x = -half + margin; x <= half - margin + 1e-9; x += 1.0) w.path.push_back({x, -1.75, 0.0});
    }
    // Cars that leave their spot or park in one, each at its time within the middle half of the
    // drive, in the traffic direction of their side (drawn after everything else: the other
    // movers and the static scene of a seed do not change with their counts).
    const int wanted = w.config.leaving_cars + w.config.parking_cars;
    if (static_cast<std::size_t>(wanted) > free_spots.size())
        throw InvalidArgument("the town has " + std::to_string(free_spots.size()) + " free curb spots for " + std::to_string(wanted) +
                              " leaving and parking cars: lengthen the street or ask for fewer");
    const double duration = w.time_at(1.0);
    for (int i = 0; i < wanted; ++i) {
        const std::size_t k = std::min(free_spots.size() - 1, static_cast<std::size_t>(rng.uniform(0.0, static_cast<double>(free_spots.size()))));
        const V spot = free_spots[k];
        free_spots.erase(free_spots.begin() + static_cast<std::ptrdiff_t>(k));
        Mover m;
        m.body = car_body(rng);
        m.motion = i < w.config.leaving_cars ? Mover::Motion::Leaving : Mover::Motion::Parking;
        m.start = spot;
        const double side = spot.y() > 0 ? 1.0 : -1.0;
        m.speed = -side * rng.uniform(6.0, 9.0);  // the curb at +y faces -x, as the parked cars do
        m.lane_y = side * 1.75;
        m.when = rng.uniform(0.25, 0.75) * duration;
        m.x_min = -half + 3;
        m.x_max = half - 3;
        w.movers.push_back(std::move(m));
    }
    // Dark cars, parked all along in free spots (drawn last, for the same reason): the hull below
    // the windows returns nothing, the cabin and the wheels do.
    if (static_cast<std::size_t>(w.config.dark_cars) > free_spots.size())
        throw InvalidArgument("the town has " + std::to_string(free_spots.size()) + " free curb spots left for " +
                              std::to_string(w.config.dark_cars) + " dark cars: lengthen the street or ask for fewer");
    MeshBuilder dark, lit;
    lit.append(w.static_mesh);
    for (int i = 0; i < w.config.dark_cars; ++i) {
        const std::size_t k = std::min(free_spots.size() - 1, static_cast<std::size_t>(rng.uniform(0.0, static_cast<double>(free_spots.size()))));
        const V spot = free_spots[k];
        free_spots.erase(free_spots.begin() + static_cast<std::ptrdiff_t>(k));
        const double yaw = spot.y() > 0 ? std::numbers::pi : 0.0;
        const CarParts parts = car_parts(rng);
        place(dark, parts.hull, spot, yaw);
        place(lit, parts.rest, spot, yaw);
    }
    if (w.config.dark_cars > 0) {
        w.static_mesh = lit.take();
        w.dark_mesh = dark.take();
    }
}

// ---- Off-road ---------------------------------------------------------------------------
struct Terrain {
    double phase[3];
    std::vector<V> hills;  // (x, y, amplitude); sigma fixed
    double track(double x) const { return 4.0 * std::sin(x / 30.0 + phase[0]); }
    double height(double x, double y) const {
        double z = 1.5 * std::sin(x / 23.0 + phase[1]) + 1.0 * std::sin(y / 17.0 + x / 40.0 + phase[2]) +
                   0.35 * std::sin((x + 2 * y) / 9.0);
        for (const auto& h : hills) {
            const double d2 = (x - h.x()) * (x - h.x()) + (y - h.y()) * (y - h.y());
            z += h.z() * std::exp(-d2 / (2 * 12.0 * 12.0));
        }
        const double dy = y - track(x);
        return z - 0.15 * std::exp(-dy * dy / 2.0);  // a worn track
    }
};

void make_offroad(World& w, Rng& rng) {
    MeshBuilder b;
    const double half = w.config.length / 2, wide = 60.0;
    Terrain t;
    for (double& p : t.phase) p = rng.uniform(0, 2 * std::numbers::pi);
    for (int i = 0; i < 10; ++i) t.hills.push_back({rng.uniform(-half, half), rng.uniform(-wide, wide), rng.uniform(-2.5, 3.5)});
    b.set_reflectivity(Material::kSoil);
    b.height_field(-half, half, -wide, wide, 0.6, [&](double x, double y) { return t.height(x, y); });
    auto off_track = [&](double x, double y, double clear) { return std::fabs(y - t.track(x)) > clear; };
    auto on_ground = [&](double x, double y) { return V(x, y, t.height(x, y)); };
    const int n_trees = static_cast<int>(w.config.length * 0.6), n_rocks = static_cast<int>(w.config.length * 0.35),
              n_bushes = static_cast<int>(w.config.length * 0.5);
    for (int i = 0; i < n_trees; ++i) {
        const double x = rng.uniform(-half + 2, half - 2), y = rng.uniform(-wide + 2, wide - 2);
        if (!off_track(x, y, 5.0)) continue;
        tree(b, rng, on_ground(x, y) - V(0, 0, 0.2), rng.chance(0.5));
    }
    for (int i = 0; i < n_rocks; ++i) {
        const double x = rng.uniform(-half + 2, half - 2), y = rng.uniform(-wide + 2, wide - 2);
        if (!off_track(x, y, 3.5)) continue;
        const double r = rng.uniform(0.3, 1.2);
        b.set_reflectivity(Material::kRock);
        b.ellipsoid(on_ground(x, y), {r * rng.uniform(0.8, 1.5), r * rng.uniform(0.8, 1.5), r * rng.uniform(0.5, 0.9)}, 6);
    }
    for (int i = 0; i < n_bushes; ++i) {
        const double x = rng.uniform(-half + 2, half - 2), y = rng.uniform(-wide + 2, wide - 2);
        if (!off_track(x, y, 3.0)) continue;
        const double r = rng.uniform(0.4, 0.9);
        b.set_reflectivity(Material::kFoliage);
        b.ellipsoid(on_ground(x, y) + V(0, 0, 0.3 * r), {r, r * rng.uniform(0.8, 1.2), 0.7 * r}, 6);
    }
    // A fence line beside part of the track, following the ground.
    const double fx0 = rng.uniform(-half + 10, -10), fx1 = fx0 + rng.uniform(40, 70), off = rng.chance(0.5) ? 6.0 : -6.0;
    b.set_reflectivity(Material::kMetal);
    for (double x = fx0; x <= fx1; x += 2.5) {
        const V g = on_ground(x, t.track(x) + off);
        b.box_between(g + V(-0.05, -0.05, -0.2), g + V(0.05, 0.05, 1.3));
        if (x + 2.5 <= fx1) {
            const V g2 = on_ground(x + 2.5, t.track(x + 2.5) + off);
            b.cylinder(g + V(0, 0, 1.0), g2 + V(0, 0, 1.0), 0.04, 6);
        }
    }
    w.static_mesh = b.take();
    const double margin = 35.0;
    for (double x = -half + margin; x <= half - margin + 1e-9; x += 0.5) w.path.push_back(on_ground(x, t.track(x)));
}

}  // namespace

std::vector<Marking> town_markings(double length) {
    const double half = length / 2;
    const double cross[2] = {-length / 4, length / 4};
    std::vector<Marking> marks;
    // Between the cross streets (and before the zebras): edge lines, the dashed centre line.
    const std::pair<double, double> spans[3] = {{-half, cross[0] - kCrossHalf}, {cross[0] + kCrossHalf, cross[1] - kCrossHalf},
                                                {cross[1] + kCrossHalf, half}};
    for (const auto& [x0, x1] : spans) {
        for (double side : {-1.0, 1.0}) marks.push_back({x0, x1, side > 0 ? 4.7 : -4.85, side > 0 ? 4.85 : -4.7});
        const double end = x1 - (x1 < half ? 5.0 : 0.0);  // clear of the zebra before the next cross street
        for (double x = x0 + 1.0; x + 3.0 <= end; x += 9.0) marks.push_back({x, x + 3.0, -0.075, 0.075});
    }
    for (double cx : cross) {
        const double x0 = cx - kCrossHalf - 4.0;
        for (int i = 0; i < 8; ++i) marks.push_back({x0, x0 + 3.0, -4.5 + i * 1.2, -3.9 + i * 1.2});
    }
    return marks;
}

SceneKind parse_scene_kind(std::string_view name) {
    if (name == "town") return SceneKind::Town;
    if (name == "offroad" || name == "off-road") return SceneKind::Offroad;
    throw InvalidArgument("unknown scene '" + std::string(name) + "' (available: town, offroad, demo, or a .ply/.obj mesh)");
}

const char* to_string(SceneKind kind) { return kind == SceneKind::Town ? "town" : "offroad"; }

void SceneConfig::validate() const {
    if (!(length >= 80 && length <= 5000)) throw InvalidArgument("scene length must be in [80, 5000] m");
    if (moving_cars < 0 || moving_cars > 100) throw InvalidArgument("moving cars must be in [0, 100]");
    if (pedestrians < 0 || pedestrians > 500) throw InvalidArgument("pedestrians must be in [0, 500]");
    if (cyclists < 0 || cyclists > 100) throw InvalidArgument("cyclists must be in [0, 100]");
    if (leaving_cars < 0 || leaving_cars > 100 || parking_cars < 0 || parking_cars > 100 || dark_cars < 0 || dark_cars > 100)
        throw InvalidArgument("leaving, parking and dark cars must be in [0, 100]");
    if (!(ego_speed > 0 && ego_speed <= 100)) throw InvalidArgument("ego speed must be in (0, 100] m/s");
    if (!(weave >= 0 && weave <= 3)) throw InvalidArgument("weave must be in [0, 3] m");
}

Eigen::Vector3d Mover::position_at(double t) const {
    if (motion == Motion::Wrapping) {
        const double span = x_max - x_min;
        double x = std::fmod(start.x() - x_min + speed * t, span);
        if (x < 0) x += span;
        return {x_min + x, start.y(), start.z()};
    }
    const double moving = motion == Motion::Leaving ? t - when : when - t;  // seconds away from the spot
    if (moving <= 0) return start;
    const double towards_spot = std::max(0.0, 1.0 - moving / kSwerveSeconds);
    const double x = start.x() + (motion == Motion::Leaving ? 1.0 : -1.0) * speed * moving;
    return {x, lane_y + (start.y() - lane_y) * towards_spot, start.z()};
}

bool Mover::present_at(double t) const {
    if (motion == Motion::Wrapping) return true;
    const double x = position_at(t).x();
    return x >= x_min && x <= x_max;
}

bool Mover::parked_at(double t) const {
    if (motion == Motion::Leaving) return t <= when;
    if (motion == Motion::Parking) return t >= when;
    return speed == 0;
}

double World::path_length() const {
    double len = 0;
    for (std::size_t i = 1; i < path.size(); ++i) len += (path[i] - path[i - 1]).norm();
    return len;
}

void World::path_at(double s, Eigen::Vector3d& point, Eigen::Vector3d& tangent) const {
    if (path.size() < 2) throw InvalidArgument("the world has no drive path");
    const double target = std::clamp(s, 0.0, 1.0) * path_length();
    double acc = 0;
    for (std::size_t i = 1; i < path.size(); ++i) {
        const double seg = (path[i] - path[i - 1]).norm();
        if (acc + seg >= target || i + 1 == path.size()) {
            const double f = seg > 0 ? std::clamp((target - acc) / seg, 0.0, 1.0) : 0.0;
            point = path[i - 1] + f * (path[i] - path[i - 1]);
            tangent = (path[i] - path[i - 1]).normalized();
            return;
        }
        acc += seg;
    }
}

Eigen::Isometry3d World::pose_at(double s, double mount_height) const {
    Eigen::Vector3d p, t;
    path_at(s, p, t);
    const Eigen::Vector3d x = t, y = Eigen::Vector3d::UnitZ().cross(x).normalized(), z = x.cross(y);
    Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
    pose.linear().col(0) = x;
    pose.linear().col(1) = y;
    pose.linear().col(2) = z;
    pose.translation() = p + mount_height * Eigen::Vector3d::UnitZ();
    return pose;
}

double World::time_at(double s) const { return std::clamp(s, 0.0, 1.0) * path_length() / config.ego_speed; }

namespace {
// A mover's body where it is at time t, facing the way it drives.
void place_mover(MeshBuilder& b, const Mover& m, double t) { place(b, m.body, m.position_at(t), m.speed < 0 ? std::numbers::pi : 0.0); }
}  // namespace

Mesh World::movers_at(double t) const {
    MeshBuilder b;
    for (const auto& m : movers)
        if (m.present_at(t)) place_mover(b, m, t);
    return b.take();
}

Mesh World::standing_at(double t) const {
    MeshBuilder b;
    b.append(static_mesh);
    b.append(dark_mesh);
    for (const auto& m : movers)
        if (m.parked_at(t)) place_mover(b, m, t);  // parked: at its spot, on the street
    return b.take();
}

Mesh World::scene_at(double t) const {
    MeshBuilder b;
    b.append(static_mesh);
    b.append(dark_mesh);
    b.append(movers_at(t));
    return b.take();
}

World make_world(const SceneConfig& config) {
    config.validate();
    World w;
    w.config = config;
    Rng rng(config.seed);
    if (config.kind == SceneKind::Town) make_town(w, rng);
    else make_offroad(w, rng);
    return w;
}

}  // namespace lidarsurf::sim
