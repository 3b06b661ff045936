// Internal to the render kernels: the AVX2 lanes' rules on whole 16-pixel tile rows, one row per AVX-512
// register (its two 8-pixel groups; a group the culling dropped is masked off). Same operations per lane, and
// each half of a row feeds its own lane-sum set, so images and gradients are bit-identical to the AVX2 and
// portable loops.
#pragma once
#include "render/lanes.h"

#ifdef ISPLAT_HAVE_AVX2_LANES
#define ISPLAT_AVX512 __attribute__((target("avx512f,avx512dq,avx512vl,avx2,fma"), always_inline)) inline
#define ISPLAT_AVX512_FN __attribute__((target("avx512f,avx512dq,avx512vl,avx2,fma")))

namespace isplat::splat {

static_assert(kTile == 2 * kLanes, "the AVX-512 loops take a tile row as two 8-pixel groups");

struct Avx512Splat {
  __m512 u, a2, opac, ncut, f[7];
};
struct Avx512Plane {
  __m512 iz0, gx, gy, zlo, izmin;
};
ISPLAT_AVX512 Avx512Plane avx512_plane(const DepthPlane<float>& p) {
  return {_mm512_set1_ps(p.iz0), _mm512_set1_ps(p.gx), _mm512_set1_ps(p.gy), _mm512_set1_ps(p.zlo),
          _mm512_set1_ps(p.izmin)};
}
ISPLAT_AVX512 Avx512Splat avx512_splat(const Splat<float>& s, int channels) {
  Avx512Splat a;
  a.u = _mm512_set1_ps(s.u), a.a2 = _mm512_set1_ps(s.a2);
  a.opac = _mm512_set1_ps(s.opac), a.ncut = _mm512_set1_ps(s.ncut);
  for (int c = 0; c < channels; ++c) a.f[c] = _mm512_set1_ps(s.f[c]);
  return a;
}

ISPLAT_AVX512 __m512 avx512_neg(__m512 x) {
  return _mm512_xor_ps(x, _mm512_set1_ps(-0.0f));
}

// avx2_exp2, 16 lanes; scalef multiplies by 2^n exactly.
ISPLAT_AVX512 __m512 avx512_exp2(__m512 y) {
  y = _mm512_max_ps(y, _mm512_set1_ps(kExp2Floor));
  const __m512 n = _mm512_roundscale_ps(y, _MM_FROUND_TO_NEAREST_INT | _MM_FROUND_NO_EXC), r = _mm512_sub_ps(y, n);
  __m512 p = _mm512_set1_ps(kExp2Poly[0]);
  for (int k = 1; k < 6; ++k) p = _mm512_fmadd_ps(p, r, _mm512_set1_ps(kExp2Poly[k]));
  return _mm512_scalef_ps(p, n);
}

// 16 lanes of one Gaussian: two 8-pixel groups, the low half on tile row r[0], the high half on r[1]. Row jobs
// (kRow) are a whole tile row, r[1] = r[0], one contiguous block per plane; a group the culling dropped is
// masked off in `lanes`. Pair jobs are two consecutive groups of a narrow Gaussian's list (one group per row, all
// in the same column): their state is loaded and stored in halves.
struct Job {
  int32_t r[2];
  __mmask16 lanes;
};
// What the jobs of one Gaussian in a tile share: its rows' terms, and the tile column and image column of lane 0
// (of both halves, for pair jobs).
struct JobSet {
  const TileRows& rows;
  int32_t col, xb;
  int32_t pixel(const Job& j, int half) const { return j.r[half] * kTile + col; }  // tile pixel of the half's lane 0
};
// make_row's terms of the tile's 16 rows; returns dy.
ISPLAT_AVX512 __m512 row_terms(const Splat<float>& s, int64_t y0, TileRows& t) {
  const __m512 lane = _mm512_setr_ps(0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15);
  const __m512 dy =  // T(py) + T(0.5) − v, with py = y0 + lane exactly
      _mm512_sub_ps(_mm512_add_ps(_mm512_add_ps(_mm512_set1_ps(float(y0)), lane), _mm512_set1_ps(0.5f)),
                    _mm512_set1_ps(s.v));
  const __m512 nb = _mm512_mul_ps(_mm512_set1_ps(s.nbk), dy);
  const __m512 nc = _mm512_mul_ps(_mm512_mul_ps(_mm512_set1_ps(s.nck), dy), dy);
  _mm512_store_ps(t.dy, dy), _mm512_store_ps(t.nb, nb), _mm512_store_ps(t.nc, nc);
  return dy;
}
ISPLAT_AVX512 void tile_rows(const Splat<float>& s, int64_t x0, int64_t y0, int64_t ys, int64_t ye, int64_t g0,
                             int64_t g1, const LiveGroups& live, TileRows& t) {
  const __m512 dy = row_terms(s, y0, t), nb = _mm512_load_ps(t.nb), nc = _mm512_load_ps(t.nc);
  const unsigned rows = box_rows(y0, ys, ye);
  const __m512 at_min = _mm512_mul_ps(_mm512_set1_ps(s.beta), dy), a2 = _mm512_set1_ps(s.a2);
  for (int g = 0; g < 2; ++g) {
    t.groups[g] = 0;
    if (g < g0 || g >= g1) continue;
    const float lo = group_dx0(s, x0 + g * kLanes), hi = lo + float(kLanes - 1);
    const __m512 dx = _mm512_min_ps(_mm512_max_ps(at_min, _mm512_set1_ps(lo)), _mm512_set1_ps(hi));
    const __m512 q = _mm512_fmadd_ps(_mm512_fmadd_ps(a2, dx, nb), dx, nc);
    t.groups[g] = rows & live.half[g] & unsigned(_mm512_cmp_ps_mask(q, _mm512_set1_ps(s.ncut_wide), _CMP_GE_OQ));
  }
}

// pixel_box (tile_loop.h) of up to 16 consecutive float records at once, on vectors and in double as pixel_box
// computes it, so every box is the one the scalar code gives. (Splat::prepare's constants done the same way, with
// four more gathers, made the forward slower.)
struct PixelBoxes {
  // Per entry, its box packed into one word: bits 0-3 ys − y0, 4-8 ye − y0, 9 g0, 10-11 g1, 12 the box is not empty.
  alignas(64) uint32_t box[16];
  bool unpack(int k, int64_t y0, int64_t& ys, int64_t& ye, int64_t& g0, int64_t& g1) const {
    const uint32_t b = box[k];
    ys = y0 + int64_t(b & 15u), ye = y0 + int64_t((b >> 4) & 31u), g0 = int64_t((b >> 9) & 1u),
    g1 = int64_t((b >> 10) & 3u);
    return (b >> 12) & 1u;
  }
};
// The box's [lo, hi) along one axis for 8 records, tile span [a, b): pixel_box's lo and hi.
ISPLAT_AVX512 void axis_span(__m512d m, __m512d r, int64_t a, int64_t b, __m256i& lo, __m256i& hi) {
  const __m512d da = _mm512_set1_pd(double(a)), db = _mm512_set1_pd(double(b)), half = _mm512_set1_pd(0.5);
  // ifloor of a value clamped to a small range is floor: both give the same integer. Each side is also clamped on
  // its other end (lo to b + 1, hi to a − 1), so an int32 holds it; a box that clamp touches is empty either way.
  // (A NaN extent, which the projection culls, gives an empty box.)
  const __m512d below = _mm512_sub_pd(da, _mm512_set1_pd(1.0)), above = _mm512_add_pd(db, _mm512_set1_pd(1.0));
  const __m512d lo_at = _mm512_sub_pd(_mm512_sub_pd(m, r), half), hi_at = _mm512_sub_pd(_mm512_add_pd(m, r), half);
  const __m512d l = _mm512_roundscale_pd(_mm512_min_pd(_mm512_max_pd(lo_at, below), above),
                                         _MM_FROUND_TO_NEG_INF | _MM_FROUND_NO_EXC);
  const __m512d h = _mm512_roundscale_pd(_mm512_min_pd(_mm512_max_pd(hi_at, below), above),
                                         _MM_FROUND_TO_NEG_INF | _MM_FROUND_NO_EXC);
  lo = _mm512_cvtpd_epi32(_mm512_max_pd(da, l));
  hi = _mm512_cvtpd_epi32(_mm512_min_pd(db, _mm512_add_pd(h, _mm512_set1_pd(1.0))));
}
// The boxes of the n ≥ 1 records from `rec` (at most 16 are read) in tile (x0, y0, x1, y1).
ISPLAT_AVX512 void pixel_boxes(const float* rec, int64_t n, int64_t x0, int64_t y0, int64_t x1, int64_t y1,
                               PixelBoxes& out) {
  const __mmask16 in = __mmask16(n >= 16 ? 0xffffu : (1u << n) - 1u);
  const __m512i at = _mm512_mullo_epi32(_mm512_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15),
                                        _mm512_set1_epi32(kRec));
  enum { U, V, RX, RY };
  const int fields[4] = {kU, kV, kRx, kRy};
  __m512 f[4];  // each record's fields (entries past n: 0, unused)
  for (int k = 0; k < 4; ++k)
    f[k] =
        _mm512_mask_i32gather_ps(_mm512_setzero_ps(), in, _mm512_add_epi32(at, _mm512_set1_epi32(fields[k])), rec, 4);
  __m256i span[4][2];  // ys, ye, xs, xe of each half
  for (int h = 0; h < 2; ++h) {
    __m512d d[4];
    for (int k = 0; k < 4; ++k)
      d[k] = _mm512_cvtps_pd(h == 0 ? _mm512_castps512_ps256(f[k]) : _mm512_extractf32x8_ps(f[k], 1));
    axis_span(d[V], d[RY], y0, y1, span[0][h], span[1][h]);
    axis_span(d[U], d[RX], x0, x1, span[2][h], span[3][h]);
  }
  __m512i joined[4];
  for (int k = 0; k < 4; ++k) joined[k] = _mm512_inserti32x8(_mm512_castsi256_si512(span[k][0]), span[k][1], 1);
  const __m512i Ys = joined[0], Ye = joined[1], Xs = joined[2], Xe = joined[3];
  const __mmask16 nonempty = in & _mm512_cmplt_epi32_mask(Ys, Ye) & _mm512_cmplt_epi32_mask(Xs, Xe);
  const __m512i X0 = _mm512_set1_epi32(int32_t(x0)), Y0 = _mm512_set1_epi32(int32_t(y0));
  const __m512i g0 = _mm512_srli_epi32(_mm512_sub_epi32(Xs, X0), 3);  // xs ≥ x0
  const __m512i g1 = _mm512_add_epi32(
      _mm512_srli_epi32(_mm512_sub_epi32(_mm512_sub_epi32(Xe, X0), _mm512_set1_epi32(1)), 3), _mm512_set1_epi32(1));
  __m512i b = _mm512_or_si512(_mm512_sub_epi32(Ys, Y0), _mm512_slli_epi32(_mm512_sub_epi32(Ye, Y0), 4));
  b = _mm512_or_si512(b, _mm512_or_si512(_mm512_slli_epi32(g0, 9), _mm512_slli_epi32(g1, 10)));
  b = _mm512_mask_or_epi32(_mm512_setzero_si512(), nonempty, b, _mm512_set1_epi32(1 << 12));
  _mm512_store_si512(out.box, b);
}

