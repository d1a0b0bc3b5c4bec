// Immutable description of one simulated robot body: voxels, links, materials, constants.
//
// Built once from a BodyPlan + PhysicsConfig by build_model() and never changed afterwards (the
// MuJoCo split of docs/architecture.md §2): flat arrays indexed by voxel id or link id, cross
// references as integer ids / CSR offsets, no pointers. Everything that changes during a
// simulation lives in State (physics/state.hpp), per-step buffers in Scratch (physics/step.hpp).
//
// Precision follows the reference (docs/model.md §1, §2.1): the voxel size goes
// through a float, material constants are computed and stored in float32, positions and momenta
// are double. Float constants are kept as `float` members so that every product the reference
// does in float is done in float here too.
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <span>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include "common/body_plan.hpp"
#include "common/config.hpp"
#include "physics/quat.hpp"
#include "physics/terrain.hpp"

namespace softevo::physics {

// The integrator is the config's choice (common/config.hpp): pneuvox, the exact two-part fork
// step of §2.12-2.13, or symplectic, the upstream single-pass symplectic Euler of §2.9.
using softevo::Integrator;

// SIMD width of the step passes (physics/step_kernels.hpp). Every width gives bit-identical
// results (same IEEE operations per lane, on x86-64 and AArch64 alike); only the speed differs.
// `best` = the widest this CPU runs (resolved by build_model; Model::simd never holds `best`).
// A build contains the scalar passes and those of its architecture (simd_widths()).
enum class Simd : std::uint8_t {
  best = 0,
  sse2 = 1,    // 2 lanes, every x86-64 CPU
  avx2 = 2,    // 4 lanes, x86-64
  avx512 = 3,  // 4 lanes, x86-64, AVX-512VL encoding (32 vector registers)
  scalar = 4,  // 1 lane, any CPU: no instruction-set extension
  neon = 5,    // 2 lanes, every AArch64 CPU
};
}  // namespace softevo::physics
template <>
struct softevo::ChoiceNames<softevo::physics::Simd> {
  static constexpr std::array<const char*, 6> names = {"best",   "sse2",   "avx2",
                                                       "avx512", "scalar", "neon"};
};
namespace softevo::physics {
// The width named by to_string (best, sse2, avx2, avx512, scalar, neon), also one this build does
// not contain; nullopt for any other name.
std::optional<Simd> parse_simd(std::string_view name);
// The widths this build contains (never `best`), narrowest first; each runs where
// simd_supported() says so.
std::vector<Simd> simd_widths();
// "best" and the names of simd_widths(): the choices of the CLIs' --simd options.
std::vector<std::string> simd_names();
// True if this build contains the passes for `simd` and this CPU (and OS) can run them.
bool simd_supported(Simd simd);
// The widest supported width.
Simd best_simd();
// The width `simd` runs at: best_simd() for `best`, any other width unchanged.
Simd resolve_simd(Simd simd);

// Link axis; also the order of the per-axis permutation of §2.2.
enum class Axis : std::uint8_t { x = 0, y = 1, z = 2 };

// Per-voxel constants read together by the voxel passes (one cache line per voxel).
// All from the voxel's own material (§2.1, Appendix A); float as in the reference.
struct VoxelConst {
  float mass;           // m = rho s^3 [kg]
  float inv_mass;       // 1/m [1/kg]
  float inv_inertia;    // 1/I, I = m s^2/6 [1/(kg m^2)]
  float c_glob;         // zeta_glob * 2 sqrt(m E s) [N s/m]
  float c_glob_rot;     // zeta_glob * 2 sqrt(I E s^3) [N m s]
  float c_col;          // zeta_col * 2 sqrt(m E s) [N s/m]
  float k_pen;          // 2 E s [N/m]
  float gravity_force;  // -m g (z component) [N]
  float damp_base;      // 2 sqrt(m) zeta_int [sqrt(kg)]; /previous_dt = link damping multiplier
  float mu_static;      // [-]
  float mu_kinetic;     // [-]
  float pad = 0.0f;     // keeps the struct at 48 bytes
};

// Per-link beam constants (§2.1, link material of the two end materials, L = s, all float).
// Twelve floats, as VoxelConst: Model also keeps both by member (see Model).
struct LinkConst {
  float e_area;     // E_L (stress = E_L * strain, linear) [Pa]; sigma*A gives the axial force
  float area;       // A = s^2 (nu = 0) [m^2]
  float a2;         // E_L L^3 / 12 [N m]
  float b1;         // E_L L [N/m]
  float b2;         // E_L L^2 / 2 [N]
  float b3;         // E_L L^3 / 6 [N m]
  float sq_a1;      // sqrt(a1) [sqrt(N/m)]
  float sq_a2xip;   // sqrt(a2 L^2 / 6)
  float sq_b1;      // sqrt(b1)
  float sq_b2xfmp;  // sqrt(b2 L / 2)
  float sq_b3xip;   // sqrt(b3 L^2 / 6)
  float pad = 0.0f;
};

struct Model {
  // ---- configuration -------------------------------------------------------------------------
  Integrator integrator = Integrator::pneuvox;
  std::array<int, 3> lattice{0, 0, 0};  // body plan lattice X, Y, Z [cells]
  double voxel_size = 0.0;     // s = (double)(float)plan.voxel_size [m] (§1: through a float)
  float dt_f = 0.0f;           // time step as the float the reference passes around [s]
  double dt = 0.0;             // = dt_f: §2.14 recommended step x dt_fraction [s]
  bool floor = true;           // ground contact (voxel centres, §2.8)
  Terrain terrain;             // the ground's shape (§2.8a); flat = the plane z = 0
  bool self_collision = true;  // §2.10
  Simd simd = Simd::scalar;    // SIMD width of the step passes (never `best`)

