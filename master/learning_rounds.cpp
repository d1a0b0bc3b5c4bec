#include "master/learning_rounds.hpp"

#include <algorithm>
#include <stdexcept>
#include <string>
#include <utility>

#include "common/wire.hpp"

namespace softevo::master {

namespace {

// Layout of serialize(): bump on any change (a checkpoint of another layout is refused, and the
// generation then learns again from round 0, which gives the same bits).
constexpr std::uint32_t kLearningStateVersion = 1;

void write_outcome(WireWriter& w, const GenomeOutcome& o) {
  w.i64(o.genome_id);
  w.u8(static_cast<std::uint8_t>(o.status));
  w.f64(o.fitness);
  w.u64(o.components.size());
  for (const UnitFitness& u : o.components) write_unit_fitness(w, u);
  w.i32(o.voxels);
  w.i32(o.chambers);
  w.f64(o.wall_seconds);
  w.i32(o.worker_rank);
  w.string(o.message);
}

GenomeOutcome read_outcome(WireReader& r) {
  GenomeOutcome o;
  o.genome_id = r.i64("outcome genome id");
  o.status = checked_status(r.u8("outcome status"), "learning state outcome");
  o.fitness = r.f64("outcome fitness");
  const std::uint64_t units = r.u64("outcome units");
  if (units > r.remaining() / 17)  // each unit takes at least 17 bytes
    throw WireError("learning state: outcome units exceed the message length");
  for (std::uint64_t k = 0; k < units; ++k)
    o.components.push_back(read_unit_fitness(r, "learning state outcome unit"));
  o.voxels = r.i32("outcome voxels");
  o.chambers = r.i32("outcome chambers");
  o.wall_seconds = r.f64("outcome wall seconds");
  o.worker_rank = r.i32("outcome worker rank");
  o.message = r.string("outcome message");
  return o;
}

}  // namespace

GenerationLearning::GenerationLearning(const Config& config, const evo::EvoParams& params,
                                       std::int64_t generation, std::vector<std::int64_t> ids,
                                       std::vector<evo::Genome> genomes,
                                       std::vector<GenomeOutcome> born, std::vector<double> costs)
    : params_(params),
      generation_(generation),
      iterations_(
          evo::learning_iterations(config.learning.evaluations, config.learning.population)),
      lambda_(static_cast<int>(config.learning.population)) {
  if (genomes.size() != ids.size() || born.size() != ids.size() ||
      (!costs.empty() && costs.size() != ids.size()))
    throw std::invalid_argument("generation learning: " + std::to_string(ids.size()) + " ids, " +
                                std::to_string(genomes.size()) + " genomes, " +
                                std::to_string(born.size()) + " outcomes, " +
                                std::to_string(costs.size()) + " costs");
  results_.resize(ids.size());
  for (std::size_t m = 0; m < ids.size(); ++m) {
    LearnedResult& r = results_[m];
    r.born = born[m];
    r.learned = born[m];
    // A body that does not learn keeps its fitness at every point (equal curve lengths).
    r.curve.assign(static_cast<std::size_t>(iterations_) + 1, born[m].fitness);
    r.wall_seconds = born[m].wall_seconds;
    if (born[m].status == EvalStatus::invalid_body || !genomes[m].has_controller()) {
      r.genome = std::move(genomes[m]);
      continue;
    }
    const evo::CandidateScore score{born[m].fitness, born[m].status == EvalStatus::ok};
    learners_.push_back(
        Body{m,
             evo::ControllerLearner(genomes[m], score, iterations_, lambda_,
                                    evo::learning_seed(config.run.seed, generation, ids[m]),
                                    config.learning.step_size_factor),
             costs.empty() ? 0.0 : costs[m]});
    r.genome = std::move(genomes[m]);
  }
}

void GenerationLearning::begin_iteration(std::vector<std::int64_t>& unit_ids,
                                         std::vector<double>& costs) {
  if (finished()) throw std::logic_error("generation learning: no iteration left");
  unit_ids.clear();
  costs.clear();
  round_genomes_.clear();
  for (Body& b : learners_) {
    for (const evo::Genome& candidate : b.learner.propose(params_)) {
      unit_ids.push_back(static_cast<std::int64_t>(round_genomes_.size()));
      costs.push_back(b.cost);
      round_genomes_.push_back(evo::encode_genome(candidate));
    }
  }
}

EvalRequest GenerationLearning::request(const WorkUnit& unit, std::uint64_t config_hash) const {
  if (unit.genome_id < 0 || static_cast<std::size_t>(unit.genome_id) >= round_genomes_.size())
    throw std::out_of_range("generation learning: no candidate " + std::to_string(unit.genome_id) +
                            " in the round");
  EvalRequest r;
  r.config_hash = config_hash;
  r.generation = generation_;
  r.genome_id = unit.genome_id;
  r.unit = unit.unit;
  r.genome = round_genomes_[static_cast<std::size_t>(unit.genome_id)];
  return r;
}

void GenerationLearning::end_iteration(const std::vector<GenomeOutcome>& outcomes) {
  if (outcomes.size() != round_genomes_.size())
    throw std::invalid_argument("generation learning: " + std::to_string(outcomes.size()) +
                                " outcomes for a round of " +
                                std::to_string(round_genomes_.size()) + " candidates");
  std::size_t k = 0;
  for (Body& b : learners_) {
    const std::size_t first = k;
    std::vector<evo::CandidateScore> scores;
    scores.reserve(static_cast<std::size_t>(lambda_));
    LearnedResult& r = results_[b.member];
    for (int c = 0; c < lambda_; ++c, ++k) {
      scores.push_back({outcomes[k].fitness, outcomes[k].status == EvalStatus::ok});
      r.wall_seconds += outcomes[k].wall_seconds;
    }
    const int taken = b.learner.tell(scores);
    if (taken >= 0) {
      const std::int64_t id = r.learned.genome_id;  // the body's, not the round-local id
      r.learned = outcomes[first + static_cast<std::size_t>(taken)];
      r.learned.genome_id = id;
      r.genome = b.learner.best();
    }
    r.evaluations = b.learner.evaluations();
    const std::vector<double>& curve = b.learner.curve();
    std::copy(curve.begin(), curve.end(), r.curve.begin());
    std::fill(r.curve.begin() + static_cast<std::ptrdiff_t>(curve.size()), r.curve.end(),
              curve.back());
  }
  round_genomes_.clear();
  ++iteration_;
}

std::vector<std::uint8_t> GenerationLearning::serialize() const {
  if (!round_genomes_.empty())
    throw std::logic_error("generation learning: serialize() with a round in flight");
  WireWriter w;
  w.u32(kLearningStateVersion);
  w.i64(generation_);
  w.i64(iterations_);
  w.i64(iteration_);
  w.i32(lambda_);
  w.u64(results_.size());
  for (const LearnedResult& r : results_) {
    write_outcome(w, r.born);
    write_outcome(w, r.learned);
    w.bytes(evo::encode_genome(r.genome));
    w.i64(r.evaluations);
    w.f64_vector(r.curve);
    w.f64(r.wall_seconds);
  }
  w.u64(learners_.size());
  for (const Body& b : learners_) {
    w.u64(b.member);
    w.f64(b.cost);
    b.learner.save(w);
  }
  return frame_message(MessageKind::learning_state, w.data());
}

GenerationLearning GenerationLearning::deserialize(std::span<const std::uint8_t> bytes,
                                                   const Config& config,
                                                   const evo::EvoParams& params,
                                                   std::int64_t generation) {
  WireReader r(unframe_message(bytes, MessageKind::learning_state), "learning state");
  const auto fail = [](const std::string& what) { throw WireError("learning state: " + what); };
  const std::uint32_t version = r.u32("layout version");
  if (version != kLearningStateVersion)
    fail("unsupported layout version " + std::to_string(version) + " (expected " +
         std::to_string(kLearningStateVersion) + ")");
  GenerationLearning l(params, r.i64("generation"));
  l.iterations_ = r.i64("iterations");
  l.iteration_ = r.i64("iteration");
  l.lambda_ = r.i32("lambda");
  const std::uint64_t members = r.u64("member count");
  if (members > r.remaining() / 64) fail("member count exceeds the message length");
  l.results_.resize(static_cast<std::size_t>(members));
  for (LearnedResult& m : l.results_) {
    m.born = read_outcome(r);
    m.learned = read_outcome(r);
    m.genome = evo::decode_genome(r.bytes("learned genome"));
    m.evaluations = r.i64("evaluations");
    m.curve = r.f64_vector("curve");
    m.wall_seconds = r.f64("wall seconds");
    if (m.curve.size() != static_cast<std::size_t>(l.iterations_) + 1)
      fail("a curve of " + std::to_string(m.curve.size()) + " points for " +
           std::to_string(l.iterations_) + " iterations");
  }
  const std::uint64_t bodies = r.u64("learner count");
  if (bodies > members) fail("more learners than members");
  for (std::uint64_t k = 0; k < bodies; ++k) {
    const std::uint64_t member = r.u64("learner member");
    const double cost = r.f64("learner cost");
    if (member >= members || (!l.learners_.empty() && member <= l.learners_.back().member))
      fail("learner members not ascending member indices");
    evo::ControllerLearner learner = evo::ControllerLearner::load(r);
    if (learner.iteration() != l.iteration_ || learner.iterations() != l.iterations_ ||
        learner.lambda() != l.lambda_)
      fail("a learner at iteration " + std::to_string(learner.iteration()) + " of " +
           std::to_string(learner.iterations()) + ", its generation at " +
           std::to_string(l.iteration_) + " of " + std::to_string(l.iterations_));
    l.learners_.push_back(Body{static_cast<std::size_t>(member), std::move(learner), cost});
  }
  r.finish();
  if (l.generation_ != generation)
    throw std::invalid_argument("learning state of generation " + std::to_string(l.generation_) +
                                ", expected " + std::to_string(generation));
  if (config.learning.method == LearningMethod::none)
    throw std::invalid_argument("learning state, but the config has no learning");
  const std::int64_t iterations =
      evo::learning_iterations(config.learning.evaluations, config.learning.population);
  if (l.iterations_ != iterations || l.lambda_ != config.learning.population)
    throw std::invalid_argument("learning state of " + std::to_string(l.iterations_) +
                                " iterations of " + std::to_string(l.lambda_) +
                                " candidates, the config has " + std::to_string(iterations) +
                                " of " + std::to_string(config.learning.population));
  if (l.iteration_ < 0 || l.finished())
    throw std::invalid_argument("learning state at iteration " + std::to_string(l.iteration_) +
                                " of " + std::to_string(l.iterations_) + ": no round left");
  return l;
}

std::vector<std::int64_t> GenerationLearning::ids() const {
  std::vector<std::int64_t> ids;
  ids.reserve(results_.size());
  for (const LearnedResult& r : results_) ids.push_back(r.born.genome_id);
  return ids;
}

double GenerationLearning::mean_improvement() const {
  if (learners_.empty()) return 0.0;
  double sum = 0.0;
  for (const Body& b : learners_)
    sum += results_[b.member].learned.fitness - results_[b.member].born.fitness;
  return sum / static_cast<double>(learners_.size());
}

double GenerationLearning::best_improvement() const {
  double best = 0.0;
  for (const Body& b : learners_)
    best = std::max(best, results_[b.member].learned.fitness - results_[b.member].born.fitness);
  return best;
}

}  // namespace softevo::master
