#pragma once
// A sparse map from lattice keys to values, stored as dense 8x8x8 blocks found through a hash map
// of block keys (the layout of VDB leaves and voxblox blocks). Every slot of a block that exists
// holds a value (the map's `empty` value until written), so a lookup is one hash probe for the
// block and one array index; an Accessor remembers the last block and skips even the probe for
// the spatially coherent lookups of the surface search and marching cubes.
//
// Blocks are never moved once created (held by pointer), so a pointer or reference to a slot
// stays valid while other blocks are added. Creating blocks is not thread-safe; reading and
// writing slots of existing blocks from several threads (distinct slots) is.
#include <array>
#include <cstdint>
#include <memory>
#include <algorithm>
#include <optional>
#include <utility>
#include <vector>

#include "lidarsurf/core/voxel_key.hpp"

namespace lidarsurf {

/// A box of block keys: [lo, lo + size) per axis.
struct BlockBox {
    VoxelKey lo = VoxelKey::Zero();
    VoxelKey size = VoxelKey::Zero();  ///< cells per axis
};
/// The smallest box of block keys holding `keys`, grown by `margin` blocks on every side, if it
/// holds at most `cells_per_key` cells per key and at most `max_cells` cells (else nullopt): a
/// box for BlockIndex::use_box.
std::optional<BlockBox> dense_block_box(const std::vector<VoxelKey>& keys, int margin, std::size_t cells_per_key,
                                        std::size_t max_cells = std::size_t{1} << 40);

/// Open-addressing hash table from block keys (packed to 64 bits) to block numbers: linear
/// probing, load <= 1/2. Much faster than std::unordered_map for this small, hot lookup. With a
/// box (use_box), the keys inside it are held by a dense table of the box instead: one load
/// and no probe (a probe for an absent key runs on to an empty slot).
class BlockIndex {
public:
    static constexpr std::uint32_t kAbsent = 0xffffffffu;

    /// Bytes held by the table.
    std::size_t memory_bytes() const {
        return keys_.capacity() * sizeof(std::uint64_t) + values_.capacity() * sizeof(std::uint32_t) + box_.capacity() * sizeof(std::uint32_t);
    }
    /// Holds the keys of `box` in a dense table from now on (the others stay in the hash). Only
    /// on an empty index; throws InvalidArgument otherwise.
    void use_box(const BlockBox& box);
    bool has_box() const { return !box_.empty(); }

