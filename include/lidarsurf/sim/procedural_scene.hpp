#pragma once
// Procedural worlds for the simulator, seeded and deterministic (the same seed gives the same
// triangles on every platform: the generator draws from its own counter-based stream).
//  - town: a straight street with curbs and sidewalks, two cross streets, buildings with facade
//    detail (recessed windows between floor bands and pillars, balconies with railings, varied
//    heights), walls and fences, parked cars and vans (body, cabin, wheels), cars driving in the
//    opposite lane, lampposts, traffic signs (thin plates on poles) and trees (trunk + canopy);
//  - offroad: hilly terrain with a winding track, rocks, bushes, broadleaf and conifer trees and
//    a fence line.
// Every surface has a material's reflectivity (Material below), kept as the meshes' per-vertex
// `intensity`, so a simulated scan carries the intensity each surface should read; the town's
// carriageway is asphalt with painted markings: edge lines, a dashed centre line and a zebra
// crossing before each cross street.
// A World also carries the drive: a ground path the sensor rig follows.
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include <Eigen/Geometry>

#include "lidarsurf/mesh/mesh.hpp"

namespace lidarsurf::sim {

enum class SceneKind { Town, Offroad };

/// The reflectivity in [0, 1] of the worlds' materials (a calibrated lidar's scale).
struct Material {
    static constexpr float kAsphalt = 0.08f;
    static constexpr float kRoadPaint = 0.6f;    ///< lane markings
    static constexpr float kConcrete = 0.25f;    ///< curbs, sidewalks, walls
    static constexpr float kFacade = 0.3f;
    static constexpr float kMetal = 0.4f;        ///< poles, lampposts, fences, railings
    static constexpr float kSignFace = 0.9f;     ///< retroreflective sheeting
    static constexpr float kCarPaint = 0.15f;
    static constexpr float kRubber = 0.04f;      ///< tyres
    static constexpr float kFoliage = 0.45f;
    static constexpr float kBark = 0.2f;
    static constexpr float kClothing = 0.3f;     ///< pedestrians, cyclists
    static constexpr float kSoil = 0.2f;         ///< off-road terrain
    static constexpr float kRock = 0.3f;
};

/// The town's carriageway markings: paint rectangles (x0, x1, y0, y1) on z = 0.
struct Marking {
    double x0, x1, y0, y1;
};

SceneKind parse_scene_kind(std::string_view name);  ///< "town" or "offroad"; InvalidArgument otherwise
const char* to_string(SceneKind kind);

struct SceneConfig {
    SceneKind kind = SceneKind::Town;
    std::uint64_t seed = 1;
    double length = 240.0;    ///< metres of street / track along x
    int moving_cars = 3;      ///< town: cars in the opposite lane
    int pedestrians = 0;      ///< town: people walking the sidewalks, both ways (1.1-1.7 m/s)
    int cyclists = 0;         ///< town: bicycles beside the opposite lane, in the drive's direction (4-6.5 m/s)
    int leaving_cars = 0;     ///< town: cars parked at the curb that pull out and drive off, each at its time within the drive
    int parking_cars = 0;     ///< town: cars that drive in and park at the curb, each at its time within the drive
    int dark_cars = 0;        ///< town: cars parked all along whose hull is too dark to return a ray (World::dark_mesh)
    double ego_speed = 8.0;   ///< m/s of the sensor rig along the path (sets the frame times)
    /// town: the drive weaves this many metres to either side of its lane, a sine of kWeaveWavelength
    /// (the rig turns: at 10 m/s and 1.5 m, up to 21 degrees a second); 0 drives straight.
    double weave = 0.0;
    static constexpr double kWeaveWavelength = 40.0;

    void validate() const;
};

/// A rigid object that moves along the street at constant speed:
///  - Wrapping: in a straight line from `start` (its position at t = 0), wrapping within
///    [x_min, x_max];
///  - Leaving: parked at `start` until `when`, then it pulls out into the lane at `lane_y` (over
///    kSwerveSeconds) and drives off, gone once past [x_min, x_max];
///  - Parking: it drives in along the lane, pulls over in the last kSwerveSeconds and stands at
///    `start` from `when` on; not on the street before it enters [x_min, x_max].
struct Mover {
    enum class Motion { Wrapping, Leaving, Parking };
    static constexpr double kSwerveSeconds = 1.5;
    Mesh body;                  ///< in its own frame, x forward
    Eigen::Vector3d start;      ///< see Motion
    double speed = 0;           ///< m/s along x (negative: driving towards -x)
    double x_min = 0, x_max = 0;  ///< the street span
    Motion motion = Motion::Wrapping;
    double when = 0;            ///< Leaving: when it pulls out; Parking: when it stands at `start` (s)
    double lane_y = 0;          ///< Leaving, Parking: the lane it drives in
    Eigen::Vector3d position_at(double t) const;
    /// Whether it is on the street at time t (a car that left, or one not come yet, is not).
    bool present_at(double t) const;
    /// Whether it stands still at time t (parked).
    bool parked_at(double t) const;
};

struct World {
    SceneConfig config;
    Mesh static_mesh;                ///< everything that does not move and returns the sensor's rays
    Mesh dark_mesh;                  ///< what does not move and returns no ray: the dark cars' hulls (below the sensor's threshold)
    std::vector<Mover> movers;
    std::vector<Eigen::Vector3d> path;  ///< ground points of the drive, in order (polyline)

    double path_length() const;
    /// The ground point at arc length fraction s in [0, 1] and the unit tangent there.
    void path_at(double s, Eigen::Vector3d& point, Eigen::Vector3d& tangent) const;
    /// Sensor-to-world pose at fraction s: `mount_height` above the path, x along the tangent
    /// (pitch follows the slope), z up, no roll.
    Eigen::Isometry3d pose_at(double s, double mount_height) const;
    /// Time (s) at which the rig is at fraction s, at config.ego_speed.
    double time_at(double s) const;
    /// The moving objects at time t, as one mesh (empty when there are none).
    Mesh movers_at(double t) const;
    /// The whole scene at time t: static and dark meshes + movers.
    Mesh scene_at(double t) const;
    /// What stands still at time t: the static and dark meshes and the movers parked then. At the
    /// end of the drive (time_at(1)), the scene a map of the drive should hold.
    Mesh standing_at(double t) const;
};

World make_world(const SceneConfig& config);

/// The markings of a town street of this length (|x| <= length / 2): the edge lines
/// (|y| in [4.7, 4.85], broken at the cross streets), the dashed centre line (|y| <= 0.075, 3 m
/// dashes every 9 m) and, 1-4 m before each cross street, a zebra crossing of eight 0.6 m bars
/// 0.6 m apart across the carriageway (|y| <= 4.5).
std::vector<Marking> town_markings(double length);

}  // namespace lidarsurf::sim
