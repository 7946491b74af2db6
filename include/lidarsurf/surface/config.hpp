#pragma once
// The surface's configuration (SurfaceConfig): the paper's parameters with the paper's defaults
// (Sec. IV-A: alpha = 0.2 m, tau = 0.2, N_min = 10, k_max = 5) and the guards we add on top of it
// (planarity, thickness, slab fallback, bridges, truncation, seeded surface, snapping), on by
// default and measured in docs/benchmarks.md; SurfaceConfig::paper() turns every one of them off.
// Its settings are one table (LIDARSURF_SURFACE_SETTINGS): the pipeline's SurfaceConfig
// (reconstruction_config.hpp) composes it with the map's carving and live-mesh settings.
#include <limits>
#include <string>
#include <string_view>

#include "lidarsurf/core/setting.hpp"

namespace lidarsurf {

/// Neighbourhood strategy (Sec. IV-B).
enum class Mode {
    AdaptiveGaussian,  ///< AN+GC: smallest k <= k_max satisfying Eq. (1) and Eq. (3). Default.
    Adaptive,          ///< AN: smallest k <= k_max satisfying Eq. (1).
    ConstantGaussian,  ///< CN+GC: k' = k, kept only if Eq. (1) and Eq. (3) hold.
    Constant,          ///< CN: k' = k, kept only if Eq. (1) holds.
};

/// "an+gc", "an", "cn+gc", "cn".
std::string_view to_string(Mode mode);
/// Parses the names above (case-insensitive); throws InvalidArgument on anything else.
Mode parse_mode(std::string_view name);

/// A truncation given in voxels, in metres; 0 voxels (disabled) gives infinity.
inline double truncation_distance_of(double truncation_voxels, double voxel_size) {
    return truncation_voxels > 0 ? truncation_voxels * voxel_size : std::numeric_limits<double>::infinity();
}

/// Upper bound on levels: H^k has (2k)^3 voxels, so k = 32 already means 262,144 per vertex.
inline constexpr int kMaxNeighbourhoodLevel = 32;

/// Upper bound on SurfaceConfig::max_reach(): a NeighbourhoodWindow covers 64 voxels
/// around its vertex block.
inline constexpr int kMaxReach = 64;

/// The surface's settings, one line each: type, name, default, accepted range, flags, the paper as
/// written's value, label, unit, earlier CLI spelling, help (core/setting.hpp). The paper's
/// parameters carry its defaults (Sec. IV-A); the guards are documented in docs/method.md under
/// the names in their help.
// clang-format off
#define LIDARSURF_SURFACE_SETTINGS(X) \
    X(double, voxel_size, 0.2, 1e-4, 1e3, kPaperParameter, kKeep, "voxel size", "m", "--voxel", "Voxel size alpha in metres (Sec. III-A)") \
    X(double, tau, 0.2, 0, kNoLimit, kPaperParameter | kAboveLow, kKeep, "tau", "", "", "Gaussian confidence threshold tau, Eq. (3)") \
    X(int, n_min, 10, 3, kNoLimit, kPaperParameter, kKeep, "n_min", "", "--nmin", "Minimum points N_min in a neighbourhood, Eq. (1): a plane needs three") \
    X(int, k_max, 5, 1, kMaxNeighbourhoodLevel, kPaperParameter, kKeep, "k_max", "", "--kmax", "Largest neighbourhood level k_max (adaptive modes)") \
    X(int, k, 5, 1, kMaxNeighbourhoodLevel, kPaperParameter, kKeep, "k", "", "", "Neighbourhood level k (constant modes cn, cn+gc)") \
    X(double, min_planarity, 0.05, 0, 1, kBelowHigh, 0, "min planarity", "", "", "Reject neighbourhoods with lambda2 < this * lambda1, a line (one scan ring) and not a plane (0 = off; docs/method.md, \"Degenerate covariances\")") \
    X(double, max_thickness, 0.6, 0, 1e3, kClosed, 0, "max thickness", "voxels", "", "Reject neighbourhoods thicker than this (sqrt lambda3, in voxels): a corner or an edge, not one surface (0 = off; docs/method.md, \"Thickness guard\")") \
    X(int, slab_from_level, 3, 2, kMaxNeighbourhoodLevel, kZeroIsOff, 0, "slab fallback level", "", "--slab", "Slab fallback from this level: a vertex whose cube has N_min points but no plane tries horizontal slabs, z up (0 = off; docs/method.md, \"Slab fallback\")") \
    X(int, slab_radial_extension, 8, 0, kMaxNeighbourhoodLevel, kClosed, kKeep, "slab radial extension", "voxels", "--slab-radial", "Slabs reach this many voxels further along the horizontal axis nearer the sensor's direction, across the scan rings (0 = square; docs/method.md, \"Radial slabs\")") \
    X(int, bridge_reach, 30, 0, kMaxReach, kClosed, 0, "bridge reach", "voxels", "", "Single scans, AN+GC: a vertex no level defines is bridged between the scan rings within this many voxels beyond k_max on each side, at a confidence below tau (0 = off; docs/method.md, \"Bridges\")") \
    X(double, bridge_range, 30.0, 0, 1e4, kClosed, kKeep, "bridge range", "m", "", "Bridges are tried within this horizontal distance of the sensor (metres)") \
    X(bool, snap_to_plane, true, 0, 1, kClosed, 0, "snap to plane", "", "--snap", "Move mesh vertices onto the plane of the nearer lattice vertex of their edge (0 = interpolate; docs/method.md, \"Snapping\")") \
    X(int, min_component_triangles, 0, 0, kNoLimit, kClosed, 0, "min component triangles", "", "--min-component", "Drop mesh pieces with fewer triangles (0 = keep all)") \
    X(double, simplify, 0.0, 0, 1e3, kClosed, kKeep, "simplify", "m", "", "Merge triangles wherever the surface stays about within this many metres of the full mesh, borders and tile seams kept (0 = off; docs/method.md, \"Simplification\")") \
    X(double, truncation_voxels, 1.05, 0.8660254037844386, kNoLimit, kZeroIsOff, 0, "truncation", "voxels", "--truncation", "TSDF truncation in voxels; below sqrt(3)/2 it would cut surfaces crossing a cube (0 = none; docs/method.md, \"Truncation\")") \
    X(bool, seeded_surface, true, 0, 1, kClosed, 0, "seeded surface", "", "--seeded", "Keep only the surface connected to the data (0 = every cube with defined corners; docs/method.md, \"Seeded surface\")") \
    X(int, seed_dilation, 0, 0, kMaxNeighbourhoodLevel, kClosed, kKeep, "seed dilation", "", "", "Seed cubes within this many cubes of an occupied voxel")
// clang-format on

/// The surface's configuration: the paper's parameters and lidarsurf's guards on the surface
/// (docs/method.md), with `mode`. SurfaceConfig::paper() turns every guard off.
struct SurfaceConfig {
    LIDARSURF_SETTINGS(SurfaceConfig, LIDARSURF_SURFACE_SETTINGS)
    Mode mode = Mode::AdaptiveGaussian;  ///< Sec. IV-B; the CLI's --mode, a name of parse_mode()

