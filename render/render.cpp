// Software rasteriser for `softevo render` (see render.hpp for the approach).
#include "render/render.hpp"
#include "render/font.hpp"
#include "scene/cells.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>
#include <optional>
#include <stdexcept>
#include <unordered_map>
#include <utility>

namespace softevo::render {

namespace {

constexpr double kPi = 3.14159265358979323846;

using Rgb = std::array<std::uint8_t, 3>;

struct Colour {
  float r = 0.0F;
  float g = 0.0F;
  float b = 0.0F;
};

Colour to_colour(Rgb c) {
  return {c[0] / 255.0F, c[1] / 255.0F, c[2] / 255.0F};
}

std::uint8_t to_byte(float v) {
  return static_cast<std::uint8_t>(std::lround(std::clamp(v, 0.0F, 1.0F) * 255.0F));
}

// One transparent sample of a face at a pixel, linked into that pixel's list.
struct Fragment {
  float depth;  // [m] along the camera's forward axis
  Colour colour;
  float alpha;
  std::int32_t next;  // index of the next fragment of the same pixel, -1 = end
};

using scene::CellIndex;
using scene::kFaceSteps;

// Chamber cells have no voxel in the simulation: place each one where its face neighbours
// (wall voxels, then already placed chamber cells, pass by pass) say it should be:
// p = mean over neighbours n of (p_n + R_n (c - c_n) s). The orientation is taken from the first
// neighbour in face order. Deterministic: each pass only uses cells placed before it.
void place_chambers(const Body& body, const CellIndex& cells, const Pose& pose,
                    std::vector<Eigen::Vector3d>& position,
                    std::vector<Eigen::Quaterniond>& orientation) {
  const int v = static_cast<int>(body.voxel_cells.size());
  const int c = static_cast<int>(body.chamber_cells.size());
  position.assign(static_cast<std::size_t>(c), Eigen::Vector3d::Zero());
  orientation.assign(static_cast<std::size_t>(c), Eigen::Quaterniond::Identity());
  std::vector<char> known(static_cast<std::size_t>(c), 0);
  auto cell_of = [&](int item) {
    return item < v ? body.voxel_cells[item] : body.chamber_cells[item - v];
  };
  bool progress = true;
  while (progress) {
    progress = false;
    const std::vector<char> known_before = known;
    for (int j = 0; j < c; ++j) {
      if (known[j]) continue;
      Eigen::Vector3d sum = Eigen::Vector3d::Zero();
      int count = 0;
      for (const auto& step : kFaceSteps) {
        const int item = cells.at(body.chamber_cells[j] + step);
        if (item < 0) continue;
        Eigen::Vector3d p;
        Eigen::Quaterniond q;
        if (item < v) {
          p = pose.position[item];
          q = pose.orientation[item];
        } else if (known_before[item - v]) {
          p = position[item - v];
          q = orientation[item - v];
        } else {
          continue;
        }
        const Eigen::Vector3d offset = (body.chamber_cells[j] - cell_of(item)).cast<double>();
        sum += p + q * (offset * body.voxel_size);
        if (count == 0) orientation[j] = q;
        ++count;
      }
      if (count > 0) {
        position[j] = sum / count;
        known[j] = 1;
        progress = true;
      }
    }
  }
  // A chamber cell with no path to a wall (cannot happen for developed bodies) follows the
  // centroid at its rest offset.
  const Eigen::Vector3d shift = centroid(pose) - centroid(rest_pose(body));
  for (int j = 0; j < c; ++j) {
    if (!known[j]) position[j] = body.chamber_cells[j].cast<double>() * body.voxel_size + shift;
  }
}

// The vertices of a body's lattice: corner (i, j, k) of the cells, i.e. cell c has the corners
// c + (0|1, 0|1, 0|1) (cells are in [0, 2^21) per axis), numbered in the order they are first
// asked for.
class VertexGrid {
 public:
  // The index of corner `corner` (0..7: bit 0 = +x, bit 1 = +y, bit 2 = +z) of `cell`.
  int at(const Eigen::Vector3i& cell, int corner) {
    const Eigen::Vector3i v = cell + Eigen::Vector3i(corner & 1, (corner >> 1) & 1, corner >> 2);
    const auto key = (static_cast<std::uint64_t>(static_cast<std::uint32_t>(v.x())) << 42) |
                     (static_cast<std::uint64_t>(static_cast<std::uint32_t>(v.y())) << 21) |
                     static_cast<std::uint64_t>(static_cast<std::uint32_t>(v.z()));
    return index_.try_emplace(key, static_cast<int>(index_.size())).first->second;
  }
  int count() const { return static_cast<int>(index_.size()); }

