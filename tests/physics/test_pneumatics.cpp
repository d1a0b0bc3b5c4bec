// Pneumatic chambers (docs/model.md §3) and the pneumatic validation of docs/model.md §9:
// analytic chamber volumes, sealed chamber (gas conserved exactly, p V = n at every step), inlet
// (pressure rises monotonically to the 1.2 bar supply), outlet (back to 1.0 bar), both open
// (analytic 1.1 bar), the valve low-pass (-12 dB at 10 Hz), the sensor mapping, and a
// free-floating inflating body that keeps zero total linear momentum.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <numbers>
#include <utility>
#include <vector>

#include "common/body_plan.hpp"
#include "common/config.hpp"
#include "common/rng.hpp"
#include "common/robot.hpp"
#include "physics/model.hpp"
#include "physics/observables.hpp"
#include "physics/pneumatics.hpp"
#include "physics/pneumatics_triangle.hpp"
#include "physics/state.hpp"
#include "physics/step.hpp"
#include "tests/physics/random_vec3.hpp"
#include "tests/reference_data.hpp"

namespace {

using namespace softevo;
using namespace softevo::physics;

// A box of material-10 voxels of size (X,Y,Z) with chamber 0 (cell value 11) in the given
// inclusive cell range.
BodyPlan box_with_cavity(std::array<int, 3> size, std::array<int, 3> lo, std::array<int, 3> hi) {
  BodyPlan plan;
  plan.lattice = size;
  plan.voxel_size = 0.01;
  for (int k = 1; k <= 10; ++k) plan.materials.push_back({1.0e4 * k, 1000.0});
  plan.cells.assign(static_cast<std::size_t>(size[0] * size[1] * size[2]), 10);
  for (int x = lo[0]; x <= hi[0]; ++x)
    for (int y = lo[1]; y <= hi[1]; ++y)
      for (int z = lo[2]; z <= hi[2]; ++z) plan.cells[plan.cell_index(x, y, z)] = kFirstChamberCell;
  return plan;
}

// Everything one pneumatic simulation needs, built as the evaluation builds it.
struct Scene {
  Model model;
  State state;
  Scratch scratch;
  PneumaticsModel pm;
  PneumaticsState ps;
  PneumaticsScratch pscratch;
  std::vector<Vec3> force;

  Scene(const BodyPlan& plan, const PhysicsConfig& phys, const PneumaticsConfig& pcfg = {})
      : model(build_model(plan, phys)),
        state(initial_state(model)),
        scratch(make_scratch(model)),
        pm(build_pneumatics(plan, model, pcfg)),
        ps(initial_pneumatics_state(pm, state.pos)),
        pscratch(make_pneumatics_scratch(pm)),
        force(static_cast<std::size_t>(model.voxel_count), Vec3::Zero()) {}

  void valves(float inlet, float outlet) {
    const std::vector<float> cmd = {inlet, outlet};
    set_valve_commands(ps, cmd);
  }
  // One pneumatic update followed by one physics step (§3.6 then §2.12).
  StepStatus advance() {
    pneumatics_update(pm, ps, pscratch, state.pos, force);
    return step(model, state, scratch, force);
  }
};

PhysicsConfig free_floating() {
  PhysicsConfig c;
  c.gravity = 0.0;
  c.floor = false;
  return c;
}

double s3() {
  const double s = static_cast<double>(static_cast<float>(0.01));  // voxel size through a float
  return s * s * s;
}

}  // namespace

TEST(Pneumatics, MeshVolumesMatchTheWallCentreBoxes) {
  // §3.2: the mesh runs through wall-voxel centres, so a cavity of a x b x c cells encloses
  // (a+1)(b+1)(c+1) s^3 (one cell: 8 cm^3; two cells: 12 cm^3, §3.2).
  struct Case {
    std::array<int, 3> size, lo, hi;
    double cells;
  };
  const std::vector<Case> cases = {{{3, 3, 3}, {1, 1, 1}, {1, 1, 1}, 8.0},
                                   {{4, 3, 3}, {1, 1, 1}, {2, 1, 1}, 12.0},
                                   {{5, 4, 5}, {1, 1, 1}, {3, 2, 3}, 48.0}};
  for (const Case& c : cases) {
    const BodyPlan plan = box_with_cavity(c.size, c.lo, c.hi);
    const Model model = build_model(plan, PhysicsConfig{});
    const PneumaticsModel pm = build_pneumatics(plan, model, PneumaticsConfig{});
    ASSERT_EQ(pm.chamber_count, 1);
    EXPECT_EQ(pm.skipped_quads, 0);
    const State st = initial_state(model);
    const double expected = c.cells * s3();
    EXPECT_NEAR(chamber_volume(pm, 0, st.pos), expected, 1e-6 * expected)
        << "cavity " << c.hi[0] - c.lo[0] + 1 << "x" << c.hi[1] - c.lo[1] + 1 << "x"
        << c.hi[2] - c.lo[2] + 1;
    const PneumaticsState ps = initial_pneumatics_state(pm, st.pos);
    EXPECT_EQ(ps.quantity[0], ps.volume[0]);  // §3.3: n0 = V0 -> 1 bar
    EXPECT_FLOAT_EQ(ps.pressure[0], 1.0f);
  }
}

