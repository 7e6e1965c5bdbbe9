// part_spans.h: rowSpan (part_score.h) for a vector of rows at a time, one Highway source for
// every target. The operations and their order are rowSpan's (and rowInterval's and
// clipLinear's), with per-lane selects where they branch per row; built with
// -ffp-contract=off, so no multiply-add is fused, as in part_score.h's callers.
//
// Highway re-includes this file once per target (foreach_target.h).
#ifndef HWY_DISABLED_TARGETS
#define HWY_DISABLED_TARGETS (HWY_SVE | HWY_SVE2 | HWY_SVE_256 | HWY_SVE2_128 | HWY_RVV)
#endif
#undef HWY_TARGET_INCLUDE
#define HWY_TARGET_INCLUDE "part_spans_hwy.cpp"
#include <hwy/foreach_target.h>  // must come before highway.h

#include <hwy/highway.h>

#include <cmath>

#include "part_spans.h"

HWY_BEFORE_NAMESPACE();
namespace body_tracking {
namespace part_spans {
namespace HWY_NAMESPACE {
namespace hn = hwy::HWY_NAMESPACE;

using part_score::PartQuadric;
using part_score::PartSetup;

// part_score::dmax / dmin, NaN behaviour included.
template <class V>
HWY_INLINE V Max(V a, V b) {
  return hn::IfThenElse(hn::Lt(a, b), b, a);
}
template <class V>
HWY_INLINE V Min(V a, V b) {
  return hn::IfThenElse(hn::Lt(b, a), b, a);
}

// part_score::clipLinear(a, b, lo, hi) with b the same in every lane.
template <class D, class V = hn::Vec<D>>
HWY_INLINE void ClipUniform(D d, V a, double b, V* lo, V* hi) {
  if (fabs(b) < 1e-15) {
    *hi = hn::IfThenElse(hn::Lt(a, hn::Zero(d)), hn::Sub(*lo, hn::Set(d, 1.0)), *hi);
    return;
  }
  const V r = hn::Div(hn::Neg(a), hn::Set(d, b));
  if (b > 0) *lo = Max(*lo, hn::Ceil(hn::Sub(r, hn::Set(d, 1e-9))));
  else *hi = Min(*hi, hn::Floor(hn::Add(r, hn::Set(d, 1e-9))));
}

// part_score::clipLinear(a, b, lo, hi) with b per lane.
template <class D, class V = hn::Vec<D>>
HWY_INLINE void ClipLanes(D d, V a, V b, V* lo, V* hi) {
  const auto flat = hn::Lt(hn::Abs(b), hn::Set(d, 1e-15));
  const V r = hn::Div(hn::Neg(a), b);
  const auto rising = hn::AndNot(flat, hn::Gt(b, hn::Zero(d)));
  const auto falling = hn::AndNot(flat, hn::Not(hn::Gt(b, hn::Zero(d))));
  const V new_lo = Max(*lo, hn::Ceil(hn::Sub(r, hn::Set(d, 1e-9))));
  const V new_hi = Min(*hi, hn::Floor(hn::Add(r, hn::Set(d, 1e-9))));
  const V emptied = hn::Sub(*lo, hn::Set(d, 1.0));
  *hi = hn::IfThenElse(falling, new_hi, *hi);
  *hi = hn::IfThenElse(hn::And(flat, hn::Lt(a, hn::Zero(d))), emptied, *hi);
  *lo = hn::IfThenElse(rising, new_lo, *lo);
}

// part_score::dot4(p, v) with v = (v0, v1, v2, v3), v0 and v3 the same in every lane.
template <class D, class V = hn::Vec<D>>
HWY_INLINE V Dot4(D d, const double* p, double v0, V v1, V v2, double v3) {
  return hn::Add(hn::Add(hn::Set(d, p[0] * v0), hn::Mul(hn::Set(d, p[2]), v2)),
                 hn::Add(hn::Mul(hn::Set(d, p[1]), v1), hn::Set(d, p[3] * v3)));
}

// part_score::rowInterval: tightens [*lo, *hi]; returns the lanes whose interval is not empty.
template <class D, class V = hn::Vec<D>>
HWY_INLINE hn::Mask<D> Interval(D d, V A, V B, double C, const PartQuadric& q, double v0, V v1,
                                V v2, double v3, double h, V* lo, V* hi) {
  auto ok = hn::Not(hn::Lt(hn::Zero(d), hn::Zero(d)));  // all lanes
  if (C > 1e-15) {
    const V disc = hn::Sub(hn::Mul(B, B), hn::Mul(hn::Mul(hn::Set(d, 4.0), A), hn::Set(d, C)));
    ok = hn::Not(hn::Lt(disc, hn::Zero(d)));
    const V sq = hn::Sqrt(disc);
    const V two_c = hn::Set(d, 2.0 * C);
    const V nb = hn::Neg(B);
    *lo = Max(*lo, hn::Ceil(hn::Sub(hn::Div(hn::Sub(nb, sq), two_c), hn::Set(d, 1e-9))));
    *hi = Min(*hi, hn::Floor(hn::Add(hn::Div(hn::Add(nb, sq), two_c), hn::Set(d, 1e-9))));
  } else {
    ClipLanes(d, hn::Neg(A), hn::Neg(B), lo, hi);
  }
  for (int i = 0; i < q.num_planes; ++i)
    ClipUniform(d, Dot4(d, q.planes[i], v0, v1, v2, v3), q.planes[i][0] * h, lo, hi);
  return hn::And(ok, hn::Le(*lo, *hi));
}

void Spans(const PartSetup& s, const PartQuadric& q, double h, size_t n, SpanRows* rows) {
  const hn::ScalableTag<double> d;
  using V = hn::Vec<decltype(d)>;
  const size_t lanes = hn::Lanes(d);
  const double v0 = s.base[0] + 0.0, v3 = s.base[3] + 0.0;
  const V one = hn::Set(d, 1.0);
  const bool shell = q.shell_weight > 0;
  for (size_t k = 0; k < n; k += lanes) {
    const V yy = hn::LoadU(d, rows->yy.data() + k), z = hn::LoadU(d, rows->z.data() + k);
    const V v1 = hn::Add(hn::Set(d, s.base[1]), hn::Mul(yy, hn::Set(d, h)));
    const V v2 = hn::Add(hn::Set(d, s.base[2]), hn::Mul(z, hn::Set(d, h)));
    // sv[i] / qv[i] = base[i] + yy dy[i] + z dz[i], summed left to right.
    const auto row_q = [&](const double* base, const double* dy, const double* dz, int i) {
      return hn::Add(hn::Add(hn::Set(d, base[i]), hn::Mul(yy, hn::Set(d, dy[i]))),
                     hn::Mul(z, hn::Set(d, dz[i])));
    };
    V olo = hn::Set(d, s.bx0), ohi = hn::Set(d, s.bx1), shell_ok = hn::Zero(d);
    if (shell) {
      V sv[4];
      for (int i = 0; i < 4; ++i) sv[i] = row_q(s.shell_q_base, s.shell_q_dy, s.shell_q_dz, i);
      const V A = hn::Add(hn::Add(hn::Mul(hn::Set(d, v0), sv[0]), hn::Mul(v2, sv[2])),
                          hn::Add(hn::Mul(v1, sv[1]), hn::Mul(hn::Set(d, v3), sv[3])));
      const V B = hn::Mul(hn::Set(d, 2.0 * h), sv[0]);
      shell_ok = hn::IfThenElseZero(Interval(d, A, B, s.shell_C, q, v0, v1, v2, v3, h, &olo, &ohi), one);
    }
    V qv[4];
    for (int i = 0; i < 4; ++i) qv[i] = row_q(s.q_base, s.q_dy, s.q_dz, i);
    const V A = hn::Add(hn::Add(hn::Mul(hn::Set(d, v0), qv[0]), hn::Mul(v2, qv[2])),
                        hn::Add(hn::Mul(v1, qv[1]), hn::Mul(hn::Set(d, v3), qv[3])));
    const V B = hn::Mul(hn::Set(d, 2.0 * h), qv[0]);
    V lo = hn::Set(d, s.bx0), hi = hn::Set(d, s.bx1);
    const V ok = hn::IfThenElseZero(Interval(d, A, B, s.C, q, v0, v1, v2, v3, h, &lo, &hi), one);
    hn::StoreU(A, d, rows->A.data() + k);
    hn::StoreU(B, d, rows->B.data() + k);
    hn::StoreU(lo, d, rows->xlo.data() + k);
    hn::StoreU(hi, d, rows->xhi.data() + k);
    hn::StoreU(ok, d, rows->ok.data() + k);
    hn::StoreU(olo, d, rows->olo.data() + k);
    hn::StoreU(ohi, d, rows->ohi.data() + k);
    hn::StoreU(shell_ok, d, rows->shell_ok.data() + k);
  }
}

}  // namespace HWY_NAMESPACE
}  // namespace part_spans
}  // namespace body_tracking
HWY_AFTER_NAMESPACE();

