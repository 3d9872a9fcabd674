// The IC-GN kernel of one instruction set (icgn_kernels.h): included once by each of
// icgn_kernel_scalar.cc, icgn_kernel_avx2.cc and icgn_kernel_avx512.cc, which define
// IMPACTDIC_DIC_KERNEL_NS (the namespace of their copy) and IMPACTDIC_DIC_KERNEL_LEVEL (0 scalar,
// 1 AVX2 + FMA, 2 AVX-512) and are compiled with those instructions enabled. Everything here has
// internal linkage but the unit's table, and uses only plain data, builtins and intrinsics (no
// inline function of a library header: see icgn_kernels.h).
//
// The passes are those of icgn.cc (the IC-GN expansion at its top): one pass over a subset per
// iteration (which also keeps the warped subset), the reference moments of PrepareSubset, and the
// residuals, influences and lag sums of the uncertainty estimate. The vectorised versions evaluate
// the same expressions in another order of summation (per-lane sums, FMA), so the kernels agree to
// float rounding (tests/dic/kernel_agreement_test.cc).
#ifndef IMPACTDIC_DIC_KERNEL_NS
#error "define IMPACTDIC_DIC_KERNEL_NS and IMPACTDIC_DIC_KERNEL_LEVEL before including this file"
#endif

#include <cstddef>

#include "icgn_kernels.h"

#if IMPACTDIC_DIC_KERNEL_LEVEL >= 1
#if !defined(__AVX2__) || !defined(__FMA__)
#error "the AVX2 kernel needs -mavx2 -mfma"
#endif
#include <immintrin.h>
#define IMPACTDIC_DIC_AVX2 1
#else
#define IMPACTDIC_DIC_AVX2 0
#if defined(__SSE2__)
#include <emmintrin.h>
#endif
#endif
#if IMPACTDIC_DIC_KERNEL_LEVEL >= 2
#if !defined(__AVX512F__) || !defined(__AVX512DQ__) || !defined(__AVX512VL__)
#error "the AVX-512 kernel needs -mavx512f -mavx512dq -mavx512vl"
#endif
#define IMPACTDIC_DIC_AVX512 1
#else
#define IMPACTDIC_DIC_AVX512 0
#endif

