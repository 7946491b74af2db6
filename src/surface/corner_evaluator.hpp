#pragma once
// The fast path's lazy, concurrent evaluation of the vertices the cube search touches
// (compute_seeded_tsdf): where the defined vertices are kept, the windows' shared voxel lists, and
// CornerEvaluator, one per task. Internal to src/surface/.
#include <array>
#include <atomic>
#include <cstdint>
#include <deque>
#include <memory>
#include <optional>
#include <thread>
#include <vector>

#include <tbb/concurrent_vector.h>

#include "lidarsurf/core/block_map.hpp"
#include "lidarsurf/core/packed_voxels.hpp"
#include "lidarsurf/surface/config.hpp"
#include "lidarsurf/surface/neighbourhood_window.hpp"
#include "lidarsurf/surface/tsdf_field.hpp"
#include "lidarsurf/surface/vertex_evaluator.hpp"
#include "cube_search.hpp"

namespace lidarsurf::seeded {

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
        const SurfaceConfig& config;
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

}  // namespace lidarsurf::seeded
