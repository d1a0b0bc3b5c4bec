// Animated GIF output (render/gif.hpp), decoded back with giflib: one frame per video frame,
// the frame delay in hundredths, looping, colours close to the rendered frames, and the refusals.
#include "render/gif.hpp"

#include <gif_lib.h>
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <limits>
#include <string>
#include <vector>

#include "tests/io/tmp_dir.hpp"
#include "tests/render/moving_bar.hpp"

namespace softevo::render {
namespace {

using test::MovingBar;
using test::small_scene;

struct Decoded {
  GifFileType* gif = nullptr;
  explicit Decoded(const std::string& path) {
    int error = 0;
    gif = DGifOpenFileName(path.c_str(), &error);
    if (gif == nullptr) throw std::runtime_error(GifErrorString(error));
    if (DGifSlurp(gif) == GIF_ERROR) throw std::runtime_error(GifErrorString(gif->Error));
  }
  ~Decoded() { DGifCloseFile(gif, nullptr); }
  Decoded(const Decoded&) = delete;
  Decoded& operator=(const Decoded&) = delete;
};

TEST(Gif, FrameDelayIsWholeHundredthsAndAtLeastTwo) {
  EXPECT_EQ(gif_frame_delay(10.0), 10);
  EXPECT_EQ(gif_frame_delay(25.0), 4);
  EXPECT_EQ(gif_frame_delay(30.0), 3);   // 3.33 rounded
  EXPECT_EQ(gif_frame_delay(100.0), 2);  // 1 is drawn as 10 by browsers
  EXPECT_EQ(gif_frame_delay(0.01), 10000);
  EXPECT_THROW(gif_frame_delay(0.0), std::runtime_error);
  EXPECT_THROW(gif_frame_delay(std::numeric_limits<double>::quiet_NaN()), std::runtime_error);
}

TEST(Gif, EveryVideoFrameLoopingWithOnePaletteAndCloseColours) {
  const softevo::test::TmpDir dir;
  const MovingBar bar;
  const VideoOptions options{10.0, 96, 64};
  const std::string out = dir.file("bar.gif");
  const VideoWritten written = write_gif(bar.clip(), View::side, options, small_scene(), out);
  std::vector<Image> frames;
  render_frames(bar.clip(), View::side, options, small_scene(), [&](const Image& image) {
    frames.push_back(image);
    return true;
  });
  ASSERT_EQ(written.frames, static_cast<int>(frames.size()));
  EXPECT_EQ(written.frames, 11);  // 0, 0.1, ..., 1.0 s
  EXPECT_EQ(written.width, 96);
  EXPECT_EQ(written.height, 64);

  const Decoded d(out);
  ASSERT_EQ(d.gif->ImageCount, written.frames);
  EXPECT_EQ(d.gif->SWidth, 96);
  EXPECT_EQ(d.gif->SHeight, 64);
  ASSERT_NE(d.gif->SColorMap, nullptr);  // one global palette
  // giflib files the extensions before the first image with that image.
  bool loops = false;
  const SavedImage& first = d.gif->SavedImages[0];
  for (int e = 0; e + 1 < first.ExtensionBlockCount; ++e) {
    const ExtensionBlock& b = first.ExtensionBlocks[e];
    if (b.Function == APPLICATION_EXT_FUNC_CODE && b.ByteCount == 11 &&
        std::string(reinterpret_cast<const char*>(b.Bytes), 11) == "NETSCAPE2.0") {
      const ExtensionBlock& count = first.ExtensionBlocks[e + 1];
      loops =
          count.ByteCount == 3 && count.Bytes[0] == 1 && count.Bytes[1] == 0 && count.Bytes[2] == 0;
    }
  }
  EXPECT_TRUE(loops) << "no NETSCAPE2.0 loop-forever extension";

  double worst_mean_error = 0.0;
  for (int f = 0; f < d.gif->ImageCount; ++f) {
    const SavedImage& image = d.gif->SavedImages[f];
    EXPECT_EQ(image.ImageDesc.Width, 96);
    EXPECT_EQ(image.ImageDesc.ColorMap, nullptr) << "frame " << f << " has its own palette";
    GraphicsControlBlock control{};
    ASSERT_EQ(DGifSavedExtensionToGCB(d.gif, f, &control), GIF_OK);
    EXPECT_EQ(control.DelayTime, 10);
    // Colours: the palette's nearest colour to each rendered pixel.
    const Image& rendered = frames[static_cast<std::size_t>(f)];
    double error = 0.0;
    long unlike_corner = 0;
    const GifColorType& corner = d.gif->SColorMap->Colors[image.RasterBits[0]];
    for (int p = 0; p < 96 * 64; ++p) {
      const GifColorType& c = d.gif->SColorMap->Colors[image.RasterBits[p]];
      const std::uint8_t* r = rendered.rgb.data() + 3 * p;
      error += std::abs(c.Red - r[0]) + std::abs(c.Green - r[1]) + std::abs(c.Blue - r[2]);
      if (std::abs(c.Red - corner.Red) + std::abs(c.Green - corner.Green) +
              std::abs(c.Blue - corner.Blue) >
          30)
        ++unlike_corner;
    }
    worst_mean_error = std::max(worst_mean_error, error / (3.0 * 96 * 64));
    EXPECT_GT(unlike_corner, 96 * 64 / 50) << "frame " << f << " shows no robot";
  }
  // A few shading levels at most (the renderer draws far fewer than 256 colours here).
  EXPECT_LT(worst_mean_error, 4.0);
}

TEST(Gif, ExistingFileIsKeptWithoutReplaceAndSinglePoseRefused) {
  const softevo::test::TmpDir dir;
  const MovingBar bar;
  const std::string out = dir.file("old.gif");
  { std::ofstream(out) << "keep me"; }
  EXPECT_THROW(write_gif(bar.clip(), View::side, {10.0, 64, 48}, small_scene(), out),
               std::runtime_error);
  std::ifstream in(out);
  std::string text;
  std::getline(in, text);
  EXPECT_EQ(text, "keep me");
  write_gif(bar.clip(), View::side, {10.0, 64, 48}, small_scene(), out, Overwrite::replace);
  EXPECT_EQ(Decoded(out).gif->ImageCount, 11);

  const Clip still{bar.body, {bar.poses.front()}, "still"};
  EXPECT_THROW(write_gif(still, View::side, {10.0, 64, 48}, small_scene(), dir.file("s.gif")),
               std::runtime_error);
  EXPECT_FALSE(std::filesystem::exists(dir.file("s.gif")));
  // Nothing but the output is left in the directory (no temporary).
  int entries = 0;
  for ([[maybe_unused]] const auto& e : std::filesystem::directory_iterator(dir.path)) ++entries;
  EXPECT_EQ(entries, 1);
}

}  // namespace
}  // namespace softevo::render