  // ---- voxels (index = voxel id, insertion order x outer, y, z inner; §2.1, §5 step 4) -----
  int voxel_count = 0;
  std::vector<std::array<int, 3>> voxel_cell;  // lattice index (i,j,k) (voxels)
  std::vector<int> cell_to_voxel;              // (X*Y*Z) voxel id or -1; index = (x*Y + y)*Z + z
  std::vector<int> voxel_material;             // structural material id k = 1..K (voxels)
  std::vector<double> voxel_mass;              // [kg] (voxels), = VoxelConst::mass
  std::vector<VoxelConst> voxel_const;         // (voxels)
  // The same constants by member, for the lane passes (a group of consecutive voxels loads each
  // member with one vector load): voxel_const_members[j][v] = float member j of voxel v, stored
  // as the double it converts to (exact), so the passes load it without a conversion.
  std::array<std::vector<double>, 12> voxel_const_members;
  std::vector<std::uint8_t> voxel_fixed;    // 1 = all DOFs fixed (validation scenes) (voxels)
  std::vector<std::uint8_t> voxel_surface;  // 1 = fewer than 6 links (§2.1 "surface") (voxels)
  int free_voxel_count = 0;                 // voxels that are not fixed

  // ---- links (index = link id) ---------------------------------------------------------------
  // Ids run axis by axis (the x links, then y, then z), each axis in the creation order of §2.1.
  // The link pass handles one axis at a time with the §2.2 permutation fixed at compile time and
  // walks a contiguous id range. Links are independent within a pass (each writes only its own
  // state and end loads) and the voxel sums run in direction order, so the numbering gives the
  // same results as creation order.
  int link_count = 0;
  std::vector<int> link_neg;  // negative-end voxel N (lower lattice index along the axis)
  std::vector<int> link_pos;  // positive-end voxel P
  std::vector<Axis> link_axis;
  std::vector<LinkConst> link_const;
  // The same constants by member, for the lane passes: link_const_members[j][i] = float member j
  // of link i, as a double (exact; see voxel_const_members).
  std::array<std::vector<double>, 12> link_const_members;
  std::array<int, 4> axis_link_begin{0, 0, 0, 0};  // links of axis a: ids [begin[a], begin[a+1])
  double rest_length = 0.0;  // L = s for every link [m] (double, as Voxelyze's baseSize)
  // 1 / L [1/m], for the division-free mode test of the link passes (link_mode.hpp)
  double inv_rest_length = 0.0;

