#include "master/learning_rounds.hpp"

#include <algorithm>
#include <stdexcept>
#include <string>
#include <utility>

namespace softevo::master {

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
