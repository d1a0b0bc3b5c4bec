// The viewer's WebSocket protocol (docs/viewer.md): what the page may send, checked before
// anything acts on it, and how the server's frames are laid out.
//
// Client -> server: one JSON object per text message, at most kMaxClientMessageBytes, with a
// "type" and only the keys of that type:
//   {"type":"play"} {"type":"pause"} {"type":"step"} {"type":"reset"} {"type":"save"}
//   {"type":"speed","value":0.25..4}    simulated seconds per wall-clock second
//   {"type":"seek","frame":N}           show record N (>= 0; clamped to the records there are)
//   {"type":"steer","deg":-180..180}    target direction of a directed robot [deg]
// Anything else (binary, oversized, not JSON, unknown type or key, a value of the wrong type or
// out of range) is a ProtocolError, answered with {"type":"error","message":...}.
//
// Server -> client: JSON text ({"type":"hello"|"ended"|"saved"|"error"|"state", ...}) and one
// binary message per shown frame (encode_frame, little-endian):
//   offset  0  u32 magic "SVF1"         4  u32 record index       8  u32 items (voxels + chamber
//   cells)
//          12  u16 chambers            14  u16 components        16  f64 time [s]
//          24  f32 fitness so far      28  f32 centroid x [m]    32  f32 centroid y [m]
//          36  f32 heading [rad]       40  f32 target [deg]      44  u32 flags (1 = last record)
//          48  f32 positions [items][3] [m], then i16 orientations [items][4] (w,x,y,z x 32767),
//              f32 pressures [chambers] [Pa], f32 valves [2 chambers], f32 components
#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>

#include "view/session.hpp"

namespace softevo::view {

inline constexpr std::size_t kMaxClientMessageBytes = 1024;
inline constexpr std::uint32_t kFrameMagic = 0x31465653;  // "SVF1" little-endian
inline constexpr std::size_t kFrameHeaderBytes = 48;
inline constexpr double kMinSpeed = 0.25, kMaxSpeed = 4.0;

class ProtocolError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

enum class MessageType { play, pause, step, reset, save, speed, seek, steer };

struct ClientMessage {
  MessageType type = MessageType::play;
  double value = 0.0;      // speed (speed) or degrees (steer)
  std::int64_t frame = 0;  // seek
};

// Throws ProtocolError saying what is wrong (never anything else).
ClientMessage parse_client_message(std::string_view text, bool is_text);

// The binary frame of a record (layout above).
std::string encode_frame(const FrameRecord& record, bool last);

// {"type":"error","message":...}
std::string error_json(const std::string& message);

}  // namespace softevo::view
