// The batched step (physics/batch.hpp): the batch layout, the lanes' own parts (collisions,
// external forces, statuses) and the order of the pneuvox step (physics/step.cpp), with the
// passes of physics/batch_kernels.hpp chosen by Model::simd.
#include "physics/batch.hpp"

#include <algorithm>
#include <stdexcept>
#include <string>

#include "physics/collision.hpp"
#include "physics/step_kernels_table.hpp"

namespace softevo::physics {
namespace {

// A batch of one, or of a Model the batched passes do not cover (symplectic), steps each lane
// with physics::step() on lane[k] itself.
bool steps_lanes_alone(const Model& m, int lanes) {
  return lanes == 1 || m.integrator != Integrator::pneuvox;
}

std::size_t at(int e, int components, int c, int padded, int k) {
  return (static_cast<std::size_t>(e) * components + c) * padded + k;
}

// The hot arrays of a batch, with their components, for copying lanes.
template <class F>
void for_each_array(BatchState& b, F&& f) {
  f(b.pos, 3);
  f(b.lin_mom, 3);
  f(b.ang_mom, 3);
  f(b.orient, 4);
  f(b.static_friction, 1);
  f(b.link_pos2, 3);
  f(b.link_angle1v, 3);
  f(b.link_angle2v, 3);
  f(b.link_strain, 1);
  f(b.link_small_angle, 1);
  f(b.link_vel_valid, 1);
}

// Lane `to` of every hot array becomes a copy of lane `from` (an ended or idle lane is kept
// busy with a running lane's values, so that it never takes a slow path).
void copy_lane(BatchState& b, int from, int to) {
  const int p = b.padded;
  for_each_array(b, [&](auto& a, int components) {
    const std::size_t elements = a.size() / (static_cast<std::size_t>(components) * p);
    for (std::size_t e = 0; e < elements * components; ++e) a[e * p + to] = a[e * p + from];
  });
}

void set_lane(BatchState& b, int k, const State& s) {
  const int p = b.padded;
  const int nv = static_cast<int>(s.pos.size()), nl = static_cast<int>(s.link_strain.size());
  for (int v = 0; v < nv; ++v) {
    for (int c = 0; c < 3; ++c) {
      b.pos[at(v, 3, c, p, k)] = s.pos[v][c];
      b.lin_mom[at(v, 3, c, p, k)] = s.lin_mom[v][c];
      b.ang_mom[at(v, 3, c, p, k)] = s.ang_mom[v][c];
    }
    const Quat& q = s.orient[v];
    b.orient[at(v, 4, 0, p, k)] = q.w;
    b.orient[at(v, 4, 1, p, k)] = q.x;
    b.orient[at(v, 4, 2, p, k)] = q.y;
    b.orient[at(v, 4, 3, p, k)] = q.z;
    b.static_friction[at(v, 1, 0, p, k)] = s.static_friction[v];
  }
  for (int i = 0; i < nl; ++i) {
    for (int c = 0; c < 3; ++c) {
      b.link_pos2[at(i, 3, c, p, k)] = c == 0   ? s.link_pos2.x[i]
                                       : c == 1 ? s.link_pos2.y[i]
                                                : s.link_pos2.z[i];
      b.link_angle1v[at(i, 3, c, p, k)] = c == 0   ? s.link_angle1v.x[i]
                                          : c == 1 ? s.link_angle1v.y[i]
                                                   : s.link_angle1v.z[i];
      b.link_angle2v[at(i, 3, c, p, k)] = c == 0   ? s.link_angle2v.x[i]
                                          : c == 1 ? s.link_angle2v.y[i]
                                                   : s.link_angle2v.z[i];
    }
    b.link_strain[at(i, 1, 0, p, k)] = s.link_strain[i];
    b.link_small_angle[at(i, 1, 0, p, k)] = s.link_small_angle[i];
    b.link_vel_valid[at(i, 1, 0, p, k)] = s.link_vel_valid[i];
  }
}

// The hot state of running lane k into `out` (whose other fields are left as they are).
void get_hot(const BatchState& b, int k, State& out) {
  const int p = b.padded;
  const int nv = static_cast<int>(out.pos.size()), nl = static_cast<int>(out.link_strain.size());
  for (int v = 0; v < nv; ++v) {
    for (int c = 0; c < 3; ++c) {
      out.pos[v][c] = b.pos[at(v, 3, c, p, k)];
      out.lin_mom[v][c] = b.lin_mom[at(v, 3, c, p, k)];
      out.ang_mom[v][c] = b.ang_mom[at(v, 3, c, p, k)];
    }
    out.orient[v] = {b.orient[at(v, 4, 0, p, k)], b.orient[at(v, 4, 1, p, k)],
                     b.orient[at(v, 4, 2, p, k)], b.orient[at(v, 4, 3, p, k)]};
    out.static_friction[v] = b.static_friction[at(v, 1, 0, p, k)];
  }
  for (int i = 0; i < nl; ++i) {
    out.link_pos2.set(i, Vec3(b.link_pos2[at(i, 3, 0, p, k)], b.link_pos2[at(i, 3, 1, p, k)],
                              b.link_pos2[at(i, 3, 2, p, k)]));
    out.link_angle1v.set(i,
                         Vec3(b.link_angle1v[at(i, 3, 0, p, k)], b.link_angle1v[at(i, 3, 1, p, k)],
                              b.link_angle1v[at(i, 3, 2, p, k)]));
    out.link_angle2v.set(i,
                         Vec3(b.link_angle2v[at(i, 3, 0, p, k)], b.link_angle2v[at(i, 3, 1, p, k)],
                              b.link_angle2v[at(i, 3, 2, p, k)]));
    out.link_strain[i] = b.link_strain[at(i, 1, 0, p, k)];
    out.link_small_angle[i] = b.link_small_angle[at(i, 1, 0, p, k)];
    out.link_vel_valid[i] = b.link_vel_valid[at(i, 1, 0, p, k)];
  }
}

// Ends running lane k of a batched Model: its state is gathered into lane[k] and its slots are
// given a running lane's values; returns that lane (-1: none is left).
int finish_lane(BatchState& b, int k) {
  get_hot(b, k, b.lane[k]);
  b.running[k] = 0;
  for (int j = 0; j < b.lanes; ++j) {
    if (b.running[j]) {
      copy_lane(b, j, k);
      return j;
    }
  }
  return -1;
}

}  // namespace

BatchState make_batch_state(const Model& model, std::span<const State> states) {
  const int lanes = static_cast<int>(states.size());
  if (lanes < 1 || lanes > kMaxBatchLanes)
    throw std::invalid_argument("physics::make_batch_state: " + std::to_string(lanes) +
                                " states; a batch holds 1 to " + std::to_string(kMaxBatchLanes));
  for (int k = 0; k < lanes; ++k) {
    const State& s = states[k];
    if (s.pos.size() != static_cast<std::size_t>(model.voxel_count) ||
        s.link_strain.size() != static_cast<std::size_t>(model.link_count))
      throw std::invalid_argument("physics::make_batch_state: state " + std::to_string(k) +
                                  " has " + std::to_string(s.pos.size()) + " voxels and " +
                                  std::to_string(s.link_strain.size()) + " links, the model " +
                                  std::to_string(model.voxel_count) + " and " +
                                  std::to_string(model.link_count));
    if (!(s.previous_dt == 0.0f || s.previous_dt == model.dt_f))
      throw std::invalid_argument("physics::make_batch_state: state " + std::to_string(k) +
                                  " has previous_dt " + std::to_string(s.previous_dt) +
                                  " s; a batch steps states whose previous_dt is 0 or the "
                                  "model's time step");
  }
  BatchState b;
  b.lanes = lanes;
  b.lane.assign(states.begin(), states.end());
  b.running.assign(static_cast<std::size_t>(lanes), 1);
  if (steps_lanes_alone(model, lanes)) return b;
  // the kernels' width that leaves fewer lanes idle (the wider one when equal)
  const StepKernels& kernels = step_kernels(model.simd);
  auto padded_at = [lanes](int width) { return (lanes + width - 1) / width * width; };
  b.width = padded_at(kernels.batch_narrow.lanes) < padded_at(kernels.batch_wide.lanes)
                ? kernels.batch_narrow.lanes
                : kernels.batch_wide.lanes;
  b.padded = padded_at(b.width);
  const std::size_t p = b.padded, nv = model.voxel_count, nl = model.link_count;
  b.pos.assign(nv * 3 * p, 0.0);
  b.lin_mom = b.ang_mom = b.pos;
  b.orient.assign(nv * 4 * p, 0.0);
  b.static_friction.assign(nv * p, 0);
  b.link_pos2.assign(nl * 3 * p, 0.0);
  b.link_angle1v = b.link_angle2v = b.link_pos2;
  b.link_strain.assign(nl * p, 0.0f);
  b.link_small_angle.assign(nl * p, 0);
  b.link_vel_valid.assign(nl * p, 0);
  for (int k = 0; k < lanes; ++k) set_lane(b, k, states[k]);
  for (int idle = lanes; idle < b.padded; ++idle) copy_lane(b, 0, idle);
  return b;
}

BatchScratch make_batch_scratch(const Model& model, const BatchState& batch) {
  BatchScratch sc;
  sc.lane.assign(static_cast<std::size_t>(batch.lanes), make_scratch(model));
  if (batch.padded == 0) return sc;
  const std::size_t p = batch.padded, nv = model.voxel_count, nl = model.link_count;
  sc.end_load.assign((2 * nl + 1) * 6 * p, 0.0);  // the last slot: a missing link's zero load
  sc.old_pos.assign(nv * 3 * p, 0.0);
  sc.part2_force = sc.fric = sc.collision_force = sc.external_force = sc.old_pos;
  sc.damping_neg.assign(nl, 0.0);
  sc.damping_pos.assign(nl, 0.0);
  for (std::size_t i = 0; i < nl; ++i) {  // §2.5 c_V = damp_base_V / previous_dt (float)
    sc.damping_neg[i] = model.voxel_const[model.link_neg[i]].damp_base / model.dt_f;
    sc.damping_pos[i] = model.voxel_const[model.link_pos[i]].damp_base / model.dt_f;
  }
  return sc;
}

bool lane_running(const BatchState& batch, int lane) {
  return batch.running.at(static_cast<std::size_t>(lane)) != 0;
}

const State& ended_lane(const BatchState& batch, int lane) {
  if (lane_running(batch, lane) && batch.padded != 0)
    throw std::logic_error("physics::ended_lane: lane " + std::to_string(lane) + " is running");
  return batch.lane[static_cast<std::size_t>(lane)];
}

void get_lane(const BatchState& batch, int lane, State& out) {
  const State& s = batch.lane.at(static_cast<std::size_t>(lane));
  if (&out != &s) out = s;
  if (batch.padded != 0 && batch.running[lane]) get_hot(batch, lane, out);
}

void end_lane(BatchState& batch, int lane) {
  if (!lane_running(batch, lane)) return;
  if (batch.padded == 0) {
    batch.running[lane] = 0;
  } else {
    finish_lane(batch, lane);
  }
}

void step_batch(const Model& model, BatchState& b, BatchScratch& sc,
                std::span<const std::span<const Vec3>> external_force,
                std::span<StepStatus> status) {
  const int lanes = b.lanes;
  if (static_cast<int>(status.size()) != lanes ||
      !(external_force.empty() || static_cast<int>(external_force.size()) == lanes) ||
      static_cast<int>(sc.lane.size()) != lanes)
    throw std::invalid_argument(
        "physics::step_batch: " + std::to_string(lanes) + " lanes, but " +
        std::to_string(status.size()) + " statuses, " + std::to_string(external_force.size()) +
        " external forces and a scratch of " + std::to_string(sc.lane.size()) + " lanes");
  for (const auto& f : external_force)
    if (!f.empty() && f.size() != static_cast<std::size_t>(model.voxel_count))
      throw std::invalid_argument("physics::step_batch: an external force has " +
                                  std::to_string(f.size()) + " entries, the model has " +
                                  std::to_string(model.voxel_count) + " voxels");
  std::fill(status.begin(), status.end(), StepStatus::ok);
  auto ext_of = [&](int k) {
    return external_force.empty() ? std::span<const Vec3>{} : external_force[k];
  };
  if (b.padded == 0) {  // one lane, or not pneuvox: each lane alone
    for (int k = 0; k < lanes; ++k) {
      if (!b.running[k]) continue;
      status[k] = step(model, b.lane[k], sc.lane[k], ext_of(k));
      if (status[k] != StepStatus::ok) b.running[k] = 0;
    }
    return;
  }
  if (std::none_of(b.running.begin(), b.running.end(), [](std::uint8_t r) { return r != 0; }))
    return;
  const StepKernels& kernels = step_kernels(model.simd);
  const StepKernels::Batch& passes =
      b.width == kernels.batch_wide.lanes ? kernels.batch_wide : kernels.batch_narrow;
  const int p = b.padded;
  // the external forces by lane; ended and idle lanes take the first running lane's, so that
  // they follow a plausible motion (their values are never read). All zero stays zero.
  int first = 0;
  while (!b.running[first]) ++first;
  const bool no_force = std::all_of(external_force.begin(), external_force.end(),
                                    [](std::span<const Vec3> f) { return f.empty(); });
  if (!(no_force && sc.external_force_zero)) {
    for (int k = 0; k < p; ++k) {
      const std::span<const Vec3> f = ext_of(k < lanes && b.running[k] ? k : first);
      for (int v = 0; v < model.voxel_count; ++v)
        for (int c = 0; c < 3; ++c)
          sc.external_force[at(v, 3, c, p, k)] = f.empty() ? 0.0 : f[v][c];
    }
    sc.external_force_zero = no_force;
  }
  // 1. link pass (forces only, §2.12 step 1); a lane with a strain > 100 ends there with the
  //    link state the one-robot step restores (physics/step.cpp), and its slots take a running
  //    lane's state and end loads
  const int diverged = passes.forces_pass(model, b, sc);
  for (int k = 0; k < lanes; ++k) {
    if (!b.running[k] || !(diverged >> k & 1)) continue;
    const int from = finish_lane(b, k);
    kernels.link_pass_restore_state(model, b.lane[k], sc.lane[k]);
    ++b.lane[k].counters.diverged_steps;
    status[k] = StepStatus::diverged;
    if (from >= 0) {
      for (std::size_t e = 0; e < sc.end_load.size() / p; ++e)
        sc.end_load[e * p + k] = sc.end_load[e * p + from];
    }
  }
  // 2. collisions of each lane on its own pair list: its surface voxels' positions and momenta
  //    (all update_collisions reads) copied to its State, its forces back into the batch
  if (model.self_collision) {
    for (int k = 0; k < lanes; ++k) {
      if (!b.running[k]) continue;
      State& s = b.lane[k];
      for (int v : model.surface_voxels)
        for (int c = 0; c < 3; ++c) {
          s.pos[v][c] = b.pos[at(v, 3, c, p, k)];
          s.lin_mom[v][c] = b.lin_mom[at(v, 3, c, p, k)];
        }
      Scratch& lsc = sc.lane[k];
      const bool was_zero = lsc.collision_force_zero;
      update_collisions(model, s, lsc);
      if (was_zero && lsc.collision_force_zero) continue;  // +0 in the batch already
      for (int v = 0; v < model.voxel_count; ++v)
        for (int c = 0; c < 3; ++c)
          sc.collision_force[at(v, 3, c, p, k)] = lsc.collision_force[v][c];
    }
  }
  // 3-9. the voxel passes; every lane advances its time (a non-finite one too, as step())
  const int non_finite = passes.voxel_passes(model, b, sc);
  for (int k = 0; k < lanes; ++k) {
    if (!b.running[k]) continue;
    State& s = b.lane[k];
    s.previous_dt = model.dt_f;
    s.time += model.dt_f;
    if (non_finite >> k & 1) {
      ++s.counters.non_finite_steps;
      finish_lane(b, k);
      status[k] = StepStatus::non_finite;
    } else {
      ++s.counters.steps;
    }
  }
}

}  // namespace softevo::physics