 private:
  std::unordered_map<std::uint64_t, int> index_;
};

// The four corners (0..7, as VertexGrid::at) of face f (kFaceSteps order) of a cell, in cyclic
// order around the face.
std::array<int, 4> face_corners(int face) {
  const int axis = face / 2;
  const int side = (face % 2 == 0) ? 1 : 0;
  const int u = (axis + 1) % 3, w = (axis + 2) % 3;
  std::array<int, 4> corners{};
  const int steps[4][2] = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
  for (int k = 0; k < 4; ++k) corners[k] = (side << axis) | (steps[k][0] << u) | (steps[k][1] << w);
  return corners;
}

// See render.hpp and docs/rendering.md "Deformed voxels".
Surface deformed_surface(const Body& body, const CellIndex& cells, const Pose& pose,
                         const std::vector<Eigen::Vector3d>& chamber_pos,
                         const std::vector<Eigen::Quaterniond>& chamber_rot) {
  const int v = static_cast<int>(body.voxel_cells.size());
  const int c = static_cast<int>(body.chamber_cells.size());
  const double s = body.voxel_size;
  VertexGrid grid;
  // Per vertex: the sum and count of the voxels' corners, and of the chamber cells' corners.
  std::vector<Eigen::Vector3d> voxel_sum, chamber_sum;
  std::vector<int> voxel_count, chamber_count;
  const auto add = [&](int vertex, const Eigen::Vector3d& p, bool voxel) {
    if (static_cast<std::size_t>(vertex) >= voxel_sum.size()) {
      voxel_sum.resize(vertex + 1, Eigen::Vector3d::Zero());
      chamber_sum.resize(vertex + 1, Eigen::Vector3d::Zero());
      voxel_count.resize(vertex + 1, 0);
      chamber_count.resize(vertex + 1, 0);
    }
    (voxel ? voxel_sum : chamber_sum)[vertex] += p;
    ++(voxel ? voxel_count : chamber_count)[vertex];
  };
  std::vector<Eigen::Matrix3d> rot(static_cast<std::size_t>(v));
  for (int i = 0; i < v; ++i) rot[i] = pose.orientation[i].normalized().toRotationMatrix();
  for (int i = 0; i < v; ++i) {
    // Half the voxel's extent towards each face: half a voxel, stretched by the strain of the
    // link on that side (docs/model.md §2.3: the offset of P in N's frame along the link axis
    // over the rest length, minus 1), the whole link's strain on each of its halves.
    double half[3][2];  // [axis][0 = negative side, 1 = positive side]
    for (int axis = 0; axis < 3; ++axis) {
      for (int side = 0; side < 2; ++side) {
        half[axis][side] = 0.5 * s;
        const int n = cells.at(body.voxel_cells[i] + kFaceSteps[2 * axis + (1 - side)]);
        if (n < 0 || n >= v) continue;  // no link: an empty or chamber cell
        const int lo = side == 1 ? i : n, hi = side == 1 ? n : i;
        const double along = (rot[lo].transpose() * (pose.position[hi] - pose.position[lo]))[axis];
        half[axis][side] = 0.5 * along;
      }
    }
    for (int corner = 0; corner < 8; ++corner) {
      const Eigen::Vector3d offset((corner & 1) ? half[0][1] : -half[0][0],
                                   (corner & 2) ? half[1][1] : -half[1][0],
                                   (corner & 4) ? half[2][1] : -half[2][0]);
      add(grid.at(body.voxel_cells[i], corner), pose.position[i] + rot[i] * offset, true);
    }
  }
  for (int j = 0; j < c; ++j) {
    const Eigen::Matrix3d r = chamber_rot[j].normalized().toRotationMatrix();
    for (int corner = 0; corner < 8; ++corner) {
      const Eigen::Vector3d offset((corner & 1) ? 0.5 * s : -0.5 * s,
                                   (corner & 2) ? 0.5 * s : -0.5 * s,
                                   (corner & 4) ? 0.5 * s : -0.5 * s);
      add(grid.at(body.chamber_cells[j], corner), chamber_pos[j] + r * offset, false);
    }
  }
  Surface surface;
  surface.vertices.resize(static_cast<std::size_t>(grid.count()));
  for (int k = 0; k < grid.count(); ++k)
    surface.vertices[k] = voxel_count[k] > 0 ? Eigen::Vector3d(voxel_sum[k] / voxel_count[k])
                                             : Eigen::Vector3d(chamber_sum[k] / chamber_count[k]);
  // The outer skin of the voxels (chambers count as filled), then the chambers' faces towards
  // anything but another chamber cell.
  for (int i = 0; i < v + c; ++i) {
    const Eigen::Vector3i cell = i < v ? body.voxel_cells[i] : body.chamber_cells[i - v];
    for (int f = 0; f < 6; ++f) {
      const int n = cells.at(cell + kFaceSteps[f]);
      if (i < v ? n >= 0 : n >= v) continue;
      Surface::Quad quad{{}, i};
      const std::array<int, 4> corners = face_corners(f);
      for (int k = 0; k < 4; ++k) quad.vertex[k] = grid.at(cell, corners[k]);
      surface.quads.push_back(quad);
    }
  }
  return surface;
}

struct Raster {
  int width;
  int height;
  double scale;    // [pixel/m] at raster resolution
  double outline;  // width of the dark cube edges [raster pixel]
  const Camera* camera;
  std::vector<float> opaque_depth;  // [m] floor depth per pixel (+inf = none)
  std::vector<std::int32_t> heads;  // first fragment per pixel, -1 = none
  std::vector<Fragment> fragments;

