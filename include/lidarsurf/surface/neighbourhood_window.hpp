#pragma once
// Fast neighbourhood statistics for the vertices of one 8^3 vertex block. The packed
// voxel blocks (PackedVoxels) that any H^k(v), k <= max_level, of those vertices can reach
// (3x3x3 blocks for max_level <= 8, 5x5x5 up to 16) are looked up at most once each, when a box
// first reaches them, so summing a box needs no hashing, skips empty
// space 64 voxels at a time (VoxelGrid::occupancy) and reads compact records stored in block
// order; and each occupied voxel is added as
// raw moments in the frame of the vertex,
//   n += |V|,  s1 += |V| d,  s2 += V_M2 + |V| d d^T   with d = V_mu - v,
// which is Chan's merge (voxel_stats.cpp) expanded: no division per voxel, and small coordinates
// (|d| <= k alpha) so no loss of precision. The result equals merge_neighbourhood() up to
// rounding (tests/surface/test_neighbourhood_window.cpp).
//
// The cubes H^k(v) (grow, box) with k <= cube_level = K go through a voxel list instead:
// the occupied voxels of the region every such cube of the block's vertices lies
// in, [8b - K, 8b + 6 + K]^3, listed once as region coordinates (bytes) and records, in the
// order add_shell meets them (blocks z, y, x, then layers, then rows). Per vertex, one SIMD pass
// gives each listed voxel its level, the smallest k with i in H^k(v) = [v - k, v + k - 1]:
//   L(i) = max over the axes a of  max(v_a, i_a + 1) - min(v_a, i_a).
// The shell H^k \ H^{k-1} is then {L = k} and H^k is {L <= k}, found 16 voxels per compare and
// added in list order: the very additions, in the very order, of add_shell (so the same bits),
// without its per-block and per-layer bookkeeping, which was most of a shell's cost on lidar
// frames. The list depends only on the voxels, the vertex block and K, so the windows of one
// vertex block, on any thread, may share it (SharedList). Slabs keep a walk over the blocks
// (add_slab): a list of their wider region (radial extensions) cost more to build than the
// bookkeeping it saved.
#include <atomic>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <vector>

#include <Eigen/Core>

#include "lidarsurf/core/packed_voxels.hpp"
#include "lidarsurf/core/simd.hpp"
#include "lidarsurf/core/voxel_grid.hpp"
#include "lidarsurf/surface/neighbourhood.hpp"

namespace lidarsurf {

/// Raw moments of a set of points about a reference point p.
struct Moments {
    double n = 0;
    Eigen::Vector3d s1 = Eigen::Vector3d::Zero();  ///< sum (x - p)
    Eigen::Matrix3d s2 = Eigen::Matrix3d::Zero();  ///< sum (x - p)(x - p)^T

    /// Count, mean and scatter about the mean (VoxelStats), given the reference point p.
    VoxelStats to_stats(const Eigen::Vector3d& p) const;
};

class NeighbourhoodWindow {
public:
    /// Memory for voxel lists that are freed together, when the arena goes: bump allocation from
    /// large chunks. The surface search builds thousands of shared lists per frame; allocating
    /// each (and freeing each, serially, at the end of the frame: ~0.5 ms of a KITTI frame) cost
    /// more than the arena's few chunks. Not thread-safe: one
    /// arena per thread.
    class ListArena {
    public:
        /// `bytes` bytes aligned for any type (alignof(std::max_align_t)), until the arena is destroyed.
        void* allocate(std::size_t bytes);

    private:
        std::vector<std::unique_ptr<std::byte[]>> chunks_;
        std::byte* next_ = nullptr;
        std::size_t left_ = 0;
    };
    /// The occupied voxels of the cube region (see above), padded to a multiple of 16 with
    /// coordinates beyond every level. Its arrays share one allocation: a frame builds and frees
    /// thousands of lists (with five allocations each, freeing them alone took 1.2 ms of a KITTI
    /// frame, on one thread).
    struct VoxelList {
        std::size_t size = 0;  ///< entries in each array
        const PackedVoxels::Voxel** records = nullptr;
        std::uint8_t *x = nullptr, *y = nullptr, *z = nullptr;
        std::uint8_t* weight = nullptr;  ///< the voxel's point count, saturated at 255 (padding: 0)
        /// A list of `size` padding entries: records nullptr, coordinates `pad`, weight 0; its
        /// arrays in `arena` if given (then they live as long as the arena), else owned.
        static VoxelList padding(std::size_t size, std::uint8_t pad, ListArena* arena = nullptr);
        /// Whether the arrays are in an arena (not owned).
        bool in_arena() const { return in_arena_; }

