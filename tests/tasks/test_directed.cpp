// The directed task (tasks/directed.hpp, docs/model.md §7.2-§7.4): components with analytic
// paths, the direction sensor, one unit per direction and their names.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <vector>

#include "tasks/directed.hpp"

using namespace softevo;
using namespace softevo::tasks;

namespace {
std::vector<Vec3d> straight(double dx, double dy, int n = 11) {
  std::vector<Vec3d> w;
  for (int i = 0; i < n; ++i) w.emplace_back(dx * i, dy * i, 0.0);
  return w;
}
}  // namespace

TEST(Directed, StraightPathAlongTheTarget) {
  // 10 segments of 5 cm along +x, target 0 deg: D = L = 50, delta = 0, P = 0, F = D^2/(L+eps).
  const auto c = directed_score(straight(5.0, 0.0), 0.0, 0.1);
  EXPECT_DOUBLE_EQ(c.distance, 50.0);
  EXPECT_DOUBLE_EQ(c.path_length, 50.0);
  EXPECT_NEAR(c.angle_error, 0.0, 1e-12);
  EXPECT_NEAR(c.perpendicular_penalty, 0.0, 1e-12);
  EXPECT_NEAR(c.fitness, 50.0 * 50.0 / (50.0 + 1e-5), 1e-9);
}

TEST(Directed, PathAtAnAngleToTheTarget) {
  // Straight line at 20 deg while the target is 0 deg: D = 50 cos20, delta = 20 deg,
  // P = 0.1 * sum_n |w_n| sin20, F = |D|/L (D/(delta+1) - P).
  const double a = 20.0 * std::numbers::pi / 180.0;
  const auto c = directed_score(straight(5.0 * std::cos(a), 5.0 * std::sin(a)), 0.0, 0.1);
  const double d = 50.0 * std::cos(a), perp = 0.1 * 5.0 * std::sin(a) * 55.0;  // sum 0..10 = 55
  EXPECT_NEAR(c.distance, d, 1e-9);
  EXPECT_NEAR(c.path_length, 50.0, 1e-9);
  EXPECT_NEAR(c.angle_error, a, 1e-9);
  EXPECT_NEAR(c.perpendicular_penalty, perp, 1e-9);
  EXPECT_NEAR(c.fitness, d / (50.0 + 1e-5) * (d / (a + 1.0) - perp), 1e-9);
  // The same path scores the same towards +20 deg as a straight path along 0 deg does at 0.
  const auto on = directed_score(straight(5.0 * std::cos(a), 5.0 * std::sin(a)), 20.0, 0.1);
  EXPECT_NEAR(on.fitness, 50.0 * 50.0 / (50.0 + 1e-5), 1e-6);
}

TEST(Directed, BackwardsIsNegativeAndStandingStillIsZero) {
  const auto back = directed_score(straight(-3.0, 0.0), 0.0, 0.1);
  EXPECT_LT(back.distance, 0.0);
  EXPECT_NEAR(back.angle_error, std::numbers::pi, 1e-9);
  EXPECT_LT(back.fitness, 0.0);
  const auto still = directed_score(straight(0.0, 0.0), 0.0, 0.1);
  EXPECT_DOUBLE_EQ(still.fitness, 0.0);
  EXPECT_NEAR(still.angle_error, std::numbers::pi / 2, 1e-12);  // normalise(0) = 0 -> acos(0)
}

TEST(Directed, DirectionSensorPointsAtTheTarget) {
  const double s = 0.01;
  // At the start, heading 0: target straight ahead -> 0; at +90 deg -> +pi/2 (left).
  EXPECT_NEAR(direction_sensor(Vec3d::Zero(), 0.0, 0.0, s), 0.0, 1e-7);
  EXPECT_NEAR(direction_sensor(Vec3d::Zero(), 0.0, 40.0, s), 40.0 * std::numbers::pi / 180, 1e-6);
  EXPECT_NEAR(direction_sensor(Vec3d::Zero(), 0.0, -20.0, s), -20.0 * std::numbers::pi / 180, 1e-6);
  // Robot 0.2 m to the right of the 0-deg line: target point (0.2, 0) seen from (0, -0.2):
  // 45 deg to the left; turning the robot by +45 deg makes it straight ahead.
  EXPECT_NEAR(direction_sensor(Vec3d(0.0, -0.2, 0.0), 0.0, 0.0, s), std::numbers::pi / 4, 1e-6);
  EXPECT_NEAR(direction_sensor(Vec3d(0.0, -0.2, 0.0), std::numbers::pi / 4, 0.0, s), 0.0, 1e-6);
}

TEST(Directed, OneUnitPerDirectionAndOneControllerInput) {
  Config c;
  c.task.kind = TaskKind::directed;
  c.task.directions = {0.0, 90.0, -45.0};
  const auto task = make_directed_task(c);
  EXPECT_EQ(task->kind(), TaskKind::directed);
  EXPECT_EQ(task->units(), 3);
  EXPECT_EQ(task->controller_inputs(), 1);
  const auto names = task->component_names();
  ASSERT_EQ(names.size(), 5u);
  EXPECT_EQ(names[0].name, "direction_deg");
  EXPECT_EQ(names[1].name, "distance");
  EXPECT_EQ(names[1].unit, "cm");
  EXPECT_EQ(names[4].name, "perpendicular_penalty");
}
