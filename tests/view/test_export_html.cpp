// The exported page (view/export_html.hpp): strings embedded in it are escaped by one rule, so a
// hostile robot name never ends its <script> element; the page's JSON reads back the same name.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <random>
#include <string>

#include <nlohmann/json.hpp>

#include "physics/terrain.hpp"
#include "tests/io/tmp_dir.hpp"
#include "tests/view/fake_web.hpp"
#include "tests/view/view_test_robot.hpp"
#include "view/client_session.hpp"
#include "view/export_html.hpp"

using namespace softevo;
using nlohmann::json;

namespace {

std::string lower(std::string s) {
  std::transform(s.begin(), s.end(), s.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return s;
}

// The text of <script ... id="ID"> ... </script> in `page`.
std::string element_text(const std::string& page, const std::string& id) {
  const auto open = page.find("id=\"" + id + "\">");
  EXPECT_NE(open, std::string::npos) << id;
  const auto start = page.find('>', open) + 1;
  const auto end = lower(page).find("</script", start);
  return page.substr(start, end - start);
}

const char* const kHostile[] = {
    "x</SCRIPT><img src=x onerror=alert(1)>",
    "x</script><script>alert(1)</script>",
    "x</ScRiPt  ><svg onload=alert(1)>",
    "<!--<script>",
    "a&amp;b&lt;/script&gt;",
    "line\xE2\x80\xA8sep\xE2\x80\xA9para",
    "quote\"back\\slash'",
};

}  // namespace

TEST(ViewExportHtml, JsonForHtmlEscapesEveryMarkupCharacterAndReadsBackTheSame) {
  for (const char* name : kHostile) {
    const std::string text = json{{"name", name}}.dump();
    const std::string safe = view::json_for_html(text);
    for (char c : {'<', '>', '&'}) EXPECT_EQ(safe.find(c), std::string::npos) << name;
    EXPECT_EQ(safe.find("\xE2\x80\xA8"), std::string::npos);
    EXPECT_EQ(safe.find("\xE2\x80\xA9"), std::string::npos);
    EXPECT_EQ(json::parse(safe)["name"], name);
  }
}

TEST(ViewExportHtml, RandomNamesNeverLeaveTheirElement) {
  // Fuzz: names drawn from the characters that matter in HTML and JSON, and UTF-8 separators.
  const std::string alphabet[] = {
      "<",  ">",      "/",      "&",      "!", "-", "\"",           "'",
      "\\", "script", "SCRIPT", "ScRiPt", " ", "=", "\xE2\x80\xA8", "\xE2\x80\xA9",
      "a",  "\n"};
  std::mt19937 rng(29);
  for (int trial = 0; trial < 2000; ++trial) {
    std::string name;
    const int parts = static_cast<int>(rng() % 24);
    for (int k = 0; k < parts; ++k) name += alphabet[rng() % std::size(alphabet)];
    const std::string safe = view::json_for_html(json{{"name", name}}.dump());
    ASSERT_EQ(lower(safe).find("</script"), std::string::npos) << name;
    ASSERT_EQ(safe.find('<'), std::string::npos) << name;
    ASSERT_EQ(json::parse(safe)["name"], name);
  }
}

// A stand-in for view/web (the real one needs npm ci): the page's markers, and an app.js whose
// string holds a closing tag in capitals, which must not end its element either.
using test::FakeWeb;

TEST(ViewExportHtml, HostileRobotNamesStayInsideTheExportedPage) {
  const FakeWeb fake;
  const std::string web = fake.dir.path;
  for (const char* name : kHostile) {
    view::ViewInput in = test::block_input(TaskKind::gait, 0.1);
    in.name = name;
    in.robot.name = name;
    view::ClientSession client(in, {});
    const std::string page = view::export_html(client, web, 30.0);
    const std::string hello = element_text(page, "softevo-hello");
    EXPECT_EQ(hello.find('<'), std::string::npos) << name;
    EXPECT_EQ(json::parse(hello)["name"], name);
    // Every "</script" of the page closes one of the page's own elements: as many as it opens.
    const std::string l = lower(page);
    std::size_t opens = 0, closes = 0;
    for (auto at = l.find("<script"); at != std::string::npos; at = l.find("<script", at + 1))
      ++opens;
    for (auto at = l.find("</script"); at != std::string::npos; at = l.find("</script", at + 1))
      ++closes;
    EXPECT_EQ(opens, closes) << name;
  }
}

namespace {

// Standard base64 back to bytes (the page's atob).
std::string unbase64(const std::string& text) {
  static const std::string kAlphabet =
      "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  std::uint32_t acc = 0;
  int bits = 0;
  for (char c : text) {
    if (c == '=') break;
    acc = (acc << 6) | static_cast<std::uint32_t>(kAlphabet.find(c));
    bits += 6;
    if (bits >= 8) {
      bits -= 8;
      out += static_cast<char>((acc >> bits) & 0xFF);
    }
  }
  return out;
}

}  // namespace

// Issue 30: the page draws the ground it is sent. A bumpy config's hello (live and in the
// exported page) carries the surface heights of physics/terrain on a grid under the robot's path; a
// flat config's carries none (the page draws its flat floor as before).
TEST(ViewExportHtml, TheHelloAndTheExportedPageCarryTheTerrain) {
  const FakeWeb fake;
  view::ViewInput in = test::block_input(TaskKind::gait, 0.1);
  in.config.terrain.kind = GroundKind::heightfield;
  in.config.terrain.heightfield = HeightfieldKind::bumps;
  in.config.terrain.shape.amplitude = 0.01;
  in.config.terrain.shape.correlation_length = 0.05;
  view::ClientSession client(in, {});
  // The exported page's hello: the session run to its end, the ground under its whole path.
  const std::string page = view::export_html(client, fake.dir.path, 30.0);
  const json hello = json::parse(element_text(page, "softevo-hello"));
  EXPECT_EQ(hello, json::parse(client.hello()));
  ASSERT_TRUE(hello.contains("terrain"));
  const json& t = hello["terrain"];
  EXPECT_EQ(t["kind"], "bumps");
  const int nx = t["nx"], ny = t["ny"];
  const double x0 = t["x0"], y0 = t["y0"], step = t["step"];
  EXPECT_EQ(step, in.body.voxel_size);
  // 1 m around the (few millimetres of) path, on the lattice of the step.
  EXPECT_GE(nx, 201);
  EXPECT_LE(nx, 203);
  EXPECT_GE(ny, 201);
  EXPECT_LE(ny, 203);
  const std::string bytes = unbase64(t["z"]);
  ASSERT_EQ(bytes.size(), 4u * static_cast<std::size_t>(nx * ny));
  std::vector<float> z(static_cast<std::size_t>(nx * ny));
  std::memcpy(z.data(), bytes.data(), bytes.size());
  // Every sample is the simulation's own ground, half a voxel below a resting centre.
  const physics::Terrain& ground = client.session().terrain();
  EXPECT_EQ(ground.kind, physics::TerrainKind::bumps);
  const double half = 0.5 * in.body.voxel_size;
  float lo = z[0], hi = z[0];
  for (int j = 0; j < ny; j += 7)
    for (int i = 0; i < nx; i += 5) {
      const float want =
          static_cast<float>(physics::terrain_height(ground, x0 + i * step, y0 + j * step) - half);
      ASSERT_EQ(z[static_cast<std::size_t>(j * nx + i)], want) << i << "," << j;
    }
  for (float h : z) lo = std::min(lo, h), hi = std::max(hi, h);
  EXPECT_LT(lo, -half - 0.005);  // valleys and bumps of about the amplitude
  EXPECT_GT(hi, -half + 0.005);
  // The grid is centred on the path: the start itself is behind the bumps' fade-in (flat).
  EXPECT_NEAR(x0 + (nx - 1) / 2 * step, ground.start_x, 0.2);

  // Flat: no terrain at all.
  const view::ViewInput flat_input = test::block_input(TaskKind::gait, 0.1);
  view::ClientSession flat(flat_input, {});
  EXPECT_FALSE(json::parse(flat.hello()).contains("terrain"));
  EXPECT_EQ(view::terrain_grid(flat.session()).nx, 0);
}
