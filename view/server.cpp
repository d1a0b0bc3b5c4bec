// See server.hpp.
#include "view/server.hpp"

#include <chrono>
#include <cstdio>
#include <deque>
#include <filesystem>
#include <fstream>
#include <map>
#include <optional>
#include <sstream>
#include <stdexcept>

#include <boost/asio/ip/tcp.hpp>
#include <boost/asio/signal_set.hpp>
#include <boost/asio/steady_timer.hpp>
#include <boost/beast/core.hpp>
#include <boost/beast/http.hpp>
#include <boost/beast/websocket.hpp>

namespace softevo::view {

namespace asio = boost::asio;
namespace beast = boost::beast;
namespace http = beast::http;
namespace websocket = beast::websocket;
using tcp = asio::ip::tcp;
namespace fs = std::filesystem;

namespace {

constexpr auto kTick = std::chrono::microseconds(1'000'000 / 60);
// A connection that does nothing for this long is closed: an HTTP request not completed, a
// WebSocket handshake not completed, a page that answers no ping. Silent clients cannot hold the
// --max-clients places for long.
constexpr auto kHttpTimeout = std::chrono::seconds(20);
constexpr auto kIdleTimeout = std::chrono::seconds(20);
// A page whose socket takes no data for this long (a write in flight that does not finish) is
// dropped: it does not read.
constexpr auto kWriteStall = std::chrono::seconds(20);
// Memory of the messages waiting to be sent (text replies included): per page and for all pages
// together. A page beyond either is dropped and its memory freed; so a client that sends and
// never reads cannot grow the server.
constexpr std::size_t kMaxQueuedBytesPerClient = 8u << 20;
constexpr std::size_t kMaxQueuedBytesTotal = 32u << 20;
constexpr std::size_t kMessageOverheadBytes = 64;  // a queued message's own allocations
// After an accept error (no descriptors left: EMFILE), wait this long before the next accept
// instead of failing again at once in a loop.
constexpr auto kAcceptBackoff = std::chrono::milliseconds(200);
// Binary frames waiting to be sent beyond this are dropped (the oldest first): a slow link sees
// fewer frames, never a growing queue.
constexpr std::size_t kMaxQueuedFrames = 4;
// A client message is read in pieces of this size [bytes]; Beast fails a connection only
// beyond the backstop (a frame header announcing more).
constexpr std::size_t kReadChunkBytes = 4096;
constexpr std::size_t kBackstopMessageBytes = 64 * kMaxWireMessageBytes;

std::string read_whole(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw std::runtime_error(path.string() + ": cannot be read");
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

}  // namespace

std::vector<std::pair<std::string, WebFile>> load_web_files(const std::string& web_dir) {
  const fs::path web(web_dir);
  const fs::path modules = web / "node_modules";
  struct Entry {
    const char* url;
    fs::path file;
    const char* type;
  };
  const Entry entries[] = {
      {"/", web / "index.html", "text/html; charset=utf-8"},
      {"/app.js", web / "app.js", "text/javascript; charset=utf-8"},
      {"/plots.js", web / "plots.js", "text/javascript; charset=utf-8"},
      {"/style.css", web / "style.css", "text/css; charset=utf-8"},
      {"/vendor/three.module.min.js", modules / "three/build/three.module.min.js",
       "text/javascript; charset=utf-8"},
      {"/vendor/OrbitControls.js", modules / "three/examples/jsm/controls/OrbitControls.js",
       "text/javascript; charset=utf-8"},
  };
  std::vector<std::pair<std::string, WebFile>> files;
  for (const auto& e : entries) {
    if (!fs::exists(e.file))
      throw std::runtime_error(e.file.string() +
                               ": missing; the page's packages are installed by " + "`npm ci` in " +
                               web.string() + " (tools/bootstrap.sh quickstart does it)");
    files.push_back({e.url, {e.type, read_whole(e.file)}});
  }
  return files;
}

struct Server::Impl {
  const ViewInput& input;
  ServerOptions options;
  asio::io_context io{1};
  tcp::acceptor acceptor{io};
  asio::signal_set signals{io, SIGINT, SIGTERM};
  std::map<std::string, WebFile> files;
  std::atomic<int> clients{0};
  int bound_port = 0;
  std::size_t queued_bytes = 0;  // of every page's queue
  asio::steady_timer accept_backoff{io};
  bool accept_error_reported = false;