namespace impactdic::internal::IMPACTDIC_DIC_KERNEL_NS {
namespace {

// Longest subset row of the vectorised reference moments, in blocks of 8 pixels.
constexpr int kMaxBlocks = 32;

inline int Min(int a, int b) { return a < b ? a : b; }
inline double Max(double a, double b) { return a < b ? b : a; }

// The cubic B-spline weights of the 4 taps at offset t in [0, 1) (as CubicWeights in bspline.h,
// whose out-of-line copy this unit must not make).
inline void CubicWeightsF(float t, float w[4]) {
  const float s = 1 - t, t2 = t * t, t3 = t2 * t;
  w[0] = s * s * s * (1.0f / 6);
  w[1] = (2.0f / 3) - t2 + 0.5f * t3;
  w[3] = t3 * (1.0f / 6);
  w[2] = 1 - w[0] - w[1] - w[3];
}

// The quintic B-spline weights of the 6 taps at offset t in [0, 1).
inline void QuinticWeightsF(float t, float w[6]) {
  const float s = 1 - t;
  const float t2 = t * t, t4 = t2 * t2, t5 = t4 * t;
  const float s2 = s * s, s4 = s2 * s2;
  constexpr float k = 1.0f / 120;
  w[0] = s4 * s * k;
  w[5] = t5 * k;
  // Distance 1 + t (mid piece) and 1 - t, 2 - t.
  const float d1 = 1 + t, d1_2 = d1 * d1, d1_4 = d1_2 * d1_2;
  w[1] = (51 + 75 * d1 - 210 * d1_2 + 150 * d1_2 * d1 - 45 * d1_4 + 5 * d1_4 * d1) * k;
  w[2] = (66 - 60 * t2 + 30 * t4 - 10 * t5) * k;
  const float s5 = s4 * s;
  w[3] = (66 - 60 * s2 + 30 * s4 - 10 * s5) * k;
  w[4] = 1 - w[0] - w[1] - w[2] - w[3] - w[5];
}

// One IC-GN pass over the subset, one pixel at a time: accumulates into out (zeroed by the
// caller) the sums of the expansion at the top of icgn.cc.
template <int kTaps, bool kQuad>
// NOLINTNEXTLINE(readability-function-size): a SIMD kernel, kept whole (docs/architecture.md)
void AccumulateScalar(const PassInput& in, PassSums* out) {
  constexpr int kLow = kTaps == 4 ? 1 : 2;
  const int h = in.half, size = 2 * h + 1;
  const float fm = in.f_mean;
  const double* p = in.p;
  const double u = in.u, v = in.v;
  const std::ptrdiff_t stride = in.stride;
  for (int j = 0; j < size; ++j) {
    const double eta = j - h;
    float ax0, ax1, ax2 = 0, ay0, ay1, ay2 = 0;
    if constexpr (kQuad) {
      ax0 = static_cast<float>(u + p[2] * eta + 0.5 * p[5] * eta * eta);
      ax1 = static_cast<float>(1 + p[1] + p[4] * eta);
      ax2 = static_cast<float>(0.5 * p[3]);
      ay0 = static_cast<float>(eta + v + p[8] * eta + 0.5 * p[11] * eta * eta);
      ay1 = static_cast<float>(p[7] + p[10] * eta);
      ay2 = static_cast<float>(0.5 * p[9]);
    } else {
      ax0 = static_cast<float>(u + p[2] * eta);
      ax1 = static_cast<float>(1 + p[1]);
      ay0 = static_cast<float>(eta + v + p[5] * eta);
      ay1 = static_cast<float>(p[4]);
    }
    const std::ptrdiff_t roff = j * in.ref_stride;
    const float* fr = in.f + roff;
    const float* gxr = in.gx + roff;
    const float* gyr = in.gy + roff;
    float sg = 0, sgg = 0, sfg = 0, a0 = 0, a1 = 0, a2 = 0, b0 = 0, b1 = 0, b2 = 0;
    for (int i = 0; i < size; ++i) {
      const float xi = static_cast<float>(i - h);
      float x, y;
      if constexpr (kQuad) {
        x = ax0 + xi * (ax1 + xi * ax2);
        y = ay0 + xi * (ay1 + xi * ay2);
      } else {
        x = ax0 + xi * ax1;
        y = ay0 + xi * ay1;
      }
      // floor() of small local coordinates without a library call.
      const int ix = static_cast<int>(x + 1024.0f) - 1024;
      const int iy = static_cast<int>(y + 1024.0f) - 1024;
      const float tx = x - static_cast<float>(ix), ty = y - static_cast<float>(iy);
      const float* c = in.centre + static_cast<std::ptrdiff_t>(iy - kLow) * stride + (ix - kLow);
      float g = 0;
      if constexpr (kTaps == 4) {
#if defined(__SSE2__)
        // Weights of the 4 taps as cubic polynomials of t, evaluated 4-wide (Horner), then the
        // 4x4 block: rows weighted by wy and summed, dot product with wx.
        const __m128 tx4 = _mm_set1_ps(tx), ty4 = _mm_set1_ps(ty);
        const __m128 kA = _mm_setr_ps(-1.0f / 6, 0.5f, -0.5f, 1.0f / 6);
        const __m128 kB = _mm_setr_ps(0.5f, -1.0f, 0.5f, 0.0f);
        const __m128 kC = _mm_setr_ps(-0.5f, 0.0f, 0.5f, 0.0f);
        const __m128 kD = _mm_setr_ps(1.0f / 6, 4.0f / 6, 1.0f / 6, 0.0f);
        const __m128 wx4 = _mm_add_ps(
            _mm_mul_ps(_mm_add_ps(_mm_mul_ps(_mm_add_ps(_mm_mul_ps(kA, tx4), kB), tx4), kC), tx4),
            kD);
        const __m128 wy4 = _mm_add_ps(
            _mm_mul_ps(_mm_add_ps(_mm_mul_ps(_mm_add_ps(_mm_mul_ps(kA, ty4), kB), ty4), kC), ty4),
            kD);
        __m128 acc = _mm_mul_ps(_mm_loadu_ps(c), _mm_shuffle_ps(wy4, wy4, 0x00));
        acc = _mm_add_ps(acc, _mm_mul_ps(_mm_loadu_ps(c + stride), _mm_shuffle_ps(wy4, wy4, 0x55)));
        acc = _mm_add_ps(acc,
                         _mm_mul_ps(_mm_loadu_ps(c + 2 * stride), _mm_shuffle_ps(wy4, wy4, 0xAA)));
        acc = _mm_add_ps(acc,
                         _mm_mul_ps(_mm_loadu_ps(c + 3 * stride), _mm_shuffle_ps(wy4, wy4, 0xFF)));
        acc = _mm_mul_ps(acc, wx4);
        __m128 sh = _mm_shuffle_ps(acc, acc, _MM_SHUFFLE(2, 3, 0, 1));
        acc = _mm_add_ps(acc, sh);
        sh = _mm_movehl_ps(sh, acc);
        g = _mm_cvtss_f32(_mm_add_ss(acc, sh));
#else
        float wx[4], wy[4];
        CubicWeightsF(tx, wx);
        CubicWeightsF(ty, wy);
        for (int r = 0; r < 4; ++r) {
          const float* cr = c + r * stride;
          g += wy[r] * (wx[0] * cr[0] + wx[1] * cr[1] + wx[2] * cr[2] + wx[3] * cr[3]);
        }
#endif
      } else {
        float wx[6], wy[6];
        QuinticWeightsF(tx, wx);
        QuinticWeightsF(ty, wy);
        for (int r = 0; r < 6; ++r) {
          const float* cr = c + r * stride;
          g += wy[r] * (wx[0] * cr[0] + wx[1] * cr[1] + wx[2] * cr[2] + wx[3] * cr[3] +
                        wx[4] * cr[4] + wx[5] * cr[5]);
        }
      }
      const float gp = g - fm;
      in.g_out[j * size + i] = gp;
      sg += gp;
      sgg += gp * gp;
      sfg += fr[i] * gp;
      const float a = gp * gxr[i], b = gp * gyr[i];
      a0 += a;
      a1 += a * xi;
      b0 += b;
      b1 += b * xi;
      if constexpr (kQuad) {
        a2 += a * xi * xi;
        b2 += b * xi * xi;
      }
    }
    out->sg += sg;
    out->sgg += sgg;
    out->sfg += sfg;
    const double e2 = eta * eta;
    out->a[0][0][0] += a0;
    out->a[0][1][0] += a1;
    out->a[0][0][1] += a0 * eta;
    out->a[1][0][0] += b0;
    out->a[1][1][0] += b1;
    out->a[1][0][1] += b0 * eta;
    if constexpr (kQuad) {
      out->a[0][2][0] += a2;
      out->a[0][1][1] += a1 * eta;
      out->a[0][0][2] += a0 * e2;
      out->a[1][2][0] += b2;
      out->a[1][1][1] += b1 * eta;
      out->a[1][0][2] += b0 * e2;
    }
  }
}

#if IMPACTDIC_DIC_AVX2
// The same pass, 8 pixels of a subset row at a time (AVX2 + FMA, one pixel per lane). The B-spline
// weights of the 8 pixels are evaluated lane-wise. Along a row the sample positions advance by
// about one pixel per pixel, so in the usual ("regular") case the tap (r, k) of the 8 pixels is 8
// consecutive coefficients: one unaligned load per tap. When a block straddles a change of the
// integer row, or its integer columns do not advance by exactly one, the taps are gathered
// instead; both paths evaluate the same expression in the same order. A row is covered by blocks
// starting at 0, 8, ...; the last block is moved back to end at the row end, its lanes that the
// previous block already covered are masked out (so nothing outside the subset is read); when it
// adds only 1 or 2 pixels, those are interpolated one by one. The per-lane sums run over the whole
// subset (float) and are reduced once at the end.
inline __m256 Splat(float v) { return _mm256_set1_ps(v); }

// Sum of the 8 lanes, in a fixed order.
inline double HorizontalSum(__m256 v) {
  const __m128 q = _mm_add_ps(_mm256_castps256_ps128(v), _mm256_extractf128_ps(v, 1));
  const __m128 d = _mm_add_ps(q, _mm_movehl_ps(q, q));
  return _mm_cvtss_f32(_mm_add_ss(d, _mm_shuffle_ps(d, d, 1)));
}

// 120 x the quintic B-spline weights b5(t + 2), b5(t + 1), b5(t), b5(t - 1), b5(t - 2),
// b5(t - 3) as polynomials of t: coefficients of 1, t, ..., t^5.
constexpr float kQuinticC[6][6] = {
    {1, -5, 10, -10, 5, -1},     // (1 - t)^5
    {26, -50, 20, 20, -20, 5},   // b5(1 + t)
    {66, 0, -60, 0, 30, -10},    // b5(t)
    {26, 50, 20, -20, -20, 10},  // b5(1 - t)
    {1, 5, 10, 10, 5, -5},       // b5(2 - t)
    {0, 0, 0, 0, 0, 1},          // t^5
};

// Scale of the weights of WeightsAvx2 (per axis): the interpolated value is the weighted sum
// divided by kWeightScale^2.
template <int kTaps>
constexpr float kWeightScale = kTaps == 4 ? 6.0f : 1.0f;

template <int kTaps>
inline void WeightsAvx2(__m256 t, __m256 w[kTaps]) {
  if constexpr (kTaps == 4) {
    // 6 x the cubic B-spline weights (the caller divides by 36 at the end): t^3, (1 - t)^3,
    // 4 - 6 t^2 + 3 t^3 and the same of 1 - t.
    const __m256 s = _mm256_sub_ps(Splat(1), t);
    const __m256 t2 = _mm256_mul_ps(t, t), s2 = _mm256_mul_ps(s, s);
    const __m256 t3 = _mm256_mul_ps(t2, t), s3 = _mm256_mul_ps(s2, s);
    w[0] = s3;
    w[1] = _mm256_fmadd_ps(t3, Splat(3), _mm256_fnmadd_ps(t2, Splat(6), Splat(4)));
    w[2] = _mm256_fmadd_ps(s3, Splat(3), _mm256_fnmadd_ps(s2, Splat(6), Splat(4)));
    w[3] = t3;
  } else {
    // Quintic B-spline weights as quintic polynomials of t (Horner), coefficients of
    // b5(t + 2), b5(t + 1), b5(t), b5(t - 1), b5(t - 2), b5(t - 3) times 120.
    for (int k = 0; k < 6; ++k) {
      __m256 v = Splat(kQuinticC[k][5] / 120);
      for (int d = 4; d >= 0; --d) v = _mm256_fmadd_ps(v, t, Splat(kQuinticC[k][d] / 120));
      w[k] = v;
    }
  }
}

// Sum over the kTaps rows of the per-row tap sums weighted by wy.
template <int kTaps>
inline __m256 CombineRows(const __m256 wy[kTaps], const __m256 rs[kTaps]) {
  __m256 g = _mm256_mul_ps(wy[0], rs[0]);
  for (int r = 1; r < kTaps; ++r) g = _mm256_fmadd_ps(wy[r], rs[r], g);
  return g;
}

// The B-spline at one local position (x, y) relative to `centre` (scalar).
template <int kTaps>
inline float SampleScalar(const float* centre, int stride, float x, float y) {
  constexpr int kLow = kTaps == 4 ? 1 : 2;
  const float fx = __builtin_floorf(x), fy = __builtin_floorf(y);
  float wx[6], wy[6];
  if constexpr (kTaps == 4) {
    CubicWeightsF(x - fx, wx);
    CubicWeightsF(y - fy, wy);
  } else {
    QuinticWeightsF(x - fx, wx);
    QuinticWeightsF(y - fy, wy);
  }
  const float* c = centre + static_cast<std::ptrdiff_t>(static_cast<int>(fy) - kLow) * stride +
                   (static_cast<int>(fx) - kLow);
  float g = 0;
  for (int r = 0; r < kTaps; ++r) {
    const float* cr = c + static_cast<std::ptrdiff_t>(r) * stride;
    float row = 0;
    for (int k = 0; k < kTaps; ++k) row += wx[k] * cr[k];
    g += wy[r] * row;
  }
  return g;
}

template <int kTaps, bool kQuad>
// NOLINTNEXTLINE(readability-function-size): a SIMD kernel, kept whole (docs/architecture.md)
void AccumulateAvx2(const PassInput& in, PassSums* out) {
  constexpr int kLow = kTaps == 4 ? 1 : 2;
  const int h = in.half, size = 2 * h + 1;
  const __m256 fm = Splat(in.f_mean);
  const double* p = in.p;
  const double u = in.u, v = in.v;
  // Coefficients around the (shifted) subset centre; tap offsets are relative to it.
  const float* centre = in.centre;
  const __m256 lane = _mm256_setr_ps(0, 1, 2, 3, 4, 5, 6, 7);
  const __m256i lane_i = _mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7);
  const int blocks = (size + 7) / 8;
  const int istride = static_cast<int>(in.stride);
  constexpr float kScale2 = kWeightScale<kTaps> * kWeightScale<kTaps>;
  __m256 sg = _mm256_setzero_ps(), sgg = sg, sfg = sg;
  // a[p][q]: sum g' gx xi^p eta^q; b: the same with gy.
  __m256 a00 = sg, a10 = sg, a01 = sg, b00 = sg, b10 = sg, b01 = sg;
  __m256 a20 = sg, a11 = sg, a02 = sg, b20 = sg, b11 = sg, b02 = sg;
  for (int j = 0; j < size; ++j) {
    const double eta = j - h;
    float ax0, ax1, ax2 = 0, ay0, ay1, ay2 = 0;
    if constexpr (kQuad) {
      ax0 = static_cast<float>(u + p[2] * eta + 0.5 * p[5] * eta * eta);
      ax1 = static_cast<float>(1 + p[1] + p[4] * eta);
      ax2 = static_cast<float>(0.5 * p[3]);
      ay0 = static_cast<float>(eta + v + p[8] * eta + 0.5 * p[11] * eta * eta);
      ay1 = static_cast<float>(p[7] + p[10] * eta);
      ay2 = static_cast<float>(0.5 * p[9]);
    } else {
      ax0 = static_cast<float>(u + p[2] * eta);
      ax1 = static_cast<float>(1 + p[1]);
      ay0 = static_cast<float>(eta + v + p[5] * eta);
      ay1 = static_cast<float>(p[4]);
    }
    const std::ptrdiff_t roff = j * in.ref_stride;
    const float* fr = in.f + roff;
    const float* gxr = in.gx + roff;
    const float* gyr = in.gy + roff;
    __m256 ra00 = _mm256_setzero_ps(), ra10 = ra00, ra20 = ra00, rb00 = ra00, rb10 = ra00,
           rb20 = ra00;
    for (int b = 0; b < blocks; ++b) {
      const int i0 = Min(8 * b, size - 8), fresh = size - 8 * b;
      const __m256 xi = _mm256_add_ps(lane, Splat(static_cast<float>(i0 - h)));
      __m256 g;
      if (fresh <= 2) {
        // A row end of 1 or 2 pixels (e.g. subset 25 = 3 x 8 + 1): per pixel, not a block.
        alignas(32) float gl[8] = {};
        for (int l = 8 - fresh; l < 8; ++l) {
          const float xs = static_cast<float>(i0 + l - h);
          const float px = kQuad ? ax0 + xs * (ax1 + xs * ax2) : ax0 + xs * ax1;
          const float py = kQuad ? ay0 + xs * (ay1 + xs * ay2) : ay0 + xs * ay1;
          gl[l] = SampleScalar<kTaps>(centre, istride, px, py) * kScale2;
        }
        g = _mm256_load_ps(gl);
      } else {
        __m256 x, y;
        if constexpr (kQuad) {
          x = _mm256_fmadd_ps(_mm256_fmadd_ps(xi, Splat(ax2), Splat(ax1)), xi, Splat(ax0));
          y = _mm256_fmadd_ps(_mm256_fmadd_ps(xi, Splat(ay2), Splat(ay1)), xi, Splat(ay0));
        } else {
          x = _mm256_fmadd_ps(xi, Splat(ax1), Splat(ax0));
          y = _mm256_fmadd_ps(xi, Splat(ay1), Splat(ay0));
        }
        const __m256 fx = _mm256_floor_ps(x), fy = _mm256_floor_ps(y);
        const __m256 tx = _mm256_sub_ps(x, fx), ty = _mm256_sub_ps(y, fy);
        const __m256i ix = _mm256_cvttps_epi32(fx), iy = _mm256_cvttps_epi32(fy);
        const int ix0 = _mm256_cvtsi256_si32(ix), iy0 = _mm256_cvtsi256_si32(iy);
        const __m256i expect_x = _mm256_add_epi32(_mm256_set1_epi32(ix0), lane_i);
        const __m256i same = _mm256_and_si256(_mm256_cmpeq_epi32(ix, expect_x),
                                              _mm256_cmpeq_epi32(iy, _mm256_set1_epi32(iy0)));
        const bool regular = _mm256_movemask_epi8(same) == -1;
        __m256 wx[kTaps], wy[kTaps];
        WeightsAvx2<kTaps>(tx, wx);
        WeightsAvx2<kTaps>(ty, wy);
        if (regular) {
          const float* c0 =
              centre + static_cast<std::ptrdiff_t>(iy0 - kLow) * istride + (ix0 - kLow);
          __m256 rs[kTaps];
          for (int r = 0; r < kTaps; ++r) {
            const float* cr = c0 + static_cast<std::ptrdiff_t>(r) * istride;
            rs[r] = _mm256_mul_ps(wx[0], _mm256_loadu_ps(cr));
            for (int k = 1; k < kTaps; ++k)
              rs[r] = _mm256_fmadd_ps(wx[k], _mm256_loadu_ps(cr + k), rs[r]);
          }
          g = CombineRows<kTaps>(wy, rs);
        } else {
          const __m256i off0 =
              _mm256_add_epi32(_mm256_mullo_epi32(_mm256_sub_epi32(iy, _mm256_set1_epi32(kLow)),
                                                  _mm256_set1_epi32(istride)),
                               _mm256_sub_epi32(ix, _mm256_set1_epi32(kLow)));
          __m256 rs[kTaps];
          for (int r = 0; r < kTaps; ++r) {
            const __m256i offr = _mm256_add_epi32(off0, _mm256_set1_epi32(r * istride));
            auto tap = [&](int k) {
              return _mm256_i32gather_ps(centre, _mm256_add_epi32(offr, _mm256_set1_epi32(k)), 4);
            };
            rs[r] = _mm256_mul_ps(wx[0], tap(0));
            for (int k = 1; k < kTaps; ++k) rs[r] = _mm256_fmadd_ps(wx[k], tap(k), rs[r]);
          }
          g = CombineRows<kTaps>(wy, rs);
        }
      }
      __m256 gp = _mm256_fmsub_ps(g, Splat(1 / kScale2), fm);
      float* g_out = in.g_out + static_cast<std::ptrdiff_t>(j) * size + i0;
      if (i0 != 8 * b) {  // Mask the lanes of the previous block.
        const __m256 fresh_lanes =
            _mm256_cmp_ps(lane, Splat(static_cast<float>(8 * b - i0)), _CMP_GE_OQ);
        gp = _mm256_and_ps(gp, fresh_lanes);
        _mm256_maskstore_ps(g_out, _mm256_castps_si256(fresh_lanes), gp);
      } else {
        _mm256_storeu_ps(g_out, gp);
      }
      sg = _mm256_add_ps(sg, gp);
      sgg = _mm256_fmadd_ps(gp, gp, sgg);
      sfg = _mm256_fmadd_ps(_mm256_loadu_ps(fr + i0), gp, sfg);
      const __m256 a = _mm256_mul_ps(gp, _mm256_loadu_ps(gxr + i0));
      const __m256 bb = _mm256_mul_ps(gp, _mm256_loadu_ps(gyr + i0));
      ra00 = _mm256_add_ps(ra00, a);
      ra10 = _mm256_fmadd_ps(a, xi, ra10);
      rb00 = _mm256_add_ps(rb00, bb);
      rb10 = _mm256_fmadd_ps(bb, xi, rb10);
      if constexpr (kQuad) {
        ra20 = _mm256_fmadd_ps(_mm256_mul_ps(a, xi), xi, ra20);
        rb20 = _mm256_fmadd_ps(_mm256_mul_ps(bb, xi), xi, rb20);
      }
    }
    const __m256 e = Splat(static_cast<float>(eta));
    a00 = _mm256_add_ps(a00, ra00);
    a10 = _mm256_add_ps(a10, ra10);
    a01 = _mm256_fmadd_ps(ra00, e, a01);
    b00 = _mm256_add_ps(b00, rb00);
    b10 = _mm256_add_ps(b10, rb10);
    b01 = _mm256_fmadd_ps(rb00, e, b01);
    if constexpr (kQuad) {
      const __m256 e2 = Splat(static_cast<float>(eta * eta));
      a20 = _mm256_add_ps(a20, ra20);
      a11 = _mm256_fmadd_ps(ra10, e, a11);
      a02 = _mm256_fmadd_ps(ra00, e2, a02);
      b20 = _mm256_add_ps(b20, rb20);
      b11 = _mm256_fmadd_ps(rb10, e, b11);
      b02 = _mm256_fmadd_ps(rb00, e2, b02);
    }
  }
  out->sg = HorizontalSum(sg);
  out->sgg = HorizontalSum(sgg);
  out->sfg = HorizontalSum(sfg);
  out->a[0][0][0] = HorizontalSum(a00);
  out->a[0][1][0] = HorizontalSum(a10);
  out->a[0][0][1] = HorizontalSum(a01);
  out->a[1][0][0] = HorizontalSum(b00);
  out->a[1][1][0] = HorizontalSum(b10);
  out->a[1][0][1] = HorizontalSum(b01);
  if constexpr (kQuad) {
    out->a[0][2][0] = HorizontalSum(a20);
    out->a[0][1][1] = HorizontalSum(a11);
    out->a[0][0][2] = HorizontalSum(a02);
    out->a[1][2][0] = HorizontalSum(b20);
    out->a[1][1][1] = HorizontalSum(b11);
    out->a[1][0][2] = HorizontalSum(b02);
  }
}
#endif  // IMPACTDIC_DIC_AVX2

#if IMPACTDIC_DIC_AVX2
// The moments of PrepareSubset (gg[k][p][q] for p + q <= kPmax, gs and gf for p + q <= kPmax / 2,
// ss), 8 pixels at a time: per-lane float sums of a row weighted by powers of xi, folded into the
// per-lane subset sums with powers of eta at the end of each row, reduced once at the end.
template <int kPmax>
void MomentsAvx2(const MomentInput& in, MomentSums* out) {
  constexpr int kPs = kPmax / 2;
  const int h = in.half;
  const int size = 2 * h + 1;
  const __m256 lane = _mm256_setr_ps(0, 1, 2, 3, 4, 5, 6, 7);
  // Intensities are taken relative to the centre pixel K (one pass: the mean is not known yet);
  // the moments about the mean follow at the end.
  const float shift = in.f[h * in.stride + h];
  const __m256 zero = _mm256_setzero_ps(), m = Splat(shift);
  const __m256 full = Splat(static_cast<float>(in.full_scale)), one = Splat(1);
  __m256 SF = zero, SAT = zero;
  const int blocks = (size + 7) / 8;
  __m256 GG[3][kPmax + 1][kPmax + 1], GS[2][kPs + 1][kPs + 1], GF[2][kPs + 1][kPs + 1];
  __m256 SS = zero;
  // Powers of xi of the lanes of each block (the same for every row), and the mask of the last
  // block's lanes that the previous block did not cover.
  __m256 xi_pow[kMaxBlocks][kPmax + 1];
  for (int b = 0; b < blocks; ++b) {
    const int i0 = Min(8 * b, size - 8);
    const __m256 xi = _mm256_add_ps(lane, Splat(static_cast<float>(i0 - h)));
    xi_pow[b][0] = Splat(1);
    for (int p = 1; p <= kPmax; ++p) xi_pow[b][p] = _mm256_mul_ps(xi_pow[b][p - 1], xi);
  }
  const __m256 keep_last =
      _mm256_cmp_ps(lane, Splat(static_cast<float>(8 * (blocks - 1) - (size - 8))), _CMP_GE_OQ);
  for (auto& a : GG)
    for (auto& b : a)
      for (auto& c : b) c = zero;
  for (int a = 0; a < 2; ++a)
    for (int p = 0; p <= kPs; ++p)
      for (int q = 0; q <= kPs; ++q) GS[a][p][q] = GF[a][p][q] = zero;
  for (int j = 0; j < size; ++j) {
    const float* f = in.f + j * in.stride;
    const float* gxr = in.gx + j * in.stride;
    const float* gyr = in.gy + j * in.stride;
    __m256 rg[3][kPmax + 1], rs[2][kPs + 1], rf[2][kPs + 1];
    for (auto& a : rg)
      for (auto& b : a) b = zero;
    for (int a = 0; a < 2; ++a)
      for (int p = 0; p <= kPs; ++p) rs[a][p] = rf[a][p] = zero;
    for (int b = 0; b < blocks; ++b) {
      const int i0 = Min(8 * b, size - 8);
      __m256 fd = _mm256_sub_ps(_mm256_loadu_ps(f + i0), m);  // f - K.
      __m256 g[2] = {_mm256_loadu_ps(gxr + i0), _mm256_loadu_ps(gyr + i0)};
      const __m256 raw = _mm256_loadu_ps(f + i0);
      __m256 sat = _mm256_and_ps(
          _mm256_or_ps(_mm256_cmp_ps(raw, zero, _CMP_LE_OQ), _mm256_cmp_ps(raw, full, _CMP_GE_OQ)),
          one);
      if (i0 != 8 * b) {  // Mask the lanes of the previous block.
        fd = _mm256_and_ps(fd, keep_last);
        g[0] = _mm256_and_ps(g[0], keep_last);
        g[1] = _mm256_and_ps(g[1], keep_last);
        sat = _mm256_and_ps(sat, keep_last);
      }
      SF = _mm256_add_ps(SF, fd);
      SAT = _mm256_add_ps(SAT, sat);
      const __m256* xp = xi_pow[b];
      SS = _mm256_fmadd_ps(fd, fd, SS);
      const __m256 prod[3] = {_mm256_mul_ps(g[0], g[0]), _mm256_mul_ps(g[0], g[1]),
                              _mm256_mul_ps(g[1], g[1])};
      const __m256 lf[2] = {_mm256_mul_ps(g[0], fd), _mm256_mul_ps(g[1], fd)};
      for (int k = 0; k < 3; ++k) {
        rg[k][0] = _mm256_add_ps(rg[k][0], prod[k]);
        for (int p = 1; p <= kPmax; ++p) rg[k][p] = _mm256_fmadd_ps(prod[k], xp[p], rg[k][p]);
      }
      for (int a = 0; a < 2; ++a) {
        rs[a][0] = _mm256_add_ps(rs[a][0], g[a]);
        rf[a][0] = _mm256_add_ps(rf[a][0], lf[a]);
        for (int p = 1; p <= kPs; ++p) {
          rs[a][p] = _mm256_fmadd_ps(g[a], xp[p], rs[a][p]);
          rf[a][p] = _mm256_fmadd_ps(lf[a], xp[p], rf[a][p]);
        }
      }
    }
    const float eta = static_cast<float>(j - h);
    float ep = 1;
    for (int q = 0; q <= kPmax; ++q) {
      const __m256 e = Splat(ep);
      for (int p = 0; p + q <= kPmax; ++p) {
        for (int k = 0; k < 3; ++k) GG[k][p][q] = _mm256_fmadd_ps(rg[k][p], e, GG[k][p][q]);
        if (p + q <= kPs) {
          for (int a = 0; a < 2; ++a) {
            GS[a][p][q] = _mm256_fmadd_ps(rs[a][p], e, GS[a][p][q]);
            GF[a][p][q] = _mm256_fmadd_ps(rf[a][p], e, GF[a][p][q]);
          }
        }
      }
      ep *= eta;
    }
  }
  for (int q = 0; q <= kPmax; ++q) {
    for (int p = 0; p + q <= kPmax; ++p) {
      for (int k = 0; k < 3; ++k) out->gg[k][p][q] = HorizontalSum(GG[k][p][q]);
      if (p + q <= kPs) {
        for (int a = 0; a < 2; ++a) {
          out->gs[a][p][q] = HorizontalSum(GS[a][p][q]);
          out->gf[a][p][q] = HorizontalSum(GF[a][p][q]);
        }
      }
    }
  }
  // About the mean: sum g (f - mean) = sum g (f - K) - (mean - K) sum g, and
  // sum (f - mean)^2 = sum (f - K)^2 - N (mean - K)^2.
  const double count = double(size) * size, offset = HorizontalSum(SF) / count;
  out->mean = shift + offset;
  out->saturated = static_cast<int>(HorizontalSum(SAT));
  for (int a = 0; a < 2; ++a)
    for (int p = 0; p <= kPs; ++p)
      for (int q = 0; p + q <= kPs; ++q) out->gf[a][p][q] -= offset * out->gs[a][p][q];
  out->ss = Max(0.0, HorizontalSum(SS) - count * offset * offset);
}
#endif  // IMPACTDIC_DIC_AVX2

#if IMPACTDIC_DIC_AVX512
// The IC-GN pass 16 pixels at a time (AVX-512): as AccumulateAvx2, with blocks of 16 lanes
// starting at 0, 16, ... and the lanes past the row end masked (masked loads read nothing
// there), so a row of 25 pixels takes two blocks.
inline __m512 Splat16(float v) { return _mm512_set1_ps(v); }
// All lanes (the zero-masking forms of some intrinsics avoid a GCC 12 false
// -Wmaybe-uninitialized in the unmasked ones).
constexpr __mmask16 kAll = 0xFFFF;

// The lanes of a row of n pixels from pixel i on: all 16, or those before the row's end.
inline __mmask16 RowMask16(int n, int i) {
  return n - i >= 16 ? kAll : static_cast<__mmask16>((1u << (n - i)) - 1);
}

// The positions xi = i - h of the 16 pixels from pixel i on.
inline __m512 RowXi16(int i, int h) {
  return _mm512_add_ps(_mm512_setr_ps(0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15),
                       Splat16(static_cast<float>(i - h)));
}

// (c0 + xi (c1 + xi c2)) gx + (c3 + xi (c4 + xi c5)) gy, lane by lane (the row's polynomials
// of J dp or of the influences: Residuals, CorrelatedSums).
inline __m512 RowTerm16(const float* c, __m512 xi, __m512 gx, __m512 gy) {
  const __m512 px =
      _mm512_fmadd_ps(xi, _mm512_fmadd_ps(xi, Splat16(c[2]), Splat16(c[1])), Splat16(c[0]));
  const __m512 py =
      _mm512_fmadd_ps(xi, _mm512_fmadd_ps(xi, Splat16(c[5]), Splat16(c[4])), Splat16(c[3]));
  return _mm512_fmadd_ps(px, gx, _mm512_mul_ps(py, gy));
}

// Sum of the 16 lanes, in a fixed order.
inline double Sum16(__m512 v) {
  alignas(64) float lanes[16];
  _mm512_store_ps(lanes, v);
  float s = 0;
  for (float l : lanes) s += l;
  return s;
}

template <int kTaps>
inline void WeightsAvx512(__m512 t, __m512 w[kTaps]) {
  if constexpr (kTaps == 4) {
    const __m512 s = _mm512_sub_ps(Splat16(1), t);
    const __m512 t2 = _mm512_mul_ps(t, t), s2 = _mm512_mul_ps(s, s);
    const __m512 t3 = _mm512_mul_ps(t2, t), s3 = _mm512_mul_ps(s2, s);
    w[0] = s3;
    w[1] = _mm512_fmadd_ps(t3, Splat16(3), _mm512_fnmadd_ps(t2, Splat16(6), Splat16(4)));
    w[2] = _mm512_fmadd_ps(s3, Splat16(3), _mm512_fnmadd_ps(s2, Splat16(6), Splat16(4)));
    w[3] = t3;
  } else {
    for (int k = 0; k < 6; ++k) {
      __m512 v = Splat16(kQuinticC[k][5] / 120);
      for (int d = 4; d >= 0; --d) v = _mm512_fmadd_ps(v, t, Splat16(kQuinticC[k][d] / 120));
      w[k] = v;
    }
  }
}

// The B-spline (times kWeightScale^2) at the local positions (x, y) of the lanes in m, relative to
// `centre`; lanes outside m are 0 and read nothing. When the lanes' integer positions advance by
// one column along one row (the usual case), each tap is one unaligned load; otherwise the taps
// are gathered (the same expression in the same order).
template <int kTaps>
inline __m512 SampleBlock16(const float* centre, int istride, __m512 x, __m512 y, __mmask16 m) {
  constexpr int kLow = kTaps == 4 ? 1 : 2;
  const __m512i lane_i = _mm512_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15);
  const __m512 fx = _mm512_maskz_roundscale_ps(kAll, x, _MM_FROUND_TO_NEG_INF | _MM_FROUND_NO_EXC);
  const __m512 fy = _mm512_maskz_roundscale_ps(kAll, y, _MM_FROUND_TO_NEG_INF | _MM_FROUND_NO_EXC);
  const __m512 tx = _mm512_sub_ps(x, fx), ty = _mm512_sub_ps(y, fy);
  const __m512i ix = _mm512_maskz_cvttps_epi32(kAll, fx), iy = _mm512_maskz_cvttps_epi32(kAll, fy);
  const int ix0 = _mm512_cvtsi512_si32(ix), iy0 = _mm512_cvtsi512_si32(iy);
  const __mmask16 off =
      _mm512_mask_cmpneq_epi32_mask(m, ix, _mm512_add_epi32(_mm512_set1_epi32(ix0), lane_i)) |
      _mm512_mask_cmpneq_epi32_mask(m, iy, _mm512_set1_epi32(iy0));
  __m512 wx[kTaps], wy[kTaps], rs[kTaps];
  WeightsAvx512<kTaps>(tx, wx);
  WeightsAvx512<kTaps>(ty, wy);
  if (off == 0) {
    const float* c0 = centre + static_cast<std::ptrdiff_t>(iy0 - kLow) * istride + (ix0 - kLow);
    for (int r = 0; r < kTaps; ++r) {
      const float* cr = c0 + static_cast<std::ptrdiff_t>(r) * istride;
      rs[r] = _mm512_mul_ps(wx[0], _mm512_maskz_loadu_ps(m, cr));
      for (int k = 1; k < kTaps; ++k)
        rs[r] = _mm512_fmadd_ps(wx[k], _mm512_maskz_loadu_ps(m, cr + k), rs[r]);
    }
  } else {
    const __m512i off0 =
        _mm512_add_epi32(_mm512_mullo_epi32(_mm512_sub_epi32(iy, _mm512_set1_epi32(kLow)),
                                            _mm512_set1_epi32(istride)),
                         _mm512_sub_epi32(ix, _mm512_set1_epi32(kLow)));
    for (int r = 0; r < kTaps; ++r) {
      const __m512i offr = _mm512_add_epi32(off0, _mm512_set1_epi32(r * istride));
      auto tap = [&](int k) {
        return _mm512_mask_i32gather_ps(_mm512_setzero_ps(), m,
                                        _mm512_add_epi32(offr, _mm512_set1_epi32(k)), centre, 4);
      };
      rs[r] = _mm512_mul_ps(wx[0], tap(0));
      for (int k = 1; k < kTaps; ++k) rs[r] = _mm512_fmadd_ps(wx[k], tap(k), rs[r]);
    }
  }
  __m512 g = _mm512_mul_ps(wy[0], rs[0]);
  for (int r = 1; r < kTaps; ++r) g = _mm512_fmadd_ps(wy[r], rs[r], g);
  return g;
}