    std::uint32_t find(const VoxelKey& key) const {
        if (const std::uint32_t* cell = box_cell(key)) return *cell;
        if (keys_.empty()) return kAbsent;
        const std::uint64_t packed = pack_key(key);
        for (std::size_t i = mix64(packed) & mask_;; i = (i + 1) & mask_) {
            if (keys_[i] == packed) return values_[i];
            if (keys_[i] == kEmpty) return kAbsent;
        }
    }
    /// The value of `key`, inserting `value` first if absent; .second tells whether it was.
    std::pair<std::uint32_t, bool> try_emplace(const VoxelKey& key, std::uint32_t value) {
        if (std::uint32_t* cell = box_cell(key)) {
            if (*cell != kAbsent) return {*cell, false};
            *cell = value;
            return {value, true};
        }
        if (2 * (size_ + 1) > keys_.size()) grow(std::max<std::size_t>(64, 2 * keys_.size()));
        const std::uint64_t packed = pack_key(key);
        std::size_t i = mix64(packed) & mask_;
        for (; keys_[i] != kEmpty; i = (i + 1) & mask_)
            if (keys_[i] == packed) return {values_[i], false};
        keys_[i] = packed;
        values_[i] = value;
        ++size_;
        return {value, true};
    }
    void reserve(std::size_t n) {
        std::size_t cap = 64;
        while (cap < 2 * n) cap *= 2;
        if (cap > keys_.size()) grow(cap);
    }

private:
    static constexpr std::uint64_t kEmpty = ~std::uint64_t{0};  // pack_key never gives this
    // The dense table's cell of `key`, or nullptr outside the box (or without one).
    const std::uint32_t* box_cell(const VoxelKey& key) const {
        const VoxelKey d = key - box_lo_;  // keys within +-2^20: no overflow
        if (static_cast<unsigned>(d.x()) >= static_cast<unsigned>(box_size_.x()) ||
            static_cast<unsigned>(d.y()) >= static_cast<unsigned>(box_size_.y()) ||
            static_cast<unsigned>(d.z()) >= static_cast<unsigned>(box_size_.z()))
            return nullptr;
        return &box_[static_cast<std::size_t>(d.x()) +
                     static_cast<std::size_t>(box_size_.x()) * (static_cast<std::size_t>(d.y()) + static_cast<std::size_t>(box_size_.y()) * static_cast<std::size_t>(d.z()))];
    }
    std::uint32_t* box_cell(const VoxelKey& key) { return const_cast<std::uint32_t*>(std::as_const(*this).box_cell(key)); }
    void grow(std::size_t capacity) {
        std::vector<std::uint64_t> old_keys(capacity, kEmpty);
        std::vector<std::uint32_t> old_values(capacity);
        old_keys.swap(keys_);
        old_values.swap(values_);
        mask_ = capacity - 1;
        for (std::size_t j = 0; j < old_keys.size(); ++j) {
            if (old_keys[j] == kEmpty) continue;
            std::size_t i = mix64(old_keys[j]) & mask_;
            while (keys_[i] != kEmpty) i = (i + 1) & mask_;
            keys_[i] = old_keys[j];
            values_[i] = old_values[j];
        }
    }
    std::vector<std::uint64_t> keys_;
    std::vector<std::uint32_t> values_;
    std::size_t mask_ = 0, size_ = 0;  // size_: the keys in the hash
    // The dense table of the box [box_lo_, box_lo_ + box_size_), x fastest (kAbsent: no key);
    // a size of 0 (no box) puts every key outside.
    std::vector<std::uint32_t> box_;
    VoxelKey box_lo_ = VoxelKey::Zero();
    VoxelKey box_size_ = VoxelKey::Zero();
};

/// Block keys numbered in creation order (0, 1, ...), found through a BlockIndex: the bookkeeping
/// of a map of blocks, whatever each block holds.
class BlockKeys {
public:
    /// Creation index of `block`, or -1.
    std::int64_t index_of(const VoxelKey& block) const {
        const std::uint32_t i = index_.find(block);
        return i == BlockIndex::kAbsent ? -1 : static_cast<std::int64_t>(i);
    }
    /// Creation index of `block`, numbering it next if absent; .second tells whether it was.
    std::pair<std::uint32_t, bool> add(const VoxelKey& block) {
        const auto added = index_.try_emplace(block, static_cast<std::uint32_t>(keys_.size()));
        if (added.second) keys_.push_back(block);
        return added;
    }
    std::size_t block_count() const { return keys_.size(); }
    /// Block keys in creation order.
    const std::vector<VoxelKey>& block_keys() const { return keys_; }
    /// Bytes held: the keys and the index.
    std::size_t memory_bytes() const { return keys_.capacity() * sizeof(VoxelKey) + index_.memory_bytes(); }
    /// Finds the keys of `box` through a dense table (BlockIndex::use_box). Only when empty.
    void use_box(const BlockBox& box) { index_.use_box(box); }
    void reserve(std::size_t n) {
        index_.reserve(n);
        keys_.reserve(n);
    }

private:
    BlockIndex index_;
    std::vector<VoxelKey> keys_;
};

template <typename T>
class BlockMap {
public:
    static constexpr int kBits = 3;
    static constexpr int kSize = 1 << kBits;  // 8 slots per block side
    static constexpr int kVolume = kSize * kSize * kSize;
    using Block = std::array<T, kVolume>;

    explicit BlockMap(T empty = T{}) : empty_(empty) {}