TEST(Pneumatics, VolumeIsTranslationInvariantAndScalesCubically) {
  const BodyPlan plan = box_with_cavity({4, 3, 3}, {1, 1, 1}, {2, 1, 1});
  const Model model = build_model(plan, PhysicsConfig{});
  const PneumaticsModel pm = build_pneumatics(plan, model, PneumaticsConfig{});
  const State st = initial_state(model);
  const double v0 = chamber_volume(pm, 0, st.pos);
  std::vector<Vec3> moved = st.pos, scaled = st.pos;
  for (auto& p : moved) p += Vec3(0.3, -1.2, 0.05);
  for (auto& p : scaled) p *= 1.1;
  EXPECT_NEAR(chamber_volume(pm, 0, moved), v0, 1e-6 * v0);
  EXPECT_NEAR(chamber_volume(pm, 0, scaled), v0 * 1.331, 1e-6 * v0);
}

TEST(Pneumatics, SealedChamberConservesGasAndObeysBoyle) {
  // Valves closed from the start: the filter input is 0 and its state starts at 0, so no gas
  // moves. An initial overpressure of 10 % makes the walls move (V changes), with gravity and
  // floor on.
  Scene sc(box_with_cavity({3, 3, 3}, {1, 1, 1}, {1, 1, 1}), PhysicsConfig{});
  sc.valves(0.0f, 0.0f);
  sc.ps.quantity[0] = 1.1f * sc.ps.volume[0];
  const float n0 = sc.ps.quantity[0];
  float v_min = 1e9f, v_max = 0.0f;
  for (int i = 0; i < 3000; ++i) {
    const float v_now = chamber_volume(sc.pm, 0, sc.state.pos);
    ASSERT_EQ(sc.advance(), StepStatus::ok) << "step " << i;
    ASSERT_EQ(sc.ps.quantity[0], n0) << "gas quantity changed at step " << i;  // exactly
    EXPECT_EQ(sc.ps.volume[0], v_now);  // V of this update is the volume of the current pose
    const double pv = static_cast<double>(sc.ps.pressure[0]) * sc.ps.volume[0];
    ASSERT_NEAR(pv, n0, 1e-6 * n0) << "p V != n at step " << i;
    v_min = std::min(v_min, v_now);
    v_max = std::max(v_max, v_now);
  }
  EXPECT_GT(v_max / v_min, 1.001f) << "walls did not move: the test would be trivial";
}

