#include "render/compose.hpp"
#include "render/font.hpp"

#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <functional>
#include <stdexcept>

namespace softevo::render {
namespace {

constexpr int kMaxSnapshots = 64;
constexpr int kTitleBandFontRows = 11;  // the 7-row font with 2 rows of margin above and below
constexpr double kPi = 3.14159265358979323846;

std::string time_label(double t) {
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "t = %.2f s", t);
  return buffer;
}

// ffmpeg's container name of a video file name: .mp4, .mkv, .webm, .avi.
std::string video_muxer(const std::string& output) {
  std::string ext = std::filesystem::path(output).extension().string();
  for (char& c : ext) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  if (ext == ".mkv") return "matroska";
  if (ext == ".webm") return "webm";
  if (ext == ".avi") return "avi";
  if (ext == ".mp4") return "mp4";
  throw std::runtime_error("render " + output + ": a video must end in .mp4, .mkv, .webm or .avi");
}

std::string shell_quote(const std::string& s) {
  std::string out = "'";
  for (char c : s) {
    if (c == '\'') {
      out += "'\\''";
    } else {
      out += c;
    }
  }
  return out + "'";
}

// `image` below a band of the sky's top colour holding `title`, in the font size the panels'
// labels have (render_poses: one font pixel per 200 image rows, rounded).
Image with_title_band(const Image& image, const std::string& title) {
  // A long title gets a smaller font rather than being cut off at the right edge.
  int size = std::max(1, (image.height + 100) / 200);
  while (size > 1 && 6 * size + text_width(title, size) > image.width) --size;
  const int band = kTitleBandFontRows * size;
  Image out(image.width, image.height + band, {247, 247, 252});
  std::copy(image.rgb.begin(), image.rgb.end(),
            out.rgb.begin() + static_cast<std::ptrdiff_t>(band) * image.width * 3);
  draw_text(out, 6 * size, 2 * size, title, {40, 40, 48}, size);
  return out;
}

// Pixel of a point under an orthographic camera.
Eigen::Vector2d project(const Camera& cam, const Eigen::Vector3d& p) {
  const Eigen::Vector3d d = p - cam.center;
  return {cam.width / 2.0 + d.dot(cam.right) * cam.scale,
          cam.height / 2.0 - d.dot(cam.up) * cam.scale};
}

void dot(Image& image, double x, double y, int radius, std::array<std::uint8_t, 3> colour) {
  const int cx = static_cast<int>(std::lround(x)), cy = static_cast<int>(std::lround(y));
  for (int dy = -radius; dy <= radius; ++dy)
    for (int dx = -radius; dx <= radius; ++dx)
      if (dx * dx + dy * dy <= radius * radius && cx + dx >= 0 && cy + dy >= 0 &&
          cx + dx < image.width && cy + dy < image.height)
        image.set(cx + dx, cy + dy, colour);
}

// A polyline through `points` and an open ring at the first (the start).
void draw_path(Image& image, const Camera& cam, const std::vector<Eigen::Vector3d>& points,
               std::array<std::uint8_t, 3> colour, int size) {
  if (points.empty()) return;
  const int half = std::max(0, size / 2);
  for (std::size_t i = 1; i < points.size(); ++i) {
    const Eigen::Vector2d a = project(cam, points[i - 1]), b = project(cam, points[i]);
    const int steps = std::max(1, static_cast<int>(std::ceil((b - a).norm())));
    for (int k = 0; k <= steps; ++k) {
      const Eigen::Vector2d q = a + (b - a) * (static_cast<double>(k) / steps);
      dot(image, q.x(), q.y(), half, colour);
    }
  }
  const Eigen::Vector2d start = project(cam, points.front());
  const int r = 4 * size;
  for (int k = 0; k < 360; ++k) {
    const double a = k * kPi / 180.0;
    dot(image, start.x() + r * std::cos(a), start.y() + r * std::sin(a), half, colour);
  }
}

}  // namespace

std::size_t pose_at(const std::vector<Pose>& poses, double t, std::size_t from) {
  // |time - t| never rises and then never falls along ascending times (poses may share a
  // time): walk to the end of the nearest run, then back to its first pose.
  const auto gap = [&](std::size_t i) { return std::abs(poses[i].time - t); };
  const std::size_t start = std::min(from, poses.size() - 1);
  std::size_t nearest = start;
  while (nearest + 1 < poses.size() && gap(nearest + 1) <= gap(nearest)) ++nearest;
  while (nearest > start && gap(nearest - 1) == gap(nearest)) --nearest;
  return nearest;
}

Eigen::AlignedBox3d scene_box(const Body& body, const std::vector<Pose>& poses, double floor_z) {
  Eigen::AlignedBox3d box;
  for (const Pose& p : poses) box.extend(pose_bounds(body, p));
  Eigen::Vector3d lo = box.min();
  lo.z() = std::min(lo.z(), floor_z);
  box.extend(lo);
  return box;
}