    private:
        std::unique_ptr<std::byte[]> storage_;  // the records' addresses, then x, y, z and weight
        bool in_arena_ = false;
    };
    /// The voxel list of one vertex block, for the windows of that block to share, whatever their
    /// thread: the first window that needs it builds and publishes it (if two race, one copy is
    /// kept). Owns the published list unless it was built in an arena (share_list), which must
    /// then outlive this.
    class SharedList {
    public:
        SharedList() = default;
        SharedList(const SharedList&) = delete;
        SharedList& operator=(const SharedList&) = delete;
        ~SharedList() {
            const VoxelList* list = list_.load(std::memory_order_relaxed);
            if (list && !list->in_arena()) delete list;
        }

    private:
        friend class NeighbourhoodWindow;
        std::atomic<const VoxelList*> list_{nullptr};
    };

    /// Window for the vertices of vertex block `vertex_block` (vertices 8 b .. 8 b + 7 per axis)
    /// and levels up to `max_level` (<= 64). The sums cache their block lookups and list in the
    /// window, so one window must not be used by two threads at once (`voxels` itself is
    /// thread-safe). Cubes up to `cube_level` (in [1, max_level]; default max_level) use the voxel
    /// list, larger ones add_shell.
    NeighbourhoodWindow(const PackedVoxels& voxels, const VoxelKey& vertex_block, int max_level, int cube_level = -1);
    /// Makes this the window of another vertex block (same voxels and levels; keeps the storage;
    /// stops sharing its list). The list scans use the simd_level() in force at construction or
    /// at the last reset().
    void reset(const VoxelKey& vertex_block);
    /// Makes the window take its voxel list from `list` (that of its vertex block, with the same
    /// voxels and cube_level), or publish there the one it builds, until the next reset(). With
    /// `arena` (this thread's, outliving `list`), a list the window builds lives in the arena.
    void share_list(SharedList* list, ListArena* arena = nullptr);

    /// Adds the voxels of H^k(v) \ H^{k-1}(v) (all of H^1 for k = 1) to `acc`, whose reference
    /// point is v's position. v must be in the window's vertex block and k <= max_level.
    void grow(const VoxelKey& v, int k, Moments& acc) const;
    /// Moments of the whole H^k(v) about v's position.
    Moments box(const VoxelKey& v, int k) const;
    /// The first level the adaptive loop needs to sum for v: 1 if H^1(v) holds n_min points, else
    /// 2 if H^2(v) does (or cube_level is 1), else 3. The levels below it fail Eq. (1) on the count
    /// alone, so the loop may start there with box() instead of growing shell by shell through
    /// them. Counted with the levels (n_min <= 255; larger n_min gives 1).
    int first_counted_level(const VoxelKey& v, int n_min) const;
    /// Moments of the whole slab S^k(v) extended by e (neighbourhood.hpp's slab_box) about v's
    /// position; k + max(e) must be <= max_level. Every method throws InvalidArgument for a box
    /// beyond the window's blocks.
    Moments slab(const VoxelKey& v, int k, SlabExtension e = {}) const;
    /// Adds S^k(v) \ S^{k-1}(v) (both extended by e) to `acc` (which holds S^{k-1}(v); k >= 2).
    void grow_slab(const VoxelKey& v, int k, Moments& acc, SlabExtension e = {}) const;
    /// Moments of any box within the window's reach (the bridge boxes) about v's position, by
    /// the slab walk.
    Moments sum_box(const VoxelBox& b, const VoxelKey& v) const;