TEST(Pneumatics, InletRaisesPressureMonotonicallyOnStaticWalls) {
  // Static geometry: with the inlet open, gas only flows in while p < 1.2 bar and V is fixed,
  // so p must never fall. Then a chamber filled to 1.2 bar with only the outlet commanded open
  // falls back to 1.0 bar, never rising. (Switching the inlet off right after filling would let
  // the 4-stage low-pass ring: the inlet reopens by a tiny amount ~0.1 s after the switch.)
  const BodyPlan plan = box_with_cavity({5, 4, 5}, {1, 1, 1}, {3, 2, 3});
  const Model model = build_model(plan, PhysicsConfig{});
  const PneumaticsModel pm = build_pneumatics(plan, model, PneumaticsConfig{});
  const State st = initial_state(model);
  PneumaticsState ps = initial_pneumatics_state(pm, st.pos);
  PneumaticsScratch scratch = make_pneumatics_scratch(pm);
  std::vector<Vec3> force(static_cast<std::size_t>(model.voxel_count), Vec3::Zero());
  const int steps = static_cast<int>(0.5 / model.dt);
  const std::vector<float> inlet = {1.0f, 0.0f}, outlet = {0.0f, 1.0f};
  set_valve_commands(ps, inlet);
  float prev = 0.0f;
  for (int i = 0; i < steps; ++i) {
    pneumatics_update(pm, ps, scratch, st.pos, force);
    // (once p is within float round-off of the reservoir it may jitter by an ulp)
    if (1.2f - prev > 1e-6f) {
      ASSERT_GE(ps.pressure[0], prev) << "inlet: p fell at update " << i;
    }
    prev = ps.pressure[0];
  }
  EXPECT_NEAR(ps.pressure[0], 1.2f, 0.012f);  // within 1 % of 1.2 bar
  ps = initial_pneumatics_state(pm, st.pos);
  ps.quantity[0] = 1.2f * ps.volume[0];
  set_valve_commands(ps, outlet);
  prev = 1.2f;
  for (int i = 0; i < steps; ++i) {
    pneumatics_update(pm, ps, scratch, st.pos, force);
    if (prev - 1.0f > 1e-6f) {
      ASSERT_LE(ps.pressure[0], prev) << "outlet: p rose at update " << i;
    }
    prev = ps.pressure[0];
  }
  EXPECT_NEAR(ps.pressure[0], 1.0f, 0.010f);  // within 1 % of 1.0 bar
}

TEST(Pneumatics, InletInflatesMovingWallsToSupplyThenOutletReleasesIt) {
  // With moving walls (gravity and floor on) the expanding chamber can dip p for a few steps;
  // the gas quantity, however, only grows while the inlet is open, and the pressure settles
  // within 1 % of the reservoir. (After the switch the inlet's low-pass closes over ~0.1 s
  // while the outlet opens, so gas may still enter for a while: only the settling is checked.)
  for (const char* integrator : {"pneuvox", "symplectic"}) {
    PhysicsConfig phys;
    phys.integrator = parse_choice<Integrator>(integrator, "integrator");
    Scene sc(box_with_cavity({5, 4, 5}, {1, 1, 1}, {3, 2, 3}), phys);
    const int steps = static_cast<int>(0.5 / sc.model.dt);
    const float v0 = sc.ps.volume[0];
    sc.valves(1.0f, 0.0f);
    float prev = sc.ps.quantity[0];
    for (int i = 0; i < steps; ++i) {
      ASSERT_EQ(sc.advance(), StepStatus::ok);
      ASSERT_GE(sc.ps.quantity[0], prev) << integrator << ": inlet: gas left at step " << i;
      prev = sc.ps.quantity[0];
    }
    EXPECT_NEAR(sc.ps.pressure[0], 1.2f, 0.012f) << integrator;
    EXPECT_NEAR(chamber_pressure_pa(sc.ps, 0), 1.2e5, 1.2e3) << integrator;  // Pa accessor
    EXPECT_GT(sc.ps.volume[0], v0) << integrator << ": the chamber did not expand";
    sc.valves(0.0f, 1.0f);
    for (int i = 0; i < steps; ++i) ASSERT_EQ(sc.advance(), StepStatus::ok);
    EXPECT_NEAR(sc.ps.pressure[0], 1.0f, 0.010f) << integrator;
  }
}

TEST(Pneumatics, BothValvesOpenSettleHalfway) {
  // Equal conductances to 1.2 and 1.0 bar: steady state c (p - 1.2) + c (p - 1.0) = 0 -> 1.1 bar.
  Scene sc(box_with_cavity({5, 4, 5}, {1, 1, 1}, {3, 2, 3}), PhysicsConfig{});
  sc.valves(1.0f, 1.0f);
  for (int i = 0; i < static_cast<int>(0.5 / sc.model.dt); ++i)
    ASSERT_EQ(sc.advance(), StepStatus::ok);
  EXPECT_NEAR(sc.ps.pressure[0], 1.1f, 1e-3f);
}

