// A small moving body for the composition tests: a bar of 3 voxels moving 1 cm along x per
// 0.1 s, over 1 s (11 poses), and a scene drawn without supersampling (fast).
#pragma once

#include <vector>

#include "render/compose.hpp"

namespace softevo::render::test {

struct MovingBar {
  Body body;
  std::vector<Pose> poses;
  MovingBar() {
    BodyPlan plan;
    plan.lattice = {3, 1, 1};
    plan.cells.assign(3, 10);
    plan.voxel_size = 0.01;
    body = scene::body_from_plan(plan);
    const Pose rest = rest_pose(body);
    for (int f = 0; f <= 10; ++f) {
      Pose p = rest;
      p.time = 0.1 * f;
      for (auto& x : p.position) x.x() += 0.01 * f;
      poses.push_back(p);
    }
  }
  Clip clip() const { return Clip{body, poses, "bar"}; }
};

inline SceneOptions small_scene() {
  SceneOptions scene;
  scene.supersample = 1;
  return scene;
}

}  // namespace softevo::render::test