template <int kTaps, bool kQuad>
// NOLINTNEXTLINE(readability-function-size): a SIMD kernel, kept whole (docs/architecture.md)
void AccumulateAvx512(const PassInput& in, PassSums* out) {
  const int h = in.half, size = 2 * h + 1;
  const __m512 fm = Splat16(in.f_mean);
  const double* p = in.p;
  const double u = in.u, v = in.v;
  const float* centre = in.centre;
  const int blocks = (size + 15) / 16;
  const int istride = static_cast<int>(in.stride);
  constexpr float kScale2 = kWeightScale<kTaps> * kWeightScale<kTaps>;
  __m512 sg = _mm512_setzero_ps(), sgg = sg, sfg = sg;
  __m512 a00 = sg, a10 = sg, a01 = sg, b00 = sg, b10 = sg, b01 = sg;
  __m512 a20 = sg, a11 = sg, a02 = sg, b20 = sg, b11 = sg, b02 = sg;
  for (int j = 0; j < size; ++j) {
    const double eta = j - h;
    float ax0, ax1, ax2 = 0, ay0, ay1, ay2 = 0;
    if constexpr (kQuad) {
      ax0 = static_cast<float>(u + p[2] * eta + 0.5 * p[5] * eta * eta);
      ax1 = static_cast<float>(1 + p[1] + p[4] * eta);
      ax2 = static_cast<float>(0.5 * p[3]);
      ay0 = static_cast<float>(eta + v + p[8] * eta + 0.5 * p[11] * eta * eta);
      ay1 = static_cast<float>(p[7] + p[10] * eta);
      ay2 = static_cast<float>(0.5 * p[9]);
    } else {
      ax0 = static_cast<float>(u + p[2] * eta);
      ax1 = static_cast<float>(1 + p[1]);
      ay0 = static_cast<float>(eta + v + p[5] * eta);
      ay1 = static_cast<float>(p[4]);
    }
    const std::ptrdiff_t roff = j * in.ref_stride;
    const float* fr = in.f + roff;
    const float* gxr = in.gx + roff;
    const float* gyr = in.gy + roff;
    __m512 ra00 = _mm512_setzero_ps(), ra10 = ra00, ra20 = ra00, rb00 = ra00, rb10 = ra00,
           rb20 = ra00;
    for (int b = 0; b < blocks; ++b) {
      const int i0 = 16 * b;
      const __mmask16 m = RowMask16(size, i0);
      const __m512 xi = RowXi16(i0, h);
      __m512 x, y;
      if constexpr (kQuad) {
        x = _mm512_fmadd_ps(_mm512_fmadd_ps(xi, Splat16(ax2), Splat16(ax1)), xi, Splat16(ax0));
        y = _mm512_fmadd_ps(_mm512_fmadd_ps(xi, Splat16(ay2), Splat16(ay1)), xi, Splat16(ay0));
      } else {
        x = _mm512_fmadd_ps(xi, Splat16(ax1), Splat16(ax0));
        y = _mm512_fmadd_ps(xi, Splat16(ay1), Splat16(ay0));
      }
      const __m512 g = SampleBlock16<kTaps>(centre, istride, x, y, m);
      const __m512 gp = _mm512_maskz_fmsub_ps(m, g, Splat16(1 / kScale2), fm);
      _mm512_mask_storeu_ps(in.g_out + static_cast<std::ptrdiff_t>(j) * size + i0, m, gp);
      sg = _mm512_add_ps(sg, gp);
      sgg = _mm512_fmadd_ps(gp, gp, sgg);
      sfg = _mm512_fmadd_ps(_mm512_maskz_loadu_ps(m, fr + i0), gp, sfg);
      const __m512 a = _mm512_mul_ps(gp, _mm512_maskz_loadu_ps(m, gxr + i0));
      const __m512 bb = _mm512_mul_ps(gp, _mm512_maskz_loadu_ps(m, gyr + i0));
      ra00 = _mm512_add_ps(ra00, a);
      ra10 = _mm512_fmadd_ps(a, xi, ra10);
      rb00 = _mm512_add_ps(rb00, bb);
      rb10 = _mm512_fmadd_ps(bb, xi, rb10);
      if constexpr (kQuad) {
        ra20 = _mm512_fmadd_ps(_mm512_mul_ps(a, xi), xi, ra20);
        rb20 = _mm512_fmadd_ps(_mm512_mul_ps(bb, xi), xi, rb20);
      }
    }
    const __m512 e = Splat16(static_cast<float>(eta));
    a00 = _mm512_add_ps(a00, ra00);
    a10 = _mm512_add_ps(a10, ra10);
    a01 = _mm512_fmadd_ps(ra00, e, a01);
    b00 = _mm512_add_ps(b00, rb00);
    b10 = _mm512_add_ps(b10, rb10);
    b01 = _mm512_fmadd_ps(rb00, e, b01);
    if constexpr (kQuad) {
      const __m512 e2 = Splat16(static_cast<float>(eta * eta));
      a20 = _mm512_add_ps(a20, ra20);
      a11 = _mm512_fmadd_ps(ra10, e, a11);
      a02 = _mm512_fmadd_ps(ra00, e2, a02);
      b20 = _mm512_add_ps(b20, rb20);
      b11 = _mm512_fmadd_ps(rb10, e, b11);
      b02 = _mm512_fmadd_ps(rb00, e2, b02);
    }
  }
  out->sg = Sum16(sg);
  out->sgg = Sum16(sgg);
  out->sfg = Sum16(sfg);
  out->a[0][0][0] = Sum16(a00);
  out->a[0][1][0] = Sum16(a10);
  out->a[0][0][1] = Sum16(a01);
  out->a[1][0][0] = Sum16(b00);
  out->a[1][1][0] = Sum16(b10);
  out->a[1][0][1] = Sum16(b01);
  if constexpr (kQuad) {
    out->a[0][2][0] = Sum16(a20);
    out->a[0][1][1] = Sum16(a11);
    out->a[0][0][2] = Sum16(a02);
    out->a[1][2][0] = Sum16(b20);
    out->a[1][1][1] = Sum16(b11);
    out->a[1][0][2] = Sum16(b02);
  }
}
#endif  // IMPACTDIC_DIC_AVX512

