// physics/floor.hpp: the flat floor is the plane z = 0 with normal +z at every point, for one
// point (double) and for lanes (a vector of doubles), so a voxel's penetration height - z keeps
// the bits of the reference's 0.0 - z.
#include "physics/floor.hpp"

#include <gtest/gtest.h>

#include <bit>
#include <cmath>
#include <cstdint>
#include <limits>

namespace softevo::physics {
namespace {

constexpr double kPoints[][2] = {
    {0.0, 0.0}, {1.5, -2.25}, {-1e6, 3e5}, {1e-300, -0.0}, {123.456, 7.0}};

TEST(Floor, FlatFloorHasHeightZeroAndNormalPlusZ) {
  for (const auto& p : kPoints) {
    const FloorPoint<double> f = floor_at(p[0], p[1]);
    EXPECT_EQ(std::bit_cast<std::uint64_t>(f.height), 0u) << "height is +0 at " << p[0];
    EXPECT_EQ(f.normal_x, 0.0);
    EXPECT_EQ(f.normal_y, 0.0);
    EXPECT_EQ(f.normal_z, 1.0);
    EXPECT_DOUBLE_EQ(std::hypot(f.normal_x, f.normal_y, f.normal_z), 1.0);
  }
  // Non-finite positions (an exploded voxel) still see the same plane.
  const double inf = std::numeric_limits<double>::infinity();
  EXPECT_EQ(floor_at(inf, std::nan("")).height, 0.0);
}

// Penetration height - z is the reference's 0.0 - z, bit for bit, also for z = +0, -0 and NaN.
TEST(Floor, PenetrationKeepsTheReferenceBits) {
  for (double z : {0.0, -0.0, 1e-3, -1e-3, 5e-324, -5e-324, 2.5, std::nan("")}) {
    const double reference = 0.0 - z;
    const double penetration = floor_at(0.3, -0.7).height - z;
    EXPECT_EQ(std::bit_cast<std::uint64_t>(penetration), std::bit_cast<std::uint64_t>(reference))
        << "z = " << z;
  }
}

TEST(Floor, LanesSeeTheSameFloorInEveryLane) {
  using Lanes = double __attribute__((vector_size(16)));  // 2 lanes: SSE2 and NEON width
  const Lanes x{1.5, -1e6}, y{-2.25, 3e5};
  const FloorPoint<Lanes> f = floor_at(x, y);
  for (int k = 0; k < 2; ++k) {
    EXPECT_EQ(std::bit_cast<std::uint64_t>(f.height[k]), 0u) << "lane " << k;
    EXPECT_EQ(f.normal_x[k], 0.0);
    EXPECT_EQ(f.normal_y[k], 0.0);
    EXPECT_EQ(f.normal_z[k], 1.0);
  }
}

}  // namespace
}  // namespace softevo::physics
