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
constexpr auto kHttpTimeout = std::chrono::seconds(30);
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

  Impl(const ViewInput& in, ServerOptions opts) : input(in), options(std::move(opts)) {}
  void accept();
};

namespace {

// One page's WebSocket: its ClientSession, a tick timer and a queue of outgoing messages (one
// write in flight at a time, as Beast requires).
class SocketSession : public std::enable_shared_from_this<SocketSession> {
 public:
  SocketSession(tcp::socket socket, Server::Impl& server)
      : ws_(std::move(socket)), timer_(ws_.get_executor()), server_(server) {}
  ~SocketSession() { --server_.clients; }

  void start(http::request<http::string_body> request) {
    ++server_.clients;
    ws_.set_option(websocket::stream_base::timeout::suggested(beast::role_type::server));
    // The message limit is checked here (read()), not by Beast: Beast's own limit fails the
    // connection at once, and its teardown in Boost 1.74 closes the socket after one read with
    // the rest of the big message unread, so the kernel answers with a reset and the page sees
    // 1006 instead of the close frame. Beast's limit stays as a backstop far above ours.
    ws_.read_message_max(kBackstopMessageBytes);
    // Kept in the session: the request must outlive the asynchronous accept.
    upgrade_ = std::move(request);
    ws_.async_accept(upgrade_, [self = shared_from_this()](beast::error_code ec) {
      if (ec) return;
      try {
        self->client_ =
            std::make_unique<ClientSession>(self->server_.input, self->server_.options.client);
      } catch (const std::exception& e) {
        self->queue({{false, error_json(std::string("cannot start the session: ") + e.what())}});
        return;
      }
      self->queue(self->client_->start());
      self->last_tick_ = std::chrono::steady_clock::now();
      self->read();
      self->schedule_tick();
    });
  }

 private:
  // Reads a message in pieces so that one over kMaxWireMessageBytes is never held: at the limit
  // the socket is closed with 1009 (close()), which drains the rest of the message first.
  void read() {
    ws_.async_read_some(buffer_, kReadChunkBytes,
                        [self = shared_from_this()](beast::error_code ec, std::size_t) {
                          if (ec) {  // closed, or the connection broke: all released
                            self->closed_ = true;
                            self->timer_.cancel();
                            return;
                          }
                          if (self->buffer_.size() > kMaxWireMessageBytes)
                            return self->close(websocket::close_code::too_big);
                          if (!self->ws_.is_message_done()) return self->read();
                          const std::string text = beast::buffers_to_string(self->buffer_.data());
                          self->buffer_.consume(self->buffer_.size());
                          self->queue(self->client_->handle(text, self->ws_.got_text()));
                          self->read();
                        });
  }

  // A close is a write for Beast (one at a time): it goes after the write in flight, and what
  // was still queued is dropped.
  void close(websocket::close_code code) {
    close_code_ = code;
    buffer_.consume(buffer_.size());
    while (queue_.size() > (writing_ ? 1u : 0u)) queue_.pop_back();
    write_next();
  }

  void schedule_tick() {
    timer_.expires_after(kTick);
    timer_.async_wait([self = shared_from_this()](beast::error_code ec) {
      if (ec || self->closed_) return;
      const auto now = std::chrono::steady_clock::now();
      const double dt = std::chrono::duration<double>(now - self->last_tick_).count();
      self->last_tick_ = now;
      self->queue(self->client_->tick(dt));
      self->schedule_tick();
    });
  }

  void queue(std::vector<Outgoing> messages) {
    for (auto& m : messages) {
      if (m.binary) {
        std::size_t frames = 0;
        for (const auto& q : queue_) frames += q.binary ? 1 : 0;
        // Drop the oldest frame not being written (the front is in flight).
        if (frames >= kMaxQueuedFrames) {
          for (auto it = queue_.begin() + (writing_ ? 1 : 0); it != queue_.end(); ++it)
            if (it->binary) {
              queue_.erase(it);
              break;
            }
        }
      }
      queue_.push_back(std::move(m));
    }
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
    ws_.binary(queue_.front().binary);
    ws_.async_write(asio::buffer(queue_.front().bytes),
                    [self = shared_from_this()](beast::error_code ec, std::size_t) {
                      self->writing_ = false;
                      if (ec) {
                        self->closed_ = true;
                        self->timer_.cancel();
                        return;
                      }
                      self->queue_.pop_front();
                      self->write_next();
                    });
  }

  websocket::stream<beast::tcp_stream> ws_;
  asio::steady_timer timer_;
  Server::Impl& server_;
  std::unique_ptr<ClientSession> client_;
  http::request<http::string_body> upgrade_;
  beast::flat_buffer buffer_;
  std::deque<Outgoing> queue_;
  bool writing_ = false;
  bool closed_ = false;
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
  // Same origin only: a page of another site may not open the socket.
  bool same_origin() const {
    const auto origin = request_.find(http::field::origin);
    if (origin == request_.end()) return true;  // not a browser page (a tool, a test)
    const std::string expected = "http://" + std::string(request_[http::field::host]);
    return std::string(origin->value()) == expected;
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

void Server::Impl::accept() {
  acceptor.async_accept([this](beast::error_code ec, tcp::socket socket) {
    if (ec) {
      if (ec != asio::error::operation_aborted) accept();
      return;
    }
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
    impl_->signals.cancel(ignored);
    impl_->io.stop();
  });
}

}  // namespace softevo::view