Image render_still(const Clip& clip, View view, double at, int width, int height,
                   SceneOptions scene) {
  const Pose& pose = clip.poses[pose_at(clip.poses, at)];
  const Camera cam = fit_camera(view, scene_box(clip.body, {pose}, scene.floor_z),
                                width > 0 ? width : 960, height > 0 ? height : 540);
  scene.label = clip.name + (clip.poses.size() > 1 ? "  " + time_label(pose.time) : "");
  return render_poses(clip.body, {pose}, cam, scene);
}

Layout parse_layout(const std::string& name) {
  if (name == "strip") return Layout::strip;
  if (name == "overlay") return Layout::overlay;
  throw std::invalid_argument("layout must be strip or overlay, not '" + name + "'");
}

std::vector<double> timelapse_times(const Timelapse& timelapse, double end) {
  const int n = timelapse.snapshots;
  if (n < 1 || n > kMaxSnapshots)
    throw std::invalid_argument("a time-lapse needs 1 to 64 snapshots, not " + std::to_string(n));
  // n evenly spaced over [start, start + span], by default over the whole clip (issue 39: 0.5 s
  // from 5 s, the old default of side and iso views, showed no motion at all).
  double start = timelapse.start ? *timelapse.start : 0.0;
  const double span = timelapse.span ? *timelapse.span : std::max(0.0, end - start);
  start = std::clamp(start, 0.0, std::max(0.0, end - span));
  std::vector<double> times;
  for (int i = 0; i < n; ++i) times.push_back(n == 1 ? start : start + span * i / (n - 1));
  return times;
}

Image render_timelapse(const Clip& clip, View view, const Timelapse& timelapse, int width,
                       int height, SceneOptions scene) {
  const int n = timelapse.snapshots;
  std::vector<Pose> snaps;
  for (const double t : timelapse_times(timelapse, clip.poses.back().time))
    snaps.push_back(clip.poses[pose_at(clip.poses, t)]);
  const Eigen::AlignedBox3d box = scene_box(clip.body, snaps, scene.floor_z);
  if (timelapse.layout == Layout::strip) {
    const Camera cam = fit_camera(view, box, width > 0 ? width : 360, height > 0 ? height : 300);
    std::vector<Image> panels;
    for (std::size_t i = 0; i < snaps.size(); ++i) {
      SceneOptions o = scene;
      o.label = time_label(snaps[i].time);
      o.legend = scene.legend && i + 1 == snaps.size();  // one scale and colour bar per strip
      panels.push_back(render_poses(clip.body, {snaps[i]}, cam, o));
    }
    // The name goes in a band above all panels: inside the first panel a long name ran into the
    // second one.
    return with_title_band(hstack(panels, 4), clip.name);
  }
  Eigen::AlignedBox3d framed = box;
  if (scene.target_direction_deg) {
    // Keep a stretch of the target line in view ahead of the start.
    const double beta = *scene.target_direction_deg * kPi / 180.0;
    const double reach = std::max(0.1, (box.max() - box.min()).head<2>().norm() * 0.5);
    framed.extend(Eigen::Vector3d(scene.target_origin.x() + reach * std::cos(beta),
                                  scene.target_origin.y() + reach * std::sin(beta), scene.floor_z));
  }
  const Camera cam = fit_camera(view, framed, width > 0 ? width : 960, height > 0 ? height : 720);
  for (int i = 0; i < n; ++i) {
    // Earlier snapshots fainter, the last one at full strength.
    scene.pose_fade.push_back(n == 1 ? 1.0 : 0.35 + 0.65 * i / (n - 1));
  }
  // The title, above the picture (a target line never crosses it), says when each pose was
  // (fainter = earlier) and, for a directed robot, the target direction.
  std::string title = clip.name + "   poses at t =";
  for (std::size_t i = 0; i < snaps.size(); ++i) {
    char t[32];
    std::snprintf(t, sizeof t, "%s %.2f", i == 0 ? "" : ",", snaps[i].time);
    title += t;
  }
  title += " s (fainter = earlier)";
  if (scene.target_direction_deg) {
    char target[48];
    std::snprintf(target, sizeof target, "   target %+.0f deg", *scene.target_direction_deg);
    title += target;
  }
  scene.label.clear();
  Image picture = render_poses(clip.body, snaps, cam, scene);
  if (view == View::top) {
    // The centroid's path up to the last snapshot, a ring at its start.
    std::vector<Eigen::Vector3d> path;
    for (const Pose& p : clip.poses)
      if (p.time <= snaps.back().time + 1e-9) path.push_back(centroid(p));
    const int size = std::max(1, (picture.height + 100) / 200);
    draw_path(picture, cam, path, {30, 30, 30}, size);
  }
  return with_title_band(picture, title);
}

