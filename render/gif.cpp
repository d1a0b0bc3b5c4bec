#include "render/gif.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <stdexcept>
#include <string>
#include <vector>

#ifdef SOFTEVO_HAVE_GIF
#include <fcntl.h>
#include <gif_lib.h>
#include <unistd.h>

#include <array>
#include <cerrno>
#include <cstring>
#include <limits>
#endif

namespace softevo::render {

void require_gif_support([[maybe_unused]] const std::string& path) {
#ifndef SOFTEVO_HAVE_GIF
  throw std::runtime_error("cannot write GIF " + path +
                           ": softevo was built without giflib (install libgif-dev, reconfigure "
                           "and rebuild; .png and .mp4 output work without it)");
#endif
}

int gif_frame_delay(double fps) {
  if (!(fps > 0.0) || !std::isfinite(fps))
    throw std::runtime_error("the frame rate must be a finite number > 0");
  // Browsers draw delays of 0 or 1 hundredth as 10 hundredths: 2 is the shortest honoured.
  const double hundredths = std::round(100.0 / fps);
  return static_cast<int>(std::clamp(hundredths, 2.0, 65535.0));
}

#ifdef SOFTEVO_HAVE_GIF
namespace {

constexpr int kPaletteFrames = 8;  // frames the palette is taken from, spread over the clip

// Colours are looked up by their top 5 bits per channel: 32768 cells, each holding the index of
// the palette colour nearest to the cell's centre.
constexpr int kCellBits = 5;
constexpr int kCells = 1 << (3 * kCellBits);

int cell_of(const std::uint8_t* rgb) {
  constexpr int drop = 8 - kCellBits;
  return (rgb[0] >> drop) << (2 * kCellBits) | (rgb[1] >> drop) << kCellBits | (rgb[2] >> drop);
}

std::vector<std::uint8_t> nearest_palette_index(const ColorMapObject& palette) {
  std::vector<std::uint8_t> nearest(kCells);
  constexpr int drop = 8 - kCellBits;
  constexpr int half = 1 << (drop - 1);
  for (int cell = 0; cell < kCells; ++cell) {
    const int r = ((cell >> (2 * kCellBits)) << drop) + half;
    const int g = (((cell >> kCellBits) & ((1 << kCellBits) - 1)) << drop) + half;
    const int b = ((cell & ((1 << kCellBits) - 1)) << drop) + half;
    int best = 0, best_distance = std::numeric_limits<int>::max();
    for (int i = 0; i < palette.ColorCount; ++i) {
      const GifColorType& c = palette.Colors[i];
      const int dr = r - c.Red, dg = g - c.Green, db = b - c.Blue;
      const int distance = dr * dr + dg * dg + db * db;
      if (distance < best_distance) best_distance = distance, best = i;
    }
    nearest[static_cast<std::size_t>(cell)] = static_cast<std::uint8_t>(best);
  }
  return nearest;
}

// The palette of the sample frames (stacked as one tall image), by giflib's median cut.
ColorMapObject* palette_of(const std::vector<Image>& sample, const std::string& output) {
  std::size_t pixels = 0;
  for (const Image& image : sample) pixels += image.rgb.size() / 3;
  std::vector<GifByteType> red(pixels), green(pixels), blue(pixels), indices(pixels);
  std::size_t at = 0;
  for (const Image& image : sample)
    for (std::size_t p = 0; p < image.rgb.size(); p += 3, ++at) {
      red[at] = image.rgb[p];
      green[at] = image.rgb[p + 1];
      blue[at] = image.rgb[p + 2];
    }
  ColorMapObject* palette = GifMakeMapObject(256, nullptr);
  if (palette == nullptr) throw std::runtime_error("render " + output + ": out of memory");
  int size = 256;
  const int width = sample.front().width;
  if (GifQuantizeBuffer(static_cast<unsigned>(width), static_cast<unsigned>(pixels / width), &size,
                        red.data(), green.data(), blue.data(), indices.data(),
                        palette->Colors) == GIF_ERROR) {
    GifFreeMapObject(palette);
    throw std::runtime_error("render " + output + ": cannot choose the GIF palette");
  }
  // The map's size must be a power of two; unused entries stay black and are never chosen
  // when an equally near used entry comes first.
  palette->ColorCount = 256;
  for (int i = size; i < 256; ++i) palette->Colors[i] = palette->Colors[0];
  return palette;
}

// Owns the encoder: closes it (and its file) however the writing ends.
struct GifWriter {
  GifFileType* gif = nullptr;
  std::string output;
  ~GifWriter() {
    if (gif != nullptr) EGifCloseFile(gif, nullptr);
  }
  void check(int rc, const char* what) const {
    if (rc == GIF_ERROR)
      throw std::runtime_error("render " + output + ": cannot write the GIF (" + what + ": " +
                               GifErrorString(gif->Error) + ")");
  }
  void close() {
    int error = 0;
    GifFileType* g = gif;
    gif = nullptr;
    if (EGifCloseFile(g, &error) == GIF_ERROR)
      throw std::runtime_error("render " + output + ": cannot finish the GIF (" +
                               GifErrorString(error) + ")");
  }
};

}  // namespace
#endif

VideoWritten write_gif(const Clip& clip, View view, const VideoOptions& options,
                       const SceneOptions& scene, const std::string& output, Overwrite overwrite) {
  require_gif_support(output);
  if (clip.poses.size() < 2)
    throw std::runtime_error("render " + output + ": a GIF needs motion (the input has a single " +
                             "pose)");
  const int delay = gif_frame_delay(options.fps);
  VideoOptions sized = options;
  if (sized.width <= 0) sized.width = kGifDefaultWidth;
  if (sized.height <= 0) sized.height = kGifDefaultHeight;
  VideoWritten written;
#ifdef SOFTEVO_HAVE_GIF
  // Pass 1: the palette, from a few frames spread over the clip (frames are drawn, not kept).
  const std::size_t total = video_frame_times(options.fps, clip.poses.back().time).size();
  const int stride =
      static_cast<int>(std::max<std::size_t>(1, (total + kPaletteFrames - 1) / kPaletteFrames));
  std::vector<Image> sample;
  render_frames(
      clip, view, sized, scene,
      [&](const Image& image) {
        sample.push_back(image);
        return true;
      },
      stride);
  ColorMapObject* palette = palette_of(sample, output);
  sample.clear();
  const std::vector<std::uint8_t> nearest = nearest_palette_index(*palette);

  // Pass 2: every frame, streamed into the temporary file beside the output.
  AtomicOutput file(output, overwrite);
  const int fd = ::open(file.temp_path().c_str(), O_WRONLY | O_TRUNC | O_CLOEXEC);
  if (fd < 0) {
    GifFreeMapObject(palette);
    throw std::runtime_error("render " + output + ": cannot open " + file.temp_path() + ": " +
                             std::strerror(errno));
  }
  GifWriter writer;
  writer.output = output;
  int error = 0;
  writer.gif = EGifOpenFileHandle(fd, &error);  // owns fd from here on
  if (writer.gif == nullptr) {
    ::close(fd);
    GifFreeMapObject(palette);
    throw std::runtime_error("render " + output + ": cannot start the GIF (" +
                             GifErrorString(error) + ")");
  }
  EGifSetGifVersion(writer.gif, true);  // GIF89a: frame delays and looping
  written.width = sized.width & ~1;     // render_frames' even sizes
  written.height = sized.height & ~1;
  const int screen = EGifPutScreenDesc(writer.gif, written.width, written.height, 8, 0, palette);
  GifFreeMapObject(palette);  // EGifPutScreenDesc keeps its own copy
  writer.check(screen, "screen");
  // Loop forever: the application extension browsers read ("NETSCAPE2.0", count 0).
  static const char kLoopId[] = "NETSCAPE2.0";
  const std::array<GifByteType, 3> loop_forever = {1, 0, 0};
  writer.check(EGifPutExtensionLeader(writer.gif, APPLICATION_EXT_FUNC_CODE), "loop");
  writer.check(EGifPutExtensionBlock(writer.gif, 11, kLoopId), "loop");
  writer.check(EGifPutExtensionBlock(writer.gif, 3, loop_forever.data()), "loop");
  writer.check(EGifPutExtensionTrailer(writer.gif), "loop");

  GraphicsControlBlock control{};
  control.DisposalMode = DISPOSE_DO_NOT;
  control.DelayTime = delay;
  control.TransparentColor = NO_TRANSPARENT_COLOR;
  std::array<GifByteType, 4> control_bytes{};
  EGifGCBToExtension(&control, control_bytes.data());
  std::vector<GifByteType> line(static_cast<std::size_t>(written.width));
  written.frames = render_frames(clip, view, sized, scene, [&](const Image& image) {
    writer.check(EGifPutExtension(writer.gif, GRAPHICS_EXT_FUNC_CODE, 4, control_bytes.data()),
                 "frame delay");
    writer.check(EGifPutImageDesc(writer.gif, 0, 0, image.width, image.height, false, nullptr),
                 "frame");
    for (int y = 0; y < image.height; ++y) {
      const std::uint8_t* row = image.rgb.data() + static_cast<std::size_t>(y) * image.width * 3;
      for (int x = 0; x < image.width; ++x)
        line[static_cast<std::size_t>(x)] = nearest[static_cast<std::size_t>(cell_of(row + 3 * x))];
      writer.check(EGifPutLine(writer.gif, line.data(), image.width), "pixels");
    }
    return true;
  });
  writer.close();
  file.commit();
#else
  (void)view, (void)scene, (void)overwrite, (void)delay;
#endif
  return written;
}

}  // namespace softevo::render
