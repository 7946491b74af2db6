#pragma once
// The breadth-first search over marching cubes from the seeds (seeded_surface.hpp), independent of
// how the vertex values are obtained: the reference (seeded_cubes, reference_seeded_tsdf) and the
// fast path (compute_seeded_tsdf) both run it. Internal to src/surface/.
#include <atomic>
#include <chrono>
#include <cstdint>
#include <utility>
#include <vector>

#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>

#include "lidarsurf/core/block_map.hpp"
#include "lidarsurf/core/block_mask.hpp"
#include "lidarsurf/core/cube.hpp"
#include "lidarsurf/core/stopwatch.hpp"
#include "lidarsurf/core/voxel_grid.hpp"
#include "lidarsurf/surface/search_region.hpp"

namespace lidarsurf::seeded {

using Clock = std::chrono::steady_clock;

inline VoxelKey corner(const VoxelKey& base, int c) { return base + corner_offset(c); }

// Calls f(b) for each vertex block b that holds a corner of a cube whose base is in block
// `block` at one of the offsets of `bases`: the block itself, and its neighbour +1 along each set
// of axes on which some base is the block's last lattice point (offset 7).
template <typename F>
void for_each_corner_block(const VoxelKey& block, const BlockMask& bases, F&& f) {
    constexpr std::uint64_t kLastX = 0x8080808080808080ull, kLastY = 0xff00000000000000ull;
    for (int n = 0; n < 8; ++n) {
        const int dx = n & 1, dy = (n >> 1) & 1, dz = n >> 2;
        const std::uint64_t select = (dx ? kLastX : ~std::uint64_t{0}) & (dy ? kLastY : ~std::uint64_t{0});
        std::uint64_t any = 0;
        for (int z = dz ? 7 : 0; z < 8; ++z) any |= bases[static_cast<std::size_t>(z)] & select;
        if (any) f(block + VoxelKey(dx, dy, dz));
    }
}
// The same for one cube: its block, and the next block along each set of axes on which the cube
// is its block's last (same order).
template <typename F>
void for_each_corner_block(const VoxelKey& cube, F&& f) {
    const VoxelKey block = BlockMap<std::int32_t>::block_of(cube);
    const int last_on = BlockMap<std::int32_t>::last_axes(cube);
    for (int n = 0; n < 8; ++n)
        if ((n & ~last_on) == 0) f(block + corner_offset(n));
}

// The TSDF values of a cube's corners (corner c = base + corner_offset(c)): all the
// search reads of a sample.
using CornerValues = std::array<float, 8>;

// What one cube of a wave tells the search, given its corners' values `s`, all defined:
// active(cube) when the surface crosses it, and next(c) for each cube it leads to, through each
// face the surface crosses. A surface through a seed's corner (|value| <= eps, e.g. data lying on
// a lattice plane) may cross only the neighbouring cubes (zero counts as positive): when
// `seeding`, the 8 cubes around such a corner are next as well.
template <typename Active, typename Next>
void classify_cube(const VoxelKey& cube, bool seeding, double eps, const CornerValues& s, Active&& active, Next&& next) {
    unsigned config = 0;
    for (int c = 0; c < 8; ++c) config |= static_cast<unsigned>(s[static_cast<std::size_t>(c)] < 0) << c;
    if (config == 0 || config == 255) {
        if (!seeding) return;
        for (int c = 0; c < 8; ++c) {
            if (!(std::fabs(s[static_cast<std::size_t>(c)]) <= eps)) continue;
            const VoxelKey v = corner(cube, c);
            for (int n = 0; n < 8; ++n) next(v - corner_offset(n));  // the 8 cubes around v
        }
        return;
    }
    active(cube);
    for (unsigned crossed = kCrossedFaces[config]; crossed; crossed &= crossed - 1) {  // in face order
        const int f = std::countr_zero(crossed);  // normal to axis f / 2, on the upper side for odd f
        VoxelKey n = cube;
        n[f >> 1] += (f & 1) ? 1 : -1;
        next(n);
    }
}

// The breadth-first search over cubes, independent of how vertex values are obtained.
class CubeSearch {
public:
    /// `blocks`: about how many blocks of cubes the search will visit (a reservation).
    CubeSearch(const VoxelGrid& grid, std::size_t blocks, const SearchRegion* region = nullptr)
        : eps_(1e-6 * grid.voxel_size()), seen_of_(visited_), region_(region) {
        visited_.reserve_blocks(blocks);
    }
    explicit CubeSearch(const VoxelGrid& grid) : CubeSearch(grid, grid.index().block_count() * 2) {}
    /// How many cubes ahead of the one it examines a wave's chunk asks its view to prefetch.
    static constexpr std::size_t kPrefetchAhead = 2;
    double eps() const { return eps_; }
    BlockMap<std::uint8_t>& visited() { return visited_; }
    std::vector<VoxelKey>& wave() { return wave_; }
    std::vector<VoxelKey>& active() { return active_; }

