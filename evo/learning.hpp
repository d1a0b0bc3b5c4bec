// Controller learning of one body (docs/model.md §8.11, thesis 5.3.6): a (1+lambda) evolution
// strategy on the controller sub-genome, body (CPPN) fixed. Its variation operator is the
// genome's own self-adaptive mutation (mutate_controller, §8.7): every candidate is the parent
// with its per-gene step sizes mutated first and its values then moved by them, so the step
// sizes the strategy ends with are those the genome carries (and, under Lamarckian inheritance,
// passes on). Selection is elitist: the best ok candidate of an iteration (highest fitness,
// the lowest candidate index on ties) replaces the parent when its fitness is at least the
// parent's, so the best-so-far curve never falls.
//
// Pure: no physics, no MPI, no I/O. All randomness comes from the learner's own Rng, seeded from
// the run's streams (learning_seed), so one body's learning is a function of (run seed,
// generation, genome id, genome, config) and of the candidates' evaluations, which are
// themselves pure: the same on any rank count and after any --resume.
#pragma once

#include <cstdint>
#include <vector>

#include "common/rng.hpp"
#include "common/wire.hpp"
#include "evo/genome.hpp"

namespace softevo::evo {

// derive_seed's last id for the learning stream (-1 is "none", the terrain's convention), so
// the stream differs from every other stream of the run.
inline constexpr std::int64_t kLearningStream = -2;
// The Rng seed of the learning of genome `genome_id`, new in `generation`.
std::uint64_t learning_seed(std::int64_t run_seed, std::int64_t generation, std::int64_t genome_id);

// Strategy iterations of a body for a budget of `evaluations` per body (the inherited
// controller's evaluation included) and `lambda` candidates per iteration:
// (evaluations - 1) / lambda, rounded down.
std::int64_t learning_iterations(std::int64_t evaluations, std::int64_t lambda);

// The evaluation of one candidate as selection sees it.
struct CandidateScore {
  double fitness = 0.0;
  bool ok = false;  // status ok; a killed or failed candidate never becomes the parent
};

class ControllerLearner {
 public:
  // `born`: the genome as created (it must carry a controller); `born_score`: its evaluation,
  // the first of the budget. The strategy starts from the genome's step sizes times
  // `step_size_factor` (learning.step_size_factor): the genome's are those of evolution, whose
  // single mutation per generation may be large; a local search needs smaller steps. Throws
  // std::invalid_argument for a genome without controller, iterations < 0, lambda < 1 or a
  // factor that is not positive and finite.
  ControllerLearner(Genome born, CandidateScore born_score, std::int64_t iterations, int lambda,
                    std::uint64_t seed, double step_size_factor = 1.0);

  bool done() const { return iteration_ >= iterations_; }
  std::int64_t iteration() const { return iteration_; }  // iterations completed
  std::int64_t iterations() const { return iterations_; }
  int lambda() const { return lambda_; }

  // The next iteration's lambda candidates: candidate k = the parent, then mutate_controller
  // with the learner's Rng, for k = 0, 1, ..., lambda - 1 in this order. Calling it again before
  // tell() returns the same candidates. Requires !done().
  const std::vector<Genome>& propose(const EvoParams& params);
  // Their scores in candidate order: selection (see the file comment), iteration += 1, one
  // point more on the curve. Returns the index of the candidate that became the parent, -1 if
  // the parent stays. Throws std::logic_error without a pending propose() and
  // std::invalid_argument for a wrong count or a non-finite fitness.
  int tell(const std::vector<CandidateScore>& scores);

  // The learned genome (the born one while no candidate was taken): the parent's controller
  // values, and its adapted step sizes divided by the factor again (in the genome's units, so
  // Lamarckian inheritance hands evolution step sizes of its own scale).
  Genome best() const;
  const CandidateScore& best_score() const { return parent_score_; }
  // Evaluations spent: 1 + lambda per completed iteration.
  std::int64_t evaluations() const { return 1 + iteration_ * lambda_; }
  // Best fitness so far after the born evaluation and after every completed iteration.
  const std::vector<double>& curve() const { return curve_; }

  // The strategy's whole state between iterations, generator included, for a run's checkpoint
  // within a learning generation (master/learning_rounds.hpp): a loaded copy proposes and
  // selects exactly as the saved one would have. Throws std::logic_error while candidates are
  // pending (proposed, not yet told): they are a function of the saved state.
  void save(WireWriter& w) const;
  // Throws WireError on malformed or inconsistent bytes.
  static ControllerLearner load(WireReader& r);

 private:
  ControllerLearner() = default;  // load() fills every field
  Genome parent_;                 // step sizes in the strategy's units (x factor)
  Genome born_;                   // kept to return it bit for bit while no candidate was taken
  bool moved_ = false;
  double factor_ = 1.0;
  CandidateScore parent_score_;
  std::int64_t iterations_ = 0;
  int lambda_ = 1;
  Rng rng_;
  std::int64_t iteration_ = 0;
  std::vector<Genome> candidates_;  // pending: proposed, not yet told
  std::vector<double> curve_;
};

}  // namespace softevo::evo
