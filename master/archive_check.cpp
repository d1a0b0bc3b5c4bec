#include "master/archive_check.hpp"

#include <algorithm>
#include <cstring>
#include <exception>
#include <optional>

#include "common/config.hpp"
#include "common/config_identity.hpp"
#include "common/eval_types.hpp"
#include "evo/search_strategy.hpp"
#include "master/learning_rounds.hpp"
#include "tasks/task.hpp"

namespace softevo::master {
namespace {

bool same_bits(double a, double b) {
  return std::memcmp(&a, &b, sizeof a) == 0;
}

constexpr std::uint8_t kLargestStatus = static_cast<std::uint8_t>(EvalStatus::invalid_body);

// The per-generation rules that need no stored digest; "" = fine, else what is wrong.
std::string rule_violation(const io::GenerationRecord& r,
                           const std::optional<io::StatsRow>& stats_row, std::string* check) {
  for (std::size_t i = 0; i < r.size(); ++i) {
    if (r.status[i] > kLargestStatus) {
      *check = "status";
      return "id " + std::to_string(r.id[i]) + " has status " + std::to_string(r.status[i]) +
             ", not an EvalStatus";
    }
    if (r.status[i] != 0 && r.fitness[i] != 0.0) {
      *check = "status";
      return "id " + std::to_string(r.id[i]) + " has status " + std::to_string(r.status[i]) +
             " (not ok) but fitness " + std::to_string(r.fitness[i]) +
             " (a failed evaluation scores 0)";
    }
  }
  const io::FitnessStats s = io::fitness_stats(r.fitness);
  if (!same_bits(s.best, r.best) || !same_bits(s.mean, r.mean) || !same_bits(s.sd, r.sd)) {
    *check = "statistics";
    return "the fitness column gives best/mean/sd " + std::to_string(s.best) + "/" +
           std::to_string(s.mean) + "/" + std::to_string(s.sd) + ", the group attributes say " +
           std::to_string(r.best) + "/" + std::to_string(r.mean) + "/" + std::to_string(r.sd);
  }
  if (stats_row) {
    const io::StatsRow& row = *stats_row;
    if (row.generation != static_cast<double>(r.generation) || !same_bits(row.best, r.best) ||
        !same_bits(row.mean, r.mean) || !same_bits(row.sd, r.sd) ||
        row.species_count != static_cast<double>(r.species_count)) {
      *check = "stats";
      return "/stats row " + std::to_string(r.generation) + " disagrees with the group";
    }
  }
  return "";
}

}  // namespace

std::string ArchiveCheck::describe(const std::string& path) const {
  std::string out;
  for (const ArchiveProblem& p : problems) {
    out += path + ": ";
    if (p.generation >= 0) out += "generation " + std::to_string(p.generation) + ": ";
    out += p.check + ": " + p.message + "\n";
  }
  return out;
}

ArchiveCheck check_archive(const io::Archive& archive) {
  ArchiveCheck c;
  const auto problem = [&](std::int64_t g, const char* check, const std::string& message) {
    c.problems.push_back(ArchiveProblem{g, check, message});
  };
  io::RunInfo info;
  try {
    info = archive.info();
  } catch (const std::exception& e) {
    problem(-1, "attributes", e.what());
    return c;
  }

  std::optional<Config> config;
  try {
    const std::string text = archive.config_text();
    if (hash_hex(text_hash(text)) != info.config_hash)
      problem(-1, "config",
              "/config hashes to " + hash_hex(text_hash(text)) + ", the config_hash attribute is " +
                  info.config_hash + " (the text was changed after the run started)");
    else
      config.emplace(parse_config(text, archive.path() + ":/config"));
  } catch (const std::exception& e) {
    problem(-1, "config", std::string("/config is unusable: ") + e.what());
  }

  std::vector<std::int64_t> groups;
  try {
    groups = archive.generations();
  } catch (const std::exception& e) {
    problem(-1, "generations_done", e.what());
  }
  bool contiguous = true;
  for (std::size_t i = 0; i < groups.size(); ++i)
    contiguous = contiguous && groups[i] == static_cast<std::int64_t>(i);
  if (!contiguous || static_cast<std::int64_t>(groups.size()) != info.generations_done)
    problem(-1, "generations_done",
            "generations_done = " + std::to_string(info.generations_done) + " but " +
                std::to_string(groups.size()) + " generation groups" +
                (contiguous ? std::string() : std::string(" (not numbered 0, 1, ...)")));

  std::vector<io::StatsRow> stats;
  try {
    stats = archive.stats();
    if (static_cast<std::int64_t>(stats.size()) != info.generations_done)
      problem(-1, "stats",
              "/stats has " + std::to_string(stats.size()) +
                  " rows, generations_done = " + std::to_string(info.generations_done));
  } catch (const std::exception& e) {
    problem(-1, "stats", e.what());
  }

  bool prefix_good = true;
  for (std::size_t i = 0; i < groups.size(); ++i) {
    const std::int64_t g = groups[i];
    ++c.generations_checked;
    bool good = g == static_cast<std::int64_t>(i);
    io::GenerationRecord r;
    try {
      r = archive.generation(g);
    } catch (const std::exception& e) {
      const std::string m = e.what();
      problem(g, m.find("sorted") != std::string::npos ? "ids" : "readable", m);
      prefix_good = false;
      continue;
    }
    try {
      if (const auto stored = archive.stored_generation_digest(g)) {
        ++c.generations_with_digest;
        const std::uint64_t now = io::generation_digest(r);
        if (*stored != now) {
          problem(g, "digest",
                  "stored digest " + hash_hex(*stored) + ", recomputed " + hash_hex(now) +
                      " (the group's data changed after it was written)");
          good = false;
        }
      }
    } catch (const std::exception& e) {
      problem(g, "digest", e.what());
      good = false;
    }
    std::string check;
    const std::optional<io::StatsRow> row =
        i < stats.size() ? std::optional<io::StatsRow>(stats[i]) : std::nullopt;
    const std::string violation = rule_violation(r, row, &check);
    if (!violation.empty()) {
      problem(g, check.c_str(), violation);
      good = false;
    }
    prefix_good = prefix_good && good;
    if (prefix_good) c.consistent_generations = g + 1;
  }

  try {
    const std::optional<io::Checkpoint> cp = archive.checkpoint();
    if (info.generations_done > 0 && !cp) {
      problem(-1, "checkpoint", "no /checkpoint although generations_done > 0");
    } else if (cp) {
      if (cp->generation != info.generations_done) {
        problem(-1, "checkpoint",
                "/checkpoint is for generation " + std::to_string(cp->generation) +
                    ", generations_done = " + std::to_string(info.generations_done));
      } else if (config) {
        const std::unique_ptr<evo::SearchStrategy> p = evo::restore_strategy(
            cp->population, *config, tasks::make_task(*config)->controller_inputs());
        if (p->generation() != cp->generation)
          problem(-1, "checkpoint",
                  "/checkpoint population is at generation " + std::to_string(p->generation()) +
                      ", its attribute says " + std::to_string(cp->generation));
        else if (!cp->learning.empty())  // throws as the resume would
          GenerationLearning::deserialize(cp->learning, *config, p->params(), cp->generation);
      }
    }
  } catch (const std::exception& e) {
    problem(-1, "checkpoint", std::string("/checkpoint is unusable: ") + e.what());
  }
  return c;
}

}  // namespace softevo::master
