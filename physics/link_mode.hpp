// §2.3 step 3, the small-angle / large-angle mode test of a link, and a form of it without
// division for the SIMD link passes.
#pragma once

namespace softevo::physics {

// §2.3 small-angle hysteresis thresholds (float, as the reference's static float constants).
constexpr float kSmallBend = 0.05f;  // turn below this -> small angle
constexpr float kSmallExt = 0.5f;    // extension below this -> small angle
constexpr float kHysteresis = 1.2f;  // leave small angle above 1.2x the thresholds

// The reference's test, per link in float with the link direction d in N's frame:
//   turn = float((|d_z| + |d_y|) / d_x),   ext = float(|1 - d_x / L|)
//   small-angle mode is left when turn > 1.2 kSmallBend or ext > 1.2 kSmallExt,
//   large-angle mode is left when turn < kSmallBend and ext < kSmallExt.
// That is two divisions per link and pass, for a decision that only compares turn and ext with
// float thresholds t. The comparisons are taken here from products, and the divisions are left
// for the rare links where the products cannot decide. For a float t > 0 and a double q:
//   q > t (1 + 2^-20)  implies  float(q) > t   (float(q) >= the float above t, monotone rounding)
//   q < t (1 - 2^-20)  implies  float(q) < t   (float(q) <= the float below t: its distance to t
//                                               is at most t 2^-23)
// The products below differ from the quotients of the exact test by a few double roundings
// (relative 2^-52; for ext also 2^-52 |d_x / L| absolute, which only matters when ext is huge),
// far inside the 2^-20 margin. NaN decides nothing; for d_x <= 0 only ext can decide.
namespace link_mode {

constexpr double kMargin = 0x1p-20;
template <bool kLarge>
constexpr double kTurnThreshold = kLarge ? static_cast<double>(kSmallBend)
                                         : static_cast<double>(kHysteresis* kSmallBend);
template <bool kLarge>
constexpr double kExtThreshold = kLarge ? static_cast<double>(kSmallExt)
                                        : static_cast<double>(kHysteresis* kSmallExt);

// The result of test_without_division, lane by lane (Mask: bool-like or a lane mask).
template <class Mask>
struct ModeTest {
  Mask decided;   // the products decide the test (else the caller does the exact test)
  Mask switches;  // where decided: the link leaves its mode
};

// Mode test of a link in large-angle mode (kLarge) or small-angle mode (!kLarge) without
// division; T is a double or a lane vector, Ops supplies abs (see rmath::ScalarOps).
template <bool kLarge, class Ops, class T>
[[gnu::always_inline]] inline auto test_without_division(const T& dx, const T& dy, const T& dz,
                                                         double inv_rest_length) {
  constexpr double t = kTurnThreshold<kLarge>, e = kExtThreshold<kLarge>;
  const T num = Ops::abs(dz) + Ops::abs(dy);  // turn = num / dx
  const auto forward = dx > 0.0;
  const auto turn_above = forward & (num > dx * (t * (1.0 + kMargin)));
  const auto turn_below = forward & (num < dx * (t * (1.0 - kMargin)));
  const T ext = Ops::abs(1.0 - dx * inv_rest_length);
  const auto ext_above = ext > e * (1.0 + kMargin);
  const auto ext_below = ext < e * (1.0 - kMargin);
  const auto above = turn_above | ext_above;  // certainly leaves small-angle mode
  const auto below = turn_below & ext_below;  // certainly leaves large-angle mode
  using Mask = decltype(above | below);
  return ModeTest<Mask>{above | below, kLarge ? below : above};
}

}  // namespace link_mode
}  // namespace softevo::physics
