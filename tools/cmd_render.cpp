// `softevo render`: pictures and videos of a robot, headless (render/render.hpp).
//
// Inputs: a robot file (rest pose, or re-simulated when motion is asked for), a trace written by
// `softevo eval --trace`, or a run archive (genome developed and re-simulated exactly as the
// run evaluated it). Outputs: PNG (single frame, time-lapse strip or overlay) or MP4 through
// ffmpeg.
#include <unistd.h>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "common/config.hpp"
#include "common/robot.hpp"
#include "motion/robot_source.hpp"
#include "render/render.hpp"
#include "tools/commands.hpp"

namespace softevo::cli {

using motion::load_motion;
using motion::Motion;
using motion::MotionRequest;

namespace {

namespace fs = std::filesystem;
using render::Body;
using render::Camera;
using render::Image;
using render::Pose;
using render::View;

// Exit code when video output is asked for but ffmpeg is not installed.
constexpr int kExitNoEncoder = 3;

struct RenderArgs {
  std::string input;
  std::string output;
  std::string view = "side";
  int timelapse = 0;                // snapshots in the time-lapse (0 = single image / video)
  std::optional<double> span;       // [s] time covered by the time-lapse
  std::optional<double> start;      // [s] first snapshot
  std::string layout;               // "strip" | "overlay" ("" = by view)
  double at = 0.0;                  // [s] time of a single image
  std::optional<double> direction;  // [deg] target direction (directed task, top view line)
  int width = 0;                    // [pixel] 0 = default
  int height = 0;
  int supersample = 2;
  double fps = 30.0;              // [1/s] video frame rate
  std::optional<double> seconds;  // [s] simulated time when re-simulating
  std::optional<std::int64_t> generation;
  std::optional<std::int64_t> id;
  bool best = false;
  std::string config_file;  // robot files: config to simulate with
  std::vector<std::string> overrides;
  std::string robot_file;    // traces: body for the chamber cells
  bool static_pose = false;  // robot/archive: draw the rest pose, never simulate
};

std::string lower(std::string s) {
  for (char& c : s) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

// Index of the recorded pose nearest to time t (poses ascending in time).
std::size_t pose_at(const std::vector<Pose>& poses, double t) {
  std::size_t best = 0;
  double best_gap = std::abs(poses[0].time - t);
  for (std::size_t i = 1; i < poses.size(); ++i) {
    const double gap = std::abs(poses[i].time - t);
    if (gap < best_gap) {
      best = i;
      best_gap = gap;
    }
  }
  return best;
}

std::string time_label(double t) {
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "t=%.2fs", t);
  return buffer;
}

// Box around poses and the floor under them.
Eigen::AlignedBox3d scene_box(const Body& body, const std::vector<Pose>& poses, double floor_z) {
  Eigen::AlignedBox3d box;
  for (const Pose& p : poses) box.extend(render::pose_bounds(body, p));
  Eigen::Vector3d lo = box.min();
  lo.z() = std::min(lo.z(), floor_z);
  box.extend(lo);
  return box;
}

std::optional<std::string> find_on_path(const std::string& program) {
  const char* path = std::getenv("PATH");
  if (path == nullptr) return std::nullopt;
  std::string dirs = path;
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

// Video: the camera keeps its scale and follows the centroid over the floor.
int write_video(const Motion& motion, const RenderArgs& args, View view,
                const render::SceneOptions& scene) {
  const auto ffmpeg = find_on_path("ffmpeg");
  if (!ffmpeg) {
    std::fprintf(stderr,
                 "softevo render: video output needs ffmpeg, which is not on PATH (install it, "
                 "e.g. apt-get install ffmpeg), or render a PNG instead\n");
    return kExitNoEncoder;
  }
  if (motion.poses.size() < 2) {
    throw std::runtime_error("render " + args.output + ": a video needs motion (" +
                             "the input has a single pose)");
  }
  const int width = (args.width > 0 ? args.width : 960) & ~1;  // yuv420p needs even sizes
  const int height = (args.height > 0 ? args.height : 540) & ~1;
  const Pose& first = motion.poses.front();
  Eigen::AlignedBox3d box = scene_box(motion.body, {first}, scene.floor_z);
  const Eigen::Vector3d grow = box.sizes() * 0.9;
  box.extend(box.min() - grow);
  box.extend(box.max() + grow);
  Camera cam = render::fit_camera(view, box, width, height);
  const Eigen::Vector3d start_centre = cam.center;
  const Eigen::Vector3d start_centroid = render::centroid(first);

  const std::string command =
      shell_quote(*ffmpeg) + " -y -loglevel error -f rawvideo -pix_fmt rgb24 -s " +
      std::to_string(width) + "x" + std::to_string(height) + " -r " + std::to_string(args.fps) +
      " -i - -pix_fmt yuv420p " + shell_quote(args.output);
  FILE* pipe = ::popen(command.c_str(), "w");
  if (pipe == nullptr) throw std::runtime_error("render: cannot start ffmpeg: " + command);
  const double end = motion.poses.back().time;
  const int frames = static_cast<int>(std::floor(end * args.fps + 1e-9)) + 1;
  bool ok = true;
  for (int f = 0; f < frames && ok; ++f) {
    const double t = f / args.fps;
    const Pose& pose = motion.poses[pose_at(motion.poses, t)];
    Eigen::Vector3d follow = render::centroid(pose) - start_centroid;
    follow.z() = 0.0;
    cam.center = start_centre + follow;
    render::SceneOptions o = scene;
    o.label = motion.name + "  " + time_label(pose.time);
    const Image image = render::render_poses(motion.body, {pose}, cam, o);
    ok = std::fwrite(image.rgb.data(), 1, image.rgb.size(), pipe) == image.rgb.size();
  }
  const int status = ::pclose(pipe);
  if (!ok || status != 0) {
    throw std::runtime_error("render " + args.output + ": ffmpeg failed (exit status " +
                             std::to_string(status) + ")");
  }
  std::printf("wrote %s (%d frames at %.0f fps, %dx%d)\n", args.output.c_str(), frames, args.fps,
              width, height);
  return kExitOk;
}

int run_render(const RenderArgs& args) {
  const View view = render::parse_view(args.view);
  const std::string ext = lower(fs::path(args.output).extension().string());
  const bool video = ext == ".mp4" || ext == ".mkv" || ext == ".webm" || ext == ".avi";
  if (!video && ext != ".png") {
    throw std::invalid_argument("render: output " + args.output +
                                " must end in .png (image) or .mp4 (video)");
  }
  if (!video) render::require_png_support(args.output);
  if (args.timelapse < 0 || args.timelapse > 64) {
    throw std::invalid_argument("render: --timelapse must be between 0 and 64");
  }
  if (video && args.timelapse > 0) {
    throw std::invalid_argument("render: --timelapse makes a PNG; video output shows every frame");
  }
  std::string layout = args.layout;
  if (layout.empty()) layout = view == View::top ? "overlay" : "strip";
  if (layout != "strip" && layout != "overlay") {
    throw std::invalid_argument("render: --layout must be strip or overlay, not '" + layout + "'");
  }

  // How much simulated time the picture needs; none = the rest pose is enough.
  MotionRequest request;
  request.direction_deg = args.direction;
  request.seconds = args.seconds;
  request.static_pose = args.static_pose;
  request.needs_motion = video || args.timelapse > 0 || args.at > 0.0;
  request.generation = args.generation;
  request.id = args.id;
  request.best = args.best;
  request.config_file = args.config_file;
  request.overrides = args.overrides;
  request.robot_file = args.robot_file;
  const Motion motion = load_motion(args.input, request);
  if (request.needs_motion && motion.poses.size() < 2 && !args.static_pose) {
    throw std::runtime_error("render " + args.input + ": no motion to show (single pose)");
  }

  render::SceneOptions scene;
  scene.supersample = args.supersample;
  scene.floor_z = -0.5 * motion.body.voxel_size;
  if (motion.poses.size() > 1) scene.voxel_scale = 1.04;  // deformed: hide the cracks
  const std::optional<double> direction = args.direction ? args.direction : motion.direction_deg;
  if (direction && view != View::side) {
    scene.target_direction_deg = direction;
    scene.target_origin = render::centroid(motion.poses.front());
  }
  if (video) return write_video(motion, args, view, scene);

  const double end = motion.poses.back().time;
  Image image;
  if (args.timelapse == 0) {
    const Pose& pose = motion.poses[pose_at(motion.poses, args.at)];
    const int width = args.width > 0 ? args.width : 960;
    const int height = args.height > 0 ? args.height : 540;
    const Camera cam =
        render::fit_camera(view, scene_box(motion.body, {pose}, scene.floor_z), width, height);
    scene.label = motion.name + (motion.poses.size() > 1 ? "  " + time_label(pose.time) : "");
    image = render::render_poses(motion.body, {pose}, cam, scene);
  } else {
    // Snapshot times: N evenly spaced over [start, start + span].
    const int n = args.timelapse;
    const double span = args.span ? *args.span : (view == View::top ? end : 0.5);
    double start = args.start ? *args.start : (view == View::top ? 0.0 : 5.0);
    start = std::clamp(start, 0.0, std::max(0.0, end - span));
    std::vector<Pose> snaps;
    for (int i = 0; i < n; ++i) {
      const double t = n == 1 ? start : start + span * i / (n - 1);
      snaps.push_back(motion.poses[pose_at(motion.poses, t)]);
    }
    const Eigen::AlignedBox3d box = scene_box(motion.body, snaps, scene.floor_z);
    if (layout == "strip") {
      const int width = args.width > 0 ? args.width : 360;
      const int height = args.height > 0 ? args.height : 300;
      const Camera cam = render::fit_camera(view, box, width, height);
      std::vector<Image> panels;
      for (std::size_t i = 0; i < snaps.size(); ++i) {
        render::SceneOptions o = scene;
        o.label = (i == 0 ? motion.name + "  " : std::string()) + time_label(snaps[i].time);
        panels.push_back(render::render_poses(motion.body, {snaps[i]}, cam, o));
      }
      image = render::hstack(panels, 4);
    } else {
      const int width = args.width > 0 ? args.width : 960;
      const int height = args.height > 0 ? args.height : 720;
      Eigen::AlignedBox3d framed = box;
      if (scene.target_direction_deg) {
        // Keep a stretch of the target line in view ahead of the start.
        const double beta = *scene.target_direction_deg * 3.14159265358979323846 / 180.0;
        const double reach = std::max(0.1, (box.max() - box.min()).head<2>().norm() * 0.5);
        framed.extend(Eigen::Vector3d(scene.target_origin.x() + reach * std::cos(beta),
                                      scene.target_origin.y() + reach * std::sin(beta),
                                      scene.floor_z));
      }
      const Camera cam = render::fit_camera(view, framed, width, height);
      for (int i = 0; i < n; ++i) {
        // Earlier snapshots fainter, the last one at full strength.
        scene.pose_fade.push_back(n == 1 ? 1.0 : 0.35 + 0.65 * i / (n - 1));
      }
      char range[64];
      std::snprintf(range, sizeof range, "  t=%.1f-%.1fs", snaps.front().time, snaps.back().time);
      scene.label = motion.name + range;
      image = render::render_poses(motion.body, snaps, cam, scene);
    }
  }
  render::write_png(image, args.output);
  std::printf("wrote %s (%dx%d)%s\n", args.output.c_str(), image.width, image.height,
              motion.summary.empty() ? "" : ("; " + motion.summary).c_str());
  return kExitOk;
}

}  // namespace

void register_render(CLI::App& app, int& exit_code) {
  auto* cmd = app.add_subcommand(
      "render",
      "draw a robot headless (PNG image or time-lapse, MP4 video through ffmpeg) from a robot "
      "file, an `eval --trace` file or a run archive");
  auto args = std::make_shared<RenderArgs>();
  cmd->add_option("INPUT", args->input, "ROBOT.json, TRACE.h5 or RUN.h5")->required();
  cmd->add_option("-o,--output", args->output, "OUT.png or OUT.mp4")->required();
  cmd->add_option("--view", args->view, "side | top | iso (default side)");
  cmd->add_option("--timelapse", args->timelapse,
                  "N snapshots over --span seconds from --start (thesis figures 4.3 and 4.4)");
  cmd->add_option("--span", args->span,
                  "seconds covered by the time-lapse (default 0.5 s side/iso, whole run top)");
  cmd->add_option("--start", args->start,
                  "time of the first snapshot [s] (default 5 s side/iso, 0 top)");
  cmd->add_option("--layout", args->layout,
                  "strip (panels side by side) | overlay (one scene, earlier poses fainter); "
                  "default strip for side/iso, overlay for top");
  cmd->add_option("--at", args->at, "time of a single image [s] (default 0 = start pose)");
  cmd->add_option("--direction", args->direction,
                  "target direction [deg, counter-clockwise]: directed task simulated towards "
                  "it, red target line in top/iso views");
  cmd->add_option("--width", args->width, "image width [pixel] (strip: per panel)");
  cmd->add_option("--height", args->height, "image height [pixel]");
  cmd->add_option("--supersample", args->supersample, "anti-aliasing samples per axis (1-4)");
  cmd->add_option("--fps", args->fps, "video frame rate (default 30)");
  cmd->add_option("--seconds", args->seconds,
                  "simulated seconds when re-simulating (default task.eval_seconds)");
  cmd->add_option("--generation", args->generation, "archive: generation (default the last)");
  auto* id_opt = cmd->add_option("--id", args->id, "archive: individual id");
  cmd->add_flag("--best", args->best, "archive: the generation's best individual (default)")
      ->excludes(id_opt);
  cmd->add_option("--config", args->config_file,
                  "robot file: config to simulate with (default: thesis defaults)");
  cmd->add_option("--set", args->overrides, "robot file: config override section.key=value");
  cmd->add_option("--robot", args->robot_file,
                  "trace: robot file giving the chamber cells when the trace has none");
  cmd->add_flag("--static", args->static_pose, "draw the start pose, never simulate");
  cmd->callback([&exit_code, args] { exit_code = run_render(*args); });
}

}  // namespace softevo::cli
