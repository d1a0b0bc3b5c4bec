// Fitness (pneuvox-model.md §7). See fitness.hpp.
#include "worker/fitness.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace softevo::worker {
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

}  // namespace

double gait_fitness(const Vec3d& centroid_displacement) {
  return kCmPerM * centroid_displacement.x();
}

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

DirectionComponents directed_components(std::span<const Vec3d> waypoints_cm, double direction_deg,
                                        double path_penalty_weight) {
  DirectionComponents c;
  c.direction_deg = direction_deg;
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
  // F = |D| / (L + eps) * (D / (delta + 1) - P)   (the code's delta + 1, SPEC 6)
  c.fitness = std::fabs(c.distance) / (c.path_length + kEpsilon) *
              (c.distance / (c.angle_error + 1.0) - c.perpendicular_penalty);
  return c;
}

EvalResult combine_directions(std::span<const EvalResult> per_direction) {
  EvalResult total;
  if (per_direction.empty()) return total;
  total.genome_id = per_direction.front().genome_id;
  total.direction_index = -1;
  double sum = 0.0;
  for (const EvalResult& r : per_direction) {
    for (const auto& comp : r.components) total.components.push_back(comp);
    total.steps += r.steps;
    total.sim_seconds += r.sim_seconds;
    total.wall_seconds += r.wall_seconds;
    total.voxels = r.voxels;
    total.chambers = r.chambers;
    if (r.status != EvalStatus::ok && total.status == EvalStatus::ok) {
      total.status = r.status;
      total.message = r.message;
    }
    sum += r.fitness;
  }
  // §7.4: any killed direction zeroes the total.
  total.fitness = total.status == EvalStatus::ok ? sum : 0.0;
  return total;
}

}  // namespace softevo::worker
