#pragma once
// The configuration of the pipeline (Reconstructor): the surface's settings (surface/config.hpp),
// free-space carving's and the live mesh's (map/), and the run's own (threads, memory budget),
// each component's settings one table (core/setting.hpp). The CLI options, the Python Config's
// properties and __repr__, the JSON reports' "config" and validate() are all made from
// ReconstructionConfig::for_each_setting: a new setting is one line in its component's table.
#include "lidarsurf/core/setting.hpp"
#include "lidarsurf/map/free_space.hpp"
#include "lidarsurf/map/live_mesh.hpp"
#include "lidarsurf/surface/config.hpp"

namespace lidarsurf {

/// The run's settings, one line each (core/setting.hpp).
// clang-format off
#define LIDARSURF_RUN_SETTINGS(X) \
    X(int, threads, 0, 0, 1024, kClosed, kKeep, "threads", "", "", "Worker threads (0 = all cores)") \
    X(double, max_memory_mb, 4096, 1, 1e9, kClosed, kKeep, "max memory", "MiB", "--max-memory", "Memory budget in MiB: an input or a reconstruction estimated to need more is refused (exit 5, MemoryError, ResourceLimit), with the estimate (docs/reliability.md)")
// clang-format on

struct RunConfig {
    LIDARSURF_SETTINGS(RunConfig, LIDARSURF_RUN_SETTINGS)
};

/// Every setting of the pipeline, under the names of its components' fields (config.voxel_size,
/// config.carve_range, config.live_growth, config.threads). Defaults: the paper's parameters with
/// lidarsurf's guards on; paper() turns every guard off.
struct ReconstructionConfig : SurfaceConfig, CarvingConfig, LiveMeshConfig, RunConfig {
    /// The paper's method as written, in `mode`: every guard of the surface off, and no carving.
    static ReconstructionConfig paper(Mode mode = Mode::AdaptiveGaussian) {
        ReconstructionConfig c;
        c.mode = mode;
        c.make_paper_literal();
        return c;
    }
    /// Turns this configuration's guards off as paper() does, keeping its other fields.
    void make_paper_literal() {
        SurfaceConfig::literal_settings();
        CarvingConfig::literal_settings();
    }
    /// f(const Setting&, member pointer) for every setting: the surface's, carving's, the live
    /// mesh's, the run's, each in its table's order.
    template <typename F>
    static void for_each_setting(F&& f) {
        SurfaceConfig::for_each_setting(f);
        CarvingConfig::for_each_setting(f);
        LiveMeshConfig::for_each_setting(f);
        RunConfig::for_each_setting(f);
    }
    /// Throws InvalidArgument naming the first bad field.
    void validate() const {
        SurfaceConfig::validate();
        CarvingConfig::validate();
        LiveMeshConfig::validate();
        RunConfig::validate();
    }

    const SurfaceConfig& surface() const { return *this; }
    const CarvingConfig& carving() const { return *this; }
    const LiveMeshConfig& live() const { return *this; }
};

}  // namespace lidarsurf
