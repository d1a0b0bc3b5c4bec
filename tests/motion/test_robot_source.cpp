// Where a motion comes from (motion/robot_source.hpp), here the bound on what a re-simulation
// keeps: only the poses the output shows (the first, the last and the nearest to each shown
// time, the same pose render::pose_at picks from all of them), and a clear refusal, before
// anything is simulated, of a motion whose kept poses would need more than kMaxMotionBytes; and
// the ground of a trace: the terrain_* attributes of a rough-terrain evaluation's trace rebuild
// the very ground the evaluation ran on.
#include "motion/robot_source.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "common/config.hpp"
#include "common/robot.hpp"
#include "io/trace.hpp"
#include "motion/trace_recorder.hpp"
#include "physics/terrain.hpp"
#include "render/compose.hpp"
#include "tasks/task.hpp"
#include "worker/evaluate.hpp"
#include "worker/simulation.hpp"

namespace softevo::motion {
namespace {

namespace fs = std::filesystem;

// A 3x1x3 open-loop robot of 8 voxels around one chamber cell; `directed`: with the direction
// input (a third input of the hidden layer).
std::string write_robot(const fs::path& dir, bool directed = false) {
  const auto numbers = [](int n, const char* value) {
    std::string s = "[";
    for (int i = 0; i < n; ++i) s += (i > 0 ? ", " : "") + std::string(value);
    return s + "]";
  };
  const std::string path = (dir / (directed ? "directed.json" : "robot.json")).string();
  std::ofstream(path) << "{\"format\": \"softevo.robot/1\", \"name\": \"r\", \"voxel_size\": 0.01,"
                      << " \"lattice\": [3, 1, 3], \"cells\": [10, 10, 10, 10, 11, 10, 10, 10, 10],"
                      << " \"controller\": {\"kind\": \"elman\", \"control\": \"open\","
                      << " \"directed\": " << (directed ? "true" : "false")
                      << ", \"hidden\": 4, \"outputs\": 20, \"frequency\": 2.0,"
                      << " \"weights_hidden\": " << numbers(directed ? 12 : 8, "1.5")
                      << ", \"bias_hidden\": " << numbers(4, "0.1")
                      << ", \"weights_out\": " << numbers(80, "2.0")
                      << ", \"bias_out\": " << numbers(20, "0.0")
                      << ", \"weights_recurrent\": " << numbers(16, "0.0")
                      << ", \"weights_recurrent_self\": " << numbers(4, "0.0")
                      << ", \"weights_context\": " << numbers(4, "0.0")
                      << ", \"bias_context\": " << numbers(4, "0.0") << "}}";
  return path;
}

class RobotSource : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("softevo-robot-source-" + std::to_string(::getpid()));
    fs::create_directories(dir_);
    robot_ = write_robot(dir_);
  }
  void TearDown() override {
    std::error_code ec;
    fs::remove_all(dir_, ec);
  }
  MotionRequest request(double seconds) const {
    MotionRequest r;
    r.needs_motion = true;
    r.seconds = seconds;
    return r;
  }
  fs::path dir_;
  std::string robot_;
};

TEST_F(RobotSource, OnlyTheShownPosesAreKeptAndTheyAreThePosesShownFromAll) {
  const std::vector<double> shown = {0.0, 0.51, 1.25, 1.5 + 1.0 / 120.0, 7.0};
  MotionRequest some = request(2.0);
  some.shown_times = [&shown](double) { return shown; };
  const Motion all = load_motion(robot_, request(2.0));
  const Motion kept = load_motion(robot_, some);
  EXPECT_EQ(all.poses.size(), 121u);  // 2 s at 60 Hz and the start
  EXPECT_LE(kept.poses.size(), shown.size() + 2);
  EXPECT_EQ(kept.poses.front().time, all.poses.front().time);
  EXPECT_EQ(kept.poses.back().time, all.poses.back().time);
  for (const double t : shown) {
    const scene::Pose& a = all.poses[render::pose_at(all.poses, t)];
    const scene::Pose& k = kept.poses[render::pose_at(kept.poses, t)];
    EXPECT_EQ(k.time, a.time) << "at t = " << t;
    ASSERT_EQ(k.position.size(), a.position.size());
    for (std::size_t v = 0; v < a.position.size(); ++v) EXPECT_EQ(k.position[v], a.position[v]);
  }
  EXPECT_EQ(kept.summary, all.summary);
}

TEST_F(RobotSource, AStillOfALongReSimulationKeepsAFewPoses) {
  MotionRequest still = request(120.0);  // 7,200 control frames
  still.shown_times = [](double) { return std::vector<double>{60.0}; };
  const Motion m = load_motion(robot_, still);
  EXPECT_LE(m.poses.size(), 3u);
  EXPECT_NEAR(m.poses[render::pose_at(m.poses, 60.0)].time, 60.0, 1.0 / 60.0);  // a frame away
}

