#include "common/wire.hpp"

#include <bit>

namespace softevo {

void WireWriter::u8(std::uint8_t v) {
  data_.push_back(v);
}
void WireWriter::u16(std::uint16_t v) {
  for (int i = 0; i < 2; ++i) data_.push_back(static_cast<std::uint8_t>(v >> (8 * i)));
}
void WireWriter::u32(std::uint32_t v) {
  for (int i = 0; i < 4; ++i) data_.push_back(static_cast<std::uint8_t>(v >> (8 * i)));
}
void WireWriter::u64(std::uint64_t v) {
  for (int i = 0; i < 8; ++i) data_.push_back(static_cast<std::uint8_t>(v >> (8 * i)));
}
void WireWriter::f64(double v) {
  u64(std::bit_cast<std::uint64_t>(v));
}
void WireWriter::string(const std::string& s) {
  u64(s.size());
  data_.insert(data_.end(), s.begin(), s.end());
}
void WireWriter::bytes(std::span<const std::uint8_t> b) {
  u64(b.size());
  data_.insert(data_.end(), b.begin(), b.end());
}
void WireWriter::f64_vector(const std::vector<double>& v) {
  u64(v.size());
  for (double x : v) f64(x);
}

WireReader::WireReader(std::span<const std::uint8_t> data, std::string what)
    : data_(data), what_(std::move(what)) {}

void WireReader::need(std::size_t n, const char* field) const {
  if (n > data_.size() - offset_) {
    throw WireError(what_ + ": truncated at field '" + field + "': need " + std::to_string(n) +
                    " bytes at offset " + std::to_string(offset_) + ", only " +
                    std::to_string(data_.size() - offset_) + " left");
  }
}

std::uint8_t WireReader::u8(const char* field) {
  need(1, field);
  return data_[offset_++];
}
std::uint16_t WireReader::u16(const char* field) {
  need(2, field);
  std::uint16_t v = 0;
  for (int i = 0; i < 2; ++i) v |= static_cast<std::uint16_t>(data_[offset_ + i]) << (8 * i);
  offset_ += 2;
  return v;
}
std::uint32_t WireReader::u32(const char* field) {
  need(4, field);
  std::uint32_t v = 0;
  for (int i = 0; i < 4; ++i) v |= static_cast<std::uint32_t>(data_[offset_ + i]) << (8 * i);
  offset_ += 4;
  return v;
}
std::uint64_t WireReader::u64(const char* field) {
  need(8, field);
  std::uint64_t v = 0;
  for (int i = 0; i < 8; ++i) v |= static_cast<std::uint64_t>(data_[offset_ + i]) << (8 * i);
  offset_ += 8;
  return v;
}
double WireReader::f64(const char* field) {
  return std::bit_cast<double>(u64(field));
}
bool WireReader::boolean(const char* field) {
  const std::uint8_t v = u8(field);
  if (v > 1) {
    throw WireError(what_ + ": field '" + field + "' is a boolean but holds " + std::to_string(v));
  }
  return v == 1;
}
std::string WireReader::string(const char* field) {
  const std::uint64_t n = u64(field);
  need(n, field);
  std::string s(reinterpret_cast<const char*>(data_.data() + offset_), n);
  offset_ += n;
  return s;
}
std::vector<std::uint8_t> WireReader::bytes(const char* field) {
  const std::uint64_t n = u64(field);
  need(n, field);
  std::vector<std::uint8_t> b(data_.begin() + offset_, data_.begin() + offset_ + n);
  offset_ += n;
  return b;
}
std::vector<double> WireReader::f64_vector(const char* field) {
  const std::uint64_t n = u64(field);
  if (n > remaining() / 8) {
    throw WireError(what_ + ": truncated at field '" + field + "': " + std::to_string(n) +
                    " doubles announced, only " + std::to_string(remaining()) + " bytes left");
  }
  std::vector<double> v(n);
  for (auto& x : v) x = f64(field);
  return v;
}
void WireReader::finish() const {
  if (offset_ != data_.size()) {
    throw WireError(what_ + ": " + std::to_string(data_.size() - offset_) +
                    " unexpected trailing bytes after offset " + std::to_string(offset_));
  }
}

std::vector<std::uint8_t> frame_message(MessageKind kind, std::span<const std::uint8_t> payload) {
  WireWriter w;
  w.u32(kWireMagic);
  w.u16(kWireVersion);
  w.u16(static_cast<std::uint16_t>(kind));
  w.u64(payload.size());
  std::vector<std::uint8_t> out = w.take();
  out.insert(out.end(), payload.begin(), payload.end());
  return out;
}

namespace {
struct Header {
  MessageKind kind;
  std::uint64_t length;
};
Header read_header(std::span<const std::uint8_t> message) {
  WireReader r(message.first(std::min(message.size(), kWireHeaderSize)), "message header");
  const std::uint32_t magic = r.u32("magic");
  if (magic != kWireMagic) {
    throw WireError("message header: bad magic 0x" + std::to_string(magic) +
                    " (not a softevo message)");
  }
  const std::uint16_t version = r.u16("version");
  if (version != kWireVersion) {
    throw WireError("message header: format version " + std::to_string(version) +
                    " not supported (this build reads version " + std::to_string(kWireVersion) +
                    ")");
  }
  const auto kind = static_cast<MessageKind>(r.u16("kind"));
  const std::uint64_t length = r.u64("length");
  if (length > kWireMaxPayload) {
    throw WireError("message header: payload length " + std::to_string(length) +
                    " exceeds the limit of " + std::to_string(kWireMaxPayload) + " bytes");
  }
  if (length != message.size() - kWireHeaderSize) {
    throw WireError("message header: payload length " + std::to_string(length) + " but " +
                    std::to_string(message.size() - kWireHeaderSize) + " bytes follow the header" +
                    (length > message.size() - kWireHeaderSize ? " (truncated)" : " (oversized)"));
  }
  return {kind, length};
}
}  // namespace

MessageKind peek_message_kind(std::span<const std::uint8_t> message) {
  return read_header(message).kind;
}

std::span<const std::uint8_t> unframe_message(std::span<const std::uint8_t> message,
                                              MessageKind expected_kind) {
  const Header h = read_header(message);
  if (h.kind != expected_kind) {
    throw WireError("message header: kind " + std::to_string(static_cast<int>(h.kind)) +
                    ", expected " + std::to_string(static_cast<int>(expected_kind)));
  }
  return message.subspan(kWireHeaderSize);
}

std::vector<std::uint8_t> encode_eval_request(const EvalRequest& request) {
  WireWriter w;
  w.u64(request.config_hash);
  w.i64(request.generation);
  w.i64(request.genome_id);
  w.i32(request.unit);
  w.bytes(request.genome);
  return frame_message(MessageKind::eval_request, w.data());
}

EvalRequest decode_eval_request(std::span<const std::uint8_t> message) {
  WireReader r(unframe_message(message, MessageKind::eval_request), "eval request");
  EvalRequest request;
  request.config_hash = r.u64("config_hash");
  request.generation = r.i64("generation");
  request.genome_id = r.i64("genome_id");
  request.unit = r.i32("unit");
  request.genome = r.bytes("genome");
  r.finish();
  return request;
}

EvalStatus checked_status(std::uint8_t value, const char* what) {
  if (value > static_cast<std::uint8_t>(EvalStatus::invalid_body)) {
    throw WireError(std::string(what) + ": unknown status " + std::to_string(value));
  }
  return static_cast<EvalStatus>(value);
}

void write_unit_fitness(WireWriter& w, const UnitFitness& unit) {
  w.f64(unit.fitness);
  w.u8(static_cast<std::uint8_t>(unit.status));
  w.f64_vector(unit.values);
}

UnitFitness read_unit_fitness(WireReader& r, const char* what) {
  UnitFitness unit;
  unit.fitness = r.f64("component.fitness");
  unit.status = checked_status(r.u8("component.status"), what);
  unit.values = r.f64_vector("component.values");
  return unit;
}

std::vector<std::uint8_t> encode_eval_result(const EvalResult& result) {
  WireWriter w;
  w.i64(result.genome_id);
  w.i32(result.unit);
  w.u8(static_cast<std::uint8_t>(result.status));
  w.f64(result.fitness);
  w.u32(static_cast<std::uint32_t>(result.components.size()));
  for (const auto& c : result.components) write_unit_fitness(w, c);
  w.i32(result.voxels);
  w.i32(result.chambers);
  w.i64(result.steps);
  w.f64(result.sim_seconds);
  w.f64(result.wall_seconds);
  w.i32(result.worker_rank);
  w.string(result.message);
  return frame_message(MessageKind::eval_result, w.data());
}

EvalResult decode_eval_result(std::span<const std::uint8_t> message) {
  WireReader r(unframe_message(message, MessageKind::eval_result), "eval result");
  EvalResult result;
  result.genome_id = r.i64("genome_id");
  result.unit = r.i32("unit");
  result.status = checked_status(r.u8("status"), "eval result");
  result.fitness = r.f64("fitness");
  const std::uint32_t n_components = r.u32("component_count");
  // Each component is at least 17 bytes (fitness, status, value count): reject a count the
  // remaining bytes cannot hold before allocating.
  if (n_components > r.remaining() / 17) {
    throw WireError("eval result: component_count " + std::to_string(n_components) +
                    " does not fit in the remaining " + std::to_string(r.remaining()) + " bytes");
  }
  result.components.resize(n_components);
  for (auto& c : result.components) c = read_unit_fitness(r, "eval result component");
  result.voxels = r.i32("voxels");
  result.chambers = r.i32("chambers");
  result.steps = r.i64("steps");
  result.sim_seconds = r.f64("sim_seconds");
  result.wall_seconds = r.f64("wall_seconds");
  result.worker_rank = r.i32("worker_rank");
  result.message = r.string("message");
  r.finish();
  return result;
}

std::vector<std::uint8_t> encode_shutdown(std::int32_t exit_code) {
  WireWriter w;
  w.i32(exit_code);
  return frame_message(MessageKind::shutdown, w.data());
}

std::int32_t decode_shutdown(std::span<const std::uint8_t> message) {
  WireReader r(unframe_message(message, MessageKind::shutdown), "shutdown");
  const std::int32_t exit_code = r.i32("exit_code");
  r.finish();
  return exit_code;
}

}  // namespace softevo
