// `softevo render` end to end: runs the built CLI on a robot file, a synthetic trace and (by
// re-simulation) a moving robot, and checks the PNG it writes: expected size and pixels that
// show the robot (stiffness colours), not a blank floor.
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <nlohmann/json.hpp>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <limits>
#include <string>
#include <utility>
#include <vector>

#include "common/robot.hpp"
#include "io/h5.hpp"
#include "render/png.hpp"

#include "tests/build_tree.hpp"
#include "tests/sanitizers.hpp"

namespace softevo {
namespace {

namespace fs = std::filesystem;

using test::build_dir;

std::string softevo_binary() {
  return build_dir() + "/bin/softevo";
}

// Runs a shell command, returns its exit status.
int run(const std::string& command) {
  const int status = std::system((command + " > /dev/null 2>&1").c_str());
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

class CmdRender : public ::testing::Test {
 protected:
  void SetUp() override {
    if (!fs::exists(softevo_binary())) GTEST_SKIP() << "softevo binary not built";
    dir_ = test::fresh_test_dir("cmd_render");
  }
  void TearDown() override {
    std::error_code ec;
    if (!dir_.empty()) fs::remove_all(dir_, ec);
  }
  // A 4x3x3 robot: soft red front half (material 1), stiff blue back half (material 10), one
  // chamber cell inside; open-loop controller with a strong inlet drive.
  std::string write_robot() {
    RobotFile robot;
    robot.name = "test-bot";
    robot.body.lattice = {4, 3, 3};
    robot.body.cells.assign(36, 0);
    for (int x = 0; x < 4; ++x)
      for (int y = 0; y < 3; ++y)
        for (int z = 0; z < 3; ++z)
          robot.body.cells[robot.body.cell_index(x, y, z)] = x < 2 ? 10 : 1;
    robot.body.cells[robot.body.cell_index(1, 1, 1)] = kFirstChamberCell;
    for (int k = 1; k <= 10; ++k) robot.body.materials.push_back({1.0e4 * k, 1000.0});
    ControllerSpec& c = robot.controller;
    const int h = c.hidden, n_out = c.outputs, n_in = c.input_count();
    c.vectors.weights_hidden.assign(static_cast<std::size_t>(n_in * h), 0.0);
    c.vectors.weights_hidden[0] = 3.0;  // sin -> hidden 0
    c.vectors.bias_hidden.assign(h, 0.0);
    c.vectors.weights_out.assign(static_cast<std::size_t>(h * n_out), 0.0);
    c.vectors.weights_out[0] = 3.0;   // hidden 0 -> inlet valve of chamber 0
    c.vectors.weights_out[1] = -3.0;  // hidden 0 -> outlet valve of chamber 0
    c.vectors.bias_out.assign(n_out, 0.0);
    c.vectors.weights_recurrent.assign(static_cast<std::size_t>(h * h), 0.0);
    c.vectors.weights_recurrent_self.assign(h, 0.0);
    c.vectors.weights_context.assign(h, 0.0);
    c.vectors.bias_context.assign(h, 0.0);
    c.vectors.freq = {2.0};
    const std::string path = (dir_ / "robot.json").string();
    write_robot_file(robot, path);
    return path;
  }
  // A directory holding a stand-in ffmpeg that stores its raw input as its output file (its
  // last argument): frames x W x H x 3 bytes.
  fs::path fake_ffmpeg_dir() {
    const fs::path bin = dir_ / "bin";
    fs::create_directories(bin);
    {
      std::ofstream script(bin / "ffmpeg");
      script << "#!/bin/sh\nfor last; do :; done\ncat > \"$last\"\n";
    }
    fs::permissions(bin / "ffmpeg", fs::perms::owner_all);
    return bin;
  }
  // Trace of the same body shape without chamber: 3 frames moving 1 cm per frame along x (the
  // first voxel's first x moved by `first_x` [m], the lattice pitch `voxel_size` [m]).
  std::string write_trace(const std::string& name = "trace.h5", double first_x = 0.0,
                          double voxel_size = 0.01) {
    const std::string path = (dir_ / name).string();
    std::vector<std::int32_t> cells;
    std::vector<std::int32_t> material;
    for (int x = 0; x < 4; ++x)
      for (int y = 0; y < 3; ++y)
        for (int z = 0; z < 3; ++z) {
          cells.insert(cells.end(), {x, y, z});
          material.push_back(x < 2 ? 10 : 1);
        }
    const hsize_t v = material.size(), frames = 3;
    std::vector<double> pos, ori;
    for (hsize_t f = 0; f < frames; ++f)
      for (hsize_t i = 0; i < v; ++i) {
        pos.insert(pos.end(), {cells[3 * i] * 0.01 + 0.01 * f, cells[3 * i + 1] * 0.01,
                               cells[3 * i + 2] * 0.01});
        ori.insert(ori.end(), {1.0, 0.0, 0.0, 0.0});
      }
    pos[0] += first_x;
    // Only what another tool would write: no time, pressures, robot or frame rate.
    const io::h5::File file = io::h5::File::create(path);
    file.write_dataset<double>("positions", {frames, v, 3}, pos);
    file.write_dataset<double>("orientations", {frames, v, 4}, ori);
    file.write_dataset<std::int32_t>("voxel_cells", {v, 3}, cells);
    file.write_dataset<std::int32_t>("voxel_material", {v}, material);
    file.write_attribute<double>("voxel_size", voxel_size);
    return path;
  }
  fs::path dir_;
};

// Pixels clearly red (soft material) and clearly blue (stiff material).
void count_material_pixels(const render::Image& img, long& red, long& blue) {
  red = blue = 0;
  for (int y = 0; y < img.height; ++y)
    for (int x = 0; x < img.width; ++x) {
      const auto p = img.pixel(x, y);
      if (p[0] > p[2] + 40 && p[0] > p[1] + 40) ++red;
      if (p[2] > p[0] + 40 && p[2] > p[1] + 40) ++blue;
    }
}

TEST_F(CmdRender, RobotFileGivesAPngOfTheRequestedSizeShowingTheRobot) {
  const std::string robot = write_robot();
  for (const char* view : {"side", "top", "iso"}) {
    const std::string out = (dir_ / (std::string(view) + ".png")).string();
    ASSERT_EQ(run(softevo_binary() + " render " + robot + " -o " + out +
                  " --width 320 --height 240 --view " + view),
              0)
        << view;
    const render::Image img = render::read_png(out);
    EXPECT_EQ(img.width, 320);
    EXPECT_EQ(img.height, 240);
    long red = 0, blue = 0;
    count_material_pixels(img, red, blue);
    // Both halves are visible and the robot fills a fair part of the frame.
    EXPECT_GT(red, 320 * 240 / 50) << view;
    EXPECT_GT(blue, 320 * 240 / 50) << view;
    EXPECT_GT(render::count_pixels_unlike(img, img.pixel(0, 0)), 320 * 240 / 10) << view;
  }
}

TEST_F(CmdRender, TraceTimelapseStripHasOnePanelPerSnapshot) {
  const std::string trace = write_trace();
  const std::string out = (dir_ / "strip.png").string();
  ASSERT_EQ(run(softevo_binary() + " render " + trace + " -o " + out +
                " --timelapse 3 --start 0 --span 0.0333334 --width 200 --height 150"),
            0);
  const render::Image img = render::read_png(out);
  EXPECT_EQ(img.width, 3 * 200 + 2 * 4);  // panels + 4-pixel gaps
  EXPECT_EQ(img.height, 11 + 150);  // the title band (11 font rows of 1 pixel) above the panels
  // The robot moves right from panel to panel: the first blue column advances.
  int first_blue[3];
  for (int panel = 0; panel < 3; ++panel) {
    first_blue[panel] = -1;
    for (int x = 0; x < 200 && first_blue[panel] < 0; ++x)
      for (int y = 11; y < 11 + 150; ++y) {
        const auto p = img.pixel(panel * 204 + x, y);
        if (p[2] > p[0] + 40 && p[2] > p[1] + 40) {
          first_blue[panel] = x;
          break;
        }
      }
    ASSERT_GE(first_blue[panel], 0) << "panel " << panel << " shows no robot";
  }
  EXPECT_GT(first_blue[1], first_blue[0]);
  EXPECT_GT(first_blue[2], first_blue[1]);
}

TEST_F(CmdRender, BadInputsFailWithUsageExitCode) {
  const std::string robot = write_robot();
  EXPECT_EQ(run(softevo_binary() + " render " + robot + " -o " + (dir_ / "x.bmp").string()), 2);
  EXPECT_EQ(run(softevo_binary() + " render " + (dir_ / "missing.json").string() + " -o " +
                (dir_ / "x.png").string()),
            2);
  EXPECT_EQ(run(softevo_binary() + " render " + robot + " -o " + (dir_ / "x.png").string() +
                " --view front"),
            2);
}

// --cutaway: the rows in front of the section go and the chambers' inlet channels (the viewer's
// yellow, 0xffc21a) are drawn; the same picture without it shows no channel. A row outside the
// lattice or a malformed value is a usage error.
TEST_F(CmdRender, CutawayShowsTheInletChannels) {
  const char* src = std::getenv("SOFTEVO_SOURCE_DIR");
  const std::string robot =
      (fs::path(src ? src : ".") / "robots" / "gait-closed-walker.robot.json").string();
  auto channel_pixels = [](const render::Image& img) {
    long n = 0;
    for (int y = 0; y < img.height; ++y)
      for (int x = 0; x < img.width; ++x) {
        const auto p = img.pixel(x, y);
        n += p[0] > 170 && p[1] > 120 && p[2] < 110 && p[0] - p[2] > 100;
      }
    return n;
  };
  const std::string cut = (dir_ / "cut.png").string(), whole = (dir_ / "whole.png").string();
  const std::string render =
      softevo_binary() + " render " + robot + " --view iso --width 1600 --height 1200 ";
  ASSERT_EQ(run(render + "--cutaway -o " + cut), 0);
  ASSERT_EQ(run(render + "--static -o " + whole), 0);
  const long with = channel_pixels(render::read_png(cut));
  EXPECT_GT(with, 50);
  EXPECT_EQ(channel_pixels(render::read_png(whole)), 0);
  ASSERT_EQ(run(render + "--cutaway y=0 -o " + (dir_ / "cut0.png").string()), 0);
  EXPECT_EQ(run(render + "--cutaway y=99 -o " + (dir_ / "x.png").string()), 2);
  EXPECT_EQ(run(render + "--cutaway 3 -o " + (dir_ / "x.png").string()), 2);
}

// Issue 39: a trace with inf positions made `view --export-html` say only "vector::reserve" (and
// the live server exit when a page connected). A trace is checked on reading: `render` and
// `view` name the file, the value and the rule, and exit 2.
TEST_F(CmdRender, ATraceWithValuesNoSimulationRecordsIsAClearError) {
  const std::string inf = write_trace("inf.h5", std::numeric_limits<double>::infinity());
  const std::string negative = write_trace("negative.h5", 0.0, -0.01);
  const std::string out = (dir_ / "x.png").string();
  const std::string html = (dir_ / "x.html").string();
  const bool has_view = run(softevo_binary() + " view --help") == 0;
  for (const auto& [trace, what] :
       {std::pair{inf, std::string("positions [m] value 0 = inf: must be finite")},
        std::pair{negative, std::string("attribute voxel_size [m] = -0.01: must be finite, in "
                                        "(0, 10]")}}) {
    std::vector<std::string> commands = {softevo_binary() + " render " + trace + " -o " + out};
    if (has_view)
      commands.push_back(softevo_binary() + " view " + trace + " --export-html " + html);
    for (const std::string& command : commands) {
      const auto r = test::run_command(command);
      EXPECT_EQ(r.code, 2) << command << "\n" << r.output;
      EXPECT_NE(r.output.find(trace + ": " + what), std::string::npos) << command << "\n"
                                                                       << r.output;
    }
  }
  EXPECT_FALSE(fs::exists(out));
  EXPECT_FALSE(fs::exists(html));
}

// Issue 39: without ffmpeg, `render -o x.mp4` wrote PNG frames and exited 0 without the video.
// It is an error that says what to install (and that a GIF needs no ffmpeg), given before
// anything is simulated or written.
TEST_F(CmdRender, VideoWithoutFfmpegIsAnErrorSayingWhatToInstall) {
  const std::string robot = write_robot();
  // PATH without ffmpeg.
  const fs::path empty_bin = dir_ / "empty-bin";
  fs::create_directories(empty_bin);
  const auto r = test::run_command("PATH=" + empty_bin.string() + " " + softevo_binary() +
                                   " render " + robot + " -o " + (dir_ / "x.mp4").string() +
                                   " --seconds 0.2 --fps 10 --width 64 --height 48");
  EXPECT_EQ(r.code, 2) << r.output;
  EXPECT_NE(r.output.find("ffmpeg, which is not on PATH: install it (Debian: apt-get install "
                          "ffmpeg)"),
            std::string::npos)
      << r.output;
  EXPECT_NE(r.output.find("x.gif"), std::string::npos) << r.output;
  EXPECT_FALSE(fs::exists(dir_ / "x.mp4"));
  EXPECT_FALSE(fs::exists(dir_ / "x-frames"));
}

// Issue 30: `render -o OUT.gif` writes an animated GIF (giflib), no ffmpeg needed.
TEST_F(CmdRender, GifIsWrittenWithoutFfmpeg) {
#ifndef SOFTEVO_HAVE_GIF
  GTEST_SKIP() << "softevo was built without giflib (libgif-dev)";
#endif
  const std::string robot = write_robot();
  const fs::path empty_bin = dir_ / "empty-bin";
  fs::create_directories(empty_bin);
  const std::string out = (dir_ / "walk.gif").string();
  const auto r =
      test::run_command("PATH=" + empty_bin.string() + " " + softevo_binary() + " render " + robot +
                        " -o " + out + " --seconds 0.2 --fps 10 --width 64 --height 48 --json");
  ASSERT_EQ(r.code, 0) << r.output;
  const auto j = nlohmann::json::parse(r.output);
  EXPECT_EQ(j["kind"], "gif");
  EXPECT_EQ(j["width"], 64);
  EXPECT_GE(j["frames"].get<int>(), 2);
  std::ifstream in(out, std::ios::binary);
  std::string magic(6, '\0');
  in.read(magic.data(), 6);
  EXPECT_EQ(magic, "GIF89a");
  // Like every output: an existing file only with --force.
  EXPECT_EQ(run(softevo_binary() + " render " + robot + " -o " + out + " --seconds 0.2"), 2);
}

TEST_F(CmdRender, VideoFramesArePipedToFfmpeg) {
  const std::string robot = write_robot();
  const fs::path bin = fake_ffmpeg_dir();
  const std::string out = (dir_ / "movie.mp4").string();
  ASSERT_EQ(run("PATH=" + bin.string() + ":/usr/bin:/bin " + softevo_binary() + " render " + robot +
                " -o " + out + " --seconds 0.2 --fps 10 --width 64 --height 48"),
            0);
  // About 0.2 s at 10 fps: 2 or 3 whole frames (the simulated frame time is a whole number of
  // physics steps, a little under 1/60 s).
  const auto size = fs::file_size(out);
  const std::uintmax_t frame = 64u * 48 * 3;
  EXPECT_EQ(size % frame, 0u);
  EXPECT_GE(size / frame, 2u);
  EXPECT_LE(size / frame, 3u);
}

// Issue 21 item 6: --fps nan passed CLI11's checks and wrote "-2147483647 frames" (exit 0).
TEST_F(CmdRender, NumberOptionsOutOfRangeAreRefusedBeforeAnything) {
  const std::string robot = write_robot();
  const std::string render = softevo_binary() + " render " + robot + " -o " +
                             (dir_ / "out.mp4").string() + " --seconds 0.2";
  for (const char* bad : {"--fps nan", "--fps 0", "--fps inf", "--at nan", "--span -1",
                          "--direction 1e9", "--width 100000", "--seconds nan", "--seconds 1e10"}) {
    const auto r = test::run_command(render + " " + bad);
    EXPECT_EQ(r.code, 2) << bad << ": " << r.output;
    const std::string option = std::string(bad).substr(0, std::string(bad).find(' '));
    const bool named = r.output.find(option) != std::string::npos ||
                       r.output.find("task.eval_seconds") != std::string::npos;
    EXPECT_TRUE(named) << bad << ": " << r.output;
    EXPECT_FALSE(fs::exists(dir_ / "out.mp4")) << bad;
  }
}

// Issue 29: a picture whose buffers exceed the memory left ended in a bare std::bad_alloc. It is
// refused before anything is simulated or allocated, naming the options to lower: under an
// address-space limit of 2 GB, 8192 x 8192 at supersample 4 (about 60 GB), 4096 x 4096 at 2
// (3.8 GB), and a strip of 64 panels of 2048 x 2048 at 2 (2.5 GB); 1024 x 1024 fits.
TEST_F(CmdRender, PictureBeyondTheAvailableMemoryIsRefusedBeforeAnything) {
  if (SOFTEVO_TEST_ASAN)
    GTEST_SKIP() << "an AddressSanitizer binary cannot start under ulimit -v (its shadow memory "
                    "needs an unlimited address space)";
  const std::string robot = write_robot();
  const std::string out = (dir_ / "big.png").string();
  const std::string render =
      "ulimit -v 2000000 && " + softevo_binary() + " render " + robot + " -o " + out + " --static ";
  for (const char* big :
       {"--width 8192 --height 8192 --supersample 4", "--width 4096 --height 4096 --supersample 2",
        "--width 2048 --height 2048 --supersample 2 --timelapse 64"}) {
    const auto r = test::run_command("sh -c '" + render + big + "'");
    EXPECT_EQ(r.code, 2) << big << ": " << r.output;
    for (const char* named : {"needs about", "ulimit -v", "--width", "--supersample"})
      EXPECT_NE(r.output.find(named), std::string::npos) << big << ": " << named << r.output;
    EXPECT_EQ(r.output.find("bad_alloc"), std::string::npos) << big << ": " << r.output;
    EXPECT_FALSE(fs::exists(out)) << big;
  }
  const auto fits =
      test::run_command("sh -c '" + render + "--width 1024 --height 1024 --supersample 2'");
  EXPECT_EQ(fits.code, 0) << fits.output;
  EXPECT_TRUE(fs::exists(out));
}

// Issue 22: choices and ranges are CLI11 validators (or, for what needs the motion, checks
// right after it is known); each names the option, nothing is written.
TEST_F(CmdRender, OutOfRangeChoicesAndMotionTimesAreRefused) {
  const std::string robot = write_robot();
  const std::string out = (dir_ / "out.png").string();
  const std::string render = softevo_binary() + " render " + robot + " -o " + out;
  for (const char* bad : {"--supersample 9", "--timelapse 0", "--timelapse 65", "--width 5",
                          "--height 5", "--layout diagonal", "--view front"}) {
    const auto r = test::run_command(render + " " + bad);
    EXPECT_EQ(r.code, 2) << bad << ": " << r.output;
    const std::string option = std::string(bad).substr(0, std::string(bad).find(' '));
    EXPECT_NE(r.output.find(option), std::string::npos) << bad << ": " << r.output;
    EXPECT_NE(r.output.find("softevo: error: "), std::string::npos) << bad << ": " << r.output;
    EXPECT_FALSE(fs::exists(out)) << bad;
  }
  // --at beyond the simulated motion (0.2 s here).
  const auto late = test::run_command(render + " --seconds 0.2 --at 50");
  EXPECT_EQ(late.code, 2) << late.output;
  EXPECT_NE(late.output.find("--at 50 is beyond the end of the motion"), std::string::npos)
      << late.output;
  // A gait robot has no target direction to draw.
  const auto direction = test::run_command(render + " --view top --seconds 0.2 --direction 30");
  EXPECT_EQ(direction.code, 2) << direction.output;
  EXPECT_NE(direction.output.find("not a directed robot"), std::string::npos) << direction.output;
  EXPECT_FALSE(fs::exists(out));
  // The checks leave good values alone.
  EXPECT_EQ(run(render + " --seconds 0.2 --at 0.1 --width 64 --height 48 --supersample 4"), 0);
}

// docs/output-files.md rule 3: an existing picture or video is replaced only with --force; a
// video is encoded into a temporary that replaces the target at the end.
TEST_F(CmdRender, ExistingOutputIsReplacedOnlyWithForce) {
  const std::string robot = write_robot();
  const fs::path bin = fake_ffmpeg_dir();
  for (const char* name : {"old.png", "old.mp4"}) {
    const fs::path out = dir_ / name;
    std::ofstream(out) << "precious";
    const std::string render = "PATH=" + bin.string() + ":/usr/bin:/bin " + softevo_binary() +
                               " render " + robot + " -o " + out.string() +
                               " --seconds 0.1 --width 64 --height 48";
    const auto refused = test::run_command(render);
    EXPECT_EQ(refused.code, 2) << refused.output;
    EXPECT_NE(refused.output.find("refusing to overwrite an existing file (pass --force"),
              std::string::npos)
        << refused.output;
    EXPECT_EQ(fs::file_size(out), 8u) << name;
    const auto forced = test::run_command(render + " --force");
    EXPECT_EQ(forced.code, 0) << forced.output;
    EXPECT_GT(fs::file_size(out), 8u) << name;
  }
  for (const auto& e : fs::directory_iterator(dir_))
    EXPECT_EQ(e.path().filename().string().find(".tmp."), std::string::npos) << e.path();
}

TEST_F(CmdRender, ResimulatedTimelapseShowsTheRobotInEveryPanel) {
  const std::string robot = write_robot();
  const std::string out = (dir_ / "sim.png").string();
  ASSERT_EQ(run(softevo_binary() + " render " + robot + " -o " + out +
                " --seconds 0.5 --timelapse 2 --start 0 --span 0.5 --width 160 --height 120"),
            0);
  const render::Image img = render::read_png(out);
  EXPECT_EQ(img.width, 2 * 160 + 4);
  for (int panel = 0; panel < 2; ++panel) {
    long blue = 0;
    for (int y = 0; y < 120; ++y)
      for (int x = 0; x < 160; ++x) {
        const auto p = img.pixel(panel * 164 + x, y);
        if (p[2] > p[0] + 40 && p[2] > p[1] + 40) ++blue;
      }
    EXPECT_GT(blue, 160 * 120 / 50) << "panel " << panel;
  }
}

// The archive path: a tiny real run, then its best individual re-developed and re-simulated.
// (Run archives store strings as UTF-8; reading them as ASCII once failed here.)
TEST_F(CmdRender, BestOfARunArchiveIsDrawn) {
  const std::string mpi = build_dir() + "/bin/softevo-mpi";
  if (!fs::exists(mpi) || !fs::exists("configs/quickstart.toml"))
    GTEST_SKIP() << "softevo-mpi or configs/quickstart.toml missing";
  const std::string archive = (dir_ / "run.h5").string();
  ASSERT_EQ(run(mpi +
                " --config configs/quickstart.toml --seed 5 --generations 1 --population 4 "
                "--set body.lattice=[4,4,4] --set task.eval_seconds=0.5 --out " +
                archive),
            0);
  const std::string out = (dir_ / "best.png").string();
  ASSERT_EQ(run(softevo_binary() + " render " + archive +
                " --best --at 0.25 --width 200 --height 150 -o " + out),
            0);
  const render::Image img = render::read_png(out);
  EXPECT_EQ(img.width, 200);
  EXPECT_EQ(img.height, 150);
  // Something besides floor and sky: the robot covers a fair part of the frame.
  EXPECT_GT(render::count_pixels_unlike(img, img.pixel(0, 0)), 200 * 150 / 20);
}

}  // namespace
}  // namespace softevo
