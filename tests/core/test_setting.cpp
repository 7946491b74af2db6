// The settings tables (core/setting.hpp) against what the documentation promises: the ranges of
// docs/method.md and docs/reliability.md written out here by hand, the paper as written's list of
// guards (Sec. IV: no guard of ours, no carving), one field per entry, CLI names in kebab-case.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <set>
#include <string>
#include <vector>

#include "lidarsurf/core/errors.hpp"
#include "lidarsurf/core/setting.hpp"
#include "lidarsurf/reconstruction_config.hpp"

using namespace lidarsurf;

namespace {

// Sets the setting named `name` of `c` to `value` (converted to its type); false when there is none.
bool set_setting(ReconstructionConfig& c, const std::string& name, double value) {
    bool found = false;
    ReconstructionConfig::for_each_setting([&](const Setting& s, auto member) {
        if (name != s.name) return;
        using T = std::remove_reference_t<decltype(c.*member)>;
        c.*member = static_cast<T>(value);
        found = true;
    });
    return found;
}

bool valid_with(const std::string& name, double value) {
    ReconstructionConfig c;
    EXPECT_TRUE(set_setting(c, name, value)) << name;
    try {
        c.validate();
        return true;
    } catch (const InvalidArgument& e) {
        EXPECT_NE(std::string(e.what()).find(name), std::string::npos) << "the message names the field: " << e.what();
        return false;
    }
}

}  // namespace

TEST(Settings, EveryEntryIsItsOwnFieldWithAUniqueName) {
    std::set<std::string> names;
    std::size_t count = 0;
    ReconstructionConfig c;
    // Writing a distinct value through each entry and reading all back: no two entries share a field.
    double next = 1;
    ReconstructionConfig::for_each_setting([&](const Setting& s, auto member) {
        ++count;
        EXPECT_TRUE(names.insert(s.name).second) << "two settings named " << s.name;
        EXPECT_GT(std::string(s.help).size(), 10u) << s.name << " has no help";
        using T = std::remove_reference_t<decltype(c.*member)>;
        if constexpr (!std::is_same_v<T, bool>) {
            c.*member = static_cast<T>(next++);
        }
    });
    next = 1;
    ReconstructionConfig::for_each_setting([&](const Setting& s, auto member) {
        using T = std::remove_reference_t<decltype(c.*member)>;
        if constexpr (!std::is_same_v<T, bool>) {
            EXPECT_EQ(static_cast<double>(c.*member), next++) << s.name;
        }
    });
    // The fields of the four tables: 17 of the surface, 9 of carving, 4 of the live mesh, 2 of the run.
    EXPECT_EQ(count, 32u);
}

TEST(Settings, OptionsAreTheFieldNamesInKebabCase) {
    ReconstructionConfig::for_each_setting([](const Setting& s, auto) {
        std::string expected = "--";
        for (const char* p = s.name; *p; ++p) expected += *p == '_' ? '-' : *p;
        EXPECT_EQ(s.option(), expected);
        if (*s.alias) {
            EXPECT_EQ(std::string(s.alias).rfind("--", 0), 0u) << s.alias;
        }
    });
    const Setting memory{"max_memory_mb", "", "", "", ""};
    EXPECT_EQ(memory.option(), "--max-memory-mb");
}

