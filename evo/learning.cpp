#include "evo/learning.hpp"

#include <cmath>
#include <stdexcept>
#include <string>
#include <utility>

#include "evo/mutation.hpp"

namespace softevo::evo {

std::uint64_t learning_seed(std::int64_t run_seed, std::int64_t generation,
                            std::int64_t genome_id) {
  return derive_seed(static_cast<std::uint64_t>(run_seed), generation, genome_id, kLearningStream);
}

std::int64_t learning_iterations(std::int64_t evaluations, std::int64_t lambda) {
  if (lambda < 1 || evaluations < 1) return 0;
  return (evaluations - 1) / lambda;
}

ControllerLearner::ControllerLearner(Genome born, CandidateScore born_score,
                                     std::int64_t iterations, int lambda, std::uint64_t seed,
                                     double step_size_factor)
    : parent_(born),
      born_(std::move(born)),
      factor_(step_size_factor),
      parent_score_(born_score),
      iterations_(iterations),
      lambda_(lambda),
      rng_(seed) {
  if (!parent_.has_controller())
    throw std::invalid_argument("controller learning: the genome has no controller");
  if (iterations < 0 || lambda < 1)
    throw std::invalid_argument("controller learning: iterations " + std::to_string(iterations) +
                                " and lambda " + std::to_string(lambda) + " (need >= 0 and >= 1)");
  if (!std::isfinite(born_score.fitness))
    throw std::invalid_argument("controller learning: non-finite fitness of the born genome");
  if (!(step_size_factor > 0.0) || !std::isfinite(step_size_factor))
    throw std::invalid_argument("controller learning: step size factor must be > 0");
  for (std::vector<double>* v : vectors_of(parent_.step_sizes))
    for (double& s : *v) s *= factor_;
  curve_.push_back(parent_score_.fitness);
}

Genome ControllerLearner::best() const {
  if (!moved_) return born_;
  Genome g = parent_;
  for (std::vector<double>* v : vectors_of(g.step_sizes))
    for (double& s : *v) s /= factor_;
  return g;
}

const std::vector<Genome>& ControllerLearner::propose(const EvoParams& params) {
  if (done()) throw std::logic_error("controller learning: propose() after the last iteration");
  if (!candidates_.empty()) return candidates_;
  candidates_.reserve(static_cast<std::size_t>(lambda_));
  for (int k = 0; k < lambda_; ++k) {
    Genome child = parent_;
    mutate_controller(child, params, rng_);
    candidates_.push_back(std::move(child));
  }
  return candidates_;
}

int ControllerLearner::tell(const std::vector<CandidateScore>& scores) {
  if (candidates_.empty()) throw std::logic_error("controller learning: tell() without propose()");
  if (scores.size() != candidates_.size())
    throw std::invalid_argument("controller learning: " + std::to_string(scores.size()) +
                                " scores for " + std::to_string(candidates_.size()) +
                                " candidates");
  int best = -1;
  for (std::size_t k = 0; k < scores.size(); ++k) {
    if (!std::isfinite(scores[k].fitness))
      throw std::invalid_argument("controller learning: non-finite fitness of candidate " +
                                  std::to_string(k));
    if (!scores[k].ok) continue;
    if (best < 0 || scores[k].fitness > scores[static_cast<std::size_t>(best)].fitness)
      best = static_cast<int>(k);
  }
  // Plus selection with ties to the candidate: moving along a plateau costs nothing and lets
  // the step sizes keep adapting.
  if (best >= 0 && scores[static_cast<std::size_t>(best)].fitness >= parent_score_.fitness) {
    parent_ = std::move(candidates_[static_cast<std::size_t>(best)]);
    parent_score_ = scores[static_cast<std::size_t>(best)];
    moved_ = true;
  } else {
    best = -1;
  }
  candidates_.clear();
  ++iteration_;
  curve_.push_back(parent_score_.fitness);
  return best;
}

void ControllerLearner::save(WireWriter& w) const {
  if (!candidates_.empty())
    throw std::logic_error("controller learning: save() with candidates pending");
  w.bytes(encode_genome(parent_));
  w.bytes(encode_genome(born_));
  w.boolean(moved_);
  w.f64(factor_);
  w.f64(parent_score_.fitness);
  w.boolean(parent_score_.ok);
  w.i64(iterations_);
  w.i32(lambda_);
  for (std::uint64_t word : rng_.state()) w.u64(word);
  w.i64(iteration_);
  w.f64_vector(curve_);
}

ControllerLearner ControllerLearner::load(WireReader& r) {
  const auto fail = [](const std::string& what) {
    throw WireError("controller learning state: " + what);
  };
  ControllerLearner l;
  l.parent_ = decode_genome(r.bytes("learner parent"));
  l.born_ = decode_genome(r.bytes("learner born genome"));
  l.moved_ = r.boolean("learner moved");
  l.factor_ = r.f64("learner step size factor");
  l.parent_score_.fitness = r.f64("learner parent fitness");
  l.parent_score_.ok = r.boolean("learner parent ok");
  l.iterations_ = r.i64("learner iterations");
  l.lambda_ = r.i32("learner lambda");
  Rng::State state{};
  for (std::uint64_t& word : state) word = r.u64("learner rng state");
  try {
    l.rng_.set_state(state);
  } catch (const std::exception& e) {
    fail(std::string("rng state: ") + e.what());
  }
  l.iteration_ = r.i64("learner iteration");
  l.curve_ = r.f64_vector("learner curve");
  if (!l.parent_.has_controller() || !l.born_.has_controller()) fail("a genome without controller");
  if (!(l.factor_ > 0.0) || !std::isfinite(l.factor_) || !std::isfinite(l.parent_score_.fitness))
    fail("non-finite or non-positive numbers");
  if (l.iterations_ < 0 || l.lambda_ < 1 || l.iteration_ < 0 || l.iteration_ > l.iterations_)
    fail("iteration " + std::to_string(l.iteration_) + " of " + std::to_string(l.iterations_) +
         " with lambda " + std::to_string(l.lambda_));
  if (l.curve_.size() != static_cast<std::size_t>(l.iteration_) + 1)
    fail(std::to_string(l.curve_.size()) + " curve points after " + std::to_string(l.iteration_) +
         " iterations");
  return l;
}

}  // namespace softevo::evo
