#!/usr/bin/env python3
"""Derive the polynomial coefficients of physics/reproducible_math.hpp.

Each polynomial is a Chebyshev fit (near-minimax) of the smooth remainder of the function, in
z = x^2, computed with mpmath at 60 digits and rounded to double. The script also measures the
error of the rounded polynomials, evaluated in double exactly as the header does (Estrin's
scheme since physics revision 3, no FMA), against mpmath, and prints the constants of the pi/2
reductions.

    python3 tools/dev/derive_math_coefficients.py        (needs python3-mpmath)
"""
import random

import mpmath as mp

mp.mp.dps = 60


def chebyshev_fit(f, a, b, n):
    poly = mp.chebyfit(f, [a, b], n)  # highest degree first
    return [float(c) for c in reversed(poly)]


def estrin(c, z):  # as rmath::estrin: pairs c[2k] + c[2k+1] z, then joined by z^2, z^4, ...
    level = [c[k] + z * c[k + 1] if k + 1 < len(c) else c[k] for k in range(0, len(c), 2)]
    power = z * z
    while len(level) > 1:
        level = [level[k] + power * level[k + 1] if k + 1 < len(level) else level[k]
                 for k in range(0, len(level), 2)]
        if len(level) > 1:
            power = power * power
    return level[0]


def ulp_error(got, exact):
    exponent = mp.floor(mp.log(abs(exact), 2))
    return float(abs(mp.mpf(got) - exact) / mp.mpf(2) ** (exponent - 52))


def asin_remainder(z):  # asin(y) = y + y z P(z), y = sqrt(z)
    if z == 0:
        return mp.mpf(1) / 6
    y = mp.sqrt(z)
    return (mp.asin(y) / y - 1) / z


def sin_remainder(z):  # sin(r) = r + r z S(z)
    if z == 0:
        return -mp.mpf(1) / 6
    r = mp.sqrt(z)
    return (mp.sin(r) / r - 1) / z


def cos_remainder(z):  # cos(r) = 1 - z/2 + z^2 C(z)
    if z == 0:
        return mp.mpf(1) / 24
    r = mp.sqrt(z)
    return (mp.cos(r) - 1 + z / 2) / (z * z)


def main():
    quarter_pi_sq = float((mp.pi / 4) ** 2) * 1.0001
    asin_c = chebyshev_fit(asin_remainder, 0, 0.25, 13)
    sin_c = chebyshev_fit(sin_remainder, 0, quarter_pi_sq, 7)
    cos_c = chebyshev_fit(cos_remainder, 0, quarter_pi_sq, 7)
    for name, c in (("kAsinCoeff", asin_c), ("kSinCoeff", sin_c), ("kCosCoeff", cos_c)):
        print(name, "=", ", ".join(x.hex() for x in c))

    rng = random.Random(1)
    worst = {"asin": 0.0, "sin": 0.0, "cos": 0.0, "sinc": 0.0}
    for _ in range(20000):
        y = rng.random() * 0.5
        z = y * y
        worst["asin"] = max(worst["asin"], ulp_error(y + y * (z * estrin(asin_c, z)), mp.asin(y)))
        r = rng.random() * float(mp.pi / 4)
        z = r * r
        worst["sin"] = max(worst["sin"], ulp_error(r + r * (z * estrin(sin_c, z)), mp.sin(r)))
        half_z = 0.5 * z
        one_minus = 1.0 - half_z
        c = one_minus + (((1.0 - one_minus) - half_z) + z * z * estrin(cos_c, z))
        worst["cos"] = max(worst["cos"], ulp_error(c, mp.cos(r)))
        # sinc_cos_of_square: sin(r) / r from z = r^2 (quat_from_rotvec)
        z = rng.random() * 0.6
        exact_r = mp.sqrt(z)
        sinc = 1.0 + z * estrin(sin_c, z)
        worst["sinc"] = max(worst["sinc"], ulp_error(sinc, mp.sin(exact_r) / exact_r))
    print("worst error in ulp:", {k: round(v, 3) for k, v in worst.items()})

    def chop(x, bits):  # x rounded to `bits` significant bits
        scale = mp.mpf(2) ** (mp.floor(mp.log(abs(x), 2)) - bits + 1)
        return mp.nint(x / scale) * scale

    half_pi = mp.pi / 2
    p1 = chop(half_pi, 33)
    p2 = chop(half_pi - p1, 33)
    p3 = float(half_pi - p1 - p2)
    print("kHalfPi1/2/3 =", float(p1).hex(), float(p2).hex(), p3.hex())
    print("kHalfPiHi/Lo =", float(half_pi).hex(), float(half_pi - float(half_pi)).hex())
    print("kPiHi/Lo =", float(mp.pi).hex(), float(mp.pi - float(mp.pi)).hex())
    print("kTwoOverPi =", float(2 / mp.pi).hex())


if __name__ == "__main__":
    main()
