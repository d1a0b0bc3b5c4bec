// The search-strategy seam (docs/model.md §8.12): NEAT behind it is the population of before
// (same members, same state bytes), and a state is restored only by its own strategy.
#include "evo/search_strategy.hpp"

#include <gtest/gtest.h>

#include "common/wire.hpp"
#include "evo/population.hpp"

namespace softevo::evo {
namespace {

Config small(SearchKind kind) {
  Config c;
  c.search.strategy = kind;
  c.body.lattice = {4, 4, 4};
  c.neat.pop_size = 5;
  return c;
}

std::vector<Evaluation> score(const std::vector<Individual>& members) {
  std::vector<Evaluation> out;
  for (const Individual& m : members)
    out.push_back({m.id, m.genome.cppn.connections.front().weight, false});
  return out;
}

TEST(SearchStrategy, NeatBehindTheSeamIsThePopulation) {
  const Config c = small(SearchKind::neat);
  std::unique_ptr<SearchStrategy> s = make_strategy(c, 2, 17);
  Population p = Population::create(c, 2, 17);
  EXPECT_STREQ(s->name(), "neat");
  for (int g = 0; g < 3; ++g) {
    ASSERT_EQ(s->serialize(), p.serialize());
    EXPECT_EQ(s->species_count(), static_cast<std::int64_t>(p.species_count()));
    s->tell(score(s->ask()));
    p.advance(score(p.members()));
  }
  EXPECT_TRUE(s->report().empty());  // species are the archive's own columns
}

TEST(SearchStrategy, EachStrategyRestoresItsOwnStateOnly) {
  for (SearchKind kind : {SearchKind::neat, SearchKind::map_elites, SearchKind::afpo}) {
    const Config c = small(kind);
    std::unique_ptr<SearchStrategy> s = make_strategy(c, 2, 5);
    s->tell(score(s->ask()));
    const std::vector<std::uint8_t> state = s->serialize();
    EXPECT_EQ(serialized_strategy(state), kind);
    EXPECT_EQ(restore_strategy(state, c, 2)->serialize(), state);
    const SearchKind other = kind == SearchKind::afpo ? SearchKind::neat : SearchKind::afpo;
    try {
      restore_strategy(state, small(other), 2);
      FAIL() << "a state of " << to_string(kind) << " restored as " << to_string(other);
    } catch (const std::invalid_argument& e) {
      const std::string what = e.what();
      EXPECT_NE(what.find(std::string("\"") + to_string(kind) + "\""), std::string::npos) << what;
      EXPECT_NE(what.find(std::string("\"") + to_string(other) + "\""), std::string::npos) << what;
    }
  }
}

}  // namespace
}  // namespace softevo::evo