TEST_F(RobotSource, AStillOfADirectedRobotHasItsTargetDirection) {
  // The start pose alone (nothing simulated) still carries the direction a directed robot is
  // shown walking towards, so a still draws its target line; a gait robot has none.
  const std::string directed = write_robot(dir_, true);
  MotionRequest still;
  still.direction_deg = 30.0;
  const Motion towards = load_motion(directed, still);
  ASSERT_EQ(towards.poses.size(), 1u);
  ASSERT_TRUE(towards.direction_deg.has_value());
  EXPECT_EQ(*towards.direction_deg, 30.0);
  // Without a request: the task's first direction, as a simulated motion has it.
  const Motion first = load_motion(directed, MotionRequest{});
  MotionRequest simulated = request(0.1);
  const Motion moving = load_motion(directed, simulated);
  ASSERT_TRUE(first.direction_deg.has_value());
  EXPECT_EQ(first.direction_deg, moving.direction_deg);
  EXPECT_FALSE(load_motion(robot_, still).direction_deg.has_value());
}

TEST_F(RobotSource, AMotionBeyondTheMemoryLimitIsRefusedBeforeItIsSimulated) {
  // A video of 3600 s at 1000 frames per second: 3.6 million poses of 8 voxels = 1.6 GiB fits;
  // of a 1000-voxel body it would not. Here: more shown times than the limit allows for 8 voxels.
  const double limit_poses = kMaxMotionBytes / (8.0 * 56.0);
  MotionRequest video = request(3600.0);
  video.shown_times = [limit_poses](double) {
    return std::vector<double>(static_cast<std::size_t>(limit_poses) + 10, 1.0);
  };
  try {
    (void)load_motion(robot_, video);
    FAIL() << "not refused";
  } catch (const std::invalid_argument& e) {
    const std::string message = e.what();
    EXPECT_NE(message.find("more than the limit of 4 GiB"), std::string::npos) << message;
    EXPECT_NE(message.find("--fps"), std::string::npos) << message;
  }
}

// Each kind of ground: a trace of a short evaluation on it, read back through load_motion, gives
// the ground that the evaluation built (same heights everywhere, same parameters and seed).
TEST_F(RobotSource, ATracesTerrainAttributesRebuildTheEvaluationsGround) {
  const RobotFile robot = read_robot_file(robot_);
  const auto rough = [](const char* heightfield) {
    Config c;
    c.task.eval_seconds = 0.2;
    c.run.eval_timeout_seconds = 0.0;
    c.terrain.kind = heightfield ? GroundKind::heightfield : GroundKind::rows;
    c.terrain.seed = 11;
    if (!heightfield) return c;
    c.terrain.heightfield = parse_choice<HeightfieldKind>(heightfield, "heightfield");
    const std::string h = heightfield;
    std::vector<std::string> keys;  // the kind's own keys, checked as a config file's
    if (h == "bumps") keys = {"terrain.amplitude=0.01", "terrain.correlation_length=0.04"};
    if (h == "steps") keys = {"terrain.step_height=0.004", "terrain.step_spacing=0.07"};
    if (h == "slope") keys = {"terrain.slope_angle=8.0", "terrain.slope_direction=30.0"};
    return apply_overrides(c, keys);
  };
  for (const Config& config : {rough("bumps"), rough("steps"), rough("slope"), rough(nullptr)}) {
    const physics::Terrain built =
        physics::make_terrain(worker::terrain_params(config, {}, 0), robot.body.lattice,
                              static_cast<double>(static_cast<float>(robot.body.voxel_size)));
    const std::string kind = softevo::to_string(built.kind);
    ASSERT_NE(kind, "flat");
    const auto task = tasks::make_task(config);
    TraceRecorder recorder;
    worker::EvaluateOptions options;
    recorder.attach(options);
    const EvalResult result =
        worker::evaluate(config, *task, robot.body, robot.controller, 0, options);
    ASSERT_EQ(result.status, EvalStatus::ok) << kind << ": " << result.message;
    const std::string path = (dir_ / (kind + ".trace.h5")).string();
    recorder.write(path, robot, result, config.task.control_rate, std::nullopt, Overwrite::replace);

    const io::Trace trace = io::read_trace(path);
    ASSERT_TRUE(trace.terrain.has_value()) << kind;
    EXPECT_EQ(trace.terrain->kind, kind);
    const Motion motion = load_motion(path, MotionRequest{});
    const physics::Terrain& back = motion.terrain;
    EXPECT_EQ(back.kind, built.kind) << kind;
    EXPECT_EQ(back.params.seed, built.params.seed) << kind;
    EXPECT_TRUE(back.params.shape == built.params.shape) << kind;
    // The ground itself, on a 1 cm grid over 1 m x 1 m around the robot (rows included).
    int differing = 0;
    for (int i = -50; i <= 50; ++i)
      for (int j = -50; j <= 50; ++j) {
        const double x = 0.01 * i, y = 0.01 * j;
        if (physics::terrain_height(back, x, y) != physics::terrain_height(built, x, y))
          ++differing;
      }
    EXPECT_EQ(differing, 0) << kind << ": heights differ at " << differing << " of 10201 points";
  }
}

}  // namespace
}  // namespace softevo::motion