TEST(Pneumatics, ValveLowPassStartsClosedAndIsMinus12dBAtCutoff) {
  // Static geometry (no physics step): only the conduit filter matters here.
  const BodyPlan plan = box_with_cavity({3, 3, 3}, {1, 1, 1}, {1, 1, 1});
  const Model model = build_model(plan, PhysicsConfig{});
  const PneumaticsModel pm = build_pneumatics(plan, model, PneumaticsConfig{});
  const State st = initial_state(model);
  PneumaticsState ps = initial_pneumatics_state(pm, st.pos);
  PneumaticsScratch scratch = make_pneumatics_scratch(pm);
  std::vector<Vec3> force(static_cast<std::size_t>(model.voxel_count), Vec3::Zero());
  // §3.5: valves start open (1.0) but the filter state starts at 0: the opening ramps up.
  pneumatics_update(pm, ps, scratch, st.pos, force);
  EXPECT_LT(ps.openness[0], 1e-3f);
  // A 10 Hz sine through 4 Butterworth sections with cut-off 10 Hz: gain 0.707^4 = -12 dB.
  const double dt = model.dt, f = 10.0, amp = 0.4;
  const int settle = static_cast<int>(1.0 / dt), measure = static_cast<int>(0.5 / dt);
  float lo = 1.0f, hi = 0.0f;
  for (int i = 0; i < settle + measure; ++i) {
    const float u = static_cast<float>(0.5 + amp * std::sin(2.0 * std::numbers::pi * f * i * dt));
    const std::vector<float> cmd = {u, u};
    set_valve_commands(ps, cmd);
    pneumatics_update(pm, ps, scratch, st.pos, force);
    if (i >= settle) {
      lo = std::min(lo, ps.openness[0]);
      hi = std::max(hi, ps.openness[0]);
    }
  }
  const double gain = 0.5 * (hi - lo) / amp;
  EXPECT_NEAR(gain, std::pow(0.707, 4), 0.005);
  EXPECT_NEAR(0.5 * (hi + lo), 0.5, 0.005);  // DC gain 1
}

TEST(Pneumatics, PressureForcesPushWallsOutwardWithFThirdPerVertex) {
  // One-cell cavity: the centre of the +z face (cell (1,1,2)) is the shared b/d corner of the
  // four quads of that face; at gauge pressure g the face (2s x 2s) carries g * 4 s^2 in total.
  const BodyPlan plan = box_with_cavity({3, 3, 3}, {1, 1, 1}, {1, 1, 1});
  const Model model = build_model(plan, PhysicsConfig{});
  const PneumaticsModel pm = build_pneumatics(plan, model, PneumaticsConfig{});
  const State st = initial_state(model);
  PneumaticsState ps = initial_pneumatics_state(pm, st.pos);
  PneumaticsScratch scratch = make_pneumatics_scratch(pm);
  std::vector<Vec3> force(static_cast<std::size_t>(model.voxel_count), Vec3::Zero());
  ps.quantity[0] = 1.1f * ps.volume[0];  // 0.1 bar gauge
  pneumatics_update(pm, ps, scratch, st.pos, force);
  const double s = model.voxel_size, gauge_pa = (ps.pressure[0] - 1.0f) * 1e5;
  Vec3 total_z_face = Vec3::Zero(), total = Vec3::Zero();
  for (int v = 0; v < model.voxel_count; ++v) {
    total += force[v];
    if (model.voxel_cell[v][2] == 2) total_z_face += force[v];
  }
  // Outward on the top face: +z; its in-plane parts cancel. Edge and corner voxels are shared
  // with the side faces, so compare the z component only.
  EXPECT_NEAR(total_z_face.z(), gauge_pa * 4.0 * s * s, 1e-4 * gauge_pa * 4.0 * s * s);
  EXPECT_NEAR(total.norm(), 0.0, 1e-5 * gauge_pa * s * s);  // closed mesh: no net force
  const int centre = model.cell_to_voxel[model.cell_index(1, 1, 2)];
  EXPECT_GT(force[centre].z(), 0.0);
}

