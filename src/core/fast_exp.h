// 2^y in float by range reduction and a polynomial, for the renderer's pixel loops and the decoder's gate.
#pragma once
#include <cstdint>
#include <cstring>

namespace isplat {

// A degree-5 fit of 2^r on [−0.5, 0.5], highest degree first (p(0) = 1 exactly; relative error below 2e-7). The
// renderer evaluates it with fused multiply-adds on every lane width (render/lanes.h); exp2_poly below without.
constexpr float kExp2Poly[6] = {1.326474594e-03f, 9.671520442e-03f, 5.550733954e-02f,
                                2.402224243e-01f, 6.931470037e-01f, 1.0f};

// 2^y for y in [−126, 126] (callers clamp): n = y rounded to the nearest integer (adding and subtracting 1.5·2^23,
// exact for |y| < 2^22), r = y − n exactly, and 2^n applied exactly in the exponent bits. Only plain arithmetic and
// bit copies, so loops over it vectorize.
inline float exp2_poly(float y) {
  constexpr float kRound = 12582912.0f;  // 1.5·2^23
  const float n = (y + kRound) - kRound, r = y - n;
  float p = kExp2Poly[0];
  for (int k = 1; k < 6; ++k) p = p * r + kExp2Poly[k];
  uint32_t bits;
  std::memcpy(&bits, &p, sizeof bits);
  bits += uint32_t(int32_t(n)) << 23;
  std::memcpy(&p, &bits, sizeof p);
  return p;
}

}  // namespace isplat
