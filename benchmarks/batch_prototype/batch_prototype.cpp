// batch_prototype ROBOT.robot.json [--steps N] [--runs R] [--eval-seconds S]: issue 40's
// measurement (benchmarks/batch_prototype/README.md). Runs ROBOT's own evaluation (its
// controller, pneumatics, collisions) and keeps 8 of its states, 0.1 s of simulated time apart;
// then, per round, steps each of them N steps
//   - with today's physics::step at the widest SIMD width of this CPU, one evaluation at a time;
//   - with the prototype's batched step (batch_prototype_kernels.cpp) at K = 1, 4 and 8 lanes,
// all on the robot's Model without self-collision and with zero external force (the prototype
// has the link and voxel passes only). Prints microseconds per voxel-step per evaluation of each,
// rounds interleaved, and whether every lane's final state equals today's step bit for bit.
#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <ctime>
#include <string>
#include <vector>

#include "benchmarks/batch_prototype/batch_prototype.hpp"
#include "common/config.hpp"
#include "common/robot.hpp"
#include "physics/scenes.hpp"
#include "physics/step.hpp"
#include "tasks/task.hpp"
#include "worker/controller.hpp"
#include "worker/simulation.hpp"

namespace softevo::batch_prototype {

namespace {
template <class T>
void put3(std::vector<T>& out, int lanes, int i, int k, double x, double y, double z) {
  const std::size_t base = static_cast<std::size_t>(i) * 3 * lanes + k;
  out[base] = x;
  out[base + lanes] = y;
  out[base + 2 * lanes] = z;
}
}  // namespace

Batch pack(const physics::Model& m, std::span<const physics::State* const> states) {
  Batch b;
  const int K = static_cast<int>(states.size());
  b.lanes = K;
  b.voxels = m.voxel_count;
  b.links = m.link_count;
  b.previous_dt = states[0]->previous_dt;
  const std::size_t nv = m.voxel_count, nl = m.link_count;
  b.pos.assign(nv * 3 * K, 0.0);
  b.lin_mom = b.ang_mom = b.old_pos = b.part2_force = b.fric = b.collision_force =
      b.external_force = b.pos;
  b.orient.assign(nv * 4 * K, 0.0);
  b.static_friction.assign(nv * K, 0);
  b.link_pos2.assign(nl * 3 * K, 0.0);
  b.link_angle1v = b.link_angle2v = b.link_pos2;
  b.link_strain.assign(nl * K, 0.0f);
  b.link_small_angle.assign(nl * K, 0);
  b.link_vel_valid.assign(nl * K, 0);
  b.end_load.assign((2 * nl + 1) * 6 * K, 0.0);
  b.damping_neg.assign(nl, 0.0);
  b.damping_pos.assign(nl, 0.0);
  for (int k = 0; k < K; ++k) {
    const physics::State& s = *states[k];
    for (int v = 0; v < m.voxel_count; ++v) {
      put3(b.pos, K, v, k, s.pos[v].x(), s.pos[v].y(), s.pos[v].z());
      put3(b.lin_mom, K, v, k, s.lin_mom[v].x(), s.lin_mom[v].y(), s.lin_mom[v].z());
      put3(b.ang_mom, K, v, k, s.ang_mom[v].x(), s.ang_mom[v].y(), s.ang_mom[v].z());
      const std::size_t q = static_cast<std::size_t>(v) * 4 * K + k;
      b.orient[q] = s.orient[v].w;
      b.orient[q + K] = s.orient[v].x;
      b.orient[q + 2 * K] = s.orient[v].y;
      b.orient[q + 3 * K] = s.orient[v].z;
      b.static_friction[static_cast<std::size_t>(v) * K + k] = s.static_friction[v];
    }
    for (int i = 0; i < m.link_count; ++i) {
      put3(b.link_pos2, K, i, k, s.link_pos2.x[i], s.link_pos2.y[i], s.link_pos2.z[i]);
      put3(b.link_angle1v, K, i, k, s.link_angle1v.x[i], s.link_angle1v.y[i], s.link_angle1v.z[i]);
      put3(b.link_angle2v, K, i, k, s.link_angle2v.x[i], s.link_angle2v.y[i], s.link_angle2v.z[i]);
      const std::size_t j = static_cast<std::size_t>(i) * K + k;
      b.link_strain[j] = s.link_strain[i];
      b.link_small_angle[j] = s.link_small_angle[i];
      b.link_vel_valid[j] = s.link_vel_valid[i];
    }
  }
  return b;
}

void unpack(const Batch& b, int k, physics::State& s) {
  const int K = b.lanes;
  auto get3 = [&](const std::vector<double>& a, int i) {
    const std::size_t base = static_cast<std::size_t>(i) * 3 * K + k;
    return physics::Vec3(a[base], a[base + K], a[base + 2 * K]);
  };
  for (int v = 0; v < b.voxels; ++v) {
    s.pos[v] = get3(b.pos, v);
    s.lin_mom[v] = get3(b.lin_mom, v);
    s.ang_mom[v] = get3(b.ang_mom, v);
    const std::size_t q = static_cast<std::size_t>(v) * 4 * K + k;
    s.orient[v] = {b.orient[q], b.orient[q + K], b.orient[q + 2 * K], b.orient[q + 3 * K]};
    s.static_friction[v] = b.static_friction[static_cast<std::size_t>(v) * K + k];
  }
  for (int i = 0; i < b.links; ++i) {
    s.link_pos2.set(i, get3(b.link_pos2, i));
    s.link_angle1v.set(i, get3(b.link_angle1v, i));
    s.link_angle2v.set(i, get3(b.link_angle2v, i));
    const std::size_t j = static_cast<std::size_t>(i) * K + k;
    s.link_strain[i] = b.link_strain[j];
    s.link_small_angle[i] = b.link_small_angle[j];
    s.link_vel_valid[i] = b.link_vel_valid[j];
  }
}

}  // namespace softevo::batch_prototype