// unstopped_groups on vectors: one tile row's T plane per register.
ISPLAT_AVX512 LiveGroups unstopped_groups_avx512(const float* st) {
  unsigned m[2] = {0, 0};
  for (int r = 0; r < kTile; ++r) {
    const unsigned lanes =
        _mm512_cmp_ps_mask(_mm512_loadu_ps(st + fwd_at(r * kTile, kPlT)), _mm512_setzero_ps(), _CMP_GT_OQ);
    m[0] |= unsigned((lanes & 0x00ffu) != 0) << r, m[1] |= unsigned((lanes & 0xff00u) != 0) << r;
  }
  LiveGroups live;
  live.half[0] = m[0], live.half[1] = m[1];
  return live;
}

// GroupLast::live_for on vectors.
ISPLAT_AVX512 LiveGroups live_for_avx512(const GroupLast& gl, int32_t i) {
  const __m512i at = _mm512_set1_epi32(i);
  LiveGroups live;
  for (int h = 0; h < 2; ++h) live.half[h] = _mm512_cmpgt_epi32_mask(_mm512_load_si512(gl.half[h]), at);
  return live;
}

// A Gaussian's jobs in a tile: the rows to visit in order, compressed from a row mask in one vector step (no loop,
// so no branch to mispredict on the number of rows).
struct JobList {
  alignas(64) int32_t row[kTile];
  alignas(64) int32_t lanes[kTile];  // row jobs: the lane mask of each row
  int rows = 0;
  // Job k: row k of the list (row jobs), or rows 2k and 2k + 1 (pair jobs; a last odd row has its high half
  // masked off, see pair_jobs).
  template <bool kRow>
  ISPLAT_AVX512 Job at(int k) const {
    if constexpr (kRow) return {{row[k], row[k]}, __mmask16(lanes[k])};
    return {{row[2 * k], row[2 * k + 1]}, __mmask16(2 * k + 1 < rows ? 0xffff : 0x00ff)};
  }
};
ISPLAT_AVX512 void compress_rows(unsigned mask, JobList& out) {
  const __m512i index = _mm512_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15);
  _mm512_store_si512(out.row, _mm512_maskz_compress_epi32(__mmask16(mask), index));
  out.rows = __builtin_popcount(mask);
}
// Row jobs, for a Gaussian that may reach both groups of the tile's rows: every row with a group to visit.
// Returns the number of jobs.
ISPLAT_AVX512 int row_jobs(const TileRows& t, JobList& out) {
  const unsigned m = t.groups[0] | t.groups[1];
  compress_rows(m, out);
  const __m512i lanes = _mm512_or_si512(_mm512_maskz_mov_epi32(__mmask16(t.groups[0]), _mm512_set1_epi32(0x00ff)),
                                        _mm512_maskz_mov_epi32(__mmask16(t.groups[1]), _mm512_set1_epi32(0xff00)));
  _mm512_store_si512(out.lanes, _mm512_maskz_compress_epi32(__mmask16(m), lanes));
  return out.rows;
}
// Pair jobs, for a Gaussian within the column of group g: its groups in row order, two per job; returns the number
// of jobs. A last unpaired group is a job whose masked high half names another row of the tile: a job loads and
// stores its halves in turn, so that row's state is stored back as it was loaded, and its lanes add exact zeros
// to the sums (as a group left out would).
ISPLAT_AVX512 int pair_jobs(const TileRows& t, int g, JobList& out) {
  compress_rows(t.groups[g], out);
  if (out.rows & 1) out.row[out.rows] = out.row[out.rows - 1] ^ 1;  // rows < 16 here
  return (out.rows + 1) / 2;
}

