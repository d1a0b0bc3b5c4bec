// Wire format: messages are bytes with a fixed header, then fields written one by one in
// little-endian order (docs/architecture.md §4). Never memcpy a struct: every field is
// spelled out, so the bytes are the same on every platform and compiler.
//
// Header (16 bytes): magic u32 = 0x4F564553 ("SEVO" read as little-endian bytes 'S','E','V','O'),
// format version u16, kind u16, payload length u64. The payload follows.
#pragma once

#include <cstdint>
#include <span>
#include <stdexcept>
#include <string>
#include <vector>

#include "common/eval_types.hpp"

namespace softevo {

inline constexpr std::uint32_t kWireMagic = 0x4F564553;  // bytes "SEVO"
inline constexpr std::uint16_t kWireVersion = 1;
inline constexpr std::size_t kWireHeaderSize = 16;
// Largest payload we accept: guards against a corrupt length allocating gigabytes.
inline constexpr std::uint64_t kWireMaxPayload = 1ULL << 30;

enum class MessageKind : std::uint16_t {
  eval_request = 1,
  eval_result = 2,
  shutdown = 3,
  genome = 4,
  population = 5,
  // 6 was config_text, never sent (the config travels as a broadcast, mpi/protocol.hpp); a new
  // kind takes 7 so that no build reads another's 6 differently.
  // The controller learning of a generation in flight, between two rounds (a run's checkpoint,
  // master/learning_rounds.hpp); never sent.
  learning_state = 7,
  // The state of a search strategy other than NEAT (evo/search_strategy.hpp: its name, then its
  // own payload); a run's checkpoint, never sent. NEAT's state stays a `population` message.
  strategy_state = 8,
};

// Malformed, truncated or oversized input: the message names the field and the offsets.
class WireError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

class WireWriter {
 public:
  void u8(std::uint8_t v);
  void u16(std::uint16_t v);
  void u32(std::uint32_t v);
  void u64(std::uint64_t v);
  void i32(std::int32_t v) { u32(static_cast<std::uint32_t>(v)); }
  void i64(std::int64_t v) { u64(static_cast<std::uint64_t>(v)); }
  void f64(double v);  // IEEE-754 bits, little-endian
  void boolean(bool v) { u8(v ? 1 : 0); }
  void string(const std::string& s);              // u64 length + bytes
  void bytes(std::span<const std::uint8_t> b);    // u64 length + bytes
  void f64_vector(const std::vector<double>& v);  // u64 count + values
  const std::vector<std::uint8_t>& data() const { return data_; }
  std::vector<std::uint8_t> take() { return std::move(data_); }

 private:
  std::vector<std::uint8_t> data_;
};

class WireReader {
 public:
  // `what` names the message in error texts ("eval request", "genome", ...).
  WireReader(std::span<const std::uint8_t> data, std::string what);
  std::uint8_t u8(const char* field);
  std::uint16_t u16(const char* field);
  std::uint32_t u32(const char* field);
  std::uint64_t u64(const char* field);
  std::int32_t i32(const char* field) { return static_cast<std::int32_t>(u32(field)); }
  std::int64_t i64(const char* field) { return static_cast<std::int64_t>(u64(field)); }
  double f64(const char* field);
  bool boolean(const char* field);
  std::string string(const char* field);
  std::vector<std::uint8_t> bytes(const char* field);
  std::vector<double> f64_vector(const char* field);
  // Throws if bytes remain: an oversized message is as wrong as a truncated one.
  void finish() const;
  std::size_t remaining() const { return data_.size() - offset_; }

 private:
  void need(std::size_t n, const char* field) const;
  std::span<const std::uint8_t> data_;
  std::size_t offset_ = 0;
  std::string what_;
};

// A status byte as EvalStatus; throws WireError naming `what` for a value that is none.
EvalStatus checked_status(std::uint8_t value, const char* what);
// One unit's score inside a message (fitness, status, values), as an eval result carries each
// of its components; the reader throws WireError naming `what` for an unknown status.
void write_unit_fitness(WireWriter& w, const UnitFitness& unit);
UnitFitness read_unit_fitness(WireReader& r, const char* what);

// Frame a payload with the header / check and strip the header (kind must match).
std::vector<std::uint8_t> frame_message(MessageKind kind, std::span<const std::uint8_t> payload);
std::span<const std::uint8_t> unframe_message(std::span<const std::uint8_t> message,
                                              MessageKind expected_kind);
MessageKind peek_message_kind(std::span<const std::uint8_t> message);

// Work units and results on the wire (framed, ready to send).
std::vector<std::uint8_t> encode_eval_request(const EvalRequest& request);
EvalRequest decode_eval_request(std::span<const std::uint8_t> message);
std::vector<std::uint8_t> encode_eval_result(const EvalResult& result);
EvalResult decode_eval_result(std::span<const std::uint8_t> message);

// The message that ends a worker: the exit code every rank of the run returns (payload: i32).
std::vector<std::uint8_t> encode_shutdown(std::int32_t exit_code);
std::int32_t decode_shutdown(std::span<const std::uint8_t> message);

}  // namespace softevo
