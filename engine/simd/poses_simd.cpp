// The pose kernel of the cpu backend: the node matrices of a crowd's instances (§3.5.3
// Transformations of the glTF 2.0.1 specification), vectorized across the instances of a
// batch (poses_simd.hpp: layout, and why every matrix is cpu-reference's bits). Compiled
// once per instruction set by Highway's foreach_target.h. It repeats
// engine/animation/character.cpp compute_world() and the backends' placement product.
#undef HWY_TARGET_INCLUDE
#define HWY_TARGET_INCLUDE "simd/poses_simd.cpp"
#include <hwy/foreach_target.h>  // IWYU pragma: keep
#include <hwy/highway.h>

#include <cstring>

#include "simd/poses_simd.hpp"
#include "simd/vecmath-inl.h"

HWY_BEFORE_NAMESPACE();
namespace kodawari::simd {
namespace HWY_NAMESPACE {
namespace {

struct M4 {  // c[column][row], as glm::mat4
    V c[4][4];
};

M4 splat(const std::array<float, 16>& m) {
    M4 r;
    for (int col = 0; col < 4; ++col) {
        for (int row = 0; row < 4; ++row) r.c[col][row] = S(m[col * 4 + row]);
    }
    return r;
}

M4 identity() {
    M4 r;
    for (int col = 0; col < 4; ++col) {
        for (int row = 0; row < 4; ++row) r.c[col][row] = S(col == row ? 1.0f : 0.0f);
    }
    return r;
}

// glm's mat4 * mat4: column j = ((A0 B[j][0] + A1 B[j][1]) + A2 B[j][2]) + A3 B[j][3].
M4 mat_mul(const M4& a, const M4& b) {
    M4 r;
    for (int j = 0; j < 4; ++j) {
        for (int row = 0; row < 4; ++row) {
            r.c[j][row] = hn::Add(hn::Add(hn::Add(hn::Mul(a.c[0][row], b.c[j][0]), hn::Mul(a.c[1][row], b.c[j][1])),
                                          hn::Mul(a.c[2][row], b.c[j][2])),
                                  hn::Mul(a.c[3][row], b.c[j][3]));
        }
    }
    return r;
}

// compute_world's local matrix: translate(mat4(1), t) * mat4_cast(r) * scale(mat4(1), s),
// each of glm's functions with its own operations on the identity.
M4 local_matrix(const V3& t, const Q4& r, const V3& s) {
    const M4 one = identity();
    M4 translate = one;
    const V tv[3] = {t.x, t.y, t.z};
    for (int row = 0; row < 4; ++row) {
        translate.c[3][row] = hn::Add(
            hn::Add(hn::Add(hn::Mul(one.c[0][row], tv[0]), hn::Mul(one.c[1][row], tv[1])), hn::Mul(one.c[2][row], tv[2])),
            one.c[3][row]);
    }
    const M3 r3 = mat3_cast(r);
    M4 rotate = one;
    for (int col = 0; col < 3; ++col) {
        rotate.c[col][0] = r3.c[col].x;
        rotate.c[col][1] = r3.c[col].y;
        rotate.c[col][2] = r3.c[col].z;
        rotate.c[col][3] = Z();
    }
    M4 scale = one;
    const V sv[3] = {s.x, s.y, s.z};
    for (int col = 0; col < 3; ++col) {
        for (int row = 0; row < 4; ++row) scale.c[col][row] = hn::Mul(one.c[col][row], sv[col]);
    }
    return mat_mul(mat_mul(translate, rotate), scale);
}

// Rows r.. of kBatchLanes floats, or a constant when the channel is -1.
V3 value3(const float* values, std::int32_t channel, const std::array<float, 4>& rest, std::size_t off) {
    return channel >= 0 ? load3(values, static_cast<std::size_t>(channel) * 4, off) : splat3(rest.data());
}
Q4 value4(const float* values, std::int32_t channel, const std::array<float, 4>& rest, std::size_t off) {
    return channel >= 0 ? load4(values, static_cast<std::size_t>(channel) * 4, off) : splat4(rest.data());
}

void evaluate_lanes(const PoseStepArgs& a, std::size_t b, std::size_t off) {
    const PoseBatch& batch = a.batches[b];
    const PoseClipPlan& plan = a.plans[batch.plan];
    const float* place_rows = a.placements + b * 16 * kBatchLanes;
    M4 placement;
    for (int col = 0; col < 4; ++col) {
        for (int row = 0; row < 4; ++row) placement.c[col][row] = load(place_rows, col * 4 + row, off);
    }
    const float* values = a.values + a.value_offset[b];
    const std::size_t lanes = std::min(hn::Lanes(D()), static_cast<std::size_t>(batch.count) - off);
    HWY_ALIGN float columns[4][4 * kBatchLanes];
    for (const std::int32_t n : plan.order) {
        const auto node = static_cast<std::size_t>(n);
        M4 world;
        if (plan.uniform_world[node] != 0) {
            world = splat(plan.world[node]);
        } else {
            const std::int32_t tc = plan.t_channel[node], rc = plan.r_channel[node], sc = plan.s_channel[node];
            const M4 local = (tc >= 0 || rc >= 0 || sc >= 0)
                                 ? local_matrix(value3(values, tc, plan.rest_t[node], off), value4(values, rc, plan.rest_r[node], off),
                                                value3(values, sc, plan.rest_s[node], off))
                                 : splat(plan.local[node]);
            const std::int32_t parent = plan.parent[node];
            if (parent < 0) {
                world = local;
            } else {
                const auto p = static_cast<std::size_t>(parent);
                M4 parent_world;
                if (plan.uniform_world[p] != 0) {
                    parent_world = splat(plan.world[p]);
                } else {
                    for (int col = 0; col < 4; ++col) {
                        for (int row = 0; row < 4; ++row) parent_world.c[col][row] = load(a.scratch, p * 16 + col * 4 + row, off);
                    }
                }
                world = mat_mul(parent_world, local);
            }
            for (int col = 0; col < 4; ++col) {
                for (int row = 0; row < 4; ++row) store(world.c[col][row], a.scratch, node * 16 + col * 4 + row, off);
            }
        }
        // The backends' output: placement_matrix(placement) * the node's world matrix.
        const M4 out = mat_mul(placement, world);
        for (int col = 0; col < 4; ++col) hn::StoreInterleaved4(out.c[col][0], out.c[col][1], out.c[col][2], out.c[col][3], D(), columns[col]);
        for (std::size_t l = 0; l < lanes; ++l) {
            float* dst = a.world + (std::size_t{batch.instance[off + l]} * a.nodes + node) * 16;
            for (int col = 0; col < 4; ++col) std::memcpy(dst + 4 * col, columns[col] + 4 * l, 4 * sizeof(float));
        }
    }
}

void evaluate_batches(const PoseStepArgs& args, std::size_t begin, std::size_t end) {
    for (std::size_t b = begin; b < end; ++b) {
        for (std::size_t off = 0; off < args.batches[b].count; off += hn::Lanes(D())) evaluate_lanes(args, b, off);
    }
}

}  // namespace

PoseKernels pose_kernels() { return {&evaluate_batches}; }

}  // namespace HWY_NAMESPACE
}  // namespace kodawari::simd
HWY_AFTER_NAMESPACE();

#if HWY_ONCE
#include "simd/dispatch.hpp"

namespace kodawari::simd {

PoseKernels pose_kernels(std::int64_t target) { KW_SIMD_SELECT(target, pose_kernels) }

}  // namespace kodawari::simd
#endif