// A job's pixel state: plane k of its low (high) half starts at b[0] (b[1]) + k·kTile (plane_at's layout), so each
// load or store is one add away from these.
template <int kPlanes>
struct JobPlanes {
  float* b[2];
  ISPLAT_AVX512 JobPlanes(float* st, const JobSet& s, const Job& j)
      : b{st + plane_at<kPlanes>(s.pixel(j, 0), 0), st + plane_at<kPlanes>(s.pixel(j, 1), 0)} {}
  template <bool kRow>
  ISPLAT_AVX512 __m512 load(int plane) const {
    if constexpr (kRow) return _mm512_loadu_ps(b[0] + plane * kTile);
    return _mm512_insertf32x8(_mm512_castps256_ps512(_mm256_loadu_ps(b[0] + plane * kTile)),
                              _mm256_loadu_ps(b[1] + plane * kTile), 1);
  }
  template <bool kRow>
  ISPLAT_AVX512 void store(int plane, __m512 v) const {
    if constexpr (kRow) {
      _mm512_storeu_ps(b[0] + plane * kTile, v);
    } else {
      _mm256_storeu_ps(b[0] + plane * kTile, _mm512_castps512_ps256(v));
      _mm256_storeu_ps(b[1] + plane * kTile, _mm512_extractf32x8_ps(v, 1));
    }
  }
};
template <bool kRow>
ISPLAT_AVX512 __m512i job_load_last(const int32_t* last, const JobSet& s, const Job& j) {
  const int32_t* l0 = last + s.pixel(j, 0);
  if constexpr (kRow) return _mm512_loadu_si512(l0);
  return _mm512_inserti32x8(_mm512_castsi256_si512(_mm256_loadu_si256(reinterpret_cast<const __m256i*>(l0))),
                            _mm256_loadu_si256(reinterpret_cast<const __m256i*>(last + s.pixel(j, 1))), 1);
}
// A row term per lane: one value for a row job, the two rows' for a pair job.
using RowTerm = float (TileRows::*)[kTile];
template <bool kRow>
ISPLAT_AVX512 __m512 job_term(const JobSet& s, const Job& j, RowTerm term) {
  const float* v = s.rows.*term;
  if constexpr (kRow) return _mm512_set1_ps(v[j.r[0]]);
  return _mm512_insertf32x8(_mm512_set1_ps(v[j.r[0]]), _mm256_set1_ps(v[j.r[1]]), 1);
}

