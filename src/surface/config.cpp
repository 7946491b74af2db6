#include "lidarsurf/surface/config.hpp"

#include <algorithm>
#include <cctype>
#include <string>

#include "lidarsurf/core/errors.hpp"

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

SurfaceConfig SurfaceConfig::paper(Mode mode) {
    SurfaceConfig c;
    c.mode = mode;
    c.make_paper_literal();
    return c;
}

int SurfaceConfig::max_level() const { return adaptive() ? k_max : k; }

int SurfaceConfig::bridge_extent() const { return std::max(0, std::min(bridge_reach, kMaxReach - k_max)); }

int SurfaceConfig::max_reach() const {
    const int reach = max_level() + (adaptive() && slab_from_level > 0 ? slab_radial_extension : 0);
    return bridges() ? std::max(reach, k_max + bridge_extent()) : reach;
}

}  // namespace lidarsurf
