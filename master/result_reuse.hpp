// No evaluation twice: an evaluation is a pure function of (config, genome bytes, work unit)
// (worker/evaluate.hpp), so a member whose genome bytes equal those of a genome already
// evaluated under the run's config takes that result instead of being simulated again. This
// covers the elites carried into the next generation, children that are unmutated copies of a
// parent, and exact duplicates within a generation. The archive marks such a row with the id
// it reuses (io/archive.hpp `reused_from`); its fitness, status, body size and components are
// the bits the evaluation gave, so fitness_digest and content_digest are those of a run that
// evaluated everything.
//
// What is remembered is the latest archived generation (every parent and elite of the next one
// is in it), so a --resume rebuilds exactly what the uninterrupted run had: remember() of the
// archive's last generation. Only results that are a function of the inputs alone are reused:
// not `failed` (a worker-side exception, e.g. out of memory) nor `timeout` (the wall clock).
#pragma once

#include <cstdint>
#include <span>
#include <string>
#include <unordered_map>
#include <vector>

#include "common/config.hpp"
#include "common/eval_types.hpp"
#include "io/archive.hpp"

namespace softevo::master {

// The archived outcome of one evaluated genome.
struct ReusableResult {
  std::int64_t origin_id = 0;  // id of the row that was really evaluated
  std::uint8_t status = 0;     // EvalStatus
  double fitness = 0.0;
  std::int32_t voxels = 0;
  std::int32_t chambers = 0;
  std::vector<double> components;  // the row's [units][component columns]
  // Controller learning (io::GenerationRecord): empty learned_genome = the run does not learn.
  double fitness_before = 0.0;
  std::int64_t learn_evaluations = 0;
  std::vector<std::uint8_t> learned_genome;
  std::vector<double> learning_curve;
};

// Whether a result with `status` is the same whenever the genome is evaluated.
bool reusable(EvalStatus status);

class ResultMemory {
 public:
  // Forgets everything, then remembers the reusable rows of `record` (an archived generation).
  // A learned row is found by its genome and by its learned genome: an elite that inherited
  // the learned controller (Lamarckian) keeps the learned result, it does not learn again.
  void remember(const io::GenerationRecord& record);
  // The remembered result of `genome` (bytes compared exactly), nullptr if none.
  const ReusableResult* find(std::span<const std::uint8_t> genome) const;
  std::size_t size() const { return by_genome_.size(); }

 private:
  std::unordered_map<std::string, ReusableResult> by_genome_;
};

// Where one member's result comes from.
struct ResultSource {
  enum class Kind { evaluated, earlier_generation, same_generation };
  Kind kind = Kind::evaluated;
  const ReusableResult* earlier = nullptr;  // earlier_generation
  std::size_t member = 0;                   // same_generation: the member that is evaluated
  std::int64_t origin_id = io::kNotReused;  // the id reused (reused_from), kNotReused if none
};

struct ReusePlan {
  std::vector<std::size_t> evaluate;  // members to evaluate, in member order
  std::vector<ResultSource> source;   // per member
  std::size_t reused() const { return source.size() - evaluate.size(); }
};

// Which equal genomes may share a result. An evaluation is a function of the genome bytes only
// where its ground is (TerrainConfig::ground_varies_with_*): a ground resampled per generation
// differs from the previous generation's, so an elite is evaluated again on the new one; a
// ground per evaluation differs between any two genome ids, so no two members share a result.
struct ReuseScope {
  bool earlier_generations = true;  // a genome of the remembered generation
  bool same_generation = true;      // an equal genome with a lower id in this generation
};
ReuseScope reuse_scope(const TerrainConfig& terrain);

// The plan of one generation: `ids` and `genomes` (encoded) in member order. Of several members
// with equal bytes that `memory` does not know, the one with the lowest id is evaluated and the
// others reuse it. `memory` = nullptr: every member is evaluated. `scope` limits both kinds.
ReusePlan plan_reuse(const std::vector<std::int64_t>& ids,
                     const std::vector<std::vector<std::uint8_t>>& genomes,
                     const ResultMemory* memory, ReuseScope scope = {});

}  // namespace softevo::master