// avx2_neg_power for the 16 lanes of job j: pixel centres at image columns xb + lane + 0.5 (rows) or
// xb + lane mod 8 + 0.5 (pairs); every term is an integer or half-integer far below 2^23, so each sum is exact.
template <bool kRow>
ISPLAT_AVX512 void avx512_neg_power(const Avx512Splat& a, const JobSet& s, const Job& j, __m512& dx, __m512& npow) {
  const __m512 lane = kRow ? _mm512_setr_ps(0.5f, 1.5f, 2.5f, 3.5f, 4.5f, 5.5f, 6.5f, 7.5f, 8.5f, 9.5f, 10.5f, 11.5f,
                                            12.5f, 13.5f, 14.5f, 15.5f)
                           : _mm512_setr_ps(0.5f, 1.5f, 2.5f, 3.5f, 4.5f, 5.5f, 6.5f, 7.5f, 0.5f, 1.5f, 2.5f, 3.5f,
                                            4.5f, 5.5f, 6.5f, 7.5f);
  dx = _mm512_sub_ps(_mm512_add_ps(_mm512_set1_ps(float(s.xb)), lane), a.u);
  npow = _mm512_fmadd_ps(_mm512_fmadd_ps(a.a2, dx, job_term<kRow>(s, j, &TileRows::nb)), dx,
                         job_term<kRow>(s, j, &TileRows::nc));
}

