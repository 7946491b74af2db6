#include "lidarsurf/surface/config.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <string>

#include "lidarsurf/core/errors.hpp"
#include "lidarsurf/core/format_value.hpp"

namespace lidarsurf {

std::string_view to_string(Mode mode) {
    switch (mode) {
        case Mode::AdaptiveGaussian: return "an+gc";
        case Mode::Adaptive: return "an";
        case Mode::ConstantGaussian: return "cn+gc";
        case Mode::Constant: return "cn";
    }
    return "?";
}

Mode parse_mode(std::string_view name) {
    std::string s(name);
    std::transform(s.begin(), s.end(), s.begin(), [](unsigned char c) { return std::tolower(c); });
    if (s == "an+gc") return Mode::AdaptiveGaussian;
    if (s == "an") return Mode::Adaptive;
    if (s == "cn+gc") return Mode::ConstantGaussian;
    if (s == "cn") return Mode::Constant;
    throw InvalidArgument("unknown mode '" + std::string(name) + "' (expected an+gc, an, cn+gc or cn)");
}

ReconstructionConfig ReconstructionConfig::paper(Mode mode) {
    ReconstructionConfig c;
    c.mode = mode;
    c.make_paper_literal();
    return c;
}

void ReconstructionConfig::make_paper_literal() {
    min_planarity = 0;
    max_thickness = 0;
    slab_from_level = 0;
    bridge_reach = 0;
    truncation_voxels = 0;
    seeded_surface = false;
    snap_to_plane = false;
    min_component_triangles = 0;
    carve = false;
}

int ReconstructionConfig::max_level() const { return adaptive() ? k_max : k; }

int ReconstructionConfig::bridge_extent() const { return std::max(0, std::min(bridge_reach, kMaxReach - k_max)); }

int ReconstructionConfig::max_reach() const {
    const int reach = max_level() + (adaptive() && slab_from_level > 0 ? slab_radial_extension : 0);
    return bridges() ? std::max(reach, k_max + bridge_extent()) : reach;
}

void ReconstructionConfig::validate() const {
    auto fail = [](const std::string& m) { throw InvalidArgument(m); };
    if (!std::isfinite(voxel_size) || voxel_size <= 0) fail("voxel size must be finite and > 0 (got " + format_value(voxel_size) + ")");
    if (voxel_size < 1e-4 || voxel_size > 1e3) fail("voxel size must be within [1e-4, 1e3] m (got " + format_value(voxel_size) + ")");
    if (!std::isfinite(tau) || tau <= 0) fail("tau must be finite and > 0 (got " + format_value(tau) + ")");
    if (n_min < 3) fail("n_min must be >= 3: a plane needs three points (got " + format_value(n_min) + ")");
    const std::string range = "[1, " + format_value(kMaxNeighbourhoodLevel) + "]";
    if (k_max < 1 || k_max > kMaxNeighbourhoodLevel) fail("k_max must be in " + range + " (got " + format_value(k_max) + ")");
    if (k < 1 || k > kMaxNeighbourhoodLevel) fail("k must be in " + range + " (got " + format_value(k) + ")");
    if (!std::isfinite(min_planarity) || min_planarity < 0 || min_planarity >= 1)
        fail("min_planarity must be in [0, 1) (got " + format_value(min_planarity) + ")");
    if (!std::isfinite(max_thickness) || max_thickness < 0 || max_thickness > 1e3)
        fail("max thickness must be within [0, 1e3] voxels (0 disables it; got " + format_value(max_thickness) + ")");
    if (slab_from_level != 0 && (slab_from_level < 2 || slab_from_level > kMaxNeighbourhoodLevel))
        fail("slab fallback level must be 0 (off) or in [2, " + format_value(kMaxNeighbourhoodLevel) + "] (got " + format_value(slab_from_level) + ")");
    if (slab_radial_extension < 0 || slab_radial_extension > kMaxNeighbourhoodLevel)
        fail("slab radial extension must be in [0, " + format_value(kMaxNeighbourhoodLevel) + "] voxels (got " +
             format_value(slab_radial_extension) + ")");
    if (bridge_reach < 0 || bridge_reach > kMaxReach)
        fail("bridge reach must be in [0, " + format_value(kMaxReach) + "] voxels (got " + format_value(bridge_reach) + ")");
    if (!std::isfinite(bridge_range) || bridge_range < 0 || bridge_range > 1e4)
        fail("bridge range must be within [0, 1e4] m (got " + format_value(bridge_range) + ")");
    if (min_component_triangles < 0) fail("min component triangles must be >= 0 (got " + format_value(min_component_triangles) + ")");
    if (!std::isfinite(truncation_voxels) || truncation_voxels < 0)
        fail("truncation must be finite and >= 0 voxels (0 disables it; got " + format_value(truncation_voxels) + ")");
    if (truncation_voxels > 0 && truncation_voxels < 0.8660254037844386)
        fail("truncation below sqrt(3)/2 voxels would cut surfaces crossing a cube (got " + format_value(truncation_voxels) + ")");
    if (seed_dilation < 0 || seed_dilation > kMaxNeighbourhoodLevel)
        fail("seed dilation must be in [0, " + format_value(kMaxNeighbourhoodLevel) + "] (got " + format_value(seed_dilation) + ")");
    if (!std::isfinite(max_memory_mb) || max_memory_mb < 1 || max_memory_mb > 1e9)
        fail("max memory must be within [1, 1e9] MiB (got " + format_value(max_memory_mb) + ")");
    if (!std::isfinite(carve_margin_voxels) || carve_margin_voxels < 0.5 || carve_margin_voxels > 1e3)
        fail("carve margin must be within [0.5, 1e3] voxels (got " + format_value(carve_margin_voxels) + ")");
    if (!std::isfinite(carve_range) || carve_range <= 0 || carve_range > 1e4)
        fail("carve range must be within (0, 1e4] m (got " + format_value(carve_range) + ")");
    if (carve_min_scans < 1 || carve_min_scans > 65535) fail("carve min scans must be in [1, 65535] (got " + format_value(carve_min_scans) + ")");
    if (carve_stale_scans < 0 || carve_stale_scans > 65535)
        fail("carve stale scans must be in [0, 65535] (got " + format_value(carve_stale_scans) + ")");
    if (!std::isfinite(live_growth) || live_growth < 0 || live_growth > 1e3)
        fail("live growth must be within [0, 1e3] (got " + format_value(live_growth) + ")");
    if (!std::isfinite(live_range) || live_range <= 0 || live_range > 1e4)
        fail("live range must be within (0, 1e4] m (got " + format_value(live_range) + ")");
    if (live_reach_blocks < 0 || live_reach_blocks > 4) fail("live reach blocks must be in [0, 4] (got " + format_value(live_reach_blocks) + ")");
    if (live_halo_cubes < 0 || live_halo_cubes > 64) fail("live halo cubes must be in [0, 64] (got " + format_value(live_halo_cubes) + ")");
    if (threads < 0 || threads > 1024) fail("threads must be in [0, 1024] (got " + format_value(threads) + ")");
}

}  // namespace lidarsurf
