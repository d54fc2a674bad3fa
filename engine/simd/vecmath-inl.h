// Vectors, quaternions and 3x3 matrices of SIMD lanes, for the kernels of one Highway
// target (included after foreach_target.h, once per target, like Highway's own -inl.h).
//
// Each operation is glm's (0.9.9, its scalar code: the project defines no GLM_FORCE_*),
// written with the same operations in the same order, so that a lane computes the bits
// glm computes for that chain: glm::dot of vec3 is (x x' + y y') + z z', of quaternions
// (w w' + x x') + (y y' + z z'); normalize multiplies by 1 / sqrt(dot) (vec3) or by
// 1 / length (quaternions, identity when the length is not > 0); q * v is
// v + ((uv w) + uuv) 2 with uv = cross(q.xyz, v), uuv = cross(q.xyz, uv). Only +, -, *, /
// and sqrt: correctly rounded on every instruction set. No MulAdd: the reference is
// compiled without contraction. Zeros glm multiplies by are multiplied here too (0 * x is
// -0 for negative x, and the sign of a zero can reach an output).

#if defined(KODAWARI_SIMD_VECMATH_INL_H_) == defined(HWY_TARGET_TOGGLE)
#ifdef KODAWARI_SIMD_VECMATH_INL_H_
#undef KODAWARI_SIMD_VECMATH_INL_H_
#else
#define KODAWARI_SIMD_VECMATH_INL_H_
#endif

#include <hwy/highway.h>

