#include "lidarsurf/surface/seeded_surface.hpp"

#include <algorithm>
#include <array>
#include <atomic>
#include <bit>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <deque>
#include <memory>
#include <optional>
#include <thread>
#include <tuple>
#include <utility>

#if defined(__SSE2__) && !defined(LIDARSURF_SCALAR)
#include <emmintrin.h>
#endif
#include <tbb/concurrent_unordered_map.h>
#include <tbb/concurrent_vector.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_invoke.h>
#include <tbb/parallel_sort.h>

#include "lidarsurf/core/block_map.hpp"
#include "lidarsurf/core/block_mask.hpp"
#include "lidarsurf/core/cube.hpp"
#include "lidarsurf/core/errors.hpp"
#include "lidarsurf/core/packed_voxels.hpp"
#include "lidarsurf/surface/neighbourhood_window.hpp"
#include "lidarsurf/surface/vertex_evaluator.hpp"

namespace lidarsurf {

namespace {

// The Morton (z-order) code of a block key: the bits of its coordinates (offset to be
// non-negative, 21 bits each) interleaved, so that keys close in space are mostly close in order.
std::uint64_t morton_code(const VoxelKey& key) {
    auto spread = [](std::int32_t c) {
        std::uint64_t v = static_cast<std::uint64_t>(static_cast<std::uint32_t>(c) + (1u << 20)) & 0x1fffffu;
        v = (v | v << 32) & 0x1f00000000ffffull;
        v = (v | v << 16) & 0x1f0000ff0000ffull;
        v = (v | v << 8) & 0x100f00f00f00f00full;
        v = (v | v << 4) & 0x10c30c30c30c30c3ull;
        v = (v | v << 2) & 0x1249249249249249ull;
        return v;
    };
    return spread(key.x()) | spread(key.y()) << 1 | spread(key.z()) << 2;
}

// Wall time from `t` to now, in seconds (SeededTiming).
using Clock = std::chrono::steady_clock;
double seconds_since(Clock::time_point t) { return std::chrono::duration<double>(Clock::now() - t).count(); }

VoxelKey corner(const VoxelKey& base, int c) { return base + corner_offset(c); }

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

}  // namespace

std::vector<VoxelKey> seeded_cubes(const TsdfField& field, const VoxelGrid& grid, int dilation) {
    CubeSearch search(grid);
    search.seed(grid, dilation);
    // Every vertex is already evaluated.
    struct FieldView {
        TsdfField::Accessor values;
        bool corners(const VoxelKey& cube, CornerValues& s) {
            std::array<const VertexSample*, 8> samples;
            if (!values.corners(cube, samples)) return false;
            for (std::size_t c = 0; c < 8; ++c) s[c] = samples[c]->tsdf;
            return true;
        }
    };
    std::vector<VoxelKey> cubes = search.run(true, 1024, [&] { return FieldView{TsdfField::Accessor(field)}; }, [](const std::vector<VoxelKey>&) {});
    sort_zyx(cubes);
    return cubes;
}

SeededTsdf reference_seeded_tsdf(const VoxelGrid& grid, const ReconstructionConfig& config, const Eigen::Vector3d& sensor_world) {
    config.validate();
    const Eigen::Vector3d sensor_local = grid.to_local(sensor_world);
    const Truncation truncation = truncation_of(config, grid);
    tbb::concurrent_unordered_map<VoxelKey, VertexSample, VoxelKeyHash> evaluated;
    CubeSearch search(grid);
    search.seed(grid, config.seed_dilation);
    // Each corner evaluated when a visited cube first needs it (the reference evaluation).
    struct LazyView {
        const VoxelGrid* grid;
        const ReconstructionConfig* config;
        const Eigen::Vector3d* sensor;
        const Truncation* truncation;
        tbb::concurrent_unordered_map<VoxelKey, VertexSample, VoxelKeyHash>* evaluated;
        bool corners(const VoxelKey& cube, CornerValues& s) {
            for (std::size_t c = 0; c < 8; ++c) {
                const VoxelKey v = cube + corner_offset(static_cast<int>(c));
                auto it = evaluated->find(v);
                if (it == evaluated->end()) it = evaluated->insert({v, evaluate_vertex(*grid, v, *config, *sensor)}).first;
                if (!truncation->keeps(it->second)) return false;
                s[c] = it->second.tsdf;
            }
            return true;
        }
    };
    SeededTsdf out;
    out.cubes = search.run(true, 256, [&] { return LazyView{&grid, &config, &sensor_local, &truncation, &evaluated}; },
                           [](const std::vector<VoxelKey>&) {});
    sort_zyx(out.cubes);
    std::vector<VoxelKey> keys;
    keys.reserve(evaluated.size());
    for (const auto& [key, sample] : evaluated) keys.push_back(key);
    sort_zyx(keys);
    std::vector<VertexSample> samples;
    samples.reserve(keys.size());
    for (const VoxelKey& key : keys) samples.push_back(evaluated.find(key)->second);
    out.evaluated = keys.size();
    out.field = assemble_field(grid, keys, samples, truncation);
    return out;
}

namespace {

// A defined vertex evaluated by the fast path, and where they are kept (in evaluation order):
// chunks of kRun entries, each with its entries' TSDF values apart, so that the search, which
// reads only those, touches 4 bytes per vertex rather than a 40-byte entry (the entries of a
// KITTI frame, 5 MB, do not fit the L2 cache). Entry i is entries[i % kRun] of chunk i / kRun.
struct Evaluated {
    VoxelKey key;
    VertexSample sample;
};
struct StoreChunk {
    static constexpr std::size_t kRun = 1024;
    StoreChunk() {}  // tsdf left unset: a value is written with its entry
    std::array<float, kRun> tsdf;
    std::array<Evaluated, kRun> entries;
};
class EvaluatedStore {
public:
    static constexpr std::size_t kRun = StoreChunk::kRun;
    void reserve(std::size_t entries) { chunks_.reserve((entries + kRun - 1) / kRun); }
    /// Claims a run of kRun entries (thread-safe); returns the first one's index.
    std::size_t claim_run() { return static_cast<std::size_t>(chunks_.grow_by(1) - chunks_.begin()) * kRun; }
    void set(std::size_t i, const VoxelKey& key, const VertexSample& sample) {
        StoreChunk& c = chunks_[i / kRun];
        c.tsdf[i % kRun] = sample.tsdf;
        c.entries[i % kRun] = {key, sample};
    }
    float tsdf(std::size_t i) const { return chunks_[i / kRun].tsdf[i % kRun]; }
    const Evaluated& operator[](std::size_t i) const { return chunks_[i / kRun].entries[i % kRun]; }

private:
    tbb::concurrent_vector<StoreChunk, std::allocator<StoreChunk>> chunks_;
};
// The part of the store a thread has claimed and not filled yet: the threads claim the store in
// runs of kRun entries (one shared atomic per run instead of one per vertex: on a Xeon the
// per-vertex push_back and counter increments, contended by both cores, were a
// tenth of a KITTI frame). Entries left unfilled at the end are never referenced by a slot.
struct StoreRun {
    std::size_t next = 0, end = 0;
};

// The windows' voxel list of each vertex block (NeighbourhoodWindow::SharedList), by slot block
// number, shared by the windows of every task and thread: a vertex block's vertices are met by
// several tasks (13,174 windows for 2,820 vertex blocks on KITTI 000000), and listing the voxels
// is most of a window's cost. Grown serially (when slot blocks are created); a deque keeps the
// elements in place.
class BlockLists {
public:
    void reserve(std::size_t count) {
        while (lists_.size() < count) lists_.emplace_back();
    }
    NeighbourhoodWindow::SharedList& operator[](std::size_t block) { return lists_[block]; }

private:
    std::deque<NeighbourhoodWindow::SharedList> lists_;
};

// Lazy, concurrent evaluation of vertices for the fast path (one object per task). A vertex's
// slot in `slots` is kUnevaluated, kBusy (a thread is evaluating it), kUndefined, or the index
// of its entry in `defined` (a concurrent vector: appending does not move the entries). The first
// thread to need a vertex claims and evaluates it; another one needing it meanwhile waits for the
// value. Blocks of `slots` must exist before (their creation is not concurrent).
class CornerEvaluator {
public:
    using Slots = BlockMap<std::int32_t>;
    static constexpr std::int32_t kUnevaluated = -1, kUndefined = -2, kBusy = -3;

