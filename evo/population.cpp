#include "evo/population.hpp"

#include <cmath>
#include <stdexcept>
#include <string>
#include <unordered_map>
#include <unordered_set>
#include <utility>

#include "common/wire.hpp"
#include "evo/development.hpp"

namespace softevo::evo {

namespace {

// A generation whose immigrants never turn out viable would loop forever: give up after this
// many rounds of creating (pop_size - #viable) random genomes.
constexpr int kMaxImmigrantRounds = 1000;

// Layout version of the population payload (bumped on any change of the layout below).
constexpr std::uint32_t kPopulationStateVersion = 1;

}  // namespace

Viability robot_viability(const BodyConfig& body) {
  return [body](const Genome& g) {
    const DevelopedBody d = develop_body(g.cppn, body);
    return d.valid && d.actuatable;
  };
}

Population::Population(const EvoParams& params, Viability viable, std::uint64_t seed)
    : params_(params), viable_(std::move(viable)), rng_(seed), innovation_(params.num_outputs) {}

Population Population::create(const Config& config, int task_inputs, std::uint64_t seed) {
  return create(evo_params(config, task_inputs), robot_viability(config.body), seed);
}

Population Population::create(const EvoParams& params, Viability viable, std::uint64_t seed) {
  if (params.neat.pop_size < 1) throw std::invalid_argument("neat.pop_size must be >= 1");
  Population pop(params, std::move(viable), seed);
  // neat Population.__init__: create_new(pop_size) with keys 1..pop_size, then speciate at g=0.
  for (std::int64_t i = 0; i < params.neat.pop_size; ++i) {
    Individual ind;
    ind.id = pop.innovation_.new_genome_id();
    ind.genome = random_genome(params, pop.rng_);
    pop.members_.push_back(std::move(ind));
  }
  pop.speciate_members();
  pop.apply_immigrants();
  return pop;
}

void Population::speciate_members() {
  std::vector<SpeciationInput> input;
  input.reserve(members_.size());
  for (const Individual& m : members_) input.push_back({m.id, &m.genome.cppn});
  const std::vector<std::int64_t> ids =
      speciate(species_, input, generation_, params_.neat, innovation_,
               params_.paper_distance ? DistanceMode::neat_paper : DistanceMode::neat_python);
  for (std::size_t i = 0; i < members_.size(); ++i) members_[i].species = ids[i];
}

void Population::apply_immigrants() {
  // §8.1 step 2: keep the viable genomes; while fewer than pop_size, create (pop_size - #viable)
  // fresh random genomes (fresh ids, consumed even by the unviable ones) and keep the viable ones.
  // A surplus (from spawn rounding or rescue clones) is never removed.
  immigrants_created_ = 0;
  if (!viable_) return speciate_members();
  std::vector<Individual> kept;
  kept.reserve(members_.size());
  for (Individual& m : members_)
    if (viable_(m.genome)) kept.push_back(std::move(m));
  const auto pop_size = static_cast<std::size_t>(params_.neat.pop_size);
  int rounds = 0;
  while (kept.size() < pop_size) {
    if (++rounds > kMaxImmigrantRounds)
      throw std::runtime_error("random immigrants: no viable genome after " +
                               std::to_string(kMaxImmigrantRounds) +
                               " rounds (check the body configuration)");
    const std::size_t missing = pop_size - kept.size();
    for (std::size_t i = 0; i < missing; ++i) {
      Individual ind;
      ind.id = innovation_.new_genome_id();
      ind.genome = random_genome(params_, rng_);
      ++immigrants_created_;
      if (viable_(ind.genome)) kept.push_back(std::move(ind));
    }
  }
  members_ = std::move(kept);
  speciate_members();  // same generation number
}

void Population::advance(const std::vector<Evaluation>& results) {
  Population next = *this;  // strong guarantee: all-or-nothing
  next.advance_impl(results);
  *this = std::move(next);
}

std::unordered_map<std::int64_t, const Evaluation*> evaluations_by_id(
    const std::vector<Evaluation>& results) {
  std::unordered_map<std::int64_t, const Evaluation*> by_id;
  for (const Evaluation& e : results) {
    if (!std::isfinite(e.fitness))
      throw std::invalid_argument("evaluation of genome " + std::to_string(e.id) +
                                  ": fitness is not finite");
    if (!by_id.emplace(e.id, &e).second)
      throw std::invalid_argument("evaluation of genome " + std::to_string(e.id) + " given twice");
  }
  return by_id;
}

void Population::advance_impl(const std::vector<Evaluation>& results) {
  const std::unordered_map<std::int64_t, const Evaluation*> by_id = evaluations_by_id(results);
  std::vector<ScoredIndividual> scored;
  scored.reserve(members_.size() + species_.size());
  std::unordered_set<std::int64_t> member_ids;
  for (const Individual& m : members_) {
    member_ids.insert(m.id);
    auto it = by_id.find(m.id);
    if (it == by_id.end())
      throw std::invalid_argument("generation " + std::to_string(generation_) +
                                  ": no evaluation for genome " + std::to_string(m.id));
    scored.push_back(ScoredIndividual{m, it->second->fitness, it->second->killed});
  }
  for (const Evaluation& e : results)
    if (!member_ids.count(e.id))
      throw std::invalid_argument("generation " + std::to_string(generation_) +
                                  ": evaluation for unknown genome " + std::to_string(e.id));

  // Step 4, singleton rescue: a species with one member gets an unmutated clone (new id, fitness
  // and killed copied), so it has two parents and the elite is not its only offspring.
  std::unordered_map<std::int64_t, std::size_t> index;
  for (std::size_t i = 0; i < scored.size(); ++i) index[scored[i].individual.id] = i;
  for (Species& s : species_) {
    if (s.members.size() != 1) continue;
    ScoredIndividual clone = scored[index.at(s.members.front())];
    clone.individual.parent1 = clone.individual.id;
    clone.individual.parent2 = clone.individual.id;
    clone.individual.id = innovation_.new_genome_id();
    s.members.push_back(clone.individual.id);
    scored.push_back(std::move(clone));
  }

  // Step 5: best genome = max fitness, first wins ties; best-ever only on a strict improvement.
  const ScoredIndividual* best = nullptr;
  for (const ScoredIndividual& m : scored)
    if (best == nullptr || m.fitness > best->fitness) best = &m;
  if (best != nullptr && (!best_ever_ || best->fitness > best_ever_->fitness))
    best_ever_ = Best{best->individual.id, generation_, best->fitness, best->individual.genome};

  // Step 6: reproduction (reset_on_extinction = False: extinction is an error).
  std::vector<Individual> next =
      reproduce(species_, scored, generation_, params_, innovation_, rng_);
  if (next.empty())
    throw std::runtime_error("generation " + std::to_string(generation_) +
                             ": every species went extinct");
  last_evaluated_ = std::move(scored);
  members_ = std::move(next);
  // Step 7: speciate the offspring (still generation g, as neat-python), then g += 1.
  speciate_members();
  ++generation_;
  // Step 2 of the new generation.
  apply_immigrants();
}

// ---------------------------------------------------------------------------------------------
// State layout (payload of a MessageKind::population frame), little-endian, in this order:
//   u32 layout version (1)
//   i64 generation
//   4 x u64 Rng state
//   i32 next node key, i64 next genome id, i64 next species id
//   u64 member count, per member: i64 id, i64 parent1, i64 parent2, i64 species, genome payload
//   u64 species count, per species: i64 id, i64 created, i64 last_improved,
//       f64_vector fitness history, f64 fitness, f64 adjusted fitness,
//       genome payload of the representative (CPPN only), u64 member count + i64 member ids
//   u8 has best-ever, then (if 1): i64 id, i64 generation, f64 fitness, genome payload
//   u64 immigrants created for this generation
std::vector<std::uint8_t> Population::serialize() const {
  WireWriter w;
  w.u32(kPopulationStateVersion);
  w.i64(generation_);
  for (std::uint64_t word : rng_.state()) w.u64(word);
  w.i32(innovation_.next_node_key());
  w.i64(innovation_.next_genome_id());
  w.i64(innovation_.next_species_id());
  w.u64(members_.size());
  for (const Individual& m : members_) {
    w.i64(m.id);
    w.i64(m.parent1);
    w.i64(m.parent2);
    w.i64(m.species);
    write_genome_payload(w, m.genome);
  }
  w.u64(species_.size());
  for (const Species& s : species_) {
    w.i64(s.id);
    w.i64(s.created);
    w.i64(s.last_improved);
    w.f64_vector(s.fitness_history);
    w.f64(s.fitness);
    w.f64(s.adjusted_fitness);
    Genome rep;
    rep.cppn = s.representative;
    write_genome_payload(w, rep);
    w.u64(s.members.size());
    for (std::int64_t id : s.members) w.i64(id);
  }
  w.boolean(best_ever_.has_value());
  if (best_ever_) {
    w.i64(best_ever_->id);
    w.i64(best_ever_->generation);
    w.f64(best_ever_->fitness);
    write_genome_payload(w, best_ever_->genome);
  }
  w.u64(static_cast<std::uint64_t>(immigrants_created_));
  return frame_message(MessageKind::population, w.data());
}

Population Population::deserialize(std::span<const std::uint8_t> bytes, const Config& config,
                                   int task_inputs) {
  return deserialize(bytes, evo_params(config, task_inputs), robot_viability(config.body));
}

Population Population::deserialize(std::span<const std::uint8_t> bytes, const EvoParams& params,
                                   Viability viable) {
  WireReader r(unframe_message(bytes, MessageKind::population), "population");
  auto fail = [](const std::string& msg) { throw WireError("population: " + msg); };
  const std::uint32_t version = r.u32("layout version");
  if (version != kPopulationStateVersion)
    fail("unsupported layout version " + std::to_string(version) + " (expected " +
         std::to_string(kPopulationStateVersion) + ")");
  Population pop(params, std::move(viable), 0);
  pop.generation_ = r.i64("generation");
  if (pop.generation_ < 0) fail("negative generation");
  Rng::State state{};
  for (std::uint64_t& word : state) word = r.u64("rng state");
  try {
    pop.rng_.set_state(state);
  } catch (const std::exception& e) {
    fail(std::string("rng state: ") + e.what());
  }
  const int next_node = r.i32("next node key");
  const std::int64_t next_genome = r.i64("next genome id");
  const std::int64_t next_species = r.i64("next species id");
  try {
    pop.innovation_.restore(next_node, next_genome, next_species);
  } catch (const std::invalid_argument& e) {
    fail(e.what());
  }
  auto check_genome = [&](const Genome& g, const std::string& what) {
    if (g.cppn.num_inputs != params.num_inputs || g.cppn.num_outputs != params.num_outputs)
      throw std::invalid_argument(
          what + ": CPPN has " + std::to_string(g.cppn.num_inputs) + " inputs and " +
          std::to_string(g.cppn.num_outputs) + " outputs, the configuration " +
          std::to_string(params.num_inputs) + " and " + std::to_string(params.num_outputs));
    for (const NodeGene& n : g.cppn.nodes)
      if (n.key >= next_node && n.key >= params.num_outputs)
        fail(what + ": node key " + std::to_string(n.key) + " not below the node-key counter");
    if (params.with_controller) {
      try {
        check_controller_shape(g, params.shape);
      } catch (const std::invalid_argument& e) {
        throw std::invalid_argument(what + ": " + e.what());
      }
    } else if (g.has_controller()) {
      throw std::invalid_argument(what + ": has a controller, the configuration none");
    }
  };
  const std::uint64_t member_count = r.u64("member count");
  if (member_count > r.remaining() / 32) fail("member count exceeds the message length");
  std::unordered_set<std::int64_t> ids;
  for (std::uint64_t i = 0; i < member_count; ++i) {
    Individual m;
    m.id = r.i64("member id");
    m.parent1 = r.i64("member parent1");
    m.parent2 = r.i64("member parent2");
    m.species = r.i64("member species");
    m.genome = read_genome_payload(r);
    const std::string what = "member " + std::to_string(m.id);
    if (m.id < 1 || m.id >= next_genome) fail(what + ": id outside [1, next genome id)");
    if (!ids.insert(m.id).second) fail(what + ": duplicate id");
    check_genome(m.genome, what);
    pop.members_.push_back(std::move(m));
  }
  const std::uint64_t species_count = r.u64("species count");
  if (species_count > r.remaining() / 48) fail("species count exceeds the message length");
  std::unordered_map<std::int64_t, std::int64_t> species_of;
  for (std::uint64_t i = 0; i < species_count; ++i) {
    Species s;
    s.id = r.i64("species id");
    s.created = r.i64("species created");
    s.last_improved = r.i64("species last_improved");
    s.fitness_history = r.f64_vector("species fitness history");
    s.fitness = r.f64("species fitness");
    s.adjusted_fitness = r.f64("species adjusted fitness");
    Genome rep = read_genome_payload(r);
    const std::string what = "species " + std::to_string(s.id);
    if (s.id < 1 || s.id >= next_species) fail(what + ": id outside [1, next species id)");
    if (rep.has_controller()) fail(what + ": representative must be a CPPN only");
    if (rep.cppn.num_inputs != params.num_inputs || rep.cppn.num_outputs != params.num_outputs)
      throw std::invalid_argument(what +
                                  ": representative CPPN dimensions differ from the "
                                  "configuration");
    s.representative = std::move(rep.cppn);
    const std::uint64_t n = r.u64("species member count");
    if (n > r.remaining() / 8) fail(what + ": member count exceeds the message length");
    for (std::uint64_t k = 0; k < n; ++k) {
      const std::int64_t id = r.i64("species member id");
      if (!ids.count(id))
        fail(what + ": member " + std::to_string(id) + " is not in the population");
      if (!species_of.emplace(id, s.id).second)
        fail(what + ": member " + std::to_string(id) + " is in two species");
      s.members.push_back(id);
    }
    pop.species_.push_back(std::move(s));
  }
  for (const Individual& m : pop.members_) {
    auto it = species_of.find(m.id);
    if (it == species_of.end() || it->second != m.species)
      fail("member " + std::to_string(m.id) + ": species " + std::to_string(m.species) +
           " does not list it");
  }
  if (r.boolean("has best")) {
    Best b;
    b.id = r.i64("best id");
    b.generation = r.i64("best generation");
    b.fitness = r.f64("best fitness");
    b.genome = read_genome_payload(r);
    check_genome(b.genome, "best genome");
    pop.best_ever_ = std::move(b);
  }
  pop.immigrants_created_ = r.i64("immigrants created");
  r.finish();
  return pop;
}

void adopt_learned_controller(std::vector<Individual>& members, std::int64_t id,
                              const Genome& learned, const ControllerShape& shape) {
  for (Individual& m : members) {
    if (m.id != id) continue;
    if (encode_genome(Genome{m.genome.cppn, {}, {}}) != encode_genome(Genome{learned.cppn, {}, {}}))
      throw std::invalid_argument("adopt_controller: genome " + std::to_string(id) +
                                  ": the learned genome has another body");
    check_controller_shape(learned, shape);
    m.genome.controller = learned.controller;
    m.genome.step_sizes = learned.step_sizes;
    return;
  }
  throw std::invalid_argument("adopt_controller: no member with id " + std::to_string(id));
}

void Population::adopt_controller(std::int64_t id, const Genome& learned) {
  adopt_learned_controller(members_, id, learned, params_.shape);
}

}  // namespace softevo::evo