#if HWY_ONCE
#include <algorithm>

#include "psfs_reconstruction/simd_dispatch.h"

namespace body_tracking {
namespace part_spans {

HWY_EXPORT(Spans);

// The target choice and the table slots are the pSfS kernels' (psfs/simd_dispatch.h), so the
// same switches (TABLETOP_SIMD, force*Kernels) apply.
void SpanRows::resize(size_t n) {
  const size_t padded = (n + 15) / 16 * 16;  // whole vectors of up to 16 lanes
  for (std::vector<double>* v : {&yy, &z, &A, &B, &xlo, &xhi, &olo, &ohi, &ok, &shell_ok})
    if (v->size() < padded) v->resize(padded, 0.0);
}

SpansFn activeSpans() {
  return HWY_DISPATCH_TABLE(Spans)[psfs::highwayDispatchIndex(psfs::highwayTarget())];
}

std::vector<Target> availableTargets() {
  std::vector<Target> out;
  for (int64_t t : hwy::SupportedAndGeneratedTargets())
    out.push_back({t, hwy::TargetName(t), HWY_DISPATCH_TABLE(Spans)[psfs::highwayDispatchIndex(t)]});
  return out;
}

double scorePart(const part_score::PartQuadric& q, const part_score::ObservationGrid& g,
                 const part_score::RowSumsView& sums, SpansFn spans, SpanRows* rows) {
  const part_score::PartSetup s = part_score::setupPart(q, g);
  part_score::PartSums acc = {0.0, 0.0, 0.0, 0.0};
  const int n = part_score::rowCount(s);
  if (n > 0) {
    rows->resize(n);
    const int ny = s.y1 - s.y0 + 1;
    for (int k = 0; k < n; ++k) {  // z outer, as part_score::scorePart walks them
      rows->yy[k] = s.y0 + k % ny;
      rows->z[k] = s.z0 + k / ny;
    }
    spans(s, q, g.voxel_size, n, rows);
    for (int k = 0; k < n; ++k) {
      const part_score::RowSpan sp = {rows->A[k],   rows->B[k],   rows->xlo[k],          rows->xhi[k],
                                      rows->olo[k], rows->ohi[k], rows->ok[k] != 0.0, rows->shell_ok[k] != 0.0};
      part_score::accumulateRow(
          part_score::rowTermsOf(s, q, g, sums, s.y0 + k % ny, s.z0 + k / ny, sp), &acc);
    }
  }
  return part_score::finishPart(acc, g.unknown, q.shell_weight);
}

}  // namespace part_spans
}  // namespace body_tracking
#endif  // HWY_ONCE
