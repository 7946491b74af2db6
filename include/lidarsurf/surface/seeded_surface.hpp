#pragma once
// The surface reachable from the data (docs/method.md, "Seeded surface"): the marching-cubes
// cubes connected, through faces the surface crosses, to a cube that is an occupied voxel. Sheets
// and blobs that the extrapolated planes create in empty space, touching no data, are dropped.
//
// Two implementations of the same definition:
//  - reference: evaluate every candidate vertex (compute_tsdf), then search the cubes;
//  - fast: search the cubes from the occupied voxels, evaluating a vertex only when a cube
//    being visited needs it, with the windowed evaluate_vertex (same conditions, same values up
//    to rounding).
#include <array>
#include <cstddef>
#include <span>
#include <utility>
#include <vector>

#include "lidarsurf/core/block_mask.hpp"
#include "lidarsurf/core/voxel_grid.hpp"
#include "lidarsurf/surface/config.hpp"
#include "lidarsurf/surface/tsdf_field.hpp"

#include "lidarsurf/surface/search_region.hpp"

namespace lidarsurf {

/// Cube with minimum corner `base` is *active* when its 8 corners are defined and their signs
/// differ (tsdf < 0 against >= 0, the marching-cubes convention). From an active cube the search
/// crosses each face whose 4 corners have differing signs. Seeds: the cubes within `dilation`
/// (Chebyshev distance, in cubes) of an occupied voxel (voxel i is the cube with minimum corner i),
/// and, for a seed that is not active but has a corner with |tsdf| <= 1e-6 alpha (a surface through
/// that corner), the 8 cubes around that corner.
/// Returns the active cubes reached, sorted (z, y, x).
std::vector<VoxelKey> seeded_cubes(const TsdfField& field, const VoxelGrid& grid, int dilation);

/// Wall time of compute_seeded_tsdf's phases, in seconds (`lidarsurf bench` prints them): where
/// the TSDF stage's time goes, and how much of it runs on one thread.
struct SeededTiming {
    double setup = 0;        ///< packing the voxels, the seed cubes and their slot blocks (mostly serial)
    double seed_wave = 0;    ///< the seeds' wave, in parallel (most of the vertices on a lidar frame)
    double later_waves = 0;  ///< the parallel parts of the later waves
    double serial = 0;       ///< between the waves: taking in each wave's cubes, creating slot blocks
    double field = 0;        ///< ordering the defined vertices into the field (in parallel), while the active cubes are sorted

    static constexpr std::size_t kPhases = 5;
    /// (name, seconds) of each phase, in the order above: the one list the bench's table and JSON
    /// and the Python summary are built from.
    std::array<std::pair<const char*, double>, kPhases> named() const {
        return {{{"setup", setup}, {"seed_wave", seed_wave}, {"later_waves", later_waves}, {"serial", serial}, {"field", field}}};
    }
};

struct SeededTsdf {
    TsdfField field;                ///< the defined vertices that were evaluated (a superset of the cubes' corners)
    std::vector<VoxelKey> cubes;    ///< as seeded_cubes(field, grid) on the full field
    std::size_t evaluated = 0;      ///< vertices evaluated
    std::size_t reused = 0;         ///< vertices taken from `previous` instead (see compute_seeded_tsdf)
    SeededTiming timing;
};

/// The reference of the same search without candidate vertices: every corner of a visited cube
/// is evaluated with the reference evaluate_vertex when the search first needs it (serially
/// memoised, Chan merges, iterative eigen solver). For configurations whose vertices can be
/// defined beyond H^{k_max} of the data (bridges), where compute_tsdf's candidates would miss
/// them; the same cubes and values as the fast path.
SeededTsdf reference_seeded_tsdf(const VoxelGrid& grid, const SurfaceConfig& config, const Eigen::Vector3d& sensor_world);

/// The fast path: the same cubes and the same values at their corners (up to rounding) as
/// compute_tsdf followed by seeded_cubes, evaluating only the vertices the search touches (each
/// visited cube's corners lazily: its two probes, then the rest), in parallel per search wave,
/// through NeighbourhoodWindows. `field` is ordered by vertex block, then offset: the result does
/// not depend on the thread count.
///
/// Incremental re-meshing: `previous`, when given, is the field of an earlier call on the same
/// grid with the same config, sensor and solver, after which the grid's touched_blocks() were
/// cleared. A vertex's value depends only on the voxels within config.max_reach() of it, so a
/// vertex whose block is more than ceil(max_reach / 8) blocks from every touched block keeps the
/// value (or the undefinedness) `previous` recorded for it, and is not evaluated again; the
/// voxel blocks the others can reach are packed up front, any other lazily. The result is the same as without
/// `previous` (tests/test_pipeline.cpp). The search and the compaction still run over the
/// whole surface.
///
/// `region`, when given, keeps the search to its cubes: the seeds are those of its cubes within
/// seed_dilation of an occupied voxel, and a face leading out of it is not crossed. Time and
/// memory then follow the region, not the grid; the values are the same as without it (a vertex's
/// value depends on the voxels, not on the search), and the cubes found are those the search
/// reaches without leaving the region (a subset of the unrestricted search's, equal to it when
/// the region holds every cube the surface of its seeds runs through). Not with `previous`.
SeededTsdf compute_seeded_tsdf(const VoxelGrid& grid, const SurfaceConfig& config, const Eigen::Vector3d& sensor_world,
                               EigenSolver solver = EigenSolver::ClosedForm, const TsdfField* previous = nullptr,
                               const SearchRegion* region = nullptr);

}  // namespace lidarsurf
