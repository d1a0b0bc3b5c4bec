// Numbers as people read them back: the shortest text that parses to the same double, as Python's
// repr() and the JSON outputs print it (5.839715928275743 where %.17g gives 5.8397159282757434;
// issue 39 asked for one form everywhere).
#pragma once

#include <charconv>
#include <string>

namespace softevo {

inline std::string round_trip(double v) {
  char text[32];  // the longest double, -2.2250738585072014e-308, takes 24
  const auto end = std::to_chars(text, text + sizeof text, v).ptr;
  return std::string(text, end);
}

}  // namespace softevo
