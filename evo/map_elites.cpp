#include "evo/map_elites.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

namespace softevo::evo {

namespace {

constexpr std::uint32_t kMapElitesStateVersion = 1;

// Fitness [cm] of the gait task over its length [s] as a speed [m/s] (docs/model.md §7.1).
double mean_speed(double fitness_cm, double eval_seconds) {
  return fitness_cm / 100.0 / eval_seconds;
}

}  // namespace

bool insert_elite(std::vector<Elite>& map, Elite candidate) {
  const auto it = std::lower_bound(map.begin(), map.end(), candidate.cell,
                                   [](const Elite& e, std::int64_t cell) { return e.cell < cell; });
  if (it != map.end() && it->cell == candidate.cell) {
    if (!(candidate.fitness > it->fitness)) return false;  // ties keep the incumbent
    *it = std::move(candidate);
    return true;
  }
  map.insert(it, std::move(candidate));
  return true;
}

std::vector<double> body_descriptor_values(const DevelopedBody& body, std::int64_t lattice_cells,
                                           double voxel_size) {
  std::int64_t voxels = 0;
  std::int64_t chamber_voxels = 0;
  for (int v : body.plan.cells) {
    if (v == kEmptyCell) continue;
    ++voxels;
    if (BodyPlan::is_chamber(v)) ++chamber_voxels;
  }
  const auto& box = body.plan.lattice;
  const int longest = std::max({box[0], box[1], box[2]});
  const int shortest = std::min({box[0], box[1], box[2]});
  const double nan = std::numeric_limits<double>::quiet_NaN();
  return {
      static_cast<double>(body.chamber_count),
      voxels > 0 ? static_cast<double>(chamber_voxels) / static_cast<double>(voxels) : 0.0,
      1.0 - static_cast<double>(voxels) / static_cast<double>(lattice_cells),
      static_cast<double>(voxels),
      static_cast<double>(box[2]) * voxel_size,
      shortest > 0 ? static_cast<double>(longest) / static_cast<double>(shortest) : 0.0,
      nan,
  };
}

MapElites MapElites::create(const Config& config, int task_inputs, std::uint64_t seed) {
  MapElites me(config, task_inputs, seed);
  me.draw_first_generation();
  return me;
}

std::vector<double> MapElites::descriptors(const Genome& genome,
                                           const Evaluation& evaluation) const {
  const DevelopedBody body = develop_body(genome.cppn, config_.body);
  const auto& l = config_.body.lattice;
  const std::vector<double> all =
      body_descriptor_values(body, l[0] * l[1] * l[2], config_.physics.voxel_size);
  std::vector<double> out;
  for (const MapAxis& a : grid_.axes)
    out.push_back(a.descriptor == MapDescriptor::mean_speed
                      ? mean_speed(evaluation.fitness, config_.task.eval_seconds)
                      : all[static_cast<std::size_t>(a.descriptor)]);
  return out;
}

void MapElites::tell_impl(const std::vector<Evaluation>& results) {
  const std::vector<Evaluation> matched = match_results(members_, results, generation_);
  std::vector<std::size_t> order(members_.size());
  for (std::size_t i = 0; i < order.size(); ++i) order[i] = i;
  std::sort(order.begin(), order.end(),
            [&](std::size_t a, std::size_t b) { return members_[a].id < members_[b].id; });
  StrategyReport report;
  report.strategy = "map_elites";
  report.rows.columns = {"cell", "placed"};
  for (const MapAxis& a : grid_.axes) report.rows.columns.push_back(a.name);
  for (std::size_t i : order) {
    const Evaluation& e = matched[i];
    std::vector<double> d = descriptors(members_[i].genome, e);
    const std::int64_t cell = grid_.cell(d);
    bool placed = false;
    // Only a robot that ran its evaluation to the end (status ok) has a place in the map.
    if (!e.killed && cell >= 0)
      placed = insert_elite(elites_, Elite{cell, members_[i], e.fitness, d, generation_});
    report.rows.values.push_back(static_cast<double>(cell));
    report.rows.values.push_back(placed ? 1.0 : 0.0);
    report.rows.values.insert(report.rows.values.end(), d.begin(), d.end());
  }
  if (elites_.empty())
    throw std::runtime_error("generation " + std::to_string(generation_) +
                             ": the map is empty (no robot of the generation was evaluated with "
                             "status ok): MAP-Elites has no elite to reproduce from");
  report.map.columns = {"cell", "id", "fitness", "generation"};
  for (const MapAxis& a : grid_.axes) report.map.columns.push_back(a.name);
  double max_fitness = -std::numeric_limits<double>::infinity();
  double sum = 0.0;
  double qd = 0.0;
  for (const Elite& e : elites_) {
    report.map.values.insert(report.map.values.end(),
                             {static_cast<double>(e.cell), static_cast<double>(e.individual.id),
                              e.fitness, static_cast<double>(e.generation)});
    report.map.values.insert(report.map.values.end(), e.descriptors.begin(), e.descriptors.end());
    max_fitness = std::max(max_fitness, e.fitness);
    sum += e.fitness;
    qd += e.fitness - config_.map_elites.qd_offset;
  }
  const auto n = static_cast<double>(elites_.size());
  report.metrics = {{"num_elites", n},
                    {"coverage", n / static_cast<double>(grid_.cells())},
                    {"qd_score", qd},
                    {"max_fitness", max_fitness},
                    {"mean_fitness", sum / n}};
  report_ = std::move(report);
  ++generation_;
  next_batch();
}

void MapElites::next_batch() {
  // Offspring of uniformly drawn elites (cells in ascending order), in batch order.
  members_.clear();
  const double p_cross = config_.map_elites.crossover_probability;
  for (std::int64_t k = 0; k < config_.neat.pop_size; ++k) {
    const Elite& a = elites_[rng_.uniform_int(elites_.size())];
    const Elite* b = nullptr;
    if (rng_.uniform() < p_cross) b = &elites_[rng_.uniform_int(elites_.size())];
    members_.push_back(mutated_offspring(a.individual, a.fitness, b ? &b->individual : nullptr,
                                         b ? b->fitness : 0.0, params_, viable_, innovation_,
                                         rng_));
  }
}

// ---------------------------------------------------------------------------------------------
// State layout (payload of a MessageKind::strategy_state frame), little-endian, in this order:
//   the head of write_state_head ("map_elites", layout version 1, generation, Rng, counters),
//   u64 member count, per member: i64 id, i64 parent1, i64 parent2, genome payload
//   u64 elite count, per elite (ascending cell): i64 cell, i64 generation, f64 fitness,
//       f64_vector descriptors, then the individual as a member
std::vector<std::uint8_t> MapElites::serialize() const {
  WireWriter w;
  write_state_head(w, SearchKind::map_elites, kMapElitesStateVersion, generation_, rng_,
                   innovation_);
  w.u64(members_.size());
  for (const Individual& m : members_) write_individual(w, m);
  w.u64(elites_.size());
  for (const Elite& e : elites_) {
    w.i64(e.cell);
    w.i64(e.generation);
    w.f64(e.fitness);
    w.f64_vector(e.descriptors);
    write_individual(w, e.individual);
  }
  return frame_message(MessageKind::strategy_state, w.data());
}

MapElites MapElites::deserialize(std::span<const std::uint8_t> bytes, const Config& config,
                                 int task_inputs) {
  WireReader r(unframe_message(bytes, MessageKind::strategy_state), "map_elites state");
  auto fail = [](const std::string& msg) { throw WireError("map_elites state: " + msg); };
  MapElites me(config, task_inputs, 0);
  me.generation_ =
      read_state_head(r, SearchKind::map_elites, kMapElitesStateVersion, me.rng_, me.innovation_);
  const std::uint64_t members = r.u64("member count");
  if (members > r.remaining() / 24) fail("member count exceeds the message length");
  for (std::uint64_t i = 0; i < members; ++i)
    me.members_.push_back(read_individual(r, me.params_, me.innovation_, "member"));
  const std::uint64_t elites = r.u64("elite count");
  if (elites > r.remaining() / 48) fail("elite count exceeds the message length");
  for (std::uint64_t i = 0; i < elites; ++i) {
    Elite e;
    e.cell = r.i64("elite cell");
    e.generation = r.i64("elite generation");
    e.fitness = r.f64("elite fitness");
    e.descriptors = r.f64_vector("elite descriptors");
    const std::string what = "elite of cell " + std::to_string(e.cell);
    e.individual = read_individual(r, me.params_, me.innovation_, what + ": genome");
    if (e.cell < 0 || e.cell >= me.grid_.cells()) fail(what + ": cell outside the grid");
    if (!me.elites_.empty() && me.elites_.back().cell >= e.cell)
      fail(what + ": cells not ascending");
    if (e.descriptors.size() != me.grid_.axes.size())
      fail(what + ": " + std::to_string(e.descriptors.size()) + " descriptors, the grid has " +
           std::to_string(me.grid_.axes.size()));
    me.elites_.push_back(std::move(e));
  }
  r.finish();
  return me;
}

}  // namespace softevo::evo