    /// The paper's method as written, in `mode`: every guard off (no planarity or thickness
    /// guard, no slab fallback, no bridges, no truncation, every cube with defined corners
    /// meshed, interpolated vertices).
    static SurfaceConfig paper(Mode mode = Mode::AdaptiveGaussian);
    /// Turns this configuration's guards off as paper() does, keeping its other fields.
    void make_paper_literal() { literal_settings(); }

    /// The truncation in metres (truncation_voxels * voxel_size), infinity when disabled.
    double truncation_distance() const { return truncation_distance_of(truncation_voxels, voxel_size); }

    /// Largest level this configuration evaluates (k_max or k).
    int max_level() const;
    /// How far (in voxels, per axis) from a vertex its neighbourhoods reach: max_level(), plus
    /// the slabs' radial extension when the slab fallback is on, or k_max + bridge_reach when
    /// bridging is on, whichever is larger.
    int max_reach() const;
    bool adaptive() const { return mode == Mode::AdaptiveGaussian || mode == Mode::Adaptive; }
    /// Whether vertices no level defines try the bridge boxes (AN+GC with bridge_reach > 0).
    bool bridges() const { return mode == Mode::AdaptiveGaussian && bridge_reach > 0; }
    /// The bridge boxes' reach beyond k_max: bridge_reach, capped so that k_max + it <= kMaxReach.
    int bridge_extent() const;
    bool gaussian() const { return mode == Mode::AdaptiveGaussian || mode == Mode::ConstantGaussian; }
};

}  // namespace lidarsurf
