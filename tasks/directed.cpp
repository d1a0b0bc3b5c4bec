// The directed task (§7.2-§7.4). See directed.hpp.
#include "tasks/directed.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <vector>

#include "physics/observables.hpp"

namespace softevo::tasks {
namespace {

constexpr double kCmPerM = 100.0;
constexpr double kEpsilon = 1e-5;            // §7.2 epsilon in |D|/(L + eps)
constexpr double kTargetAheadVoxels = 20.0;  // §7.3 "2 body lengths" = 20 voxel lengths

// Explicit left-to-right products (Eigen may reorder a vectorised reduction).
double dot(const Vec3d& a, const Vec3d& b) {
  return a.x() * b.x() + a.y() * b.y() + a.z() * b.z();
}
double length(const Vec3d& v) {
  return std::sqrt(dot(v, v));
}
Vec3d cross(const Vec3d& a, const Vec3d& b) {
  return {a.y() * b.z() - a.z() * b.y(), a.z() * b.x() - a.x() * b.z(),
          a.x() * b.y() - a.y() * b.x()};
}

// §2.11 Vec normalise: a zero vector is returned unchanged.
Vec3d normalized(const Vec3d& v) {
  const double n = length(v);
  return n > 0.0 ? Vec3d(v.x() / n, v.y() / n, v.z() / n) : v;
}

double clamped_acos(double x) {
  return std::acos(std::clamp(x, -1.0, 1.0));
}

// One direction: the direction sensor every frame, a waypoint at the start of every
// `waypoint_every`-th frame (once per simulated second, §7.2) and after the last frame.
class DirectedScoreKeeper : public UnitScore {
 public:
  DirectedScoreKeeper(double direction_deg, int waypoint_every, double path_penalty_weight,
                      int expected_waypoints)
      : direction_deg_(direction_deg),
        waypoint_every_(waypoint_every),
        path_penalty_weight_(path_penalty_weight) {
    waypoints_cm_.reserve(static_cast<std::size_t>(expected_waypoints));
  }

  void controller_inputs(const physics::Model& model, const physics::State& state,
                         std::span<float> inputs) override {
    const Vec3d c = physics::centroid_displacement(model, state);
    const double heading = physics::mean_rotation_vector(model, state).z();
    inputs[0] = direction_sensor(c, heading, direction_deg_, model.voxel_size);
  }

  void observe(int frame, const physics::Model& model, const physics::State& state) override {
    if (frame % waypoint_every_ == 0) record_waypoint(model, state);
  }

  UnitFitness finish(const physics::Model& model, const physics::State& state) override {
    waypoints_cm_.push_back(waypoint_cm(model, state));
    return score(waypoints_cm_);
  }

  UnitFitness so_far(const physics::Model& model, const physics::State& state) const override {
    std::vector<Vec3d> waypoints = waypoints_cm_;  // the final waypoint, on a copy
    waypoints.push_back(waypoint_cm(model, state));
    return score(waypoints);
  }

  // A steered unit (the viewer's dial, a Python agent) senses and is scored towards the new
  // target; its waypoints so far stay.
  void steer(double direction_deg) override { direction_deg_ = direction_deg; }

 private:
  static Vec3d waypoint_cm(const physics::Model& model, const physics::State& state) {
    const Vec3d c = physics::centroid_displacement(model, state);
    return {c.x() * kCmPerM, c.y() * kCmPerM, 0.0};  // cm, z set to 0
  }
  void record_waypoint(const physics::Model& model, const physics::State& state) {
    waypoints_cm_.push_back(waypoint_cm(model, state));
  }
  UnitFitness score(std::span<const Vec3d> waypoints) const {
    const DirectedScore s = directed_score(waypoints, direction_deg_, path_penalty_weight_);
    UnitFitness f;
    f.fitness = s.fitness;
    f.values = {direction_deg_, s.distance, s.path_length, s.angle_error, s.perpendicular_penalty};
    return f;
  }