    static VoxelKey block_of(const VoxelKey& key) { return {key.x() >> kBits, key.y() >> kBits, key.z() >> kBits}; }
    /// Index of `key` inside its block: x fastest, then y, then z.
    static int offset_of(const VoxelKey& key) {
        constexpr int m = kSize - 1;
        return (key.x() & m) | ((key.y() & m) << kBits) | ((key.z() & m) << (2 * kBits));
    }
    /// Bit a (x = 0, y = 1, z = 2) set where `key` is its block's last slot along axis a: the axes
    /// along which the cube with minimum corner `key` has corners in the next block.
    static int last_axes(const VoxelKey& key) {
        constexpr int m = kSize - 1;
        return ((key.x() & m) == m) | ((key.y() & m) == m) << 1 | ((key.z() & m) == m) << 2;
    }
    /// Slots from a cube's minimum corner `base` to its corner c (offset (c & 1, c >> 1 & 1, c >> 2),
    /// core/cube.hpp's corner_offset) when the cube's corners share its block (last_axes(base) == 0).
    static int corner_step(int c) { return (c & 1) | ((c >> 1) & 1) << kBits | (c >> 2) << (2 * kBits); }
    /// The key at `offset` of block `block` (inverse of block_of/offset_of).
    static VoxelKey key_at(const VoxelKey& block, int offset) {
        constexpr int m = kSize - 1;
        return {(block.x() << kBits) | (offset & m), (block.y() << kBits) | ((offset >> kBits) & m),
                (block.z() << kBits) | (offset >> (2 * kBits))};
    }

    /// The block with key `block`, or nullptr.
    const Block* find_block(const VoxelKey& block) const {
        const std::int64_t i = keys_.index_of(block);
        return i < 0 ? nullptr : blocks_[static_cast<std::size_t>(i)];
    }
    Block* find_block(const VoxelKey& block) {
        const std::int64_t i = keys_.index_of(block);
        return i < 0 ? nullptr : blocks_[static_cast<std::size_t>(i)];
    }
    /// The block with key `block`, created (filled with the empty value) if absent.
    Block& block(const VoxelKey& block) { return *blocks_[block_index(block)]; }
    /// Creation index of the block with key `block`, creating it if absent.
    std::uint32_t block_index(const VoxelKey& block) {
        const auto [i, added] = block_index_unfilled(block);
        if (added) blocks_.back()->fill(empty_);
        return i;
    }
    /// As block_index(), but a block it creates (.second true) holds garbage until fill_block():
    /// for creating many blocks (serial) and filling them in parallel.
    std::pair<std::uint32_t, bool> block_index_unfilled(const VoxelKey& block) {
        const auto [i, added] = keys_.add(block);
        if (added) blocks_.push_back(new_block());
        return {i, added};
    }
    /// Fills block i with the empty value (block_index_unfilled).
    void fill_block(std::size_t i) { blocks_[i]->fill(empty_); }

    /// The slot of `key`, or nullptr when its block does not exist.
    const T* find(const VoxelKey& key) const {
        const Block* b = find_block(block_of(key));
        return b ? &(*b)[static_cast<std::size_t>(offset_of(key))] : nullptr;
    }
    /// The slot of `key`, creating its block.
    T& operator[](const VoxelKey& key) { return block(block_of(key))[static_cast<std::size_t>(offset_of(key))]; }

    std::size_t block_count() const { return blocks_.size(); }
    /// Bytes held by the map: the blocks' pages, their pointers, keys and index.
    std::size_t memory_bytes() const {
        return pages_.size() * (kPageBlocks * sizeof(Block) + 16) + (blocks_.capacity() + pages_.capacity()) * sizeof(void*) +
               keys_.memory_bytes();
    }
    /// Block keys in creation order; block i of block_at(i).
    const std::vector<VoxelKey>& block_keys() const { return keys_.block_keys(); }
    const Block& block_at(std::size_t i) const { return *blocks_[i]; }
    Block& block_at(std::size_t i) { return *blocks_[i]; }
    /// Creation index of a block key, or -1.
    std::int64_t index_of(const VoxelKey& block) const { return keys_.index_of(block); }
    const T& empty_value() const { return empty_; }

    /// Finds the blocks of `box` through a dense table (BlockIndex::use_box): for a map whose
    /// blocks are known to lie mostly in a box (those of one frame). Only on an empty map.
    void use_box(const BlockBox& box) { keys_.use_box(box); }
    void reserve_blocks(std::size_t n) {
        keys_.reserve(n);
        blocks_.reserve(n);
    }

    /// Read access that remembers the last existing block looked up (blocks never move, so it
    /// stays valid while blocks are added; an absent block is probed again each time).
    class Accessor {
    public:
        explicit Accessor(const BlockMap& map) : map_(&map) {}
        const T* find(const VoxelKey& key) {
            const VoxelKey b = block_of(key);
            if (!last_ || !same_key(b, last_key_)) {
                const Block* found = map_->find_block(b);
                if (!found) return nullptr;
                last_key_ = b;
                last_ = found;
            }
            return &(*last_)[static_cast<std::size_t>(offset_of(key))];
        }

