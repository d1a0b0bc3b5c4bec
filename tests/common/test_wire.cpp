// Wire format: round trips, and rejection of truncated, oversized and foreign input.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "common/wire.hpp"

namespace softevo {

TEST(Wire, ScalarsAreLittleEndian) {
  WireWriter w;
  w.u32(0x01020304);
  w.f64(1.0);  // 0x3FF0000000000000
  const auto& d = w.data();
  ASSERT_EQ(d.size(), 12u);
  EXPECT_EQ(d[0], 0x04);
  EXPECT_EQ(d[3], 0x01);
  EXPECT_EQ(d[10], 0xF0);
  EXPECT_EQ(d[11], 0x3F);
}

TEST(Wire, RoundTripAllFieldTypes) {
  WireWriter w;
  w.u8(200);
  w.u16(65000);
  w.i32(-5);
  w.i64(-1234567890123LL);
  w.f64(-0.0);
  w.f64(std::numeric_limits<double>::quiet_NaN());
  w.boolean(true);
  w.string("héllo");
  w.f64_vector({1.5, -2.25, 1e300});
  WireReader r(w.data(), "test");
  EXPECT_EQ(r.u8("a"), 200);
  EXPECT_EQ(r.u16("b"), 65000);
  EXPECT_EQ(r.i32("c"), -5);
  EXPECT_EQ(r.i64("d"), -1234567890123LL);
  const double neg_zero = r.f64("e");
  EXPECT_TRUE(neg_zero == 0.0 && std::signbit(neg_zero));
  EXPECT_TRUE(std::isnan(r.f64("f")));
  EXPECT_TRUE(r.boolean("g"));
  EXPECT_EQ(r.string("h"), "héllo");
  EXPECT_EQ(r.f64_vector("i"), (std::vector<double>{1.5, -2.25, 1e300}));
  EXPECT_NO_THROW(r.finish());
}

EvalResult sample_result() {
  EvalResult r;
  r.genome_id = 77;
  r.unit = 3;
  r.status = EvalStatus::killed_flipped;
  r.fitness = 0.1 + 0.2;
  r.components.push_back({1.5, EvalStatus::ok, {20.0, 2.5, 3.5, 0.25, 0.125}});
  r.voxels = 812;
  r.chambers = 2;
  r.steps = 62400;
  r.sim_seconds = 9.93;
  r.wall_seconds = 1.25;
  r.worker_rank = 2;
  r.message = "flipped at frame 400";
  return r;
}

TEST(Wire, EvalRequestRoundTrip) {
  EvalRequest q{0xDEADBEEFCAFEF00DULL, 12, 345, 4, {1, 2, 3, 250}};
  const EvalRequest back = decode_eval_request(encode_eval_request(q));
  EXPECT_EQ(back.config_hash, q.config_hash);
  EXPECT_EQ(back.generation, 12);
  EXPECT_EQ(back.genome_id, 345);
  EXPECT_EQ(back.unit, 4);
  EXPECT_EQ(back.genome, q.genome);
}

TEST(Wire, EvalResultRoundTripIsBitExact) {
  const EvalResult r = sample_result();
  const auto bytes = encode_eval_result(r);
  const EvalResult back = decode_eval_result(bytes);
  EXPECT_EQ(encode_eval_result(back), bytes);
  EXPECT_EQ(back.fitness, r.fitness);
  EXPECT_EQ(back.message, r.message);
  ASSERT_EQ(back.components.size(), 1u);
  EXPECT_EQ(back.components[0].values, r.components[0].values);
  EXPECT_EQ(back.components[0].fitness, 1.5);
}

TEST(Wire, RejectsEveryTruncation) {
  const auto bytes = encode_eval_result(sample_result());
  for (std::size_t n = 0; n < bytes.size(); ++n) {
    std::vector<std::uint8_t> cut(bytes.begin(), bytes.begin() + n);
    EXPECT_THROW(decode_eval_result(cut), WireError) << "prefix of " << n << " bytes";
  }
}

TEST(Wire, RejectsOversizedAndTrailingBytes) {
  auto bytes = encode_eval_request({1, 2, 3, 0, {9}});
  bytes.push_back(0);
  try {
    decode_eval_request(bytes);
    FAIL() << "trailing byte accepted";
  } catch (const WireError& e) {
    EXPECT_NE(std::string(e.what()).find("oversized"), std::string::npos) << e.what();
  }
  // A payload that claims more elements than it holds is rejected before allocating.
  WireWriter w;
  w.u64(1ULL << 60);
  WireReader r(w.data(), "vector");
  EXPECT_THROW(r.f64_vector("values"), WireError);
}

TEST(Wire, RejectsForeignMagicVersionAndKind) {
  auto bytes = encode_eval_request({1, 2, 3, 0, {}});
  auto bad_magic = bytes;
  bad_magic[0] ^= 0xFF;
  EXPECT_THROW(decode_eval_request(bad_magic), WireError);
  auto bad_version = bytes;
  bad_version[4] = 99;
  EXPECT_THROW(decode_eval_request(bad_version), WireError);
  // A request is not a result.
  try {
    decode_eval_result(bytes);
    FAIL();
  } catch (const WireError& e) {
    EXPECT_NE(std::string(e.what()).find("kind"), std::string::npos) << e.what();
  }
}

TEST(Wire, ErrorNamesTheField) {
  WireWriter w;
  w.u32(1);
  WireReader r(w.data(), "genome");
  r.u32("node_count");
  try {
    r.f64("bias");
    FAIL();
  } catch (const WireError& e) {
    const std::string msg = e.what();
    EXPECT_NE(msg.find("genome"), std::string::npos) << msg;
    EXPECT_NE(msg.find("'bias'"), std::string::npos) << msg;
  }
}

TEST(Wire, ShutdownCarriesTheExitCode) {
  const std::vector<std::uint8_t> bytes = encode_shutdown(75);
  // Header (magic "SEVO", version 1, kind 3 = shutdown, payload length 4), then the i32 code.
  const std::vector<std::uint8_t> expected = {'S', 'E', 'V', 'O', 1, 0, 3,  0, 4, 0,
                                              0,   0,   0,   0,   0, 0, 75, 0, 0, 0};
  EXPECT_EQ(bytes, expected);
  EXPECT_EQ(decode_shutdown(bytes), 75);
  EXPECT_EQ(decode_shutdown(encode_shutdown(-3)), -3);
  EXPECT_THROW(decode_shutdown(encode_eval_request({})), WireError);  // another kind
  std::vector<std::uint8_t> longer = frame_message(MessageKind::shutdown, expected);
  EXPECT_THROW(decode_shutdown(longer), WireError);  // trailing bytes after the code
}

}  // namespace softevo
