// PNG files (render/png.hpp): a round trip keeps every pixel, a symlink target is refused and
// leaves no temporary file, an unwritable path is an error naming it.
#include "render/png.hpp"

#include <gtest/gtest.h>

#include <array>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <stdexcept>
#include <string>

namespace softevo::render {
namespace {

TEST(RenderPng, RoundTripKeepsSizeAndPixels) {
  Image img(7, 5, {10, 20, 30});
  img.set(3, 2, {200, 100, 50});
  const std::string path =
      (std::filesystem::temp_directory_path() / "softevo_test_render_roundtrip.png").string();
  write_png(img, path, softevo::Overwrite::replace);  // a file left by an aborted run
  const Image back = read_png(path);
  std::filesystem::remove(path);
  EXPECT_EQ(back.width, 7);
  EXPECT_EQ(back.height, 5);
  EXPECT_EQ(back.pixel(3, 2), (std::array<std::uint8_t, 3>{200, 100, 50}));
  EXPECT_EQ(back.pixel(0, 0), (std::array<std::uint8_t, 3>{10, 20, 30}));
}

TEST(RenderPng, SymlinkTargetIsRefusedAndNoTemporaryRemains) {
  namespace fs = std::filesystem;
  const fs::path dir = fs::temp_directory_path() / "softevo_test_render_symlink";
  fs::remove_all(dir);
  fs::create_directories(dir);
  std::FILE* victim = std::fopen((dir / "victim").c_str(), "w");
  ASSERT_NE(victim, nullptr);
  std::fputs("precious", victim);
  std::fclose(victim);
  fs::create_symlink(dir / "victim", dir / "out.png");
  Image img(2, 2, {0, 0, 0});
  EXPECT_THROW(write_png(img, (dir / "out.png").string()), std::runtime_error);
  EXPECT_EQ(fs::file_size(dir / "victim"), 8u);
  EXPECT_TRUE(fs::is_symlink(dir / "out.png"));
  write_png(img, (dir / "new.png").string());
  std::size_t files = 0;
  for (const auto& e : fs::directory_iterator(dir)) {
    EXPECT_EQ(e.path().filename().string().find(".tmp."), std::string::npos) << e.path();
    ++files;
  }
  EXPECT_EQ(files, 3u);  // victim, out.png (the link), new.png
  fs::remove_all(dir);
}

TEST(RenderPng, UnwritablePathIsAnErrorNamingIt) {
  Image img(2, 2, {0, 0, 0});
  try {
    write_png(img, "/nonexistent-dir/x.png");
    FAIL() << "expected an error";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("/nonexistent-dir/x.png"), std::string::npos);
  }
}

}  // namespace
}  // namespace softevo::render
