#include "evo/search_strategy.hpp"

#include <cmath>
#include <stdexcept>
#include <string>
#include <unordered_map>

#include "evo/afpo.hpp"
#include "evo/crossover.hpp"
#include "evo/map_elites.hpp"
#include "evo/mutation.hpp"
#include "evo/neat_strategy.hpp"

namespace softevo::evo {

namespace {

// Unviable draws allowed per genome wanted before the strategy gives up (as NEAT's immigrants).
constexpr std::size_t kMaxDrawsPerGenome = 1000;

}  // namespace

std::unique_ptr<SearchStrategy> make_strategy(const Config& config, int task_inputs,
                                              std::uint64_t seed) {
  switch (config.search.strategy) {
    case SearchKind::map_elites:
      return std::make_unique<MapElites>(MapElites::create(config, task_inputs, seed));
    case SearchKind::afpo:
      return std::make_unique<Afpo>(Afpo::create(config, task_inputs, seed));
    case SearchKind::neat:
      break;
  }
  return std::make_unique<NeatStrategy>(Population::create(config, task_inputs, seed));
}

SearchKind serialized_strategy(std::span<const std::uint8_t> bytes) {
  const MessageKind kind = peek_message_kind(bytes);
  if (kind == MessageKind::population) return SearchKind::neat;
  if (kind != MessageKind::strategy_state)
    throw WireError("strategy state: message kind " + std::to_string(static_cast<int>(kind)) +
                    " is no strategy's");
  WireReader r(unframe_message(bytes, MessageKind::strategy_state), "strategy state");
  const std::string name = r.string("strategy");
  const auto k = choice_from_string<SearchKind>(name);
  if (!k) throw WireError("strategy state: unknown strategy \"" + name + "\"");
  return *k;
}

std::unique_ptr<SearchStrategy> restore_strategy(std::span<const std::uint8_t> bytes,
                                                 const Config& config, int task_inputs) {
  const SearchKind kind = serialized_strategy(bytes);
  if (kind != config.search.strategy)
    throw std::invalid_argument(std::string("the state is of search strategy \"") +
                                to_string(kind) + "\", the configuration's search.strategy is \"" +
                                to_string(config.search.strategy) + "\"");
  switch (kind) {
    case SearchKind::map_elites:
      return std::make_unique<MapElites>(MapElites::deserialize(bytes, config, task_inputs));
    case SearchKind::afpo:
      return std::make_unique<Afpo>(Afpo::deserialize(bytes, config, task_inputs));
    case SearchKind::neat:
      break;
  }
  return std::make_unique<NeatStrategy>(Population::deserialize(bytes, config, task_inputs));
}

std::vector<Evaluation> match_results(const std::vector<Individual>& members,
                                      const std::vector<Evaluation>& results,
                                      std::int64_t generation) {
  const std::unordered_map<std::int64_t, const Evaluation*> by_id = evaluations_by_id(results);
  std::vector<Evaluation> out;
  out.reserve(members.size());
  for (const Individual& m : members) {
    const auto it = by_id.find(m.id);
    if (it == by_id.end())
      throw std::invalid_argument("generation " + std::to_string(generation) +
                                  ": no evaluation for genome " + std::to_string(m.id));
    out.push_back(*it->second);
  }
  if (results.size() != members.size())
    throw std::invalid_argument("generation " + std::to_string(generation) + ": " +
                                std::to_string(results.size()) + " evaluations for " +
                                std::to_string(members.size()) + " members");
  return out;
}

std::vector<Individual> random_individuals(std::size_t count, const EvoParams& params,
                                           const Viability& viable, InnovationTracker& innovation,
                                           Rng& rng) {
  std::vector<Individual> out;
  std::size_t draws = 0;
  while (out.size() < count) {
    if (++draws > kMaxDrawsPerGenome * count)
      throw std::runtime_error("random genomes: " + std::to_string(draws - 1) +
                               " draws gave only " + std::to_string(out.size()) + " of " +
                               std::to_string(count) +
                               " viable bodies (check the body configuration)");
    Genome g = random_genome(params, rng);
    if (viable && !viable(g)) continue;
    Individual ind;
    ind.id = innovation.new_genome_id();
    ind.genome = std::move(g);
    out.push_back(std::move(ind));
  }
  return out;
}

Individual mutated_offspring(const Individual& a, double fitness_a, const Individual* b,
                             double fitness_b, const EvoParams& params, const Viability& viable,
                             InnovationTracker& innovation, Rng& rng) {
  for (std::size_t draw = 0; draw < kMaxDrawsPerGenome; ++draw) {
    Genome g =
        b == nullptr ? a.genome : crossover(a.genome, fitness_a, b->genome, fitness_b, params, rng);
    mutate(g, params, innovation, rng);
    if (viable && !viable(g)) continue;
    Individual child;
    child.id = innovation.new_genome_id();
    child.parent1 = a.id;
    child.parent2 = b == nullptr ? -1 : b->id;
    child.genome = std::move(g);
    return child;
  }
  throw std::runtime_error("offspring of genome " + std::to_string(a.id) + ": " +
                           std::to_string(kMaxDrawsPerGenome) + " mutations gave no viable body");
}

void write_state_head(WireWriter& w, SearchKind kind, std::uint32_t version,
                      std::int64_t generation, const Rng& rng, const InnovationTracker& counters) {
  w.string(to_string(kind));
  w.u32(version);
  w.i64(generation);
  for (std::uint64_t word : rng.state()) w.u64(word);
  w.i32(counters.next_node_key());
  w.i64(counters.next_genome_id());
  w.i64(counters.next_species_id());
}

std::int64_t read_state_head(WireReader& r, SearchKind kind, std::uint32_t version, Rng& rng,
                             InnovationTracker& counters) {
  const std::string what = std::string(to_string(kind)) + " state: ";
  const auto fail = [&](const std::string& msg) { throw WireError(what + msg); };
  const std::string name = r.string("strategy");
  if (name != to_string(kind)) fail("the state is of strategy \"" + name + "\"");
  const std::uint32_t v = r.u32("layout version");
  if (v != version)
    fail("unsupported layout version " + std::to_string(v) + " (expected " +
         std::to_string(version) + ")");
  const std::int64_t generation = r.i64("generation");
  if (generation < 0) fail("negative generation");
  Rng::State state{};
  for (std::uint64_t& word : state) word = r.u64("rng state");
  const int next_node = r.i32("next node key");
  const std::int64_t next_genome = r.i64("next genome id");
  const std::int64_t next_species = r.i64("next species id");
  try {
    rng.set_state(state);
    counters.restore(next_node, next_genome, next_species);
  } catch (const std::exception& e) {
    fail(e.what());
  }
  return generation;
}

void write_individual(WireWriter& w, const Individual& m) {
  w.i64(m.id);
  w.i64(m.parent1);
  w.i64(m.parent2);
  write_genome_payload(w, m.genome);
}

Individual read_individual(WireReader& r, const EvoParams& params,
                           const InnovationTracker& counters, const std::string& what) {
  Individual m;
  m.id = r.i64("member id");
  m.parent1 = r.i64("member parent1");
  m.parent2 = r.i64("member parent2");
  m.genome = read_genome_payload(r);
  const std::string who = what + " " + std::to_string(m.id);
  if (m.id < 1 || m.id >= counters.next_genome_id())
    throw WireError(who + ": id outside [1, next genome id)");
  if (m.genome.cppn.num_inputs != params.num_inputs ||
      m.genome.cppn.num_outputs != params.num_outputs)
    throw std::invalid_argument(who + ": CPPN dimensions differ from the configuration");
  check_controller_shape(m.genome, params.shape);
  return m;
}

}  // namespace softevo::evo
