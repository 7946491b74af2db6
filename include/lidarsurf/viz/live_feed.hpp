#pragma once
// The live mesh as a server hands it to its clients (viz/live_server.hpp): the map's blocks,
// encoded once each in the stream format (viz/live_stream.hpp), the sensor's trajectory, and per
// client what it still lacks. A client that joins mid-drive gets the whole map first (nearest the
// sensor first, in messages of about max_message_bytes), then what changed since; a client that
// is slow to take its messages gets, when it is ready, each block's latest mesh once, however many
// updates it missed (its state is the set of blocks it lacks: bounded by the map, not by time).
// publish() and finish() are for the producer (one thread); the others for the sending side (one
// thread). Either side only waits for the other's short, copy-free hand-overs.
#include <cstddef>
#include <cstdint>
#include <mutex>
#include <optional>
#include <string>
#include <unordered_map>
#include <unordered_set>
#include <vector>

#include <Eigen/Geometry>

#include "lidarsurf/map/live_mesh.hpp"

namespace lidarsurf {

class LiveFeed {
public:
    using Client = std::uint64_t;  ///< never 0

    /// A catch-up is cut into messages of about this many bytes (one block at least).
    explicit LiveFeed(std::size_t max_message_bytes = std::size_t{4} << 20);

    /// Producer: what an update changed, with the sensor's pose after scan number `scans`. Takes
    /// the delta as it is (no copy, no encoding: the sending side does that).
    void publish(MeshDelta delta, const Eigen::Isometry3d& pose, std::uint32_t scans);
    /// Producer: the drive has ended; `blocks` (the final mesh cut at the blocks, e.g. by
    /// split_into_blocks) replace the live mesh for every client, and each one's last message
    /// then carries live_stream::kFinal.
    void finish(std::vector<MeshBlock> blocks, const Eigen::Isometry3d& pose, std::uint32_t scans);

    /// Sending side: a new client, which lacks everything.
    Client add_client();
    void remove_client(Client client);
    /// The next message for `client`, or nullopt when it has everything published so far.
    std::optional<std::string> next_message(Client client);
    std::size_t clients() const;
    /// Blocks that have a triangle.
    std::size_t blocks() const;

private:
    struct Published {
        MeshDelta delta;
        Eigen::Isometry3d pose;
        std::uint32_t scans;
        std::optional<std::vector<MeshBlock>> final_blocks;  // finish(): the blocks that replace the live mesh
    };
    struct ClientState {
        std::unordered_set<std::uint64_t> lacks;  // packed keys of the blocks to send (changed or removed)
        std::size_t trajectory_sent = 0;
        bool joined = true;      // its first message resets it
        bool final_sent = false;
    };
    void absorb();  // moves the published updates into the state (sending side, state_mutex_ held)
    void mark(std::uint64_t key);

    const std::size_t max_message_bytes_;
    mutable std::mutex incoming_mutex_;
    std::vector<Published> incoming_;

    mutable std::mutex state_mutex_;
    bool has_origin_ = false, finished_ = false;
    Eigen::Vector3d origin_ = Eigen::Vector3d::Zero();
    Eigen::Isometry3d pose_ = Eigen::Isometry3d::Identity();
    std::uint32_t scans_ = 0;
    std::vector<Eigen::Vector3d> trajectory_;
    struct Block {
        VoxelKey key;
        Eigen::Vector3d anchor;  // a vertex of it (world): where it is, for the nearest-first order
        std::string encoded;
    };
    std::unordered_map<std::uint64_t, Block> blocks_;  // by packed key
    std::unordered_map<Client, ClientState> clients_;
    Client next_client_ = 1;
};

}  // namespace lidarsurf