std::optional<std::string> find_on_path(const std::string& program) {
  const char* path = std::getenv("PATH");
  if (path == nullptr) return std::nullopt;
  const std::string dirs = path;
  std::size_t start = 0;
  while (start <= dirs.size()) {
    const std::size_t colon = dirs.find(':', start);
    const std::string dir =
        dirs.substr(start, colon == std::string::npos ? std::string::npos : colon - start);
    const std::string candidate = (dir.empty() ? std::string(".") : dir) + "/" + program;
    if (::access(candidate.c_str(), X_OK) == 0) return candidate;
    if (colon == std::string::npos) break;
    start = colon + 1;
  }
  return std::nullopt;
}

std::vector<double> video_frame_times(double fps, double end) {
  const int frames = static_cast<int>(std::floor(end * fps + 1e-9)) + 1;
  std::vector<double> times;
  times.reserve(static_cast<std::size_t>(frames));
  for (int f = 0; f < frames; ++f) times.push_back(f / fps);
  return times;
}

int render_frames(const Clip& clip, View view, const VideoOptions& options,
                  const SceneOptions& scene, const std::function<bool(const Image&)>& sink,
                  int stride) {
  if (clip.poses.size() < 2) throw std::runtime_error("a video needs motion (a single pose)");
  if (stride < 1) throw std::invalid_argument("render_frames: stride must be at least 1");
  if (!(options.fps > 0.0) || !std::isfinite(options.fps))
    throw std::runtime_error("the frame rate must be a finite number > 0");
  const int width = (options.width > 0 ? options.width : 960) & ~1;  // yuv420p needs even sizes
  const int height = (options.height > 0 ? options.height : 540) & ~1;
  const Pose& first = clip.poses.front();
  Eigen::AlignedBox3d box = scene_box(clip.body, {first}, scene.floor_z);
  const Eigen::Vector3d grow = box.sizes() * 0.9;
  box.extend(box.min() - grow);
  box.extend(box.max() + grow);
  Camera cam = fit_camera(view, box, width, height);
  const Eigen::Vector3d start_centre = cam.center;
  const Eigen::Vector3d start_centroid = centroid(first);
  const std::vector<double> times = video_frame_times(options.fps, clip.poses.back().time);
  std::size_t nearest = 0;
  int given = 0;
  for (std::size_t f = 0; f < times.size(); f += static_cast<std::size_t>(stride)) {
    // Walking on from the last frame's pose: a search from the start for every frame made a
    // long video quadratic in its length.
    nearest = pose_at(clip.poses, times[f], nearest);
    const Pose& pose = clip.poses[nearest];
    Eigen::Vector3d follow = centroid(pose) - start_centroid;
    follow.z() = 0.0;
    cam.center = start_centre + follow;
    SceneOptions o = scene;
    o.label = clip.name + "  " + time_label(pose.time);
    if (!sink(render_poses(clip.body, {pose}, cam, o))) return given;
    ++given;
  }
  return given;
}

VideoWritten write_video(const Clip& clip, View view, const VideoOptions& options,
                         const SceneOptions& scene, const std::string& ffmpeg,
                         const std::string& output, Overwrite overwrite) {
  if (clip.poses.size() < 2) {
    throw std::runtime_error("render " + output + ": a video needs motion (" +
                             "the input has a single pose)");
  }
  if (!(options.fps > 0.0) || !std::isfinite(options.fps))
    throw std::runtime_error("render " + output + ": the frame rate must be a finite number > 0");
  // The temporary's name has no extension, so the container is named explicitly.
  const std::string muxer = video_muxer(output);
  VideoWritten written;
  written.width = (options.width > 0 ? options.width : 960) & ~1;
  written.height = (options.height > 0 ? options.height : 540) & ~1;

  AtomicOutput file(output, overwrite);  // ffmpeg writes the temporary; -y: it exists, empty
  const std::string command = shell_quote(ffmpeg) +
                              " -y -loglevel error -f rawvideo -pix_fmt rgb24 -s " +
                              std::to_string(written.width) + "x" + std::to_string(written.height) +
                              " -r " + std::to_string(options.fps) + " -i - -pix_fmt yuv420p -f " +
                              muxer + " " + shell_quote(file.temp_path());
  FILE* pipe = ::popen(command.c_str(), "w");
  if (pipe == nullptr) throw std::runtime_error("render: cannot start ffmpeg: " + command);
  bool ok = true;
  written.frames = render_frames(clip, view, options, scene, [&](const Image& image) {
    ok = std::fwrite(image.rgb.data(), 1, image.rgb.size(), pipe) == image.rgb.size();
    return ok;
  });
  const int status = ::pclose(pipe);
  if (!ok || status != 0) {
    throw std::runtime_error("render " + output + ": ffmpeg failed (exit status " +
                             std::to_string(status) + ")");
  }
  file.commit();
  return written;
}

}  // namespace softevo::render
