#include "physics/observables.hpp"

#include <algorithm>

namespace softevo::physics {

double max_link_strain(const Model& model, const State& state) {
  float mx = 0.0f;
  for (int i = 0; i < model.link_count; ++i) mx = std::max(mx, state.link_strain[i]);
  return mx;
}

bool exploded(const Model& model, const State& state) {
  return max_link_strain(model, state) > 2.0;  // §2.15
}

Vec3 mean_rotation_vector(const Model& model, const State& state) {
  Vec3 sum = Vec3::Zero();
  for (int v = 0; v < model.voxel_count; ++v)
    if (!model.voxel_fixed[v]) sum += rotvec(state.orient[v]);
  return model.free_voxel_count > 0 ? Vec3(sum / model.free_voxel_count) : sum;
}

bool flipped(const Model& model, const State& state) {
  const Vec3 r = mean_rotation_vector(model, state);
  const double lim = 3.14159 / 3;  // §2.15
  return r.x() > lim || r.x() < -lim || r.y() > lim || r.y() < -lim;
}

Vec3 centroid_displacement(const Model& model, const State& state) {
  Vec3 sum = Vec3::Zero();
  const double s = model.voxel_size;
  for (int v = 0; v < model.voxel_count; ++v) {
    if (model.voxel_fixed[v]) continue;
    const auto& c = model.voxel_cell[v];
    sum += state.pos[v] - Vec3(s * c[0], s * c[1], s * c[2]);
  }
  return model.free_voxel_count > 0 ? Vec3(sum / model.free_voxel_count) : sum;
}

Vec3 centre_of_mass(const Model& model, const State& state) {
  Vec3 sum = Vec3::Zero();
  for (int v = 0; v < model.voxel_count; ++v)
    if (!model.voxel_fixed[v]) sum += state.pos[v];
  return model.free_voxel_count > 0 ? Vec3(sum / model.free_voxel_count) : sum;
}

Vec3 total_linear_momentum(const Model& model, const State& state) {
  Vec3 sum = Vec3::Zero();
  for (int v = 0; v < model.voxel_count; ++v)
    if (!model.voxel_fixed[v]) sum += state.lin_mom[v];
  return sum;
}

Vec3 total_angular_momentum(const Model& model, const State& state, const Vec3& about) {
  Vec3 sum = Vec3::Zero();
  for (int v = 0; v < model.voxel_count; ++v)
    if (!model.voxel_fixed[v])
      sum += cross(state.pos[v] - about, state.lin_mom[v]) + state.ang_mom[v];
  return sum;
}

double kinetic_energy(const Model& model, const State& state) {
  double e = 0.0;
  for (int v = 0; v < model.voxel_count; ++v) {
    const VoxelConst& c = model.voxel_const[v];
    e += 0.5 * state.lin_mom[v].squaredNorm() * c.inv_mass +
         0.5 * state.ang_mom[v].squaredNorm() * c.inv_inertia;
  }
  return e;
}

double elastic_energy(const Model& model, const State& state) {
  // U = 1/2 q^T K q = -1/2 (F_P . pos2 + M_N . theta1 + M_P . theta2) with the elastic end
  // loads of §2.4 (F_P = -F_N acts on the displaced end P).
  double e = 0.0;
  for (int i = 0; i < model.link_count; ++i) {
    const LinkConst& c = model.link_const[i];
    const Vec3 p = state.link_pos2[i];
    const Vec3 a1 = state.link_angle1v[i];
    const Vec3 a2 = state.link_angle2v[i];
    const double fx = c.e_area * (p.x() / model.rest_length) * c.area;
    const Vec3 fn(fx, c.b1 * p.y() - c.b2 * (a1.z() + a2.z()),
                  c.b1 * p.z() + c.b2 * (a1.y() + a2.y()));
    const Vec3 mn(c.a2 * (a2.x() - a1.x()), -c.b2 * p.z() - c.b3 * (2 * a1.y() + a2.y()),
                  c.b2 * p.y() - c.b3 * (2 * a1.z() + a2.z()));
    const Vec3 mp(c.a2 * (a1.x() - a2.x()), -c.b2 * p.z() - c.b3 * (a1.y() + 2 * a2.y()),
                  c.b2 * p.y() - c.b3 * (a1.z() + 2 * a2.z()));
    e += -0.5 * ((-fn).dot(p) + mn.dot(a1) + mp.dot(a2));
  }
  return e;
}

double gravity_energy(const Model& model, const State& state, double gravity) {
  double e = 0.0;
  for (int v = 0; v < model.voxel_count; ++v)
    e += model.voxel_const[v].mass * gravity * state.pos[v].z();
  return e;
}

}  // namespace softevo::physics