// The mesh passes of pneumatics_update run W triangles at a time (volumes and pressure forces).
// At every SIMD width this CPU runs they give the bits of the one-triangle-at-a-time reference
// (chamber_volume and the §3.4 triangle formula summed in mesh order), on a randomly deformed
// two-chamber body (108 and 6 triangles: full groups and a tail).
TEST(Pneumatics, MeshPassesGiveTheReferenceBitsAtEverySimdWidth) {
  BodyPlan plan = box_with_cavity({7, 4, 4}, {1, 1, 1}, {2, 2, 2});
  plan.cells[plan.cell_index(6, 3, 3)] = kFirstChamberCell + 1;  // a corner cell: 3 quads
  const Model model = build_model(plan, PhysicsConfig{});
  PneumaticsModel pm = build_pneumatics(plan, model, PneumaticsConfig{});
  ASSERT_EQ(pm.chamber_count, 2);
  State st = initial_state(model);
  Rng rng(7);
  for (Vec3& p : st.pos)
    p += softevo::physics::test::random_vec3([&rng] { return rng.normal(); }) *
         (0.1 * model.voxel_size);
  const PneumaticsState start = initial_pneumatics_state(pm, st.pos);

  // reference: per chamber, p = n / V with n = 1.15 V0 (gauge > 0), forces triangle by triangle
  std::vector<float> ref_volume(2);
  std::vector<std::array<float, 3>> ref_slot(pm.wall_voxel.size(), {0.0f, 0.0f, 0.0f});
  for (int q = 0; q < 2; ++q) {
    const int triangles = pm.chamber_triangle_begin[q + 1] - pm.chamber_triangle_begin[q];
    EXPECT_EQ(triangles, q == 0 ? 108 : 6);  // 6: not a multiple of 4, the 4-lane pass has a tail
    ref_volume[q] = chamber_volume(pm, q, st.pos);
    const float gauge = (1.15f * start.volume[q]) / ref_volume[q] - 1.0f;
    for (int t = pm.chamber_triangle_begin[q]; t < pm.chamber_triangle_begin[q + 1]; ++t) {
      const auto& tri = pm.triangle_voxels[t];
      const Point3<double> f3 = triangle_force_third<ScalarTriangleOps>(
          to_point3(st.pos[tri[0]]), to_point3(st.pos[tri[1]]), to_point3(st.pos[tri[2]]),
          static_cast<double>(gauge));
      for (int v : pm.triangle_slots[t])
        for (int c = 0; c < 3; ++c) ref_slot[v][c] += static_cast<float>((&f3.x)[c]);
    }
  }
  int widths = 0;
  for (Simd simd : simd_widths()) {
    if (!simd_supported(simd)) continue;
    ++widths;
    pm.simd = simd;
    PneumaticsState ps = start;
    for (int q = 0; q < 2; ++q) ps.quantity[q] = 1.15f * start.volume[q];
    PneumaticsScratch scratch = make_pneumatics_scratch(pm);
    std::vector<Vec3> force(static_cast<std::size_t>(model.voxel_count), Vec3::Zero());
    pneumatics_update(pm, ps, scratch, st.pos, force);
    for (int q = 0; q < 2; ++q) EXPECT_EQ(ps.volume[q], ref_volume[q]) << to_string(simd);
    double largest = 0.0;
    for (std::size_t w = 0; w < pm.wall_voxel.size(); ++w) {
      const Vec3& f = force[pm.wall_voxel[w]];
      for (int c = 0; c < 3; ++c) {
        EXPECT_EQ(f[c], static_cast<double>(ref_slot[w][c])) << to_string(simd) << " slot " << w;
        largest = std::max(largest, std::fabs(f[c]));
      }
    }
    EXPECT_GT(largest, 1.0) << "forces of a 0.15 bar gauge pressure on 1 cm^2 faces [N]";
  }
  EXPECT_GE(widths, 2);  // the 1-lane passes and those of this architecture
}

TEST(Pneumatics, SensorNormalisation) {
  EXPECT_FLOAT_EQ(pressure_sensor_input(1.0f), -1.0f);
  EXPECT_NEAR(pressure_sensor_input(1.1f), 1.0f, 1e-5f);
  EXPECT_NEAR(pressure_sensor_input(1.2f), 3.0f, 1e-5f);  // not clipped (§3.7)
  EXPECT_FLOAT_EQ(pressure_sensor_input(0.0f), -21.0f);   // first-frame reading of 0 bar
}

