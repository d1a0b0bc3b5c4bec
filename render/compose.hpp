// Pictures and videos of a moving body, composed from render_poses (render.hpp): one image at
// a time, a time-lapse (panels side by side, or one scene with earlier poses fainter, thesis
// figures 4.3 and 4.4) and a video piped through ffmpeg with a camera that follows the robot.
// Used by `softevo render`; meant for the viewer too.
#pragma once

#include <cstddef>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "common/safe_write.hpp"
#include "render/render.hpp"

namespace softevo::render {

// What is drawn: a body, its poses ascending in time, and the name the labels show.
struct Clip {
  const Body& body;
  const std::vector<Pose>& poses;  // at least one
  std::string name;
};

// Index of the pose nearest to time t [s], the earlier of two equally near. Poses ascend in
// time, so the search walks on from `from` (a caller asking for ascending times passes its last
// answer: a whole video is then one pass).
std::size_t pose_at(const std::vector<Pose>& poses, double t, std::size_t from = 0);
// Box around the poses' cubes and the floor at `floor_z` [m] under them.
Eigen::AlignedBox3d scene_box(const Body& body, const std::vector<Pose>& poses, double floor_z);

// One image of the pose nearest to `at` [s], framed to fit; size 0 = 960 x 540 pixels.
Image render_still(const Clip& clip, View view, double at, int width, int height,
                   SceneOptions scene);

enum class Layout { strip, overlay };
// "strip" | "overlay"; throws std::invalid_argument otherwise.
Layout parse_layout(const std::string& name);

struct Timelapse {
  int snapshots = 4;            // evenly spaced over [start, start + span]
  std::optional<double> span;   // [s] default: from start to the end of the clip
  std::optional<double> start;  // [s] default: 0; clamped into the clip
  Layout layout = Layout::strip;
};
// Strip: one panel per snapshot (size per panel, 0 = 360 x 300 pixels), each labelled with its
// time, below a title band with the name (11 font rows high, the font's pixel being
// max(1, (height + 100) / 200) image pixels). Overlay: one scene (0 = 960 x 720 pixels), earlier
// snapshots fainter, with the target line kept in view. Throws std::invalid_argument unless 1 <=
// snapshots <= 64.
Image render_timelapse(const Clip& clip, View view, const Timelapse& timelapse, int width,
                       int height, SceneOptions scene);
// The snapshot times [s] render_timelapse shows of a clip whose last pose is at `end` [s].
// Throws std::invalid_argument unless 1 <= snapshots <= 64.
std::vector<double> timelapse_times(const Timelapse& timelapse, double end);

// Full path of an executable `program` on PATH, if any.
std::optional<std::string> find_on_path(const std::string& program);

struct VideoOptions {
  double fps = 30.0;  // [1/s] frames per second of video
  int width = 0;      // [pixel] 0 = 960; rounded down to even (yuv420p)
  int height = 0;     // [pixel] 0 = 540; rounded down to even
};
struct VideoWritten {
  int frames = 0;
  int width = 0;
  int height = 0;
};
// The frame times [s] write_video shows of a clip whose last pose is at `end` [s]: 0, 1/fps, ...
// up to `end`.
std::vector<double> video_frame_times(double fps, double end);
// Encodes the clip at `fps` through `ffmpeg` (a path) into `output`: the camera keeps its scale
// and follows the centroid over the floor. ffmpeg writes a temporary file beside `output` that
// replaces it at the end (common/safe_write.hpp: an existing regular file only with
// Overwrite::replace). Throws std::runtime_error when the clip has a single pose, the frame
// rate is not a finite number > 0 or ffmpeg fails.
VideoWritten write_video(const Clip& clip, View view, const VideoOptions& options,
                         const SceneOptions& scene, const std::string& ffmpeg,
                         const std::string& output, Overwrite overwrite = Overwrite::refuse);
// The frames of that video, in order, to `sink` (false stops); returns the frames given.
// `softevo render` writes them as a PNG sequence when there is no ffmpeg. With `stride` > 1 only
// frames 0, stride, 2 stride, ... are drawn (the others are skipped, not drawn): a sample of
// the video, e.g. for a GIF's palette.
int render_frames(const Clip& clip, View view, const VideoOptions& options,
                  const SceneOptions& scene, const std::function<bool(const Image&)>& sink,
                  int stride = 1);

}  // namespace softevo::render