  Impl(const ViewInput& in, ServerOptions opts) : input(in), options(std::move(opts)) {
    if (!options.client.save_budget) options.client.save_budget = std::make_shared<SaveBudget>();
    if (!options.client.log) options.client.log = [this](const std::string& line) { log(line); };
  }
  // The server's log: stderr, or the options' log when one is given.
  void log(const std::string& line) const {
    if (options.log) return options.log(line);
    std::fprintf(stderr, "softevo view: %s\n", line.c_str());
  }
  void accept();
  bool allowed_origin(std::string_view origin) const;
};

namespace {

// One page's WebSocket: its ClientSession, a tick timer and a queue of outgoing messages (one
// write in flight at a time, as Beast requires).
class SocketSession : public std::enable_shared_from_this<SocketSession> {
 public:
  SocketSession(tcp::socket socket, Server::Impl& server)
      : ws_(std::move(socket)), timer_(ws_.get_executor()), server_(server) {}
  ~SocketSession() {
    --server_.clients;
    server_.queued_bytes -= queued_bytes_;
  }

  void start(http::request<http::string_body> request) {
    ++server_.clients;
    websocket::stream_base::timeout timeouts{};
    timeouts.handshake_timeout = kIdleTimeout;
    timeouts.idle_timeout = kIdleTimeout;  // a ping at half of it; no answer: closed
    timeouts.keep_alive_pings = true;
    ws_.set_option(timeouts);
    // The message limit is checked here (read()), not by Beast: Beast's own limit fails the
    // connection at once, and its teardown in Boost 1.74 closes the socket after one read with
    // the rest of the big message unread, so the kernel answers with a reset and the page sees
    // 1006 instead of the close frame. Beast's limit stays as a backstop far above ours.
    ws_.read_message_max(kBackstopMessageBytes);
    // Kept in the session: the request must outlive the asynchronous accept.
    upgrade_ = std::move(request);
    ws_.async_accept(upgrade_, [self = shared_from_this()](beast::error_code ec) {
      if (ec) return;
      const bool started = self->guarded([&] {
        self->client_ =
            std::make_unique<ClientSession>(self->server_.input, self->server_.options.client);
        return self->client_->start();
      });
      if (!started) return;
      self->last_tick_ = std::chrono::steady_clock::now();
      self->read();
      self->schedule_tick();
    });
  }

 private:
  // Runs what a page's session does (start, a message, a tick) and queues its messages. An
  // exception never leaves the handler (it would end the server's one thread, and so every
  // page): the page gets a plain error and is closed, and the server's log says why. Returns
  // false then. (Issue 39: a trace with non-finite positions ended the server when the first
  // page connected.)
  template <class Act>
  bool guarded(Act&& act) {
    try {
      queue(act());
      return true;
    } catch (const std::exception& e) {
      server_.log(std::string("a page's session failed and was closed: ") + e.what());
    } catch (...) {
      server_.log("a page's session failed and was closed");
    }
    queue({{false, error_json("the session failed and was closed (the server's log says why)")}});
    close(websocket::close_code::internal_error);
    return false;
  }

  // Reads a message in pieces so that one over kMaxWireMessageBytes is never held: at the limit
  // the socket is closed with 1009 (close()), which drains the rest of the message first.
  void read() {
    ws_.async_read_some(
        buffer_, kReadChunkBytes, [self = shared_from_this()](beast::error_code ec, std::size_t) {
          if (ec) {  // closed, or the connection broke: all released
            self->closed_ = true;
            self->timer_.cancel();
            self->read_delay_.cancel();
            return;
          }
          if (self->buffer_.size() > kMaxWireMessageBytes)
            return self->close(websocket::close_code::too_big);
          if (!self->ws_.is_message_done()) return self->read();
          const std::string text = beast::buffers_to_string(self->buffer_.data());
          self->buffer_.consume(self->buffer_.size());
          const auto t0 = std::chrono::steady_clock::now();
          if (!self->guarded([&] { return self->client_->handle(text, self->ws_.got_text()); }))
            return;
          self->read_after(std::chrono::steady_clock::now() - t0);
        });
  }