  // Screen position and depth of a world point.
  Eigen::Vector3d project(const Eigen::Vector3d& p) const {
    const Eigen::Vector3d d = p - camera->center;
    return {d.dot(camera->right) * scale + 0.5 * width, 0.5 * height - d.dot(camera->up) * scale,
            d.dot(camera->forward)};
  }
  Eigen::Vector3d project_vector(const Eigen::Vector3d& v) const {
    return {v.dot(camera->right) * scale, -v.dot(camera->up) * scale, v.dot(camera->forward)};
  }
};

// Light from the front-left above (direction towards the light), plus ambient.
const Eigen::Vector3d kLight = Eigen::Vector3d(-0.35, -0.55, 1.0).normalized();
constexpr double kAmbient = 0.5;
constexpr double kDiffuse = 0.5;

// Rasterises one triangle (a, b, c) of a face: a pixel centre lies in it iff its barycentric
// coordinates are all >= 0 (> 0 for the coordinates in `strict`, so that the two triangles of a
// quad do not both draw their shared diagonal); depth is affine in them under orthographic
// projection. Pixels within r.outline of an edge in `outlined` (edge k is the one opposite
// vertex k) are darker and more opaque: the dark voxel edges.
constexpr double kEdgeTolerance = 1e-9;  // [-] in barycentric coordinates

void raster_triangle(Raster& r, const std::array<Eigen::Vector3d, 3>& p, Colour colour, float alpha,
                     std::array<bool, 3> outlined, std::array<bool, 3> strict) {
  const double det =
      (p[1].x() - p[0].x()) * (p[2].y() - p[0].y()) - (p[2].x() - p[0].x()) * (p[1].y() - p[0].y());
  if (std::abs(det) < 1e-9) return;  // seen edge-on: covers no pixel centre
  // Height of the triangle over each edge [pixel]: lambda_k * height_k is a pixel's distance
  // from edge k.
  std::array<double, 3> height{};
  for (int k = 0; k < 3; ++k) {
    const Eigen::Vector3d& e0 = p[(k + 1) % 3];
    const Eigen::Vector3d& e1 = p[(k + 2) % 3];
    height[k] = std::abs(det) / std::max(std::hypot(e1.x() - e0.x(), e1.y() - e0.y()), 1e-12);
  }
  const double min_x = std::min({p[0].x(), p[1].x(), p[2].x()});
  const double max_x = std::max({p[0].x(), p[1].x(), p[2].x()});
  const double min_y = std::min({p[0].y(), p[1].y(), p[2].y()});
  const double max_y = std::max({p[0].y(), p[1].y(), p[2].y()});
  const int x0 = std::max(0, static_cast<int>(std::floor(min_x)));
  const int x1 = std::min(r.width - 1, static_cast<int>(std::ceil(max_x)));
  const int y0 = std::max(0, static_cast<int>(std::floor(min_y)));
  const int y1 = std::min(r.height - 1, static_cast<int>(std::ceil(max_y)));
  for (int py = y0; py <= y1; ++py) {
    for (int px = x0; px <= x1; ++px) {
      const double x = px + 0.5, y = py + 0.5;
      std::array<double, 3> l{};
      bool inside = true;
      for (int k = 0; k < 3 && inside; ++k) {
        const Eigen::Vector3d& e0 = p[(k + 1) % 3];
        const Eigen::Vector3d& e1 = p[(k + 2) % 3];
        l[k] = ((e1.x() - e0.x()) * (y - e0.y()) - (x - e0.x()) * (e1.y() - e0.y())) / det;
        // A little tolerance: a pixel centre on an edge two faces share belongs to at least one.
        inside = strict[k] ? l[k] > kEdgeTolerance : l[k] >= -kEdgeTolerance;
      }
      if (!inside) continue;
      const std::size_t idx = static_cast<std::size_t>(py) * r.width + px;
      const float depth = static_cast<float>(l[0] * p[0].z() + l[1] * p[1].z() + l[2] * p[2].z());
      if (depth >= r.opaque_depth[idx]) continue;
      double edge = std::numeric_limits<double>::infinity();
      for (int k = 0; k < 3; ++k)
        if (outlined[k]) edge = std::min(edge, l[k] * height[k]);
      const bool dark = edge < r.outline;
      const float factor = dark ? 0.55F : 1.0F;
      r.fragments.push_back(
          Fragment{depth, Colour{colour.r * factor, colour.g * factor, colour.b * factor},
                   dark ? std::min(1.0F, alpha + 0.25F) : alpha, r.heads[idx]});
      r.heads[idx] = static_cast<std::int32_t>(r.fragments.size() - 1);
    }
  }
}

// Rasterises one face of the surface, a quad (q0, q1, q2, q3) in world coordinates (in general
// not flat: a deformed voxel's face), as the triangles (q0, q1, q2) and (q0, q2, q3), outlined
// along the quad's four edges only. Lit as one face by the normal of its diagonals' cross
// product, from both sides (a face turned away from the camera is seen from inside the body).
void raster_quad(Raster& r, const std::array<Eigen::Vector3d, 4>& q, Colour base, float alpha) {
  Eigen::Vector3d n = (q[2] - q[0]).cross(q[3] - q[1]);
  if (n.norm() < 1e-300) return;
  n.normalize();
  if (n.dot(r.camera->forward) > 0.0) n = -n;
  const float shade = static_cast<float>(kAmbient + kDiffuse * std::max(0.0, n.dot(kLight)));
  const Colour lit{base.r * shade, base.g * shade, base.b * shade};
  std::array<Eigen::Vector3d, 4> s;
  for (int k = 0; k < 4; ++k) s[k] = r.project(q[k]);
  raster_triangle(r, {s[0], s[1], s[2]}, lit, alpha, {true, false, true}, {false, false, false});
  raster_triangle(r, {s[0], s[2], s[3]}, lit, alpha, {true, true, false}, {false, false, true});
}

// A box of half sizes `half` [m] about `centre`, turned by `rot` (SceneOptions::insets): its six
// faces as quads.
void raster_box(Raster& r, const Eigen::Vector3d& centre, const Eigen::Matrix3d& rot,
                const Eigen::Vector3d& half, Colour colour, float alpha) {
  for (int axis = 0; axis < 3; ++axis) {
    const Eigen::Vector3d a = rot.col((axis + 1) % 3) * half[(axis + 1) % 3];
    const Eigen::Vector3d b = rot.col((axis + 2) % 3) * half[(axis + 2) % 3];
    for (double sign : {1.0, -1.0}) {
      const Eigen::Vector3d c = centre + sign * rot.col(axis) * half[axis];
      raster_quad(r, {c - a - b, c + a - b, c + a + b, c - a + b}, colour, alpha);
    }
  }
}

// Grid spacing [m] for the floor: the finest of 1, 5, 10, 50 cm that is at least 8 output
// pixels wide.
double grid_spacing(double output_scale) {
  for (double g : {0.01, 0.05, 0.1, 0.5, 1.0}) {
    if (g * output_scale >= 8.0) return g;
  }
  return 1.0;
}

bool near_grid_line(double coordinate, double spacing, double half_width) {
  const double m = coordinate - spacing * std::floor(coordinate / spacing);
  return m < half_width || spacing - m < half_width;
}

// Where a ray p + t forward first meets options.ground (between ground_max and ground_min): t and
// a Lambert shade of the surface there (light from the front-left above), or none. Marches in
// steps of `step` [m] (about a quarter of an output pixel) and refines by bisection.
std::optional<std::pair<double, float>> ground_hit(const SceneOptions& options,
                                                   const Eigen::Vector3d& p,
                                                   const Eigen::Vector3d& forward, double step,
                                                   double t_min) {
  const auto below = [&](double t) {
    const Eigen::Vector3d q = p + t * forward;
    return q.z() <= options.ground(q.x(), q.y());
  };
  const double t_top = (options.ground_max - p.z()) / forward.z();
  const double t_bottom = (options.ground_min - p.z()) / forward.z();
  double lo = std::max(t_top, t_min), hi = lo;
  // Below the ground where the stage starts: its cut face where the ground is raised above the
  // plane floor_z (a row's end), nothing below the plane (as the plane's stage).
  if (lo > t_top && below(lo) && (p + lo * forward).z() < options.floor_z) return std::nullopt;
  while (!below(hi)) {
    if (hi >= t_bottom) return std::nullopt;
    lo = hi;
    hi = std::min(hi + step, t_bottom);
  }
  for (int i = 0; i < 20 && hi - lo > 1e-6; ++i) {
    const double mid = 0.5 * (lo + hi);
    (below(mid) ? hi : lo) = mid;
  }
  const Eigen::Vector3d q = p + hi * forward;
  const double e = 2e-4;  // [m]
  const Eigen::Vector3d normal =
      Eigen::Vector3d(options.ground(q.x() - e, q.y()) - options.ground(q.x() + e, q.y()),
                      options.ground(q.x(), q.y() - e) - options.ground(q.x(), q.y() + e), 2 * e)
          .normalized();
  const Eigen::Vector3d light = Eigen::Vector3d(-0.4, -0.6, 0.7).normalized();
  const double lambert = std::max(0.0, normal.dot(light)) / light.z();
  return std::make_pair(hi, static_cast<float>(std::clamp(0.55 + 0.45 * lambert, 0.4, 1.1)));
}

// Floor and background of every raster pixel: colour and depth of the floor plane (or of the
// ground's surface, options.ground).
void draw_floor(Raster& r, std::vector<Colour>& base, const SceneOptions& options,
                const Eigen::AlignedBox3d& scene, int supersample) {
  const Camera& cam = *r.camera;
  const Colour sky_top{0.97F, 0.97F, 0.99F};
  const Colour sky_bottom{0.90F, 0.91F, 0.94F};
  const Colour floor_colour{0.84F, 0.84F, 0.82F};
  const Colour minor_line{0.74F, 0.74F, 0.72F};
  const Colour major_line{0.58F, 0.58F, 0.56F};
  const Colour target_colour{0.86F, 0.08F, 0.08F};
  const double output_scale = r.scale / supersample;
  const double spacing = grid_spacing(output_scale);
  const double line_half = 0.6 * supersample / r.scale;  // [m] ~1.2 output pixels wide
  // A floor seen from the side is a stage a little deeper than the robot's path (y range);
  // from above it is unbounded.
  const bool bounded = std::abs(cam.forward.z()) < 0.35;
  const double y_lo = scene.min().y() - 0.04;
  const double y_hi = scene.max().y() + 0.04;
  Eigen::Vector2d target_dir(0.0, 0.0);
  if (options.target_direction_deg) {
    const double beta = *options.target_direction_deg * kPi / 180.0;
    target_dir = Eigen::Vector2d(std::cos(beta), std::sin(beta));
  }
  // A bounded stage starts at y_lo: the terrain in front of it (a row's near end) is not drawn;
  // the plane floor is (below).
  const auto stage_front = [&](const Eigen::Vector3d& p) {
    return bounded && cam.forward.y() > 1e-9 ? (y_lo - p.y()) / cam.forward.y()
                                             : -std::numeric_limits<double>::infinity();
  };
  for (int py = 0; py < r.height; ++py) {
    const float t_sky = static_cast<float>(py) / std::max(1, r.height - 1);
    const Colour sky{sky_top.r + (sky_bottom.r - sky_top.r) * t_sky,
                     sky_top.g + (sky_bottom.g - sky_top.g) * t_sky,
                     sky_top.b + (sky_bottom.b - sky_top.b) * t_sky};
    for (int px = 0; px < r.width; ++px) {
      const std::size_t idx = static_cast<std::size_t>(py) * r.width + px;
      base[idx] = sky;
      r.opaque_depth[idx] = std::numeric_limits<float>::infinity();
      if (!options.floor || cam.forward.z() > -1e-9) continue;
      const Eigen::Vector3d p = cam.center + cam.right * ((px + 0.5 - 0.5 * r.width) / r.scale) +
                                cam.up * ((0.5 * r.height - (py + 0.5)) / r.scale);
      double t = (options.floor_z - p.z()) / cam.forward.z();
      float shade = 1.0F;
      bool ground_seen = true;
      if (options.ground) {
        const auto hit = ground_hit(options, p, cam.forward, std::max(0.25 / output_scale, 1e-3),
                                    stage_front(p));
        ground_seen = hit.has_value();
        if (!ground_seen && !bounded) continue;
        if (ground_seen) {
          t = hit->first;
          shade = hit->second;
        }
      }
      Eigen::Vector3d q = p + t * cam.forward;
      // In front of a bounded stage the plane floor goes on to the frame's lower edge, so that
      // the picture has no empty band below the stage (its far edge stays the horizon).
      if (bounded && (!ground_seen || q.y() < y_lo)) {
        t = (options.floor_z - p.z()) / cam.forward.z();
        q = p + t * cam.forward;
        shade = 1.0F;
        if (q.y() >= y_lo) continue;  // a ray under a raised stage's cut face: background
      }
      if (bounded && q.y() > y_hi) continue;
      Colour c = floor_colour;
      if (near_grid_line(q.x(), spacing * 10.0, line_half) ||
          near_grid_line(q.y(), spacing * 10.0, line_half)) {
        c = major_line;
      } else if (near_grid_line(q.x(), spacing, line_half * 0.7) ||
                 near_grid_line(q.y(), spacing, line_half * 0.7)) {
        c = minor_line;
      }
      if (options.target_direction_deg) {
        const Eigen::Vector2d rel(q.x() - options.target_origin.x(),
                                  q.y() - options.target_origin.y());
        const double along = rel.dot(target_dir);
        const double across = std::abs(rel.x() * target_dir.y() - rel.y() * target_dir.x());
        if ((along >= 0.0 && across < 2.0 * line_half) || rel.norm() < 4.0 * line_half) {
          c = target_colour;
        }
      }
      base[idx] = {c.r * shade, c.g * shade, c.b * shade};
      r.opaque_depth[idx] = static_cast<float>(t);
    }
  }
}

}  // namespace

Image::Image(int w, int h, std::array<std::uint8_t, 3> fill) : width(w), height(h) {
  if (w <= 0 || h <= 0) throw std::invalid_argument("image size must be positive");
  rgb.resize(static_cast<std::size_t>(w) * h * 3);
  for (std::size_t i = 0; i < rgb.size(); i += 3) std::memcpy(&rgb[i], fill.data(), 3);
}

std::array<std::uint8_t, 3> Image::pixel(int x, int y) const {
  const std::size_t i = (static_cast<std::size_t>(y) * width + x) * 3;
  return {rgb[i], rgb[i + 1], rgb[i + 2]};
}

void Image::set(int x, int y, std::array<std::uint8_t, 3> c) {
  if (x < 0 || y < 0 || x >= width || y >= height) return;
  const std::size_t i = (static_cast<std::size_t>(y) * width + x) * 3;
  std::memcpy(&rgb[i], c.data(), 3);
}

void place_chamber_cells(const Body& body, const Pose& pose, std::vector<Eigen::Vector3d>& position,
                         std::vector<Eigen::Quaterniond>& orientation) {
  const CellIndex cells(body);
  place_chambers(body, cells, pose, position, orientation);
}

View parse_view(const std::string& name) {
  if (name == "side") return View::side;
  if (name == "top") return View::top;
  if (name == "iso") return View::iso;
  throw std::invalid_argument("unknown view '" + name + "' (expected side, top or iso)");
}

Camera view_camera(View view, int width, int height) {
  Camera cam;
  cam.width = width;
  cam.height = height;
  if (view == View::top) {
    cam.forward = -Eigen::Vector3d::UnitZ();
    cam.up = Eigen::Vector3d::UnitY();
    cam.right = Eigen::Vector3d::UnitX();
    return cam;
  }
  // Looking along azimuth `az` (from +x, counter-clockwise), `elevation` below the horizon.
  const double az = (view == View::side ? 90.0 : 45.0) * kPi / 180.0;
  const double el = (view == View::side ? 12.0 : 30.0) * kPi / 180.0;
  cam.forward =
      Eigen::Vector3d(std::cos(el) * std::cos(az), std::cos(el) * std::sin(az), -std::sin(el));
  cam.right = cam.forward.cross(Eigen::Vector3d::UnitZ()).normalized();
  cam.up = cam.right.cross(cam.forward).normalized();
  return cam;
}

Camera fit_camera(View view, const Eigen::AlignedBox3d& box, int width, int height, double margin) {
  Camera cam = view_camera(view, width, height);
  double lo_r = std::numeric_limits<double>::infinity(), hi_r = -lo_r;
  double lo_u = lo_r, hi_u = -lo_r;
  for (int i = 0; i < 8; ++i) {
    const Eigen::Vector3d corner = box.corner(static_cast<Eigen::AlignedBox3d::CornerType>(i));
    lo_r = std::min(lo_r, corner.dot(cam.right));
    hi_r = std::max(hi_r, corner.dot(cam.right));
    lo_u = std::min(lo_u, corner.dot(cam.up));
    hi_u = std::max(hi_u, corner.dot(cam.up));
  }
  const double extent_r = std::max(hi_r - lo_r, 1e-6);
  const double extent_u = std::max(hi_u - lo_u, 1e-6);
  const double usable = std::max(0.05, 1.0 - 2.0 * margin);
  cam.scale = std::min(width * usable / extent_r, height * usable / extent_u);
  cam.center = box.center();
  return cam;
}

Surface body_surface(const Body& body, const Pose& pose) {
  if (pose.position.size() != body.voxel_cells.size() ||
      pose.orientation.size() != body.voxel_cells.size()) {
    throw std::invalid_argument("render: pose has " + std::to_string(pose.position.size()) +
                                " voxels, body has " + std::to_string(body.voxel_cells.size()));
  }
  const CellIndex cells(body);
  std::vector<Eigen::Vector3d> chamber_pos;
  std::vector<Eigen::Quaterniond> chamber_rot;
  place_chambers(body, cells, pose, chamber_pos, chamber_rot);
  return deformed_surface(body, cells, pose, chamber_pos, chamber_rot);
}

Eigen::AlignedBox3d pose_bounds(const Body& body, const Pose& pose) {
  Eigen::AlignedBox3d box;
  for (const Eigen::Vector3d& p : body_surface(body, pose).vertices) box.extend(p);
  return box;
}

namespace {

// CIELAB (D65 white) to 8-bit sRGB, clamped to the gamut (docs/rendering.md, "Stiffness colours").
std::array<std::uint8_t, 3> lab_to_srgb(double lightness, double a, double b) {
  const double fy = (lightness + 16.0) / 116.0;
  const double fx = fy + a / 500.0, fz = fy - b / 200.0;
  // The inverse of CIELAB's cube-root compression, linear below (6/29)^3.
  const auto expand = [](double t) {
    return t > 6.0 / 29.0 ? t * t * t : 3.0 * (6.0 / 29.0) * (6.0 / 29.0) * (t - 4.0 / 29.0);
  };
  const double x = 0.95047 * expand(fx), y = expand(fy), z = 1.08883 * expand(fz);
  const double linear[3] = {3.2406 * x - 1.5372 * y - 0.4986 * z,
                            -0.9689 * x + 1.8758 * y + 0.0415 * z,
                            0.0557 * x - 0.2040 * y + 1.0570 * z};
  std::array<std::uint8_t, 3> out{};
  for (int c = 0; c < 3; ++c) {
    const double v = std::clamp(linear[c], 0.0, 1.0);
    const double encoded = v <= 0.0031308 ? 12.92 * v : 1.055 * std::pow(v, 1.0 / 2.4) - 0.055;
    out[static_cast<std::size_t>(c)] = static_cast<std::uint8_t>(std::lround(255.0 * encoded));
  }
  return out;
}

}  // namespace

std::array<std::uint8_t, 3> material_colour(int material, int material_count) {
  // f = 0 softest (material 1) ... 1 stiffest. A helix in CIELCh: lightness and hue linear in f
  // at constant chroma, so every step of f is the same colour difference (CIE76 dE) and
  // lightness orders the materials (docs/rendering.md, "Stiffness colours"): soft is a light
  // red (L* 58, h 40 deg), stiff a dark blue (L* 32, h 302 deg), through magenta.
  const double f =
      material_count > 1
          ? std::clamp(static_cast<double>(material - 1) / (material_count - 1), 0.0, 1.0)
          : 1.0;
  const double lightness = kSoftLightness + (kStiffLightness - kSoftLightness) * f;
  const double hue_rad = (kSoftHueDeg + (kStiffHueDeg - kSoftHueDeg) * f) * kPi / 180.0;
  return lab_to_srgb(lightness, kMaterialChroma * std::cos(hue_rad),
                     kMaterialChroma * std::sin(hue_rad));
}

namespace {

void fill_rect(Image& image, int x0, int y0, int x1, int y1, std::array<std::uint8_t, 3> colour) {
  for (int y = std::max(0, y0); y < std::min(image.height, y1); ++y)
    for (int x = std::max(0, x0); x < std::min(image.width, x1); ++x) image.set(x, y, colour);
}

// A scale bar of a round length in cm at the bottom left, and the materials' colours from soft
// (left) to stiff (right) at the bottom right. Orthographic cameras: `camera.scale` pixels per
// metre hold everywhere in the picture plane.
void draw_legend(Image& image, const Camera& camera, int material_count, int size) {
  const std::array<std::uint8_t, 3> ink{40, 40, 48};
  const int margin = 6 * size, bar_height = 2 * size;
  const int text_height = 9 * size;
  const int baseline = image.height - margin - text_height;
  if (baseline < image.height / 2) return;  // no room: a tiny picture
  // The longest round length (1, 2, 5 x 10^k cm) under a quarter of the width.
  double length_cm = 0.0;
  for (double decade = 0.1; decade <= 1000.0; decade *= 10.0)
    for (const double step : {1.0, 2.0, 5.0})
      if (step * decade * 0.01 * camera.scale <= image.width / 4.0) length_cm = step * decade;
  if (length_cm > 0.0) {
    const int pixels = static_cast<int>(std::lround(length_cm * 0.01 * camera.scale));
    fill_rect(image, margin, baseline - bar_height, margin + pixels, baseline, ink);
    fill_rect(image, margin, baseline - 3 * bar_height, margin + size, baseline, ink);
    fill_rect(image, margin + pixels - size, baseline - 3 * bar_height, margin + pixels, baseline,
              ink);
    char text[32];
    std::snprintf(text, sizeof text, "%g cm", length_cm);
    draw_text(image, margin, baseline + size, text, ink, size);
  }
  if (material_count < 1) return;
  const int swatch = 5 * size;
  const int right = image.width - margin;
  const int left = right - swatch * material_count;
  if (left < image.width / 2) return;
  for (int k = 1; k <= material_count; ++k)
    fill_rect(image, left + (k - 1) * swatch, baseline - 3 * bar_height, left + k * swatch,
              baseline, material_colour(k, material_count));
  draw_text(image, left, baseline + size, "soft", ink, size);
  draw_text(image, right - text_width("stiff", size), baseline + size, "stiff", ink, size);
}

}  // namespace

std::uint64_t render_buffer_bytes(int width, int height, int supersample) {
  const auto ss = static_cast<std::uint64_t>(std::clamp(supersample, 1, 4));
  const std::uint64_t pixels = static_cast<std::uint64_t>(std::max(width, 0)) *
                               static_cast<std::uint64_t>(std::max(height, 0));
  // Raster::opaque_depth, Raster::heads, base and resolved below, and one Fragment: the robot,
  // framed to fit, covers much of the picture with a few layers of skin, in a vector that grows
  // by doubling (measured: 881 MB peak for gait-closed-walker at 2048 x 2048, supersample 2,
  // --static; this gives 908 MiB). The image's RGB.
  constexpr std::uint64_t kPerSample =
      sizeof(float) + sizeof(std::int32_t) + 2 * sizeof(Colour) + sizeof(Fragment);
  return pixels * ss * ss * kPerSample + pixels * 3;
}

Image render_poses(const Body& body, const std::vector<Pose>& poses, const Camera& camera,
                   const SceneOptions& options) {
  if (poses.empty()) throw std::invalid_argument("render: no pose to draw");
  std::vector<Surface> surfaces;
  for (const Pose& pose : poses) surfaces.push_back(body_surface(body, pose));
  const int ss = std::clamp(options.supersample, 1, 4);
  Raster r{camera.width * ss, camera.height * ss, camera.scale * ss, 0.7 * ss, &camera, {}, {}, {}};
  const std::size_t pixels = static_cast<std::size_t>(r.width) * r.height;
  r.opaque_depth.assign(pixels, std::numeric_limits<float>::infinity());
  r.heads.assign(pixels, -1);
  std::vector<Colour> base(pixels);

  Eigen::AlignedBox3d scene;
  for (const Surface& surface : surfaces)
    for (const Eigen::Vector3d& p : surface.vertices) scene.extend(p);
  draw_floor(r, base, options, scene, ss);

  const int v = static_cast<int>(body.voxel_cells.size());
  for (std::size_t k = 0; k < poses.size(); ++k) {
    const Pose& pose = poses[k];
    const Surface& surface = surfaces[k];
    const float fade =
        k < options.pose_fade.size() ? static_cast<float>(options.pose_fade[k]) : 1.0F;
    for (const Surface::Quad& quad : surface.quads) {
      std::array<Eigen::Vector3d, 4> corners;
      for (int c = 0; c < 4; ++c) corners[c] = surface.vertices[quad.vertex[c]];
      if (quad.item < v) {
        // Only the outer skin of the body (chambers count as filled) is transparent material;
        // inner faces would add up to an opaque block.
        raster_quad(r, corners,
                    to_colour(material_colour(body.voxel_material[quad.item], body.material_count)),
                    static_cast<float>(options.body_alpha) * fade);
        continue;
      }
      // A chamber cell: dark, darker the more the chamber is inflated (1.0 -> 1.2 bar, §3.5).
      // Its faces are the walls' inner faces, which are not drawn (not skin).
      const int j = quad.item - v;
      double inflation = 0.0;
      const int q = body.chamber_index[j];
      // (A chamber that encloses no volume has a NaN pressure: not inflated.)
      if (q >= 0 && static_cast<std::size_t>(q) < pose.chamber_pressure.size() &&
          std::isfinite(pose.chamber_pressure[q])) {
        inflation = std::clamp((pose.chamber_pressure[q] - 1.0e5) / 0.2e5, 0.0, 1.0);
      }
      const float g = static_cast<float>(0.26 - 0.16 * inflation);
      raster_quad(r, corners, Colour{g, g, g * 1.1F},
                  static_cast<float>(options.chamber_alpha) * fade);
    }
    for (const SceneOptions::Inset& inset : options.insets) {
      const Eigen::Matrix3d rot = pose.orientation[inset.voxel].normalized().toRotationMatrix();
      raster_box(r, pose.position[inset.voxel] + rot * inset.centre, rot, 0.5 * inset.size,
                 to_colour(inset.colour), fade);
    }
  }

  // Resolve: blend each pixel's fragments back to front over the floor.
  std::vector<const Fragment*> list;
  std::vector<Colour> resolved(pixels);
  for (std::size_t idx = 0; idx < pixels; ++idx) {
    list.clear();
    for (std::int32_t f = r.heads[idx]; f >= 0; f = r.fragments[f].next) {
      list.push_back(&r.fragments[f]);
    }
    std::sort(list.begin(), list.end(),
              [](const Fragment* a, const Fragment* b) { return a->depth > b->depth; });
    Colour c = base[idx];
    for (const Fragment* f : list) {
      c.r = f->alpha * f->colour.r + (1.0F - f->alpha) * c.r;
      c.g = f->alpha * f->colour.g + (1.0F - f->alpha) * c.g;
      c.b = f->alpha * f->colour.b + (1.0F - f->alpha) * c.b;
    }
    resolved[idx] = c;
  }

  // Box-filter the supersamples down to the output size.
  Image image(camera.width, camera.height, {0, 0, 0});
  const float norm = 1.0F / static_cast<float>(ss * ss);
  for (int y = 0; y < camera.height; ++y) {
    for (int x = 0; x < camera.width; ++x) {
      Colour sum;
      for (int sy = 0; sy < ss; ++sy) {
        for (int sx = 0; sx < ss; ++sx) {
          const Colour& s = resolved[static_cast<std::size_t>(y * ss + sy) * r.width + x * ss + sx];
          sum.r += s.r;
          sum.g += s.g;
          sum.b += s.b;
        }
      }
      image.set(x, y, {to_byte(sum.r * norm), to_byte(sum.g * norm), to_byte(sum.b * norm)});
    }
  }
  const int size = std::max(1, (camera.height + 100) / 200);
  if (!options.label.empty())
    draw_text(image, 6 * size, 6 * size, options.label, {40, 40, 48}, size);
  if (options.legend) draw_legend(image, camera, body.material_count, size);
  return image;
}

Image hstack(const std::vector<Image>& panels, int gap, std::array<std::uint8_t, 3> gap_colour) {
  if (panels.empty()) throw std::invalid_argument("hstack: no panel");
  int width = 0;
  const int height = panels.front().height;
  for (const Image& p : panels) {
    if (p.height != height) throw std::invalid_argument("hstack: panels differ in height");
    width += p.width;
  }
  width += gap * static_cast<int>(panels.size() - 1);
  Image out(width, height, gap_colour);
  int x0 = 0;
  for (const Image& p : panels) {
    for (int y = 0; y < height; ++y) {
      std::memcpy(&out.rgb[(static_cast<std::size_t>(y) * width + x0) * 3],
                  &p.rgb[static_cast<std::size_t>(y) * p.width * 3],
                  static_cast<std::size_t>(p.width) * 3);
    }
    x0 += p.width + gap;
  }
  return out;
}

long count_pixels_unlike(const Image& image, std::array<std::uint8_t, 3> background,
                         int tolerance) {
  long count = 0;
  for (std::size_t i = 0; i + 2 < image.rgb.size(); i += 3) {
    for (int ch = 0; ch < 3; ++ch) {
      if (std::abs(static_cast<int>(image.rgb[i + ch]) - background[ch]) > tolerance) {
        ++count;
        break;
      }
    }
  }
  return count;
}

}  // namespace softevo::render
