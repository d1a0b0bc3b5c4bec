// The ground under the robot (docs/model.md §2.8a): flat, the reference's rows of fixed voxels, or
// a height field (random bumps, steps, a slope). Part of the immutable Model: built once per
// evaluation by make_terrain() from TerrainParams (which the worker resolves from the config and
// the evaluation's ids), never changed and never allocating during a step.
//
// Frame: the floor contact works on voxel centres (§2.8). The flat floor is z = 0 for a voxel
// centre, that is the ground surface lies half a voxel below the lowest centres. Every height
// here is in that centre frame: a raised feature of geometric height H (above the ground surface)
// is a floor height H for a centre, and a vertical face at x = a pushes a centre back from
// x = a - s/2 (the voxel's half size). Rows and steps are therefore boxes expanded by half a voxel.
//
// Reproducibility: terrain_contact() uses IEEE +, -, *, /, sqrt and floor only (no libm call
// whose bits could differ between machines), so every SIMD width, compiler and x86-64 / AArch64
// sees the same ground; the slope's sin / cos / tan are formed once at build time with
// physics/reproducible_math.hpp.
#pragma once

#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <string>
#include <vector>

#include "common/config.hpp"  // GroundKind, HeightfieldKind
#include "common/terrain_shape.hpp"

namespace softevo::physics {

enum class TerrainKind : std::uint8_t {
  flat = 0,   // the plane z = 0 (bit-identical to the floor before terrain existed)
  rows = 1,   // the thesis system's 10 rows of fixed voxels (docs/model.md §2.8a)
  bumps = 2,  // height field: smooth random bumps
  steps = 3,  // height field: a staircase rising along +x
  slope = 4,  // height field: an inclined plane in front of the robot
};
}  // namespace softevo::physics
template <>
struct softevo::ChoiceNames<softevo::physics::TerrainKind> {
  static constexpr std::array<const char*, 5> names = {"flat", "rows", "bumps", "steps", "slope"};
};
namespace softevo::physics {
// The ground of the config's terrain.kind and terrain.heightfield (docs/model.md §2.8a).
constexpr TerrainKind terrain_kind(GroundKind ground, HeightfieldKind heightfield) {
  switch (ground) {
    case GroundKind::flat:
      return TerrainKind::flat;
    case GroundKind::rows:
      return TerrainKind::rows;
    case GroundKind::heightfield:
      break;
  }
  switch (heightfield) {
    case HeightfieldKind::bumps:
      return TerrainKind::bumps;
    case HeightfieldKind::steps:
      return TerrainKind::steps;
    case HeightfieldKind::slope:
      break;
  }
  return TerrainKind::slope;
}

// What defines one evaluation's ground: the resolved config values and the seed derived for the
// evaluation (worker/terrain_seed). Recorded in traces so that a viewer can rebuild the ground.
struct TerrainParams {
  TerrainKind kind = TerrainKind::flat;
  std::uint64_t seed = 0;  // seed of this ground (bumps, rows)
  TerrainShape shape;      // the heightfield's numbers (common/terrain_shape.hpp)
};

// The thesis system's rows of fixed voxels (docs/model.md §2.8a), in lattice cells.
inline constexpr int kRowCount = 10;
inline constexpr int kRowFirstOffsetCells = 10;  // first row at x = lattice x extent + 10
inline constexpr int kRowGapMinCells = 5;        // next row 5 .. 20 cells further
inline constexpr int kRowGapMaxCells = 20;
inline constexpr int kRowYMinCell = -20;  // each row spans y = -20 .. 24 cells at z = 0
inline constexpr int kRowYMaxCell = 24;

// One contact query: penetration of a voxel centre into the ground surface along its normal,
// rounded to float as the reference's penetration (touching when >= 0; NaN never touches), and
// the unit normal pointing out of the ground. vertical = the normal is exactly +z (nx = ny = 0,
// nz = 1): the contact formulas then take the axis-aligned form of the flat floor.
// Against a vertical face (a row's side, a step's riser) a centre also touches the face:
// side_penetration >= 0 and the face's horizontal normal. The face pushes without friction (the
// voxel's one static-friction state belongs to the surface it stands on).
struct FloorContact {
  float penetration = -1.0f;  // [m]
  bool vertical = true;
  double nx = 0.0, ny = 0.0, nz = 1.0;
  float side_penetration = -1.0f;  // [m]
  double side_nx = 0.0, side_ny = 0.0;
  bool touches() const { return penetration >= 0 || side_penetration >= 0; }
};

struct Terrain {
  TerrainKind kind = TerrainKind::flat;
  TerrainParams params;
  // Highest floor height anywhere [m] (centre frame): a centre above it touches nothing, so the
  // passes skip the query (most voxels of a robot are above the ground's highest point).
  double top = 0.0;
  double voxel_size = 0.0;  // s [m]
  // bumps: value noise of cell size correlation_length, faded in over one cell from start_x
  std::uint64_t noise_key = 0;
  double inv_cell = 0.0;  // 1 / correlation_length [1/m]
  double start_x = 0.0;   // [m] the fade-in starts here (the robot's front face)
  // steps: centre-frame x of the first riser [m]
  double first_riser_x = 0.0;
  // slope: h = gradient * max(0, d - start_d), d = x cos(dir) + y sin(dir)
  double cos_dir = 1.0, sin_dir = 0.0;
  double start_d = 0.0;   // [m]
  double gradient = 0.0;  // tan(angle) [-]
  double slope_nx = 0.0, slope_ny = 0.0, slope_nz = 1.0;
  // rows: centre-frame x of each row's voxel centres [m], and the y span of the expanded boxes
  std::array<double, kRowCount> row_x{};
  double row_y_min = 0.0, row_y_max = 0.0;
};

// The x positions (lattice cells) of the reference's rows for a body lattice of `lattice_x`
// cells: std::mt19937 seeded with `seed`, gaps uniform in 5 .. 20 cells as GCC's
// std::uniform_int_distribution draws them (the reference was built with GCC; the draw is written
// out so that every standard library gives the same rows).
std::array<int, kRowCount> reference_row_cells(int lattice_x, std::uint32_t seed);

// The terrain of `params` for a body lattice of `lattice` cells and voxel size s [m]. Throws
// std::invalid_argument for a parameter out of range (each names the config key).
Terrain make_terrain(const TerrainParams& params, const std::array<int, 3>& lattice,
                     double voxel_size);

namespace terrain_detail {

// Uniform in [-1, 1) from the noise key and a grid corner.
[[gnu::always_inline]] inline double corner_value(std::uint64_t key, std::int64_t i,
                                                  std::int64_t j) {
  std::uint64_t z = key ^ (static_cast<std::uint64_t>(i) * 0x9E3779B97F4A7C15ULL) ^
                    (static_cast<std::uint64_t>(j) * 0xC2B2AE3D27D4EB4FULL);
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ULL;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBULL;
  z ^= z >> 31;
  return static_cast<double>(z >> 11) * 0x1p-52 - 1.0;
}
[[gnu::always_inline]] inline double smoothstep(double t) {
  return t * t * (3.0 - 2.0 * t);
}
[[gnu::always_inline]] inline double smoothstep_slope(double t) {
  return 6.0 * t * (1.0 - t);
}
// Beyond this |coordinate| [cells] the noise is flat: keeps the integer conversion defined for
// exploded (huge or non-finite) positions.
inline constexpr double kNoiseLimit = 0x1p40;

// Height-field contact: penetration (h - z) nz along the normal of the surface (-hx, -hy, 1)/len.
[[gnu::always_inline]] inline FloorContact height_field_contact(double h, double hx, double hy,
                                                                double z) {
  FloorContact c;
  if (hx == 0.0 && hy == 0.0) {
    c.penetration = static_cast<float>((h + 0.0) - z);  // + 0.0: h = -0 is the plane's +0
    return c;
  }
  const double inv_len = 1.0 / std::sqrt((hx * hx + hy * hy) + 1.0);
  c.vertical = false;
  c.nx = -hx * inv_len;
  c.ny = -hy * inv_len;
  c.nz = inv_len;
  c.penetration = static_cast<float>((h - z) * inv_len);
  return c;
}

// The bumps' height h [m] and its slope dh/dx, dh/dy [-] at (x, y): value noise (smoothstep
// interpolation of uniform corner values on a grid of cell size correlation_length) times the
// amplitude, faded in over one cell in front of the robot (flat where x <= start_x).
struct HeightSample {
  double h = 0.0, hx = 0.0, hy = 0.0;
};
[[gnu::always_inline]] inline HeightSample bumps_height(const Terrain& t, double x, double y) {
  const double u = x * t.inv_cell, v = y * t.inv_cell;
  const double ramp = (x - t.start_x) * t.inv_cell;
  if (!(ramp > 0.0) || !(std::fabs(u) < kNoiseLimit) || !(std::fabs(v) < kNoiseLimit)) return {};
  const double fu = std::floor(u), fv = std::floor(v);
  const auto i = static_cast<std::int64_t>(fu), j = static_cast<std::int64_t>(fv);
  const double tu = u - fu, tv = v - fv;
  const double v00 = corner_value(t.noise_key, i, j), v10 = corner_value(t.noise_key, i + 1, j);
  const double v01 = corner_value(t.noise_key, i, j + 1);
  const double v11 = corner_value(t.noise_key, i + 1, j + 1);
  const double su = smoothstep(tu), sv = smoothstep(tv);
  const double a = v00 + su * (v10 - v00), b = v01 + su * (v11 - v01);
  const double noise = a + sv * (b - a);
  const double noise_u = smoothstep_slope(tu) * ((v10 - v00) + sv * ((v11 - v01) - (v10 - v00)));
  const double noise_v = smoothstep_slope(tv) * (b - a);
  double fade = 1.0, fade_x = 0.0;  // [-], [1/m]
  if (ramp < 1.0) {
    fade = smoothstep(ramp);
    fade_x = smoothstep_slope(ramp) * t.inv_cell;
  }
  const double amp = t.params.shape.amplitude;
  return {amp * (fade * noise), amp * (fade_x * noise + fade * (noise_u * t.inv_cell)),
          amp * (fade * (noise_v * t.inv_cell))};
}

[[gnu::always_inline]] inline FloorContact bumps_contact(const Terrain& t, double x, double y,
                                                         double z) {
  const HeightSample s = bumps_height(t, x, y);
  return height_field_contact(s.h, s.hx, s.hy, z);
}

[[gnu::always_inline]] inline FloorContact slope_contact(const Terrain& t, double x, double y,
                                                         double z) {
  const double d = (x * t.cos_dir + y * t.sin_dir) - t.start_d;
  if (!(d > 0.0) || t.gradient == 0.0) return height_field_contact(0.0, 0.0, 0.0, z);
  const double h = t.gradient * d;
  FloorContact c;
  c.vertical = false;
  c.nx = t.slope_nx;
  c.ny = t.slope_ny;
  c.nz = t.slope_nz;
  c.penetration = static_cast<float>((h - z) * t.slope_nz);
  return c;
}

// A centre inside a raised box (expanded by half a voxel): the smaller of the top penetration
// and the side one decides which face it meets. On the top it stands on the box; at the side it
// stands on the ground below (`ground_pen`, a vertical normal) and the face pushes it back.
[[gnu::always_inline]] inline FloorContact box_contact(double top_pen, double side_pen,
                                                       double side_nx, double side_ny,
                                                       double ground_pen) {
  FloorContact c;
  if (top_pen <= side_pen) {
    c.penetration = static_cast<float>(top_pen);
    return c;
  }
  c.penetration = static_cast<float>(ground_pen);
  c.side_penetration = static_cast<float>(side_pen);
  c.side_nx = side_nx;
  c.side_ny = side_ny;
  return c;
}

[[gnu::always_inline]] inline FloorContact steps_contact(const Terrain& t, double x, double z) {
  const double spacing = t.params.shape.step_spacing, rise = t.params.shape.step_height;
  const double from_riser = x - t.first_riser_x;
  if (!(from_riser >= 0.0) || !(from_riser < kNoiseLimit * spacing))
    return height_field_contact(0.0, 0.0, 0.0, z);
  const double tread = std::floor(from_riser / spacing);  // 0 = first step
  const double h = (tread + 1.0) * rise;
  const double top_pen = h - z;
  // The riser of this step faces -x; a centre below the previous step's top can only leave
  // upwards (it is inside the stair below, not at the riser).
  const double below = tread * rise;  // the previous step's top
  const double side_pen =
      z >= below ? from_riser - tread * spacing : std::numeric_limits<double>::infinity();
  return box_contact(top_pen, side_pen, -1.0, 0.0, below - z);
}

[[gnu::always_inline]] inline FloorContact rows_contact(const Terrain& t, double x, double y,
                                                        double z) {
  const double s = t.voxel_size;
  if (z < s && y > t.row_y_min && y < t.row_y_max) {
    for (double rx : t.row_x) {
      const double dx = x - rx;
      if (!(std::fabs(dx) < s)) continue;
      const double side_x = s - std::fabs(dx);
      const double side_y = std::fmin(y - t.row_y_min, t.row_y_max - y);
      if (side_y < side_x)
        return box_contact(s - z, side_y, 0.0, y - t.row_y_min <= side_y ? -1.0 : 1.0, 0.0 - z);
      return box_contact(s - z, side_x, dx < 0.0 ? -1.0 : 1.0, 0.0, 0.0 - z);
    }
  }
  return height_field_contact(0.0, 0.0, 0.0, z);
}

}  // namespace terrain_detail

// The ground's contact with a voxel centre at (x, y, z) [m]. Flat: penetration (float)(0 - z)
// and normal +z, the bits of the floor before terrain (penetration of §2.8). Inline and without
// a libm call: it runs in every step pass (also compiled for AVX2 / AVX-512, see quat.hpp).
[[gnu::always_inline]] inline FloorContact terrain_contact(const Terrain& t, double x, double y,
                                                           double z) {
  switch (t.kind) {
    case TerrainKind::flat:
      break;
    case TerrainKind::rows:
      return terrain_detail::rows_contact(t, x, y, z);
    case TerrainKind::bumps:
      return terrain_detail::bumps_contact(t, x, y, z);
    case TerrainKind::steps:
      return terrain_detail::steps_contact(t, x, z);
    case TerrainKind::slope:
      return terrain_detail::slope_contact(t, x, y, z);
  }
  FloorContact c;
  c.penetration = static_cast<float>(0.0 - z);
  return c;
}

// Floor height under (x, y) for drawing and tests [m] (centre frame; for rows and steps the top
// of the expanded box): the z at which terrain_contact's penetration is 0 on a top face.
double terrain_height(const Terrain& t, double x, double y);

}  // namespace softevo::physics