TEST(Pneumatics, FreeFloatingInflatingBodyKeepsZeroLinearMomentum) {
  // No gravity, no floor: pressure forces over a closed mesh and beam forces are internal, so
  // the total linear momentum must stay at round-off level while individual voxels move. The
  // forces are float (as the reference's External force), so "round-off" is float round-off of
  // the applied impulses: compare with 1e-6 x the summed magnitude of all pressure impulses.
  for (const char* integrator : {"pneuvox", "symplectic"}) {
    PhysicsConfig phys = free_floating();
    phys.integrator = parse_choice<Integrator>(integrator, "integrator");
    Scene sc(box_with_cavity({5, 4, 5}, {1, 1, 1}, {3, 2, 3}), phys);
    sc.valves(1.0f, 0.0f);
    const Vec3 com0 = centre_of_mass(sc.model, sc.state);
    double max_voxel_momentum = 0.0, max_total = 0.0, impulse = 0.0, max_disp = 0.0;
    for (int i = 0; i < 3000; ++i) {
      ASSERT_EQ(sc.advance(), StepStatus::ok);
      for (const Vec3& f : sc.force) impulse += f.norm() * sc.model.dt;
      for (const Vec3& p : sc.state.lin_mom)
        max_voxel_momentum = std::max(max_voxel_momentum, p.norm());
      max_total = std::max(max_total, total_linear_momentum(sc.model, sc.state).norm());
    }
    const State st0 = initial_state(sc.model);
    for (int v = 0; v < sc.model.voxel_count; ++v)
      max_disp = std::max(max_disp, (sc.state.pos[v] - st0.pos[v]).norm());
    EXPECT_GT(sc.ps.pressure[0], 1.1f) << integrator;  // it did inflate
    EXPECT_GT(max_disp, 1e-4) << integrator << ": walls did not move (trivial test)";  // [m]
    EXPECT_LT(max_total, 1e-6 * impulse)
        << integrator << ": total linear momentum " << max_total << " kg m/s, pressure impulses "
        << impulse << " N s, largest voxel momentum " << max_voxel_momentum;
    // The centre of mass integrates the round-off momentum: float forces (relative precision
    // 6e-8) accumulated over 3000 steps as a random walk give ~sqrt(3000) x 6e-8 = 3e-6 of the
    // wall displacement; allow 1e-5 (a real momentum leak would be of order 1).
    EXPECT_LT((centre_of_mass(sc.model, sc.state) - com0).norm(), 1e-5 * max_disp) << integrator;
  }
}

// ---- §3.8 supply pressure scaling --------------------------------------------------------------

namespace {

PneumaticsConfig inverse_volume(double reference_volume, double max_supply_bar = 2.0) {
  PneumaticsConfig c;
  c.supply_pressure_scaling = SupplyScaling::inverse_volume;
  c.scaling_reference_volume = reference_volume;
  c.max_supply_pressure = max_supply_bar * kPascalPerBar;
  return c;
}

}  // namespace

TEST(SupplyScaling, NoneGivesEveryChamberTheConfiguredSupplyBits) {
  const BodyPlan plan = box_with_cavity({5, 4, 5}, {1, 1, 1}, {3, 2, 3});
  const Model model = build_model(plan, PhysicsConfig{});
  const PneumaticsModel pm = build_pneumatics(plan, model, PneumaticsConfig{});
  ASSERT_EQ(pm.chamber_supply_bar.size(), 1u);
  EXPECT_EQ(pm.chamber_supply_bar[0], 1.2f);
  EXPECT_EQ(pm.reservoir_bar(0), 1.2f);
  EXPECT_EQ(pm.reservoir_bar(1), 1.0f);
}

TEST(SupplyScaling, HandComputedPressures) {
  // p_in = min(p_a + (p_s - p_a) V_ref / V0, p_max), §3.8; defaults p_s = 1.2 bar, p_a = 1.0 bar.
  const double v_ref = kThesisMedianChamberVolume;
  const PneumaticsConfig c = inverse_volume(v_ref);
  EXPECT_EQ(chamber_supply_pressure(c, v_ref), 1.2e5);             // the median chamber: 1.2 bar
  EXPECT_DOUBLE_EQ(chamber_supply_pressure(c, v_ref / 2), 1.4e5);  // half volume: 2 x 0.2 bar gauge
  EXPECT_DOUBLE_EQ(chamber_supply_pressure(c, 2 * v_ref), 1.1e5);  // double volume: 0.1 bar gauge
  EXPECT_DOUBLE_EQ(chamber_supply_pressure(c, v_ref / 5), 2.0e5);  // exactly at the 2 bar cap
  EXPECT_EQ(chamber_supply_pressure(c, v_ref / 50), 2.0e5);        // far below: the cap holds
  EXPECT_EQ(chamber_supply_pressure(inverse_volume(v_ref, 1.5), v_ref / 4), 1.5e5);
  PneumaticsConfig none;
  EXPECT_EQ(chamber_supply_pressure(none, v_ref / 50), 1.2e5);
}

