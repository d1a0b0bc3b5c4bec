// The viewer's server (view/server.hpp): its origin rule without a socket, and on a socket a
// page whose session fails.
#include "view/server.hpp"

#include <gtest/gtest.h>

#include <limits>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include <boost/asio/ip/tcp.hpp>
#include <boost/beast/core.hpp>
#include <boost/beast/websocket.hpp>
#include <nlohmann/json.hpp>

#include "physics/terrain.hpp"
#include "tests/view/fake_web.hpp"
#include "tests/view/view_test_robot.hpp"

using namespace softevo;

// The WebSocket's origin check compares with the address the server was started for, never
// with the client's own Host header: a DNS-rebinding page (Origin http://evil.example:PORT,
// Host evil.example:PORT) used to be accepted.
TEST(ViewOrigin, OnlyPagesOfTheBoundAddressMayOpenTheSocket) {
  using view::origin_allowed;
  for (const char* ok : {"http://127.0.0.1:8765", "http://localhost:8765", "http://127.0.0.2:8765",
                         "http://[::1]:8765"})
    EXPECT_TRUE(origin_allowed(ok, "127.0.0.1", 8765)) << ok;
  for (const char* bad :
       {"http://evil.example:8765", "http://127.0.0.1:8766", "https://127.0.0.1:8765",
        "http://127.0.0.1", "http://192.168.1.5:8765", "null", "", "http://127.0.0.1:8765/x",
        "http://localhost.evil.example:8765"})
    EXPECT_FALSE(origin_allowed(bad, "127.0.0.1", 8765)) << bad;
  // Bound to one address of the network: that address, not a name.
  EXPECT_TRUE(origin_allowed("http://10.0.0.7:9000", "10.0.0.7", 9000));
  EXPECT_FALSE(origin_allowed("http://localhost:9000", "10.0.0.7", 9000));
  EXPECT_FALSE(origin_allowed("http://node7.cluster:9000", "10.0.0.7", 9000));
  // Bound to every interface: any address literal or localhost, still no name.
  EXPECT_TRUE(origin_allowed("http://10.0.0.7:9000", "0.0.0.0", 9000));
  EXPECT_TRUE(origin_allowed("http://localhost:9000", "0.0.0.0", 9000));
  EXPECT_FALSE(origin_allowed("http://rebind.evil.example:9000", "0.0.0.0", 9000));
}

namespace {

namespace beast = boost::beast;
namespace websocket = beast::websocket;
using tcp = boost::asio::ip::tcp;

// A trace input whose page session cannot start: a voxel's position is not finite, so there is
// no ground grid to send under its path (what a trace with inf positions did before the trace
// reader refused it, issue 39).
view::ViewInput unstartable_input() {
  view::ViewInput in = test::block_input(TaskKind::gait, 0.1);
  in.kind = view::InputKind::trace;
  in.trace_motion.body = in.body;
  scene::Pose pose = scene::rest_pose(in.body);
  pose.position[0].x() = std::numeric_limits<double>::infinity();
  in.trace_motion.poses = {pose};
  physics::TerrainParams bumps;
  bumps.kind = physics::TerrainKind::bumps;
  bumps.seed = 7;
  bumps.shape.amplitude = 0.01;
  bumps.shape.correlation_length = 0.05;
  in.trace_motion.terrain = physics::make_terrain(bumps, {1, 1, 1}, in.body.voxel_size);
  return in;
}

// The text messages a page gets on /ws until the server closes the socket.
std::vector<std::string> page_messages(int port) {
  boost::asio::io_context io;
  websocket::stream<tcp::socket> ws(io);
  ws.next_layer().connect(
      {boost::asio::ip::make_address("127.0.0.1"), static_cast<unsigned short>(port)});
  ws.handshake("127.0.0.1:" + std::to_string(port), "/ws");
  std::vector<std::string> texts;
  for (;;) {
    beast::flat_buffer buffer;
    beast::error_code ec;
    ws.read(buffer, ec);
    if (ec) break;
    if (ws.got_text()) texts.push_back(beast::buffers_to_string(buffer.data()));
  }
  return texts;
}

}  // namespace

// Issue 39: a page whose session fails (here: at its start) gets a plain error and is closed;
// the server lives on for the next page, and its log says what failed. Before, the exception
// left the server's one thread and `softevo view` exited when the first page connected.
TEST(ViewServer, APageWhoseSessionFailsIsClosedAndTheServerLivesOn) {
  const test::FakeWeb web;
  const view::ViewInput in = unstartable_input();
  view::ServerOptions options;
  options.port = 0;
  options.web_dir = web.dir.path;
  std::vector<std::string> log;
  std::mutex log_mutex;
  options.log = [&](const std::string& line) {
    const std::lock_guard<std::mutex> lock(log_mutex);
    log.push_back(line);
  };
  view::Server server(in, options);
  std::thread serving([&] { server.run(); });
  for (int page = 0; page < 2; ++page) {
    const std::vector<std::string> texts = page_messages(server.port());
    ASSERT_EQ(texts.size(), 1u) << page;
    const auto error = nlohmann::json::parse(texts[0]);
    EXPECT_EQ(error["type"], "error");
    EXPECT_NE(error["message"].get<std::string>().find("the server's log says why"),
              std::string::npos)
        << texts[0];
  }
  server.stop();
  serving.join();
  const std::lock_guard<std::mutex> lock(log_mutex);
  ASSERT_EQ(log.size(), 2u);
  EXPECT_NE(log[0].find("not finite"), std::string::npos) << log[0];
}
