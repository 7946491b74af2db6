#pragma once
// One setting of a configuration, described once: each component's Config lists its settings in
// one table (an X-macro: LIDARSURF_SURFACE_SETTINGS, LIDARSURF_CARVING_SETTINGS, ...), one line a
// setting, from which the struct's fields and defaults, validate(), the CLI options, the Python
// properties, their __repr__ and the JSON reports' "config" are all made.
//
// A table line is X(type, name, default, low, high, flags, literal, label, unit, alias, help):
//   name     the field, the Python property; the CLI option is --name in kebab-case
//   low/high the accepted range (kNoLimit: unbounded on that side), with `flags`
//   literal  the value the paper as written takes (make_paper_literal), or kKeep
//   label    words naming it in messages ("voxel size"); unit: "m", "voxels", ... or ""
//   alias    an earlier CLI spelling, kept as a hidden option, or ""
//   help     one line: the CLI's --help and the Python docstring
#include <cmath>
#include <limits>
#include <string>
#include <type_traits>

#include "lidarsurf/core/errors.hpp"
#include "lidarsurf/core/format_value.hpp"

namespace lidarsurf {

/// How a setting's range reads (Setting::flags, or-ed).
enum SettingFlag : unsigned {
    kClosed = 0,       ///< [low, high]
    kAboveLow = 1,     ///< low itself is refused: (low, ...
    kBelowHigh = 2,    ///< high itself is refused: ..., high)
    kZeroIsOff = 4,    ///< 0 is accepted besides the range (the guard is off)
    kPaperParameter = 8,  ///< one of the paper's own parameters (not a guard: --literal keeps it)
};

inline constexpr double kNoLimit = std::numeric_limits<double>::infinity();
/// Setting::literal of a setting the paper as written leaves as it is.
inline constexpr double kKeep = std::numeric_limits<double>::quiet_NaN();

struct Setting {
    const char* name;
    const char* label;
    const char* unit;
    const char* alias;
    const char* help;
    double low = -kNoLimit, high = kNoLimit;
    unsigned flags = kClosed;
    double literal = kKeep;

    /// The CLI option: "--" and the name in kebab-case.
    std::string option() const {
        std::string s = std::string("--") + name;
        for (char& c : s)
            if (c == '_') c = '-';
        return s;
    }
    /// Whether make_paper_literal() sets it (to `literal`).
    bool literal_sets() const { return !std::isnan(literal); }
    /// A lidarsurf guard (the paper as written has none): everything but the paper's parameters.
    bool guard() const { return (flags & kPaperParameter) == 0; }

    /// Whether `value` is accepted: finite, within the range, or 0 where 0 is off.
    bool accepts(double value) const {
        if (!std::isfinite(value)) return false;
        if ((flags & kZeroIsOff) && value == 0) return true;
        const bool above = (flags & kAboveLow) ? value > low : value >= low;
        const bool below = (flags & kBelowHigh) ? value < high : value <= high;
        return above && below;
    }
    /// The accepted values in words: "within [0.0001, 1000] m", "0 (off) or in [2, 32]", ">= 3".
    std::string range_text(bool integral) const {
        std::string s = (flags & kZeroIsOff) ? "0 (off) or " : "";
        const bool lo = std::isfinite(low), hi = std::isfinite(high);
        if (lo && hi)
            s += std::string(integral ? "in " : "within ") + ((flags & kAboveLow) ? "(" : "[") + format_value(low) + ", " + format_value(high) +
                 ((flags & kBelowHigh) ? ")" : "]");
        else if (lo)
            s += ((flags & kAboveLow) ? "> " : ">= ") + format_value(low);
        else if (hi)
            s += ((flags & kBelowHigh) ? "< " : "<= ") + format_value(high);
        if (*unit) s += std::string(" ") + unit;
        return s;
    }
    /// Throws InvalidArgument naming the setting, its accepted values and `value` when it is refused.
    template <typename T>
    void check(T value) const {
        if constexpr (std::is_same_v<T, bool>) {
            return;
        } else {
            if (accepts(static_cast<double>(value))) return;
            const bool integral = std::is_integral_v<T>;
            throw InvalidArgument(std::string(label) + " must be " + (integral ? "" : "finite and ") + range_text(integral) + " (" + name +
                                  " = " + format_value(value) + ")");
        }
    }
};

}  // namespace lidarsurf

/// The fields of a settings table (inside the Config struct).
#define LIDARSURF_SETTING_FIELD(type, name, def, ...) type name = def;
/// One call of f(setting, &Config::name) (inside Config::for_each_setting).
#define LIDARSURF_SETTING_VISIT(type, name, def, low, high, flags, literal, label, unit, alias, help) \
    {                                                                                                \
        static constexpr ::lidarsurf::Setting s{#name, label, unit, alias, help, low, high, flags, literal}; \
        f(s, &Self::name);                                                                           \
    }
/// Inside a Config: the fields of TABLE, for_each_setting(f) calling f(const Setting&, member
/// pointer) for each in order, validate() (each against its range: InvalidArgument naming the
/// first bad field) and literal_settings() (those the paper as written sets, to its value).
#define LIDARSURF_SETTINGS(Config, TABLE)                                             \
    TABLE(LIDARSURF_SETTING_FIELD)                                                    \
    template <typename F>                                                             \
    static void for_each_setting(F&& f) {                                             \
        using Self = Config;                                                          \
        TABLE(LIDARSURF_SETTING_VISIT)                                                \
    }                                                                                 \
    void validate() const {                                                           \
        for_each_setting([this](const ::lidarsurf::Setting& s, auto member) { s.check(this->*member); }); \
    }                                                                                 \
    void literal_settings() {                                                         \
        for_each_setting([this](const ::lidarsurf::Setting& s, auto member) {         \
            using T = std::remove_reference_t<decltype(this->*member)>;                \
            if (s.literal_sets()) this->*member = static_cast<T>(s.literal);          \
        });                                                                           \
    }
