// The viewer's WebSocket protocol (view/protocol.hpp): every message type parses; binary,
// oversized, non-JSON, unknown types and keys, wrong types and values out of range are
// ProtocolErrors that say what is wrong; the frame layout is the documented one.
#include <gtest/gtest.h>

#include <cstring>
#include <string>

#include "view/protocol.hpp"

using namespace softevo::view;

namespace {

std::string error_of(const std::string& text, bool is_text = true) {
  try {
    parse_client_message(text, is_text);
  } catch (const ProtocolError& e) {
    return e.what();
  }
  return "";
}

template <class T>
T at(const std::string& bytes, std::size_t offset) {
  T v;
  std::memcpy(&v, bytes.data() + offset, sizeof v);
  return v;
}

}  // namespace

TEST(ViewProtocol, ParsesEveryMessageType) {
  EXPECT_EQ(parse_client_message(R"({"type":"play"})", true).type, MessageType::play);
  EXPECT_EQ(parse_client_message(R"({"type":"pause"})", true).type, MessageType::pause);
  EXPECT_EQ(parse_client_message(R"({"type":"step"})", true).type, MessageType::step);
  EXPECT_EQ(parse_client_message(R"({"type":"reset"})", true).type, MessageType::reset);
  EXPECT_EQ(parse_client_message(R"({"type":"save"})", true).type, MessageType::save);
  const ClientMessage speed = parse_client_message(R"({"type":"speed","value":0.25})", true);
  EXPECT_EQ(speed.type, MessageType::speed);
  EXPECT_EQ(speed.value, 0.25);
  const ClientMessage steer = parse_client_message(R"({"deg":-40.5,"type":"steer"})", true);
  EXPECT_EQ(steer.type, MessageType::steer);
  EXPECT_EQ(steer.value, -40.5);
  const ClientMessage seek = parse_client_message(R"({"type":"seek","frame":120})", true);
  EXPECT_EQ(seek.type, MessageType::seek);
  EXPECT_EQ(seek.frame, 120);
}

TEST(ViewProtocol, RefusesWhatIsNotAMessage) {
  EXPECT_NE(error_of(R"({"type":"play"})", false).find("binary"), std::string::npos);
  EXPECT_NE(error_of(std::string(2000, ' ')).find("more than 1024"), std::string::npos);
  EXPECT_NE(error_of("{not json").find("not JSON"), std::string::npos);
  EXPECT_NE(error_of("").find("not JSON"), std::string::npos);
  EXPECT_NE(error_of("\xff\xfe").find("not JSON"), std::string::npos);
  EXPECT_NE(error_of("[1,2]").find("object"), std::string::npos);
  EXPECT_NE(error_of("{}").find("\"type\""), std::string::npos);
  EXPECT_NE(error_of(R"({"type":7})").find("\"type\""), std::string::npos);
  EXPECT_NE(error_of(R"({"type":"launch"})").find("unknown message type \"launch\""),
            std::string::npos);
  // No file path (or anything else) rides along on a known type.
  EXPECT_NE(error_of(R"({"type":"save","path":"/etc/passwd"})").find("unknown key \"path\""),
            std::string::npos);
}

TEST(ViewProtocol, RefusesValuesOfTheWrongTypeOrRange) {
  EXPECT_NE(error_of(R"({"type":"speed"})").find("needs \"value\""), std::string::npos);
  EXPECT_NE(error_of(R"({"type":"speed","value":"fast"})").find("number"), std::string::npos);
  EXPECT_NE(error_of(R"({"type":"speed","value":8})").find("within [0.25, 4"), std::string::npos);
  EXPECT_NE(error_of(R"({"type":"speed","value":0.1})").find("within"), std::string::npos);
  EXPECT_FALSE(error_of(R"({"type":"speed","value":1e999})").empty());  // beyond a double
  EXPECT_NE(error_of(R"({"type":"steer","deg":181})").find("within [-180"), std::string::npos);
  EXPECT_NE(error_of(R"({"type":"steer","deg":null})").find("number"), std::string::npos);
  EXPECT_NE(error_of(R"({"type":"seek","frame":1.5})").find("integer"), std::string::npos);
  EXPECT_NE(error_of(R"({"type":"seek","frame":-1})").find("within"), std::string::npos);
  EXPECT_NE(error_of(R"({"type":"seek","frame":99999999999})").find("within"), std::string::npos);
}

TEST(ViewProtocol, FrameLayoutIsTheDocumentedOne) {
  FrameRecord r;
  r.frame = 7;
  r.time = 0.125;
  r.positions = {1, 2, 3, 4, 5, 6};  // 2 items
  r.orientations = {32767, 0, 0, 0, 0, 32767, 0, 0};
  r.pressures_pa = {1.1e5f};
  r.valves = {0.25f, 0.75f};
  r.components = {3.5f, 4.5f, 5.5f};
  r.fitness = 9.0f;
  r.centroid_x = 0.5f;
  r.target_deg = 40.0f;
  const std::string b = encode_frame(r, true);
  EXPECT_EQ(at<std::uint32_t>(b, 0), kFrameMagic);
  EXPECT_EQ(at<std::uint32_t>(b, 4), 7u);
  EXPECT_EQ(at<std::uint32_t>(b, 8), 2u);
  EXPECT_EQ(at<std::uint16_t>(b, 12), 1u);
  EXPECT_EQ(at<std::uint16_t>(b, 14), 3u);
  EXPECT_EQ(at<double>(b, 16), 0.125);
  EXPECT_EQ(at<float>(b, 24), 9.0f);
  EXPECT_EQ(at<float>(b, 28), 0.5f);
  EXPECT_EQ(at<float>(b, 40), 40.0f);
  EXPECT_EQ(at<std::uint32_t>(b, 44), 1u);
  EXPECT_EQ(at<float>(b, 48 + 5 * 4), 6.0f);               // last position
  EXPECT_EQ(at<std::int16_t>(b, 48 + 24 + 5 * 2), 32767);  // second item's x
  EXPECT_EQ(at<float>(b, 48 + 24 + 16), 1.1e5f);           // pressure
  EXPECT_EQ(at<float>(b, 48 + 24 + 16 + 4 + 4), 0.75f);    // outlet valve
  EXPECT_EQ(at<float>(b, 48 + 24 + 16 + 12 + 8), 5.5f);    // last component
  EXPECT_EQ(b.size(), 48u + 24 + 16 + 4 + 8 + 12);
}
