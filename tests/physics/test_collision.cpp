// Voxel-voxel self-collision (docs/model.md §2.10): the grid broadphase produces exactly the
// reference's O(N^2) pair list, and the contact keeps a folding body's voxels apart.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <vector>

#include "common/rng.hpp"
#include "physics/model.hpp"
#include "physics/observables.hpp"
#include "physics/scenes.hpp"
#include "physics/step.hpp"
#include "tests/physics/random_vec3.hpp"

namespace softevo::physics {
namespace {

// The reference rule, written the slow way: pairs (a < b, list order) of surface voxels with
// |pos_a - pos_b|^2 <= (2.5 s)^2 (float threshold) that are more than 5 link hops apart
// (hop distance by a plain BFS here, independent of the model's bitmask).
std::vector<std::pair<int, int>> brute_force_pairs(const Model& m, const std::vector<Vec3>& pos) {
  const int n = m.voxel_count;
  std::vector<std::vector<int>> hops(n, std::vector<int>(n, 1 << 20));
  for (int src = 0; src < n; ++src) {
    std::vector<int> queue{src};
    hops[src][src] = 0;
    for (std::size_t h = 0; h < queue.size(); ++h) {
      const int u = queue[h];
      for (int l = 0; l < m.link_count; ++l) {
        int w = -1;
        if (m.link_neg[l] == u) w = m.link_pos[l];
        if (m.link_pos[l] == u) w = m.link_neg[l];
        if (w >= 0 && hops[src][w] > hops[src][u] + 1) {
          hops[src][w] = hops[src][u] + 1;
          queue.push_back(w);
        }
      }
    }
  }
  const float r = static_cast<float>(m.collision_watch_radius);
  const float r2 = r * r;
  std::vector<std::pair<int, int>> out;
  for (int a = 0; a < n; ++a) {
    if (!m.voxel_surface[a]) continue;
    for (int b = a + 1; b < n; ++b) {
      if (!m.voxel_surface[b]) continue;
      if ((pos[a] - pos[b]).squaredNorm() > r2) continue;
      if (hops[a][b] <= 5) continue;
      out.emplace_back(a, b);
    }
  }
  return out;
}

// A "hairpin": two 14-voxel arms along x (z = 0 and z = 2) joined at x = 13 by one voxel, soft
// (E = 10 kPa). Gravity folds the upper arm down onto the lower one, whose voxels are > 5 hops
// away (the link path goes round the joint).
BodyPlan hairpin() {
  BodyPlan plan = solid_block(14, 1, 3, 1.0e4);
  for (int x = 0; x < 13; ++x) plan.cells[plan.cell_index(x, 0, 1)] = kEmptyCell;
  return plan;
}

// Smallest centre distance between a voxel of the upper arm and one of the lower arm, in s.
double min_arm_distance(const Model& m, const State& st) {
  double best = 1e9;
  for (int a = 0; a < m.voxel_count; ++a) {
    if (m.voxel_cell[a][2] != 2 || m.voxel_cell[a][0] > 10) continue;
    for (int b = 0; b < m.voxel_count; ++b) {
      if (m.voxel_cell[b][2] != 0 || m.voxel_cell[b][0] > 10) continue;
      best = std::min(best, (st.pos[a] - st.pos[b]).norm() / m.voxel_size);
    }
  }
  return best;
}

double fold(bool collisions, const std::string& integrator, int& pairs_seen) {
  PhysicsConfig cfg;
  cfg.integrator = parse_choice<Integrator>(integrator, "integrator");
  cfg.self_collision = collisions;
  const Model m = build_model(hairpin(), cfg);
  State st = initial_state(m);
  Scratch sc = make_scratch(m);
  double closest = 1e9;
  pairs_seen = 0;
  for (int i = 0; i < 3000; ++i) {  // 1.5 s
    const StepStatus s = step(m, st, sc);
    if (s != StepStatus::ok) break;
    closest = std::min(closest, min_arm_distance(m, st));
    pairs_seen = std::max(pairs_seen, st.col_pair_count);
  }
  return closest;
}

class SelfCollision : public ::testing::TestWithParam<std::string> {};

TEST_P(SelfCollision, FoldingBodyStaysApart) {
  int pairs_on = 0, pairs_off = 0;
  const double with = fold(true, GetParam(), pairs_on);
  const double without = fold(false, GetParam(), pairs_off);
  std::printf(
      "[%s] hairpin fold: closest arm-to-arm centre distance %.3f s with self-collision "
      "(%d pairs max), %.3f s without\n",
      GetParam().c_str(), with, pairs_on, without);
  // Without collisions the arms pass into each other; with them the contact envelope
  // (D0 = 1.25 s) holds them apart.
  EXPECT_LT(without, 0.5);
  EXPECT_GT(with, 0.9);
  EXPECT_GT(pairs_on, 0);
  EXPECT_EQ(pairs_off, 0);
}

INSTANTIATE_TEST_SUITE_P(Integrators, SelfCollision, ::testing::Values("pneuvox", "symplectic"),
                         [](const auto& info) { return info.param; });

// The grid broadphase gives the same pairs in the same order as the O(N^2) scan, on a randomly
// deformed body (a 6x5x4 block with two holes, positions jittered by up to 0.8 s), and with the
// voxels scattered at random over a 15 s cube: about one voxel per grid cell, so that several
// cells share a hash bucket of the grid and the pairs cross between many cells.
TEST(SelfCollisionPairs, GridMatchesBruteForce) {
  BodyPlan plan = solid_block(6, 5, 4, 5.0e4);
  plan.cells[plan.cell_index(2, 2, 1)] = kEmptyCell;
  plan.cells[plan.cell_index(4, 1, 2)] = kEmptyCell;
  PhysicsConfig cfg;
  const Model m = build_model(plan, cfg);
  Rng rng(7);
  for (const bool scattered : {false, true}) {
    int total = 0;
    for (int trial = 0; trial < 5; ++trial) {
      State st = initial_state(m);
      Scratch sc = make_scratch(m);
      for (auto& p : st.pos) {
        if (scattered) {
          p = test::random_vec3([&rng] { return rng.uniform(0.0, 15.0); }) * m.voxel_size;
        } else {
          p += test::random_vec3([&rng] { return rng.uniform(-0.8, 0.8); }) * m.voxel_size;
        }
      }
      const std::vector<Vec3> before = st.pos;
      step(m, st, sc);  // rebuilds (stale at start) from `before`, then moves the voxels
      const auto expected = brute_force_pairs(m, before);
      ASSERT_EQ(st.col_pair_count, static_cast<int>(expected.size()));
      for (int k = 0; k < st.col_pair_count; ++k) {
        EXPECT_EQ(st.col_pairs[k].a, expected[k].first) << "pair " << k;
        EXPECT_EQ(st.col_pairs[k].b, expected[k].second) << "pair " << k;
      }
      total += st.col_pair_count;
    }
    std::printf("grid broadphase (%s): %d pairs over 5 trials identical to the O(N^2) scan\n",
                scattered ? "scattered" : "jittered", total);
    EXPECT_GT(total, 0);
  }
}

// Staleness (§2.10): no rebuild while every surface voxel stays within 0.5 s of its position at
// the last rebuild; a rebuild as soon as one moves further.
TEST(SelfCollisionPairs, RebuildOnlyWhenStale) {
  PhysicsConfig cfg;
  cfg.gravity = 0.0;
  cfg.floor = false;
  const Model m = build_model(solid_block(3, 3, 3, 5.0e4), cfg);
  State st = initial_state(m);
  Scratch sc = make_scratch(m);
  step(m, st, sc);
  EXPECT_EQ(st.counters.collision_rebuilds, 1u);
  step(m, st, sc);
  EXPECT_EQ(st.counters.collision_rebuilds, 1u);
  st.pos[0].x() += 0.6 * m.voxel_size;  // corner voxel jumps beyond the recalc distance
  step(m, st, sc);
  EXPECT_EQ(st.counters.collision_rebuilds, 2u);
}

}  // namespace
}  // namespace softevo::physics
