// Headless software renderer for voxel robots: no GPU, no display. Used by `softevo render`.
//
// Every voxel is drawn deformed, as the thesis system's viewer draws it: its eight corners follow
// from its simulated position, its orientation and the strains of its links (a voxel stretched
// along a link is drawn longer on that side), and the corners that neighbouring voxels share
// meet at their mean, so a body is drawn as one body however it is stretched or inflated
// (docs/rendering.md "Deformed voxels"). Structural material is semi-transparent and coloured by
// stiffness like the thesis (figure 3.1: blue = stiffest, red = softest); chamber cells, which
// have no voxel of their own in the simulation, are placed between their wall voxels and drawn
// dark, so they show through the body. The projection is orthographic; every face (a quad, in
// general not flat) is drawn as two triangles. Transparency is exact per pixel: all fragments
// are kept in per-pixel lists, sorted by depth and blended back to front over the floor. PNG
// files: render/png.hpp; text: render/font.hpp.
#pragma once

#include <array>
#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "common/body_plan.hpp"
#include "scene/scene.hpp"

namespace softevo::render {

// What the renderer draws: a robot's cells and where they are (scene/scene.hpp, the plain types
// that motion/ produces without depending on the renderer).
using scene::Body;
using scene::Pose;

// 8-bit RGB image, rows top to bottom, 3 bytes per pixel.
struct Image {
  int width = 0;
  int height = 0;
  std::vector<std::uint8_t> rgb;

