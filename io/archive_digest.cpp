// The run archive's digests (docs/archive.md "Identity and digests"): per generation, of the
// fitness values, and of the whole content; equal digests are how runs are compared across builds.
#include <cstdint>
#include <string>
#include <vector>

#include "common/fnv1a.hpp"
#include "io/archive.hpp"
#include "io/archive_internal.hpp"
#include "io/h5.hpp"

namespace softevo::io {
namespace {
using namespace detail;

// ---- digests: FNV-1a 64 (common/fnv1a.hpp), values little-endian, containers length-first ----
class Fnv {
 public:
  void byte(std::uint8_t b) { h_.byte(b); }
  void u64(std::uint64_t v) { h_.u64_le(v); }
  void i64(std::int64_t v) { u64(static_cast<std::uint64_t>(v)); }
  void f64(double v) { h_.f64_le(v); }
  void bytes(const std::vector<std::uint8_t>& b) {
    u64(b.size());
    h_.bytes(b.data(), b.size());
  }
  void str(const std::string& s) {
    u64(s.size());
    h_.text(s);
  }
  std::uint64_t value() const { return h_.value(); }

 private:
  Fnv1a64 h_;
};

}  // namespace

namespace {

// The deterministic part of one generation, in content_digest's order (which must not change:
// equal digests across builds are how runs are compared).
void hash_generation_results(Fnv& h, const GenerationRecord& r) {
  h.i64(r.generation);
  h.u64(r.size());
  h.i64(r.units);
  // Named columns are part of the content; an archive without names (the legacy six) keeps
  // the digest it always had.
  if (r.component_columns != legacy_component_columns())
    for (const std::string& c : r.component_columns) h.str(c);
  for (std::size_t i = 0; i < r.size(); ++i) {
    h.i64(r.id[i]);
    h.i64(r.parent1[i]);
    h.i64(r.parent2[i]);
    h.i64(r.species[i]);
    h.byte(r.status[i]);
    h.f64(r.fitness[i]);
    h.i64(r.voxels[i]);
    h.i64(r.chambers[i]);
    h.bytes(r.genome[i]);
  }
  for (double c : r.components) h.f64(c);
  // Only a run with controller learning hashes its columns: every other digest is unchanged.
  if (r.has_learning()) {
    h.i64(r.learning_points);
    for (std::size_t i = 0; i < r.size(); ++i) {
      h.f64(r.fitness_before[i]);
      h.i64(r.learn_evaluations[i]);
      h.bytes(r.learned_genome[i]);
    }
    for (double c : r.learning_curve) h.f64(c);
  }
  // Only a strategy other than NEAT hashes its group: every NEAT digest is unchanged.
  if (!r.strategy.empty()) {
    h.str(r.strategy.strategy);
    for (const StrategyTable* t : {&r.strategy.rows, &r.strategy.map}) {
      h.u64(t->columns.size());
      for (const std::string& c : t->columns) h.str(c);
      h.u64(t->values.size());
      for (double v : t->values) h.f64(v);
    }
    for (const auto& [name, value] : r.strategy.metrics) {
      h.str(name);
      h.f64(value);
    }
  }
  h.f64(r.best);
  h.f64(r.mean);
  h.f64(r.sd);
  h.i64(r.species_count);
  h.i64(r.evaluations);
}

}  // namespace

std::uint64_t generation_digest(const GenerationRecord& r) {
  Fnv h;
  hash_generation_results(h, r);
  for (std::size_t i = 0; i < r.size(); ++i) {
    h.f64(r.wall_seconds[i]);
    h.i64(r.worker_rank[i]);
  }
  h.f64(r.eval_wall_seconds);
  // Only a generation that reused a result hashes the column, so every digest stored before it
  // existed (and of a generation without reuse) is unchanged.
  if (std::any_of(r.reused_from.begin(), r.reused_from.end(),
                  [](std::int64_t from) { return from != kNotReused; }))
    for (std::int64_t from : r.reused_from) h.i64(from);
  return h.value();
}

std::optional<std::uint64_t> Archive::stored_generation_digest(std::int64_t gen) const {
  return archive_errors([&]() -> std::optional<std::uint64_t> {
    const std::string name = "generations/" + generation_group_name(gen);
    require_segment(name);
    const h5::Group g = file_->open_group(name);
    if (!g.has_attribute("digest")) return std::nullopt;
    const std::string text = g.read_string_attribute("digest", kStringBytes);
    char* end = nullptr;
    const unsigned long long v = std::strtoull(text.c_str(), &end, 16);
    if (text.size() != 16 || end != text.c_str() + text.size())
      throw ArchiveError(path_ + ": /" + name + ": attribute digest \"" + text +
                         "\" is not 16 hex digits");
    return v;
  });
}

std::uint64_t fitness_digest(const Archive& archive) {
  Fnv h;
  for (std::int64_t gen : archive.generations()) {
    const GenerationRecord r = archive.generation(gen);
    for (std::size_t i = 0; i < r.size(); ++i) {
      h.i64(gen);
      h.i64(r.id[i]);
      h.byte(r.status[i]);
      h.f64(r.fitness[i]);
    }
  }
  return h.value();
}

std::uint64_t content_digest(const Archive& archive) {
  Fnv h;
  const RunInfo info = archive.info();
  h.str(info.format);
  h.i64(info.seed);
  h.str(info.config_hash);
  h.str(info.experiment);
  h.str(to_string(info.state));
  h.i64(info.generations_done);
  h.str(archive.config_text());
  for (std::int64_t gen : archive.generations()) {
    hash_generation_results(h, archive.generation(gen));
  }
  for (const StatsRow& s : archive.stats()) {
    h.f64(s.generation);
    h.f64(s.best);
    h.f64(s.mean);
    h.f64(s.sd);
    h.f64(s.species_count);
  }
  if (const auto c = archive.checkpoint()) {
    h.i64(c->generation);
    h.bytes(c->population);
  }
  return h.value();
}

}  // namespace softevo::io