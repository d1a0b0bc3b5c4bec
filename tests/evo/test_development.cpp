// Body development (docs/model.md §6.2-6.6): morphology helpers with scipy.ndimage semantics,
// binning, rounding, hand-made CPPNs, and the 40 thesis champions rebuilt from their CPPNs.
#include "evo/development.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <limits>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include "common/chamber_quads.hpp"
#include "common/rng.hpp"
#include "common/robot.hpp"
#include "tests/random_cppn.hpp"

namespace softevo::evo {
namespace {

using morph::Dims;
using morph::Grid;

std::size_t at(const Dims& d, int x, int y, int z) {
  return (static_cast<std::size_t>(x) * d[1] + y) * d[2] + z;
}

Grid box(const Dims& d, std::array<int, 3> lo, std::array<int, 3> hi) {  // inclusive bounds
  Grid g(static_cast<std::size_t>(d[0]) * d[1] * d[2], 0);
  for (int x = lo[0]; x <= hi[0]; ++x)
    for (int y = lo[1]; y <= hi[1]; ++y)
      for (int z = lo[2]; z <= hi[2]; ++z) g[at(d, x, y, z)] = 1;
  return g;
}

int count(const Grid& g) {
  return static_cast<int>(std::count(g.begin(), g.end(), 1));
}

TEST(Morphology, FillHolesFillsEnclosedSpaceOnly) {
  const Dims d{5, 5, 5};
  Grid shell = box(d, {1, 1, 1}, {3, 3, 3});
  shell[at(d, 2, 2, 2)] = 0;  // a closed one-cell cavity
  Grid filled = morph::fill_holes(shell, d);
  EXPECT_EQ(filled[at(d, 2, 2, 2)], 1);
  EXPECT_EQ(count(filled), 27);
  // Open a face-connected tunnel from the cavity to the outside: nothing is filled.
  shell[at(d, 2, 2, 1)] = 0;
  filled = morph::fill_holes(shell, d);
  EXPECT_EQ(filled[at(d, 2, 2, 2)], 0);
  EXPECT_EQ(count(filled), 25);
}

TEST(Morphology, FillHolesUsesSixConnectedBackground) {
  // A cavity touching the outside only through an edge (diagonal) is enclosed for 6-connectivity.
  const Dims d{4, 4, 4};
  Grid g = box(d, {0, 0, 0}, {3, 3, 3});
  g[at(d, 1, 1, 1)] = 0;  // interior cell
  g[at(d, 0, 0, 1)] = 0;  // border cell, touches (1,1,1) only along an edge
  const Grid filled = morph::fill_holes(g, d);
  EXPECT_EQ(filled[at(d, 1, 1, 1)], 1);
  EXPECT_EQ(filled[at(d, 0, 0, 1)], 0);  // border background stays background
  // Background on the array border is never filled, even if enclosed by nothing else.
  Grid empty(64, 0);
  EXPECT_EQ(count(morph::fill_holes(empty, d)), 0);
}

TEST(Morphology, Erode26TreatsOutsideAsFalse) {
  const Dims d{5, 5, 5};
  Grid g = morph::erode26(box(d, {1, 1, 1}, {3, 3, 3}), d);
  EXPECT_EQ(count(g), 1);
  EXPECT_EQ(g[at(d, 2, 2, 2)], 1);
  // A full array: border cells never survive.
  const Dims s{3, 3, 4};
  g = morph::erode26(box(s, {0, 0, 0}, {2, 2, 3}), s);
  EXPECT_EQ(count(g), 2);
  EXPECT_EQ(g[at(s, 1, 1, 1)], 1);
  EXPECT_EQ(g[at(s, 1, 1, 2)], 1);
  // A missing corner (26-neighbour) kills the centre.
  Grid c = box(d, {1, 1, 1}, {3, 3, 3});
  c[at(d, 3, 3, 3)] = 0;
  EXPECT_EQ(count(morph::erode26(c, d)), 0);
}

TEST(Morphology, Dilate26ClipsAtBorder) {
  const Dims d{5, 5, 5};
  EXPECT_EQ(count(morph::dilate26(box(d, {2, 2, 2}, {2, 2, 2}), d)), 27);
  const Grid corner = morph::dilate26(box(d, {0, 0, 0}, {0, 0, 0}), d);
  EXPECT_EQ(count(corner), 8);
  EXPECT_EQ(corner[at(d, 1, 1, 1)], 1);
  EXPECT_EQ(corner[at(d, 2, 0, 0)], 0);
}

TEST(Morphology, LabelNumberingAndConnectivity) {
  const Dims d{4, 4, 4};
  Grid g(64, 0);
  g[at(d, 3, 0, 0)] = 1;  // later in C order
  g[at(d, 0, 2, 2)] = 1;  // first in C order
  g[at(d, 1, 3, 3)] = 1;  // diagonal (edge) neighbour of (0,2,2)
  int n = 0;
  auto l6 = morph::label(g, d, 6, n);
  EXPECT_EQ(n, 3);
  EXPECT_EQ(l6[at(d, 0, 2, 2)], 1);
  EXPECT_EQ(l6[at(d, 1, 3, 3)], 2);
  EXPECT_EQ(l6[at(d, 3, 0, 0)], 3);
  auto l26 = morph::label(g, d, 26, n);
  EXPECT_EQ(n, 2);
  EXPECT_EQ(l26[at(d, 0, 2, 2)], 1);
  EXPECT_EQ(l26[at(d, 1, 3, 3)], 1);
  EXPECT_EQ(l26[at(d, 3, 0, 0)], 2);
  EXPECT_EQ(l26[at(d, 0, 0, 0)], 0);
  EXPECT_THROW(morph::label(g, d, 18, n), std::invalid_argument);
}

TEST(Binning, NumpyDigitizeEdges) {
  // Edges e_j = j*(2/9) - 1 with numpy arithmetic; e_7 = 0.5555555555555554, e_9 = 1.0.
  const double e7 = 7.0 * (2.0 / 9.0) + -1.0;
  EXPECT_EQ(e7, 0.5555555555555554);
  EXPECT_EQ(morph::stiffness_bin(e7), 8);
  EXPECT_EQ(morph::stiffness_bin(std::nextafter(e7, 0.0)), 7);
  EXPECT_EQ(morph::stiffness_bin(5.0 / 9.0), 8);  // 0.5555555555555556 is above e7
  EXPECT_EQ(morph::stiffness_bin(-1.0), 1);
  EXPECT_EQ(morph::stiffness_bin(-7.0), 1);  // clipped to -1
  EXPECT_EQ(morph::stiffness_bin(0.0), 5);   // a stuck-at-0 output gives material 5
  EXPECT_EQ(morph::stiffness_bin(0.9999999999999999), 9);
  EXPECT_EQ(morph::stiffness_bin(1.0), 10);  // material 10 only when saturated
  EXPECT_EQ(morph::stiffness_bin(3.0), 10);
  for (int k = 1; k <= 9; ++k) {
    const double lo = (k - 1) * (2.0 / 9.0) + -1.0;
    EXPECT_EQ(morph::stiffness_bin(lo), k) << k;
    EXPECT_EQ(morph::stiffness_bin(lo + 0.1), k) << k;
  }
}

TEST(Inputs, NumpyLinspaceSemantics) {
  EXPECT_EQ(morph::linspace01(7, 10), 0.7777777777777777);
  EXPECT_NE(morph::linspace01(7, 10), 7.0 / 9.0);
  EXPECT_EQ(morph::linspace01(9, 10), 1.0);
  EXPECT_EQ(morph::linspace01(0, 10), 0.0);
  EXPECT_EQ(morph::linspace01(0, 1), 0.0);
}

TEST(Rounding, HalfToEvenLikePython) {
  EXPECT_EQ(morph::round_half_even(0.5), 0);
  EXPECT_EQ(morph::round_half_even(1.5), 2);
  EXPECT_EQ(morph::round_half_even(2.5), 2);
  EXPECT_EQ(morph::round_half_even(4.5), 4);
  EXPECT_EQ(morph::round_half_even(3.5), 4);
  EXPECT_EQ(morph::round_half_even(2.4999999), 2);
  EXPECT_EQ(morph::round_half_even(2.5000001), 3);
}

// Hand-made CPPNs: outputs 0..3 clamped unless changed, presence = 1 everywhere.
CppnGenome base_genome() {
  CppnGenome g;
  g.nodes = {{0, 1.0, 1.0, Activation::clamped},
             {1, 0.0, 1.0, Activation::clamped},
             {2, 0.0, 1.0, Activation::clamped},
             {3, 0.0, 1.0, Activation::clamped}};
  g.connections = {{-1, 0, 0.0, true}};  // presence = clamped(1 + 0*x) = 1
  return g;
}

BodyConfig body_config(DistanceInput distance = DistanceInput::center) {
  BodyConfig b;
  b.lattice = {10, 10, 10};
  b.distance_input = distance;
  return b;
}

// Two pneumatic slabs x = 1..3 and 6..8 (is_pneu = sin(5(2.26x - 0.2)) > 0.1), eroded to the
// single planes x = 2 and x = 7 with y, z in 1..8: two chambers with centroids (2, 4.5, 4.5)
// and (7, 4.5, 4.5).
CppnGenome two_slab_genome() {
  CppnGenome g = base_genome();
  g.nodes[1] = {1, -0.2, 1.0, Activation::sin};
  g.connections.push_back({-1, 1, 2.26, true});
  return g;
}

int value_at(const BodyPlan& p, int x, int y, int z) {
  return p.cell(x, y, z);
}

TEST(Development, NoStructureIsInvalid) {
  CppnGenome g = base_genome();
  g.connections.clear();  // presence never computed: stays 0.0 -> nothing present
  const DevelopedBody b = develop_body(g, body_config());
  EXPECT_FALSE(b.valid);
  EXPECT_FALSE(b.actuatable);
  // Everything pneumatic: still no structural cell -> invalid.
  g = base_genome();
  g.nodes[1].bias = 1.0;
  g.connections.push_back({-1, 1, 0.0, true});
  EXPECT_FALSE(develop_body(g, body_config()).valid);
}

TEST(Development, SolidBlockWithStuckStiffnessIsMaterialFiveAndNotActuatable) {
  const DevelopedBody b = develop_body(base_genome(), body_config());
  EXPECT_TRUE(b.valid);
  EXPECT_FALSE(b.actuatable);
  EXPECT_EQ(b.chamber_count, 0);
  EXPECT_EQ(b.plan.lattice, (std::array<int, 3>{10, 10, 10}));
  EXPECT_TRUE(std::all_of(b.plan.cells.begin(), b.plan.cells.end(), [](int v) { return v == 5; }));
  EXPECT_TRUE(b.plan.materials.empty());
}

TEST(Development, StiffnessFollowsOutputBins) {
  CppnGenome g = base_genome();
  g.connections.push_back({-1, 2, 2.0, true});  // stiffness = clamped(2x): x=0 -> 5, x=1 -> 10
  g.nodes[2].bias = 0.0;
  const DevelopedBody b = develop_body(g, body_config());
  EXPECT_EQ(value_at(b.plan, 0, 3, 3), morph::stiffness_bin(0.0));
  EXPECT_EQ(value_at(b.plan, 9, 3, 3), 10);
  EXPECT_EQ(value_at(b.plan, 3, 0, 0), morph::stiffness_bin(2.0 * morph::linspace01(3, 10)));
}

TEST(Development, TrimsToBoundingBox) {
  // presence = clamped(1 - 2x... ) > 0.1 only for small x: x <= 4/9 -> lattice 5 x 10 x 10.
  CppnGenome g = base_genome();
  g.connections[0].weight = -2.0;  // presence = 1 - 2x > 0.1 <=> x < 0.45
  const DevelopedBody b = develop_body(g, body_config());
  EXPECT_EQ(b.plan.lattice, (std::array<int, 3>{5, 10, 10}));
  EXPECT_EQ(b.plan.cells.size(), 500u);
}

TEST(Development, TwoChambersSortedBySortingOutput) {
  CppnGenome g = two_slab_genome();
  g.connections.push_back({-1, 3, 1.0, true});  // sorting = clamped(x): slab at x=2 first
  DevelopedBody b = develop_body(g, body_config());
  ASSERT_TRUE(b.valid);
  EXPECT_TRUE(b.actuatable);
  EXPECT_EQ(b.chamber_count, 2);
  EXPECT_EQ(b.plan.chamber_count(), 2);
  EXPECT_EQ(value_at(b.plan, 2, 4, 4), 11);
  EXPECT_EQ(value_at(b.plan, 7, 4, 4), 12);
  // Erosion: the chamber never touches the lattice border, the slab's outer layers are shell.
  EXPECT_EQ(value_at(b.plan, 2, 0, 4), 5);
  EXPECT_EQ(value_at(b.plan, 1, 4, 4), 5);
  EXPECT_EQ(value_at(b.plan, 2, 1, 1), 11);
  int chamber_cells = 0;
  for (int v : b.plan.cells) chamber_cells += v >= 11;
  EXPECT_EQ(chamber_cells, 2 * 8 * 8);

  g.connections.back().weight = -1.0;  // sorting = -x: order reversed
  b = develop_body(g, body_config());
  EXPECT_EQ(value_at(b.plan, 2, 4, 4), 12);
  EXPECT_EQ(value_at(b.plan, 7, 4, 4), 11);
}

TEST(Development, ChamberSortingRoundsCentroidHalfToEven) {
  // Both centroids have y = 4.5. sorting = sin(5(x + 2y)): at y index 4 the slab x=2 sorts first
  // (-0.665 < 0.887); at y index 5 (round half up) it would sort second (0.374 > -0.020).
  CppnGenome g = two_slab_genome();
  g.nodes[3] = {3, 0.0, 1.0, Activation::sin};
  g.connections.push_back({-1, 3, 1.0, true});
  g.connections.push_back({-2, 3, 2.0, true});
  const DevelopedBody b = develop_body(g, body_config());
  ASSERT_EQ(b.chamber_count, 2);
  EXPECT_EQ(value_at(b.plan, 2, 4, 4), 11);
  EXPECT_EQ(value_at(b.plan, 7, 4, 4), 12);
}

TEST(Development, ChambersBeyondMaximumStayVoids) {
  CppnGenome g = two_slab_genome();
  g.connections.push_back({-1, 3, -1.0, true});  // slab x=7 first
  BodyConfig cfg = body_config();
  cfg.max_chambers = 1;
  const DevelopedBody b = develop_body(g, cfg);
  EXPECT_EQ(b.chamber_count, 1);
  EXPECT_EQ(value_at(b.plan, 7, 4, 4), 11);
  EXPECT_EQ(value_at(b.plan, 2, 4, 4), 0);  // unactuated void
  cfg.max_chambers = 0;
  EXPECT_FALSE(develop_body(g, cfg).actuatable);
}

TEST(Development, EnclosedEmptySpaceBecomesChamber) {
  // presence = gauss(4d - 1.88) > 0.1 <=> 0.3 < d < 0.64: a thick spherical shell around the
  // centre with empty space inside and at the cube corners. Step 2 turns the enclosed empty core
  // into a chamber.
  CppnGenome g;
  g.nodes = {{0, -1.88, 1.0, Activation::gauss},
             {1, 0.0, 1.0, Activation::clamped},
             {2, 0.0, 1.0, Activation::clamped},
             {3, 0.0, 1.0, Activation::clamped}};
  g.connections = {{-4, 0, 4.0, true}};
  const DevelopedBody b = develop_body(g, body_config(DistanceInput::center));
  ASSERT_TRUE(b.valid);
  EXPECT_TRUE(b.actuatable);
  EXPECT_EQ(b.chamber_count, 1);
  const auto& L = b.plan.lattice;
  // Every chamber cell is surrounded (26) by chamber or structural cells.
  for (int x = 0; x < L[0]; ++x)
    for (int y = 0; y < L[1]; ++y)
      for (int z = 0; z < L[2]; ++z) {
        if (b.plan.cell(x, y, z) != 11) continue;
        for (int dx = -1; dx <= 1; ++dx)
          for (int dy = -1; dy <= 1; ++dy)
            for (int dz = -1; dz <= 1; ++dz) {
              const int nx = x + dx, ny = y + dy, nz = z + dz;
              ASSERT_TRUE(nx >= 0 && ny >= 0 && nz >= 0 && nx < L[0] && ny < L[1] && nz < L[2]);
              EXPECT_NE(b.plan.cell(nx, ny, nz), 0);
            }
      }
}

TEST(Development, DistanceInputChoiceMatters) {
  // presence = clamped(1.5 - d) > 0.1 keeps everything for "center" (d <= 0.87) but nothing for
  // "pneuvox" (d >= 6.9).
  CppnGenome g = base_genome();
  g.nodes[0].bias = 1.5;
  g.connections = {{-4, 0, -1.0, true}};
  EXPECT_TRUE(develop_body(g, body_config(DistanceInput::center)).valid);
  EXPECT_FALSE(develop_body(g, body_config(DistanceInput::pneuvox)).valid);
}

TEST(Development, BadConfigIsRejected) {
  BodyConfig cfg = body_config();
  cfg.lattice = {10, 10};
  EXPECT_THROW(develop_body(base_genome(), cfg), std::invalid_argument);
  cfg = body_config();
  cfg.lattice = {10, 0, 10};
  EXPECT_THROW(develop_body(base_genome(), cfg), std::invalid_argument);
  cfg = body_config();
  cfg.max_chambers = 11;
  EXPECT_THROW(develop_body(base_genome(), cfg), std::invalid_argument);
}

CppnGenome random_genome(Rng& rng) {
  return test::random_cppn(rng);
}

// Invariants of §6.5 on many random bodies: trimmed lattice within the query lattice, dense
// chamber ids 11.., every chamber cell enclosed (all 26 neighbours inside the lattice and either
// the same chamber or structural), and closed, consistently oriented chamber meshes (§6.7).
TEST(Development, RandomBodiesSatisfyInvariants) {
  Rng rng(12345);
  int actuatable = 0, multi = 0;
  for (int it = 0; it < 1500; ++it) {
    const CppnGenome g = random_genome(rng);
    const DevelopedBody b =
        develop_body(g, body_config(it % 2 ? DistanceInput::center : DistanceInput::pneuvox));
    if (!b.valid) {
      EXPECT_TRUE(b.plan.cells.empty());
      continue;
    }
    const auto& L = b.plan.lattice;
    ASSERT_TRUE(L[0] >= 1 && L[0] <= 10 && L[1] >= 1 && L[1] <= 10 && L[2] >= 1 && L[2] <= 10);
    ASSERT_EQ(b.plan.cells.size(), static_cast<std::size_t>(L[0] * L[1] * L[2]));
    EXPECT_EQ(b.plan.chamber_count(), b.chamber_count);
    EXPECT_EQ(b.actuatable, b.chamber_count > 0);
    std::vector<int> cells_per_chamber(static_cast<std::size_t>(b.chamber_count), 0);
    for (int v : b.plan.cells) {
      ASSERT_TRUE(v >= 0 && v <= 10 + b.chamber_count) << v;
      if (v >= 11) ++cells_per_chamber[static_cast<std::size_t>(v - 11)];
    }
    for (int n : cells_per_chamber) EXPECT_GT(n, 0);  // ids are dense
    if (!b.actuatable) continue;
    ++actuatable;
    multi += b.chamber_count > 1;
    int unenclosed = 0;
    for (int x = 0; x < L[0]; ++x)
      for (int y = 0; y < L[1]; ++y)
        for (int z = 0; z < L[2]; ++z) {
          const int v = b.plan.cell(x, y, z);
          if (v < 11) continue;
          for (int dx = -1; dx <= 1; ++dx)
            for (int dy = -1; dy <= 1; ++dy)
              for (int dz = -1; dz <= 1; ++dz) {
                const int nx = x + dx, ny = y + dy, nz = z + dz;
                if (nx < 0 || ny < 0 || nz < 0 || nx >= L[0] || ny >= L[1] || nz >= L[2]) {
                  ++unenclosed;
                  continue;
                }
                const int w = b.plan.cell(nx, ny, nz);
                if (w == 0 || (w >= 11 && w != v)) ++unenclosed;
              }
        }
    EXPECT_EQ(unenclosed, 0) << "random genome " << it;
    for (const auto& ch : chamber_quads(b.plan)) {
      ASSERT_FALSE(ch.quads.empty());
      std::map<std::pair<std::array<int, 3>, std::array<int, 3>>, int> edges;
      for (const auto& q : ch.quads) {
        const std::array<std::array<int, 3>, 3> tris[2] = {{q[0], q[1], q[2]}, {q[2], q[3], q[0]}};
        for (const auto& t : tris)
          for (int k = 0; k < 3; ++k) ++edges[{t[k], t[(k + 1) % 3]}];
      }
      for (const auto& [e, n] : edges) {
        auto rev = edges.find({e.second, e.first});
        ASSERT_TRUE(rev != edges.end() && rev->second == n) << "random genome " << it;
      }
    }
  }
  // The sample must exercise chambers at all, including several per body.
  EXPECT_GT(actuatable, 100);
  EXPECT_GT(multi, 10);
}

// §6 acceptance: the 40 thesis champions' stored bodies from their stored CPPNs.
TEST(DevelopmentReference, ReproducesAllFortyChampions) {
  const std::filesystem::path dir = "../shared/reference/bestbots";
  if (!std::filesystem::is_directory(dir))
    GTEST_SKIP() << "reference data not found at " << dir
                 << " (relative to the repo root); skipping the champion reproduction test";
  std::vector<std::filesystem::path> files;
  for (const auto& e : std::filesystem::directory_iterator(dir))
    if (e.path().string().ends_with(".robot.json")) files.push_back(e.path());
  std::sort(files.begin(), files.end());
  ASSERT_EQ(files.size(), 40u);
  int reproduced = 0;
  for (const auto& f : files) {
    const RobotFile robot = read_robot_file(f.string());
    ASSERT_TRUE(robot.genome.has_value()) << f;
    const RobotGenomeRecord& rec = *robot.genome;
    ASSERT_EQ(rec.distance_input, DistanceInput::pneuvox) << f;
    BodyConfig cfg;
    cfg.lattice.assign(rec.body_lattice.begin(), rec.body_lattice.end());
    cfg.distance_input = DistanceInput::pneuvox;
    const DevelopedBody b = develop_body(cppn_from_records(rec.nodes, rec.connections), cfg);
    EXPECT_TRUE(b.valid) << f;
    EXPECT_TRUE(b.actuatable) << f;
    EXPECT_EQ(b.plan.lattice, robot.body.lattice) << f;
    EXPECT_EQ(b.chamber_count, robot.body.chamber_count()) << f;
    const bool same = b.plan.lattice == robot.body.lattice && b.plan.cells == robot.body.cells;
    EXPECT_TRUE(same) << f << ": cells differ";
    reproduced += same ? 1 : 0;
  }
  std::printf("reproduced %d of %zu champion bodies cell for cell\n", reproduced, files.size());
}

}  // namespace
}  // namespace softevo::evo
