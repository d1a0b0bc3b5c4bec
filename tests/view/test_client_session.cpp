// What one page controls (view/client_session.hpp): the hello and first frame; a malformed
// message is answered with an error and changes nothing; playback, pause, step, seek, speed,
// reset; steering and saving refused when they make no sense; a save writes into the save
// directory and tells the page only the file names.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <set>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "tests/io/tmp_dir.hpp"
#include "tests/view/view_test_robot.hpp"
#include "view/client_session.hpp"

using namespace softevo;
using nlohmann::json;

namespace {

int frames_in(const std::vector<view::Outgoing>& out) {
  int n = 0;
  for (const auto& m : out) n += m.binary ? 1 : 0;
  return n;
}

std::vector<json> texts(const std::vector<view::Outgoing>& out) {
  std::vector<json> j;
  for (const auto& m : out)
    if (!m.binary) j.push_back(json::parse(m.bytes));
  return j;
}

std::string first_error(const std::vector<view::Outgoing>& out) {
  for (const auto& j : texts(out))
    if (j["type"] == "error") return j["message"];
  return "";
}

}  // namespace

TEST(ViewClientSession, StartsWithTheHelloAndTheFirstFrame) {
  const view::ViewInput in = test::block_input(TaskKind::directed, 0.2);
  view::ClientSession c(in, {});
  const auto out = c.start();
  const json hello = texts(out).at(0);
  EXPECT_EQ(hello["type"], "hello");
  EXPECT_EQ(hello["voxels"], in.body.voxel_cells.size());
  EXPECT_EQ(hello["chamber_cells"], in.body.chamber_cells.size());
  // The lattice cells the page draws the deformed body from (issue 39): voxels, then chambers.
  const auto& cells = hello["cells"];
  ASSERT_EQ(cells.size(), 3 * (in.body.voxel_cells.size() + in.body.chamber_cells.size()));
  EXPECT_EQ(cells[3], in.body.voxel_cells[1].x());
  const std::size_t j = 3 * in.body.voxel_cells.size();
  EXPECT_EQ(cells[j + 2], in.body.chamber_cells[0].z());
  EXPECT_EQ(hello["directed"], true);
  EXPECT_EQ(hello["planned_records"], 13);
  EXPECT_EQ(hello["component_names"].size(), 5u);
  // Units for the page's labels (issue 30): the fitness in cm, not "task units"; the target
  // direction in degrees (the page plots only the components in the fitness's unit).
  EXPECT_EQ(hello["fitness_unit"], "cm");
  EXPECT_EQ(hello["component_units"], json::array({"deg", "cm", "cm", "rad", "cm"}));
  EXPECT_EQ(frames_in(out), 1);
}

TEST(ViewClientSession, TheHelloCarriesEachChambersInletChannelForTheFabricationView) {
  const view::ViewInput in = test::block_input(TaskKind::gait, 0.2);
  view::ClientSession c(in, {});
  const json fab = texts(c.start()).at(0)["fabrication"];
  ASSERT_TRUE(fab.contains("channels")) << fab.dump();
  std::set<int> chambers;
  const double s = in.body.voxel_size;
  for (const json& seg : fab["channels"]) {
    chambers.insert(seg["chamber"].get<int>());
    // A wall voxel of the body, and a box inside its cube: 1.5 mm square, a voxel long.
    const int v = seg["voxel"];
    ASSERT_TRUE(v >= 0 && v < static_cast<int>(in.body.voxel_cells.size()));
    std::vector<double> size = seg["size"];
    std::sort(size.begin(), size.end());
    EXPECT_NEAR(size[0], 1.5e-3, 1e-12);
    EXPECT_NEAR(size[1], 1.5e-3, 1e-12);
    EXPECT_NEAR(size[2], s, 1e-12);
    for (double x : seg["centre"].get<std::vector<double>>()) EXPECT_LE(std::abs(x), s / 2);
  }
  EXPECT_EQ(static_cast<int>(chambers.size()), in.body.chamber_count);
}

TEST(ViewClientSession, MalformedMessagesAreAnsweredAndChangeNothing) {
  const view::ViewInput in = test::block_input(TaskKind::gait, 0.2);
  view::ClientSession c(in, {});
  c.start();
  for (const std::string& bad :
       std::vector<std::string>{"", "{", "[]", R"({"type":"evil"})",
                                R"({"type":"speed","value":9})", std::string(5000, 'x')}) {
    const auto out = c.handle(bad, true);
    ASSERT_EQ(out.size(), 1u) << bad.substr(0, 20);
    EXPECT_FALSE(first_error(out).empty());
  }
  EXPECT_FALSE(first_error(c.handle("\x01\x02", false)).empty());
  EXPECT_TRUE(c.playing());
  EXPECT_EQ(c.speed(), 1.0);
  EXPECT_EQ(c.shown(), 0);
  // Still serving: a step shows the next frame.
  EXPECT_EQ(frames_in(c.handle(R"({"type":"step"})", true)), 1);
  EXPECT_EQ(c.shown(), 1);
}

