// Pneumatic chambers, conduits and valves of docs/model.md §3 (th555/pneuvox PV_Chamber,
// PV_Pneunet, PV_Conduit, PV_Valve, Biquad), split like the voxel physics:
//  - PneumaticsModel: immutable chamber meshes (triangles through wall-voxel centres, §3.1),
//    reservoir pressures, conductivity and the valve low-pass coefficients;
//  - PneumaticsState: what changes (gas quantity, volume, pressure, valve and conduit values,
//    biquad filter memory); copyable with `=`;
//  - PneumaticsScratch: the float force accumulator of the wall voxels, allocated once.
//
// Precision follows the reference: the gas model is float32 (n, V, p, conductivity, transfer),
// the volume and pressure-force geometry is double with float accumulation, the biquad keeps a
// double state with float input/output (§3.2-3.5, §1). Pressures are in bar inside this
// module (the reference's unit; n is "m^3 at 1 bar"); the config boundary and the accessors
// below speak Pa.
//
// One physics step (§3.6): pneumatics_update(model, pstate, scratch, positions, ext_force), then
// physics::step(..., ext_force). The controller sets the valve commands once per control frame
// with set_valve_commands().
#pragma once

#include <array>
#include <cstdint>
#include <span>
#include <vector>

#include <Eigen/Core>

#include "common/body_plan.hpp"
#include "common/config.hpp"
#include "physics/model.hpp"
#include "physics/quat.hpp"

namespace softevo::physics {

inline constexpr double kPascalPerBar = 1.0e5;  // [Pa/bar]

// One second-order low-pass section (normalised coefficients of §3.5, transposed direct form II).
struct BiquadCoeffs {
  double a0 = 0.0, a1 = 0.0, a2 = 0.0;  // feed-forward [-]
  double b1 = 0.0, b2 = 0.0;            // feedback [-]
};

// §3.5: low-pass biquad for normalised cut-off fc = f_c / f_sample and quality factor q:
// K = tan(pi fc); norm = 1/(1 + K/Q + K^2); a0 = K^2 norm; a1 = 2 a0; a2 = a0;
// b1 = 2 (K^2 - 1) norm; b2 = (1 - K/Q + K^2) norm.
BiquadCoeffs lowpass_biquad(double normalised_cutoff, double q);

struct PneumaticsModel {
  int chamber_count = 0;
  int valve_count = 0;    // = conduit count = 2 * chambers: [in_0, out_0, in_1, out_1, ...] (§3.5)
  int filter_stages = 4;  // biquad sections in series per conduit (§3.5)

  // ---- meshes (§3.1): quad (a,b,c,d) -> triangles (a,b,c), (c,d,a); normals point inwards ----
  // Triangle vertices as wall slots (index into wall_voxel), chamber by chamber, quad order.
  std::vector<std::array<int, 3>> triangle_slots;  // (triangles)
  // The same vertices as voxel ids (= wall_voxel of the slots), so the mesh passes read
  // positions without a second indirection.
  std::vector<std::array<int, 3>> triangle_voxels;  // (triangles)
  std::vector<int> chamber_triangle_begin;          // CSR (chambers + 1) into triangle_slots
  // Unique wall voxels over all chambers, in order of first use; a voxel shared by two chambers
  // has one slot and accumulates both chambers' forces (§3.6 step 1).
  std::vector<int> wall_voxel;  // voxel id (wall slots)
  // The triangles with a vertex at each wall slot, ascending (the order in which the reference
  // adds their forces to the slot): CSR, slot s = slot_triangles[slot_triangle_begin[s] ..
  // slot_triangle_begin[s + 1]).
  std::vector<int> slot_triangle_begin;  // (wall slots + 1)
  std::vector<int> slot_triangles;       // (3 x triangles)
  int skipped_quads = 0;                 // quads with a corner that is not a voxel (§3.1: skipped)

  // ---- gas and conduits (reference units: bar, m^3 "at 1 bar", s) ----------------------------
  float supply_bar = 1.2f;   // configured inlet reservoir, absolute [bar]
  float ambient_bar = 1.0f;  // outlet reservoir, absolute [bar]
  // Inlet reservoir of each chamber, absolute [bar] (chambers): supply_bar for every chamber
  // unless pneumatics.supply_pressure_scaling scales it by the rest volume (§3.8).
  std::vector<float> chamber_supply_bar;
  std::vector<float> rest_volume;  // V0 of each chamber at the initial positions [m^3] (chambers)
  float conductivity = 0.025f;     // conduit conductivity scale [m^3/(bar s)] (§3.5)
  float dt_f = 0.0f;               // physics time step as float [s]
  BiquadCoeffs filter;             // one section of the valve low-pass (f_c = valve_cutoff at 1/dt)
  // SIMD width of the mesh passes (volumes, pressure forces): the model's, never `best`.
  // Results do not depend on it.
  Simd simd = Simd::scalar;