// The reference moments one pixel at a time (double sums, about the mean of a first pass).
void MomentsScalar(const MomentInput& in, MomentSums* out) {
  const int h = in.half, size = 2 * h + 1, pmax = in.pmax;
  double sum = 0;
  int saturated = 0;
  for (int j = 0; j < size; ++j) {
    const float* f = in.f + j * in.stride;
    for (int i = 0; i < size; ++i) {
      sum += f[i];
      saturated += (f[i] <= 0 || f[i] >= in.full_scale) ? 1 : 0;
    }
  }
  const double mean = sum / (double(size) * size);
  out->mean = mean;
  out->saturated = saturated;
  for (int j = 0; j < size; ++j) {
    const double eta = j - h;
    const float* f = in.f + j * in.stride;
    const float* gx = in.gx + j * in.stride;
    const float* gy = in.gy + j * in.stride;
    double rg[3][5] = {}, rs[2][3] = {}, rf[2][3] = {};
    for (int i = 0; i < size; ++i) {
      const double xi = i - h, fd = f[i] - mean;
      out->ss += fd * fd;
      const double g[2] = {gx[i], gy[i]};
      const double prod[3] = {g[0] * g[0], g[0] * g[1], g[1] * g[1]};
      double xp = 1;
      for (int p = 0; p <= pmax; ++p) {
        for (int k = 0; k < 3; ++k) rg[k][p] += prod[k] * xp;
        if (p <= 2) {
          for (int a = 0; a < 2; ++a) {
            rs[a][p] += g[a] * xp;
            rf[a][p] += g[a] * fd * xp;
          }
        }
        xp *= xi;
      }
    }
    double ep = 1;
    for (int q = 0; q <= pmax; ++q) {
      for (int p = 0; p + q <= pmax; ++p) {
        for (int k = 0; k < 3; ++k) out->gg[k][p][q] += rg[k][p] * ep;
        if (p + q <= 2) {
          for (int a = 0; a < 2; ++a) {
            out->gs[a][p][q] += rs[a][p] * ep;
            out->gf[a][p][q] += rf[a][p] * ep;
          }
        }
      }
      ep *= eta;
    }
  }
}