  // Fairness: a message that kept the server's one thread busy (a reset, a long seek) delays
  // this page's next read by as long, so one page's message loop takes at most about half of
  // the thread and every other page keeps its ticks.
  void read_after(std::chrono::steady_clock::duration busy) {
    if (closed_) return;
    if (busy < std::chrono::milliseconds(2)) return read();
    read_delay_.expires_after(busy);
    read_delay_.async_wait([self = shared_from_this()](beast::error_code ec) {
      if (!ec && !self->closed_) self->read();
    });
  }

  // Drops the page at once (it does not read, or is over its memory budget): the socket is
  // closed, the pending operations end, and the queue is freed but for the write in flight,
  // whose buffer the socket still holds until its handler runs.
  void drop() {
    if (dropped_) return;
    dropped_ = true;
    closed_ = true;
    timer_.cancel();
    read_delay_.cancel();
    while (queue_.size() > (writing_ ? 1u : 0u)) pop_back();
    buffer_.clear();
    buffer_.shrink_to_fit();
    beast::error_code ignored;
    beast::get_lowest_layer(ws_).socket().shutdown(tcp::socket::shutdown_both, ignored);
    beast::get_lowest_layer(ws_).socket().close(ignored);
  }

  static std::size_t cost(const Outgoing& m) { return m.bytes.capacity() + kMessageOverheadBytes; }
  void push_back(Outgoing m) {
    queued_bytes_ += cost(m);
    server_.queued_bytes += cost(m);
    queue_.push_back(std::move(m));
  }
  void pop_front() {
    queued_bytes_ -= cost(queue_.front());
    server_.queued_bytes -= cost(queue_.front());
    queue_.pop_front();
  }
  void pop_back() {
    queued_bytes_ -= cost(queue_.back());
    server_.queued_bytes -= cost(queue_.back());
    queue_.pop_back();
  }
  void erase(std::deque<Outgoing>::iterator it) {
    queued_bytes_ -= cost(*it);
    server_.queued_bytes -= cost(*it);
    queue_.erase(it);
  }

  // A close is a write for Beast (one at a time): it goes after the write in flight, and what
  // was still queued is dropped.
  void close(websocket::close_code code) {
    close_code_ = code;
    buffer_.consume(buffer_.size());
    while (queue_.size() > (writing_ ? 1u : 0u)) pop_back();
    write_next();
  }

  void schedule_tick() {
    timer_.expires_after(kTick);
    timer_.async_wait([self = shared_from_this()](beast::error_code ec) {
      if (ec || self->closed_) return;
      const auto now = std::chrono::steady_clock::now();
      if (self->writing_ && now - self->write_started_ > kWriteStall) return self->drop();
      const double dt = std::chrono::duration<double>(now - self->last_tick_).count();
      self->last_tick_ = now;
      if (!self->guarded([&] { return self->client_->tick(dt); })) return;
      self->schedule_tick();
    });
  }

  void queue(std::vector<Outgoing> messages) {
    if (closed_) return;
    for (auto& m : messages) {
      if (m.binary) {
        std::size_t frames = 0;
        for (const auto& q : queue_) frames += q.binary ? 1 : 0;
        // Drop the oldest frame not being written (the front is in flight).
        if (frames >= kMaxQueuedFrames) {
          for (auto it = queue_.begin() + (writing_ ? 1 : 0); it != queue_.end(); ++it)
            if (it->binary) {
              erase(it);
              break;
            }
        }
      }
      push_back(std::move(m));
    }
    if (queued_bytes_ > kMaxQueuedBytesPerClient || server_.queued_bytes > kMaxQueuedBytesTotal)
      return drop();
    write_next();
  }

  void write_next() {
    if (writing_ || closed_) return;
    if (close_code_) {
      writing_ = true;
      closed_ = true;  // nothing more is queued or ticked
      timer_.cancel();
      ws_.async_close(*close_code_,
                      [self = shared_from_this()](beast::error_code) { self->writing_ = false; });
      return;
    }
    if (queue_.empty()) return;
    writing_ = true;
    write_started_ = std::chrono::steady_clock::now();
    ws_.binary(queue_.front().binary);
    ws_.async_write(asio::buffer(queue_.front().bytes),
                    [self = shared_from_this()](beast::error_code ec, std::size_t) {
                      self->writing_ = false;
                      if (ec) {
                        self->closed_ = true;
                        self->timer_.cancel();
                        self->read_delay_.cancel();
                        while (!self->queue_.empty()) self->pop_back();
                        return;
                      }
                      self->pop_front();
                      self->write_next();
                    });
  }

