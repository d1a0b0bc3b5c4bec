// The identities of a config: FNV-1a 64 hashes of its canonical text (common/config.hpp
// canonical_text). The config hash covers every key; the experiment hash leaves out the run
// length and the seed (run.generations, run.seed), so that runs of one experiment are
// repetitions of each other (other seeds) or extensions (more generations) of one another.
// `--resume` checks the experiment hash, so a finished run can be continued with a larger
// --generations; analysis/figures.py groups repetitions by it.
#pragma once

#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "common/config.hpp"

namespace softevo {

// FNV-1a 64 of any text: config_hash(c) == text_hash(canonical_text(c)). Hashing the stored text
// (not a re-parse) checks an archive or robot file of an older build, which knew fewer keys,
// against the hash it was written with.
std::uint64_t text_hash(const std::string& text);

// Canonical text without the lines of run.generations and run.seed. Works on text, so it also
// applies to the stored config of an archive written before the experiment hash existed.
std::string experiment_text(const std::string& canonical_config_text);
std::uint64_t experiment_hash_of_text(const std::string& canonical_config_text);
std::uint64_t experiment_hash(const Config& config);

// ("section.key", TOML value text) of every "key = value" line of a canonical text, in order.
std::vector<std::pair<std::string, std::string>> canonical_entries(const std::string& text);

// One key whose value differs between two canonical texts: "neat.pop_size", the value in each
// ("" where the text has no such key: one written by a build that knew fewer keys).
struct KeyDifference {
  std::string key;
  std::string first;
  std::string second;
};
// Every differing key of two canonical texts, in the order of `first` (then keys only in
// `second`), so a refused --resume can name all of them rather than two hashes.
std::vector<KeyDifference> config_differences(const std::string& first, const std::string& second);

}  // namespace softevo