  // ---- voxel -> links, six direction slots X+, X-, Y+, Y-, Z+, Z- (§2.1) ----------------------
  // Slot d of voxel v = 2 * link + end (0: v is the negative end N, 1: v is the positive end P),
  // the index of that end's load in Scratch::link_end_load; a missing link is missing_load_slot(),
  // where Scratch keeps an always-zero end load, so the voxel passes sum six loads per voxel
  // without a data-dependent loop. Adding +0.0 never changes these sums: they start at +0.0, so a
  // partial sum is never -0.0 (round to nearest), and x + 0.0 = x otherwise.
  std::vector<std::array<int, 6>> voxel_load_slots;  // (voxels)
  int missing_load_slot() const { return 2 * link_count; }

  // ---- self-collision (§2.10) ------------------------------------------------------------------
  std::vector<int> surface_voxels;  // ids of surface voxels, ascending
  // Surface voxels within 5 link hops (the "nearby" list), as a bitmask over the 231 lattice
  // offsets with |di|+|dj|+|dk| <= 5 (4 words per voxel; bit = nearby_bit_of_offset()).
  std::vector<std::uint64_t> nearby_mask;  // (voxels x 4)
  double collision_watch_radius = 0.0;     // 2.5 s [m] (float as in the reference)
  double collision_recalc_distance = 0.0;  // 0.5 s [m] (float)

  int cell_index(int x, int y, int z) const { return (x * lattice[1] + y) * lattice[2] + z; }
};

// Lattice offset (di, dj, dk), each in -5..5, -> bit index 0..230 in Model::nearby_mask, or -1
// if |di|+|dj|+|dk| > 5; a compile-time constant table (the pair rebuild of §2.10 looks it up
// for every candidate pair, so it is inline here rather than behind a call).
struct NearbyOffsetTable {
  std::array<std::int16_t, 11 * 11 * 11> bit{};
  constexpr NearbyOffsetTable() {
    int next = 0;
    for (int di = -5; di <= 5; ++di)
      for (int dj = -5; dj <= 5; ++dj)
        for (int dk = -5; dk <= 5; ++dk) {
          const int hops = (di < 0 ? -di : di) + (dj < 0 ? -dj : dj) + (dk < 0 ? -dk : dk);
          bit[((di + 5) * 11 + (dj + 5)) * 11 + (dk + 5)] =
              static_cast<std::int16_t>(hops <= 5 ? next++ : -1);
        }
  }
};
inline constexpr NearbyOffsetTable kNearbyOffsetTable{};

// Lattice offset -> bit index 0..230 in Model::nearby_mask, or -1 if |di|+|dj|+|dk| > 5.
inline int nearby_bit_of_offset(int di, int dj, int dk) {
  if (di < -5 || di > 5 || dj < -5 || dj > 5 || dk < -5 || dk > 5) return -1;
  return kNearbyOffsetTable.bit[((di + 5) * 11 + (dj + 5)) * 11 + (dk + 5)];
}
// True if surface voxel b is in the "nearby" list of voxel a (within 5 link hops).
inline bool is_nearby(const Model& model, int a, int b) {
  const auto& ca = model.voxel_cell[a];
  const auto& cb = model.voxel_cell[b];
  const int bit = nearby_bit_of_offset(cb[0] - ca[0], cb[1] - ca[1], cb[2] - ca[2]);
  if (bit < 0) return false;
  return (model.nearby_mask[static_cast<std::size_t>(a) * 4 + (bit >> 6)] >> (bit & 63)) & 1u;
}

struct BuildOptions {
  // Lattice cells (x, y, z) whose voxel is fixed in place (all 6 DOFs; validation scenes).
  // Each must be a structural cell of the plan.
  std::vector<std::array<int, 3>> fixed_cells;
  // SIMD width of the step passes; a width this CPU cannot run is an error. Results do not
  // depend on it (tests and `softevo bench physics --simd` compare the widths).
  Simd simd = Simd::best;
  // The ground (§2.8a), laid out for this body's lattice; flat by default.
  TerrainParams terrain;
};

// Build the model of §2.1 / §5 step 4: one voxel per structural cell (1..K) in the order x outer,
// y, z inner; chamber (11+) and empty cells make no voxel; links between face-adjacent voxels.
// Throws std::invalid_argument with a reason for malformed plans or configs (unknown integrator,
// bad material id, non-positive sizes, dt_fraction <= 0, ...).
Model build_model(const BodyPlan& plan, const PhysicsConfig& cfg, const BuildOptions& options = {});

// §2.14 recommended time step (float arithmetic) of a built model, without dt_fraction.
float recommended_time_step(const Model& model);

}  // namespace softevo::physics