// The moments into out (zeroed by the caller): 8 pixels at a time with AVX2 for subset rows of 8
// to 8 kMaxBlocks pixels, else one at a time.
void Moments(const MomentInput& in, MomentSums* out) {
#if IMPACTDIC_DIC_AVX2
  const int size = 2 * in.half + 1;
  if (size >= 8 && size <= 8 * kMaxBlocks) {
    if (in.pmax == 2)
      MomentsAvx2<2>(in, out);
    else
      MomentsAvx2<4>(in, out);
    return;
  }
#endif
  MomentsScalar(in, out);
}

// One IC-GN pass: the vectorised pass where it is compiled in and the subset is at least 8 px
// wide, else one pixel at a time.
template <int kTaps, bool kQuad>
void Pass(const PassInput& in, PassSums* out) {
#if IMPACTDIC_DIC_AVX512
  if (2 * in.half + 1 >= 8) {
    AccumulateAvx512<kTaps, kQuad>(in, out);
    return;
  }
#elif IMPACTDIC_DIC_AVX2
  if (2 * in.half + 1 >= 8) {
    AccumulateAvx2<kTaps, kQuad>(in, out);
    return;
  }
#endif
  AccumulateScalar<kTaps, kQuad>(in, out);
}

// sum_k term(k) over k = 0 .. length - 1 (a multiple of kResidualLanes) in kResidualLanes float
// lanes (which the compiler maps onto the unit's vector registers), added up in a fixed order.
// a[l] += a[l + kW] for l < kW, then the same with kW / 2, ..., 1: a[0] is the sum of the 2 kW
// lanes, in a fixed order (each step one vector addition where the unit has the width).
template <int kW>
inline void FoldLanes(float* a) {
  for (int l = 0; l < kW; ++l) a[l] += a[l + kW];
  if constexpr (kW > 1) FoldLanes<kW / 2>(a);
}

