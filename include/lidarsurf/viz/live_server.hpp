#pragma once
// A live view of the map in a browser: an HTTP server (Boost.Beast) that serves one page at "/"
// and the live mesh's stream (viz/live_feed.hpp, viz/live_stream.hpp) as a WebSocket at "/live",
// nothing else. It runs on a thread of its own; the producer only hands over each update.
//  - Loopback by default; another address only when the caller names it.
//  - Every client gets the map so far, then each update; a slow client gets each block's latest
//    mesh once when it is ready (its state is bounded by the map), and one that takes longer than
//    write_timeout to take a message is dropped. The producer never waits for a client.
//  - The stream is one way: a client that sends a message (or a malformed frame, or a request
//    over header_limit bytes) is dropped; the others go on. At most max_clients at once.
#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>

#include <Eigen/Geometry>

#include "lidarsurf/map/live_mesh.hpp"

namespace lidarsurf {
namespace detail {
struct LiveServerState;
}

struct LiveServerConfig {
    std::string bind = "127.0.0.1";  ///< address to listen on (an IPv4 or IPv6 literal)
    int port = 8080;                 ///< 0: a free port chosen by the system (port() tells it)
    std::size_t max_clients = 16;    ///< WebSocket clients at once; more are refused (HTTP 503)
    std::size_t max_message_bytes = std::size_t{4} << 20;  ///< a catch-up is cut into messages of about this size
    std::size_t send_buffer_bytes = std::size_t{1} << 20;  ///< each client's socket send buffer (SO_SNDBUF)
    double write_timeout = 10;       ///< seconds a client may take to take one message
    double request_timeout = 10;     ///< seconds a client may take to send its request, or to answer a close
    /// Throws InvalidArgument naming the first bad field.
    void validate() const;
};

class LiveServer {
public:
    /// Listens at once and serves `page` (HTML) at "/". Throws InvalidArgument for a bad address
    /// or config, IoError when the port cannot be had (in use, not permitted).
    LiveServer(const LiveServerConfig& config, std::string page);
    /// Closes the port, drops the clients and joins the thread.
    ~LiveServer();
    LiveServer(const LiveServer&) = delete;
    LiveServer& operator=(const LiveServer&) = delete;

    /// The port it listens on.
    int port() const;
    /// What an update changed, with the sensor's pose after scan number `scans` (see LiveFeed).
    void publish(MeshDelta delta, const Eigen::Isometry3d& pose, std::uint32_t scans);
    /// The drive has ended: `blocks` (the final mesh cut at the blocks) replace the live mesh.
    void finish(std::vector<MeshBlock> blocks, const Eigen::Isometry3d& pose, std::uint32_t scans);

    struct Stats {
        std::size_t clients = 0;   ///< WebSocket clients connected now
        std::size_t accepted = 0;  ///< WebSocket clients accepted so far
        std::size_t dropped = 0;   ///< clients dropped for an error, a message, a timeout
        std::size_t messages = 0;  ///< messages sent
        std::size_t bytes = 0;     ///< bytes of messages sent
        std::size_t wire_bytes = 0;  ///< bytes they took on the wire (permessage-deflate, WebSocket frames)
    };
    Stats stats() const;

private:
    std::unique_ptr<detail::LiveServerState> impl_;
};

}  // namespace lidarsurf