  // External reservoir pressure of conduit k (even = inlet/supply, odd = outlet/ambient) [bar].
  float reservoir_bar(int conduit) const {
    return (conduit & 1) == 0 ? chamber_supply_bar[conduit >> 1] : ambient_bar;
  }
};

struct PneumaticsState {
  std::vector<float> quantity;       // n, gas quantity as volume at 1 bar [m^3] (chambers)
  std::vector<float> volume;         // V of the last update, >= 1e-12 [m^3] (chambers)
  std::vector<float> pressure;       // p = n/V of the last update, absolute [bar] (chambers)
  std::vector<float> valve_state;    // commanded opening in [0,1] (valves), initially 1 (§3.5)
  std::vector<float> valve_applied;  // last state passed to the conduit (valves), initially 1
  std::vector<float> conduit_open;   // conduit "open" input of the filter (valves), initially 1
  std::vector<float> openness;       // filtered, clipped opening of the last update (valves)
  std::vector<double> filter_z;      // biquad memory (valves x stages x {z1, z2}), initially 0
  std::uint64_t updates = 0;         // pneumatic updates performed (= physics steps)
};

// The pressure force share F/3 of each triangle [N], as the floats (x, y, z, 0) (the reference's
// External force is a float vector, §3.4), so that one 4-float vector add performs the three
// float additions of a share to a wall slot. Allocated once.
struct PneumaticsScratch {
  std::vector<std::array<float, 4>> triangle_force;  // [N] (triangles); [3] unused, 0
};

// Build the chamber meshes of `plan` (quads of §6.7 from common/chamber_quads.hpp) on the voxels
// of `model`, and the conduit constants of `cfg` (pressures in Pa -> bar). Throws
// std::invalid_argument for a plan that does not match the model or bad config values.
PneumaticsModel build_pneumatics(const BodyPlan& plan, const Model& model,
                                 const PneumaticsConfig& cfg);

// §3.8: inlet pressure of a chamber of rest volume `rest_volume` [m^3], absolute [Pa]. "none":
// supply_pressure. "inverse_volume": the gauge pressure above ambient scales with V_ref / V0,
//   p_in = min(p_a + (p_s - p_a) V_ref / V0, p_max),
// with p_s = supply_pressure, p_a = ambient_pressure, V_ref = scaling_reference_volume and
// p_max = max_supply_pressure.
double chamber_supply_pressure(const PneumaticsConfig& cfg, double rest_volume);

// Initial state (§3.3): V0 from `positions` (normally initial_state(model).pos), n0 = V0 so that
// p = 1 bar; valves and conduits open (1.0), filter memory zero (§3.5).
PneumaticsState initial_pneumatics_state(const PneumaticsModel& pm,
                                         std::span<const Vec3> positions);

PneumaticsScratch make_pneumatics_scratch(const PneumaticsModel& pm);

// Chamber volume of §3.2 for the current positions: signed tetrahedra against the first vertex
// of the first triangle, double products accumulated in a float, then max(V, 1e-12) [m^3].
float chamber_volume(const PneumaticsModel& pm, int chamber, std::span<const Vec3> positions);

// Valve commands of one control frame: commands[k] is the opening of valve k in [0,1]
// (k = 2q inlet, 2q+1 outlet of chamber q). Extra commands are ignored, missing valves keep
// their state.
void set_valve_commands(PneumaticsState& ps, std::span<const float> commands);

// One pneumatic update, before every physics step, in the order of §3.6:
//  1. clear the wall voxels' forces, recompute every chamber volume from `positions`;
//  2. valve pre-update: a changed valve state is passed to its conduit's "open" value;
//  3. per chamber: p = n/V and the pressure forces F = -n_hat (p - 1) area 1e5, F/3 per vertex;
//  4. per conduit (in_0, out_0, in_1, ...): 4-stage low-pass of "open", clip [0,1],
//     q = openness conductivity (p - p_ext) dt, n -= q (p from step 3 for both conduits).
// Writes the wall voxels' entries of `external_force` [N] (other entries are left untouched;
// the caller zeroes them once). No allocation.
void pneumatics_update(const PneumaticsModel& pm, PneumaticsState& ps, PneumaticsScratch& scratch,
                       std::span<const Vec3> positions, std::span<Vec3> external_force);

// Pressure of chamber q from the last update, absolute [Pa].
inline double chamber_pressure_pa(const PneumaticsState& ps, int chamber) {
  return static_cast<double>(ps.pressure[chamber]) * kPascalPerBar;
}

// §3.7: normalised sensor input for an absolute pressure [bar]: (p - 1) * 20 - 1 (float, not
// clipped; [1.0, 1.1] bar -> [-1, 1], 1.2 bar -> 3, 0 bar -> -21).
inline float pressure_sensor_input(float pressure_bar) {
  return (pressure_bar - 1.0f) * 20.0f - 1.0f;
}

}  // namespace softevo::physics