// What the probes of fwd_tile_generic measure, on vectors (kChannels 0): the entry's largest weight so far
// (max_weight), and each tile pixel's median depth, 0 until found (median_depth).
struct ProbeOut {
  __m512 max_weight;
  float* median;
};

// fwd_groups_avx2 on the N jobs k0, ..., k0 + N − 1 of q; returns the lanes that stopped, OR-ed over the jobs (nonzero
// if any). Adds to `hits` the groups where a pixel was composited (RasterOutput::group_hits' bits). kProbe as in
// fwd_tile_generic: max_weight takes the largest weight of the composited lanes into probe.max_weight; median_depth
// gives a pixel whose transmittance this Gaussian takes to 0.5 or less its depth in probe.median and stops it there.
template <int N, int kChannels, bool kPlane, bool kRow, Probe kProbe = Probe::none>
ISPLAT_AVX512 unsigned fwd_jobs_avx512(const Avx512Splat& a, const Avx512Plane& plane, const JobSet& s,
                                       const JobList& q, int k0, float* st, int32_t* last, int32_t id, uint32_t& hits,
                                       ProbeOut& probe) {
  __m512 raw[N], npow[N], dxs[N];
  for (int k = 0; k < N; ++k) {
    avx512_neg_power<kRow>(a, s, q.at<kRow>(k0 + k), dxs[k], npow[k]);
    raw[k] = _mm512_mul_ps(a.opac, avx512_exp2(npow[k]));
  }
  unsigned stops = 0;
  for (int k = 0; k < N; ++k) {
    const Job j = q.at<kRow>(k0 + k);
    const __m512 alpha = _mm512_min_ps(raw[k], _mm512_set1_ps(float(kAlphaMax)));
    const JobPlanes<kFwdPlanes> pl(st, s, j);
    const __m512 t = pl.load<kRow>(kPlT);
    const __m512 next = _mm512_mul_ps(t, _mm512_sub_ps(_mm512_set1_ps(1.0f), alpha));
    const __mmask16 hit = j.lanes & _mm512_cmp_ps_mask(npow[k], a.ncut, _CMP_GE_OQ) &
                          _mm512_cmp_ps_mask(raw[k], _mm512_set1_ps(float(kAlphaMin)), _CMP_GE_OQ) &
                          _mm512_cmp_ps_mask(t, _mm512_setzero_ps(), _CMP_GT_OQ);
    const __mmask16 stop = hit & _mm512_cmp_ps_mask(next, _mm512_set1_ps(float(kTransmittanceMin)), _CMP_LT_OQ);
    const __mmask16 add = hit & ~stop;
    const __m512 w = _mm512_mul_ps(alpha, t);
    __m512 z = _mm512_setzero_ps();  // the composited depth: read by kChannels > 3 and the median probe
    if constexpr (kChannels > 3 || kProbe == Probe::median_depth) z = a.f[3];
    if constexpr (kPlane) {  // plane_z
      const __m512 dy = job_term<kRow>(s, j, &TileRows::dy);
      const __m512 iz = _mm512_fmadd_ps(plane.gx, dxs[k], _mm512_fmadd_ps(plane.gy, dy, plane.iz0));
      z = _mm512_max_ps(plane.zlo, _mm512_div_ps(_mm512_set1_ps(1.0f), _mm512_max_ps(iz, plane.izmin)));
    }
    if constexpr (kProbe == Probe::max_weight)  // fwd_group's keep_max sink
      probe.max_weight = _mm512_mask_max_ps(probe.max_weight, add, w, probe.max_weight);
    if constexpr (kProbe == Probe::median_depth) {  // its first_half sink: found where next ≤ 0.5; stops at −next
      const __mmask16 found = add & _mm512_cmp_ps_mask(next, _mm512_set1_ps(0.5f), _CMP_LE_OQ);
      if constexpr (kRow) {
        _mm512_mask_storeu_ps(probe.median + s.pixel(j, 0), found, z);
      } else {
        _mm256_mask_storeu_ps(probe.median + s.pixel(j, 0), __mmask8(found), _mm512_castps512_ps256(z));
        _mm256_mask_storeu_ps(probe.median + s.pixel(j, 1), __mmask8(found >> 8), _mm512_extractf32x8_ps(z, 1));
      }
      const __m512 kept = _mm512_mask_mov_ps(t, add & ~found, next);
      pl.store<kRow>(kPlT, _mm512_mask_mov_ps(_mm512_mask_mov_ps(kept, stop, avx512_neg(t)), found, avx512_neg(next)));
      stops |= stop | found;
      continue;
    }
    for (int c = 0; c < kChannels; ++c)  // acc stays where nothing is added (AVX2: 0·f + acc, the same value)
      pl.store<kRow>(kPlAcc + c, _mm512_mask3_fmadd_ps(w, c == 3 ? z : a.f[c], pl.load<kRow>(kPlAcc + c), add));
    pl.store<kRow>(kPlT, _mm512_mask_mov_ps(_mm512_mask_mov_ps(t, add, next), stop, avx512_neg(t)));
    if constexpr (kRow) {
      _mm512_mask_storeu_epi32(last + s.pixel(j, 0), add, _mm512_set1_epi32(id));
    } else {
      const __m256i ids = _mm256_set1_epi32(id);
      _mm256_mask_storeu_epi32(last + s.pixel(j, 0), __mmask8(add), ids);
      _mm256_mask_storeu_epi32(last + s.pixel(j, 1), __mmask8(add >> 8), ids);
    }
    stops |= stop;
    // The low half's group starts at the job's half-0 pixel; the high half's at its half-1 pixel, one group further
    // along the row in row jobs.
    hits |= unsigned((add & 0x00ffu) != 0) << group_bit(s.pixel(j, 0)) |
            unsigned((add & 0xff00u) != 0) << group_bit(s.pixel(j, 1) + (kRow ? kLanes : 0));
  }
  return stops;
}

