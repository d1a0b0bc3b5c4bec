// Animated GIF of a clip: the frames of the video (compose.hpp render_frames), one global
// palette, looping forever. GIF is what READMEs, slides and issue threads show inline.
#pragma once

#include <string>

#include "common/safe_write.hpp"
#include "render/compose.hpp"

namespace softevo::render {

// Throws std::runtime_error naming `path` when softevo was built without giflib.
void require_gif_support(const std::string& path);

// Frame size of a GIF when VideoOptions leaves it at 0 [pixel]: smaller than a video's, since a
// GIF stores every frame losslessly (640 x 360 of a 10 s walk at 25 fps is a few MB).
constexpr int kGifDefaultWidth = 640;
constexpr int kGifDefaultHeight = 360;

// Writes `clip` as an animated GIF to `output` (atomically: an existing regular file is replaced
// only with Overwrite::replace). The palette (at most 256 colours, median cut) is taken from up
// to 8 frames spread over the clip, so it does not change from frame to frame; every frame's
// pixels then map to their nearest palette colour. Frame delays are whole hundredths of a second
// (the format's unit): 1/fps rounded, at least 2 (browsers slow shorter delays down to 10).
// Throws std::runtime_error for a single pose, a frame rate that is not finite and > 0, or an
// encoder failure.
VideoWritten write_gif(const Clip& clip, View view, const VideoOptions& options,
                       const SceneOptions& scene, const std::string& output,
                       Overwrite overwrite = Overwrite::refuse);

// The delay between frames [1/100 s] stored for `fps`.
int gif_frame_delay(double fps);

}  // namespace softevo::render