  websocket::stream<beast::tcp_stream> ws_;
  asio::steady_timer timer_;
  asio::steady_timer read_delay_{ws_.get_executor()};
  Server::Impl& server_;
  std::unique_ptr<ClientSession> client_;
  http::request<http::string_body> upgrade_;
  beast::flat_buffer buffer_;
  std::deque<Outgoing> queue_;
  std::size_t queued_bytes_ = 0;  // cost() of queue_
  bool writing_ = false;
  bool closed_ = false;
  bool dropped_ = false;
  std::chrono::steady_clock::time_point write_started_;
  std::optional<websocket::close_code> close_code_;  // a close to send after the write in flight
  std::chrono::steady_clock::time_point last_tick_;
};

// One HTTP connection: a request, its answer, then the next request (or the upgrade to /ws).
class HttpSession : public std::enable_shared_from_this<HttpSession> {
 public:
  HttpSession(tcp::socket socket, Server::Impl& server)
      : stream_(std::move(socket)), server_(server) {}

  void read() {
    request_ = {};
    parser_.emplace();
    parser_->body_limit(4096);
    parser_->header_limit(16 * 1024);
    stream_.expires_after(kHttpTimeout);
    http::async_read(stream_, buffer_, *parser_,
                     [self = shared_from_this()](beast::error_code ec, std::size_t) {
                       if (ec) return;  // closed, timed out or malformed: drop the connection
                       self->request_ = self->parser_->release();
                       self->answer();
                     });
  }

 private:
  // Pages of this server only: a page of another site may not open the socket. Compared with
  // the address the server was started for, never with the request's own Host header (a page
  // of a DNS-rebinding site sends a Host that matches its own Origin).
  bool same_origin() const {
    const auto origin = request_.find(http::field::origin);
    if (origin == request_.end()) return true;  // not a browser page (a tool, a test)
    return server_.allowed_origin(std::string_view(origin->value().data(), origin->value().size()));
  }

  void answer() {
    std::string target(request_.target());
    if (const auto q = target.find('?'); q != std::string::npos) target.resize(q);
    if (websocket::is_upgrade(request_)) {
      if (target != "/ws") return reply(http::status::not_found, "no such socket\n");
      if (!same_origin()) return reply(http::status::forbidden, "cross-origin socket refused\n");
      if (server_.clients >= server_.options.max_clients)
        return reply(http::status::service_unavailable,
                     "too many viewers connected (at most " +
                         std::to_string(server_.options.max_clients) + ")\n");
      stream_.expires_never();
      std::make_shared<SocketSession>(stream_.release_socket(), server_)
          ->start(std::move(request_));
      return;
    }
    if (request_.method() != http::verb::get && request_.method() != http::verb::head)
      return reply(http::status::method_not_allowed, "only GET\n");
    const auto file = server_.files.find(target == "/index.html" ? "/" : target);
    if (file == server_.files.end()) return reply(http::status::not_found, "not found\n");
    reply(http::status::ok, file->second.bytes, file->second.content_type);
  }

  void reply(http::status status, std::string body,
             const std::string& type = "text/plain; charset=utf-8") {
    auto res = std::make_shared<http::response<http::string_body>>(status, request_.version());
    res->set(http::field::server, "softevo-view");
    res->set(http::field::content_type, type);
    res->set(http::field::cache_control, "no-store");
    res->set("X-Content-Type-Options", "nosniff");
    res->keep_alive(request_.keep_alive());
    const bool head = request_.method() == http::verb::head;
    res->body() = head ? std::string() : std::move(body);
    res->prepare_payload();
    http::async_write(stream_, *res,
                      [self = shared_from_this(), res](beast::error_code ec, std::size_t) {
                        if (ec || !res->keep_alive()) {
                          beast::error_code ignored;
                          self->stream_.socket().shutdown(tcp::socket::shutdown_send, ignored);
                          return;
                        }
                        self->read();
                      });
  }