// fwd_jobs_avx512 on the n jobs of q, four at a time where it can. Nonzero if a pixel stopped.
template <int kChannels, bool kPlane, bool kRow, Probe kProbe = Probe::none>
ISPLAT_AVX512 unsigned fwd_all_jobs_avx512(const Avx512Splat& a, const Avx512Plane& plane, const JobSet& s,
                                           const JobList& q, int n, float* st, int32_t* last, int32_t id,
                                           uint32_t& hits, ProbeOut& probe) {
  unsigned stops = 0;
  int k = 0;
  for (; k + 4 <= n; k += 4)
    stops |= fwd_jobs_avx512<4, kChannels, kPlane, kRow, kProbe>(a, plane, s, q, k, st, last, id, hits, probe);
  for (; k + 2 <= n; k += 2)
    stops |= fwd_jobs_avx512<2, kChannels, kPlane, kRow, kProbe>(a, plane, s, q, k, st, last, id, hits, probe);
  if (k < n) stops |= fwd_jobs_avx512<1, kChannels, kPlane, kRow, kProbe>(a, plane, s, q, k, st, last, id, hits, probe);
  return stops;
}

// Per 128 bits: a0 + a1, a2 + a3, b0 + b1, b2 + b3.
ISPLAT_AVX512 __m512 pairs(__m512 a, __m512 b) {
  return _mm512_add_ps(_mm512_shuffle_ps(a, b, _MM_SHUFFLE(2, 0, 2, 0)),
                       _mm512_shuffle_ps(a, b, _MM_SHUFFLE(3, 1, 3, 1)));
}

