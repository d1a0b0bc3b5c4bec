// A robot's plain drawn types (scene/scene.hpp): the body in simulator voxel order with its
// chamber cells, the rest pose on the lattice and the centroid of a pose.
#include "scene/scene.hpp"

#include <gtest/gtest.h>

#include <stdexcept>

namespace softevo::scene {
namespace {

constexpr double kS = 0.01;  // voxel size [m]

// A 3x3x3 block of material 10 with a chamber cell in the middle.
BodyPlan block_with_chamber() {
  BodyPlan plan;
  plan.lattice = {3, 3, 3};
  plan.cells.assign(27, 10);
  plan.cells[plan.cell_index(1, 1, 1)] = kFirstChamberCell;
  plan.voxel_size = kS;
  return plan;
}

TEST(SceneBody, SimulatorVoxelOrderAndChambers) {
  const Body body = body_from_plan(block_with_chamber());
  ASSERT_EQ(body.voxel_cells.size(), 26u);
  EXPECT_EQ(body.voxel_cells[0], Eigen::Vector3i(0, 0, 0));
  EXPECT_EQ(body.voxel_cells[1], Eigen::Vector3i(0, 0, 1));  // z inner
  ASSERT_EQ(body.chamber_cells.size(), 1u);
  EXPECT_EQ(body.chamber_cells[0], Eigen::Vector3i(1, 1, 1));
  EXPECT_EQ(body.chamber_count, 1);
  EXPECT_EQ(body.voxel_size, kS);
  BodyPlan empty;
  empty.lattice = {3, 1, 1};
  empty.cells.assign(3, kEmptyCell);
  EXPECT_THROW(body_from_plan(empty), std::invalid_argument);
  BodyPlan mismatched = block_with_chamber();
  mismatched.cells.pop_back();
  EXPECT_THROW(body_from_plan(mismatched), std::invalid_argument);
}

TEST(ScenePose, RestPoseSitsOnTheLatticeAndItsCentroidIsTheMiddle) {
  const Body body = body_from_plan(block_with_chamber());
  const Pose pose = rest_pose(body);
  ASSERT_EQ(pose.position.size(), body.voxel_cells.size());
  ASSERT_EQ(pose.orientation.size(), body.voxel_cells.size());
  EXPECT_EQ(pose.position[1], Eigen::Vector3d(0.0, 0.0, kS));
  EXPECT_TRUE(pose.orientation[5].isApprox(Eigen::Quaterniond::Identity()));
  // 26 voxels around the empty middle cell: their mean is the middle.
  EXPECT_TRUE(centroid(pose).isApprox(Eigen::Vector3d(kS, kS, kS)));
  EXPECT_EQ(centroid(Pose{}), Eigen::Vector3d::Zero());
}

}  // namespace
}  // namespace softevo::scene
