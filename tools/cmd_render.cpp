// `softevo render`: pictures and videos of a robot, headless (render/compose.hpp).
//
// Inputs: a robot file (rest pose, or re-simulated when motion is asked for), a trace written by
// `softevo eval --trace`, or a run archive (genome developed and re-simulated exactly as the
// run evaluated it). Outputs: PNG (single frame, time-lapse strip or overlay), an animated GIF
// (giflib) or MP4 through ffmpeg, all written atomically; an existing output is replaced only with
// --force (docs/output-files.md). Every number option is checked for range (NaN included) before
// anything is simulated; --seconds and --direction go through the config's checks.
#include <cstdio>
#include <filesystem>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "common/available_memory.hpp"
#include "common/config.hpp"
#include "common/robot.hpp"
#include "common/safe_write.hpp"
#include "fabricate/fabricate.hpp"
#include "motion/robot_source.hpp"
#include "render/compose.hpp"
#include "render/gif.hpp"
#include "render/png.hpp"
#include "render/render.hpp"
#include "tools/commands.hpp"
#include "tools/elite_cell.hpp"

namespace softevo::cli {

using motion::load_motion;
using motion::Motion;
using motion::MotionRequest;

namespace {

namespace fs = std::filesystem;
using render::Image;

// The inlet channels in a cutaway: the viewer's yellow (view/web/app.js, 0xffc21a).
constexpr std::array<std::uint8_t, 3> kChannelColour = {0xff, 0xc2, 0x1a};
using render::View;

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
  std::string cell;         // a MAP-Elites run: the elite of this cell (tools/elite_cell.hpp)
  std::string config_file;  // robot files: config to simulate with
  std::vector<std::string> overrides;
  std::string robot_file;              // traces: body for the chamber cells
  bool static_pose = false;            // robot/archive: draw the rest pose, never simulate
  std::optional<std::string> cutaway;  // "" = default section, "y=K" = rows y >= K kept
  bool force = false;                  // replace an existing output file
  bool json = false;                   // one JSON object instead of the line
};

std::string lower(std::string s) {
  for (char& c : s) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

void print_written_json(const RenderArgs& args, const char* kind, int width, int height, int frames,
                        const std::string& summary) {
  nlohmann::ordered_json j;
  j["input"] = args.input;
  j["output"] = args.output;
  j["kind"] = kind;
  j["width"] = width;
  j["height"] = height;
  j["frames"] = frames;
  j["summary"] = summary;
  std::printf("%s\n", j.dump().c_str());
}

// Refuses a picture whose buffers cannot fit in the memory left, before anything is simulated
// or allocated (issue 29: 8192 x 8192 at supersample 4, 60 GB, ended in a bare
// std::bad_alloc). One frame is rendered at a time; a strip keeps its panels and joins them.
void check_render_memory(const RenderArgs& args, bool gif, bool strip,
                         const std::optional<AvailableMemory>& available) {
  if (!available) return;
  // The sizes 0 stands for (render/compose.hpp); the overlay's default is 960 x 720.
  const int width = args.width > 0 ? args.width : (gif ? 640 : 960);
  const int height = args.height > 0 ? args.height : (gif ? 360 : 720);
  const int panels = strip ? args.timelapse : 1;
  const std::uint64_t image_bytes =
      static_cast<std::uint64_t>(width) * static_cast<std::uint64_t>(height) * 3;
  const std::uint64_t needed =
      render::render_buffer_bytes(width, height, args.supersample) +
      (panels > 1 ? 2 * image_bytes * static_cast<std::uint64_t>(panels) : 0);
  if (needed <= available->bytes) return;
  throw std::invalid_argument(
      "render: a " + std::to_string(width) + "x" + std::to_string(height) + " image" +
      (panels > 1 ? " per panel (" + std::to_string(panels) + " panels)" : std::string()) +
      " at --supersample " + std::to_string(args.supersample) + " needs about " +
      mebibytes(needed) + " of memory, but " + mebibytes(available->bytes) + " are available (" +
      available->where + "): lower --width and --height, or --supersample (memory grows with " +
      "its square)" + (panels > 1 ? ", or --timelapse" : ""));
}

int run_render(const RenderArgs& args) {
  const View view = render::parse_view(args.view);
  const std::string ext = lower(fs::path(args.output).extension().string());
  const bool gif = ext == ".gif";
  const bool video = gif || ext == ".mp4" || ext == ".mkv" || ext == ".webm" || ext == ".avi";
  if (!video && ext != ".png") {
    throw std::invalid_argument("render: output " + args.output +
                                " must end in .png (image), .gif (animation) or .mp4 (video)");
  }
  if (gif) render::require_gif_support(args.output);
  if (!video) render::require_png_support(args.output);
  const Overwrite overwrite = args.force ? Overwrite::replace : Overwrite::refuse;
  check_output_target(args.output, overwrite);  // before the simulation, not after
  if (video && args.timelapse > 0) {
    throw std::invalid_argument("render: --timelapse makes a PNG; video output shows every frame");
  }
  // A video other than a GIF is encoded by ffmpeg: without it, say so before anything is
  // simulated (issue 39: frames were written and the exit was 0, with no video).
  std::optional<std::string> ffmpeg;
  if (video && !gif) {
    ffmpeg = render::find_on_path("ffmpeg");
    if (!ffmpeg)
      throw std::runtime_error("render: " + args.output +
                               " is encoded by ffmpeg, which is not on PATH: install it (Debian: "
                               "apt-get install ffmpeg) or write an animated GIF (-o " +
                               fs::path(args.output).replace_extension(".gif").string() +
                               "), which needs no ffmpeg");
  }
  render::Timelapse timelapse;
  timelapse.snapshots = args.timelapse;
  timelapse.span = args.span;
  timelapse.start = args.start;
  try {
    timelapse.layout = args.layout.empty()
                           ? (view == View::top ? render::Layout::overlay : render::Layout::strip)
                           : render::parse_layout(args.layout);
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument(std::string("render: --") + e.what());
  }

  check_render_memory(args, gif, args.timelapse > 0 && timelapse.layout == render::Layout::strip,
                      available_memory());

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
  // Only the poses the output shows are kept (memory bounded for long re-simulations).
  if (video) {
    request.shown_times = [fps = args.fps](double end) {
      return render::video_frame_times(fps, end);
    };
  } else if (args.timelapse > 0) {
    request.shown_times = [timelapse](double end) {
      return render::timelapse_times(timelapse, end);
    };
  } else {
    request.shown_times = [at = args.at](double) { return std::vector<double>{at}; };
  }
  Motion motion = load_motion(args.input, request);
  // --cutaway: the cells in front of the section go, the inlet channels behind it are drawn
  // (docs/rendering.md "Cutaway", docs/fabrication.md).
  std::vector<render::SceneOptions::Inset> channels;
  if (args.cutaway) {
    std::optional<int> cut_y;
    if (!args.cutaway->empty()) {
      char* end = nullptr;
      const long y =
          args.cutaway->rfind("y=", 0) == 0 ? std::strtol(args.cutaway->c_str() + 2, &end, 10) : -1;
      if (!end || *end != '\0' || end == args.cutaway->c_str() + 2)
        throw std::invalid_argument("render: --cutaway " + *args.cutaway +
                                    " is not y=ROW (the first lattice row kept)");
      cut_y = static_cast<int>(y);
    }
    fabricate::Cutaway cut = fabricate::cut_away(motion.body, motion.poses, cut_y);
    motion.body = std::move(cut.body);
    motion.poses = std::move(cut.poses);
    for (const fabricate::ChannelPiece& p : cut.channels)
      channels.push_back({p.voxel, p.centre, p.size, kChannelColour});
  }
  if (request.needs_motion && motion.poses.size() < 2 && !args.static_pose) {
    throw std::runtime_error("render " + args.input + ": no motion to show (single pose)");
  }
  // Checks that need the motion: times within it, a direction only for a directed robot.
  const double end_time = motion.poses.back().time;
  const auto within = [&](const char* option, std::optional<double> t) {
    if (t && *t > end_time + 1e-9) {
      char text[200];
      std::snprintf(text, sizeof text, "render: %s %g is beyond the end of the motion (%.3f s%s)",
                    option, *t, end_time,
                    request.needs_motion ? "; --seconds simulates longer" : "");
      throw std::invalid_argument(text);
    }
  };
  within("--at", args.at > 0.0 ? std::optional<double>(args.at) : std::nullopt);
  within("--start", args.start);
  if (args.direction && !motion.direction_deg)
    throw std::invalid_argument("render: --direction " + toml_number(*args.direction) + ": " +
                                args.input +
                                " is not a directed robot (its controller has no direction "
                                "input), so it has no target direction");

  render::SceneOptions scene;
  if (args.cutaway) {
    // Fainter walls and cavities, so that the channels behind them show.
    scene.insets = channels;
    scene.body_alpha = 0.3;
    scene.chamber_alpha = 0.6;
  }
  scene.supersample = args.supersample;
  scene.legend = true;
  scene.floor_z = -0.5 * motion.body.voxel_size;
  if (motion.terrain.kind != physics::TerrainKind::flat) {
    // The surface half a voxel below the height a voxel centre rests at (docs/model.md §2.8a),
    // its range sampled over the ground the robot crosses (and a margin).
    const physics::Terrain terrain = motion.terrain;
    const double half = 0.5 * motion.body.voxel_size;
    scene.ground = [terrain, half](double x, double y) {
      return physics::terrain_height(terrain, x, y) - half;
    };
    Eigen::AlignedBox3d box;
    for (const auto& pose : motion.poses) box.extend(render::pose_bounds(motion.body, pose));
    const double margin = 0.3;  // [m]
    double lo = scene.floor_z, hi = scene.floor_z;
    for (double x = box.min().x() - margin; x <= box.max().x() + margin; x += 0.002)
      for (double y = box.min().y() - margin; y <= box.max().y() + margin; y += 0.002) {
        const double h = scene.ground(x, y);
        lo = std::min(lo, h);
        hi = std::max(hi, h);
      }
    scene.ground_min = lo;
    scene.ground_max = hi;
  }
  const std::optional<double> direction = args.direction ? args.direction : motion.direction_deg;
  if (direction && view != View::side) {
    scene.target_direction_deg = direction;
    scene.target_origin = scene::centroid(motion.poses.front());
  }
  // The title names the status: a killed robot is not to pass for a result.
  const render::Clip clip{
      motion.body, motion.poses,
      motion.status.empty() ? motion.name : motion.name + " (" + motion.status + ")"};
  if (gif) {
    const render::VideoWritten g = render::write_gif(
        clip, view, {args.fps, args.width, args.height}, scene, args.output, overwrite);
    if (args.json)
      print_written_json(args, "gif", g.width, g.height, g.frames, motion.summary);
    else
      std::printf("wrote %s (%d frames, %d/100 s apart, %dx%d)\n", args.output.c_str(), g.frames,
                  render::gif_frame_delay(args.fps), g.width, g.height);
    return kExitOk;
  }
  if (video) {
    const render::VideoWritten v = render::write_video(
        clip, view, {args.fps, args.width, args.height}, scene, *ffmpeg, args.output, overwrite);
    if (args.json)
      print_written_json(args, "video", v.width, v.height, v.frames, motion.summary);
    else
      std::printf("wrote %s (%d frames at %.0f fps, %dx%d)\n", args.output.c_str(), v.frames,
                  args.fps, v.width, v.height);
    return kExitOk;
  }
  const Image image =
      args.timelapse == 0
          ? render::render_still(clip, view, args.at, args.width, args.height, scene)
          : render::render_timelapse(clip, view, timelapse, args.width, args.height, scene);
  render::write_png(image, args.output, overwrite);
  if (args.json)
    print_written_json(args, "image", image.width, image.height, 1, motion.summary);
  else
    std::printf("wrote %s (%dx%d)%s\n", args.output.c_str(), image.width, image.height,
                motion.summary.empty() ? "" : ("; " + motion.summary).c_str());
  return kExitOk;
}

}  // namespace

void register_render(CLI::App& app, int& exit_code) {
  auto* cmd = app.add_subcommand(
      "render",
      "draw a robot headless (PNG image or time-lapse, animated GIF, MP4 video through ffmpeg) "
      "from a robot "
      "file, an `eval --trace` file or a run archive");
  auto args = std::make_shared<RenderArgs>();
  cmd->add_option("INPUT", args->input, "ROBOT.json, TRACE.h5 or RUN.h5")->required();
  cmd->add_option("-o,--output,--out", args->output, "OUT.png, OUT.gif or OUT.mp4")->required();
  cmd->add_option("--view", args->view, "side | top | iso (default side)")
      ->check(CLI::IsMember({"side", "top", "iso"}));
  cmd->add_option("--timelapse", args->timelapse,
                  "N snapshots (1-64) over --span seconds from --start (thesis figures 4.3 and "
                  "4.4); without it a single image or a video")
      ->check(CLI::Range(1, 64));
  cmd->add_option("--span", args->span,
                  "seconds covered by the time-lapse (default: from --start to the end)")
      ->check(finite_in(0.0, 3600.0));
  cmd->add_option("--start", args->start, "time of the first snapshot [s] (default 0)")
      ->check(finite_in(0.0, 3600.0));
  cmd->add_option("--layout", args->layout,
                  "strip (panels side by side) | overlay (one scene, earlier poses fainter); "
                  "default strip for side/iso, overlay for top")
      ->check(CLI::IsMember({"strip", "overlay"}));
  cmd->add_option("--at", args->at, "time of a single image [s] (default 0 = start pose)")
      ->check(finite_in(0.0, 3600.0));
  cmd->add_option("--direction", args->direction,
                  "target direction [deg, counter-clockwise]: directed task simulated towards "
                  "it, red target line in top/iso views")
      ->check(finite_in(-180.0, 180.0));
  // Images are held in memory: 8192 x 8192 at supersample 4 takes about 60 GB, checked
  // against the available memory before anything is allocated (check_render_memory).
  // Below 32 pixels nothing is recognisable.
  cmd->add_option("--width", args->width,
                  "image width [pixel] (32-8192; strip: per panel; default 960, GIF 640)")
      ->check(CLI::Range(32, 8192));
  cmd->add_option("--height", args->height, "image height [pixel] (32-8192; default 540, GIF 360)")
      ->check(CLI::Range(32, 8192));
  cmd->add_option("--supersample", args->supersample, "anti-aliasing samples per axis (1-4)")
      ->check(CLI::Range(1, 4));
  cmd->add_option("--fps", args->fps,
                  "video or GIF frame rate (default 30; a GIF stores 1/fps in whole 1/100 s)")
      ->check(finite_in(0.01, 1000.0));
  add_seconds_option(*cmd, args->seconds, "simulated seconds when re-simulating");
  add_individual_options(*cmd, args->generation, args->id, args->best, &args->cell, "archive: ");
  cmd->add_option("--config", args->config_file,
                  "robot file: config to simulate with (default: the robot file's run config, "
                  "else the thesis defaults)");
  cmd->add_option("--set", args->overrides, "robot file: config override section.key=value");
  cmd->add_option("--robot", args->robot_file,
                  "trace: robot file giving the chamber cells when the trace has none");
  cmd->add_flag("--static", args->static_pose, "draw the start pose, never simulate");
  cmd->add_option("--cutaway", args->cutaway,
                  "section through the body: the lattice rows in front of y=ROW removed (default "
                  "row: the one with the most chamber cells), the chambers' cavities and inlet "
                  "channels shown (docs/fabrication.md)")
      ->expected(0, 1)
      ->type_name("[y=ROW]");
  cmd->add_flag("--force", args->force, "replace an existing output file");
  cmd->add_flag("--json", args->json, "print one JSON object describing what was written");
  cmd->callback([&exit_code, args] {
    select_cell(args->input, args->cell, args->generation, args->id);
    exit_code = run_render(*args);
  });
}

}  // namespace softevo::cli
