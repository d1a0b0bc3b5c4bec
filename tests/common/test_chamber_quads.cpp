// Chamber quad generation (docs/model.md §6.7) and the mesh properties §3.1/§3.2 rely on.
#include "common/chamber_quads.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <map>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "common/robot.hpp"

namespace softevo {
namespace {

using Vec = std::array<double, 3>;
using Quad = std::array<std::array<int, 3>, 4>;

Vec position(const std::array<int, 3>& c, double s) {
  return {c[0] * s, c[1] * s, c[2] * s};
}
Vec sub(const Vec& a, const Vec& b) {
  return {a[0] - b[0], a[1] - b[1], a[2] - b[2]};
}
Vec cross(const Vec& a, const Vec& b) {
  return {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
}
double dot(const Vec& a, const Vec& b) {
  return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

// §3.2: triangles (a,b,c), (c,d,a) of every quad; p0 = first vertex of the first triangle;
// V = sum (C-p0).((B-p0)x(A-p0))/6, positive for the inward-normal orientation. [m^3]
double mesh_volume(const std::vector<Quad>& quads, double s) {
  if (quads.empty()) return 0.0;
  const Vec p0 = position(quads[0][0], s);
  double v = 0.0;
  for (const Quad& q : quads) {
    const std::array<std::array<int, 3>, 3> tris[2] = {{q[0], q[1], q[2]}, {q[2], q[3], q[0]}};
    for (const auto& t : tris) {
      const Vec a = sub(position(t[0], s), p0), b = sub(position(t[1], s), p0),
                c = sub(position(t[2], s), p0);
      v += dot(c, cross(b, a)) / 6.0;
    }
  }
  return v;
}

// Closed and consistently oriented: every directed triangle edge is matched by its reverse as
// often as it occurs. (Usually once each; a one-cell-thick wall with the same cavity on both
// sides gets a quad from each side with opposite orientation, so some edges occur twice.)
int unmatched_edges(const std::vector<Quad>& quads) {
  std::map<std::pair<std::array<int, 3>, std::array<int, 3>>, int> edges;
  for (const Quad& q : quads) {
    const std::array<std::array<int, 3>, 3> tris[2] = {{q[0], q[1], q[2]}, {q[2], q[3], q[0]}};
    for (const auto& t : tris)
      for (int k = 0; k < 3; ++k) ++edges[{t[k], t[(k + 1) % 3]}];
  }
  int bad = 0;
  for (const auto& [e, n] : edges) {
    auto rev = edges.find({e.second, e.first});
    if (rev == edges.end() || rev->second != n) ++bad;
  }
  return bad;
}

void expect_closed_and_oriented(const std::vector<Quad>& quads, const std::string& what) {
  EXPECT_EQ(unmatched_edges(quads), 0) << what << ": directed edges without a matching reverse";
}

BodyPlan solid_plan(std::array<int, 3> lattice, int material) {
  BodyPlan p;
  p.lattice = lattice;
  p.cells.assign(static_cast<std::size_t>(lattice[0]) * lattice[1] * lattice[2], material);
  return p;
}

TEST(ChamberQuads, SingleCellCavityIsACubeOfEightCubicCentimetres) {
  BodyPlan p = solid_plan({3, 3, 3}, 10);
  p.cells[p.cell_index(1, 1, 1)] = 11;
  const auto chambers = chamber_quads(p);
  ASSERT_EQ(chambers.size(), 1u);
  const auto& quads = chambers[0].quads;
  EXPECT_EQ(quads.size(), 24u);  // 6 faces of the 3x3x3 wall-centre lattice, 2x2 quads each
  expect_closed_and_oriented(quads, "single cell");
  // The check can fail: an open mesh or a flipped quad is detected.
  std::vector<Quad> open(quads.begin(), quads.end() - 1);
  EXPECT_GT(unmatched_edges(open), 0);
  std::vector<Quad> flipped = quads;
  std::swap(flipped[5][1], flipped[5][3]);
  EXPECT_GT(unmatched_edges(flipped), 0);
  // Manifold here: no quad appears twice.
  for (std::size_t i = 0; i < quads.size(); ++i)
    for (std::size_t j = i + 1; j < quads.size(); ++j) EXPECT_NE(quads[i], quads[j]);
  // (2s)^3 = 8 cm^3 (§3.2 example).
  EXPECT_NEAR(mesh_volume(quads, 0.01), 8e-6, 1e-18);
  // The first pass (XY, probe +z) starts at the lowest wall cell: bottom face, listed first.
  EXPECT_EQ(quads[0], (Quad{{{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}}}));
  // Inward normals: (c-b)x(a-b) of the first triangle points up (+z, into the cavity).
  const Vec a = position(quads[0][0], 1), b = position(quads[0][1], 1),
            c = position(quads[0][2], 1);
  EXPECT_GT(cross(sub(c, b), sub(a, b))[2], 0.0);
}

TEST(ChamberQuads, OneQuadListPerChamberInIdOrder) {
  BodyPlan p = solid_plan({7, 3, 4}, 3);
  p.cells[p.cell_index(1, 1, 1)] = 12;  // chamber 1: one cell
  p.cells[p.cell_index(1, 1, 2)] = 12;
  for (int x = 4; x <= 5; ++x) p.cells[p.cell_index(x, 1, 1)] = 11;  // chamber 0: 2 cells in x
  const auto chambers = chamber_quads(p);
  ASSERT_EQ(chambers.size(), 2u);
  for (const auto& c : chambers) expect_closed_and_oriented(c.quads, "two chambers");
  // A 1x1x2 cavity: wall-centre box 2s x 2s x 3s = 12 cm^3.
  EXPECT_NEAR(mesh_volume(chambers[0].quads, 0.01), 12e-6, 1e-18);
  EXPECT_NEAR(mesh_volume(chambers[1].quads, 0.01), 12e-6, 1e-18);
  // Chamber 0 lies at x >= 3, chamber 1 at x <= 2.
  for (const auto& q : chambers[0].quads)
    for (const auto& v : q) EXPECT_GE(v[0], 3);
  for (const auto& q : chambers[1].quads)
    for (const auto& v : q) EXPECT_LE(v[0], 2);
}

TEST(ChamberQuads, NoChamberNoQuadsAndBadSizeRejected) {
  EXPECT_TRUE(chamber_quads(solid_plan({4, 4, 4}, 1)).empty());
  BodyPlan bad = solid_plan({4, 4, 4}, 1);
  bad.cells.pop_back();
  EXPECT_THROW(chamber_quads(bad), std::invalid_argument);
}

// §9.8 on the thesis champions.
TEST(ChamberQuadsReference, ChampionMeshesClosedOrientedAndVolumesMatch) {
  const std::filesystem::path dir = "../shared/reference/bestbots";
  if (!std::filesystem::is_directory(dir))
    GTEST_SKIP() << "reference data not found at " << dir
                 << " (relative to the repo root); skipping the champion mesh test";
  // Reference initial volumes [cm^3], rounded to whole cm^3 in §9.8.
  const std::map<std::string, std::vector<double>> expected = {
      {"gait-closed-10", {12, 12, 12, 12, 20}},
      {"gait-open-03", {171}},
      {"dir-open-09", {80, 425}}};
  int files = 0, checked = 0;
  for (const auto& e : std::filesystem::directory_iterator(dir)) {
    const std::string name = e.path().filename().string();
    if (!name.ends_with(".robot.json")) continue;
    ++files;
    const RobotFile robot = read_robot_file(e.path().string());
    const auto chambers = chamber_quads(robot.body);
    ASSERT_EQ(static_cast<int>(chambers.size()), robot.body.chamber_count()) << name;
    std::vector<double> volumes;
    for (std::size_t q = 0; q < chambers.size(); ++q) {
      expect_closed_and_oriented(chambers[q].quads, name + " chamber " + std::to_string(q));
      const double v = mesh_volume(chambers[q].quads, robot.body.voxel_size) * 1e6;  // [cm^3]
      EXPECT_GE(v, 8.0 - 1e-9) << name;   // at least one cavity cell
      EXPECT_LE(v, 425.0 + 0.5) << name;  // §3.2: champions have 8-425 cm^3
      volumes.push_back(v);
      std::printf("%s chamber %zu: %zu quads, volume %.3f cm^3\n", name.c_str(), q,
                  chambers[q].quads.size(), v);
    }
    const std::string stem = name.substr(0, name.size() - std::string(".robot.json").size());
    if (auto it = expected.find(stem); it != expected.end()) {
      ASSERT_EQ(volumes.size(), it->second.size()) << name;
      for (std::size_t q = 0; q < volumes.size(); ++q)
        EXPECT_NEAR(volumes[q], it->second[q], 0.5) << name << " chamber " << q;
      ++checked;
    }
  }
  EXPECT_EQ(files, 40);
  EXPECT_EQ(checked, 3);
}

}  // namespace
}  // namespace softevo