// Both lane-sum sets in one register per quantity: the left groups' in the low half, the right groups' in the
// high half (row jobs).
struct Avx512Sums {
  __m512 s[kGrad2d];
  ISPLAT_AVX512 void zero() {
    for (auto& v : s) v = _mm512_setzero_ps();
  }
  // LaneSums::reduce in registers, four quantities at a time: each step adds the neighbours the scalar tree
  // adds (addition commutes, so every partial sum is the tree's), then the left set's total + the right's.
  ISPLAT_AVX512 void reduce(float* out) const {
    const __m512 p[5] = {pairs(s[0], s[1]), pairs(s[2], s[3]), pairs(s[4], s[5]), pairs(s[6], s[7]), pairs(s[8], s[9])};
    const __m512 quads[3] = {pairs(p[0], p[1]), pairs(p[2], p[3]), pairs(p[4], p[4])};  // 4-sums of 4 quantities
    float tail[4];
    for (int k = 0; k < 3; ++k) {
      const __m512 trees = _mm512_add_ps(quads[k], _mm512_shuffle_f32x4(quads[k], quads[k], _MM_SHUFFLE(2, 3, 0, 1)));
      const __m128 total = _mm_add_ps(_mm512_castps512_ps128(trees), _mm512_extractf32x4_ps(trees, 2));
      _mm_storeu_ps(k < 2 ? out + 4 * k : tail, total);
    }
    out[8] = tail[0], out[9] = tail[1];
  }
};

// Where a job's 16 lanes add to lane sums. Row jobs: Avx512Sums, each half to its own set. Pair jobs: both
// groups to one Avx2Sums set (a narrow Gaussian's groups share a column), the low group first.
template <bool kRow>
struct JobSums;
template <>
struct JobSums<true> {
  Avx512Sums& g;
  // g += x·y, or where `keep` is clear g stays.
  ISPLAT_AVX512 void fma(int k, __m512 x, __m512 y) { g.s[k] = _mm512_fmadd_ps(x, y, g.s[k]); }
  ISPLAT_AVX512 void fma_where(int k, __mmask16 keep, __m512 x, __m512 y) {
    g.s[k] = _mm512_mask3_fmadd_ps(x, y, g.s[k], keep);
  }
};
template <>
struct JobSums<false> {
  Avx2Sums& g;
  static ISPLAT_AVX512 __m256 lo(__m512 v) { return _mm512_castps512_ps256(v); }
  static ISPLAT_AVX512 __m256 hi(__m512 v) { return _mm512_extractf32x8_ps(v, 1); }
  ISPLAT_AVX512 void fma(int k, __m512 x, __m512 y) {
    g.s[k] = _mm256_fmadd_ps(hi(x), hi(y), _mm256_fmadd_ps(lo(x), lo(y), g.s[k]));
  }
  ISPLAT_AVX512 void fma_where(int k, __mmask16 keep, __m512 x, __m512 y) {
    const __m256 first = _mm256_mask3_fmadd_ps(lo(x), lo(y), g.s[k], __mmask8(keep));
    g.s[k] = _mm256_mask3_fmadd_ps(hi(x), hi(y), first, __mmask8(keep >> 8));
  }
};