TEST(SupplyScaling, BuiltChambersGetTheirScaledSupply) {
  // One 1-cell chamber (8 s^3) and one 2x2x2-cell chamber (27 s^3), reference 27 s^3: the small
  // chamber gets 1.0 + 0.2 x 27/8 = 1.675 bar, the large one 1.2 bar.
  BodyPlan plan = box_with_cavity({7, 4, 4}, {1, 1, 1}, {1, 1, 1});
  for (int x = 3; x <= 4; ++x)
    for (int y = 1; y <= 2; ++y)
      for (int z = 1; z <= 2; ++z) plan.cells[plan.cell_index(x, y, z)] = kFirstChamberCell + 1;
  const Model model = build_model(plan, PhysicsConfig{});
  const PneumaticsModel probe = build_pneumatics(plan, model, PneumaticsConfig{});
  ASSERT_EQ(probe.chamber_count, 2);
  const double large = probe.rest_volume[1];
  EXPECT_NEAR(large, 27 * s3(), 1e-6 * large);
  const PneumaticsModel pm = build_pneumatics(plan, model, inverse_volume(large));
  EXPECT_EQ(pm.chamber_supply_bar[1], 1.2f);
  EXPECT_FLOAT_EQ(pm.chamber_supply_bar[0],
                  static_cast<float>(1.0 + 0.2 * large / probe.rest_volume[0]));
  EXPECT_NEAR(pm.chamber_supply_bar[0], 1.675f, 1e-5f);
  EXPECT_EQ(pm.reservoir_bar(0), pm.chamber_supply_bar[0]);
  EXPECT_EQ(pm.reservoir_bar(2), pm.chamber_supply_bar[1]);

  // An open inlet fills the small chamber to its own supply (static walls: fixed volume).
  Scene scene(plan, free_floating(), inverse_volume(large));
  scene.valves(1.0f, 0.0f);
  const std::vector<Vec3> rest = scene.state.pos;
  for (int i = 0; i < 20000; ++i)
    pneumatics_update(scene.pm, scene.ps, scene.pscratch, rest, scene.force);
  EXPECT_NEAR(scene.ps.pressure[0], pm.chamber_supply_bar[0], 1e-4f);
}

TEST(SupplyScaling, ReferenceVolumeIsTheMedianOfTheThesisChampionsChambers) {
  // The default scaling_reference_volume: every chamber of the 40 champions, rest volume by the
  // code of §3.2 at the initial positions, pooled; the median (odd count: the middle one).
  const std::filesystem::path dir = softevo::test::reference_bestbots();
  if (!std::filesystem::is_directory(dir))
    GTEST_SKIP() << "thesis champions not found at " << dir << " (../shared/reference)";
  std::vector<std::pair<double, float>> volumes;  // rest volume [m^3], scaled supply [bar]
  int robots = 0;
  for (const auto& entry : std::filesystem::directory_iterator(dir)) {
    if (!entry.path().string().ends_with(".robot.json")) continue;
    const RobotFile robot = read_robot_file(entry.path().string());
    const Model model = build_model(robot.body, PhysicsConfig{});
    const PneumaticsModel pm =
        build_pneumatics(robot.body, model, inverse_volume(kThesisMedianChamberVolume));
    for (int q = 0; q < pm.chamber_count; ++q)
      volumes.emplace_back(pm.rest_volume[q], pm.chamber_supply_bar[q]);
    ++robots;
  }
  ASSERT_EQ(robots, 40);
  std::sort(volumes.begin(), volumes.end());
  const std::size_t n = volumes.size();
  ASSERT_EQ(n % 2, 1u);  // 57 chambers: the median is a chamber
  const double median = volumes[n / 2].first;
  std::printf("%zu chambers, %.17g .. %.17g m^3, median %.17g m^3\n", n, volumes.front().first,
              volumes.back().first, median);
  EXPECT_EQ(median, kThesisMedianChamberVolume);
  EXPECT_EQ(volumes[n / 2].second, 1.2f);  // the thesis' median chamber keeps 1.2 bar
  for (std::size_t i = 0; i < n / 2; ++i) EXPECT_GE(volumes[i].second, 1.2f);
  for (std::size_t i = n / 2 + 1; i < n; ++i) EXPECT_LT(volumes[i].second, 1.2f);
}