  Image() = default;
  Image(int w, int h, std::array<std::uint8_t, 3> fill);
  std::array<std::uint8_t, 3> pixel(int x, int y) const;
  void set(int x, int y, std::array<std::uint8_t, 3> c);
};

// The surface drawn of a body in one pose (docs/rendering.md "Deformed voxels"): the lattice's
// vertices (cell corners) where the voxels' deformed corners meet, and the faces that are drawn.
struct Surface {
  // [m] One per lattice vertex a cell touches: the mean of the corners of the voxels that share
  // it; a vertex no voxel touches (inside a chamber) is the mean of the chamber cells' corners.
  std::vector<Eigen::Vector3d> vertices;
  struct Quad {
    std::array<int, 4> vertex;  // indices into `vertices`, in order around the face
    int item;                   // voxel i (< voxels), or voxels + j for chamber cell j
  };
  // The voxels' outer skin (a face towards an empty cell; chambers count as filled), and the
  // chamber cells' faces towards anything but another chamber cell.
  std::vector<Quad> quads;
};
// Throws std::invalid_argument when the pose does not match the body.
Surface body_surface(const Body& body, const Pose& pose);

// Where the chamber cells of `body` are drawn in `pose` (they have no voxel in the simulation):
// between their wall voxels, as the renderer places them. Used by the browser viewer, which
// draws the same picture. One position and orientation per chamber cell.
void place_chamber_cells(const Body& body, const Pose& pose, std::vector<Eigen::Vector3d>& position,
                         std::vector<Eigen::Quaterniond>& orientation);

enum class View { side, top, iso };
// "side" | "top" | "iso"; throws std::invalid_argument otherwise.
View parse_view(const std::string& name);

// Orthographic camera: a pixel (u, v) looks along `forward` from
// center + right * (u - width/2) / scale + up * (height/2 - v) / scale.
struct Camera {
  Eigen::Vector3d center = Eigen::Vector3d::Zero();  // [m]
  Eigen::Vector3d right = Eigen::Vector3d::UnitX();
  Eigen::Vector3d up = Eigen::Vector3d::UnitZ();
  Eigen::Vector3d forward = Eigen::Vector3d::UnitY();
  double scale = 1000.0;  // [pixel/m]
  int width = 640;        // [pixel]
  int height = 480;       // [pixel]
};
// Camera axes of a view. Side: from -y, slightly from above, +x to the right. Top: from +z,
// +x to the right, +y up. Iso: from the front-left, 30 degrees above the floor.
Camera view_camera(View view, int width, int height);
// Same axes, centre and scale chosen so that `box` fills the image with `margin` (fraction of
// the image) left free on each side.
Camera fit_camera(View view, const Eigen::AlignedBox3d& box, int width, int height,
                  double margin = 0.06);
// Bounding box of the surface of a pose (body_surface), chamber cells included.
Eigen::AlignedBox3d pose_bounds(const Body& body, const Pose& pose);

struct SceneOptions {
  double body_alpha = 0.5;     // opacity of one structural face [-]
  double chamber_alpha = 0.9;  // opacity of one chamber face [-]
  int supersample = 2;         // anti-aliasing: render at n x n samples per pixel
  bool floor = true;
  // Visual floor height [m]: a voxel touches the floor when its centre is at z = 0 (§2.8), so
  // the cube's lower face is half a voxel below it.
  double floor_z = -0.005;
  // The ground when it is not that plane (terrain, docs/model.md §2.8a): the surface height [m]
  // at (x, y), and the range of heights it takes where the scene is (the picture looks for the
  // surface between them). Empty = the plane at floor_z.
  std::function<double(double, double)> ground;
  double ground_min = -0.005, ground_max = -0.005;  // [m]
  // Red target line on the floor (thesis figure 4.4): from `target_origin` [m] in direction
  // `target_direction_deg` (counter-clockwise from +x, §7.2).
  std::optional<double> target_direction_deg;
  Eigen::Vector3d target_origin = Eigen::Vector3d::Zero();
  // Opacity factor per pose when several poses are overlaid (time-lapse); empty = all 1.
  std::vector<double> pose_fade;
  std::string label;  // drawn in the top-left corner, "" = none
  // A scale bar in cm (bottom left) and the stiffness colour bar of the materials (bottom
  // right), as a figure in a paper needs them (`softevo render` draws them).
  bool legend = false;
  // Boxes drawn opaque inside voxels, moving with them (`softevo render --cutaway`: the inlet
  // channels of docs/fabrication.md): centre relative to the voxel's centre and size [m], in
  // the voxel's frame.
  struct Inset {
    int voxel = 0;
    Eigen::Vector3d centre = Eigen::Vector3d::Zero(), size = Eigen::Vector3d::Zero();
    std::array<std::uint8_t, 3> colour{};
  };
  std::vector<Inset> insets;
};

// The memory render_poses takes for a width x height image at `supersample` (clamped to 1-4):
// per sample its depth, fragment list head, the floor's and the resolved colours and about one
// fragment of the robot's faces (an estimate: the fragments scale with the area the robot
// covers), and the image. `softevo render` checks it against the available memory before it
// allocates (issue 29: 8192 x 8192 at supersample 4 ended in std::bad_alloc).
std::uint64_t render_buffer_bytes(int width, int height, int supersample);

// Renders one or more poses of the same body into a single image (several poses = overlaid
// time-lapse). Throws std::invalid_argument when a pose does not match the body.
Image render_poses(const Body& body, const std::vector<Pose>& poses, const Camera& camera,
                   const SceneOptions& options);

// Panels side by side (same height), separated by `gap` pixels of colour `gap_colour`.
Image hstack(const std::vector<Image>& panels, int gap,
             std::array<std::uint8_t, 3> gap_colour = {255, 255, 255});
// Number of pixels that differ from `background` by more than `tolerance` in any channel.
long count_pixels_unlike(const Image& image, std::array<std::uint8_t, 3> background,
                         int tolerance = 8);

// Stiffness colour: material k of n from a light red (k = 1, softest) to a dark blue (k = n,
// stiffest) in equal perceived steps with falling lightness (docs/rendering.md).
std::array<std::uint8_t, 3> material_colour(int material, int material_count);
// The map's ends in CIELCh (lightness L*, hue [deg], one chroma).
inline constexpr double kSoftLightness = 58.0, kStiffLightness = 32.0;
inline constexpr double kSoftHueDeg = 400.0, kStiffHueDeg = 302.0;  // 400 = 40 past a turn
inline constexpr double kMaterialChroma = 70.0;

}  // namespace softevo::render