// The wall-clock budget of a tick (and of a seek) unbounded: what is simulated then depends on
// the messages only, not on how fast this machine (or an instrumented build) simulates.
static view::ClientOptions unbounded() {
  view::ClientOptions o;
  o.max_simulation_seconds_per_tick = 1e9;
  return o;
}

TEST(ViewClientSession, PlaysPausesSeeksAndResets) {
  const view::ViewInput in = test::block_input(TaskKind::gait, 0.5);
  view::ClientSession c(in, unbounded());
  c.start();
  c.handle(R"({"type":"speed","value":2})", true);
  EXPECT_EQ(frames_in(c.tick(0.05)), 1);  // 0.1 s simulated at 2x
  EXPECT_EQ(c.shown(), 6);
  c.handle(R"({"type":"pause"})", true);
  EXPECT_EQ(frames_in(c.tick(0.5)), 0);
  EXPECT_EQ(c.shown(), 6);
  c.handle(R"({"type":"seek","frame":2})", true);
  EXPECT_EQ(c.shown(), 2);
  c.handle(R"({"type":"seek","frame":100000})", true);  // beyond the end: simulated, clamped
  EXPECT_EQ(c.shown(), 30);
  EXPECT_TRUE(c.session().finished());
  c.handle(R"({"type":"reset"})", true);
  EXPECT_EQ(c.shown(), 0);
  EXPECT_EQ(c.session().records(), 1);
}

TEST(ViewClientSession, PlaybackWaitsForASimulationOutOfBudget) {
  // A zero budget: a tick simulates nothing, so the page is shown no new frame, and the
  // playback clock does not run ahead of the simulation (it holds one control step past the
  // last record); once the budget allows, playback goes on from there.
  const view::ViewInput in = test::block_input(TaskKind::gait, 0.5);
  view::ClientOptions starved;
  starved.max_simulation_seconds_per_tick = 0.0;
  view::ClientSession c(in, starved);
  c.start();
  for (int i = 0; i < 10; ++i) EXPECT_EQ(frames_in(c.tick(0.1)), 0);
  EXPECT_EQ(c.shown(), 0);
  EXPECT_EQ(c.session().records(), 1);
  // A step is a message, not playback: it simulates its one frame whatever the budget.
  EXPECT_EQ(frames_in(c.handle(R"({"type":"step"})", true)), 1);
  EXPECT_EQ(c.shown(), 1);
}

TEST(ViewClientSession, RefusesSteeringAGaitRobotAndSavingEarly) {
  const view::ViewInput in = test::block_input(TaskKind::gait, 0.2);
  view::ClientSession c(in, {});
  c.start();
  EXPECT_NE(first_error(c.handle(R"({"type":"steer","deg":40})", true)).find("directed"),
            std::string::npos);
  EXPECT_NE(first_error(c.handle(R"({"type":"save"})", true)).find("ended"), std::string::npos);
}

TEST(ViewClientSession, SavesIntoTheSaveDirectoryAndTellsOnlyTheNames) {
  const test::TmpDir dir;
  const view::ViewInput in = test::block_input(TaskKind::directed, 0.2);
  view::ClientOptions options = unbounded();
  options.save_dir = dir.path;
  view::ClientSession c(in, options);
  c.start();
  c.handle(R"({"type":"steer","deg":40})", true);
  const auto ended = c.handle(R"({"type":"seek","frame":1000})", true);
  bool noted = false;
  for (const auto& j : texts(ended)) noted = noted || j["type"] == "ended";
  EXPECT_TRUE(noted);
  const auto out = c.handle(R"({"type":"save"})", true);
  json saved;
  for (const auto& j : texts(out))
    if (j["type"] == "saved") saved = j;
  ASSERT_FALSE(saved.is_null()) << first_error(out);
  EXPECT_EQ(saved["trace"], "block-view-1.h5");
  EXPECT_EQ(saved["steering"], "block-view-1.steering.json");
  EXPECT_TRUE(std::filesystem::exists(dir.file("block-view-1.h5")));
  EXPECT_TRUE(std::filesystem::exists(dir.file("block-view-1.steering.json")));
  // The same session is not saved twice (each save writes a whole trace: a page could fill the
  // disk); after a reset and a new run, the next save does not replace the first.
  EXPECT_NE(first_error(c.handle(R"({"type":"save"})", true)).find("saved already"),
            std::string::npos);
  EXPECT_FALSE(std::filesystem::exists(dir.file("block-view-2.h5")));
  c.handle(R"({"type":"reset"})", true);
  c.handle(R"({"type":"seek","frame":1000})", true);
  EXPECT_NE(first_error(c.handle(R"({"type":"save"})", true)).find("one save per 2"),
            std::string::npos);
}

