// Little-endian byte strings of the viewer's binary messages (view/protocol.hpp frames and the
// packed frames of view/export_html.hpp): plain values appended as the host stores them.
#pragma once

#include <bit>
#include <cstring>
#include <string>
#include <vector>

namespace softevo::view {

static_assert(std::endian::native == std::endian::little,
              "the viewer's binary layouts are little-endian and written as the host stores them");

template <class T>
void append_value(std::string& out, const T& value) {
  char bytes[sizeof(T)];
  std::memcpy(bytes, &value, sizeof(T));
  out.append(bytes, sizeof(T));
}

template <class T>
void append_values(std::string& out, const std::vector<T>& values) {
  if (values.empty()) return;
  out.append(reinterpret_cast<const char*>(values.data()), values.size() * sizeof(T));
}

}  // namespace softevo::view
