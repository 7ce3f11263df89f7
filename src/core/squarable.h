// Private to the library: the range of a value that is used in floating point, divided by
// and squared (a step h, a rest length): [the smallest normal, sqrt(the largest finite)] of
// float or double, and the one message that names it (the integrators, the particle step
// and the soft bodies' lengths and substeps all refuse with the same words).
#pragma once

#include <cmath>
#include <limits>
#include <string>
#include <string_view>

#include "pba/core.h"

namespace pba::detail {

// [min normal, sqrt(max)] of T: about [1.2e-38, 1.8e19] for float, [2.2e-308, 1.3e154] for double
template <class T>
double squarable_lo() {
  return static_cast<double>(std::numeric_limits<T>::min());
}
template <class T>
double squarable_hi() {
  return std::sqrt(static_cast<double>(std::numeric_limits<T>::max()));
}

// true when v rounded to T is normal and its square is finite in T
template <class T>
bool squarable(double v) {
  const T h = static_cast<T>(v);
  return std::isnormal(h) && std::isfinite(h * h);
}

// the reason a step dt of the particles is held to squarable<float> (ParticleSystem::step,
// and World::tick before any stage moves)
inline constexpr std::string_view kParticleStepWhy = "the particles step in float, divide by it and square it";

// Error "<where>: must be in [lo, hi] <unit> (<why>), got <v>"
template <class T>
[[noreturn]] void throw_not_squarable(double v, std::string_view where, std::string_view unit, std::string_view why) {
  throw Error(std::string(where) + ": must be in [" + format_value(squarable_lo<T>()) + ", " +
              format_value(squarable_hi<T>()) + "] " + std::string(unit) + " (" + std::string(why) + "), got " +
              format_value(v));
}

}  // namespace pba::detail
