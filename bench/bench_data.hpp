#pragma once
// The input of the micro-benchmarks: one simulated HDL-64 frame of the procedural town (the
// frame `lidarsurf bench` and docs/benchmarks.md time end to end), built once per process.
#include "lidarsurf/core/voxel_grid.hpp"
#include "lidarsurf/sim/procedural_scene.hpp"
#include "lidarsurf/sim/simulator.hpp"

namespace lidarsurf::bench {

inline const PointCloud& town_scan() {
    static const PointCloud scan = [] {
        sim::SimulatorConfig sc;
        sc.gt_beams = 0;
        return sim::Simulator(sim::make_world(sim::SceneConfig{}), sc).frame(50).scan;  // sensor frame
    }();
    return scan;
}

inline VoxelGrid town_grid(double alpha = 0.2) {
    VoxelGrid g(alpha);
    for (const auto& p : town_scan().points) g.insert(p);
    return g;
}

}  // namespace lidarsurf::bench