    /// Adds `cube` to `out` unless it was visited before.
    void visit(const VoxelKey& cube, std::vector<VoxelKey>& out) {
        std::uint8_t& seen = seen_of_[cube];
        if (!seen) {
            seen = 1;
            out.push_back(cube);
        }
    }
    /// The seeds, one by one: the cubes within `dilation` of an occupied voxel.
    void seed(const VoxelGrid& grid, int dilation) {
        for (const VoxelKey& k : grid.keys())
            for (int z = -dilation; z <= dilation; ++z)
                for (int y = -dilation; y <= dilation; ++y)
                    for (int x = -dilation; x <= dilation; ++x) visit(k + VoxelKey(x, y, z), wave_);
    }
    /// The visited flags, through an accessor (one per thread: examine()'s `seen`).
    BlockMap<std::uint8_t>::CornerAccessor visited_reader() const { return BlockMap<std::uint8_t>::CornerAccessor(visited_); }
    /// What one part of a wave (a chunk of cubes, or a seed block) yields: its active cubes, and
    /// the cubes they lead to, claimed (`next`) or left to absorb() (`deferred`).
    struct Part {
        std::vector<VoxelKey> active, next, deferred;
    };
    /// Examines one cube of a wave through `view` (see run()): its active part goes to
    /// `out.active`, the cubes it leads to and nobody visited yet to `out.next`, each claimed
    /// there by setting its visited flag (atomically: the threads examine at the same time, and a
    /// cube the wave leads to twice goes to one `next` only), or to `out.deferred` when its flag's
    /// block does not exist yet (blocks are created by absorb(), serially).
    template <typename View>
    void examine(View& view, const VoxelKey& cube, bool seeding, Part& out, BlockMap<std::uint8_t>::CornerAccessor& seen) const {
        CornerValues s;
        if (!view.corners(cube, s)) return;  // a corner is undefined: not active, leads nowhere
        classify_cube(
            cube, seeding, eps_, s, [&](const VoxelKey& a) { out.active.push_back(a); },
            [&](const VoxelKey& n) {
                if (region_ && !region_->contains(n)) return;  // the search is kept to the region
                const std::uint8_t* flag = seen.find(n);
                if (!flag)
                    out.deferred.push_back(n);
                else if (claim(*flag))
                    out.next.push_back(n);
            });
    }
    /// Appends the parts' results in part order: the active cubes, and the cubes they lead to:
    /// those claimed, then the deferred ones, visited into `out` (creating their blocks).
    void absorb(const std::vector<Part>& parts, std::vector<VoxelKey>& out) {
        std::size_t claimed = 0;
        for (const Part& p : parts) claimed += p.next.size();
        out.reserve(out.size() + claimed);
        for (const Part& p : parts) {
            active_.insert(active_.end(), p.active.begin(), p.active.end());
            out.insert(out.end(), p.next.begin(), p.next.end());
        }
        for (const Part& p : parts)
            for (const VoxelKey& n : p.deferred) visit(n, out);
    }
    /// Wall time run() spent in the waves' parallel parts, and between them (seconds).
    double seconds_parallel() const { return seconds_parallel_; }
    double seconds_serial() const { return seconds_serial_; }
    /// Runs the waves from wave(). A wave is examined in parallel chunks of `chunk` cubes, each
    /// with its own `make_view()`: `view.corners(cube, s)` sets the samples of the cube's corners
    /// and returns whether they are all defined (false: the cube cannot be active, skip it; `s`
    /// may then be incomplete); a view with a `prefetch(cube)` is asked to prefetch for the cube
    /// kPrefetchAhead ahead in the chunk. `before_wave(cubes)` runs serially before each wave. Returns the
    /// active cubes, in wave order. Which cubes a wave leads to does not depend on the timing of
    /// the threads, but their order in the next wave does (the first thread to claim a cube takes
    /// it): nothing the search returns depends on that order (the callers sort the active cubes,
    /// sort_zyx, which makes the mesh's vertex and triangle order deterministic, and
    /// compute_seeded_tsdf orders the field by block key).
    template <typename MakeView, typename BeforeWave>
    std::vector<VoxelKey> run(bool seeding, std::size_t chunk, MakeView&& make_view, BeforeWave&& before_wave) {
        std::vector<VoxelKey> next;
        std::vector<Part> parts;
        while (!wave_.empty()) {
            const auto t0 = Clock::now();
            before_wave(wave_);
            const std::size_t chunks = (wave_.size() + chunk - 1) / chunk;
            parts.assign(chunks, {});
            const auto t1 = Clock::now();
            tbb::parallel_for(std::size_t{0}, chunks, [&](std::size_t c) {
                auto&& view = make_view();
                // About one active cube and one new cube per cube examined: one allocation each
                // rather than growing one element at a time.
                parts[c].active.reserve(chunk);
                parts[c].next.reserve(chunk);
                BlockMap<std::uint8_t>::CornerAccessor seen = visited_reader();
                const std::size_t end = std::min(wave_.size(), (c + 1) * chunk);
                for (std::size_t i = c * chunk; i < end; ++i) {
                    if constexpr (requires { view.prefetch(wave_[i]); })
                        if (i + kPrefetchAhead < end) view.prefetch(wave_[i + kPrefetchAhead]);
                    examine(view, wave_[i], seeding, parts[c], seen);
                }
            });
            seconds_parallel_ += seconds_since(t1);
            const auto t2 = Clock::now();
            next.clear();
            absorb(parts, next);
            std::swap(wave_, next);
            seeding = false;
            seconds_serial_ += std::chrono::duration<double>(t1 - t0).count() + seconds_since(t2);
        }
        return std::move(active_);
    }

private:
    // Sets a visited flag found unset; whether this call did (false: visited, or claimed by
    // another thread meanwhile). The flags are only ever set, and only their value is shared.
    static bool claim(const std::uint8_t& flag) {
        std::atomic_ref<std::uint8_t> f(const_cast<std::uint8_t&>(flag));  // the accessor reads; the flag's block is the map's
        return f.load(std::memory_order_relaxed) == 0 && f.exchange(1, std::memory_order_relaxed) == 0;
    }

    double eps_;
    BlockMap<std::uint8_t> visited_{0};
    BlockMap<std::uint8_t>::WriteAccessor seen_of_;
    const SearchRegion* region_;
    std::vector<VoxelKey> wave_, active_;
    double seconds_parallel_ = 0, seconds_serial_ = 0;
};

}  // namespace lidarsurf::seeded
