#include "physics/state.hpp"

#include "common/fnv1a.hpp"

#include <cstring>
#include <type_traits>

namespace softevo::physics {

State initial_state(const Model& model) {
  State st;
  const int nv = model.voxel_count;
  const double s = model.voxel_size;
  st.pos.resize(nv);
  for (int v = 0; v < nv; ++v) {
    const auto& c = model.voxel_cell[v];
    st.pos[v] = Vec3(s * c[0], s * c[1], s * c[2]);  // §2.1: pos = s (i, j, k)
  }
  st.lin_mom.assign(nv, Vec3::Zero());
  st.orient.assign(nv, Quat{});
  st.ang_mom.assign(nv, Vec3::Zero());
  st.static_friction.assign(nv, 1);  // §2.8: every voxel starts in static friction
  const int nl = model.link_count;
  st.link_pos2.assign(nl, 0.0);
  st.link_angle1v.assign(nl, 0.0);
  st.link_angle2v.assign(nl, 0.0);
  st.link_strain.assign(nl, 0.0f);
  st.link_small_angle.assign(nl, 1);
  st.link_vel_valid.assign(nl, 0);
  st.collisions_stale = true;
  st.col_watch_pos.assign(nv, {0.0f, 0.0f, 0.0f});
  // Pair capacity: 128 partners per surface voxel covers any body whose surface voxels are not
  // packed denser than the 2.5 s watch sphere allows; more grows the list (counted).
  const std::size_t ns = model.surface_voxels.size();
  std::size_t cap = ns * 128;
  if (ns > 1 && cap > ns * (ns - 1) / 2) cap = ns * (ns - 1) / 2;
  st.col_pairs.assign(cap, CollisionPair{0, 0});
  st.col_pair_count = 0;
  return st;
}

namespace {

// The state hash: FNV-1a 64 (common/fnv1a.hpp) over each field's object representation, arrays
// preceded by their length.
struct StateHasher {
  Fnv1a64 f;
  template <class T>
  void value(const T& v) {
    f.object(v);
  }
  void bytes(const void* p, std::size_t n) { f.bytes(p, n); }
  void array(const LinkVec3Columns& c) {  // as the array of Vec3
    value(static_cast<std::uint64_t>(c.size()));
    for (std::size_t i = 0; i < c.size(); ++i) {
      value(c.x[i]);
      value(c.y[i]);
      value(c.z[i]);
    }
  }
  template <class T>
  void array(const std::vector<T>& v) {
    value(static_cast<std::uint64_t>(v.size()));
    if (!v.empty()) bytes(v.data(), v.size() * sizeof(T));
  }
};

static_assert(sizeof(Vec3) == 3 * sizeof(double), "Vec3 must be three packed doubles");
static_assert(sizeof(Quat) == 4 * sizeof(double), "Quat must be four packed doubles");
static_assert(sizeof(CollisionPair) == 8, "CollisionPair must be unpadded");

}  // namespace

std::uint64_t state_hash(const State& st) {
  StateHasher f;
  f.value(st.time);
  f.value(st.previous_dt);
  f.array(st.pos);
  f.array(st.lin_mom);
  f.array(st.orient);
  f.array(st.ang_mom);
  f.array(st.static_friction);
  f.array(st.link_pos2);
  f.array(st.link_angle1v);
  f.array(st.link_angle2v);
  f.array(st.link_strain);
  f.array(st.link_small_angle);
  f.array(st.link_vel_valid);
  f.value(static_cast<std::uint8_t>(st.collisions_stale));
  f.array(st.col_watch_pos);
  f.value(static_cast<std::uint64_t>(st.col_pair_count));
  if (st.col_pair_count > 0)
    f.bytes(st.col_pairs.data(), st.col_pair_count * sizeof(CollisionPair));
  f.value(st.counters.steps);
  f.value(st.counters.diverged_steps);
  f.value(st.counters.non_finite_steps);
  f.value(st.counters.collision_rebuilds);
  f.value(st.counters.collision_pair_growths);
  return f.f.value();
}

}  // namespace softevo::physics