  double direction_deg_;
  int waypoint_every_;
  double path_penalty_weight_;
  std::vector<Vec3d> waypoints_cm_;
};

class DirectedTask : public Task {
 public:
  explicit DirectedTask(const Config& config) : config_(config) {}
  TaskKind kind() const override { return TaskKind::directed; }
  std::vector<std::string> controller_input_names() const override {
    return {"direction_sensor"};  // §7.3
  }
  bool steerable() const override { return true; }
  int units() const override { return static_cast<int>(config_.task.directions.size()); }
  // |D| / L x (D / (delta + 1) - P): a distance (§7.2)
  std::string fitness_unit() const override { return "cm"; }
  std::vector<ComponentName> component_names() const override {
    return {{"direction_deg", "deg"},
            {"distance", "cm"},
            {"path_length", "cm"},
            {"angle_error", "rad"},
            {"perpendicular_penalty", "cm"}};
  }
  std::unique_ptr<UnitScore> start_unit(int unit, const physics::Model&) const override {
    const TaskConfig& t = config_.task;
    const int waypoint_every = std::max(1, static_cast<int>(std::lround(t.control_rate)));
    const int frames = static_cast<int>(std::lround(t.control_rate * t.eval_seconds));
    return std::make_unique<DirectedScoreKeeper>(t.directions.at(static_cast<std::size_t>(unit)),
                                                 waypoint_every, t.path_penalty_weight,
                                                 frames / waypoint_every + 2);
  }

 private:
  const Config& config_;
};

}  // namespace

Vec3d target_direction(double direction_deg) {
  const double beta = direction_deg * std::numbers::pi / 180.0;
  return {std::cos(beta), std::sin(beta), 0.0};
}

float direction_sensor(const Vec3d& centroid, double heading, double direction_deg,
                       double voxel_size) {
  const Vec3d t = target_direction(direction_deg);
  // T = (t.c + 20 s) t: projection of c on the target line, moved 20 voxel lengths further.
  const Vec3d target = (dot(t, centroid) + kTargetAheadVoxels * voxel_size) * t;
  Vec3d u = target - centroid;
  u.z() = 0.0;
  u = normalized(u);
  const Vec3d r(std::cos(heading), std::sin(heading), 0.0);  // x axis turned by the heading
  const double sign = normalized(cross(r, u)).z();           // +1 left, -1 right, 0 parallel
  return static_cast<float>(clamped_acos(dot(normalized(r), u)) * sign);
}

DirectedScore directed_score(std::span<const Vec3d> waypoints_cm, double direction_deg,
                             double path_penalty_weight) {
  DirectedScore c;
  if (waypoints_cm.empty()) return c;
  const Vec3d t = target_direction(direction_deg);
  auto flat = [](const Vec3d& w) { return Vec3d(w.x(), w.y(), 0.0); };
  const Vec3d first = flat(waypoints_cm.front()), last = flat(waypoints_cm.back());
  c.distance = dot(t, last);  // D: signed distance along the target line (line through w_0 = 0)
  double path = 0.0;          // L: path length through the waypoints
  for (std::size_t n = 0; n + 1 < waypoints_cm.size(); ++n)
    path += length(flat(waypoints_cm[n + 1]) - flat(waypoints_cm[n]));
  c.path_length = path;
  c.angle_error = clamped_acos(dot(normalized(last - first), t));  // delta in [0, pi]
  double perpendicular = 0.0;  // sum of the waypoints' distances to the target line
  for (const Vec3d& w3 : waypoints_cm) {
    const Vec3d w = flat(w3);
    perpendicular += length(w - dot(t, w) * t);
  }
  c.perpendicular_penalty = path_penalty_weight * perpendicular;  // P (x omega)
  // F = |D| / (L + eps) * (D / (delta + 1) - P)   (the code's delta + 1, §7.2)
  c.fitness = std::fabs(c.distance) / (c.path_length + kEpsilon) *
              (c.distance / (c.angle_error + 1.0) - c.perpendicular_penalty);
  return c;
}

std::unique_ptr<Task> make_directed_task(const Config& config) {
  return std::make_unique<DirectedTask>(config);
}

}  // namespace softevo::tasks