#if IMPACTDIC_DIC_AVX512
static_assert(kResidualLanes == 16, "FoldLanes16 folds one AVX-512 register");
// FoldLanes<8> of the 16 lanes of v, in its order: lane l + lane l + 8, then + 4, + 2, + 1.
inline float FoldLanes16(__m512 v) {
  const __m256 h8 = _mm256_add_ps(_mm512_maskz_extractf32x8_ps(0xFF, v, 0),
                                  _mm512_maskz_extractf32x8_ps(0xFF, v, 1));
  const __m128 h4 = _mm_add_ps(_mm256_castps256_ps128(h8), _mm256_extractf128_ps(h8, 1));
  const __m128 h2 = _mm_add_ps(h4, _mm_movehl_ps(h4, h4));
  return _mm_cvtss_f32(_mm_add_ss(h2, _mm_shuffle_ps(h2, h2, 1)));
}
#endif

template <int kTerms, typename Term>
void LaneSums(int length, Term term, double sums[kTerms]) {
  float acc[kTerms][kResidualLanes] = {};
  for (int k = 0; k < length; k += kResidualLanes) {
    for (int l = 0; l < kResidualLanes; ++l) {
      float t[kTerms] = {};
      term(k + l, t);
      for (int q = 0; q < kTerms; ++q) acc[q][l] += t[q];
    }
  }
  for (int q = 0; q < kTerms; ++q) {
    FoldLanes<kResidualLanes / 2>(acc[q]);
    sums[q] = acc[q][0];
  }
}

