// physics/terrain.hpp: the ground's shapes and their contact queries, the reference's row
// placement, and the flat-equivalent grounds that must keep the flat floor's bits.
#include "physics/terrain.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "physics/model.hpp"
#include "tests/physics/golden_scene.hpp"

namespace softevo::physics {
namespace {

constexpr double kS = 0.009999999776482582;  // the voxel size 0.01 through a float
const std::array<int, 3> kLattice{10, 10, 10};

// The rows draw their gaps as GCC's std::uniform_int_distribution(5, 20) on std::mt19937 does
// (the reference's build); written out, the draw gives those rows with any standard library.
TEST(Terrain, RowsFollowTheReferenceSeedingRule) {
  for (std::uint32_t seed : {1u, 2u, 12345u, 4294967295u}) {
    const auto cells = reference_row_cells(10, seed);
    EXPECT_EQ(cells[0], 20) << "first row at bbox_x + 10";
#ifdef __GLIBCXX__
    std::mt19937 gen(seed);
    std::uniform_int_distribution<int> gap(5, 20);
    int x = 20;
    for (int r = 0; r < kRowCount; ++r) {
      EXPECT_EQ(cells[r], x) << "seed " << seed << " row " << r;
      x += gap(gen);
    }
#endif
    for (int r = 1; r < kRowCount; ++r) {
      EXPECT_GE(cells[r] - cells[r - 1], 5);
      EXPECT_LE(cells[r] - cells[r - 1], 20);
    }
  }
}

TEST(Terrain, RowContactPicksTheNearestFace) {
  TerrainParams p;
  p.kind = TerrainKind::rows;
  p.seed = 1;
  const Terrain t = make_terrain(p, kLattice, kS);
  const double rx = t.row_x[0];
  // On top of the row: stands on it, normal +z, penetration s - z.
  FloorContact top = terrain_contact(t, rx, 0.0, kS - 1e-4);
  EXPECT_TRUE(top.vertical);
  EXPECT_FLOAT_EQ(top.penetration, 1e-4f);
  EXPECT_LT(top.side_penetration, 0.0f);
  // Against its -x side at ground level: stands on the ground, the face pushes along -x.
  FloorContact side = terrain_contact(t, rx - kS + 2e-4, 0.0, -1e-5);
  EXPECT_FLOAT_EQ(side.penetration, 1e-5f);
  EXPECT_FLOAT_EQ(side.side_penetration, 2e-4f);
  EXPECT_EQ(side.side_nx, -1.0);
  // Past its +y end: the end face pushes along +y.
  FloorContact end = terrain_contact(t, rx, t.row_y_max - 1e-4, 0.0);
  EXPECT_EQ(end.side_ny, 1.0);
  // Between rows: the flat floor.
  FloorContact gap = terrain_contact(t, rx + 2 * kS, 0.0, 1e-3);
  EXPECT_LT(gap.penetration, 0.0f);
  EXPECT_LT(gap.side_penetration, 0.0f);
  EXPECT_EQ(terrain_height(t, rx, 0.0), kS);
  EXPECT_EQ(terrain_height(t, rx + 2 * kS, 0.0), 0.0);
}

TEST(Terrain, BumpsAreSmoothBoundedAndFlatUnderTheRobot) {
  TerrainParams p;
  p.kind = TerrainKind::bumps;
  p.shape.amplitude = 0.01;
  p.shape.correlation_length = 0.05;
  p.seed = 99;
  const Terrain t = make_terrain(p, kLattice, kS);
  double highest = -1.0, lowest = 1.0;
  for (int i = 0; i < 400; ++i)
    for (int j = -50; j < 50; ++j) {
      const double x = 0.003 * i, y = 0.0037 * j;
      const double h = terrain_height(t, x, y);
      highest = std::max(highest, h);
      lowest = std::min(lowest, h);
      if (x <= t.start_x) {
        EXPECT_EQ(h, 0.0) << "under the robot's start at x " << x;
      }
      // The normal is the height field's: finite differences of h agree with it.
      const FloorContact c = terrain_contact(t, x, y, h);
      const double d = 1e-7;
      const double hx = (terrain_height(t, x + d, y) - terrain_height(t, x - d, y)) / (2 * d);
      const double hy = (terrain_height(t, x, y + d) - terrain_height(t, x, y - d)) / (2 * d);
      const double len = std::sqrt(1 + hx * hx + hy * hy);
      EXPECT_NEAR(c.nx, -hx / len, 1e-5);
      EXPECT_NEAR(c.ny, -hy / len, 1e-5);
      EXPECT_NEAR(std::hypot(c.nx, c.ny, c.nz), 1.0, 1e-12);
      EXPECT_NEAR(c.penetration, 0.0f, 1e-9f) << "on the surface";
    }
  EXPECT_LE(highest, p.shape.amplitude);
  EXPECT_GE(lowest, -p.shape.amplitude);
  EXPECT_GT(highest - lowest, p.shape.amplitude) << "bumps of about the amplitude";
  // Another seed, another ground.
  p.seed = 100;
  const Terrain other = make_terrain(p, kLattice, kS);
  EXPECT_NE(terrain_height(other, 0.4, 0.1), terrain_height(t, 0.4, 0.1));
  // Exploded positions see the flat floor instead of an undefined conversion.
  EXPECT_EQ(terrain_height(t, 1e300, 0.0), 0.0);
  EXPECT_TRUE(terrain_contact(t, std::nan(""), 0.0, -1e-3).touches());
  EXPECT_FALSE(terrain_contact(t, std::nan(""), 0.0, 1e-3).touches());
}

TEST(Terrain, SlopeRisesAtItsAngleInItsDirection) {
  TerrainParams p;
  p.kind = TerrainKind::slope;
  p.shape.slope_angle = 20.0;
  p.shape.slope_direction = 90.0;  // uphill along +y
  const Terrain t = make_terrain(p, kLattice, kS);
  const double y0 = t.start_d;  // the robot's far side along +y
  EXPECT_NEAR(y0, 9.5 * kS, 1e-12);
  EXPECT_EQ(terrain_height(t, 0.3, y0 - 1e-3), 0.0);
  EXPECT_NEAR(terrain_height(t, 0.3, y0 + 0.1), 0.1 * std::tan(20.0 * M_PI / 180.0), 1e-15);
  const FloorContact c = terrain_contact(t, 0.3, y0 + 0.1, 0.0);
  EXPECT_NEAR(c.nx, 0.0, 1e-15);
  EXPECT_NEAR(c.ny, -std::sin(20.0 * M_PI / 180.0), 1e-15);
  EXPECT_NEAR(c.nz, std::cos(20.0 * M_PI / 180.0), 1e-15);
  EXPECT_THROW(make_terrain(
                   [] {
                     TerrainParams q;
                     q.kind = TerrainKind::slope;
                     q.shape.slope_angle = 85.0;
                     return q;
                   }(),
                   kLattice, kS),
               std::invalid_argument);
}

// Grounds that are the plane z = 0 everywhere the scene goes, queried through terrain_contact
// (not the flat lanes): the golden scene keeps the flat floor's bits at every SIMD width and for
// both integrators, so the flat branch of the new contact is the old floor.
TEST(Terrain, FlatGroundThroughTheTerrainContactKeepsTheFlatBits) {
  TerrainParams zero_bumps;
  zero_bumps.kind = TerrainKind::bumps;
  zero_bumps.shape.amplitude = 0.0;
  zero_bumps.shape.correlation_length = 0.01;
  zero_bumps.seed = 5;
  TerrainParams level_slope;
  level_slope.kind = TerrainKind::slope;
  level_slope.shape.slope_angle = 0.0;
  TerrainParams flat_steps;
  flat_steps.kind = TerrainKind::steps;
  flat_steps.shape.step_height = 0.0;
  flat_steps.shape.step_spacing = 0.05;
  for (const char* integrator : {"pneuvox", "symplectic"}) {
    const std::uint64_t flat = golden::run_scene(integrator, Simd::scalar);
    for (Simd simd : simd_widths()) {
      if (!simd_supported(simd)) continue;
      EXPECT_EQ(golden::run_scene(integrator, simd), flat) << to_string(simd);
      for (const TerrainParams& t : {zero_bumps, level_slope, flat_steps})
        EXPECT_EQ(golden::run_scene(integrator, simd, golden::Motion::gentle, false, t), flat)
            << integrator << " " << to_string(simd) << " " << to_string(t.kind);
    }
  }
}

// A ground with bumps gives the same bits at every SIMD width (the terrain query runs per lane
// in scalar code with the same IEEE operations). The scene is moved onto the bumps.
TEST(Terrain, BumpyGroundIsTheSameAtEverySimdWidth) {
  TerrainParams bumps;
  bumps.kind = TerrainKind::bumps;
  bumps.shape.amplitude = 0.002;
  bumps.shape.correlation_length = 0.02;
  bumps.seed = 3;
  for (const char* integrator : {"pneuvox", "symplectic"}) {
    const double onto = 0.2;  // [m]
    const std::uint64_t scalar =
        golden::run_scene(integrator, Simd::scalar, golden::Motion::gentle, false, bumps, onto);
    EXPECT_NE(scalar,
              golden::run_scene(integrator, Simd::scalar, golden::Motion::gentle, false, {}, onto))
        << "the bumps matter";
    for (Simd simd : simd_widths()) {
      if (!simd_supported(simd)) continue;
      EXPECT_EQ(golden::run_scene(integrator, simd, golden::Motion::gentle, false, bumps, onto),
                scalar)
          << integrator << " " << to_string(simd);
    }
  }
}

}  // namespace
}  // namespace softevo::physics
