// Composition of pictures from poses (render/compose.hpp): pose lookup by time, image sizes of
// stills and time-lapses, snapshot spacing, the overlay's fading, and the refusals.
#include "render/compose.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>
#include <string>
#include <vector>

#include "tests/render/moving_bar.hpp"

namespace softevo::render {
namespace {

using test::MovingBar;
using test::small_scene;

TEST(Compose, PoseAtIsTheNearestInTime) {
  const MovingBar bar;
  EXPECT_EQ(pose_at(bar.poses, -1.0), 0u);
  EXPECT_EQ(pose_at(bar.poses, 0.34), 3u);
  EXPECT_EQ(pose_at(bar.poses, 0.36), 4u);
  EXPECT_EQ(pose_at(bar.poses, 99.0), 10u);
  // Walking on from an earlier answer gives the same choice.
  EXPECT_EQ(pose_at(bar.poses, 0.36, 2), 4u);
  EXPECT_EQ(pose_at(bar.poses, 0.36, 4), 4u);
}

TEST(Compose, PoseAtTakesTheEarlierOfEquallyNearAndWalksOverSharedTimes) {
  std::vector<Pose> poses(6);
  const double times[] = {0.0, 0.1, 0.1, 0.2, 0.3, 0.3};
  for (std::size_t i = 0; i < poses.size(); ++i) poses[i].time = times[i];
  EXPECT_EQ(pose_at(poses, 0.25), 3u);  // 0.2 and 0.3 equally near: the earlier
  EXPECT_EQ(pose_at(poses, 0.1), 1u);   // the first of the poses at 0.1
  EXPECT_EQ(pose_at(poses, 0.2), 3u);   // past the shared time 0.1
  EXPECT_EQ(pose_at(poses, 0.4), 4u);   // the first of the last two
  EXPECT_EQ(pose_at(poses, 0.2, 1), 3u);
}

// Issue 39: `render --timelapse 6` of a 10 s robot drew 6 snapshots within 0.5 s (5.0 ... 5.5 s),
// which show no motion. By default the snapshots span the whole clip, in every view; --start
// alone spans from there to the end, --span alone from 0.
TEST(Compose, TimelapseSpansTheWholeClipByDefault) {
  Timelapse six;
  six.snapshots = 6;
  EXPECT_EQ(timelapse_times(six, 10.0), (std::vector<double>{0, 2, 4, 6, 8, 10}));
  six.start = 5.0;
  EXPECT_EQ(timelapse_times(six, 10.0), (std::vector<double>{5, 6, 7, 8, 9, 10}));
  six.start.reset();
  six.span = 1.0;
  EXPECT_EQ(timelapse_times(six, 10.0), (std::vector<double>{0, 0.2, 0.4, 0.6, 0.8, 1}));
  // A start beyond what the span leaves is moved back into the clip; one snapshot is the start.
  six.start = 9.5;
  EXPECT_EQ(timelapse_times(six, 10.0).front(), 9.0);
  Timelapse one;
  one.snapshots = 1;
  EXPECT_EQ(timelapse_times(one, 3.0), (std::vector<double>{0}));
}

TEST(Compose, SceneBoxReachesDownToTheFloor) {
  const MovingBar bar;
  const Eigen::AlignedBox3d box = scene_box(bar.body, {bar.poses[0], bar.poses[10]}, -0.2);
  EXPECT_DOUBLE_EQ(box.min().z(), -0.2);
  // The far face of the last voxel of the last pose (pose_bounds: the drawn surface).
  EXPECT_NEAR(box.max().x(), 0.02 + 0.1 + 0.5 * 0.01, 1e-12);
}

TEST(Compose, StillAndStripHaveTheRequestedSizes) {
  const MovingBar bar;
  const Image still = render_still(bar.clip(), View::side, 0.5, 0, 0, small_scene());
  EXPECT_EQ(still.width, 960);
  EXPECT_EQ(still.height, 540);
  Timelapse strip;
  strip.snapshots = 3;
  strip.start = 0.0;
  strip.span = 1.0;
  const Image panels = render_timelapse(bar.clip(), View::side, strip, 50, 40, small_scene());
  EXPECT_EQ(panels.width, 3 * 50 + 2 * 4);  // 4-pixel gaps
  EXPECT_EQ(panels.height, 40 + 11);        // the title band: 11 font rows of 1 pixel
}

// The name stands in a band of its own above the panels, so a long name cannot run into the
// second panel's time label.
TEST(Compose, StripTitleIsAboveThePanels) {
  const MovingBar bar;
  Timelapse strip;
  strip.snapshots = 2;
  strip.start = 0.0;
  strip.span = 1.0;
  Clip named = bar.clip();
  named.name = "A LONG NAME THAT IS WIDER THAN ONE PANEL";
  const Image titled = render_timelapse(named, View::side, strip, 60, 300, small_scene());
  Clip unnamed = bar.clip();
  unnamed.name.clear();
  const Image plain = render_timelapse(unnamed, View::side, strip, 60, 300, small_scene());
  // Font pixel 2 at 300 rows; a title wider than the strip is drawn smaller (down to font
  // pixel 1) instead of being cut off, and its band shrinks with it.
  const int band = titled.height - 300;
  ASSERT_GE(band, 11);
  ASSERT_LE(band, 11 * 2);
  const int plain_band = plain.height - 300;
  const std::array<std::uint8_t, 3> band_colour = plain.pixel(0, 0);
  long title_pixels = 0, panel_differences = 0;
  for (int y = 0; y < titled.height; ++y)
    for (int x = 0; x < titled.width; ++x) {
      if (y < band)
        title_pixels += titled.pixel(x, y) != band_colour;
      else
        panel_differences += titled.pixel(x, y) != plain.pixel(x, y - band + plain_band);
    }
  EXPECT_GT(title_pixels, 100);     // the name is drawn, across both panels' width
  EXPECT_EQ(panel_differences, 0);  // and nothing of it inside the panels
}

TEST(Compose, OverlayIsOneSceneOfEverySnapshot) {
  const MovingBar bar;
  Timelapse overlay;
  overlay.layout = Layout::overlay;
  overlay.start = 0.0;
  overlay.span = 1.0;
  overlay.snapshots = 4;
  const Image four = render_timelapse(bar.clip(), View::top, overlay, 120, 90, small_scene());
  // The title (pose times) is in a band above the picture: font pixel 1 at 90 rows, 11 rows.
  EXPECT_EQ(four.width, 120);
  EXPECT_EQ(four.height, 90 + 11);
  // Framed like the overlay, the last snapshot alone covers less than all four together.
  SceneOptions last_only = small_scene();
  last_only.label = "bar  t=1.0-1.0s";  // as long as the overlay's label
  const Image last = render_poses(
      bar.body, {bar.poses[10]},
      fit_camera(View::top, scene_box(bar.body, {bar.poses[0], bar.poses[10]}, -0.005), 120, 90),
      last_only);
  const std::array<std::uint8_t, 3> floor = four.pixel(2, four.height - 3);
  EXPECT_GT(count_pixels_unlike(four, floor, 24), count_pixels_unlike(last, floor, 24));
}

TEST(Compose, RefusesWhatItCannotDraw) {
  const MovingBar bar;
  Timelapse none;
  none.snapshots = 0;
  EXPECT_THROW(render_timelapse(bar.clip(), View::side, none, 10, 10, small_scene()),
               std::invalid_argument);
  none.snapshots = 65;
  EXPECT_THROW(render_timelapse(bar.clip(), View::side, none, 10, 10, small_scene()),
               std::invalid_argument);
  EXPECT_THROW(parse_layout("grid"), std::invalid_argument);
  EXPECT_EQ(parse_layout("overlay"), Layout::overlay);
  const std::vector<Pose> single = {bar.poses[0]};
  EXPECT_THROW(write_video(Clip{bar.body, single, "bar"}, View::side, {}, small_scene(),
                           "/bin/false", "/tmp/never.mp4"),
               std::runtime_error);
}

TEST(Compose, FindOnPathFindsExecutablesOnly) {
  EXPECT_TRUE(find_on_path("sh").has_value());
  EXPECT_FALSE(find_on_path("softevo-no-such-program").has_value());
}

}  // namespace
}  // namespace softevo::render
