// Config choices as types: each string-valued config key with a fixed set of values (integrator,
// terrain kind, ...) is an enum, parsed once at the config boundary (common/config.cpp) and
// compared as an enum everywhere else. Other enums with names (statuses, SIMD widths, CPPN
// activations) use the same: one table of names instead of a switch per enum. A choice enum
// declares its config names, in enum order, by specialising ChoiceNames; to_string and
// choice_from_string work for every such enum.
#pragma once

#include <array>
#include <cstddef>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

namespace softevo {

template <class E>
struct ChoiceNames;  // specialise: static constexpr std::array<const char*, N> names = {...};

template <class E>
concept ConfigChoice = requires {
  ChoiceNames<E>::names;
};

// A value outside the enum (a corrupt byte cast to it) is "unknown", never read past the names.
template <ConfigChoice E>
constexpr const char* to_string(E value) {
  const auto index = static_cast<std::size_t>(value);
  return index < ChoiceNames<E>::names.size() ? ChoiceNames<E>::names[index] : "unknown";
}

template <ConfigChoice E>
constexpr std::optional<E> choice_from_string(std::string_view name) {
  const auto& names = ChoiceNames<E>::names;
  for (std::size_t i = 0; i < names.size(); ++i)
    if (name == names[i]) return static_cast<E>(i);
  return std::nullopt;
}

// Every config name of E, in enum order (for option checks and messages).
template <ConfigChoice E>
std::vector<std::string> choice_names() {
  return {ChoiceNames<E>::names.begin(), ChoiceNames<E>::names.end()};
}

// `name` as a choice of E, for inputs outside a config file (a command option, a Python
// argument); std::invalid_argument naming `what` and the allowed names otherwise.
template <ConfigChoice E>
E parse_choice(std::string_view name, std::string_view what) {
  if (const auto value = choice_from_string<E>(name)) return *value;
  std::string allowed;
  for (const char* n : ChoiceNames<E>::names)
    allowed += (allowed.empty() ? "" : ", ") + std::string(n);
  throw std::invalid_argument(std::string(what) + ": '" + std::string(name) + "' is not one of " +
                              allowed);
}

}  // namespace softevo