void Residuals(const ResidualInput& in, float* r, double noise[2]) {
  const int size = 2 * in.half + 1, stride = in.stride;
  float* rs = r + in.lead;
  const float fm = in.f_mean, gm = in.g_mean, ratio = in.ratio;
  const int h = in.half;
  for (int j = 0; j < size; ++j) {
    const std::ptrdiff_t roff = static_cast<std::ptrdiff_t>(j) * in.ref_stride;
    const float* f = in.f + roff;
    const float* gx = in.gx + roff;
    const float* gy = in.gy + roff;
    const float* g = in.g + static_cast<std::ptrdiff_t>(j) * size;
    const float* c = in.step + static_cast<std::ptrdiff_t>(6) * j;
    float* rj = rs + static_cast<std::ptrdiff_t>(j) * stride;
#if IMPACTDIC_DIC_AVX512
    // 16 pixels at a time, the lanes past the row's end masked (its padding stays zero).
    for (int i = 0; i < size; i += 16) {
      const __mmask16 m = RowMask16(size, i);
      const __m512 own = _mm512_fnmadd_ps(
          Splat16(ratio), _mm512_sub_ps(_mm512_maskz_loadu_ps(m, g + i), Splat16(gm)),
          _mm512_sub_ps(_mm512_maskz_loadu_ps(m, f + i), Splat16(fm)));
      const __m512 step = RowTerm16(c, RowXi16(i, h), _mm512_maskz_loadu_ps(m, gx + i),
                                    _mm512_maskz_loadu_ps(m, gy + i));
      _mm512_mask_storeu_ps(rj + i, m, _mm512_add_ps(own, step));
    }
#else
    for (int i = 0; i < size; ++i) {
      const float xi = static_cast<float>(i - h);
      rj[i] = ((f[i] - fm) - ratio * (g[i] - gm)) +
              ((c[0] + xi * (c[1] + xi * c[2])) * gx[i] + (c[3] + xi * (c[4] + xi * c[5])) * gy[i]);
    }
#endif
  }
  const float* xm = in.x_inside + in.lead;
  const float* ym = in.y_inside + in.lead;
#if IMPACTDIC_DIC_AVX512
  // As LaneSums<2> below: lane l sums the cells l, l + 16, ... in order, then the lanes fold.
  __m512 ax = _mm512_setzero_ps(), ay = _mm512_setzero_ps();
  for (int k = 0; k < in.length; k += 16) {
    const __m512 dx = _mm512_sub_ps(_mm512_loadu_ps(rs + k + 1), _mm512_loadu_ps(rs + k - 1));
    const __m512 dy =
        _mm512_sub_ps(_mm512_loadu_ps(rs + k + stride), _mm512_loadu_ps(rs + k - stride));
    ax = _mm512_fmadd_ps(_mm512_loadu_ps(xm + k), _mm512_mul_ps(dx, dx), ax);
    ay = _mm512_fmadd_ps(_mm512_loadu_ps(ym + k), _mm512_mul_ps(dy, dy), ay);
  }
  noise[0] = FoldLanes16(ax);
  noise[1] = FoldLanes16(ay);
#else
  LaneSums<2>(
      in.length,
      [&](int k, float t[2]) {
        const float dx = rs[k + 1] - rs[k - 1], dy = rs[k + stride] - rs[k - stride];
        t[0] = xm[k] * (dx * dx);
        t[1] = ym[k] * (dy * dy);
      },
      noise);
#endif
}

