// The rotate task (§7.6). See rotate.hpp.
#include "tasks/rotate.hpp"

#include <algorithm>
#include <cmath>

#include "physics/observables.hpp"
#include "physics/reproducible_math.hpp"

namespace softevo::tasks {
namespace {

using Vec2 = Eigen::Vector2d;

Vec2 mean_xy(std::span<const Eigen::Vector3d> points) {
  double x = 0.0, y = 0.0;  // summed in point order: the same bits on every build
  for (const auto& p : points) {
    x += p.x();
    y += p.y();
  }
  const auto n = static_cast<double>(std::max<std::size_t>(1, points.size()));
  return {x / n, y / n};
}

// Positions [m] of the voxels the physics moves (fixed voxels only occur in validation scenes).
std::vector<Eigen::Vector3d> free_voxels(const physics::Model& model,
                                         std::span<const physics::Vec3> positions) {
  std::vector<Eigen::Vector3d> out;
  out.reserve(positions.size());
  for (int v = 0; v < model.voxel_count; ++v)
    if (!model.voxel_fixed[v]) out.push_back(positions[v]);
  return out;
}

std::vector<Eigen::Vector3d> rest_shape(const physics::Model& model) {
  std::vector<Eigen::Vector3d> out;
  const double s = model.voxel_size;
  for (int v = 0; v < model.voxel_count; ++v) {
    if (model.voxel_fixed[v]) continue;
    const auto& c = model.voxel_cell[v];
    out.emplace_back(s * c[0], s * c[1], s * c[2]);
  }
  return out;
}

// The larger horizontal extent of the rest shape [m] (a voxel counts with its full edge).
double body_length(const physics::Model& model) {
  int lo[2] = {0, 0}, hi[2] = {-1, -1};
  bool first = true;
  for (int v = 0; v < model.voxel_count; ++v) {
    if (model.voxel_fixed[v]) continue;
    for (int a = 0; a < 2; ++a) {
      const int c = model.voxel_cell[v][a];
      lo[a] = first ? c : std::min(lo[a], c);
      hi[a] = first ? c : std::max(hi[a], c);
    }
    first = false;
  }
  return model.voxel_size * static_cast<double>(std::max(hi[0] - lo[0], hi[1] - lo[1]) + 1);
}

class RotateScoreKeeper : public UnitScore {
 public:
  RotateScoreKeeper(const physics::Model& model, double travel_penalty_weight)
      : tracker_(rest_shape(model)),
        body_length_(body_length(model)),
        travel_penalty_weight_(travel_penalty_weight) {}

  void observe(int, const physics::Model& model, const physics::State& state) override {
    tracker_.observe(free_voxels(model, state.pos));
  }

  UnitFitness finish(const physics::Model& model, const physics::State& state) override {
    tracker_.observe(free_voxels(model, state.pos));
    return score(tracker_, model, state);
  }

  UnitFitness so_far(const physics::Model& model, const physics::State& state) const override {
    HeadingTracker tracker = tracker_;  // the final observation, on a copy
    tracker.observe(free_voxels(model, state.pos));
    return score(tracker, model, state);
  }

 private:
  UnitFitness score(const HeadingTracker& tracker, const physics::Model& model,
                    const physics::State& state) const {
    const Eigen::Vector3d c = physics::centroid_displacement(model, state);
    const double travel = std::sqrt(c.x() * c.x() + c.y() * c.y());
    const RotateScore s =
        rotate_score(tracker.heading_change(), travel, body_length_, travel_penalty_weight_);
    UnitFitness f;
    f.fitness = s.fitness;
    f.values = {s.heading_change, s.travel, s.travel_penalty};
    return f;
  }

  HeadingTracker tracker_;
  double body_length_;
  double travel_penalty_weight_;
};

class RotateTask : public Task {
 public:
  explicit RotateTask(const Config& config) : config_(config) {}
  TaskKind kind() const override { return TaskKind::rotate; }
  std::vector<std::string> controller_input_names() const override { return {}; }
  int units() const override { return 1; }
  // |heading change| - travel penalty (§7.6)
  std::string fitness_unit() const override { return "rad"; }
  std::vector<ComponentName> component_names() const override {
    return {{"heading_change", "rad"}, {"travel", "body lengths"}, {"travel_penalty", "rad"}};
  }
  std::unique_ptr<UnitScore> start_unit(int, const physics::Model& model) const override {
    return std::make_unique<RotateScoreKeeper>(model, config_.task.rotate_travel_penalty);
  }

 private:
  const Config& config_;
};

}  // namespace

HeadingTracker::HeadingTracker(std::span<const Eigen::Vector3d> rest) {
  const Vec2 centre = mean_xy(rest);
  rest_offsets_.reserve(rest.size());
  for (const auto& p : rest) rest_offsets_.emplace_back(p.x() - centre.x(), p.y() - centre.y());
}

void HeadingTracker::observe(std::span<const Eigen::Vector3d> positions) {
  const Vec2 centre = mean_xy(positions);
  // The rotation angle phi minimising sum |R(phi) r0 - r|^2 has (cos, sin) ~ (sum r0.r,
  // sum r0 x r).
  double c = 0.0, s = 0.0;
  const std::size_t n = std::min(positions.size(), rest_offsets_.size());
  for (std::size_t i = 0; i < n; ++i) {
    const Vec2& r0 = rest_offsets_[i];
    const double rx = positions[i].x() - centre.x(), ry = positions[i].y() - centre.y();
    c += r0.x() * rx + r0.y() * ry;
    s += r0.x() * ry - r0.y() * rx;
  }
  const double norm = std::sqrt(c * c + s * s);
  if (!(norm > 0.0)) return;  // no horizontal extent: no heading to follow
  const Vec2 heading(c / norm, s / norm);
  if (has_heading_) {
    const double cos_turn = heading_.x() * heading.x() + heading_.y() * heading.y();
    const double sin_turn = heading_.x() * heading.y() - heading_.y() * heading.x();
    const double turn = physics::rmath::acos(std::clamp(cos_turn, -1.0, 1.0));
    heading_change_ += sin_turn < 0.0 ? -turn : turn;
  }
  heading_ = heading;
  has_heading_ = true;
}

RotateScore rotate_score(double heading_change, double travel, double body_length,
                         double travel_penalty_weight) {
  RotateScore r;
  r.heading_change = heading_change;
  r.travel = travel / body_length;
  r.travel_penalty = travel_penalty_weight * r.travel;
  r.fitness = std::fabs(heading_change) - r.travel_penalty;
  return r;
}

std::unique_ptr<Task> make_rotate_task(const Config& config) {
  return std::make_unique<RotateTask>(config);
}

}  // namespace softevo::tasks