  beast::tcp_stream stream_;
  Server::Impl& server_;
  beast::flat_buffer buffer_;
  std::optional<http::request_parser<http::string_body>> parser_;
  http::request<http::string_body> request_;
};

}  // namespace

bool Server::Impl::allowed_origin(std::string_view origin) const {
  return origin_allowed(origin, options.bind, bound_port);
}

bool origin_allowed(std::string_view origin, const std::string& bind, int port) {
  // "http://HOST:PORT" with this server's port, HOST "localhost" or an IP address literal: the
  // address bound, or any literal when bound to every interface (0.0.0.0, ::). A DNS name other
  // than localhost is never allowed: that is what a rebinding attack needs.
  const std::string scheme = "http://";
  if (origin.substr(0, scheme.size()) != scheme) return false;
  std::string_view rest = origin.substr(scheme.size());
  const auto colon = rest.rfind(':');
  if (colon == std::string_view::npos || rest.substr(colon + 1) != std::to_string(port))
    return false;
  std::string host(rest.substr(0, colon));
  if (host.size() > 2 && host.front() == '[' && host.back() == ']')
    host = host.substr(1, host.size() - 2);
  beast::error_code ec;
  const auto bound = asio::ip::make_address(bind, ec);
  if (ec) return false;
  if (host == "localhost") return bound.is_loopback() || bound.is_unspecified();
  const auto address = asio::ip::make_address(host, ec);
  if (ec) return false;  // a DNS name
  if (bound.is_unspecified()) return true;
  return address == bound || (bound.is_loopback() && address.is_loopback());
}

void Server::Impl::accept() {
  acceptor.async_accept([this](beast::error_code ec, tcp::socket socket) {
    if (ec) {
      if (ec == asio::error::operation_aborted) return;
      // Out of descriptors (EMFILE, ENFILE) or memory: accepting again at once fails again at
      // once, a loop at full CPU. Wait, then try again (the idle timeouts free descriptors).
      if (!accept_error_reported) {
        log("cannot accept a connection (" + ec.message() + "); retrying");
        accept_error_reported = true;
      }
      accept_backoff.expires_after(kAcceptBackoff);
      accept_backoff.async_wait([this](beast::error_code e) {
        if (!e) accept();
      });
      return;
    }
    accept_error_reported = false;
    std::make_shared<HttpSession>(std::move(socket), *this)->read();
    accept();
  });
}

Server::Server(const ViewInput& input, ServerOptions options)
    : impl_(std::make_unique<Impl>(input, std::move(options))) {
  for (auto& [url, file] : load_web_files(impl_->options.web_dir))
    impl_->files[url] = std::move(file);
  const std::string where = impl_->options.bind + ":" + std::to_string(impl_->options.port);
  beast::error_code ec;
  const auto address = asio::ip::make_address(impl_->options.bind, ec);
  if (ec) throw std::runtime_error("--bind " + impl_->options.bind + ": not an IP address");
  const tcp::endpoint endpoint(address, static_cast<unsigned short>(impl_->options.port));
  impl_->acceptor.open(endpoint.protocol(), ec);
  if (!ec) impl_->acceptor.set_option(asio::socket_base::reuse_address(true), ec);
  if (!ec) impl_->acceptor.bind(endpoint, ec);
  if (!ec) impl_->acceptor.listen(asio::socket_base::max_listen_connections, ec);
  if (ec) throw std::runtime_error("cannot listen on " + where + ": " + ec.message());
  impl_->bound_port = impl_->acceptor.local_endpoint().port();
}

Server::~Server() = default;

int Server::port() const {
  return impl_->bound_port;
}

std::string Server::url() const {
  const std::string host = impl_->options.bind == "0.0.0.0" ? "127.0.0.1" : impl_->options.bind;
  const bool v6 = host.find(':') != std::string::npos;
  return "http://" + (v6 ? "[" + host + "]" : host) + ":" + std::to_string(port()) + "/";
}

bool Server::loopback_only() const {
  beast::error_code ec;
  const auto address = asio::ip::make_address(impl_->options.bind, ec);
  return !ec && address.is_loopback();
}

int Server::clients() const {
  return impl_->clients;
}

void Server::run() {
  impl_->signals.async_wait([this](beast::error_code, int) { stop(); });
  impl_->accept();
  impl_->io.run();
}

void Server::stop() {
  asio::post(impl_->io, [this] {
    beast::error_code ignored;
    impl_->acceptor.close(ignored);
    impl_->accept_backoff.cancel();
    impl_->signals.cancel(ignored);
    impl_->io.stop();
  });
}

}  // namespace softevo::view
