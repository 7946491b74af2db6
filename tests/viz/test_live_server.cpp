// The live view's server (viz/live_server.hpp) over real sockets on 127.0.0.1, with Boost.Beast
// clients: it serves the page and the stream and nothing else; several clients each end with the
// final mesh (decoded and applied by the test's own client); a client that stalls, sends a
// malformed frame or a message is dropped while the others go on; a port in use is refused.
#include <gtest/gtest.h>

#include <chrono>
#include <future>
#include <optional>
#include <thread>

#include <boost/asio.hpp>
#include <boost/beast/core.hpp>
#include <boost/beast/http.hpp>
#include <boost/beast/websocket.hpp>

#include "../map/town_drive.hpp"
#include "lidarsurf/core/errors.hpp"
#include "lidarsurf/pipeline.hpp"
#include "lidarsurf/viz/live_server.hpp"
#include "live_client.hpp"

using namespace lidarsurf;
namespace beast = boost::beast;
namespace http = beast::http;
namespace websocket = beast::websocket;
namespace net = boost::asio;
using tcp = net::ip::tcp;

namespace {

const char* const kPage = "<!DOCTYPE html><title>live</title>";

tcp::endpoint loopback(int port) { return {net::ip::make_address("127.0.0.1"), static_cast<unsigned short>(port)}; }

// One HTTP request, the response's status and body.
std::pair<unsigned, std::string> request(int port, http::verb verb, const std::string& target) {
    net::io_context ioc;
    tcp::socket socket(ioc);
    socket.connect(loopback(port));
    http::request<http::empty_body> req(verb, target, 11);
    req.set(http::field::host, "127.0.0.1");
    http::write(socket, req);
    beast::flat_buffer buffer;
    http::response<http::string_body> res;
    http::read(socket, buffer, res);
    return {res.result_int(), res.body()};
}

// A WebSocket client of /live; reads with a deadline.
class WsClient {
public:
    explicit WsClient(int port, int receive_buffer = 0) : ws_(ioc_) {
        tcp::socket& s = ws_.next_layer();
        s.open(tcp::v4());
        if (receive_buffer > 0) s.set_option(net::socket_base::receive_buffer_size(receive_buffer));
        s.connect(loopback(port));
        ws_.handshake("127.0.0.1", "/live");
        ws_.read_message_max(std::size_t{1} << 30);
    }
    // The next message; nullopt when the server closed the connection or nothing came in time.
    std::optional<std::string> read(double seconds = 60) {
        beast::flat_buffer buffer;
        std::optional<beast::error_code> result;
        ws_.async_read(buffer, [&](beast::error_code ec, std::size_t) { result = ec; });
        ioc_.restart();
        ioc_.run_for(std::chrono::duration_cast<std::chrono::milliseconds>(std::chrono::duration<double>(seconds)));
        if (!result) {
            beast::error_code ignored;
            ws_.next_layer().cancel(ignored);
            ioc_.restart();
            ioc_.run();
            return std::nullopt;
        }
        if (*result) {
            closed_ = true;
            return std::nullopt;
        }
        return beast::buffers_to_string(buffer.data());
    }
    // Reads until the final message; false when the stream ended before it.
    bool read_to_final(test::LiveClient& client) {
        while (!client.final) {
            const std::optional<std::string> m = read();
            if (!m) return false;
            client.take(*m);
        }
        return true;
    }
    websocket::stream<tcp::socket>& ws() { return ws_; }
    // Whether a read found the connection ended (not just no message in time).
    bool closed() const { return closed_; }

private:
    bool closed_ = false;
    net::io_context ioc_;
    websocket::stream<tcp::socket> ws_;
};

// The drive's updates published, then the final mesh; returns the final blocks.
std::vector<MeshBlock> publish_drive(LiveServer& server, std::size_t scans = 0) {
    const std::vector<test::Scan>& drive = test::town_drive();
    const std::size_t n = scans ? scans : drive.size();
    Reconstructor rec(ReconstructionConfig{}, drive[0].from);
    for (std::size_t i = 0; i < n; ++i) {
        rec.integrate(drive[i].points, drive[i].from);
        server.publish(rec.update_mesh(5.0), drive[i].pose, static_cast<std::uint32_t>(i + 1));
    }
    std::vector<MeshBlock> blocks = split_into_blocks(rec.extract_mesh(), rec.grid().origin(), ReconstructionConfig{}.voxel_size);
    server.finish(blocks, drive[n - 1].pose, static_cast<std::uint32_t>(n));
    return blocks;
}

LiveServerConfig any_port() {
    LiveServerConfig c;
    c.port = 0;
    return c;
}

template <typename F>
bool eventually(F&& f, double seconds = 30) {
    const auto until = std::chrono::steady_clock::now() + std::chrono::duration<double>(seconds);
    while (!f()) {
        if (std::chrono::steady_clock::now() > until) return false;
        std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
    return true;
}

}  // namespace

TEST(LiveServer, ServesThePageAndTheStreamAndNothingElse) {
    LiveServer server(any_port(), kPage);
    EXPECT_EQ(LiveServerConfig{}.bind, "127.0.0.1") << "loopback unless the user names an address";
    const int port = server.port();
    ASSERT_GT(port, 0);
    EXPECT_EQ(request(port, http::verb::get, "/"), std::make_pair(200u, std::string(kPage)));
    EXPECT_EQ(request(port, http::verb::get, "/index.html").first, 200u);
    for (const char* target : {"/live", "/favicon.ico", "/../../etc/passwd", "/index.html/..", "//", "/?file=/etc/passwd"})
        EXPECT_EQ(request(port, http::verb::get, target).first, 404u) << target;
    EXPECT_EQ(request(port, http::verb::post, "/").first, 405u);
    EXPECT_EQ(request(port, http::verb::put, "/live").first, 405u);
    // An upgrade anywhere but /live is refused.
    net::io_context ioc;
    websocket::stream<tcp::socket> ws(ioc);
    ws.next_layer().connect(loopback(port));
    EXPECT_THROW(ws.handshake("127.0.0.1", "/other"), boost::system::system_error);
}

TEST(LiveServer, ManyClientsEachEndWithTheFinalMesh) {
    LiveServer server(any_port(), kPage);
    std::vector<std::unique_ptr<WsClient>> clients;
    for (int i = 0; i < 4; ++i) clients.push_back(std::make_unique<WsClient>(server.port()));
    ASSERT_TRUE(eventually([&] { return server.stats().clients == 4; }));
    std::vector<test::LiveClient> got(5);
    std::vector<std::future<bool>> reading;
    for (std::size_t i = 0; i < 4; ++i)  // each reads as the updates come, on a thread of its own
        reading.push_back(std::async(std::launch::async, [&got, i, c = clients[i].get()] { return c->read_to_final(got[i]); }));
    const std::vector<MeshBlock> final_blocks = publish_drive(server);
    clients.push_back(std::make_unique<WsClient>(server.port()));  // joins after the end: gets the final map at once
    reading.push_back(std::async(std::launch::async, [&got, c = clients[4].get()] { return c->read_to_final(got[4]); }));
    for (std::size_t i = 0; i < clients.size(); ++i) {
        ASSERT_TRUE(reading[i].get()) << "client " << i;
        const test::LiveClient& client = got[i];
        EXPECT_TRUE(client.headers_only.front().header.flags & live_stream::kReset);
        EXPECT_EQ(client.headers_only.back().header.scans, test::town_drive().size());
        EXPECT_EQ(client.trajectory, test::town_drive().size());
        test::expect_same_blocks(client.blocks, final_blocks, "client " + std::to_string(i));
    }
    EXPECT_EQ(server.stats().dropped, 0u);
    EXPECT_EQ(server.stats().accepted, 5u);
}

TEST(LiveServer, AStalledClientIsDroppedAndTheOthersGoOn) {
    LiveServerConfig c = any_port();
    c.write_timeout = 2;
    c.max_message_bytes = 256 * 1024;
    c.send_buffer_bytes = 16 * 1024;  // the drive's compressed blocks would fit the default's buffers
    LiveServer server(c, kPage);
    WsClient stalled(server.port(), 4096);  // never reads; a small receive buffer fills at once
    WsClient reader(server.port());
    ASSERT_TRUE(eventually([&] { return server.stats().clients == 2; }));
    test::LiveClient client;
    auto reading = std::async(std::launch::async, [&] { return reader.read_to_final(client); });  // reads as it comes
    const std::vector<MeshBlock> final_blocks = publish_drive(server);
    ASSERT_TRUE(reading.get());
    test::expect_same_blocks(client.blocks, final_blocks, "the reading client");
    EXPECT_TRUE(eventually([&] { return server.stats().dropped == 1 && server.stats().clients == 1; }))
        << "the stalled client is dropped after write_timeout";
    // The reader is still served: a new update reaches it.
    Eigen::Isometry3d moved = test::town_drive().back().pose;
    moved.translation().x() += 1;
    server.publish(MeshDelta{}, moved, 99);
    const std::optional<std::string> m = reader.read();
    ASSERT_TRUE(m);
    client.take(*m);
    EXPECT_EQ(client.headers_only.back().header.scans, 99u);
}

TEST(LiveServer, AClientThatSendsAMalformedFrameOrAMessageIsDroppedAlone) {
    LiveServerConfig c = any_port();
    c.write_timeout = 1;  // the server's close waits for an answer at most as long as its pings do
    LiveServer server(c, kPage);
    WsClient garbage(server.port()), talker(server.port()), reader(server.port());
    ASSERT_TRUE(eventually([&] { return server.stats().clients == 3; }));
    // Frame headers no WebSocket client sends: reserved bits set, an unknown opcode, no mask.
    const unsigned char junk[] = {0xFF, 0x00, 0xFF, 0x00};
    net::write(garbage.ws().next_layer(), net::buffer(junk));
    talker.ws().text(true);
    talker.ws().write(net::buffer(std::string("{\"colour\": \"level\"}")));  // the stream is one way
    ASSERT_TRUE(eventually([&] { return server.stats().dropped == 2; }, 10)) << server.stats().dropped << " dropped";
    for (int i = 0; i < 3 && garbage.read(10); ++i) {  // what was sent before it misbehaved
    }
    EXPECT_TRUE(garbage.closed()) << "its connection is closed";
    test::LiveClient client;
    auto reading = std::async(std::launch::async, [&] { return reader.read_to_final(client); });
    const std::vector<MeshBlock> final_blocks = publish_drive(server, 2);
    ASSERT_TRUE(reading.get());
    test::expect_same_blocks(client.blocks, final_blocks, "the well-behaved client");
    EXPECT_EQ(server.stats().clients, 1u);
}

TEST(LiveServer, RefusesClientsBeyondItsLimit) {
    LiveServerConfig c = any_port();
    c.max_clients = 2;
    LiveServer server(c, kPage);
    WsClient a(server.port()), b(server.port());
    ASSERT_TRUE(eventually([&] { return server.stats().clients == 2; }));
    EXPECT_THROW(WsClient{server.port()}, boost::system::system_error);
    EXPECT_EQ(request(server.port(), http::verb::get, "/").first, 200u) << "the page is still served";
}

TEST(LiveServer, APortInUseOrABadAddressIsRefused) {
    LiveServer first(any_port(), kPage);
    LiveServerConfig c;
    c.port = first.port();
    EXPECT_THROW(LiveServer(c, kPage), IoError);
    c.port = 0;
    c.bind = "localhost:80";
    EXPECT_THROW(LiveServer(c, kPage), InvalidArgument);
    c.bind = "127.0.0.1";
    c.port = 70000;
    EXPECT_THROW(LiveServer(c, kPage), InvalidArgument);
    c.port = 0;
    c.write_timeout = 0;
    EXPECT_THROW(LiveServer(c, kPage), InvalidArgument);
}