// Save is bounded per page (count, rate) and for all pages together (bytes), and its errors
// never show the page a path of the machine.
TEST(ViewClientSession, SavesAreBoundedAndTheirErrorsNameNoPath) {
  const test::TmpDir dir;
  const view::ViewInput in = test::block_input(TaskKind::gait, 0.1);
  view::ClientOptions options = unbounded();
  options.save_dir = dir.path;
  options.min_save_interval_seconds = 0.0;
  options.max_saves = 2;
  options.save_budget = std::make_shared<view::SaveBudget>();
  const auto saved_one = [](view::ClientSession& c) {
    c.handle(R"({"type":"reset"})", true);
    c.handle(R"({"type":"seek","frame":1000})", true);
    return first_error(c.handle(R"({"type":"save"})", true));
  };
  view::ClientSession c(in, options);
  c.start();
  EXPECT_EQ(saved_one(c), "");
  EXPECT_EQ(saved_one(c), "");
  EXPECT_NE(saved_one(c).find("at most 2 saves per page"), std::string::npos);
  const std::uint64_t used = (1ULL << 30) - options.save_budget->bytes_left;
  EXPECT_GT(used, std::filesystem::file_size(dir.file("block-view-1.h5")));

  // The budget is shared: a page of a server whose budget is spent saves nothing.
  options.save_budget->bytes_left = 1;
  options.max_saves = 8;
  view::ClientSession d(in, options);
  d.start();
  EXPECT_EQ(saved_one(d), "");  // within the budget when it starts; the budget is then spent
  EXPECT_NE(saved_one(d).find("save budget is used up"), std::string::npos);

  // A save directory that cannot be written: the page is told why in plain words, never the
  // error's own text (issue 39: libhdf5's error stack reached the page with a temporary path,
  // the process id, a file descriptor and a heap address); the server's log gets all of it.
  const std::string secret = dir.file("secret-place/deeper");
  view::ClientOptions bad = unbounded();
  bad.save_dir = secret;
  std::vector<std::string> log;
  bad.log = [&log](const std::string& line) { log.push_back(line); };
  view::ClientSession e(in, bad);
  e.start();
  const std::string error = saved_one(e);
  EXPECT_EQ(error, "the save failed: the save directory does not exist; nothing was written");
  ASSERT_EQ(log.size(), 1u);
  EXPECT_NE(log[0].find(secret + "/block-view-1.h5"), std::string::npos) << log[0];
  EXPECT_NE(log[0].find("No such file or directory"), std::string::npos) << log[0];
}

// Issue 30: a live robot near the edge of the ground its page has gets the ground under its path
// so far, so that every frame shown lies inside the page's grid. The rough-ground walker that
// ships in robots/, with a margin of a millimetre: its centimetres of walking cross it often.
TEST(ViewClientSession, ALiveRobotNearTheEdgeOfItsGroundGetsMore) {
  const char* source = std::getenv("SOFTEVO_SOURCE_DIR");
  ASSERT_NE(source, nullptr) << "SOFTEVO_SOURCE_DIR is set by ctest";
  view::ViewRequest request;
  request.config_file = std::string(source) + "/configs/gait-rough-open.toml";
  request.seconds = 2.0;
  const view::ViewInput in =
      view::load_view_input(std::string(source) + "/robots/gait-rough-walker.robot.json", request);
  view::ClientOptions options;
  options.terrain_margin_m = 0.001;
  options.max_simulation_seconds_per_tick = 10.0;
  view::ClientSession c(in, options);
  view::TerrainGrid page;  // the page's ground: the hello's, then each "terrain" message's
  const auto take = [&](const std::vector<view::Outgoing>& out) {
    int updates = 0;
    for (const json& j : texts(out)) {
      const json* t = j["type"] == "hello" ? &j.at("terrain") : nullptr;
      if (j["type"] == "terrain") t = &j.at("terrain"), ++updates;
      if (!t) continue;
      page.x0 = (*t)["x0"], page.y0 = (*t)["y0"], page.step = (*t)["step"];
      page.nx = (*t)["nx"], page.ny = (*t)["ny"];
    }
    return updates;
  };
  take(c.start());
  ASSERT_GT(page.nx, 1);
  int updates = 0;
  while (!c.session().finished() || c.shown() + 1 < c.session().records()) {
    updates += take(c.handle(R"({"type":"step"})", true));
    const auto [x, y] = view::record_centre(c.session().record(c.shown()));
    ASSERT_TRUE(page.covers(x, y, 0.5 * options.terrain_margin_m - 1e-12)) << c.shown();
  }
  EXPECT_GT(updates, 0);
  // A flat floor sends none.
  const view::ViewInput flat = test::block_input(TaskKind::gait, 0.2);
  view::ClientSession f(flat, {});
  for (const json& j : texts(f.start())) EXPECT_FALSE(j.contains("terrain"));
}
