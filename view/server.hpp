// The HTTP + WebSocket server of `softevo view` (Boost.Beast on Boost.Asio, one thread).
//
// HTTP serves a fixed table of files read into memory at start: the page (view/web) and three.js
// from view/web/node_modules; no path from a request ever reaches the file system. The WebSocket
// at /ws gives each page its own ClientSession, ticked 60 times a second. Limits: at most
// `max_clients` pages at once (more get HTTP 503), a page from another origin is refused (403;
// a web site the user visits must not drive the local server; the origin is compared with the
// address the server was started for), client messages larger than kMaxWireMessageBytes close
// the socket (code 1009), smaller bad ones are answered with an error by ClientSession. Memory
// of queued replies is bounded per page and in total (a page beyond it, or one that takes no
// data for 20 s, is dropped); idle connections close after 20 s. A page that goes away releases
// its session at once.
#pragma once

#include <atomic>
#include <functional>
#include <memory>
#include <string>
#include <string_view>

#include "view/client_session.hpp"
#include "view/session.hpp"

namespace softevo::view {

inline constexpr std::size_t kMaxWireMessageBytes = 64 * 1024;

struct ServerOptions {
  std::string bind = "127.0.0.1";
  int port = 8765;  // 0 = any free port
  int max_clients = 4;
  std::string web_dir;   // view/web with node_modules
  ClientOptions client;  // its log, when empty, is the server's
  // The server's log, one line per call without a newline: what pages are not told (a page's
  // failed session, a failed save). Empty = stderr, each line prefixed "softevo view: ".
  std::function<void(const std::string&)> log;
};

// The files the page needs, by URL path -> (content type, bytes). Throws std::runtime_error
// naming the missing file and how to get it (npm ci in view/web).
struct WebFile {
  std::string content_type;
  std::string bytes;
};
std::vector<std::pair<std::string, WebFile>> load_web_files(const std::string& web_dir);

// Whether a page of `origin` (the Origin header) may open the socket of a server bound to
// `bind`:`port`: "http://HOST:PORT" with HOST "localhost" (loopback or wildcard binds), the
// bound address, any loopback address for a loopback bind, or any IP literal for a wildcard bind
// (0.0.0.0, ::). A DNS name other than localhost never is (what DNS rebinding needs).
bool origin_allowed(std::string_view origin, const std::string& bind, int port);

class Server {
 public:
  // Binds at once (throws std::runtime_error naming the address when it cannot).
  Server(const ViewInput& input, ServerOptions options);
  ~Server();
  int port() const;  // the bound port
  std::string url() const;
  // Serves until stop() or SIGINT / SIGTERM.
  void run();
  void stop();
  // Pages connected now (for tests and the status line).
  int clients() const;
  // Bound to a loopback address only (else other machines reach it: `softevo view` warns).
  bool loopback_only() const;

  struct Impl;  // the connections of server.cpp reach it (public only for them)

 private:
  std::unique_ptr<Impl> impl_;
};

}  // namespace softevo::view
