// Sine and cosine of an angle near one whose sine and cosine are known: the angle-addition formula with
// Taylor series of the difference. For loops whose angles move by small steps (the compensator's
// iterations, a dense path's next point), where even sinCos costs more than the rest.
#pragma once

#include <cmath>

#include "model/common/sin_cos.hpp"

namespace jointcomp {

// An angle with its sine and cosine (from sinCos, or carried from such by sinCosNear).
struct SinCosAnchor {
  double angle = 0.0, sin = 0.0, cos = 1.0;
};

// Within this of an anchor, sinCosNear's Taylor terms leave less than 1e-20.
constexpr double kSinCosNearAnchor = 0.0625;  // rad

// Out of line: inlined, sinCos's code in the rare branch slowed the common one (the compensator along a path).
[[gnu::noinline]] inline void reanchor(double angle, SinCosAnchor& anchor, double& sine, double& cosine) {
  sinCos(angle, sine, cosine);
  anchor = {angle, sine, cosine};
}

// sin and cos of `angle`. With `reuse` and the angle within kSinCosNearAnchor of the anchor: from the anchor
// by Taylor terms to d^9 (sine) and d^10 (cosine), which leave less than 1e-20, or within 1/128 rad to d^5
// and d^6, which leave less than 4e-19; the anchor is kept. Otherwise sinCos's, and the anchor moves there.
inline void sinCosNear(double angle, bool reuse, SinCosAnchor& anchor, double& sine, double& cosine) {
  const double d = angle - anchor.angle;
  const double distance = std::abs(d);
  if (reuse && distance <= kSinCosNearAnchor) {
    const double d2 = d * d;
    double sin_d, cos_d_minus_1;
    if (distance <= 0.0078125) {
      sin_d = d * (1.0 - d2 * (1.0 / 6.0) * (1.0 - d2 * (1.0 / 20.0)));
      cos_d_minus_1 = -d2 * (1.0 / 2.0) * (1.0 - d2 * (1.0 / 12.0) * (1.0 - d2 * (1.0 / 30.0)));
    } else {
      sin_d = d * (1.0 - d2 * (1.0 / 6.0) *
                             (1.0 - d2 * (1.0 / 20.0) * (1.0 - d2 * (1.0 / 42.0) * (1.0 - d2 * (1.0 / 72.0)))));
      cos_d_minus_1 =
          -d2 * (1.0 / 2.0) *
          (1.0 - d2 * (1.0 / 12.0) * (1.0 - d2 * (1.0 / 30.0) * (1.0 - d2 * (1.0 / 56.0) * (1.0 - d2 * (1.0 / 90.0)))));
    }
    // sin(a + d) = sin a + (sin a (cos d - 1) + cos a sin d): the small correction added last; cosine alike.
    sine = anchor.sin + (anchor.sin * cos_d_minus_1 + anchor.cos * sin_d);
    cosine = anchor.cos + (anchor.cos * cos_d_minus_1 - anchor.sin * sin_d);
  } else {
    reanchor(angle, anchor, sine, cosine);
  }
}

}  // namespace jointcomp
