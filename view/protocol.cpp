// See protocol.hpp.
#include "view/protocol.hpp"

#include <cmath>
#include <cstring>
#include <initializer_list>
#include <limits>

#include <nlohmann/json.hpp>

#include "view/bytes.hpp"

namespace softevo::view {

namespace {

using nlohmann::json;

struct TypeSpec {
  const char* name;
  MessageType type;
  const char* key;  // the one value key of the type, nullptr = none
};

constexpr TypeSpec kTypes[] = {
    {"play", MessageType::play, nullptr}, {"pause", MessageType::pause, nullptr},
    {"step", MessageType::step, nullptr}, {"reset", MessageType::reset, nullptr},
    {"save", MessageType::save, nullptr}, {"speed", MessageType::speed, "value"},
    {"seek", MessageType::seek, "frame"}, {"steer", MessageType::steer, "deg"},
};

double finite_number(const json& j, const std::string& key, double lo, double hi) {
  if (!j.is_number()) throw ProtocolError("\"" + key + "\" must be a number");
  const double v = j.get<double>();
  if (!std::isfinite(v) || v < lo || v > hi)
    throw ProtocolError("\"" + key + "\" must be within [" + json(lo).dump() + ", " +
                        json(hi).dump() + "]");
  return v;
}

}  // namespace

ClientMessage parse_client_message(std::string_view text, bool is_text) {
  if (!is_text) throw ProtocolError("binary messages are not accepted; send JSON text");
  if (text.size() > kMaxClientMessageBytes)
    throw ProtocolError("message of " + std::to_string(text.size()) + " bytes, more than " +
                        std::to_string(kMaxClientMessageBytes));
  const json j = json::parse(text, nullptr, /*allow_exceptions=*/false);
  if (j.is_discarded()) throw ProtocolError("message is not JSON");
  if (!j.is_object()) throw ProtocolError("message must be a JSON object");
  if (!j.contains("type") || !j["type"].is_string())
    throw ProtocolError("message needs a string \"type\"");
  const std::string type = j["type"].get<std::string>();
  const TypeSpec* spec = nullptr;
  for (const auto& t : kTypes)
    if (type == t.name) spec = &t;
  if (!spec) throw ProtocolError("unknown message type \"" + type.substr(0, 40) + "\"");
  for (const auto& [key, value] : j.items()) {
    (void)value;
    if (key != "type" && !(spec->key && key == spec->key))
      throw ProtocolError("unknown key \"" + key.substr(0, 40) + "\" for type " + type);
  }
  ClientMessage m;
  m.type = spec->type;
  if (!spec->key) return m;
  if (!j.contains(spec->key)) throw ProtocolError("type " + type + " needs \"" + spec->key + "\"");
  const json& v = j[spec->key];
  switch (m.type) {
    case MessageType::speed:
      m.value = finite_number(v, "value", kMinSpeed, kMaxSpeed);
      break;
    case MessageType::steer:
      m.value = finite_number(v, "deg", -180.0, 180.0);
      break;
    case MessageType::seek:
      if (!v.is_number_integer()) throw ProtocolError("\"frame\" must be an integer");
      m.frame = static_cast<std::int64_t>(
          finite_number(v, "frame", 0.0, static_cast<double>(std::numeric_limits<int>::max())));
      break;
    default:
      break;
  }
  return m;
}

std::string encode_frame(const FrameRecord& r, bool last) {
  const auto items = static_cast<std::uint32_t>(r.positions.size() / 3);
  std::string out;
  out.reserve(kFrameHeaderBytes + r.positions.size() * 4 + r.orientations.size() * 2 +
              (r.pressures_pa.size() + r.valves.size() + r.components.size()) * 4);
  append_value(out, kFrameMagic);
  append_value(out, static_cast<std::uint32_t>(r.frame));
  append_value(out, items);
  append_value(out, static_cast<std::uint16_t>(r.pressures_pa.size()));
  append_value(out, static_cast<std::uint16_t>(r.components.size()));
  append_value(out, r.time);
  for (float f : {r.fitness, r.centroid_x, r.centroid_y, r.heading_rad, r.target_deg})
    append_value(out, f);
  append_value(out, static_cast<std::uint32_t>(last ? 1 : 0));
  append_values(out, r.positions);
  append_values(out, r.orientations);
  // A trace without valve commands still sends 2 per chamber (zeros), so the layout holds.
  std::vector<float> valves = r.valves;
  valves.resize(2 * r.pressures_pa.size(), 0.0f);
  append_values(out, r.pressures_pa);
  append_values(out, valves);
  append_values(out, r.components);
  return out;
}

std::string error_json(const std::string& message) {
  return json{{"type", "error"}, {"message", message}}.dump();
}

}  // namespace softevo::view