namespace {

using namespace softevo;
namespace bp = softevo::batch_prototype;

double cpu_now() {
  timespec t{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
  return static_cast<double>(t.tv_sec) + 1e-9 * static_cast<double>(t.tv_nsec);
}

template <class T>
bool same_bytes(const std::vector<T>& a, const std::vector<T>& b) {
  return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(T)) == 0;
}
bool same_bytes(const physics::LinkVec3Columns& a, const physics::LinkVec3Columns& b) {
  return same_bytes(a.x, b.x) && same_bytes(a.y, b.y) && same_bytes(a.z, b.z);
}
// The fields the prototype steps (not time, counters or collision bookkeeping).
bool same_physics(const physics::State& a, const physics::State& b) {
  return same_bytes(a.pos, b.pos) && same_bytes(a.lin_mom, b.lin_mom) &&
         same_bytes(a.ang_mom, b.ang_mom) && same_bytes(a.orient, b.orient) &&
         same_bytes(a.static_friction, b.static_friction) && same_bytes(a.link_pos2, b.link_pos2) &&
         same_bytes(a.link_angle1v, b.link_angle1v) && same_bytes(a.link_angle2v, b.link_angle2v) &&
         same_bytes(a.link_strain, b.link_strain) &&
         same_bytes(a.link_small_angle, b.link_small_angle) &&
         same_bytes(a.link_vel_valid, b.link_vel_valid);
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 2) {
    std::fprintf(stderr,
                 "usage: batch_prototype ROBOT.robot.json [--steps N] [--runs R] "
                 "[--eval-seconds S]\n");
    return 2;
  }
  int steps = 600, runs = 5;
  double snapshot_gap = 0.1;  // [s] of simulated time between the lanes' states
  bool same_lanes = false;    // every lane from the first state (no divergence between lanes)
  for (int a = 2; a + 1 < argc; a += 2) {
    const std::string opt = argv[a];
    if (opt == "--steps")
      steps = std::atoi(argv[a + 1]);
    else if (opt == "--runs")
      runs = std::atoi(argv[a + 1]);
    else if (opt == "--gap")
      snapshot_gap = std::atof(argv[a + 1]);
    else if (opt == "--same-lanes")
      same_lanes = std::atoi(argv[a + 1]) != 0;
    else {
      std::fprintf(stderr, "batch_prototype: unknown option %s\n", opt.c_str());
      return 2;
    }
  }
  constexpr int kLanes = 8;
  std::vector<physics::State> snaps;
  physics::Model model;
  std::string name = argv[1];
  int block = 0;
  if (std::sscanf(argv[1], "block%d", &block) == 1 && block > 0) {
    // a solid block dropped from rest (bench physics' material), its states every 20 steps
    PhysicsConfig pc;
    model = physics::build_model(physics::solid_block(block, block, block, 1.0e5), pc);
    model.self_collision = false;
    physics::State s = physics::initial_state(model);
    physics::Scratch sc = physics::make_scratch(model);
    for (int k = 0; k < kLanes; ++k) {
      for (int i = 0; i < 20; ++i) physics::step(model, s, sc);
      snaps.push_back(s);
    }
  } else {
    const RobotFile robot = read_robot_file(argv[1]);
    name = robot.name;
    Config cfg;
    cfg.run.eval_timeout_seconds = 0.0;
    cfg.task.eval_seconds = 10.0;
    cfg.task.control = robot.controller.closed_loop ? ControlLoop::closed : ControlLoop::open;
    cfg.task.kind = tasks::default_task_for(robot.controller.task_inputs());
    const auto task = tasks::make_task(cfg);
    worker::Simulation sim(cfg, *task, robot.body, 0, physics::Simd::best);
    worker::ElmanController brain(robot.controller, cfg.task.control_rate);
    std::vector<float> inputs(static_cast<std::size_t>(task->controller_inputs()), 0.0f);
    std::vector<float> sensor(static_cast<std::size_t>(sim.chambers()), 0.0f);
    std::vector<float> commands(static_cast<std::size_t>(sim.valve_count()), 1.0f);
    double next = 0.5;  // [s]
    while (sim.running() && static_cast<int>(snaps.size()) < kLanes) {
      sim.task_inputs(inputs);
      for (int q = 0; q < sim.chambers(); ++q) sensor[q] = sim.sensor_pressure_bar(q);
      brain.act(inputs, sensor, commands);
      if (sim.step(commands) != EvalStatus::ok) break;
      if (sim.time() >= next) {
        snaps.push_back(sim.state());
        next += snapshot_gap;
      }
    }
    if (static_cast<int>(snaps.size()) < kLanes) {
      std::fprintf(stderr, "batch_prototype: the evaluation ended before 8 states\n");
      return 1;
    }
    model = sim.model();
    model.self_collision = false;
  }
  if (same_lanes)
    for (int k = 1; k < kLanes; ++k) snaps[k] = snaps[0];
  model.simd = physics::best_simd();
  const int nv = model.voxel_count;
  const std::vector<physics::Vec3> ext(static_cast<std::size_t>(nv), physics::Vec3::Zero());
  std::printf(
      "robot %s: %d voxels, %d links, today's step at %s, %d steps per evaluation, "
      "%d rounds\n",
      name.c_str(), nv, model.link_count, physics::to_string(model.simd), steps, runs);

