// The cpu backend's grid buckets for every instruction set (flock_kernel.hpp's
// BucketsFn): shaders/lib/flock_hash.glsl's flock_bucket() for a vector of birds at a
// time, its integer arithmetic lane for lane (exact): the grid's build of 10 000 birds
// took 136 thousand cycles a substep with it, 313 with flock_bucket() bird by bird on one
// thread (about 170 on two, a parallel pass's wake-up included).
#undef HWY_TARGET_INCLUDE
#define HWY_TARGET_INCLUDE "domains/flocking/flock_grid_simd.cpp"
#include <hwy/foreach_target.h>  // IWYU pragma: keep
#include <hwy/highway.h>

#include <cmath>
#include <cstdint>
#include <limits>

#include "domains/flocking/flock_kernel.hpp"

HWY_BEFORE_NAMESPACE();
namespace kodawari::flocking {
namespace HWY_NAMESPACE {
namespace {

namespace hn = hwy::HWY_NAMESPACE;

using D = hn::ScalableTag<float>;
using DU = hn::RebindToUnsigned<D>;

// flock_hash.glsl's flock_spread3(), a vector of cells at a time.
HWY_INLINE hn::Vec<DU> spread3(hn::Vec<DU> v) {
    const DU du;
    v = hn::And(v, hn::Set(du, 0x3FFu));
    v = hn::And(hn::Or(v, hn::ShiftLeft<16>(v)), hn::Set(du, 0x030000FFu));
    v = hn::And(hn::Or(v, hn::ShiftLeft<8>(v)), hn::Set(du, 0x0300F00Fu));
    v = hn::And(hn::Or(v, hn::ShiftLeft<4>(v)), hn::Set(du, 0x030C30C3u));
    v = hn::And(hn::Or(v, hn::ShiftLeft<2>(v)), hn::Set(du, 0x09249249u));
    return v;
}

// One axis's cell, flock_cell(): floor(c inv_radius), and the int range's lowest value
// where that lies beyond it (NaN, infinite, far).
HWY_INLINE hn::Vec<DU> cell_of(hn::Vec<D> c, hn::Vec<D> inv_radius) {
    const D d;
    const DU du;
    const hn::RebindToSigned<D> di;
    const auto f = hn::Floor(hn::Mul(c, inv_radius));
    const auto in_range = hn::Lt(hn::Abs(f), hn::Set(d, KW_FLOCK_CELL_LIMIT));
    // Lanes out of range converted to anything (Highway's saturating conversion), then replaced.
    const auto cell = hn::IfThenElse(hn::RebindMask(di, in_range), hn::ConvertTo(di, hn::IfThenElseZero(in_range, f)),
                                     hn::Set(di, std::numeric_limits<std::int32_t>::min()));
    return hn::BitCast(du, cell);
}

// kw_lowbias32() (lib/hash.glsl), lanes at a time.
HWY_INLINE hn::Vec<DU> mix(hn::Vec<DU> x) {
    const DU du;
    x = hn::Xor(x, hn::ShiftRight<16>(x));
    x = hn::Mul(x, hn::Set(du, KW_LOWBIAS32_M1));
    x = hn::Xor(x, hn::ShiftRight<15>(x));
    x = hn::Mul(x, hn::Set(du, KW_LOWBIAS32_M2));
    x = hn::Xor(x, hn::ShiftRight<16>(x));
    return x;
}

// BucketsFn: flock_bucket() of a vector of birds at a time from the slots' arrays; the
// last birds short of a vector one by one. Whether any coordinate is NaN or infinite.
bool buckets(const float* x, const float* y, const float* z, std::size_t n, float inv_radius, std::uint32_t mask,
             std::uint32_t* out) {
    const D d;
    const DU du;
    const std::size_t lanes = hn::Lanes(d);
    const auto inv = hn::Set(d, inv_radius);
    const auto mask_v = hn::Set(du, mask), high = hn::Set(du, ~mask);
    const auto half_block = hn::Set(du, KW_FLOCK_HALF_BLOCK);
    auto finite = hn::FirstN(d, lanes);  // every lane
    std::size_t i = 0;
    for (; i + lanes <= n; i += lanes) {
        const auto px = hn::LoadU(d, x + i), py = hn::LoadU(d, y + i), pz = hn::LoadU(d, z + i);
        finite = hn::And(finite, hn::And(hn::IsFinite(px), hn::And(hn::IsFinite(py), hn::IsFinite(pz))));
        const auto ux = hn::Add(cell_of(px, inv), half_block);
        const auto uy = hn::Add(cell_of(py, inv), half_block);
        const auto uz = hn::Add(cell_of(pz, inv), half_block);
        const auto morton = hn::Or(hn::Or(spread3(ux), hn::ShiftLeft<1>(spread3(uy))), hn::ShiftLeft<2>(spread3(uz)));
        auto wrap = hn::And(morton, high);
        wrap = hn::Xor(wrap, hn::Mul(hn::ShiftRight<KW_FLOCK_BLOCK_BITS>(ux), hn::Set(du, KW_FLOCK_PRIME_X)));
        wrap = hn::Xor(wrap, hn::Mul(hn::ShiftRight<KW_FLOCK_BLOCK_BITS>(uy), hn::Set(du, KW_FLOCK_PRIME_Y)));
        wrap = hn::Xor(wrap, hn::Mul(hn::ShiftRight<KW_FLOCK_BLOCK_BITS>(uz), hn::Set(du, KW_FLOCK_PRIME_Z)));
        hn::StoreU(hn::And(hn::Xor(morton, mix(wrap)), mask_v), du, out + i);
    }
    bool not_finite = !hn::AllTrue(d, finite);
    for (; i < n; ++i) {
        out[i] = glsl::flock_bucket(glsl::vec3(x[i], y[i], z[i]), inv_radius, mask);
        not_finite = not_finite || !std::isfinite(x[i]) || !std::isfinite(y[i]) || !std::isfinite(z[i]);
    }
    return not_finite;
}

}  // namespace

BucketsFn flock_buckets_kernel() { return &buckets; }

}  // namespace HWY_NAMESPACE
}  // namespace kodawari::flocking
HWY_AFTER_NAMESPACE();

#if HWY_ONCE
#include "simd/dispatch.hpp"

namespace kodawari::flocking {

BucketsFn flock_buckets_kernel(std::int64_t target) { KW_SIMD_SELECT(target, flock_buckets_kernel) }

}  // namespace kodawari::flocking
#endif
