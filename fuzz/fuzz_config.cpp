// libFuzzer target: the config parser (common/config) on arbitrary TOML text and --set
// overrides. Input: the TOML text, then optionally a NUL byte and one override per line. Every
// input must either give a Config or raise ConfigError; a Config must survive its canonical text.
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "common/config.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string input(reinterpret_cast<const char*>(data), size);
  const std::size_t nul = input.find('\0');
  const std::string text = input.substr(0, nul);
  std::vector<std::string> overrides;
  if (nul != std::string::npos) {
    std::size_t start = nul + 1;
    while (start <= input.size()) {
      const std::size_t end = input.find('\n', start);
      overrides.push_back(input.substr(start, end == std::string::npos ? end : end - start));
      if (end == std::string::npos) break;
      start = end + 1;
    }
  }
  try {
    const softevo::Config config = softevo::parse_config(text, "fuzz.toml", overrides);
    const std::string canonical = softevo::canonical_text(config);
    if (softevo::canonical_text(softevo::parse_config(canonical, "canonical")) != canonical)
      __builtin_trap();
  } catch (const softevo::ConfigError&) {
  }
  return 0;
}