    double voxel_size() const { return alpha_; }
    /// The SimdLevel of the window's kernels (simd_level() at construction or the last reset()).
    SimdLevel simd() const { return simd_; }
    const VoxelGrid& grid() const { return voxels_->grid(); }

private:
    // Adds the voxels of the box lo <= key <= hi (inclusive) to acc, without its interior box
    // [lo + inset, hi - inset] when inset > 0 (a shell). The general path, for the cubes the list
    // does not cover.
    void add_shell(const VoxelKey& lo, const VoxelKey& hi, int inset, const Eigen::Vector3d& p, Moments& acc) const;
    // The same walk for a slab (two layers, hi.z = lo.z + 1; `ring`: without the x-y interior
    // [lo + 1, hi - 1] on both layers, the ring S^k \ S^{k-1}): blocks z, y, x, then layers, then
    // rows, as add_shell, with the box's row and column masks computed once per block row and
    // column instead of per block and layer (slabs reach 3 to 4 blocks along their radial axis,
    // and that bookkeeping was most of the walk's cost on lidar frames).
    void add_slab(const VoxelKey& lo, const VoxelKey& hi, bool ring, const Eigen::Vector3d& p, Moments& acc) const;
    // add_slab's walk, ranking the records with the byte table (Block::at) or, compiled for the
    // Avx2 level (add_slab_v3), with a population count (Block::at_layer_bit): the same records.
    template <bool Popcount>
    void add_slab_walk(const VoxelKey& lo, const VoxelKey& hi, bool ring, const Eigen::Vector3d& p, Moments& acc) const;
    void add_slab_v3(const VoxelKey& lo, const VoxelKey& hi, bool ring, const Eigen::Vector3d& p, Moments& acc) const;
    // Calls f(block, b, layers, full) for each window block b = (bx, by, bz) whose layers within
    // the box [l, h] (window coordinates) hold voxels, in the order z, y, x: `layers` has bit z
    // set for those layers, `full` is the box's 8x8 layer mask in the block (bit x + 8 y).
    template <typename F>
    void for_each_block(const VoxelKey& l, const VoxelKey& h, F&& f) const;
    // Block (bx, by, bz) of the window, looked up (look_up) on first use.
    const PackedVoxels::Block* block(int bx, int by, int bz) const;
    const PackedVoxels::Block* look_up(int bx, int by, int bz) const;

    // The voxel list (building it, or taking it from the shared list, on first use: first_list).
    const VoxelList& list() const;
    const VoxelList& first_list() const;
    VoxelList build_list(ListArena* arena = nullptr) const;
    // Whether H^k(v) goes through the voxel list.
    bool listed(const VoxelKey& v, int k) const;
    // The level of each listed voxel for v (computed once per vertex).
    const std::uint8_t* levels(const VoxelKey& v) const;
    // Adds the listed voxels with level k (whole: level <= k) to acc, in list order.
    void add_listed(const VoxelKey& v, int k, bool whole, Moments& acc) const;

    const PackedVoxels* voxels_;
    double alpha_;
    int cube_level_;
    int radius_;   // blocks on each side of the vertex block
    int side_;     // 2 radius + 1
    VoxelKey vertex_block_;
    VoxelKey first_voxel_;  // smallest voxel key covered by the window
    // side^3 blocks, x fastest: kNoVoxels (layers 0) when the block holds no voxel; looked up when
    // a box first reaches them (an entry whose stamp is not stamp_ is not looked up yet). Most
    // boxes stay within the 3x3x3 blocks around the vertex block (the 5x5x5 of the radial slabs
    // are reached along one axis), and a window is built per vertex block a task meets, so
    // looking all of them up front cost ~9 % of a KITTI frame.
    struct WindowBlock {
        const PackedVoxels::Block* block = nullptr;
        std::uint32_t stamp = 0;
    };
    mutable std::vector<WindowBlock> blocks_;
    std::uint32_t stamp_ = 0;

    SharedList* shared_ = nullptr;          // where the list is shared (nullptr: own_)
    ListArena* arena_ = nullptr;            // where a shared list this window builds lives (nullptr: the heap)
    mutable const VoxelList* list_ = nullptr;  // the list in use, nullptr until first use
    mutable VoxelList own_;                 // the list built for this window alone
    // The levels for vertex level_vertex_, while levels_valid_.
    mutable std::vector<std::uint8_t> levels_;
    mutable VoxelKey level_vertex_;
    mutable int count1_ = 0, count2_ = 0;  // points of H^1(level_vertex_), of H^2(level_vertex_)
    mutable bool levels_valid_ = false;
    SimdLevel simd_ = SimdLevel::Portable;  // simd_level() when the window was (re)set: which scan kernels run
};

}  // namespace lidarsurf
