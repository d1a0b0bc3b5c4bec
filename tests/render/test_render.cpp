// Unit tests of the software renderer (render/render.hpp): colours, projection,
// orientation, chamber placement and the target line, on small hand-made bodies whose
// projection is known.
#include "render/render.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

namespace softevo::render {
namespace {

constexpr double kS = 0.01;  // voxel size [m]

// A bar of `n` voxels along x, material k, optionally with a chamber cell in the middle of a
// 3x3x3 block instead.
BodyPlan bar(int n, int material) {
  BodyPlan plan;
  plan.lattice = {n, 1, 1};
  plan.cells.assign(static_cast<std::size_t>(n), material);
  plan.voxel_size = kS;
  return plan;
}

BodyPlan block_with_chamber(bool chamber) {
  BodyPlan plan;
  plan.lattice = {3, 3, 3};
  plan.cells.assign(27, 10);
  if (chamber) plan.cells[plan.cell_index(1, 1, 1)] = kFirstChamberCell;
  plan.voxel_size = kS;
  return plan;
}

struct Bounds {
  int x0 = 1 << 30, y0 = 1 << 30, x1 = -1, y1 = -1;
  long count = 0;
};

// Bounding box of pixels where blue clearly dominates red and green (stiff material).
Bounds blue_bounds(const Image& img) {
  Bounds b;
  for (int y = 0; y < img.height; ++y) {
    for (int x = 0; x < img.width; ++x) {
      const auto p = img.pixel(x, y);
      if (p[2] > p[0] + 40 && p[2] > p[1] + 40) {
        b.x0 = std::min(b.x0, x);
        b.x1 = std::max(b.x1, x);
        b.y0 = std::min(b.y0, y);
        b.y1 = std::max(b.y1, y);
        ++b.count;
      }
    }
  }
  return b;
}

long red_line_pixels(const Image& img, int x_from, int x_to) {
  long n = 0;
  for (int y = 0; y < img.height; ++y) {
    for (int x = x_from; x < x_to; ++x) {
      const auto p = img.pixel(x, y);
      if (p[0] > 150 && p[1] < 90 && p[2] < 90) ++n;
    }
  }
  return n;
}

// 8-bit sRGB to CIELAB (D65), written out here independently of the renderer's inverse.
std::array<double, 3> srgb_to_lab(std::array<std::uint8_t, 3> c) {
  double lin[3];
  for (int i = 0; i < 3; ++i) {
    const double v = c[static_cast<std::size_t>(i)] / 255.0;
    lin[i] = v <= 0.04045 ? v / 12.92 : std::pow((v + 0.055) / 1.055, 2.4);
  }
  const double x = (0.4124 * lin[0] + 0.3576 * lin[1] + 0.1805 * lin[2]) / 0.95047;
  const double y = 0.2126 * lin[0] + 0.7152 * lin[1] + 0.0722 * lin[2];
  const double z = (0.0193 * lin[0] + 0.1192 * lin[1] + 0.9505 * lin[2]) / 1.08883;
  const auto f = [](double t) {
    return t > 216.0 / 24389.0 ? std::cbrt(t) : (24389.0 / 27.0 * t + 16.0) / 116.0;
  };
  return {116.0 * f(y) - 16.0, 500.0 * (f(x) - f(y)), 200.0 * (f(y) - f(z))};
}

TEST(RenderColour, SoftRedToStiffBlueInEqualPerceivedSteps) {
  constexpr int kMaterials = 10;
  std::vector<std::array<double, 3>> lab;
  for (int k = 1; k <= kMaterials; ++k) lab.push_back(srgb_to_lab(material_colour(k, kMaterials)));
  // Ends at the documented lightness (within the 8-bit rounding, ~0.5 L*).
  EXPECT_NEAR(lab.front()[0], kSoftLightness, 0.6);
  EXPECT_NEAR(lab.back()[0], kStiffLightness, 0.6);
  // The softest is red, the stiffest blue.
  const auto soft = material_colour(1, kMaterials), stiff = material_colour(kMaterials, kMaterials);
  EXPECT_GT(soft[0], soft[2] + 100);
  EXPECT_GT(soft[0], soft[1] + 100);
  EXPECT_GT(stiff[2], stiff[0] + 80);
  EXPECT_GT(stiff[2], stiff[1] + 80);
  // Lightness falls with stiffness, and every step is the same colour difference: on the helix
  // dE = sqrt(dL^2 + (C dh)^2) = sqrt((26/9)^2 + (70 x 98 deg / 9 in rad)^2) = 13.62.
  const double expected_step =
      std::hypot(26.0 / 9.0, 70.0 * (98.0 * 3.14159265358979 / 180.0) / 9.0);
  for (std::size_t k = 1; k < lab.size(); ++k) {
    EXPECT_LT(lab[k][0], lab[k - 1][0]) << "material " << k + 1;
    const double step =
        std::hypot(lab[k][0] - lab[k - 1][0], lab[k][1] - lab[k - 1][1], lab[k][2] - lab[k - 1][2]);
    EXPECT_NEAR(step, expected_step, 0.05 * expected_step) << "material " << k + 1;
  }
  // One material only: the stiff end.
  EXPECT_EQ(material_colour(1, 1), stiff);
}

TEST(RenderImage, TopViewShowsTheBodyWhereTheCameraPutsIt) {
  const Body body = scene::body_from_plan(bar(5, 10));
  const Pose pose = scene::rest_pose(body);
  // Top view, 2000 pixel/m, centred on the bar's middle voxel: the bar is 5 cm = 100 px long
  // and 1 cm = 20 px wide, centred in a 300 x 200 image.
  Camera cam = view_camera(View::top, 300, 200);
  cam.scale = 2000.0;
  cam.center = Eigen::Vector3d(2 * kS, 0.0, 0.0);
  SceneOptions opt;
  opt.supersample = 1;
  const Image img = render_poses(body, {pose}, cam, opt);
  ASSERT_EQ(img.width, 300);
  ASSERT_EQ(img.height, 200);
  const Bounds b = blue_bounds(img);
  EXPECT_NEAR(b.x1 - b.x0 + 1, 100, 3);
  EXPECT_NEAR(b.y1 - b.y0 + 1, 20, 3);
  EXPECT_NEAR(0.5 * (b.x0 + b.x1), 150, 2);
  EXPECT_NEAR(0.5 * (b.y0 + b.y1), 100, 2);
}

TEST(RenderImage, OrientationTurnsTheCubes) {
  // One voxel seen from above: turning it 45 degrees about z makes its footprint wider
  // (diagonal sqrt(2) s instead of s).
  const Body body = scene::body_from_plan(bar(1, 10));
  Pose pose = scene::rest_pose(body);
  Camera cam = view_camera(View::top, 200, 200);
  cam.scale = 5000.0;
  cam.center = Eigen::Vector3d::Zero();
  SceneOptions opt;
  opt.supersample = 1;
  const Bounds straight = blue_bounds(render_poses(body, {pose}, cam, opt));
  pose.orientation[0] = Eigen::Quaterniond(Eigen::AngleAxisd(M_PI / 4, Eigen::Vector3d::UnitZ()));
  const Bounds turned = blue_bounds(render_poses(body, {pose}, cam, opt));
  EXPECT_NEAR(straight.x1 - straight.x0 + 1, 50, 2);
  EXPECT_NEAR(turned.x1 - turned.x0 + 1, 50 * std::sqrt(2.0), 3);
  // Same area up to the outline (rotation preserves area).
  EXPECT_NEAR(static_cast<double>(turned.count) / straight.count, 1.0, 0.1);
}

TEST(RenderImage, MovingThePoseMovesTheImage) {
  const Body body = scene::body_from_plan(bar(2, 10));
  Pose pose = scene::rest_pose(body);
  Camera cam = view_camera(View::side, 400, 200);
  cam.scale = 2000.0;
  cam.center = Eigen::Vector3d(0.005, 0.0, 0.0);
  SceneOptions opt;
  opt.supersample = 1;
  opt.floor = false;
  const Bounds before = blue_bounds(render_poses(body, {pose}, cam, opt));
  for (auto& p : pose.position) p.x() += 0.03;  // 3 cm forward = 60 px to the right
  const Bounds after = blue_bounds(render_poses(body, {pose}, cam, opt));
  EXPECT_NEAR(after.x0 - before.x0, 60, 1);
  EXPECT_NEAR(after.y0 - before.y0, 0, 1);
}

TEST(RenderImage, ChamberShowsDarkThroughTheBody) {
  Camera cam = view_camera(View::top, 120, 120);
  cam.scale = 3000.0;
  cam.center = Eigen::Vector3d(kS, kS, kS);
  SceneOptions opt;
  opt.supersample = 1;
  auto centre_brightness = [&](bool chamber) {
    const Body body = scene::body_from_plan(block_with_chamber(chamber));
    const auto p = render_poses(body, {scene::rest_pose(body)}, cam, opt).pixel(60, 60);
    return p[0] + p[1] + p[2];
  };
  EXPECT_LT(centre_brightness(true) + 60, centre_brightness(false));
}

TEST(RenderImage, ChamberCellsFollowTheirWalls) {
  // The whole block moved by 2 cm: the dark centre moves with it (chamber cells are placed
  // from their wall voxels, they have no position of their own).
  const Body body = scene::body_from_plan(block_with_chamber(true));
  Pose pose = scene::rest_pose(body);
  for (auto& p : pose.position) p.x() += 0.02;
  Camera cam = view_camera(View::top, 200, 120);
  cam.scale = 3000.0;
  cam.center = Eigen::Vector3d(kS + 0.01, kS, kS);
  SceneOptions opt;
  opt.supersample = 1;
  const Image img = render_poses(body, {pose}, cam, opt);
  const auto at_chamber = img.pixel(100 + 30, 60);    // block centre (x = 3 cm) is at 130 px
  const auto at_wall = img.pixel(100 + 30 + 36, 60);  // 1.2 cm further: wall, no chamber
  EXPECT_LT(at_chamber[0] + at_chamber[1] + at_chamber[2] + 60,
            at_wall[0] + at_wall[1] + at_wall[2]);
}

// Issue 39: voxels were drawn as rigid cubes of the rest size at their centres, so a stretched
// or inflated body fell apart into detached cubes. Each voxel is drawn from its corners, which
// follow the strains of its links, and the corners neighbours share meet (docs/rendering.md
// "Deformed voxels"): a bar of two voxels pulled to twice its rest length is one body from end
// to end, 3 cm long (half a voxel beyond each centre on the free ends).
TEST(RenderImage, AStretchedBodyIsDrawnAsOneBody) {
  const Body body = scene::body_from_plan(bar(2, 10));
  Pose pose = scene::rest_pose(body);
  pose.position[1].x() = 2 * kS;  // the link's strain is 1
  const Surface surface = body_surface(body, pose);
  ASSERT_EQ(surface.vertices.size(), 12u);  // 3 x 2 x 2 lattice vertices
  const Eigen::AlignedBox3d box = pose_bounds(body, pose);
  EXPECT_NEAR(box.min().x(), -0.5 * kS, 1e-15);
  EXPECT_NEAR(box.max().x(), 2.5 * kS, 1e-15);
  EXPECT_NEAR(box.max().y() - box.min().y(), kS, 1e-15);  // not stretched across the link
  EXPECT_EQ(surface.quads.size(), 10u);                   // the skin: 5 faces per voxel

  // Top view, 2000 px/m: the bar from x = -5 mm (image x 110) to 25 mm (170) along its row.
  Camera cam = view_camera(View::top, 240, 80);
  cam.scale = 2000.0;
  cam.center = Eigen::Vector3d(0.0, 0.0, 0.0);
  SceneOptions opt;
  opt.supersample = 1;
  const Image img = render_poses(body, {pose}, cam, opt);
  const int row = 40;
  for (int x = 112; x <= 168; ++x) {
    const auto p = img.pixel(x, row);
    EXPECT_GT(p[2], p[0] + 30) << "x " << x;  // stiff blue all along (its edges darker), no floor
  }
  for (int x : {106, 174}) {  // the floor beyond the ends
    const auto p = img.pixel(x, row);
    EXPECT_LT(std::abs(p[2] - p[0]), 20) << "x " << x;
  }

  // Compressed to half its length and turned, the corners still meet: the four vertices of the
  // shared face are each one vertex, at the mean of both voxels' corners.
  pose.position[1] = Eigen::Vector3d(0.5 * kS, 0.0, 0.0);
  pose.orientation[1] = Eigen::Quaterniond(Eigen::AngleAxisd(0.3, Eigen::Vector3d::UnitX()));
  const Surface squeezed = body_surface(body, pose);
  const Eigen::AlignedBox3d small = pose_bounds(body, pose);
  EXPECT_NEAR(small.min().x(), -0.5 * kS, 1e-15);
  EXPECT_LT(small.max().x(), 1.1 * kS);
}

TEST(RenderImage, TargetLineGoesTheRequestedWay) {
  const Body body = scene::body_from_plan(bar(1, 10));
  const Pose pose = scene::rest_pose(body);
  Camera cam = view_camera(View::top, 200, 100);
  cam.scale = 1000.0;
  cam.center = Eigen::Vector3d::Zero();
  SceneOptions opt;
  opt.supersample = 1;
  opt.target_direction_deg = 0.0;
  const Image ahead = render_poses(body, {pose}, cam, opt);
  EXPECT_GT(red_line_pixels(ahead, 120, 200), 40);
  EXPECT_EQ(red_line_pixels(ahead, 0, 80), 0);
  opt.target_direction_deg = 180.0;
  const Image behind = render_poses(body, {pose}, cam, opt);
  EXPECT_EQ(red_line_pixels(behind, 120, 200), 0);
  EXPECT_GT(red_line_pixels(behind, 0, 80), 40);
}

// A ground that is not the plane (SceneOptions::ground): a raised, tilted strip in front of the
// body is drawn where it is, shaded by its slope, in the side and the top view; the plane
// elsewhere looks as without a ground.
TEST(RenderImage, GroundIsDrawnAsItIs) {
  const Body body = scene::body_from_plan(bar(1, 10));
  const Pose pose = scene::rest_pose(body);
  SceneOptions flat;
  flat.supersample = 1;
  SceneOptions ramp = flat;
  ramp.ground = [](double x, double) {
    return x > 0.05 && x < 0.1 ? -0.005 + 0.5 * (x - 0.05) : -0.005;  // a 26.6 deg ramp
  };
  ramp.ground_min = -0.005;
  ramp.ground_max = 0.02;
  for (View view : {View::top, View::side}) {
    Camera cam = view_camera(view, 300, 150);
    cam.scale = 2000.0;
    cam.center = Eigen::Vector3d(0.05, 0.0, 0.0);
    const Image a = render_poses(body, {pose}, cam, flat);
    const Image b = render_poses(body, {pose}, cam, ramp);
    long differ_ramp = 0, differ_elsewhere = 0;
    for (int y = 0; y < a.height; ++y)
      for (int x = 0; x < a.width; ++x) {
        const std::size_t i = (static_cast<std::size_t>(y) * a.width + x) * 3;
        const bool differs = std::abs(a.rgb[i] - b.rgb[i]) + std::abs(a.rgb[i + 1] - b.rgb[i + 1]) +
                                 std::abs(a.rgb[i + 2] - b.rgb[i + 2]) >
                             6;
        // image x of world x: 150 + (x_w - 0.05) * 2000; the ramp spans 150 .. 250
        if (x > 160 && x < 240) differ_ramp += differs;
        if (x < 140) differ_elsewhere += differs;
      }
    EXPECT_GT(differ_ramp, 500) << "view " << static_cast<int>(view);
    EXPECT_LT(differ_elsewhere, differ_ramp / 4) << "view " << static_cast<int>(view);
  }
}

TEST(RenderImage, SideViewFloorFillsTheFrameBelowTheStage) {
  // A side view framed with room below the floor: every pixel of the bottom row is floor (the
  // floor's grey), none is the pale background, with and without a terrain.
  const Body body = scene::body_from_plan(bar(3, 10));
  const Pose pose = scene::rest_pose(body);
  Camera cam = view_camera(View::side, 200, 150);
  cam.scale = 2000.0;
  cam.center = Eigen::Vector3d(kS, 0.0, 0.02);  // the floor (z = -s/2) sits low in the frame
  SceneOptions flat;
  flat.supersample = 1;
  SceneOptions bumps = flat;
  bumps.ground = [](double x, double) { return -0.005 + 0.003 * std::sin(200.0 * x); };
  bumps.ground_min = -0.008;
  bumps.ground_max = -0.002;
  for (const SceneOptions* opt : {&flat, &bumps}) {
    const Image img = render_poses(body, {pose}, cam, *opt);
    int background = 0;
    for (int x = 0; x < img.width; ++x) {
      const auto p = img.pixel(x, img.height - 1);
      background += p[2] > 225;  // the background is bluish white; the floor is at most 214
    }
    EXPECT_EQ(background, 0) << (opt == &flat ? "flat" : "bumps");
  }
}

TEST(RenderImage, FitCameraKeepsEverythingInside) {
  const Body body = scene::body_from_plan(block_with_chamber(true));
  const Pose pose = scene::rest_pose(body);
  for (View v : {View::side, View::top, View::iso}) {
    const Camera cam = fit_camera(v, pose_bounds(body, pose), 160, 120);
    SceneOptions opt;
    opt.floor = false;
    opt.supersample = 1;
    const Bounds b = blue_bounds(render_poses(body, {pose}, cam, opt));
    ASSERT_GT(b.count, 0);
    EXPECT_GT(b.x0, 0);
    EXPECT_GT(b.y0, 0);
    EXPECT_LT(b.x1, 159);
    EXPECT_LT(b.y1, 119);
    // ... and fills a good part of it.
    EXPECT_GT(b.count, 160 * 120 / 10);
  }
}

TEST(RenderImage, MismatchedPoseIsAnError) {
  const Body body = scene::body_from_plan(bar(3, 5));
  Pose pose = scene::rest_pose(body);
  pose.position.pop_back();
  EXPECT_THROW(render_poses(body, {pose}, view_camera(View::top, 10, 10), {}),
               std::invalid_argument);
  EXPECT_THROW(parse_view("front"), std::invalid_argument);
}

TEST(RenderImage, HstackLaysPanelsSideBySide) {
  const Image a(10, 6, {255, 0, 0});
  const Image b(5, 6, {0, 255, 0});
  const Image s = hstack({a, b}, 2, {0, 0, 0});
  EXPECT_EQ(s.width, 17);
  EXPECT_EQ(s.height, 6);
  EXPECT_EQ(s.pixel(9, 3), (std::array<std::uint8_t, 3>{255, 0, 0}));
  EXPECT_EQ(s.pixel(11, 3), (std::array<std::uint8_t, 3>{0, 0, 0}));
  EXPECT_EQ(s.pixel(12, 3), (std::array<std::uint8_t, 3>{0, 255, 0}));
  EXPECT_EQ(count_pixels_unlike(s, {0, 0, 0}), 15 * 6);
}

}  // namespace
}  // namespace softevo::render
