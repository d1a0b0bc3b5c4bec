// Global node-key / genome-id / species-id counters.
#include "evo/innovation.hpp"

#include <gtest/gtest.h>

#include <stdexcept>

namespace softevo::evo {
namespace {

TEST(Innovation, CountersStartAfterOutputsAndAtOne) {
  InnovationTracker t(4);
  EXPECT_EQ(t.new_node_key(), 4);  // neat-python: max(output keys) + 1
  EXPECT_EQ(t.new_node_key(), 5);
  EXPECT_EQ(t.new_genome_id(), 1);
  EXPECT_EQ(t.new_genome_id(), 2);
  EXPECT_EQ(t.new_species_id(), 1);
  EXPECT_EQ(t.next_node_key(), 6);
  EXPECT_EQ(t.next_genome_id(), 3);
  EXPECT_EQ(t.next_species_id(), 2);
}

TEST(Innovation, RestoreContinuesAndRejectsNonsense) {
  InnovationTracker t(1);
  t.restore(40, 1000, 17);
  EXPECT_EQ(t.new_node_key(), 40);
  EXPECT_EQ(t.new_genome_id(), 1000);
  EXPECT_EQ(t.new_species_id(), 17);
  EXPECT_THROW(t.restore(-1, 1, 1), std::invalid_argument);
  EXPECT_THROW(t.restore(4, 0, 1), std::invalid_argument);
  EXPECT_THROW(t.restore(4, 1, 0), std::invalid_argument);
}

}  // namespace
}  // namespace softevo::evo
