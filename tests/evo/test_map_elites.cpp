// MAP-Elites (docs/model.md §8.12.2): replacement and ties on hand-made maps, descriptor
// formulas on a hand-made body, and the strategy's contract (tell, state round trip, an empty
// map is an error).
#include "evo/map_elites.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "common/wire.hpp"

namespace softevo::evo {
namespace {

Elite elite(std::int64_t cell, std::int64_t id, double fitness) {
  Elite e;
  e.cell = cell;
  e.individual.id = id;
  e.fitness = fitness;
  return e;
}

std::vector<std::int64_t> ids_of(const std::vector<Elite>& map) {
  std::vector<std::int64_t> ids;
  for (const Elite& e : map) ids.push_back(e.individual.id);
  return ids;
}

TEST(MapElitesReplacement, EmptyCellTakesAnyFitnessAndCellsStayAscending) {
  std::vector<Elite> map;
  EXPECT_TRUE(insert_elite(map, elite(7, 1, -3.0)));  // a negative fitness still fills a cell
  EXPECT_TRUE(insert_elite(map, elite(2, 2, 1.0)));
  EXPECT_TRUE(insert_elite(map, elite(5, 3, 0.0)));
  ASSERT_EQ(map.size(), 3u);
  EXPECT_EQ(map[0].cell, 2);
  EXPECT_EQ(map[1].cell, 5);
  EXPECT_EQ(map[2].cell, 7);
  EXPECT_EQ(ids_of(map), (std::vector<std::int64_t>{2, 3, 1}));
}

TEST(MapElitesReplacement, OnlyAStrictImprovementReplacesTiesKeepTheIncumbent) {
  std::vector<Elite> map;
  insert_elite(map, elite(4, 10, 2.5));
  EXPECT_FALSE(insert_elite(map, elite(4, 11, 2.5)));  // tie: incumbent 10 stays
  EXPECT_FALSE(insert_elite(map, elite(4, 12, 2.4)));  // worse
  EXPECT_EQ(ids_of(map), (std::vector<std::int64_t>{10}));
  EXPECT_TRUE(insert_elite(map, elite(4, 13, std::nextafter(2.5, 3.0))));  // one ulp better
  EXPECT_EQ(ids_of(map), (std::vector<std::int64_t>{13}));
  EXPECT_EQ(map.size(), 1u);
}

TEST(MapElitesDescriptors, FormulasOnAHandMadeBody) {
  // A 2 x 1 x 3 body in a 4 x 4 x 4 lattice: 5 voxels (one empty cell), 2 of them chamber 1
  // voxels (value 11). actuated 2/5, void 1 - 5/64, height 3 voxels of 1 cm, elongation 3/1.
  DevelopedBody b;
  b.valid = b.actuatable = true;
  b.chamber_count = 1;
  b.plan.lattice = {2, 1, 3};
  b.plan.cells = {1, 11, 0, 5, 11, 3};
  const std::vector<double> d = body_descriptor_values(b, 64, 0.01);
  ASSERT_EQ(d.size(), map_descriptor_names().size());
  EXPECT_EQ(d[0], 1.0);
  EXPECT_DOUBLE_EQ(d[1], 0.4);
  EXPECT_DOUBLE_EQ(d[2], 1.0 - 5.0 / 64.0);
  EXPECT_EQ(d[3], 5.0);
  EXPECT_DOUBLE_EQ(d[4], 0.03);
  EXPECT_EQ(d[5], 3.0);
  EXPECT_TRUE(std::isnan(d[6]));  // mean_speed comes from the evaluation
}

Config map_config() {
  Config c;
  c.search.strategy = SearchKind::map_elites;
  c.body.lattice = {4, 4, 4};
  c.neat.pop_size = 6;
  c.map_elites.descriptors = {"voxels", "mean_speed"};
  c.map_elites.min = {0, -0.05};
  c.map_elites.max = {64, 0.05};
  c.map_elites.bins = {8, 4};
  return c;
}

std::vector<Evaluation> score(const SearchStrategy& s, bool killed = false) {
  std::vector<Evaluation> out;
  for (const Individual& m : s.ask())
    out.push_back({m.id, m.genome.cppn.connections.front().weight, killed});
  return out;
}

TEST(MapElitesStrategy, TheBatchFillsTheMapAndOffspringComeFromElites) {
  const Config c = map_config();
  MapElites me = MapElites::create(c, 2, 9);
  ASSERT_EQ(me.ask().size(), 6u);
  const std::vector<Evaluation> results = score(me);
  const std::vector<Individual> batch = me.ask();
  me.tell(results);
  EXPECT_EQ(me.generation(), 1);
  ASSERT_FALSE(me.elites().empty());
  // Every elite sits in the cell of its descriptors: voxels, and fitness [cm] / 100 / 10 s.
  for (const Elite& e : me.elites()) {
    EXPECT_EQ(e.cell, me.grid().cell(e.descriptors));
    EXPECT_DOUBLE_EQ(e.descriptors[1], e.fitness / 100.0 / c.task.eval_seconds);
  }
  // The report: one row per member (ascending id), the map, the metrics.
  const StrategyReport& r = me.report();
  EXPECT_EQ(r.rows.rows(), 6u);
  EXPECT_EQ(r.map.rows(), me.elites().size());
  EXPECT_EQ(r.metric("num_elites"), static_cast<double>(me.elites().size()));
  EXPECT_DOUBLE_EQ(r.metric("coverage"), static_cast<double>(me.elites().size()) / 32.0);
  double qd = 0.0;
  for (const Elite& e : me.elites()) qd += e.fitness;
  EXPECT_DOUBLE_EQ(r.metric("qd_score"), qd);  // qd_offset 0
  // The next batch: pop_size offspring, each of an elite.
  ASSERT_EQ(me.ask().size(), 6u);
  for (const Individual& m : me.ask()) {
    bool of_elite = false;
    for (const Elite& e : me.elites()) of_elite = of_elite || e.individual.id == m.parent1;
    EXPECT_TRUE(of_elite) << "offspring " << m.id << " of " << m.parent1;
    EXPECT_GT(m.id, batch.back().id);
  }
}

TEST(MapElitesStrategy, KilledRobotsStayOutAndAnEmptyMapIsAnError) {
  MapElites me = MapElites::create(map_config(), 2, 9);
  const std::vector<std::uint8_t> before = me.serialize();
  try {
    me.tell(score(me, true));
    FAIL() << "an empty map was accepted";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("map is empty"), std::string::npos) << e.what();
  }
  EXPECT_EQ(me.serialize(), before);
}

TEST(MapElitesStrategy, StateRoundTripContinuesIdentically) {
  const Config c = map_config();
  MapElites a = MapElites::create(c, 2, 4);
  a.tell(score(a));
  MapElites b = MapElites::deserialize(a.serialize(), c, 2);
  EXPECT_EQ(b.serialize(), a.serialize());
  a.tell(score(a));
  b.tell(score(b));
  EXPECT_EQ(b.serialize(), a.serialize());
  EXPECT_EQ(b.report(), a.report());
}

}  // namespace
}  // namespace softevo::evo
