// The viewer's session (view/session.hpp): unsteered it gives worker::evaluate's bits; steered,
// its steering log reproduces it bit for bit; only a directed robot steers; a saved session is
// a trace (softevo.trace/1) with its log beside it, and the trace plays back as a session.
#include <gtest/gtest.h>

#include <bit>
#include <cmath>
#include <cstdint>
#include <fstream>
#include <memory>
#include <sstream>

#include "io/trace.hpp"
#include "tasks/task.hpp"
#include "tests/io/tmp_dir.hpp"
#include "tests/view/view_test_robot.hpp"
#include "view/session.hpp"
#include "worker/evaluate.hpp"

using namespace softevo;

namespace {

void run_to_end(view::Session& s) {
  while (s.advance()) {
  }
}

// A session steered to +40 degrees after 0.2 s and back to 0 after 0.4 s.
std::unique_ptr<view::Session> steered(const view::ViewInput& in) {
  auto s = std::make_unique<view::Session>(in);
  std::vector<std::pair<double, double>> plan = {{0.2, 40.0}, {0.4, 0.0}};
  std::size_t next = 0;
  while (s->advance()) {
    if (next < plan.size() && s->record(s->records() - 1).time >= plan[next].first)
      s->steer(plan[next++].second);
  }
  return s;
}

std::string read_text(const std::string& path) {
  std::ifstream in(path);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

}  // namespace

TEST(ViewSession, UnsteeredGivesTheBitsOfEvaluate) {
  for (TaskKind kind : {TaskKind::gait, TaskKind::directed}) {
    const view::ViewInput in = test::block_input(kind, 0.5);
    view::Session s(in);
    run_to_end(s);
    const auto task = tasks::make_task(in.config);
    const EvalResult direct =
        worker::evaluate(in.config, *task, in.robot.body, in.robot.controller, 0);
    ASSERT_TRUE(s.result().has_value());
    ASSERT_EQ(direct.status, EvalStatus::ok) << direct.message;
    EXPECT_EQ(s.result()->status, direct.status);
    EXPECT_EQ(std::bit_cast<std::uint64_t>(s.result()->fitness),
              std::bit_cast<std::uint64_t>(direct.fitness));
    EXPECT_EQ(s.result()->components[0].values, direct.components[0].values);
    EXPECT_EQ(s.records(), s.planned_records());
    EXPECT_EQ(s.records(), 31);  // 30 control frames at 60 Hz and the final state
    // The last record's components are the final ones; before, the task's formula so far.
    EXPECT_EQ(s.record(s.records() - 1).fitness, static_cast<float>(direct.fitness));
    EXPECT_FALSE(s.advance());
  }
}

// Issue 28: the viewer asks the task for its score so far, so every task shows its
// components while the robot moves (the rotate task showed nothing), and the score so far at the
// last frame is the result's.
TEST(ViewSession, EveryTaskShowsItsComponentsSoFar) {
  for (TaskKind kind : task_kinds()) {
    const view::ViewInput in = test::block_input(kind, 0.5);
    view::Session s(in);
    run_to_end(s);
    ASSERT_TRUE(s.result().has_value());
    ASSERT_EQ(s.result()->status, EvalStatus::ok) << to_string(kind);
    const auto names = s.component_names();
    ASSERT_FALSE(names.empty()) << to_string(kind);
    int moving = 0;
    for (int r = 1; r + 1 < s.records(); ++r) {
      const auto& c = s.record(r).components;
      ASSERT_EQ(c.size(), names.size()) << to_string(kind);
      bool any = false;
      for (float v : c) any = any || (v != 0.0f && std::isfinite(v));
      moving += any ? 1 : 0;
    }
    EXPECT_GT(moving, s.records() / 2) << to_string(kind) << ": components stay 0 while it moves";
    const auto& last = s.record(s.records() - 1);
    for (std::size_t i = 0; i < names.size(); ++i)
      EXPECT_EQ(last.components[i], static_cast<float>(s.result()->components[0].values[i]))
          << to_string(kind) << " " << names[i];
  }
}

TEST(ViewSession, TheSteeringLogReproducesASteeredSession) {
  const view::ViewInput in = test::block_input(TaskKind::directed, 0.6);
  const auto steered_session = steered(in);
  const view::Session& a = *steered_session;
  ASSERT_EQ(a.steering_log().size(), 2u);
  EXPECT_EQ(a.steering_log()[0].direction_deg, 40.0);
  view::Session b(in, a.steering_log());
  run_to_end(b);
  ASSERT_EQ(a.records(), b.records());
  for (int r = 0; r < a.records(); ++r) {
    ASSERT_EQ(a.record(r).positions, b.record(r).positions) << "record " << r;
    ASSERT_EQ(a.record(r).target_deg, b.record(r).target_deg) << "record " << r;
  }
  EXPECT_EQ(std::bit_cast<std::uint64_t>(a.result()->fitness),
            std::bit_cast<std::uint64_t>(b.result()->fitness));
  // Steering changed the walk: the sensor fed the controller another input.
  view::Session unsteered(in);
  run_to_end(unsteered);
  EXPECT_NE(unsteered.record(unsteered.records() - 1).positions,
            a.record(a.records() - 1).positions);
  EXPECT_EQ(a.record(15).target_deg, 40.0f);
}

TEST(ViewSession, OnlyALiveDirectedRobotSteers) {
  const view::ViewInput gait = test::block_input(TaskKind::gait, 0.1);
  view::Session s(gait);
  EXPECT_THROW(s.steer(10.0), std::logic_error);
  EXPECT_THROW(view::Session(gait, {{0, 10.0}}), std::invalid_argument);
  const view::ViewInput directed = test::block_input(TaskKind::directed, 0.1);
  view::Session d(directed);
  EXPECT_THROW(d.steer(200.0), std::invalid_argument);
  run_to_end(d);
  EXPECT_THROW(d.steer(10.0), std::logic_error);  // ended
}

TEST(ViewSession, SteeringLogRoundTripsAndBadLogsNameTheProblem) {
  const std::vector<view::SteerCommand> log = {{3, 40.0}, {9, -12.25}};
  EXPECT_EQ(view::parse_steering_log(view::steering_log_json(log, "x"), "log"), log);
  auto error = [](const std::string& text) {
    try {
      view::parse_steering_log(text, "s.json");
    } catch (const std::invalid_argument& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  EXPECT_NE(error("nope").find("s.json: not JSON"), std::string::npos);
  EXPECT_NE(error(R"({"format":"x","commands":[]})").find("format"), std::string::npos);
  EXPECT_NE(error(R"({"format":"softevo.steering/1","commands":[[5,1],[4,1]]})").find("ascending"),
            std::string::npos);
  EXPECT_NE(error(R"({"format":"softevo.steering/1","commands":[[1,400]]})").find("[-180, 180]"),
            std::string::npos);
  EXPECT_NE(error(R"({"format":"softevo.steering/1","commands":[["a",1]]})").find("commands[0]"),
            std::string::npos);
}

TEST(ViewSession, SavesATraceWithItsLogThatPlaysBack) {
  const test::TmpDir dir;
  const view::ViewInput in = test::block_input(TaskKind::directed, 0.6);
  const auto steered_session = steered(in);
  const view::Session& a = *steered_session;
  const std::string path = dir.file("steered.h5");
  a.save(path, Overwrite::refuse);
  EXPECT_THROW(a.save(path, Overwrite::refuse), OutputFileError);
  const io::Trace trace = io::read_trace(path);
  ASSERT_EQ(trace.frames, a.records());
  EXPECT_EQ(trace.status, "ok");
  EXPECT_EQ(std::bit_cast<std::uint64_t>(*trace.fitness),
            std::bit_cast<std::uint64_t>(a.result()->fitness));
  const std::size_t last = static_cast<std::size_t>(trace.frames - 1) * trace.voxels * 3;
  EXPECT_EQ(static_cast<float>(trace.positions[last]), a.record(a.records() - 1).positions[0]);
  EXPECT_EQ(view::parse_steering_log(read_text(view::steering_log_path(path)), "log"),
            a.steering_log());
  // The trace as an input: the same records, no simulation.
  const view::ViewInput replay = view::load_view_input(path, {});
  EXPECT_EQ(replay.kind, view::InputKind::trace);
  view::Session b(replay);
  EXPECT_FALSE(b.live());
  ASSERT_EQ(b.records(), a.records());
  const auto& pa = a.record(a.records() - 1).positions;
  const auto& pb = b.record(b.records() - 1).positions;
  ASSERT_EQ(pa.size(), pb.size());
  // Voxels exactly; chamber cells are placed with the trace's voxel size, the model's (float).
  const std::size_t voxel_values = 3 * in.body.voxel_cells.size();
  for (std::size_t i = 0; i < pa.size(); ++i) {
    if (i < voxel_values)
      ASSERT_EQ(pa[i], pb[i]) << "value " << i;
    else
      ASSERT_NEAR(pa[i], pb[i], 1e-7) << "value " << i;
  }
  EXPECT_EQ(b.record(5).valves, a.record(5).valves);
}

namespace {

// A trace of the test block sliding `metres` along +x over `poses` poses on a 10% slope (the
// ground rises from x = 0 on), for the ground grid's coverage.
view::ViewInput sliding_trace(double metres, int poses) {
  view::ViewInput in = test::block_input(TaskKind::gait, 0.1);
  in.kind = view::InputKind::trace;
  in.trace_motion.body = in.body;
  physics::Terrain& ground = in.trace_motion.terrain;
  ground.kind = physics::TerrainKind::slope;
  ground.voxel_size = in.body.voxel_size;
  ground.gradient = 0.1;
  for (int k = 0; k < poses; ++k) {
    scene::Pose pose = scene::rest_pose(in.body);
    for (Eigen::Vector3d& p : pose.position) p.x() += metres * k / (poses - 1);
    pose.time = 0.1 * k;
    in.trace_motion.poses.push_back(std::move(pose));
  }
  return in;
}

}  // namespace

// Issue 30: the ground a page draws covers the whole path (and 1 m around it), at the voxel
// spacing while a side fits 401 points, coarser beyond; a live robot near the edge of the grid
// its page has gets a new one.
TEST(ViewSession, TheGroundGridCoversThePathSoFar) {
  const view::ViewInput walk = sliding_trace(1.5, 31);
  const view::Session session(walk);
  ASSERT_EQ(session.records(), 31);
  const view::TerrainGrid grid = view::terrain_grid(session);
  EXPECT_EQ(grid.kind, "slope");
  EXPECT_EQ(grid.step, walk.body.voxel_size);
  EXPECT_LE(grid.nx, view::kTerrainGridMaxSide);
  ASSERT_EQ(grid.z.size(), static_cast<std::size_t>(grid.nx) * grid.ny);
  for (int r = 0; r < session.records(); ++r) {
    const auto [x, y] = view::record_centre(session.record(r));
    EXPECT_TRUE(grid.covers(x, y, view::kTerrainGridMargin - 1e-9)) << r;
  }
  // On the lattice of the step, each sample the simulation's ground half a voxel down.
  EXPECT_EQ(grid.x0, std::floor(grid.x0 / grid.step) * grid.step);
  const double half = 0.5 * walk.body.voxel_size;
  for (int i = 0; i < grid.nx; i += 17) {
    const double want =
        physics::terrain_height(walk.trace_motion.terrain, grid.x0 + i * grid.step, grid.y0) - half;
    EXPECT_EQ(grid.z[static_cast<std::size_t>(i)], static_cast<float>(want)) << i;
  }
  // The grid of the start alone does not cover the end of the walk: the update does.
  view::ViewInput first = walk;
  first.trace_motion.poses.resize(1);
  const view::Session at_start(first);
  const view::TerrainGrid start_grid = view::terrain_grid(at_start);
  EXPECT_LT(start_grid.nx, grid.nx);
  EXPECT_FALSE(view::terrain_update(session, start_grid, 0).has_value());
  const auto update = view::terrain_update(session, start_grid, 30);
  ASSERT_TRUE(update.has_value());
  EXPECT_EQ(update->nx, grid.nx);
  EXPECT_EQ(update->x0, grid.x0);
  EXPECT_FALSE(view::terrain_update(session, grid, 30).has_value());
  // A walk longer than 401 voxels: the step grows and a side stays within 401 points.
  const view::ViewInput far = sliding_trace(6.0, 7);
  const view::Session far_session(far);
  const view::TerrainGrid coarse = view::terrain_grid(far_session);
  EXPECT_GT(coarse.step, far.body.voxel_size);
  EXPECT_LE(coarse.nx, view::kTerrainGridMaxSide);
  EXPECT_LE(coarse.ny, view::kTerrainGridMaxSide);
  for (int r : {0, 6}) {
    const auto [x, y] = view::record_centre(far_session.record(r));
    EXPECT_TRUE(coarse.covers(x, y, view::kTerrainGridMargin - 1e-9)) << r;
  }
  // Flat ground: no grid and no update.
  view::ViewInput flat = walk;
  flat.trace_motion.terrain = physics::Terrain{};
  const view::Session flat_session(flat);
  EXPECT_EQ(view::terrain_grid(flat_session).nx, 0);
  EXPECT_FALSE(view::terrain_update(flat_session, start_grid, 30).has_value());
}
