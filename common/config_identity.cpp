// The identities of a config (common/config_identity.hpp): hashes of its canonical text.
#include "common/config_identity.hpp"

#include <cstdio>
#include <sstream>
#include <string_view>

#include "common/fnv1a.hpp"

namespace softevo {

std::uint64_t text_hash(const std::string& text) {
  return fnv1a64(text);
}

std::uint64_t config_hash(const Config& config) {
  return text_hash(canonical_text(config));
}

std::string experiment_text(const std::string& canonical_config_text) {
  // Canonical text has one "key = value" line per key under its "[section]" line; the lines of
  // run.generations and run.seed are left out.
  std::string out;
  std::string section;
  std::size_t begin = 0;
  while (begin < canonical_config_text.size()) {
    std::size_t end = canonical_config_text.find('\n', begin);
    end = end == std::string::npos ? canonical_config_text.size() : end + 1;
    const std::string_view line(canonical_config_text.data() + begin, end - begin);
    if (line.starts_with("[")) section = std::string(line.substr(0, line.find(']') + 1));
    const bool run_identity_only =
        section == "[run]" && (line.starts_with("generations = ") || line.starts_with("seed = "));
    if (!run_identity_only) out.append(line);
    begin = end;
  }
  return out;
}

std::vector<std::pair<std::string, std::string>> canonical_entries(const std::string& text) {
  std::vector<std::pair<std::string, std::string>> entries;
  std::string section;
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);) {
    if (line.starts_with("[")) {
      section = line.substr(1, line.find(']') - 1);
      continue;
    }
    const std::size_t eq = line.find(" = ");
    if (eq == std::string::npos) continue;
    entries.emplace_back(section + "." + line.substr(0, eq), line.substr(eq + 3));
  }
  return entries;
}

std::vector<KeyDifference> config_differences(const std::string& first, const std::string& second) {
  const auto a = canonical_entries(first);
  const auto b = canonical_entries(second);
  const auto find = [](const auto& entries, const std::string& key) -> const std::string* {
    for (const auto& [k, v] : entries)
      if (k == key) return &v;
    return nullptr;
  };
  std::vector<KeyDifference> out;
  for (const auto& [key, value] : a) {
    const std::string* other = find(b, key);
    if (other == nullptr || *other != value) out.push_back({key, value, other ? *other : ""});
  }
  for (const auto& [key, value] : b)
    if (find(a, key) == nullptr) out.push_back({key, "", value});
  return out;
}

std::uint64_t experiment_hash_of_text(const std::string& canonical_config_text) {
  return text_hash(experiment_text(canonical_config_text));
}

std::uint64_t experiment_hash(const Config& config) {
  return experiment_hash_of_text(canonical_text(config));
}

std::string hash_hex(std::uint64_t hash) {
  char buf[17];
  std::snprintf(buf, sizeof buf, "%016llx", static_cast<unsigned long long>(hash));
  return buf;
}

}  // namespace softevo
