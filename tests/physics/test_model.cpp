// Model construction (docs/model.md §2.1, §2.14, §5 step 4, Appendix A) and the rotation
// utilities of §2.11.
#include <gtest/gtest.h>

#include <random>

#include <cmath>
#include <stdexcept>

#include "physics/lane_math.hpp"
#include "physics/lanes_scalar.hpp"
#include "physics/model.hpp"
#include "physics/observables.hpp"
#include "physics/quat.hpp"
#include "physics/scenes.hpp"
#include "physics/state.hpp"

namespace softevo::physics {
namespace {

TEST(Model, VoxelOrderAndCellMap) {
  // 2x2x2 lattice: chamber at (0,1,0), empty at (1,0,1), material 2 at (1,1,1)
  BodyPlan plan = solid_block(2, 2, 2, 1.0e4);
  plan.materials.push_back({1.0e5, 1000.0});
  plan.cells[plan.cell_index(0, 1, 0)] = kFirstChamberCell;
  plan.cells[plan.cell_index(1, 0, 1)] = kEmptyCell;
  plan.cells[plan.cell_index(1, 1, 1)] = 2;
  const Model m = build_model(plan, PhysicsConfig{});
  ASSERT_EQ(m.voxel_count, 6);
  const std::array<std::array<int, 3>, 6> expected = {
      {{0, 0, 0}, {0, 0, 1}, {0, 1, 1}, {1, 0, 0}, {1, 1, 0}, {1, 1, 1}}};
  for (int v = 0; v < 6; ++v) {
    EXPECT_EQ(m.voxel_cell[v], expected[v]) << v;
    EXPECT_EQ(m.cell_to_voxel[m.cell_index(expected[v][0], expected[v][1], expected[v][2])], v);
  }
  EXPECT_EQ(m.cell_to_voxel[m.cell_index(0, 1, 0)], -1);
  EXPECT_EQ(m.cell_to_voxel[m.cell_index(1, 0, 1)], -1);
  EXPECT_EQ(m.voxel_material[5], 2);
  // links in creation order: (0,0,0)-(0,0,1) z; (0,0,1)-(0,1,1) y; (0,0,0)-(1,0,0) x;
  // (1,0,0)-(1,1,0) y; (0,1,1)-(1,1,1) x; (1,1,0)-(1,1,1) z; numbered axis by axis (x, y, z),
  // each axis in creation order
  ASSERT_EQ(m.link_count, 6);
  const int neg[6] = {0, 2, 1, 3, 0, 4}, pos[6] = {3, 5, 2, 4, 1, 5};
  const Axis axis[6] = {Axis::x, Axis::x, Axis::y, Axis::y, Axis::z, Axis::z};
  for (int l = 0; l < 6; ++l) {
    EXPECT_EQ(m.link_neg[l], neg[l]) << l;
    EXPECT_EQ(m.link_pos[l], pos[l]) << l;
    EXPECT_EQ(m.link_axis[l], axis[l]) << l;
  }
  EXPECT_EQ(m.axis_link_begin, (std::array<int, 4>{0, 2, 4, 6}));
  // voxel 5 = (1,1,1): links in direction order X- (link 1), Y- none, Z- (link 5); the other
  // slots are the zero end load 2 * link_count
  EXPECT_EQ(m.missing_load_slot(), 12);
  EXPECT_EQ(m.voxel_load_slots[5], (std::array<int, 6>{12, 1 * 2 + 1, 12, 12, 12, 5 * 2 + 1}));
  EXPECT_NEAR(m.link_const[1].e_area, 2 * 1e4 * 1e5 / 1.1e5, 0.01);
}

// Appendix A constants for E = 1e5 Pa, s = 0.01 m (through a float), rho = 1000.
TEST(Model, DerivedConstantsAppendixA) {
  const Model m = build_model(solid_block(2, 1, 1, 1.0e5), PhysicsConfig{});
  EXPECT_EQ(m.voxel_size, static_cast<double>(0.01f));
  const VoxelConst& c = m.voxel_const[0];
  EXPECT_FLOAT_EQ(c.mass, 9.9999993e-4f);
  EXPECT_NEAR(1.0 / c.inv_inertia, 1.6667e-8, 1e-12);
  EXPECT_NEAR(c.k_pen, 2000.0, 1e-3);
  EXPECT_NEAR(c.c_glob, 2.0e-3, 1e-7);
  EXPECT_NEAR(c.c_col, 0.2, 1e-5);
  EXPECT_NEAR(c.c_glob_rot, 8.165e-8, 1e-11);
  EXPECT_NEAR(c.damp_base / static_cast<float>(m.dt), 39.74, 0.01);  // 2 sqrt(m) 0.1 / dt
  const LinkConst& k = m.link_const[0];
  EXPECT_NEAR(k.b1, 1000.0, 1e-3);
  EXPECT_NEAR(k.b2, 5.0, 1e-5);
  EXPECT_NEAR(k.b3, 1.6667e-2, 1e-6);
  EXPECT_NEAR(k.a2, 8.333e-3, 1e-6);
}

// §2.14 table: dt = 1/(2 pi sqrt(10 E_L,max)) in float, x dt_fraction.
TEST(Model, RecommendedTimeStepTable) {
  const double table[][2] = {{1e4, 5.032921e-4}, {5e4, 2.250791e-4}, {1e5, 1.591549e-4}};
  for (const auto& row : table) {
    const Model m = build_model(solid_block(2, 2, 1, row[0]), PhysicsConfig{});
    EXPECT_NEAR(m.dt, row[1], 1e-9) << row[0];
    EXPECT_EQ(m.dt, static_cast<double>(m.dt_f));
  }
  PhysicsConfig half;
  half.dt_fraction = 0.5;
  const Model m = build_model(solid_block(2, 2, 1, 1e5), half);
  EXPECT_NEAR(m.dt, 0.5 * 1.591549e-4, 1e-9);
  // a single voxel has no links: E s / m instead, same value for a uniform material
  const Model one = build_model(solid_block(1, 1, 1, 1e5), PhysicsConfig{});
  EXPECT_NEAR(one.dt, 1.591549e-4, 1e-9);
}

TEST(Model, SurfaceAndNearby) {
  const Model m = build_model(solid_block(3, 3, 3, 1e5), PhysicsConfig{});
  const int centre = m.cell_to_voxel[m.cell_index(1, 1, 1)];
  EXPECT_EQ(m.voxel_surface[centre], 0);
  EXPECT_EQ(static_cast<int>(m.surface_voxels.size()), 26);
  const int a = m.cell_to_voxel[m.cell_index(0, 0, 0)], b = m.cell_to_voxel[m.cell_index(2, 2, 2)];
  // (0,0,0)-(2,2,2) is 6 hops apart: not nearby; (0,0,0)-(2,2,1) is 5: nearby
  EXPECT_FALSE(is_nearby(m, a, b));
  const int c = m.cell_to_voxel[m.cell_index(2, 2, 1)];
  EXPECT_TRUE(is_nearby(m, a, c));
}

TEST(Model, RejectsBadInput) {
  BodyPlan plan = solid_block(2, 2, 2, 1e5);
  plan.cells[0] = 3;  // only one material defined
  EXPECT_THROW(build_model(plan, PhysicsConfig{}), std::invalid_argument);
  plan = solid_block(2, 2, 2, 1e5);
  plan.cells.pop_back();
  EXPECT_THROW(build_model(plan, PhysicsConfig{}), std::invalid_argument);
  BuildOptions opt;
  opt.fixed_cells = {{5, 0, 0}};
  EXPECT_THROW(build_model(solid_block(2, 2, 2, 1e5), PhysicsConfig{}, opt), std::invalid_argument);
  PhysicsConfig cfg;
  cfg.dt_fraction = 0.0;
  EXPECT_THROW(build_model(solid_block(2, 2, 2, 1e5), cfg), std::invalid_argument);
}

TEST(Model, InitialStateAndObservables) {
  const Model m = build_model(solid_block(3, 2, 2, 1e5), PhysicsConfig{});
  const State st = initial_state(m);
  EXPECT_EQ(st.pos[m.cell_to_voxel[m.cell_index(2, 1, 1)]], Vec3(2, 1, 1) * m.voxel_size);
  for (auto f : st.static_friction) EXPECT_EQ(f, 1);
  EXPECT_EQ(centroid_displacement(m, st), Vec3::Zero());
  EXPECT_EQ(mean_rotation_vector(m, st), Vec3::Zero());
  EXPECT_FALSE(flipped(m, st));
  EXPECT_FALSE(exploded(m, st));
  State tilted = st;
  for (auto& q : tilted.orient) q = quat_from_rotvec(Vec3(1.1, 0, 0));  // > pi/3
  EXPECT_TRUE(flipped(m, tilted));
  State stretched = st;
  stretched.link_strain[0] = 2.5f;
  EXPECT_TRUE(exploded(m, stretched));
}

// §2.11 utilities.
TEST(Quat, RotationVectorRoundTripAndBranches) {
  for (const Vec3& r : {Vec3(0.3, -0.2, 0.5), Vec3(1e-5, 2e-5, -1e-5), Vec3(0.0, 0.0, 2.0)}) {
    const Quat q = quat_from_rotvec(r);
    EXPECT_LT((rotvec(q) - r).norm(), 1e-9 * std::max(1.0, r.norm())) << r.transpose();
  }
  // Taylor branch (half-angle^4 < 5.328e-15): w = 1 - t/2 exactly, not cos
  const Quat small = quat_from_rotvec(Vec3(2e-4, 0, 0));
  EXPECT_EQ(small.w, 1.0 - (1e-4 * 1e-4) / 2);
  EXPECT_EQ(rotvec(Quat{}), Vec3::Zero());
  // rotate: 90 degrees about z maps x to y; inverse maps back
  const Quat qz = quat_from_rotvec(Vec3(0, 0, M_PI / 2));
  EXPECT_LT((rotate(qz, Vec3(1, 0, 0)) - Vec3(0, 1, 0)).norm(), 1e-15);
  EXPECT_LT((rotate_inv(qz, Vec3(0, 1, 0)) - Vec3(1, 0, 0)).norm(), 1e-15);
  // composition: rotate by A then B = B (x) A
  const Quat qx = quat_from_rotvec(Vec3(M_PI / 2, 0, 0));
  const Vec3 v(0.3, 0.7, -0.2);
  EXPECT_LT((rotate(mul(qx, qz), v) - rotate(qx, rotate(qz, v))).norm(), 1e-15);
}

// The link pass's angle to +X (physics/lane_math.hpp) one lane wide, as a link switching mode
// runs it, on a Vec3.
void frame_to_pos_x(const Vec3& d, Quat& q1, Vec3& a1) {
  using L = LanesScalar;
  const VL<L> lanes{DV<L>{d.x()}, DV<L>{d.y()}, DV<L>{d.z()}};
  const DV<L> len = L::sqrt(lanes.x * lanes.x + lanes.y * lanes.y + lanes.z * lanes.z);
  QL<L> q;
  VL<L> a;
  frame_to_pos_x_lanes<L>(lanes, len, q, a);
  q1 = {q.w[0], q.x[0], q.y[0], q.z[0]};
  a1 = Vec3(a.x[0], a.y[0], a.z[0]);
}

// §2.11 angle to +X (frame_to_pos_x): q1 rotates d onto +X, and a1 is its rotation vector. The
// general branch is in closed form (physics revision 2); it must agree with the reference
// formulas (q1 from sin / cos of theta / 2, a1 = rotvec(q1)) to rounding.
TEST(Quat, AngleToPosX) {
  std::mt19937_64 gen(5);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::vector<Vec3> dirs = {Vec3(1, 0.5, -0.3),    Vec3(1, 1e-3, 2e-3),  Vec3(-1, 0.2, 0.1),
                            Vec3(0.01, 0.0, -2.0), Vec3(1, 0.0173, 0.0), Vec3(-0.3, 0.0, 1.0)};
  for (int i = 0; i < 2000; ++i) dirs.emplace_back(u(gen), u(gen), u(gen));
  for (const Vec3& d : dirs) {
    Quat q;
    Vec3 a1;
    frame_to_pos_x(d, q, a1);
    const Vec3 r = rotate(q, d);
    // the reference's near-+X Taylor branch is good to ~|d_y / d_x|^3 < 6e-6
    EXPECT_NEAR(r.x(), d.norm(), 1e-5 * d.norm()) << d.transpose();
    EXPECT_NEAR(r.y(), 0.0, 1e-5 * d.norm()) << d.transpose();
    EXPECT_NEAR(r.z(), 0.0, 1e-5 * d.norm()) << d.transpose();
    EXPECT_LT((a1 - rotvec(q)).norm(), 1e-12) << d.transpose();
    const Vec3 n = d.normalized();
    if (std::fabs(d.y() / d.x()) >= 1.732e-2 || std::fabs(d.z() / d.x()) >= 1.732e-2) {
      const double theta = std::acos(n.x()), k = 1.0 / std::hypot(n.y(), n.z());
      const Quat ref{std::cos(theta / 2), 0.0, n.z() * k * std::sin(theta / 2),
                     -n.y() * k * std::sin(theta / 2)};
      // to rounding: both forms lose digits as theta -> pi (1 + n_x and acos(n_x) cancel)
      EXPECT_NEAR(q.w, ref.w, 1e-13) << d.transpose();
      EXPECT_NEAR(q.y, ref.y, 1e-13) << d.transpose();
      EXPECT_NEAR(q.z, ref.z, 1e-13) << d.transpose();
      EXPECT_NEAR(q.w * q.w + q.y * q.y + q.z * q.z, 1.0, 1e-13);
      EXPECT_EQ(q.x, 0.0);
    }
  }
  Quat id;
  Vec3 a0;
  frame_to_pos_x(Vec3::Zero(), id, a0);
  EXPECT_EQ(id.w, 1.0);
  EXPECT_EQ(a0, Vec3::Zero());
  // the small-ratio branch looks at y/x and z/x only, as the reference: -X counts as aligned
  Quat back;
  frame_to_pos_x(Vec3(-1, 0, 0), back, a0);
  EXPECT_EQ(back.w, 1.0);
}

}  // namespace
}  // namespace softevo::physics