  // today's step: the 8 evaluations one after the other
  std::vector<physics::State> today_end(kLanes);
  auto run_today = [&] {
    std::vector<physics::State> st(snaps);
    physics::Scratch sc = physics::make_scratch(model);
    int bad = 0;
    const double t0 = cpu_now();
    for (int k = 0; k < kLanes; ++k)
      for (int s = 0; s < steps; ++s)
        bad += physics::step(model, st[k], sc, ext) != physics::StepStatus::ok;
    const double t = cpu_now() - t0;
    today_end = st;
    if (bad) std::printf("  today: %d failed steps\n", bad);
    return t;
  };
  // the batched step, K lanes per batch, 8 / K batches
  int mismatches[3] = {0, 0, 0};
  auto run_batched = [&](int K, int slot) {
    std::vector<bp::Batch> batches;
    for (int first = 0; first < kLanes; first += K) {
      std::vector<const physics::State*> lanes;
      for (int k = 0; k < K; ++k) lanes.push_back(&snaps[first + k]);
      batches.push_back(bp::pack(model, lanes));
    }
    int bad = 0;
    const double t0 = cpu_now();
    for (bp::Batch& b : batches)
      for (int s = 0; s < steps; ++s)
        bad |= K == 8   ? bp::step_k8(model, b)
               : K == 4 ? bp::step_k4(model, b)
                        : bp::step_k1(model, b);
    const double t = cpu_now() - t0;
    if (bad) std::printf("  K=%d: lanes failed (%x)\n", K, bad);
    mismatches[slot] = 0;
    for (int k = 0; k < kLanes; ++k) {
      physics::State s = snaps[k];
      bp::unpack(batches[k / K], k % K, s);
      if (!same_physics(s, today_end[k])) ++mismatches[slot];
    }
    return t;
  };
  const double per = 1e6 / (static_cast<double>(kLanes) * steps * nv);  // us per eval-voxel-step
  std::vector<double> t_today, t1, t4, t8;
  for (int r = 0; r < runs; ++r) {
    t_today.push_back(run_today() * per);
    t1.push_back(run_batched(1, 0) * per);
    t4.push_back(run_batched(4, 1) * per);
    t8.push_back(run_batched(8, 2) * per);
    std::printf(
        "round %d: us per voxel-step per evaluation: today %.4f  K=1 %.4f  K=4 %.4f  "
        "K=8 %.4f   (lanes differing from today: %d %d %d of 8)\n",
        r, t_today.back(), t1.back(), t4.back(), t8.back(), mismatches[0], mismatches[1],
        mismatches[2]);
    std::fflush(stdout);
  }
  auto med = [](std::vector<double> v) {
    std::sort(v.begin(), v.end());
    return v[v.size() / 2];
  };
  auto best = [](const std::vector<double>& v) { return *std::min_element(v.begin(), v.end()); };
  std::printf(
      "median (best): today %.4f (%.4f)  K=1 %.4f (%.4f)  K=4 %.4f (%.4f)  K=8 %.4f "
      "(%.4f)\n",
      med(t_today), best(t_today), med(t1), best(t1), med(t4), best(t4), med(t8), best(t8));
  std::printf("gain over today (median): K=1 %.2fx  K=4 %.2fx  K=8 %.2fx\n", med(t_today) / med(t1),
              med(t_today) / med(t4), med(t_today) / med(t8));
  return mismatches[0] + mismatches[1] + mismatches[2] == 0 ? 0 : 3;
}
