// The heightfield's numbers written once (common/terrain_shape.hpp): every TerrainShape member
// has one row, and the config keys derived from the table are printed, parsed and refused on
// exactly the heightfield the row names.
#include "common/terrain_shape.hpp"

#include <gtest/gtest.h>

#include <set>
#include <string>

#include "common/config.hpp"

namespace softevo {
namespace {

const char* heightfield_name(HeightfieldKind kind) {
  return kind == HeightfieldKind::bumps   ? "bumps"
         : kind == HeightfieldKind::steps ? "steps"
                                          : "slope";
}

TEST(TerrainShape, EveryMemberHasOneRowWithItsOwnKeyAndAttribute) {
  std::set<std::string> keys, attributes;
  TerrainShape marked;
  for (const TerrainShapeField& f : kTerrainShapeFields) {
    keys.insert(f.key);
    attributes.insert(f.trace_attribute);
    EXPECT_EQ(std::string(f.trace_attribute).rfind("terrain_" + std::string(f.key), 0), 0u)
        << f.key;
    EXPECT_LT(f.min, f.max) << f.key;
    marked.*f.member = 1.0;
  }
  EXPECT_EQ(keys.size(), kTerrainShapeFields.size());
  EXPECT_EQ(attributes.size(), kTerrainShapeFields.size());
  // Every member is reached by some row (a member added without a row stays 0).
  EXPECT_TRUE(marked == (TerrainShape{1.0, 1.0, 1.0, 1.0, 1.0, 1.0}));
}

TEST(TerrainShape, EachKeyIsReadPrintedAndSettableOnItsHeightfieldOnly) {
  for (const TerrainShapeField& f : kTerrainShapeFields) {
    const std::string value = toml_number(0.5 * (f.min + f.max) + (f.min_exclusive ? 0.25 : 0.0));
    const std::string ground = std::string("[terrain]\nkind = \"heightfield\"\nheightfield = \"") +
                               heightfield_name(f.heightfield) + "\"\n";
    const Config c = parse_config(ground + f.key + " = " + value + "\n", "test");
    EXPECT_EQ(toml_number(c.terrain.shape.*f.member), value) << f.key;
    EXPECT_NE(canonical_text(c).find(std::string(f.key) + " = " + value), std::string::npos)
        << f.key;
    for (HeightfieldKind other :
         {HeightfieldKind::bumps, HeightfieldKind::steps, HeightfieldKind::slope}) {
      if (other == f.heightfield) continue;
      const std::string elsewhere = std::string("[terrain]\nkind = \"heightfield\"\n") +
                                    "heightfield = \"" + heightfield_name(other) + "\"\n" + f.key +
                                    " = " + value + "\n";
      EXPECT_THROW(parse_config(elsewhere, "test"), ConfigError) << f.key;
      EXPECT_EQ(
          canonical_text(parse_config(std::string("[terrain]\nkind = \"heightfield\"\n") +
                                          "heightfield = \"" + heightfield_name(other) + "\"\n",
                                      "test"))
              .find(std::string(f.key) + " = "),
          std::string::npos)
          << f.key;
    }
  }
}

TEST(TerrainShape, TheConfigRangeIsTheTables) {
  for (const TerrainShapeField& f : kTerrainShapeFields) {
    const std::string ground = std::string("[terrain]\nkind = \"heightfield\"\nheightfield = \"") +
                               heightfield_name(f.heightfield) + "\"\n" + f.key + " = ";
    EXPECT_THROW(parse_config(ground + toml_number(f.max + 1.0) + "\n", "test"), ConfigError)
        << f.key;
    EXPECT_THROW(parse_config(ground + toml_number(f.min - 1.0) + "\n", "test"), ConfigError)
        << f.key;
  }
}

}  // namespace
}  // namespace softevo
