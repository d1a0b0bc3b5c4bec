// [search], [map_elites] and [afpo] in the config (docs/model.md §8.12) and the MAP-Elites grid
// (common/map_grid.hpp): strict keys per strategy, clear errors naming the key, cell indices.
#include "common/map_grid.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "common/config_identity.hpp"

namespace softevo {
namespace {

void expect_error(const std::string& text, const std::string& needle) {
  try {
    parse_config(text, "m.toml");
    ADD_FAILURE() << "expected an error for " << text;
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find(needle), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("m.toml"), std::string::npos) << e.what();
  }
}

const std::string kMap = "[search]\nstrategy = \"map_elites\"\n[map_elites]\n";

TEST(SearchConfig, NeatIsTheDefaultAndLeavesTheCanonicalTextAsItWas) {
  const Config c = parse_config("", "d.toml");
  EXPECT_EQ(c.search.strategy, SearchKind::neat);
  EXPECT_EQ(canonical_text(c).find("search"), std::string::npos);
  EXPECT_EQ(canonical_text(c).find("map_elites"), std::string::npos);
  const Config m = parse_config(kMap, "m.toml");
  const std::string text = canonical_text(m);
  EXPECT_NE(text.find("[search]\nstrategy = \"map_elites\"\n[map_elites]\ndescriptors = "),
            std::string::npos)
      << text;
  EXPECT_EQ(text.find("[afpo]"), std::string::npos);
  EXPECT_EQ(config_hash(parse_config(text, "round trip")), config_hash(m));
}

TEST(SearchConfig, EachStrategysKeysApplyToItAlone) {
  expect_error("[map_elites]\nbins = [4, 4]\n",
               "map_elites.bins applies only when search.strategy = \"map_elites\"");
  expect_error("[afpo]\nage = \"body\"\n", "afpo.age applies only when search.strategy = \"afpo\"");
  expect_error("[search]\nstrategy = \"afpo\"\n[map_elites]\nbins = [4, 4]\n",
               "map_elites.bins applies only when search.strategy = \"map_elites\"");
  expect_error("[search]\nstrategy = \"mapelites\"\n", "search.strategy");
  EXPECT_EQ(
      parse_config("[search]\nstrategy = \"afpo\"\n[afpo]\nage = \"body\"\n", "a.toml").afpo.age,
      AfpoAge::body);
}

TEST(SearchConfig, BadDescriptorsNameTheKey) {
  expect_error(kMap + "descriptors = [\"legs\", \"voxels\"]\n", "map_elites.descriptors[0]");
  expect_error(kMap + "min = [5, 0]\nmax = [5, 1]\n",
               "map_elites.min[0] = 5.0 must be below map_elites.max[0] = 5.0");
  expect_error(kMap + "bins = [0, 4]\n", "map_elites.bins[0]");
  expect_error(kMap + "bins = [200, 100]\n",
               "map_elites.bins = [200, 100] gives more cells than map_elites.max_cells = 10000");
  expect_error(kMap + "bins = [4]\n", "map_elites.bins has 1 entry, map_elites.descriptors 2");
  expect_error(kMap + "descriptors = [\"voxels\", \"height\", \"void_fraction\", \"elongation\"]\n",
               "map_elites.descriptors has 4 entries; a map has 1-3");
  expect_error("[task]\nkind = \"rotate\"\n" + kMap +
                   "descriptors = [\"mean_speed\"]\nmin = [0]\nmax = [1]\nbins = [4]\n",
               "map_elites.descriptors[0] = \"mean_speed\" needs task.kind = \"gait\"");
}

TEST(MapGrid, CellsAreRowMajorAndEdgesClamp) {
  Config c = parse_config(kMap +
                              "descriptors = [\"chamber_count\", \"actuated_fraction\"]\n"
                              "min = [0.5, 0]\nmax = [10.5, 1]\nbins = [10, 4]\n",
                          "m.toml");
  const MapGrid g = map_grid(c);
  EXPECT_EQ(g.cells(), 40);
  EXPECT_EQ(g.cell({1, 0.0}), 0);  // 1 chamber: bin 0; fraction 0: bin 0
  EXPECT_EQ(g.cell({3, 0.3}), 2 * 4 + 1);
  EXPECT_EQ(g.cell({10, 1.0}), 39);      // max is exclusive: the last bin
  EXPECT_EQ(g.cell({25, -1.0}), 9 * 4);  // outside: the nearest edge bin
  EXPECT_EQ(g.cell({std::nan(""), 0.5}), -1);
  EXPECT_EQ(g.coordinates(9), (std::vector<std::int64_t>{2, 1}));
  EXPECT_EQ(g.cell_of_bins({2, 1}), 9);
}

}  // namespace
}  // namespace softevo