    struct Shared {
        Slots& slots;
        const PackedVoxels& packed;
        const ReconstructionConfig& config;
        Eigen::Vector3d sensor_local;
        EigenSolver solver;
        Truncation truncation;
        EvaluatedStore& defined;
        std::atomic<std::size_t>& evaluated;  ///< vertices evaluated, defined or not
        const TsdfField* previous;            ///< values to reuse outside `dirty` (nullptr: none)
        const BlockIndex& dirty;              ///< vertex blocks whose values may have changed
        std::atomic<std::size_t>& reused;     ///< vertices taken from `previous`
        tbb::enumerable_thread_specific<StoreRun>& runs;  ///< each thread's claimed part of `defined`
        BlockLists& lists;                    ///< the windows' shared voxel list, by slot block
        /// Each thread's memory for the lists it builds (outlives `lists`; freed at once at the end).
        tbb::enumerable_thread_specific<NeighbourhoodWindow::ListArena>& arenas;
    };
    explicit CornerEvaluator(const Shared& shared)
        : s_(shared), values_(shared.slots), ahead_(shared.slots), run_(shared.runs.local()), arena_(shared.arenas.local()) {
        if (shared.previous) previous_.emplace(*shared.previous);
    }
    CornerEvaluator(const CornerEvaluator&) = delete;
    CornerEvaluator& operator=(const CornerEvaluator&) = delete;
    /// Adds this evaluator's counts to the shared ones (once, not per vertex).
    ~CornerEvaluator() {
        if (evaluated_) s_.evaluated.fetch_add(evaluated_, std::memory_order_relaxed);
        if (reused_) s_.reused.fetch_add(reused_, std::memory_order_relaxed);
    }