// The influences, then sum_d rho(d) A(d) over all lags d with |dx|, |dy| <= kResidualLagPx
// (d = 0 included): the variance of u and v per unit residual variance.
void CorrelatedSums(const ResidualInput& in, const float* r, const float* coef, float* au,
                    float* av, double sums[2]) {
  const int h = in.half, size = 2 * h + 1, stride = in.stride, count = size * size;
  const float* rs = r + in.lead;
  float* us = au + in.lead;
  float* vs = av + in.lead;
  for (int j = 0; j < size; ++j) {
    const float* gx = in.gx + static_cast<std::ptrdiff_t>(j) * in.ref_stride;
    const float* gy = in.gy + static_cast<std::ptrdiff_t>(j) * in.ref_stride;
    const float* c = coef + static_cast<std::ptrdiff_t>(12) * j;
    float* uj = us + static_cast<std::ptrdiff_t>(j) * stride;
    float* vj = vs + static_cast<std::ptrdiff_t>(j) * stride;
#if IMPACTDIC_DIC_AVX512
    for (int i = 0; i < size; i += 16) {  // As Residuals.
      const __mmask16 m = RowMask16(size, i);
      const __m512 xi = RowXi16(i, h);
      const __m512 x = _mm512_maskz_loadu_ps(m, gx + i), y = _mm512_maskz_loadu_ps(m, gy + i);
      _mm512_mask_storeu_ps(uj + i, m, RowTerm16(c, xi, x, y));
      _mm512_mask_storeu_ps(vj + i, m, RowTerm16(c + 6, xi, x, y));
    }
#else
    for (int i = 0; i < size; ++i) {
      const float xi = static_cast<float>(i - h);
      uj[i] = (c[0] + xi * (c[1] + xi * c[2])) * gx[i] + (c[3] + xi * (c[4] + xi * c[5])) * gy[i];
      vj[i] = (c[6] + xi * (c[7] + xi * c[8])) * gx[i] + (c[9] + xi * (c[10] + xi * c[11])) * gy[i];
    }
#endif
  }
  // The lags d with dy > 0, or dy == 0 and dx >= 0 (d = 0 first), each standing for itself and
  // its opposite -d: all kLags sums of one array in one sweep, each cell loaded once and multiplied
  // by its kLags partners.
  constexpr int kL = kResidualLagPx, kLags = 1 + kL + kL * (2 * kL + 1);
#if IMPACTDIC_DIC_AVX512
  // The same sums in registers: one load of x per 16 cells, one FMA per lag, each lag's lanes
  // folded as FoldLanes folds them (the same sums, bit for bit, without the generic version's
  // stack array: its zeroing and its folds through memory were a fifth of the function).
  int offset[kLags];
  {
    int q = 0;
    for (int dx = 0; dx <= kL; ++dx) offset[q++] = dx;
    for (int dy = 1; dy <= kL; ++dy)
      for (int dx = -kL; dx <= kL; ++dx) offset[q++] = dy * stride + dx;
  }
  const auto lags = [&](const float* x, double out[kLags]) {
    __m512 acc[kLags];
    for (int q = 0; q < kLags; ++q) acc[q] = _mm512_setzero_ps();
    for (int k = 0; k < in.length; k += 16) {
      const __m512 xk = _mm512_loadu_ps(x + k);
      for (int q = 0; q < kLags; ++q)
        acc[q] = _mm512_fmadd_ps(xk, _mm512_loadu_ps(x + k + offset[q]), acc[q]);
    }
    for (int q = 0; q < kLags; ++q) out[q] = FoldLanes16(acc[q]);
  };
#else
  const auto lags = [&](const float* x, double out[kLags]) {
    LaneSums<kLags>(
        in.length,
        [&](int k, float t[kLags]) {
          const float xk = x[k];
          int q = 0;
          for (int dx = 0; dx <= kL; ++dx) t[q++] = xk * x[k + dx];
          for (int dy = 1; dy <= kL; ++dy) {
            const float* row = x + static_cast<std::ptrdiff_t>(dy) * stride;
            for (int dx = -kL; dx <= kL; ++dx) t[q++] = xk * row[k + dx];
          }
        },
        out);
  };
#endif
  double rr[kLags], uu[kLags], vv[kLags];
  lags(rs, rr);
  lags(us, uu);
  lags(vs, vv);
  const double c0 = rr[0] / count;
  sums[0] = uu[0];
  sums[1] = vv[0];
  if (!(c0 > 0)) return;
  // Each lag d and its opposite -d once, counted twice.
  int q = 1;
  for (int dy = 0; dy <= kL; ++dy) {
    for (int dx = dy == 0 ? 1 : -kL; dx <= kL; ++dx, ++q) {
      const int adx = dx < 0 ? -dx : dx;
      const double rho = rr[q] / (double(size - adx) * (size - dy)) / c0;
      sums[0] += 2 * rho * uu[q];
      sums[1] += 2 * rho * vv[q];
    }
  }
}

}  // namespace

// This unit's kernel.
const IcgnKernel* Kernel() {
  static constexpr IcgnKernel kKernel{
      .kind = IMPACTDIC_DIC_KERNEL_LEVEL == 0   ? DicKernel::kScalar
              : IMPACTDIC_DIC_KERNEL_LEVEL == 1 ? DicKernel::kAvx2
                                                : DicKernel::kAvx512,
      .accumulate = {{Pass<4, false>, Pass<4, true>}, {Pass<6, false>, Pass<6, true>}},
      .moments = Moments,
      .residuals = Residuals,
      .correlated_sums = CorrelatedSums,
  };
  return &kKernel;
}

}  // namespace impactdic::internal::IMPACTDIC_DIC_KERNEL_NS

#undef IMPACTDIC_DIC_AVX2
#undef IMPACTDIC_DIC_AVX512