TEST(Settings, TheDefaultsAreValidAndTheDocumentedRangesHold) {
    EXPECT_NO_THROW(ReconstructionConfig{}.validate());
    EXPECT_NO_THROW(ReconstructionConfig::paper().validate());
    const double nan = std::numeric_limits<double>::quiet_NaN(), inf = std::numeric_limits<double>::infinity();
    struct Row {
        const char* name;
        std::vector<double> accepted, refused;
    };
    // docs/method.md and docs/reliability.md: voxel size 0.1 mm to 1 km; tau > 0; N_min >= 3 (a
    // plane needs three points); levels 1..32; the truncation 0 (none) or at least half the cube
    // diagonal; the slab fallback 0 (off) or from level 2; carving's margin at least half a voxel.
    const std::vector<Row> rows = {
        {"voxel_size", {1e-4, 0.2, 1e3}, {0, -1, 9e-5, 1001, nan, inf}},
        {"tau", {1e-9, 0.2, 1e6}, {0, -0.1, nan, inf}},
        {"n_min", {3, 10, 1e6}, {2, 0, -5}},
        {"k_max", {1, 5, 32}, {0, 33}},
        {"k", {1, 32}, {0, 33}},
        {"min_planarity", {0, 0.05, 0.999}, {1, -0.01, nan}},
        {"truncation_voxels", {0, 0.8660254037844386, 1.05, 100}, {0.5, 0.86, -1, nan, inf}},
        {"slab_from_level", {0, 2, 3, 32}, {1, -1, 33}},
        {"bridge_reach", {0, 30, kMaxReach}, {-1, kMaxReach + 1}},
        {"carve_margin_voxels", {0.5, 2, 1e3}, {0.4, 0, nan}},
        {"carve_min_scans", {1, 65535}, {0, 65536}},
        {"carve_range", {1e-3, 40, 1e4}, {0, -1, 1e4 + 1, nan}},
        {"live_range", {1, 1e4}, {0, 1e4 + 1}},
        {"live_reach_blocks", {0, 4}, {-1, 5}},
        {"threads", {0, 1024}, {-1, 1025}},
        {"max_memory_mb", {1, 4096, 1e9}, {0, 0.5, 2e9, nan}},
    };
    for (const Row& r : rows) {
        for (double v : r.accepted) EXPECT_TRUE(valid_with(r.name, v)) << r.name << " = " << v;
        for (double v : r.refused) EXPECT_FALSE(valid_with(r.name, v)) << r.name << " = " << v;
    }
}

TEST(Settings, ThePaperAsWrittenHasNoGuardAndKeepsItsParameters) {
    ReconstructionConfig base;
    base.voxel_size = 0.1, base.tau = 0.3, base.n_min = 7, base.k_max = 4, base.k = 2;
    base.mode = Mode::ConstantGaussian;
    base.threads = 3, base.max_memory_mb = 100, base.live_range = 20;
    ReconstructionConfig p = base;
    p.make_paper_literal();
    // The surface as SurfaceConfig::paper() has it (its guards: tests/surface/test_vertex_evaluator.cpp,
    // Config.PaperTurnsEveryGuardOff), and no carving.
    SurfaceConfig surface = base;
    surface.make_paper_literal();
    SurfaceConfig::for_each_setting([&](const Setting& s, auto member) { EXPECT_EQ(p.*member, surface.*member) << s.name; });
    EXPECT_FALSE(p.carve);
    EXPECT_FALSE(p.seeded_surface);
    // The paper's parameters, the mode and the run's settings stay.
    EXPECT_EQ(p.voxel_size, 0.1);
    EXPECT_EQ(p.tau, 0.3);
    EXPECT_EQ(p.n_min, 7);
    EXPECT_EQ(p.k_max, 4);
    EXPECT_EQ(p.k, 2);
    EXPECT_EQ(p.mode, Mode::ConstantGaussian);
    EXPECT_EQ(p.threads, 3);
    EXPECT_EQ(p.max_memory_mb, 100);
    EXPECT_EQ(p.live_range, 20);
    EXPECT_FALSE(ReconstructionConfig::paper(Mode::Adaptive).carve);
    EXPECT_EQ(ReconstructionConfig::paper(Mode::Adaptive).mode, Mode::Adaptive);
    // Of the surface's and carving's settings, the paper's five parameters are not guards (the
    // CLI's --literal keeps them and refuses the others).
    std::set<std::string> parameters;
    const auto collect = [&](const Setting& s, auto) {
        if (!s.guard()) parameters.insert(s.name);
    };
    SurfaceConfig::for_each_setting(collect);
    CarvingConfig::for_each_setting(collect);
    EXPECT_EQ(parameters, (std::set<std::string>{"voxel_size", "tau", "n_min", "k_max", "k"}));
}

TEST(Settings, MessagesSayWhatIsAccepted) {
    const Setting s{"slab_from_level", "slab fallback level", "", "", "help", 2, 32, kZeroIsOff};
    try {
        s.check(1);
        FAIL() << "1 is refused";
    } catch (const InvalidArgument& e) {
        EXPECT_STREQ(e.what(), "slab fallback level must be 0 (off) or in [2, 32] (slab_from_level = 1)");
    }
    const Setting v{"voxel_size", "voxel size", "m", "", "help", 1e-4, 1e3};
    try {
        v.check(0.0);
        FAIL() << "0 is refused";
    } catch (const InvalidArgument& e) {
        EXPECT_STREQ(e.what(), "voxel size must be finite and within [0.0001, 1000] m (voxel_size = 0)");
    }
}
