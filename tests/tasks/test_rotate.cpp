// The rotate task (tasks/rotate.hpp, docs/model.md §7.6) against analytic cases: a body
// turned by a known angle about z gives that angle (several full turns included), a pure
// translation gives only the travel penalty.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <vector>

#include "physics/model.hpp"
#include "physics/state.hpp"
#include "tasks/rotate.hpp"

using namespace softevo;
using namespace softevo::tasks;

namespace {

constexpr double kPi = std::numbers::pi;

// `points` turned by `angle` [rad] about the vertical line through `centre`, then moved by
// `shift` [m].
std::vector<Eigen::Vector3d> turned(const std::vector<Eigen::Vector3d>& points,
                                    const Eigen::Vector3d& centre, double angle,
                                    const Eigen::Vector3d& shift = Eigen::Vector3d::Zero()) {
  std::vector<Eigen::Vector3d> out;
  const double c = std::cos(angle), s = std::sin(angle);
  for (const auto& p : points) {
    const Eigen::Vector3d d = p - centre;
    out.emplace_back(centre.x() + c * d.x() - s * d.y() + shift.x(),
                     centre.y() + s * d.x() + c * d.y() + shift.y(), p.z() + shift.z());
  }
  return out;
}

// An L-shaped set of points (no symmetry that would hide a wrong sign).
std::vector<Eigen::Vector3d> l_shape() {
  return {{0, 0, 0}, {0.01, 0, 0}, {0.02, 0, 0}, {0.03, 0, 0.01}, {0, 0.01, 0}, {0, 0.02, 0}};
}

Eigen::Vector3d centre_of(const std::vector<Eigen::Vector3d>& points) {
  Eigen::Vector3d c = Eigen::Vector3d::Zero();
  for (const auto& p : points) c += p;
  return c / static_cast<double>(points.size());
}

// A 4 x 2 x 1 block of one material with a one-cell chamber: body length 4 voxels.
BodyPlan block() {
  BodyPlan plan;
  plan.lattice = {4, 2, 1};
  plan.voxel_size = 0.01;
  for (int k = 1; k <= 10; ++k) plan.materials.push_back({1.0e4 * k, 1000.0});
  plan.cells.assign(4 * 2 * 1, 5);
  plan.cells[plan.cell_index(1, 0, 0)] = 11;
  return plan;
}

}  // namespace

TEST(Rotate, HeadingChangeOfAKnownTurn) {
  const auto rest = l_shape();
  const Eigen::Vector3d centre = centre_of(rest);
  for (double total : {0.7, -1.2, 2.0 * kPi, -5.0 * kPi, 2.5 * 2.0 * kPi}) {
    HeadingTracker tracker(rest);
    const int frames = 240;  // well below half a turn per frame
    for (int f = 0; f <= frames; ++f) tracker.observe(turned(rest, centre, total * f / frames));
    EXPECT_NEAR(tracker.heading_change(), total, 1e-9) << "total " << total;
  }
}

TEST(Rotate, TranslationAndABodyFarFromTheOriginDoNotTurn) {
  const auto rest = l_shape();
  HeadingTracker tracker(rest);
  for (int f = 0; f <= 60; ++f)
    tracker.observe(turned(rest, centre_of(rest), 0.0, Eigen::Vector3d(0.5 * f, -0.2 * f, 0.01)));
  EXPECT_NEAR(tracker.heading_change(), 0.0, 1e-12);
  // A turn about a point far away is still the body's own turn (translation does not count).
  HeadingTracker far(rest);
  for (int f = 0; f <= 60; ++f)
    far.observe(turned(rest, Eigen::Vector3d(3.0, -2.0, 0.0), 0.9 * f / 60));
  EXPECT_NEAR(far.heading_change(), 0.9, 1e-9);
}

TEST(Rotate, ScoreIsTurnMinusTravelPenalty) {
  // 1.5 rad turned, 6 cm travelled, body 4 cm long, 0.5 rad per body length.
  const RotateScore s = rotate_score(-1.5, 0.06, 0.04, 0.5);
  EXPECT_DOUBLE_EQ(s.heading_change, -1.5);
  EXPECT_DOUBLE_EQ(s.travel, 1.5);
  EXPECT_DOUBLE_EQ(s.travel_penalty, 0.75);
  EXPECT_DOUBLE_EQ(s.fitness, 1.5 - 0.75);
  // Pure translation: only the penalty.
  EXPECT_DOUBLE_EQ(rotate_score(0.0, 0.08, 0.04, 1.0).fitness, -2.0);
}

TEST(Rotate, TaskScoresTheSimulatedBody) {
  Config config;
  config.task.kind = TaskKind::rotate;
  config.task.rotate_travel_penalty = 0.5;  // [rad / body length]
  const auto task = make_rotate_task(config);
  EXPECT_EQ(task->units(), 1);
  EXPECT_EQ(task->controller_inputs(), 0);
  ASSERT_EQ(task->component_names().size(), 3u);
  EXPECT_EQ(task->component_names()[0].name, "heading_change");

  const physics::Model model = physics::build_model(block(), config.physics);
  physics::State state = physics::initial_state(model);
  const std::vector<Eigen::Vector3d> rest(state.pos.begin(), state.pos.end());
  const Eigen::Vector3d centre = centre_of(rest);
  const auto score = task->start_unit(0, model);
  const double total = 3.0 * kPi;                // one and a half turns
  const Eigen::Vector3d shift(0.03, 0.04, 0.0);  // 5 cm = 1.25 body lengths
  const int frames = 120;
  auto place = [&](int f) {
    const auto pos = turned(rest, centre, total * f / frames, shift * f / frames);
    for (std::size_t v = 0; v < pos.size(); ++v) state.pos[v] = pos[v];
  };
  for (int f = 0; f < frames; ++f) {
    place(f);
    score->observe(f, model, state);
  }
  place(frames);
  const UnitFitness u = score->finish(model, state);
  ASSERT_EQ(u.values.size(), 3u);
  EXPECT_NEAR(u.values[0], total, 1e-9);
  // The travel is the centroid's: the mean of the voxel displacements (to 1e-9 m: the model's
  // voxel size is the single-precision one).
  EXPECT_NEAR(u.values[1], 0.05 / 0.04, 1e-6);
  EXPECT_NEAR(u.values[2], 0.5 * 0.05 / 0.04, 1e-6);
  EXPECT_NEAR(u.fitness, total - 0.5 * 0.05 / 0.04, 1e-6);
}