    /// Whether vertex v is defined, evaluating it if nobody has; its TSDF value in `value` if so.
    bool sample(const VoxelKey& v, float& value) {
        // The block exists and is not const: the accessor only caches it.
        return sample(v, *const_cast<std::int32_t*>(values_.find(v)), value);
    }
    /// The same given v's slot.
    bool sample(const VoxelKey& v, std::int32_t& slot, float& value) {
        // Most calls find the vertex already evaluated (two thirds on a lidar frame): answered
        // inline, the evaluation (with its large stack frame) only when needed.
        const std::int32_t state = std::atomic_ref<std::int32_t>(slot).load(std::memory_order_acquire);
        if (state >= 0) [[likely]] {
            value = s_.defined.tsdf(static_cast<std::size_t>(state));
            return true;
        }
        if (state == kUndefined) return false;
        return claim_or_wait(v, slot, state, value);
    }
    /// Asks for the cache lines of `cube`'s corner slots, which corners() will read (a cube of a
    /// later wave is rarely next to the one before it, and its slots then miss the caches).
    void prefetch(const VoxelKey& cube) {
        const std::int32_t* slot = ahead_.find(cube);
        if (!slot) return;
        // The corners lie on rows y, y + 1 of layers z, z + 1 (corner_step): where the cube's
        // corners leave its block, the lines of the next block are not asked for.
        if (Slots::last_axes(cube) != 0) {
            __builtin_prefetch(slot);
            return;
        }
        for (int c : {0, 2, 4, 6}) __builtin_prefetch(slot + Slots::corner_step(c));
    }
    /// Sets the samples of `cube`'s corners and returns whether all are defined. A cube with an
    /// undefined corner cannot be active, so they are evaluated lazily, stopping at the first
    /// undefined one: its all-even corner, its all-odd corner, then the other six in index order
    /// (every cube has exactly one corner of each parity). Which corners a cube evaluates depends
    /// only on their values, so the set of evaluated vertices does not depend on the order.
    bool corners(const VoxelKey& cube, CornerValues& s) {
        // The even corner's index has bit a set where the base is odd on axis a; the odd one is its complement.
        const int even = (cube.x() & 1) | ((cube.y() & 1) << 1) | ((cube.z() & 1) << 2);
        // The lazy order, given how corner c's sample is obtained (`at(c)`, false if undefined).
        auto lazily = [&](auto&& at) {
            if (!at(even) || !at(7 ^ even)) return false;
            for (int c = 0; c < 8; ++c)
                if (c != even && c != (7 ^ even) && !at(c)) return false;
            return true;
        };
        if (Slots::last_axes(cube) == 0) {
            // All 8 corners in the cube's block (7 in 8 per axis): one block lookup.
            std::int32_t* slot = const_cast<std::int32_t*>(values_.find(cube));
            return lazily([&](int c) { return sample(corner(cube, c), slot[Slots::corner_step(c)], s[static_cast<std::size_t>(c)]); });
        }
        return lazily([&](int c) { return sample(corner(cube, c), s[static_cast<std::size_t>(c)]); });
    }

private:
    // sample() for a vertex not evaluated yet (`state` kUnevaluated) or being evaluated by
    // another thread (kBusy): claims and evaluates it, or waits for its value.
    [[gnu::noinline]] bool claim_or_wait(const VoxelKey& v, std::int32_t& slot_ref, std::int32_t state, float& value) {
        std::atomic_ref<std::int32_t> slot(slot_ref);
        if (state == kUnevaluated && slot.compare_exchange_strong(state, kBusy, std::memory_order_acq_rel)) {
            state = kUndefined;
            if (const std::optional<TsdfField::Known> known = reusable(v)) {
                ++reused_;
                if (known->sample) state = store(v, *known->sample);
            } else {
                VertexSample sample = evaluate_vertex(window(Slots::block_of(v)), v, s_.config, s_.sensor_local, s_.solver);
                ++evaluated_;
                if (s_.truncation.keeps(sample))  // as assemble_field
                    state = store(v, sample);
            }
            slot.store(state, std::memory_order_release);
        }
        while (state == kBusy) {
            std::this_thread::yield();
            state = slot.load(std::memory_order_acquire);
        }
        if (state < 0) return false;
        value = s_.defined.tsdf(static_cast<std::size_t>(state));
        return true;
    }
    // Keeps v's sample in the thread's run of the store (claiming a new run when it is full) and
    // returns its index there.
    std::int32_t store(const VoxelKey& v, const VertexSample& sample) {
        if (run_.next == run_.end) {
            run_.next = s_.defined.claim_run();
            run_.end = run_.next + EvaluatedStore::kRun;
        }
        s_.defined.set(run_.next, v, sample);
        return static_cast<std::int32_t>(run_.next++);
    }
    // What `previous` recorded for v when v's block is clean and v was evaluated then.
    std::optional<TsdfField::Known> reusable(const VoxelKey& v) {
        if (!previous_) return std::nullopt;
        const VoxelKey block = Slots::block_of(v);
        if (!clean_block_ || !same_key(*clean_block_, block)) {
            if (s_.dirty.find(block) != BlockIndex::kAbsent) return std::nullopt;
            clean_block_ = block;
        }
        const TsdfField::Known known = previous_->known(v);
        if (!known.evaluated) return std::nullopt;
        return known;
    }
    // The window of a vertex block, from the last few built (a cube's corners are in 1 to 8).
    const NeighbourhoodWindow& window(const VoxelKey& block) {
        for (int w = 0; w < kWindows; ++w)
            if (windows_[w] && same_key(window_block_[w], block)) return *windows_[w];
        const int w = next_window_++ % kWindows;
        if (windows_[w]) windows_[w]->reset(block);
        else windows_[w].emplace(s_.packed, block, s_.config.max_reach(), s_.config.max_level());
        // The block exists: v's slot is in it.
        windows_[w]->share_list(&s_.lists[static_cast<std::size_t>(s_.slots.index_of(block))], &arena_);
        window_block_[w] = block;
        return *windows_[w];
    }
    static constexpr int kWindows = 4;
    const Shared& s_;
    Slots::CornerAccessor values_;
    Slots::CornerAccessor ahead_;  // prefetch()'s own, so that it does not displace values_'s blocks
    StoreRun& run_;
    NeighbourhoodWindow::ListArena& arena_;  // the lists this thread builds
    std::size_t evaluated_ = 0, reused_ = 0;
    std::array<std::optional<NeighbourhoodWindow>, kWindows> windows_;
    std::array<VoxelKey, kWindows> window_block_;
    int next_window_ = 0;
    std::optional<VoxelKey> clean_block_;  // the last vertex block found clean
    std::optional<TsdfField::Accessor> previous_;
};

// The blocks an incremental re-mesh must redo (compute_seeded_tsdf's `previous`): the vertex
// blocks within `reach` blocks of a touched voxel block (their windows can see a new point),
// and, as flags per grid block, the voxel blocks within 2 `reach` (what those windows read, packed
// up front; a clean vertex block that `previous` had not evaluated packs what its window needs
// when it is built).
struct DirtyRegion {
    BlockIndex vertex_blocks;
    std::vector<std::uint8_t> eager_blocks;
};
DirtyRegion dirty_region(const VoxelGrid& grid, int reach) {
    DirtyRegion d;
    const BlockKeys& index = grid.index();
    d.eager_blocks.assign(index.block_count(), 0);
    for (std::uint32_t b : grid.touched_blocks()) {
        const VoxelKey key = index.block_keys()[b];
        for (int z = -2 * reach; z <= 2 * reach; ++z)
            for (int y = -2 * reach; y <= 2 * reach; ++y)
                for (int x = -2 * reach; x <= 2 * reach; ++x) {
                    const VoxelKey near = key + VoxelKey(x, y, z);
                    if (std::max({std::abs(x), std::abs(y), std::abs(z)}) <= reach) d.vertex_blocks.try_emplace(near, 0);
                    const std::int64_t i = index.index_of(near);
                    if (i >= 0) d.eager_blocks[static_cast<std::size_t>(i)] = 1;
                }
    }
    return d;
}

// Bit i set when slots[i] >= 0 (a defined vertex), for 64 slots: the slots' sign bits, 4 per
// SSE2 instruction (x86-64's baseline), else one by one.
std::uint64_t defined_bits(const std::int32_t* slots) {
#if defined(__SSE2__) && !defined(LIDARSURF_SCALAR)
    std::uint64_t negative = 0;
    for (int i = 0; i < 64; i += 4)
        negative |= static_cast<std::uint64_t>(_mm_movemask_ps(_mm_castsi128_ps(_mm_loadu_si128(reinterpret_cast<const __m128i*>(slots + i))))) << i;
    return ~negative;
#else
    std::uint64_t bits = 0;
    for (int i = 0; i < 64; ++i) bits |= static_cast<std::uint64_t>(slots[i] >= 0) << i;
    return bits;
#endif
}

}  // namespace

namespace {
// The grid blocks a region's windows read (creation indices, each once): those within `reach`
// blocks of a vertex block of the region's cubes (a region block or the next one along some axes),
// that is the region's blocks dilated by [-reach, reach + 1], one axis after the other (6 + 2 reach
// keys per block and axis instead of (2 reach + 2)^3 per block).
std::vector<std::uint32_t> blocks_read_by(const VoxelGrid& grid, const SearchRegion& region, int reach) {
    std::vector<VoxelKey> keys = region.blocks();
    for (int axis = 0; axis < 3; ++axis) {
        BlockIndex seen;
        seen.reserve(keys.size() * 2);
        std::vector<VoxelKey> dilated;
        for (const VoxelKey& key : keys)
            for (int d = -reach; d <= reach + 1; ++d) {
                VoxelKey k = key;
                k[axis] += d;
                if (seen.try_emplace(k, 0).second) dilated.push_back(k);
            }
        keys = std::move(dilated);
    }
    std::vector<std::uint32_t> out;
    for (const VoxelKey& key : keys)
        if (const std::int64_t b = grid.index().index_of(key); b >= 0) out.push_back(static_cast<std::uint32_t>(b));
    return out;
}
}  // namespace

namespace {

// Byte b spread over the rows of an 8x8 layer: bit p of b becomes bit 8 p (a column, x = 0).
constexpr std::array<std::uint64_t, 256> kColumnOfByte = [] {
    std::array<std::uint64_t, 256> t{};
    for (std::size_t b = 0; b < 256; ++b)
        for (int p = 0; p < 8; ++p)
            if ((b >> p) & 1u) t[b] |= std::uint64_t{1} << (8 * p);
    return t;
}();

// `in` with every cube grown by `halo` cubes both ways along `axis` (0: x, 1: y, 2: z), in
// `in`'s blocks and the blocks beyond: each line of a block along the axis (8 cubes, a byte)
// becomes the union of its runs grown by the halo. Blocks of `in` first, in its order.
void dilate_along(const std::vector<VoxelKey>& blocks, const std::vector<BlockMask>& masks, int axis, int halo, SearchRegion& out) {
    constexpr int B = BlockMap<std::int32_t>::kSize;
    const int rings = (halo + B - 1) / B;
    for (std::size_t i = 0; i < blocks.size(); ++i) out.add(blocks[i], masks[i]);
    std::vector<BlockMask> grown(static_cast<std::size_t>(2 * rings + 1));
    // Line (i, j) of a mask along the axis: its 8 cubes as a byte; and bits added to it.
    const auto line = [axis](const BlockMask& m, int i, int j) -> unsigned {
        if (axis == 0) return static_cast<unsigned>((m[static_cast<std::size_t>(j)] >> (8 * i)) & 0xffu);  // (y, z)
        unsigned b = 0;
        for (int p = 0; p < B; ++p)
            b |= static_cast<unsigned>(axis == 1 ? (m[static_cast<std::size_t>(j)] >> (i + 8 * p)) & 1u      // (x, z)
                                                 : (m[static_cast<std::size_t>(p)] >> (i + 8 * j)) & 1u) << p;  // (x, y)
        return b;
    };
    const auto set_line = [axis](BlockMask& m, int i, int j, unsigned bits) {
        if (axis == 0) {
            m[static_cast<std::size_t>(j)] |= std::uint64_t{bits} << (8 * i);
        } else if (axis == 1) {
            m[static_cast<std::size_t>(j)] |= kColumnOfByte[bits] << i;
        } else {
            for (; bits; bits &= bits - 1) m[static_cast<std::size_t>(std::countr_zero(bits))] |= std::uint64_t{1} << (i + 8 * j);
        }
    };
    // Fills `grown` with mask m's lines grown by the halo, block offset d - rings in grown[d].
    const auto grow = [&](const BlockMask& m) {
        for (BlockMask& g : grown) g.fill(0);
        for (int j = 0; j < B; ++j)
            for (int i = 0; i < B; ++i) {
                unsigned b = line(m, i, j);
                int lo = 0, hi = -1;  // the interval being merged, cubes relative to the block
                const auto flush = [&] {
                    for (int d = 0; d <= 2 * rings; ++d) {
                        const int from = std::max(lo - B * (d - rings), 0), to = std::min(hi - B * (d - rings), B - 1);
                        if (from <= to) set_line(grown[static_cast<std::size_t>(d)], i, j, (0xffu >> (B - 1 - (to - from))) << from);
                    }
                };
                while (b) {
                    const int a = std::countr_zero(b);
                    const int e = a + std::countr_one(b >> a) - 1;  // the run [a, e]
                    b &= ~((0xffu >> (B - 1 - (e - a))) << a);
                    if (hi >= lo && a - halo <= hi + 1) {
                        hi = e + halo;
                    } else {
                        if (hi >= lo) flush();
                        lo = a - halo, hi = e + halo;
                    }
                }
                if (hi >= lo) flush();
            }
    };
    // A full block grows the same way wherever it is (most of a region's core): grown once.
    const auto is_full = [](const BlockMask& m) { return std::all_of(m.begin(), m.end(), [](std::uint64_t w) { return w == ~std::uint64_t{0}; }); };
    BlockMask all;
    all.fill(~std::uint64_t{0});
    grow(all);
    const std::vector<BlockMask> grown_full = grown;
    for (std::size_t k = 0; k < blocks.size(); ++k) {
        if (is_full(masks[k]))
            grown = grown_full;
        else
            grow(masks[k]);
        for (int d = 0; d <= 2 * rings; ++d) {
            const BlockMask& g = grown[static_cast<std::size_t>(d)];
            if (d == rings || std::all_of(g.begin(), g.end(), [](std::uint64_t w) { return w == 0; })) continue;
            VoxelKey to = blocks[k];
            to[axis] += d - rings;
            out.add(to, g);
        }
    }
}

}  // namespace

SearchRegion SearchRegion::around(std::span<const VoxelKey> core, int halo) {
    // The cubes within Chebyshev distance `halo` of the core: the core grown along x, then y, then
    // z (a box is the Minkowski sum of its three edges), line by line rather than block by block.
    SearchRegion region;
    BlockMask full;
    full.fill(~std::uint64_t{0});
    for (const VoxelKey& block : core) region.add(block, full);
    if (halo <= 0) return region;
    for (int axis = 0; axis < 3; ++axis) {
        SearchRegion next;
        dilate_along(region.blocks_, region.masks_, axis, halo, next);
        region = std::move(next);
    }
    return region;
}

void SearchRegion::add(const VoxelKey& block, const BlockMask& mask) {
    const auto [i, added] = index_.try_emplace(block, static_cast<std::uint32_t>(blocks_.size()));
    if (added) {
        blocks_.push_back(block);
        masks_.push_back(mask);
        return;
    }
    for (std::size_t z = 0; z < mask.size(); ++z) masks_[i][z] |= mask[z];
}

SeededTsdf compute_seeded_tsdf(const VoxelGrid& grid, const ReconstructionConfig& config, const Eigen::Vector3d& sensor_world,
                               EigenSolver solver, const TsdfField* previous, const SearchRegion* region) {
    config.validate();
    if (previous && region) throw InvalidArgument("compute_seeded_tsdf: a region search does not reuse a previous field");
    SeededTiming timing;
    auto t0 = Clock::now();
    // A window of vertex block b reads the voxel blocks within ceil(max_reach / 8) of b.
    const int reach = (config.max_reach() + BlockMap<std::int32_t>::kSize - 1) / BlockMap<std::int32_t>::kSize;
    const DirtyRegion dirty = previous ? dirty_region(grid, reach) : DirtyRegion{};
    // What the search can visit: the grid's blocks, or the region's.
    const std::size_t search_blocks = region ? region->blocks().size() : grid.index().block_count();
    using Slots = CornerEvaluator::Slots;
    Slots slots(CornerEvaluator::kUnevaluated);
    slots.reserve_blocks(search_blocks * 2);
    // The search's vertex and cube blocks lie within `reach` blocks of the voxel blocks (one more
    // for a cube's far corners): through a dense table of that box, when it is small (a frame's
    // is ~100k cells, 0.4 MB; the hash, which the blocks outside it use, probed ~300k times per
    // KITTI frame). A region's lie within one block of its blocks.
    const std::optional<BlockBox> search_box =
        region ? dense_block_box(region->blocks(), 1, PackedVoxels::kDenseCellsPerBlock, std::size_t{1} << 21)
               : dense_block_box(grid.index().block_keys(), reach + 1, PackedVoxels::kDenseCellsPerBlock, std::size_t{1} << 21);
    if (search_box) slots.use_box(*search_box);
    std::size_t region_voxels = 0;
    if (region)
        for (const VoxelKey& b : region->blocks())
            if (const std::int64_t i = grid.index().index_of(b); i >= 0) region_voxels += static_cast<std::size_t>(popcount(grid.occupancy(static_cast<std::size_t>(i))));
    EvaluatedStore defined_vertices;
    // ~3 per occupied voxel on lidar frames (more grows it). One block reserved up front costs
    // page faults only where written, and avoids the growth's smaller blocks (measured: 10k more
    // page faults per 16 frames without it); capped so a huge grid does not reserve gigabytes.
    defined_vertices.reserve(std::min<std::size_t>(4 * (region ? region_voxels : grid.size()), std::size_t{1} << 22));
    std::atomic<std::size_t> evaluated{0}, reused{0};
    tbb::enumerable_thread_specific<StoreRun> runs;
    tbb::enumerable_thread_specific<NeighbourhoodWindow::ListArena> arenas;  // before `lists`: destroyed after it
    BlockLists lists;
    const PackedVoxels packed = region ? PackedVoxels(grid, blocks_read_by(grid, *region, reach))
                                       : PackedVoxels(grid, previous ? &dirty.eager_blocks : nullptr);
    const CornerEvaluator::Shared shared{slots, packed, config, grid.to_local(sensor_world), solver, truncation_of(config, grid),
                                         defined_vertices, evaluated, previous, dirty.vertex_blocks, reused, runs,
                                         lists, arenas};
    CubeSearch search(grid, search_blocks * 2, region);
    if (search_box) search.visited().use_box(*search_box);
    // One evaluator per thread, for every task and wave: its windows (and their voxel lists and
    // level buffers) stay built from one task to the next.
    tbb::enumerable_thread_specific<std::unique_ptr<CornerEvaluator>> evaluators;
    auto evaluator = [&]() -> CornerEvaluator& {
        std::unique_ptr<CornerEvaluator>& e = evaluators.local();
        if (!e) e = std::make_unique<CornerEvaluator>(shared);
        return *e;
    };

    // Wave 0, the seeds (three quarters of the vertices on a lidar frame), in parallel per block:
    // the seed cubes are the occupied voxels dilated by [-d, d] (block masks, no per-cube
    // hashing). Each seed cube's corners are evaluated lazily, then the cube is classified; the
    // cubes it leads to are visited serially, in block order.
    const int d = config.seed_dilation;
    {
        std::vector<MaskedBlock> seeds;
        if (region) {
            for (std::size_t i = 0; i < region->blocks().size(); ++i) {
                BlockMask mask = dilated_occupancy(grid, region->blocks()[i], -d, d);
                bool any = false;
                for (std::size_t z = 0; z < mask.size(); ++z) any |= (mask[z] &= region->mask(i)[z]) != 0;
                if (any) seeds.push_back({region->blocks()[i], mask});
            }
        } else {
            seeds = dilated_occupancy(grid, -d, d);
        }
        // In Morton order of the block keys, so that the blocks a task takes (and the two
        // threads' ranges) are compact in space and share the voxel records their windows read.
        {
            std::vector<std::pair<std::uint64_t, std::size_t>> order(seeds.size());
            for (std::size_t i = 0; i < seeds.size(); ++i) order[i] = {morton_code(seeds[i].block), i};
            std::sort(order.begin(), order.end());
            std::vector<MaskedBlock> sorted(seeds.size());
            for (std::size_t i = 0; i < seeds.size(); ++i) sorted[i] = seeds[order[i].second];
            seeds = std::move(sorted);
        }
        // Every seed is marked visited before the wave, so that the wave's claims drop the seeds
        // the cubes lead to (three fifths of the cubes they lead to on a KITTI frame). The
        // blocks of the marks and of the seeds' corners are created serially, then filled with
        // their empty values and marked in parallel (filling 5 MB of new slot blocks was most of
        // the setup on a KITTI frame). The seeds' blocks are distinct: one task per seed.
        BlockMap<std::uint8_t>& visited = search.visited();
        std::vector<std::uint32_t> seen_block(seeds.size()), new_slot_blocks;
        const std::size_t first_seen = visited.block_count();
        for (std::size_t i = 0; i < seeds.size(); ++i) {
            seen_block[i] = visited.block_index_unfilled(seeds[i].block).first;
            for_each_corner_block(seeds[i].block, seeds[i].mask, [&](const VoxelKey& b) {
                if (const auto [index, added] = slots.block_index_unfilled(b); added) new_slot_blocks.push_back(index);
            });
        }
        tbb::parallel_for(tbb::blocked_range<std::size_t>(0, new_slot_blocks.size(), 32), [&](const auto& r) {
            for (std::size_t j = r.begin(); j != r.end(); ++j) slots.fill_block(new_slot_blocks[j]);
        });
        tbb::parallel_for(tbb::blocked_range<std::size_t>(0, seeds.size(), 64), [&](const auto& r) {
            for (std::size_t i = r.begin(); i != r.end(); ++i) {
                if (seen_block[i] >= first_seen) visited.fill_block(seen_block[i]);  // created above
                BlockMap<std::uint8_t>::Block& seen = visited.block_at(seen_block[i]);
                for_each_bit(seeds[i].mask, [&](int offset) { seen[static_cast<std::size_t>(offset)] = 1; });
            }
        });
        lists.reserve(slots.block_count());
        std::vector<CubeSearch::Part> parts(seeds.size());
        timing.setup = seconds_since(t0);
        t0 = Clock::now();
        tbb::parallel_for(tbb::blocked_range<std::size_t>(0, seeds.size(), 4), [&](const auto& r) {
            CornerEvaluator& corners = evaluator();
            BlockMap<std::uint8_t>::CornerAccessor seen = search.visited_reader();
            // One part per range of seed blocks, kept at the range's first index (the ranges are
            // disjoint and absorb() takes the parts in index order, so the cubes come in seed
            // order as with a part per seed): a part per seed was 2 allocations per seed block,
            // and freeing them, serially after the wave, took ~0.3 ms of a KITTI frame.
            CubeSearch::Part& part = parts[r.begin()];
            std::size_t n = 0;
            for (std::size_t i = r.begin(); i != r.end(); ++i) n += static_cast<std::size_t>(popcount(seeds[i].mask));
            part.active.reserve(n);  // as in the later waves
            part.next.reserve(n);
            for (std::size_t i = r.begin(); i != r.end(); ++i)
                for_each_bit(seeds[i].mask, [&](int offset) { search.examine(corners, Slots::key_at(seeds[i].block, offset), true, part, seen); });
        });
        timing.seed_wave = seconds_since(t0);
        t0 = Clock::now();
        search.absorb(parts, search.wave());
        timing.serial = seconds_since(t0);
    }
    // The later waves (about two fifths of a KITTI frame's vertices, ~20 small waves; the
    // seed wave and these are timed apart, SeededTiming): the corners' blocks are
    // created serially (one lookup per cube unless it is a block's last on some axis, or the
    // block changes), then each cube's corners are evaluated lazily and the cube classified, in
    // parallel chunks of a few cubes.
    Slots::WriteAccessor slot_blocks(slots);  // remembers the blocks met recently, from wave to wave
    // Most cubes' corner blocks exist already (nine in ten on a KITTI frame): they are looked for
    // in parallel (reads only), and the cubes with a missing one are then visited serially, in
    // wave order, to create them. Flags per chunk of the wave, then per cube of the chunks with a
    // miss.
    std::vector<std::uint8_t> missing;
    auto before_wave = [&](const std::vector<VoxelKey>& cubes) {
        missing.assign(cubes.size(), 0);
        tbb::parallel_for(tbb::blocked_range<std::size_t>(0, cubes.size(), 2048), [&](const auto& r) {
            std::optional<VoxelKey> last;  // a block found to exist
            for (std::size_t i = r.begin(); i != r.end(); ++i) {
                const VoxelKey block = Slots::block_of(cubes[i]);
                if (Slots::last_axes(cubes[i]) == 0 && last && same_key(*last, block)) continue;  // all its corners in `block`
                bool all = true;
                for_each_corner_block(cubes[i], [&](const VoxelKey& b) { all = all && slots.find_block(b); });
                missing[i] = !all;
                if (all) last = block;
            }
        });
        for (std::size_t i = 0; i < cubes.size(); ++i)
            if (missing[i]) for_each_corner_block(cubes[i], [&](const VoxelKey& b) { slot_blocks.block_index(b); });
        lists.reserve(slots.block_count());
    };
    SeededTsdf out;
    out.cubes = search.run(false, 64, evaluator, before_wave);
    evaluators.clear();  // adds their counts
    out.evaluated = evaluated.load();
    out.reused = reused.load();
    timing.later_waves = search.seconds_parallel();
    timing.serial += search.seconds_serial();
    t0 = Clock::now();

    // The field: the defined evaluated vertices, ordered by slot (blocks in z, y, x order of their
    // keys, then offset), which does not depend on the thread count or on the threads' timing
    // (the blocks' creation order does: it follows the waves' order, run()). Assembled while
    // another task sorts the active cubes: the sort is serial (~1 ms on a KITTI frame), and run
    // after the waves it left one of the two cores idle.
    std::vector<VoxelKey> field_keys;
    std::vector<VertexSample> field_samples;
    auto assemble = [&] {
        // The first pass counts each block's defined slots and keeps them as a bit mask (one word per
        // 64 slots, branch-free), so that the second visits only those (a twelfth of the slots on a
        // KITTI frame) instead of testing every slot again.
        const std::size_t nblocks = slots.block_count();
        constexpr std::size_t kWords = Slots::kVolume / 64;
        std::vector<std::size_t> block_start(nblocks, 0);
        std::vector<std::array<std::uint64_t, kWords>> defined_mask(nblocks);
        std::vector<std::uint32_t> order(nblocks);  // the blocks by key
        for (std::size_t b = 0; b < nblocks; ++b) order[b] = static_cast<std::uint32_t>(b);
        const std::vector<VoxelKey>& block_keys = slots.block_keys();
        std::sort(order.begin(), order.end(), [&](std::uint32_t a, std::uint32_t b) {
            const VoxelKey &ka = block_keys[a], &kb = block_keys[b];
            return std::tie(ka.z(), ka.y(), ka.x()) < std::tie(kb.z(), kb.y(), kb.x());
        });
        tbb::parallel_for(tbb::blocked_range<std::size_t>(0, nblocks, 16), [&](const auto& r) {
            for (std::size_t b = r.begin(); b != r.end(); ++b) {
                const Slots::Block& block = slots.block_at(b);
                std::size_t count = 0;
                for (std::size_t w = 0; w < kWords; ++w) {
                    const std::uint64_t bits = defined_bits(block.data() + 64 * w);
                    defined_mask[b][w] = bits;
                    count += static_cast<std::size_t>(std::popcount(bits));
                }
                block_start[b] = count;
            }
        });
        std::size_t defined = 0;  // the blocks' counts to their starts, in key order
        for (const std::uint32_t b : order) defined += std::exchange(block_start[b], defined);
        field_keys.resize(defined);
        field_samples.resize(defined);
        tbb::parallel_for(tbb::blocked_range<std::size_t>(0, nblocks, 16), [&](const auto& r) {
            for (std::size_t b = r.begin(); b != r.end(); ++b) {
                Slots::Block& block = slots.block_at(b);
                std::size_t at = block_start[b];
                for (std::size_t w = 0; w < kWords; ++w)
                    for (std::uint64_t bits = defined_mask[b][w]; bits; bits &= bits - 1, ++at) {
                        std::int32_t& slot = block[64 * w + static_cast<std::size_t>(std::countr_zero(bits))];
                        const Evaluated& e = defined_vertices[static_cast<std::size_t>(slot)];
                        slot = static_cast<std::int32_t>(at);
                        field_keys[at] = e.key;
                        field_samples[at] = e.sample;
                    }
            }
        });
    };
    tbb::parallel_invoke([&] { sort_zyx(out.cubes); }, assemble);
    out.field = TsdfField(std::move(slots), std::move(field_keys), std::move(field_samples), grid.voxel_size(), grid.origin());
    timing.field = seconds_since(t0);
    out.timing = timing;
    return out;
}

}  // namespace lidarsurf
