#include "lidarsurf/viz/live_server.hpp"

#include <atomic>
#include <chrono>
#include <cmath>
#include <limits>
#include <optional>
#include <set>
#include <thread>
#include <vector>

#include <boost/asio.hpp>
#include <boost/beast/core.hpp>
#include <boost/beast/http.hpp>
#include <boost/beast/websocket.hpp>

#include "lidarsurf/core/errors.hpp"
#include "lidarsurf/viz/live_feed.hpp"

namespace lidarsurf {

namespace beast = boost::beast;
namespace http = beast::http;
namespace websocket = beast::websocket;
namespace net = boost::asio;
using tcp = net::ip::tcp;

namespace {

std::chrono::steady_clock::duration after(double seconds) {
    return std::chrono::duration_cast<std::chrono::steady_clock::duration>(std::chrono::duration<double>(seconds));
}

// A request's header may be this long; a request may have no body.
constexpr std::uint32_t kHeaderLimit = 8192;
// A client may send control frames (pong, close); a data message ends it.
constexpr std::size_t kReadMessageMax = 1024;

// The stream's socket counts what it writes: the bytes on the wire, after permessage-deflate.
class CountingRatePolicy {
public:
    std::size_t written = 0;

private:
    friend class boost::beast::rate_policy_access;
    std::size_t available_read_bytes() const noexcept { return (std::numeric_limits<std::size_t>::max)(); }
    std::size_t available_write_bytes() const noexcept { return (std::numeric_limits<std::size_t>::max)(); }
    void transfer_read_bytes(std::size_t) const noexcept {}
    void transfer_write_bytes(std::size_t n) noexcept { written += n; }
    void on_timer() const noexcept {}
};
using CountedStream = beast::basic_stream<tcp, net::any_io_executor, CountingRatePolicy>;

class WsSession;

}  // namespace

void LiveServerConfig::validate() const {
    if (port < 0 || port > 65535) throw InvalidArgument("LiveServerConfig.port must be in [0, 65535] (got " + std::to_string(port) + ")");
    if (max_clients < 1) throw InvalidArgument("LiveServerConfig.max_clients must be >= 1");
    if (max_message_bytes < 4096) throw InvalidArgument("LiveServerConfig.max_message_bytes must be >= 4096");
    if (send_buffer_bytes < 4096 || send_buffer_bytes > (std::size_t{1} << 30))
        throw InvalidArgument("LiveServerConfig.send_buffer_bytes must be in [4096, 2^30]");
    if (!std::isfinite(write_timeout) || write_timeout <= 0 || !std::isfinite(request_timeout) || request_timeout <= 0)
        throw InvalidArgument("LiveServerConfig.write_timeout and request_timeout must be > 0 seconds");
}

namespace detail {
struct LiveServerState {
    LiveServerState(const LiveServerConfig& c, std::string p) : config(c), page(std::move(p)), feed(c.max_message_bytes) {}

    LiveServerConfig config;
    std::string page;
    net::io_context ioc{1};
    tcp::acceptor acceptor{ioc};
    LiveFeed feed;
    std::set<std::shared_ptr<WsSession>> sessions;  // the io thread's
    std::atomic<bool> kick_pending{false};
    std::atomic<std::size_t> accepted{0}, dropped{0}, messages{0}, bytes{0}, wire_bytes{0};
    int port = 0;  // the one listened on (set before the thread starts)
    std::thread thread;

    void accept();
    // Has every client take what it lacks (from the io thread, once per burst of updates).
    void kick();
    void close_all();
};
}  // namespace detail

namespace {

class WsSession : public std::enable_shared_from_this<WsSession> {
public:
    WsSession(detail::LiveServerState& server, tcp::socket&& socket) : server_(server), ws_(std::move(socket)), timer_(server.ioc) {}

    void run(http::request<http::empty_body> request) {
        request_ = std::move(request);
        websocket::stream_base::timeout t;
        t.handshake_timeout = after(server_.config.request_timeout);
        t.idle_timeout = after(3 * server_.config.write_timeout);  // pings at half of it; no answer: dropped
        t.keep_alive_pings = true;
        ws_.set_option(t);
        ws_.set_option(websocket::stream_base::decorator([](websocket::response_type& r) { r.set(http::field::server, "lidarsurf"); }));
        ws_.read_message_max(kReadMessageMax);
        ws_.binary(true);
        // permessage-deflate when the client offers it (browsers do): each message compressed with
        // the ones before as context, at zlib's fastest level (the blocks' codes leave it a third).
        websocket::permessage_deflate deflate;
        deflate.server_enable = true;
        deflate.compLevel = 1;
        deflate.memLevel = 8;  // zlib's default: ~300 KiB a client
        ws_.set_option(deflate);
        ws_.async_accept(request_, [self = shared_from_this()](beast::error_code ec) { self->on_accept(ec); });
    }

