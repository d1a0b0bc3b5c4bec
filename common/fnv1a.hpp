// FNV-1a 64, the one hash behind every digest softevo stores or compares: the physics state hash
// (physics/state.cpp), the config and experiment hashes (common/config_identity.hpp) and the
// per-generation and fitness digests of run archives (io/archive_digest.cpp). It is not a
// cryptographic hash: it detects accidental change (docs/archive.md), and its value for given bytes
// is fixed forever, because archives and golden tests store it.
#pragma once

#include <cstddef>
#include <cstdint>
#include <cstring>
#include <string_view>
#include <type_traits>

namespace softevo {

class Fnv1a64 {
 public:
  static constexpr std::uint64_t kOffsetBasis = 14695981039346656037ULL;  // 0xcbf29ce484222325
  static constexpr std::uint64_t kPrime = 1099511628211ULL;               // 0x100000001b3

  void byte(std::uint8_t b) {
    hash_ ^= b;
    hash_ *= kPrime;
  }
  void bytes(const void* data, std::size_t count) {
    const auto* b = static_cast<const unsigned char*>(data);
    for (std::size_t i = 0; i < count; ++i) byte(b[i]);
  }
  void text(std::string_view s) { bytes(s.data(), s.size()); }

  // A 64-bit value as 8 bytes, least significant first, whatever the host's byte order: the
  // digests stored in archives are the same on every machine.
  void u64_le(std::uint64_t v) {
    for (int i = 0; i < 8; ++i) byte(static_cast<std::uint8_t>(v >> (8 * i)));
  }
  void f64_le(double v) {
    std::uint64_t bits = 0;
    std::memcpy(&bits, &v, sizeof bits);
    u64_le(bits);
  }

  // The object representation of a trivially copyable value, in host order (the physics state
  // hash compares runs on one machine kind at a time; x86-64 and AArch64 are both little-endian).
  template <class T>
  void object(const T& v) {
    static_assert(std::is_trivially_copyable_v<T>);
    bytes(&v, sizeof(T));
  }

  std::uint64_t value() const { return hash_; }

 private:
  std::uint64_t hash_ = kOffsetBasis;
};

inline std::uint64_t fnv1a64(std::string_view text) {
  Fnv1a64 h;
  h.text(text);
  return h.value();
}

}  // namespace softevo
