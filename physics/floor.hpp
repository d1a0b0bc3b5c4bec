// The floor the robots stand on (§2.8): the one place that knows where the ground is. The contact
// forces (physics/floor_contact.hpp, the voxel passes) ask floor_at() for the ground height under
// a voxel and compare it with the voxel's z; nothing else in physics/ assumes a floor height.
//
// Today the floor is the plane z = 0 with normal +z everywhere. A terrain gives another height and
// normal per point; the contact formulas then have to use the normal too (they take it to be +z:
// penetration along z, friction in the x-y plane).
#pragma once

namespace softevo::physics {

// The floor below one point (or below W points: T = a lane vector of the grouped passes).
template <class T>
struct FloorPoint {
  T height;                        // z of the floor surface [m]
  T normal_x, normal_y, normal_z;  // unit normal of the surface, pointing out of the ground
};

// The floor below the horizontal position (x, y) [m]. Flat: height +0 and normal +z everywhere, so
// a voxel's penetration height - z is the reference's 0.0 - z, bit for bit. Generic over T
// (double, or a lane vector: T{} is +0 in every lane); always_inline, as every helper the lane
// passes share (they are also compiled for AVX2 / AVX-512, see quat.hpp).
template <class T>
[[gnu::always_inline]] inline FloorPoint<T> floor_at(T x, T y) {
  (void)x;
  (void)y;
  const T zero{};
  return {zero, zero, zero, zero + 1.0};
}

}  // namespace softevo::physics