    // Sends the next message when none is on its way.
    void pump() {
        if (closed_ || writing_ || !joined()) return;
        std::optional<std::string> message = server_.feed.next_message(id_);
        if (!message) return;
        out_ = std::move(*message);
        writing_ = true;
        timer_.expires_after(after(server_.config.write_timeout));
        timer_.async_wait([self = shared_from_this()](beast::error_code ec) {
            if (!ec) self->drop(true);  // the client took too long: it goes, the others go on
        });
        ws_.async_write(net::buffer(out_), [self = shared_from_this()](beast::error_code ec, std::size_t n) {
            self->timer_.cancel();
            self->writing_ = false;
            if (ec) return self->drop(true);
            ++self->server_.messages;
            self->server_.bytes += n;
            CountingRatePolicy& wire = self->ws_.next_layer().rate_policy();
            self->server_.wire_bytes += wire.written;
            wire.written = 0;
            self->out_ = std::string();
            self->pump();
        });
    }

    void drop(bool error) {
        if (closed_) return;
        closed_ = true;
        if (error) ++server_.dropped;
        if (joined()) {
            server_.feed.remove_client(id_);
            server_.sessions.erase(shared_from_this());
        }
        beast::error_code ec;
        beast::get_lowest_layer(ws_).socket().shutdown(tcp::socket::shutdown_both, ec);
        beast::get_lowest_layer(ws_).close();
        timer_.cancel();
    }

private:
    void on_accept(beast::error_code ec) {
        if (ec) return drop(true);
        if (server_.sessions.size() >= server_.config.max_clients) {  // full since the request was read
            ws_.async_close(websocket::close_code::try_again_later, [self = shared_from_this()](beast::error_code) { self->drop(false); });
            return;
        }
        id_ = server_.feed.add_client();
        server_.sessions.insert(shared_from_this());
        ++server_.accepted;
        read();
        pump();
    }

    // The stream is one way: any data message, a malformed frame or the connection's end ends it.
    void read() {
        ws_.async_read(in_, [self = shared_from_this()](beast::error_code ec, std::size_t) {
            self->drop(ec != websocket::error::closed && ec != net::error::eof && ec != net::error::operation_aborted);
        });
    }

    detail::LiveServerState& server_;
    websocket::stream<CountedStream> ws_;
    http::request<http::empty_body> request_;
    beast::flat_buffer in_;
    std::string out_;
    net::steady_timer timer_;
    bool joined() const { return id_ != 0; }  // the feed's clients are numbered from 1

    LiveFeed::Client id_ = 0;
    bool writing_ = false, closed_ = false;
};

// One HTTP request: the page, the WebSocket's upgrade, or a refusal; then the connection ends.
class HttpSession : public std::enable_shared_from_this<HttpSession> {
public:
    HttpSession(detail::LiveServerState& server, tcp::socket&& socket) : server_(server), stream_(std::move(socket)) {}

    void run() {
        parser_.header_limit(kHeaderLimit);
        parser_.body_limit(0);
        stream_.expires_after(after(server_.config.request_timeout));
        http::async_read(stream_, buffer_, parser_, [self = shared_from_this()](beast::error_code ec, std::size_t) { self->on_read(ec); });
    }

private:
    void on_read(beast::error_code ec) {
        if (ec) {  // a malformed or oversized request, a timeout, the client gone
            if (ec != http::error::end_of_stream) ++server_.dropped;
            return;
        }
        const http::request<http::empty_body>& request = parser_.get();
        const beast::string_view target = request.target();
        if (websocket::is_upgrade(request)) {
            if (target != "/live") return respond(http::status::not_found, "not found\n", "text/plain");
            if (server_.sessions.size() >= server_.config.max_clients)
                return respond(http::status::service_unavailable, "too many viewers\n", "text/plain");
            stream_.expires_never();
            std::make_shared<WsSession>(server_, stream_.release_socket())->run(parser_.release());
            return;
        }
        if (request.method() != http::verb::get) return respond(http::status::method_not_allowed, "only GET\n", "text/plain");
        if (target == "/" || target == "/index.html") return respond(http::status::ok, server_.page, "text/html; charset=utf-8");
        respond(http::status::not_found, "not found\n", "text/plain");
    }