    private:
        const BlockMap* map_;
        VoxelKey last_key_ = VoxelKey::Zero();
        const Block* last_ = nullptr;
    };

    /// Read access that remembers the existing blocks looked up last, one per parity of the block
    /// coordinates: the up to eight blocks around a block corner, which the corners and the
    /// neighbours of a cube there fall in, are all remembered at once (the surface search's
    /// lookups alternate between them; Accessor probes the hash each time the block changes).
    /// Accessor stays for lookups that rarely alternate (marching cubes looks each neighbour block
    /// of a border cube up once): there the table cost more instructions than it saved probes.
    class CornerAccessor {
    public:
        explicit CornerAccessor(const BlockMap& map) : map_(&map) {}
        const T* find(const VoxelKey& key) {
            const VoxelKey b = block_of(key);
            Recent& r = recent_[static_cast<std::size_t>((b.x() & 1) | (b.y() & 1) << 1 | (b.z() & 1) << 2)];
            if (!r.block || !same_key(b, r.key)) {
                const Block* found = map_->find_block(b);
                if (!found) return nullptr;
                r = {b, found};
            }
            return &(*r.block)[static_cast<std::size_t>(offset_of(key))];
        }

    private:
        struct Recent {
            VoxelKey key = VoxelKey::Zero();
            const Block* block = nullptr;
        };
        const BlockMap* map_;
        std::array<Recent, 8> recent_{};
    };

    /// Write access (creating blocks) that remembers the last block, and the blocks met recently
    /// in a small direct-mapped table (the surface search's cubes alternate between a few
    /// neighbouring blocks: one hash probe each time without it): for one thread.
    class WriteAccessor {
    public:
        explicit WriteAccessor(BlockMap& map) : map_(&map) {}
        T& operator[](const VoxelKey& key) {
            const VoxelKey b = block_of(key);
            if (!last_ || !same_key(b, last_key_)) use(b);
            return (*last_)[static_cast<std::size_t>(offset_of(key))];
        }
        /// Creation index of the block with key `block`, creating it if absent (as
        /// BlockMap::block_index, through the same caches).
        std::uint32_t block_index(const VoxelKey& block) {
            if (!last_ || !same_key(block, last_key_)) use(block);
            return last_index_;
        }
        /// Creation index of the block of the last key accessed.
        std::uint32_t block_index() const { return last_index_; }

    private:
        struct Recent {
            VoxelKey key = VoxelKey::Zero();
            Block* block = nullptr;
            std::uint32_t index = 0;
        };
        static constexpr int kRecentBits = 4;
        void use(const VoxelKey& b) {
            const std::uint32_t h = static_cast<std::uint32_t>(b.x()) * 0x9e3779b1u ^ static_cast<std::uint32_t>(b.y()) * 0x85ebca77u ^
                                    static_cast<std::uint32_t>(b.z()) * 0xc2b2ae3du;
            Recent& r = recent_[h >> (32 - kRecentBits)];
            if (!r.block || !same_key(r.key, b)) {
                r.key = b;
                r.index = map_->block_index(b);
                r.block = &map_->block_at(r.index);
            }
            last_ = r.block;
            last_index_ = r.index;
            last_key_ = b;
        }
        BlockMap* map_;
        VoxelKey last_key_ = VoxelKey::Zero();
        Block* last_ = nullptr;
        std::uint32_t last_index_ = 0;
        std::array<Recent, std::size_t{1} << kRecentBits> recent_{};
    };

private:
    T empty_;
    BlockKeys keys_;
    // Blocks are allocated kPageBlocks at a time (one allocation instead of one per block: block
    // creation is a serial step of the surface search); a page's blocks are filled when handed out.
    static constexpr std::size_t kPageBlocks = 32;
    Block* new_block() {
        if (page_free_ == 0) {
            pages_.emplace_back(new Block[kPageBlocks]);
            page_free_ = kPageBlocks;
        }
        return &pages_.back()[kPageBlocks - page_free_--];
    }
    std::vector<Block*> blocks_;
    std::vector<std::unique_ptr<Block[]>> pages_;
    std::size_t page_free_ = 0;
};

}  // namespace lidarsurf