HWY_BEFORE_NAMESPACE();
namespace kodawari::simd {
namespace HWY_NAMESPACE {
namespace hn = hwy::HWY_NAMESPACE;

using D = hn::ScalableTag<float>;
using V = hn::Vec<D>;
using M = hn::Mask<D>;

struct V3 {
    V x, y, z;
};
struct Q4 {  // quaternion (x, y, z, w)
    V x, y, z, w;
};
struct M3 {  // columns, as glm::mat3: c[col].x is row 0
    V3 c[3];
};

HWY_INLINE V S(float s) { return hn::Set(D(), s); }
HWY_INLINE V Z() { return hn::Zero(D()); }

// Rows of kBatchLanes floats: lane `off` onwards of row r.
HWY_INLINE V load(const float* rows, std::size_t r, std::size_t off) { return hn::Load(D(), rows + r * 16 + off); }
HWY_INLINE void store(V v, float* rows, std::size_t r, std::size_t off) { hn::Store(v, D(), rows + r * 16 + off); }
HWY_INLINE V3 load3(const float* rows, std::size_t r, std::size_t off) {
    return {load(rows, r, off), load(rows, r + 1, off), load(rows, r + 2, off)};
}
HWY_INLINE Q4 load4(const float* rows, std::size_t r, std::size_t off) {
    return {load(rows, r, off), load(rows, r + 1, off), load(rows, r + 2, off), load(rows, r + 3, off)};
}
HWY_INLINE void store3(const V3& v, float* rows, std::size_t r, std::size_t off) {
    store(v.x, rows, r, off);
    store(v.y, rows, r + 1, off);
    store(v.z, rows, r + 2, off);
}
HWY_INLINE void store4(const Q4& q, float* rows, std::size_t r, std::size_t off) {
    store(q.x, rows, r, off);
    store(q.y, rows, r + 1, off);
    store(q.z, rows, r + 2, off);
    store(q.w, rows, r + 3, off);
}

HWY_INLINE V3 splat3(const float* v) { return {S(v[0]), S(v[1]), S(v[2])}; }
HWY_INLINE Q4 splat4(const float* q) { return {S(q[0]), S(q[1]), S(q[2]), S(q[3])}; }
HWY_INLINE V3 zero3() { return {Z(), Z(), Z()}; }

HWY_INLINE V3 add(const V3& a, const V3& b) { return {hn::Add(a.x, b.x), hn::Add(a.y, b.y), hn::Add(a.z, b.z)}; }
HWY_INLINE V3 sub(const V3& a, const V3& b) { return {hn::Sub(a.x, b.x), hn::Sub(a.y, b.y), hn::Sub(a.z, b.z)}; }
HWY_INLINE V3 mul(V s, const V3& a) { return {hn::Mul(s, a.x), hn::Mul(s, a.y), hn::Mul(s, a.z)}; }
HWY_INLINE V3 div(const V3& a, V s) { return {hn::Div(a.x, s), hn::Div(a.y, s), hn::Div(a.z, s)}; }
HWY_INLINE V3 select(M m, const V3& a, const V3& b) {
    return {hn::IfThenElse(m, a.x, b.x), hn::IfThenElse(m, a.y, b.y), hn::IfThenElse(m, a.z, b.z)};
}
HWY_INLINE Q4 select(M m, const Q4& a, const Q4& b) {
    return {hn::IfThenElse(m, a.x, b.x), hn::IfThenElse(m, a.y, b.y), hn::IfThenElse(m, a.z, b.z),
            hn::IfThenElse(m, a.w, b.w)};
}

// glm::min, glm::max and glm::clamp of floats: (y < x) ? y : x, (x < y) ? y : x,
// min(max(x, lo), hi). Comparisons, not hn::Min/Max (x86's minps and maxps pick the
// second operand for a NaN or two zeros, where glm picks by the comparison).
HWY_INLINE V glm_min(V x, V y) { return hn::IfThenElse(hn::Lt(y, x), y, x); }
HWY_INLINE V glm_max(V x, V y) { return hn::IfThenElse(hn::Lt(x, y), y, x); }
HWY_INLINE V glm_clamp(V x, V lo, V hi) { return glm_min(glm_max(x, lo), hi); }

// glm::dot(vec3), glm::length(vec3), glm::cross, glm::normalize(vec3).
HWY_INLINE V dot(const V3& a, const V3& b) {
    return hn::Add(hn::Add(hn::Mul(a.x, b.x), hn::Mul(a.y, b.y)), hn::Mul(a.z, b.z));
}
HWY_INLINE V length(const V3& a) { return hn::Sqrt(dot(a, a)); }
HWY_INLINE V3 cross(const V3& x, const V3& y) {
    return {hn::Sub(hn::Mul(x.y, y.z), hn::Mul(y.y, x.z)), hn::Sub(hn::Mul(x.z, y.x), hn::Mul(y.z, x.x)),
            hn::Sub(hn::Mul(x.x, y.y), hn::Mul(y.x, x.y))};
}
HWY_INLINE V3 normalize(const V3& v) {
    const V inv = hn::Div(S(1.0f), hn::Sqrt(dot(v, v)));
    return {hn::Mul(v.x, inv), hn::Mul(v.y, inv), hn::Mul(v.z, inv)};
}

// Quaternions: glm's operator*, conjugate, operator+, dot, normalize; q * v.
HWY_INLINE Q4 qmul(const Q4& p, const Q4& q) {
    return {hn::Sub(hn::Add(hn::Add(hn::Mul(p.w, q.x), hn::Mul(p.x, q.w)), hn::Mul(p.y, q.z)), hn::Mul(p.z, q.y)),
            hn::Sub(hn::Add(hn::Add(hn::Mul(p.w, q.y), hn::Mul(p.y, q.w)), hn::Mul(p.z, q.x)), hn::Mul(p.x, q.z)),
            hn::Sub(hn::Add(hn::Add(hn::Mul(p.w, q.z), hn::Mul(p.z, q.w)), hn::Mul(p.x, q.y)), hn::Mul(p.y, q.x)),
            hn::Sub(hn::Sub(hn::Sub(hn::Mul(p.w, q.w), hn::Mul(p.x, q.x)), hn::Mul(p.y, q.y)), hn::Mul(p.z, q.z))};
}
HWY_INLINE Q4 conj(const Q4& q) { return {hn::Neg(q.x), hn::Neg(q.y), hn::Neg(q.z), q.w}; }
HWY_INLINE Q4 qadd(const Q4& a, const Q4& b) {
    return {hn::Add(a.x, b.x), hn::Add(a.y, b.y), hn::Add(a.z, b.z), hn::Add(a.w, b.w)};
}
HWY_INLINE V qdot(const Q4& a, const Q4& b) {
    return hn::Add(hn::Add(hn::Mul(a.w, b.w), hn::Mul(a.x, b.x)), hn::Add(hn::Mul(a.y, b.y), hn::Mul(a.z, b.z)));
}
HWY_INLINE Q4 qnormalize(const Q4& q) {
    const V len = hn::Sqrt(qdot(q, q));
    const V inv = hn::Div(S(1.0f), len);
    const Q4 n{hn::Mul(q.x, inv), hn::Mul(q.y, inv), hn::Mul(q.z, inv), hn::Mul(q.w, inv)};
    return select(hn::Le(len, Z()), Q4{Z(), Z(), Z(), S(1.0f)}, n);
}
// q with w >= 0 (solver_internal.hpp positive_w).
HWY_INLINE Q4 positive_w(const Q4& q) {
    const M neg = hn::Lt(q.w, Z());
    return select(neg, Q4{hn::Neg(q.x), hn::Neg(q.y), hn::Neg(q.z), hn::Neg(q.w)}, q);
}
HWY_INLINE V3 rotate(const Q4& q, const V3& v) {
    const V3 u{q.x, q.y, q.z};
    const V3 uv = cross(u, v);
    const V3 uuv = cross(u, uv);
    const V two = S(2.0f);
    return {hn::Add(v.x, hn::Mul(hn::Add(hn::Mul(uv.x, q.w), uuv.x), two)),
            hn::Add(v.y, hn::Mul(hn::Add(hn::Mul(uv.y, q.w), uuv.y), two)),
            hn::Add(v.z, hn::Mul(hn::Add(hn::Mul(uv.z, q.w), uuv.z), two))};
}
// normalize(q + quat(0, t) * q): the first-order turn of solver.cpp (prediction and the
// rotation extraction), glm's product with its literal zero.
HWY_INLINE Q4 turn(const Q4& q, const V3& t) { return qnormalize(qadd(q, qmul(Q4{t.x, t.y, t.z, Z()}, q))); }

// glm::mat3_cast.
HWY_INLINE M3 mat3_cast(const Q4& q) {
    const V one = S(1.0f), two = S(2.0f);
    const V qxx = hn::Mul(q.x, q.x), qyy = hn::Mul(q.y, q.y), qzz = hn::Mul(q.z, q.z);
    const V qxz = hn::Mul(q.x, q.z), qxy = hn::Mul(q.x, q.y), qyz = hn::Mul(q.y, q.z);
    const V qwx = hn::Mul(q.w, q.x), qwy = hn::Mul(q.w, q.y), qwz = hn::Mul(q.w, q.z);
    M3 r;
    r.c[0] = {hn::Sub(one, hn::Mul(two, hn::Add(qyy, qzz))), hn::Mul(two, hn::Add(qxy, qwz)), hn::Mul(two, hn::Sub(qxz, qwy))};
    r.c[1] = {hn::Mul(two, hn::Sub(qxy, qwz)), hn::Sub(one, hn::Mul(two, hn::Add(qxx, qzz))), hn::Mul(two, hn::Add(qyz, qwx))};
    r.c[2] = {hn::Mul(two, hn::Add(qxz, qwy)), hn::Mul(two, hn::Sub(qyz, qwx)), hn::Sub(one, hn::Mul(two, hn::Add(qxx, qyy)))};
    return r;
}

}  // namespace HWY_NAMESPACE
}  // namespace kodawari::simd
HWY_AFTER_NAMESPACE();

#endif  // include guard toggle