// bwd_groups_avx2 on the N jobs k0, ..., k0 + N − 1 of q.
template <int N, bool kRow, int kCh>
ISPLAT_AVX512 void bwd_jobs_avx512(const Avx512Splat& a, const JobSet& s, const JobList& q, int k0, float* st,
                                   const int32_t* last, int32_t i, JobSums<kRow> g) {
  __m512 dxs[N], npow[N], G[N];
  for (int k = 0; k < N; ++k) {
    avx512_neg_power<kRow>(a, s, q.at<kRow>(k0 + k), dxs[k], npow[k]);
    G[k] = avx512_exp2(npow[k]);
  }
  for (int k = 0; k < N; ++k) {
    const Job j = q.at<kRow>(k0 + k);
    const __m512 dx = dxs[k];
    const __m512 raw = _mm512_mul_ps(a.opac, G[k]);
    const __m512 alpha = _mm512_min_ps(raw, _mm512_set1_ps(float(kAlphaMax)));
    const __mmask16 hit = j.lanes & _mm512_cmp_ps_mask(npow[k], a.ncut, _CMP_GE_OQ) &
                          _mm512_cmp_ps_mask(raw, _mm512_set1_ps(float(kAlphaMin)), _CMP_GE_OQ) &
                          _mm512_cmpgt_epi32_mask(job_load_last<kRow>(last, s, j), _mm512_set1_epi32(i));
    const __m512 one_minus = _mm512_sub_ps(_mm512_set1_ps(1.0f), alpha);
    const JobPlanes<kBwdPlanes> pl(st, s, j);
    const __m512 t = pl.load<kRow>(kPbT);
    const __m512 t_in = _mm512_div_ps(t, one_minus);
    __m512 dc[kCh];
    for (int c = 0; c < kCh; ++c) dc[c] = pl.load<kRow>(kPbDC + c);
    __m512 dq = _mm512_mul_ps(dc[0], a.f[0]);
    for (int c = 1; c < kCh; ++c) dq = _mm512_fmadd_ps(dc[c], a.f[c], dq);
    const __m512 S = pl.load<kRow>(kPbS);
    const __m512 diff = _mm512_sub_ps(dq, S), d_alpha = _mm512_mul_ps(diff, t_in);
    pl.store<kRow>(kPbS, _mm512_mask3_fmadd_ps(alpha, diff, S, hit));  // α·diff + S where hit
    pl.store<kRow>(kPbT, _mm512_mask_mov_ps(t, hit, t_in));
    // Masked lanes add exactly zero, as in bwd_groups_avx2.
    const __m512 wh = _mm512_maskz_mul_ps(hit, alpha, t_in);
    for (int c = 0; c < std::min(kCh, 4); ++c) g.fma(kGr + c, wh, dc[c]);
    const __mmask16 free = hit & _mm512_cmp_ps_mask(raw, _mm512_set1_ps(float(kAlphaMax)), _CMP_LE_OQ);
    g.fma_where(kGo, free, G[k], d_alpha);
    const __m512 qp = _mm512_maskz_mul_ps(free, alpha, d_alpha);  // −dL/dpower
    const __m512 dy = job_term<kRow>(s, j, &TileRows::dy), qx = _mm512_mul_ps(qp, dx), qy = _mm512_mul_ps(qp, dy);
    g.fma(kGu, qp, dx);  // moments, see moments_to_grads
    g.fma(kGv, qp, dy);
    g.fma(kGA, qx, dx);
    g.fma(kGB, qx, dy);
    g.fma(kGC, qy, dy);
  }
}

// bwd_jobs_avx512 on the n jobs of q, four at a time where it can.
template <bool kRow, int kCh>
ISPLAT_AVX512 void bwd_all_jobs_avx512(const Avx512Splat& a, const JobSet& s, const JobList& q, int n, float* st,
                                       const int32_t* last, int32_t i, JobSums<kRow> g) {
  int k = 0;
  for (; k + 4 <= n; k += 4) bwd_jobs_avx512<4, kRow, kCh>(a, s, q, k, st, last, i, g);
  for (; k + 2 <= n; k += 2) bwd_jobs_avx512<2, kRow, kCh>(a, s, q, k, st, last, i, g);
  if (k < n) bwd_jobs_avx512<1, kRow, kCh>(a, s, q, k, st, last, i, g);
}

}  // namespace isplat::splat
#endif  // ISPLAT_HAVE_AVX2_LANES
