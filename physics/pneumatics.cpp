// Pneumatic chambers, conduits and valves (docs/model.md §3). See pneumatics.hpp.
#include "physics/pneumatics.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <numbers>
#include <stdexcept>
#include <string>

#include "common/chamber_quads.hpp"
#include "physics/pneumatics_triangle.hpp"
#include "physics/state.hpp"
#include "physics/step_kernels_table.hpp"

namespace softevo::physics {

BiquadCoeffs lowpass_biquad(double normalised_cutoff, double q) {
  // §3.5 (EarLevel biquad, low-pass, gain unused).
  const double k = std::tan(std::numbers::pi * normalised_cutoff);
  const double norm = 1.0 / (1.0 + k / q + k * k);
  BiquadCoeffs c;
  c.a0 = k * k * norm;
  c.a1 = 2.0 * c.a0;
  c.a2 = c.a0;
  c.b1 = 2.0 * (k * k - 1.0) * norm;
  c.b2 = (1.0 - k / q + k * k) * norm;
  return c;
}

double chamber_supply_pressure(const PneumaticsConfig& cfg, double rest_volume) {
  if (cfg.supply_pressure_scaling == SupplyScaling::none) return cfg.supply_pressure;
  // §3.8: the gauge part scales, because the wall force (§3.4) and the gas a stroke moves are
  // proportional to it; scaling the absolute pressure would multiply the gauge of a half-size
  // chamber by 7 instead of 2 at the default 1.2 bar.
  const double gauge = (cfg.supply_pressure - cfg.ambient_pressure) *
                       (cfg.scaling_reference_volume / rest_volume);  // [Pa]
  return std::min(cfg.ambient_pressure + gauge, cfg.max_supply_pressure);
}

PneumaticsModel build_pneumatics(const BodyPlan& plan, const Model& model,
                                 const PneumaticsConfig& cfg) {
  if (plan.lattice != model.lattice)
    throw std::invalid_argument("build_pneumatics: body plan lattice does not match the model");
  if (!(cfg.supply_pressure > 0.0) || !(cfg.ambient_pressure > 0.0))
    throw std::invalid_argument("build_pneumatics: reservoir pressures must be > 0 Pa");
  if (cfg.supply_pressure_scaling == SupplyScaling::inverse_volume &&
      (!(cfg.scaling_reference_volume > 0.0) || !(cfg.max_supply_pressure >= cfg.supply_pressure) ||
       !(cfg.supply_pressure > cfg.ambient_pressure)))
    throw std::invalid_argument(
        "build_pneumatics: inverse_volume needs scaling_reference_volume > 0 m^3, "
        "max_supply_pressure >= supply_pressure > ambient_pressure");
  if (!(cfg.conductivity >= 0.0))
    throw std::invalid_argument("build_pneumatics: conductivity must be >= 0");
  if (cfg.valve_filter_stages < 0 || cfg.valve_filter_stages > 16)
    throw std::invalid_argument("build_pneumatics: valve_filter_stages must be in [0, 16]");
  if (!(cfg.valve_cutoff > 0.0) || !(cfg.valve_filter_q > 0.0))
    throw std::invalid_argument("build_pneumatics: valve_cutoff and valve_filter_q must be > 0");
  if (!(model.dt > 0.0)) throw std::invalid_argument("build_pneumatics: model dt must be > 0");
  if (!(cfg.valve_cutoff * model.dt < 0.5))
    throw std::invalid_argument(
        "build_pneumatics: valve_cutoff must be below the Nyquist "
        "frequency 1/(2 dt)");

  PneumaticsModel pm;
  const std::vector<ChamberQuads> quads = chamber_quads(plan);
  pm.chamber_count = static_cast<int>(quads.size());
  pm.valve_count = 2 * pm.chamber_count;
  pm.filter_stages = static_cast<int>(cfg.valve_filter_stages);
  pm.chamber_triangle_begin.push_back(0);

  // voxel id -> wall slot, -1 = not yet a wall voxel (setup only)
  std::vector<int> slot_of_voxel(static_cast<std::size_t>(model.voxel_count), -1);
  auto slot = [&](int voxel) {
    int& s = slot_of_voxel[static_cast<std::size_t>(voxel)];
    if (s < 0) {
      s = static_cast<int>(pm.wall_voxel.size());
      pm.wall_voxel.push_back(voxel);
    }
    return s;
  };
  for (const ChamberQuads& chamber : quads) {
    for (const auto& quad : chamber.quads) {
      std::array<int, 4> voxel{};
      bool ok = true;
      for (int i = 0; i < 4; ++i) {
        const auto& c = quad[i];
        const bool inside = c[0] >= 0 && c[1] >= 0 && c[2] >= 0 && c[0] < model.lattice[0] &&
                            c[1] < model.lattice[1] && c[2] < model.lattice[2];
        voxel[i] = inside ? model.cell_to_voxel[model.cell_index(c[0], c[1], c[2])] : -1;
        ok = ok && voxel[i] >= 0;
      }
      if (!ok) {  // §3.1: a quad whose voxel does not exist is skipped
        ++pm.skipped_quads;
        continue;
      }
      const int a = slot(voxel[0]), b = slot(voxel[1]), c = slot(voxel[2]), d = slot(voxel[3]);
      // §3.1: quad (a,b,c,d) -> triangles (a,b,c) and (c,d,a)
      pm.triangle_slots.push_back({a, b, c});
      pm.triangle_slots.push_back({c, d, a});
      pm.triangle_voxels.push_back({voxel[0], voxel[1], voxel[2]});
      pm.triangle_voxels.push_back({voxel[2], voxel[3], voxel[0]});
    }
    pm.chamber_triangle_begin.push_back(static_cast<int>(pm.triangle_slots.size()));
  }
  // slot -> its triangles in ascending order (counting sort over the triangles in order)
  pm.slot_triangle_begin.assign(pm.wall_voxel.size() + 1, 0);
  for (const auto& tri : pm.triangle_slots)
    for (int s : tri) ++pm.slot_triangle_begin[static_cast<std::size_t>(s) + 1];
  for (std::size_t s = 0; s < pm.wall_voxel.size(); ++s)
    pm.slot_triangle_begin[s + 1] += pm.slot_triangle_begin[s];
  pm.slot_triangles.resize(pm.triangle_slots.size() * 3);
  std::vector<int> next(pm.slot_triangle_begin.begin(), pm.slot_triangle_begin.end() - 1);
  for (std::size_t t = 0; t < pm.triangle_slots.size(); ++t)
    for (int s : pm.triangle_slots[t]) pm.slot_triangles[next[s]++] = static_cast<int>(t);

  // Reference units: bar (config Pa / 1e5, then float as the reference stores it).
  pm.supply_bar = static_cast<float>(cfg.supply_pressure / kPascalPerBar);
  pm.ambient_bar = static_cast<float>(cfg.ambient_pressure / kPascalPerBar);
  pm.conductivity = static_cast<float>(cfg.conductivity);
  pm.dt_f = model.dt_f;
  pm.simd = model.simd;
  // §3.8: rest volumes at the initial positions (the V0 of §3.3) and each chamber's inlet
  // pressure, fixed for the robot's life.
  const State rest = initial_state(model);
  pm.rest_volume.resize(quads.size());
  pm.chamber_supply_bar.resize(quads.size());
  for (int q = 0; q < pm.chamber_count; ++q) {
    pm.rest_volume[q] = chamber_volume(pm, q, rest.pos);
    pm.chamber_supply_bar[q] = static_cast<float>(
        chamber_supply_pressure(cfg, static_cast<double>(pm.rest_volume[q])) / kPascalPerBar);
  }
  // §3.5: normalised cut-off Fc = dt * f_c (f_c Hz sampled at 1/dt).
  pm.filter =
      lowpass_biquad(static_cast<double>(model.dt_f) * cfg.valve_cutoff, cfg.valve_filter_q);
  return pm;
}

float chamber_volume(const PneumaticsModel& pm, int chamber, std::span<const Vec3> positions) {
  const int begin = pm.chamber_triangle_begin[chamber];
  const int end = pm.chamber_triangle_begin[chamber + 1];
  float volume = 0.0f;  // [m^3], accumulated in float as the reference
  if (begin < end) {
    const Point3<double> p0 = to_point3(positions[pm.triangle_voxels[begin][0]]);
    for (int t = begin; t < end; ++t) {
      const auto& tri = pm.triangle_voxels[t];
      // §3.2: V += (C-p0) . ((B-p0) x (A-p0)) / 6 (double products, float accumulation)
      const double tet =
          triangle_tet_volume(to_point3(positions[tri[0]]), to_point3(positions[tri[1]]),
                              to_point3(positions[tri[2]]), p0);
      volume = static_cast<float>(volume + tet);
    }
  }
  return std::max(volume, 1e-12f);  // §3.2: V = max(V, 1e-12)
}

PneumaticsState initial_pneumatics_state(const PneumaticsModel& pm,
                                         std::span<const Vec3> positions) {
  PneumaticsState ps;
  const auto chambers = static_cast<std::size_t>(pm.chamber_count);
  const auto valves = static_cast<std::size_t>(pm.valve_count);
  ps.quantity.resize(chambers);
  ps.volume.resize(chambers);
  ps.pressure.resize(chambers);
  for (int q = 0; q < pm.chamber_count; ++q) {
    // §3.3: n0 = V0 (1 bar absolute). The reference leaves `pressure` unset until the first
    // update (§3.7); here it is n0/V0 = 1, and the first sensor reading is a config value.
    ps.volume[q] = chamber_volume(pm, q, positions);
    ps.quantity[q] = ps.volume[q];
    ps.pressure[q] = ps.quantity[q] / ps.volume[q];
  }
  ps.valve_state.assign(valves, 1.0f);    // §3.5: valve state initially 1.0
  ps.valve_applied.assign(valves, 1.0f);  // last applied state initially 1.0
  ps.conduit_open.assign(valves, 1.0f);   // conduit "open" initially 1.0
  ps.openness.assign(valves, 0.0f);
  ps.filter_z.assign(valves * static_cast<std::size_t>(pm.filter_stages) * 2, 0.0);
  return ps;
}

PneumaticsScratch make_pneumatics_scratch(const PneumaticsModel& pm) {
  PneumaticsScratch s;
  s.triangle_force.assign(pm.triangle_slots.size(), {0.0f, 0.0f, 0.0f, 0.0f});
  return s;
}

void set_valve_commands(PneumaticsState& ps, std::span<const float> commands) {
  const std::size_t n = std::min(commands.size(), ps.valve_state.size());
  for (std::size_t k = 0; k < n; ++k) ps.valve_state[k] = commands[k];
}

void pneumatics_update(const PneumaticsModel& pm, PneumaticsState& ps, PneumaticsScratch& scratch,
                       std::span<const Vec3> positions, std::span<Vec3> external_force) {
  // 1. Recompute every volume (all chambers first).
  const StepKernels& kernels = step_kernels(pm.simd);
  for (int q = 0; q < pm.chamber_count; ++q)
    ps.volume[q] = kernels.chamber_volume(pm, q, positions);

  // 2. Valve pre-update (§3.5): a changed state is handed to the conduit's "open" value.
  for (int k = 0; k < pm.valve_count; ++k) {
    if (ps.valve_state[k] != ps.valve_applied[k]) {
      ps.valve_applied[k] = ps.valve_state[k];
      ps.conduit_open[k] = ps.valve_state[k];
    }
  }

  // 3. Pressure and pressure forces (§3.3, §3.4).
  for (int q = 0; q < pm.chamber_count; ++q) {
    const float p = ps.quantity[q] / ps.volume[q];  // p = n/V [bar] (float)
    ps.pressure[q] = p;
    const float gauge = p - 1.0f;  // [bar] relative to 1 bar ambient
    kernels.pressure_forces(pm, q, gauge, positions, scratch);
  }
  // Each wall voxel's force: the float sum, from 0, of its triangles' shares in triangle order
  // (chamber by chamber, mesh order: the order of the reference's additions). Summed per slot, so
  // that the slots' sums are independent chains; the four floats of a share are added as one
  // vector (element-wise IEEE float additions: the bits of four scalar sums, on any target).
  using Float4 = float __attribute__((vector_size(16)));
  static_assert(sizeof(Float4) == sizeof(scratch.triangle_force[0]));
  for (std::size_t s = 0; s < pm.wall_voxel.size(); ++s) {
    Float4 sum{};
    for (int k = pm.slot_triangle_begin[s]; k < pm.slot_triangle_begin[s + 1]; ++k) {
      Float4 share;
      std::memcpy(&share, scratch.triangle_force[pm.slot_triangles[k]].data(), sizeof share);
      sum += share;
    }
    external_force[pm.wall_voxel[s]] = Vec3(sum[0], sum[1], sum[2]);
  }

  // 4. Conduits in creation order: low-pass the opening, then transfer gas (§3.5).
  const BiquadCoeffs& bq = pm.filter;
  for (int k = 0; k < pm.valve_count; ++k) {
    float x = ps.conduit_open[k];
    double* z = &ps.filter_z[static_cast<std::size_t>(k) * pm.filter_stages * 2];
    for (int st = 0; st < pm.filter_stages; ++st, z += 2) {
      // transposed direct form II, double state, float in/out
      const double y = x * bq.a0 + z[0];
      z[0] = x * bq.a1 + z[1] - bq.b1 * y;
      z[1] = x * bq.a2 - bq.b2 * y;
      x = static_cast<float>(y);
    }
    const float openness = std::clamp(x, 0.0f, 1.0f);
    ps.openness[k] = openness;
    const float conductivity = openness * pm.conductivity;  // [m^3/(bar s)]
    const int q = k / 2;
    // q = conductivity (p - p_ext) dt; positive = gas leaving the chamber
    const float flow = conductivity * (ps.pressure[q] - pm.reservoir_bar(k)) * pm.dt_f;
    ps.quantity[q] -= flow;
  }
  ++ps.updates;
}

}  // namespace softevo::physics