    void respond(http::status status, const std::string& body, const char* type) {
        response_.version(11);
        response_.result(status);
        response_.set(http::field::server, "lidarsurf");
        response_.set(http::field::content_type, type);
        response_.set(http::field::cache_control, "no-store");
        response_.set("X-Content-Type-Options", "nosniff");
        response_.keep_alive(false);
        response_.body() = body;
        response_.prepare_payload();
        http::async_write(stream_, response_, [self = shared_from_this()](beast::error_code, std::size_t) {
            beast::error_code ignored;
            self->stream_.socket().shutdown(tcp::socket::shutdown_send, ignored);
        });
    }

    detail::LiveServerState& server_;
    beast::tcp_stream stream_;
    beast::flat_buffer buffer_{kHeaderLimit};
    http::request_parser<http::empty_body> parser_;
    http::response<http::string_body> response_;
};

}  // namespace

void detail::LiveServerState::accept() {
    acceptor.async_accept([this](beast::error_code ec, tcp::socket socket) {
        if (ec == net::error::operation_aborted || !acceptor.is_open()) return;
        if (!ec) {
            // The kernel's share of a client's memory: its send buffer, bounded.
            beast::error_code ignored;
            socket.set_option(net::socket_base::send_buffer_size(static_cast<int>(config.send_buffer_bytes)), ignored);
            std::make_shared<HttpSession>(*this, std::move(socket))->run();
        }
        accept();
    });
}

void detail::LiveServerState::kick() {
    if (kick_pending.exchange(true)) return;
    net::post(ioc, [this] {
        kick_pending = false;
        const std::vector<std::shared_ptr<WsSession>> all(sessions.begin(), sessions.end());
        for (const auto& s : all) s->pump();
    });
}

void detail::LiveServerState::close_all() {
    beast::error_code ec;
    acceptor.close(ec);
    const std::vector<std::shared_ptr<WsSession>> all(sessions.begin(), sessions.end());
    for (const auto& s : all) s->drop(false);
}

LiveServer::LiveServer(const LiveServerConfig& config, std::string page) {
    config.validate();
    impl_ = std::make_unique<detail::LiveServerState>(config, std::move(page));
    beast::error_code ec;
    const net::ip::address address = net::ip::make_address(config.bind, ec);
    if (ec) throw InvalidArgument("'" + config.bind + "' is not an IP address to listen on (e.g. 127.0.0.1, 0.0.0.0, ::1)");
    const tcp::endpoint endpoint(address, static_cast<unsigned short>(config.port));
    const std::string where = config.bind + " port " + std::to_string(config.port);
    tcp::acceptor& a = impl_->acceptor;
    if (a.open(endpoint.protocol(), ec); ec) throw IoError("cannot listen on " + where + ": " + ec.message());
    a.set_option(net::socket_base::reuse_address(true), ec);  // a restart right after a stop; two listeners still conflict
    if (a.bind(endpoint, ec); ec) {
        if (ec == net::error::address_in_use) throw IoError("cannot listen on " + where + ": the port is in use (choose another one)");
        throw IoError("cannot listen on " + where + ": " + ec.message());
    }
    if (a.listen(net::socket_base::max_listen_connections, ec); ec) throw IoError("cannot listen on " + where + ": " + ec.message());
    impl_->port = a.local_endpoint().port();
    impl_->accept();
    impl_->thread = std::thread([this] { impl_->ioc.run(); });
}

LiveServer::~LiveServer() {
    net::post(impl_->ioc, [this] {
        impl_->close_all();
        impl_->ioc.stop();
    });
    impl_->thread.join();
    impl_->sessions.clear();
}

int LiveServer::port() const { return impl_->port; }

void LiveServer::publish(MeshDelta delta, const Eigen::Isometry3d& pose, std::uint32_t scans) {
    impl_->feed.publish(std::move(delta), pose, scans);
    impl_->kick();
}

void LiveServer::finish(std::vector<MeshBlock> blocks, const Eigen::Isometry3d& pose, std::uint32_t scans) {
    impl_->feed.finish(std::move(blocks), pose, scans);
    impl_->kick();
}

LiveServer::Stats LiveServer::stats() const {
    return {impl_->feed.clients(), impl_->accepted.load(), impl_->dropped.load(), impl_->messages.load(), impl_->bytes.load(), impl_->wire_bytes.load()};
}

}  // namespace lidarsurf
