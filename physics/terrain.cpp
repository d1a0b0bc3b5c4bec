// The ground under the robot (docs/model.md §2.8a). See terrain.hpp.
#include "physics/terrain.hpp"

#include <algorithm>
#include <random>
#include <stdexcept>

#include "physics/reproducible_math.hpp"

namespace softevo::physics {
namespace {

[[noreturn]] void fail(const std::string& message) {
  throw std::invalid_argument("terrain: " + message);
}

// GCC's (libstdc++ 11+) std::uniform_int_distribution draw from a 32-bit generator: Lemire's
// multiply-shift with rejection of the biased low products.
int uniform_int_gcc(std::mt19937& gen, int lo, int hi) {
  const auto range = static_cast<std::uint32_t>(hi - lo) + 1u;
  std::uint64_t product = static_cast<std::uint64_t>(gen()) * range;
  auto low = static_cast<std::uint32_t>(product);
  if (low < range) {
    const std::uint32_t threshold = (0u - range) % range;
    while (low < threshold) {
      product = static_cast<std::uint64_t>(gen()) * range;
      low = static_cast<std::uint32_t>(product);
    }
  }
  return lo + static_cast<int>(product >> 32);
}

constexpr double kRadiansPerDegree = 0x1.921fb54442d18p+1 / 180.0;

}  // namespace

std::array<int, kRowCount> reference_row_cells(int lattice_x, std::uint32_t seed) {
  std::mt19937 gen(seed);
  std::array<int, kRowCount> cells{};
  int x = lattice_x + kRowFirstOffsetCells;
  for (int r = 0; r < kRowCount; ++r) {
    cells[r] = x;
    x += uniform_int_gcc(gen, kRowGapMinCells, kRowGapMaxCells);
  }
  return cells;
}

Terrain make_terrain(const TerrainParams& params, const std::array<int, 3>& lattice,
                     double voxel_size) {
  Terrain t;
  t.kind = params.kind;
  t.params = params;
  t.voxel_size = voxel_size;
  const double s = voxel_size;
  const double front = (lattice[0] - 0.5) * s;  // the robot's front face at the start [m]
  switch (params.kind) {
    case TerrainKind::flat:
      break;
    case TerrainKind::rows: {
      const auto cells = reference_row_cells(lattice[0], static_cast<std::uint32_t>(params.seed));
      for (int r = 0; r < kRowCount; ++r) t.row_x[r] = cells[r] * s;
      t.row_y_min = (kRowYMinCell - 1) * s;
      t.row_y_max = (kRowYMaxCell + 1) * s;
      t.top = s;
      break;
    }
    case TerrainKind::bumps: {
      if (!(params.shape.amplitude >= 0.0) || !std::isfinite(params.shape.amplitude))
        fail("terrain.amplitude must be a finite number >= 0 [m]");
      if (!(params.shape.correlation_length > 0.0) ||
          !std::isfinite(params.shape.correlation_length))
        fail("terrain.correlation_length must be > 0 [m]");
      std::uint64_t key = params.seed;
      key = (key ^ (key >> 33)) * 0xFF51AFD7ED558CCDULL;
      t.noise_key = key ^ (key >> 33);
      t.inv_cell = 1.0 / params.shape.correlation_length;
      t.start_x = front + 0.5 * s;
      t.top = params.shape.amplitude;
      break;
    }
    case TerrainKind::steps:
      if (!(params.shape.step_height >= 0.0) || !std::isfinite(params.shape.step_height))
        fail("terrain.step_height must be a finite number >= 0 [m]");
      if (!(params.shape.step_spacing >= s) || !std::isfinite(params.shape.step_spacing))
        fail("terrain.step_spacing must be at least one voxel (" + std::to_string(s) + " m)");
      t.first_riser_x = front + params.shape.step_spacing - 0.5 * s;
      t.top = std::numeric_limits<double>::infinity();
      break;
    case TerrainKind::slope: {
      if (!(std::fabs(params.shape.slope_angle) < 80.0))
        fail("terrain.slope_angle must be in (-80, 80) deg");
      if (!(std::fabs(params.shape.slope_direction) <= 360.0))
        fail("terrain.slope_direction must be in [-360, 360] deg");
      double sin_a = 0.0, cos_a = 1.0;
      rmath::sincos(params.shape.slope_angle * kRadiansPerDegree, sin_a, cos_a);
      rmath::sincos(params.shape.slope_direction * kRadiansPerDegree, t.sin_dir, t.cos_dir);
      t.gradient = sin_a / cos_a;
      t.slope_nx = -sin_a * t.cos_dir;
      t.slope_ny = -sin_a * t.sin_dir;
      t.slope_nz = cos_a;
      // The incline starts at the footprint corner farthest along the uphill direction, so the
      // robot starts on flat ground.
      double start = -std::numeric_limits<double>::infinity();
      for (double cx : {-0.5 * s, front})
        for (double cy : {-0.5 * s, (lattice[1] - 0.5) * s})
          start = std::max(start, cx * t.cos_dir + cy * t.sin_dir);
      t.start_d = start;
      t.top = params.shape.slope_angle > 0.0 ? std::numeric_limits<double>::infinity() : 0.0;
      break;
    }
  }
  return t;
}

double terrain_height(const Terrain& t, double x, double y) {
  switch (t.kind) {
    case TerrainKind::flat:
      return 0.0;
    case TerrainKind::rows:
      if (y > t.row_y_min && y < t.row_y_max)
        for (double rx : t.row_x)
          if (std::fabs(x - rx) < t.voxel_size) return t.voxel_size;
      return 0.0;
    case TerrainKind::bumps:
      return terrain_detail::bumps_height(t, x, y).h;
    case TerrainKind::steps: {
      const double from_riser = x - t.first_riser_x;
      if (!(from_riser >= 0.0)) return 0.0;
      return (std::floor(from_riser / t.params.shape.step_spacing) + 1.0) *
             t.params.shape.step_height;
    }
    case TerrainKind::slope: {
      const double d = (x * t.cos_dir + y * t.sin_dir) - t.start_d;
      return d > 0.0 ? t.gradient * d : 0.0;
    }
  }
  return 0.0;
}

}  // namespace softevo::physics
