#include "lidarsurf/viz/live_feed.hpp"

#include <algorithm>

#include "lidarsurf/core/errors.hpp"
#include "lidarsurf/viz/live_stream.hpp"

namespace lidarsurf {

LiveFeed::LiveFeed(std::size_t max_message_bytes) : max_message_bytes_(max_message_bytes) {
    if (max_message_bytes_ < live_stream::kHeaderBytes) throw InvalidArgument("LiveFeed: max_message_bytes is smaller than a header");
}

void LiveFeed::publish(MeshDelta delta, const Eigen::Isometry3d& pose, std::uint32_t scans) {
    const std::lock_guard lock(incoming_mutex_);
    incoming_.push_back({std::move(delta), pose, scans, std::nullopt});
}

void LiveFeed::finish(std::vector<MeshBlock> blocks, const Eigen::Isometry3d& pose, std::uint32_t scans) {
    const std::lock_guard lock(incoming_mutex_);
    incoming_.push_back({{}, pose, scans, std::move(blocks)});
}

void LiveFeed::mark(std::uint64_t key) {
    for (auto& [id, c] : clients_) c.lacks.insert(key);
}

void LiveFeed::absorb() {
    std::vector<Published> updates;
    {
        const std::lock_guard lock(incoming_mutex_);
        updates.swap(incoming_);
    }
    for (Published& u : updates) {
        if (!has_origin_) origin_ = u.pose.translation(), has_origin_ = true;
        if (!u.final_blocks && (trajectory_.empty() || !(trajectory_.back() == u.pose.translation())))  // the same pose again: no motion
            trajectory_.push_back(u.pose.translation());
        pose_ = u.pose;
        scans_ = u.scans;
        auto put = [&](MeshBlock& b) {
            const std::uint64_t packed = pack_key(b.key);
            const Eigen::Vector3d anchor = b.mesh.vertices.empty() ? Eigen::Vector3d::Zero() : b.mesh.vertices.front();
            blocks_[packed] = {b.key, anchor, live_stream::encode_block(b, origin_)};
            mark(packed);
        };
        if (u.final_blocks) {
            // Every block the final mesh does not have is removed; every one it has is sent again.
            for (const auto& [packed, block] : blocks_) mark(packed);
            blocks_.clear();
            for (MeshBlock& b : *u.final_blocks)
                if (!b.mesh.triangles.empty()) put(b);
            finished_ = true;
            continue;
        }
        for (const VoxelKey& key : u.delta.removed) {
            const std::uint64_t packed = pack_key(key);
            blocks_.erase(packed);
            mark(packed);
        }
        for (MeshBlock& b : u.delta.changed) put(b);
    }
}

LiveFeed::Client LiveFeed::add_client() {
    const std::lock_guard lock(state_mutex_);
    absorb();
    const Client id = next_client_++;
    ClientState& c = clients_[id];
    c.lacks.reserve(blocks_.size());
    for (const auto& [packed, block] : blocks_) c.lacks.insert(packed);
    return id;
}

void LiveFeed::remove_client(Client client) {
    const std::lock_guard lock(state_mutex_);
    clients_.erase(client);
}

std::size_t LiveFeed::clients() const {
    const std::lock_guard lock(state_mutex_);
    return clients_.size();
}

std::size_t LiveFeed::blocks() const {
    const std::lock_guard lock(state_mutex_);
    return blocks_.size();
}

std::optional<std::string> LiveFeed::next_message(Client client) {
    const std::lock_guard lock(state_mutex_);
    absorb();
    const auto it = clients_.find(client);
    if (it == clients_.end()) return std::nullopt;
    ClientState& c = it->second;
    const bool final_due = finished_ && !c.final_sent;
    if (!c.joined && c.lacks.empty() && c.trajectory_sent == trajectory_.size() && !final_due) return std::nullopt;

    // The blocks it lacks, nearest the sensor first, until the message is full (one at least).
    struct Lacked {
        double distance2;     // -1 for a removal: removals first
        std::uint64_t packed;
        const Block* block;   // nullptr: removed
    };
    std::vector<Lacked> order;
    order.reserve(c.lacks.size());
    const Eigen::Vector3d sensor = pose_.translation();
    for (const std::uint64_t packed : c.lacks) {
        const auto b = blocks_.find(packed);
        const Block* block = b == blocks_.end() ? nullptr : &b->second;
        order.push_back({block ? (block->anchor - sensor).squaredNorm() : -1.0, packed, block});
    }
    std::sort(order.begin(), order.end(), [](const Lacked& a, const Lacked& b) {
        return a.distance2 < b.distance2 || (a.distance2 == b.distance2 && a.packed < b.packed);
    });
    std::vector<VoxelKey> removed;
    std::vector<const std::string*> changed;
    std::size_t bytes = live_stream::kHeaderBytes + 12 * (trajectory_.size() - c.trajectory_sent);
    std::size_t taken = 0;
    for (; taken < order.size(); ++taken) {
        const Lacked& l = order[taken];
        const std::size_t size = l.block ? l.block->encoded.size() : 12;
        if (taken > 0 && bytes + size > max_message_bytes_) break;
        bytes += size;
        if (l.block) changed.push_back(&l.block->encoded);
        else removed.push_back(unpack_key(l.packed));
    }
    for (std::size_t i = 0; i < taken; ++i) c.lacks.erase(order[i].packed);

    live_stream::Header header;
    header.origin = origin_;
    header.pose = pose_;
    header.scans = scans_;
    if (c.joined) header.flags |= live_stream::kReset;
    if (!c.lacks.empty()) header.flags |= live_stream::kMore;
    else if (finished_) header.flags |= live_stream::kFinal, c.final_sent = true;
    const std::span<const Eigen::Vector3d> trajectory(trajectory_.data() + c.trajectory_sent, trajectory_.size() - c.trajectory_sent);
    std::string message = live_stream::encode_message(header, trajectory, removed, changed);
    c.trajectory_sent = trajectory_.size();
    c.joined = false;
    return message;
}

}  // namespace lidarsurf
