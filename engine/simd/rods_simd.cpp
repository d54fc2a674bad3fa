// The rods kernel of the cpu backend (SPEC A.2-A.5), vectorized across the chains of a
// batch (rods_simd.hpp: layout, and why every lane gets cpu-reference's bits). Compiled
// once per instruction set by Highway's foreach_target.h. Each step below cites the
// function of engine/rods whose expressions it repeats; the SPEC sections and papers are
// cited there.
#undef HWY_TARGET_INCLUDE
#define HWY_TARGET_INCLUDE "simd/rods_simd.cpp"
#include <hwy/foreach_target.h>  // IWYU pragma: keep
#include <algorithm>
#include <hwy/cache_control.h>
#include <hwy/highway.h>

#include "simd/rod_colliders-inl.h"
#include "simd/rods_simd.hpp"
#include "simd/scalar_math.hpp"
#include "simd/vecmath-inl.h"

HWY_BEFORE_NAMESPACE();
namespace kodawari::simd {
namespace HWY_NAMESPACE {
namespace {

constexpr std::size_t kMaxJ = rods::kMaxChainJoints;
constexpr std::size_t kMaxK = rods::kMaxChainColliders;

// This frame's input of a batch's 16 lanes, gathered from the frame's per-chain arrays.
// kKeyed: the chain's raw keyed weights u_1 .. u_4 (keyed-examples.md K.2, K.3).
// kAir: the air's velocity around the chain (RodStepArgs::air).
enum InputRow : std::uint32_t { kRefP = 0, kRefQ = 3, kToP = 7, kToQ = 10, kKeyed = 14, kAir = 18, kInputRows = 21 };

struct Inputs {
    HWY_ALIGN float rows[kInputRows * kBatchLanes];
    HWY_ALIGN float colliders[kMaxK * kColliderRows * kBatchLanes];
};

void gather_inputs(const RodStepArgs& args, const RodBatch& batch, const RodTemplateConsts& t, Inputs& in) {
    const rods::RodFrame& frame = *args.frame;
    for (std::size_t l = 0; l < kBatchLanes; ++l) {
        const std::uint32_t c = batch.chain[l];
        const rods::ChainInstance& chain = args.chains[c];
        const rods::Transform& ref = frame.reference[chain.character];
        const rods::Transform& to = frame.roots[c];
        const float values[kInputRows] = {ref.position.x, ref.position.y, ref.position.z, ref.rotation.x, ref.rotation.y,
                                          ref.rotation.z, ref.rotation.w, to.position.x,  to.position.y,  to.position.z,
                                          to.rotation.x,  to.rotation.y,  to.rotation.z,  to.rotation.w};
        for (std::size_t r = 0; r < kKeyed; ++r) in.rows[r * kBatchLanes + l] = values[r];
        // Only a keyed template's kernel reads them (step_lanes).
        for (std::size_t j = 0; j < t.keyed; ++j) {
            in.rows[(kKeyed + j) * kBatchLanes + l] = args.keyed[c * rods::kMaxKeyedExamples + j];
        }
        if (args.air != nullptr) {
            for (std::size_t r = 0; r < 3; ++r) in.rows[(kAir + r) * kBatchLanes + l] = args.air[c * 3 + r];
        }
        for (std::uint32_t k = 0; k < batch.colliders; ++k) {
            float* rows = in.colliders + k * kColliderRows * kBatchLanes;
            float cap[kColliderRows] = {};
            if (k < chain.collider_count) {
                const rods::Collider& cs = frame.colliders[chain.collider_begin + k];
                const float r[kCapOutside] = {cs.a.x, cs.a.y, cs.a.z, cs.b.x, cs.b.y, cs.b.z, rods::collider_reach(cs, t.thickness)};
                for (std::size_t i = 0; i < kCapOutside; ++i) cap[i] = r[i];
                cap[cs.kind == rods::ColliderKind::Plane    ? kCapPlane
                    : cs.kind == rods::ColliderKind::Inside ? kCapInside
                                                            : kCapOutside] = 1.0f;
            }
            for (std::size_t r = 0; r < kColliderRows; ++r) rows[r * kBatchLanes + l] = cap[r];
        }
    }
}

// A quaternion through scalar_math.cpp's partial() lane by lane (solver.cpp partial()).
Q4 partial(const Q4& q, float fraction) {
    if (fraction >= 1.0f) return q;  // partial() returns q itself
    HWY_ALIGN float rows[4 * kBatchLanes];
    store4(q, rows, 0, 0);
    partial_lanes(rows, kBatchLanes, fraction, hn::Lanes(D()));
    return load4(rows, 0, 0);
}

// shape.cpp shortest_arc(), both of its cases computed and one chosen per lane.
Q4 shortest_arc(const V3& from, const V3& to) {
    const V3 h = add(from, to);
    const V h_len = length(h);
    const V3 hn_ = div(h, h_len);
    const V3 c = cross(from, hn_);
    const Q4 regular = qnormalize(Q4{c.x, c.y, c.z, dot(from, hn_)});
    const M opposite = hn::Lt(h_len, S(1e-6f));
    if (hn::AllFalse(D(), opposite)) return regular;  // the usual case: no lane needs the other
    // Opposite vectors: a half turn about the axis from the least aligned coordinate axis.
    const V ax = hn::Abs(from.x), ay = hn::Abs(from.y), az = hn::Abs(from.z);
    const M use_x = hn::And(hn::Le(ax, ay), hn::Le(ax, az));
    const M use_y = hn::AndNot(use_x, hn::Le(ay, az));
    const M use_z = hn::Not(hn::Or(use_x, use_y));
    const V one = S(1.0f);
    const V3 other{hn::IfThenElseZero(use_x, one), hn::IfThenElseZero(use_y, one), hn::IfThenElseZero(use_z, one)};
    const V3 axis = normalize(cross(from, other));
    return select(opposite, Q4{axis.x, axis.y, axis.z, Z()}, regular);
}

// solver.cpp extract_rotation() (one step: kExtractIterations), given the warm start q and
// its matrix r = mat3_cast(q) (the ellipsoid term of the group's centre computed both).
Q4 extract_rotation(const M3& a, const Q4& q, const M3& r) {
    const V3 torque = add(add(cross(r.c[0], a.c[0]), cross(r.c[1], a.c[1])), cross(r.c[2], a.c[2]));
    const V alignment = hn::Abs(hn::Add(hn::Add(dot(r.c[0], a.c[0]), dot(r.c[1], a.c[1])), dot(r.c[2], a.c[2])));
    const V3 half_omega = mul(hn::Div(S(0.5f), hn::Add(alignment, S(1e-9f))), torque);
    return turn(q, half_omega);
}

// shape.cpp blend_one(): the normalized weighted sum of shape k's quaternion i (k = 0..m,
// each flipped into the base's hemisphere).
Q4 blend_one(const std::array<float, 4>* shapes, const float* signs, std::size_t n, std::size_t i, const V* w, std::size_t m) {
    Q4 sum{Z(), Z(), Z(), Z()};
    for (std::size_t k = 0; k <= m; ++k) {
        const V s = hn::Mul(S(signs[k * n + i]), w[k]);
        const float* q = shapes[k * n + i].data();
        sum = qadd(sum, Q4{hn::Mul(S(q[0]), s), hn::Mul(S(q[1]), s), hn::Mul(S(q[2]), s), hn::Mul(S(q[3]), s)});
    }
    const V len = hn::Sqrt(qdot(sum, sum));
    const Q4 normalized{hn::Div(sum.x, len), hn::Div(sum.y, len), hn::Div(sum.z, len), hn::Div(sum.w, len)};
    return select(hn::Gt(len, S(1e-12f)), normalized, splat4(shapes[i].data()));
}

// One frame of the lanes [off, off + Lanes) of a batch. `prefetch`: the next batch's
// block, [prefetch, prefetch_end), asked for a few cache lines at a time while this one
// computes: a batch's state is streamed from memory once per frame (100 000 chains hold
// 130 MB), and the hardware prefetchers see only the current block.
void step_lanes(const RodStepArgs& args, const RodBatch& batch, std::uint32_t resting, const Inputs& in, std::size_t off,
                const float* prefetch, const float* prefetch_end) {
    const RodTemplateConsts& t = args.templates[batch.templ];
    const rods::RodFrame& frame = *args.frame;
    const std::size_t n = t.joints;
    const std::size_t m = t.views;
    float* block = args.storage + batch.offset;
    float* chain_rows = block + n * kJointRows * kBatchLanes;
    auto joint_row = [](std::size_t i, std::uint32_t field) { return i * kJointRows + field; };

    // ---- SPEC A.3: view direction (view.cpp view_direction) and weights (view_weights) ----
    const V3 ref_p = load3(in.rows, kRefP, off);
    const Q4 to_reference = conj(load4(in.rows, kRefQ, off));
    const float back[3] = {-frame.camera.forward.x, -frame.camera.forward.y, -frame.camera.forward.z};
    V3 d = normalize(rotate(to_reference, splat3(back)));
    if (frame.camera.projection == rods::Camera::Projection::Perspective) {
        const float eye[3] = {frame.camera.position.x, frame.camera.position.y, frame.camera.position.z};
        const V3 offset = sub(splat3(eye), ref_p);
        const V len = length(offset);
        d = select(hn::Ge(len, S(1e-6f)), rotate(to_reference, div(offset, len)), d);
    }
    V w[rods::kMaxViewExamples + 1];
    {
        V sum = Z();
        HWY_ALIGN float lanes[kBatchLanes];
        for (std::size_t k = 0; k < m; ++k) {
            const V s = hn::Mul(hn::Add(dot(splat3(t.view_direction[k].data()), d), S(1.0f)), S(0.5f));
            hn::Store(hn::IfThenElse(hn::Lt(s, Z()), Z(), hn::IfThenElse(hn::Lt(S(1.0f), s), S(1.0f), s)), D(), lanes);
            pow_lanes(lanes, t.influence[k], lanes, hn::Lanes(D()));
            w[k + 1] = hn::Load(D(), lanes);
            sum = hn::Add(sum, w[k + 1]);
        }
        const M whole = hn::Ge(sum, S(1.0f));
        for (std::size_t k = 1; k <= m; ++k) w[k] = hn::IfThenElse(whole, hn::Div(w[k], sum), w[k]);
        w[0] = hn::Sub(S(1.0f), hn::IfThenElse(whole, S(1.0f), sum));
    }
    // keyed-examples.md K.4, keyed.cpp combine_weights(): the keyed examples take their
    // share from the view weights.
    const std::size_t mk = m + t.keyed;
    if (t.keyed > 0) {
        V u[rods::kMaxKeyedExamples];
        V sum = Z();
        for (std::size_t j = 0; j < t.keyed; ++j) {
            u[j] = load(in.rows, kKeyed + j, off);
            sum = hn::Add(sum, u[j]);
        }
        const M whole = hn::Ge(sum, S(1.0f));
        const V rest = hn::Sub(S(1.0f), hn::IfThenElse(whole, S(1.0f), sum));
        for (std::size_t k = 0; k <= m; ++k) w[k] = hn::Mul(rest, w[k]);
        for (std::size_t j = 0; j < t.keyed; ++j) w[m + 1 + j] = hn::IfThenElse(whole, hn::Div(u[j], sum), u[j]);
    }

    // ---- SPEC A.2: the blend and forward kinematics (shape.cpp blend, to_positions) ----
    V3 rest_p[kMaxJ];
    Q4 rest_o[kMaxJ];
    if (mk == 0) {  // the base shape, blended at load
        for (std::size_t i = 0; i < n; ++i) {
            rest_p[i] = splat3(t.fixed_rest_position[i].data());
            rest_o[i] = splat4(t.fixed_rest_orientation[i].data());
        }
    } else {
        for (std::size_t i = 0; i < n; ++i) rest_o[i] = blend_one(t.orientation.data(), t.orientation_sign.data(), n, i, w, mk);
        V3 dir = splat3(t.first_direction.data());
        rest_p[0] = zero3();
        for (std::size_t i = 0; i + 1 < n; ++i) {
            const Q4 r = blend_one(t.rotation.data(), t.rotation_sign.data(), n, i, w, mk);
            // Renormalized every segment (shape.cpp).
            dir = normalize(rotate(r, dir));
            rest_p[i + 1] = add(rest_p[i], mul(S(t.lengths[i]), dir));
        }
    }

    // ---- the state ----
    V3 x[kMaxJ], v[kMaxJ], omega[kMaxJ];
    Q4 q[kMaxJ];
    for (std::size_t i = 0; i < n; ++i) {
        x[i] = load3(block, joint_row(i, kX), off);
        v[i] = load3(block, joint_row(i, kV), off);
        q[i] = load4(block, joint_row(i, kQ), off);
        omega[i] = load3(block, joint_row(i, kOmega), off);
    }
    const V3 from_p = load3(chain_rows, kRootP, off);
    const Q4 from_q = load4(chain_rows, kRootQ, off);
    const V3 to_p = load3(in.rows, kToP, off);
    const Q4 to_q = load4(in.rows, kToQ, off);
    const V3 travel = sub(to_p, from_p);

    // ---- the posed level of detail (solver_posed.cpp step_posed) for lanes not full, from the
    // state before the step; a vector of lanes none of which is full skips the substeps ----
    // Posed and hidden lanes (levels 1 and 2), reduced ones (3); the rest are full.
    const V level = args.lod ? load(chain_rows, kLevel, off) : Z();
    const M posed = args.lod ? hn::And(hn::Gt(level, Z()), hn::Lt(level, S(3.0f))) : hn::FirstN(D(), 0);
    const M reduced = args.lod ? hn::Eq(level, S(3.0f)) : hn::FirstN(D(), 0);
    const V share = args.lod ? load(chain_rows, kBlendIn, off) : S(1.0f);
    const M handing = args.lod ? hn::AndNot(posed, hn::Lt(share, S(1.0f))) : hn::FirstN(D(), 0);
    const bool any_handing = args.lod && !hn::AllFalse(D(), handing);
    const bool any_posed = args.lod && (any_handing || !hn::AllFalse(D(), posed));
    V3 posed_x[kMaxJ], posed_v[kMaxJ], posed_omega[kMaxJ], x_before[kMaxJ];
    Q4 posed_q[kMaxJ], q_before[kMaxJ];
    if (any_handing) {
        for (std::size_t i = 0; i < n; ++i) {
            x_before[i] = x[i];
            q_before[i] = q[i];
        }
    }
    if (any_posed) {
        // Over the frames the step covers (cpu_rods.cpp step_chain_reference): dt x (idle + 1)
        // and the blend of that length; a handing lane's posed frame is one frame's.
        const V steps = hn::IfThenElse(handing, S(1.0f), hn::Add(load(chain_rows, kIdle, off), S(1.0f)));
        const V dt = hn::Mul(S(frame.dt), steps);
        const V two_over_dt = hn::Div(S(2.0f), dt);
        V blend = S(args.blend[0]);
        for (std::size_t k = 1; k < args.blend.size(); ++k) {
            blend = hn::IfThenElse(hn::Eq(steps, S(static_cast<float>(k + 1))), S(args.blend[k]), blend);
        }
        const Q4 turn_by = qnormalize(qmul(to_q, conj(from_q)));
        // The colliders at their end-of-frame poses relative to the last root position
        // (solver_posed.cpp step_posed), as place() would leave them.
        CollidersK posed_colliders[kMaxK];
        for (std::size_t k = 0; k < batch.colliders; ++k) {
            const float* rows = in.colliders + k * kColliderRows * kBatchLanes;
            CollidersK& c = posed_colliders[k];
            load_kinds(rows, off, c);
            const V3 b = load3(rows, kCapB, off);
            c.a = sub(load3(rows, kCapA, off), from_p);
            c.ab = select(c.plane, b, sub(sub(b, from_p), c.a));
            c.len2 = dot(c.ab, c.ab);
        }
        V3 parent = zero3();
        for (std::size_t i = 0; i < n; ++i) {
            Q4 goal = qnormalize(qmul(to_q, rest_o[i]));
            V3 px;
            Q4 pq = goal;
            if (i == 0) {
                px = add(travel, rotate(to_q, rest_p[0]));
            } else {
                const V3 sagged = add(travel, rotate(to_q, add(rest_p[i], load3(args.sag + batch.sag_offset, 3 * i, off))));
                const V3 carried = add(travel, rotate(turn_by, x[i]));
                px = add(carried, mul(blend, sub(sagged, carried)));
                const V3 dd = sub(px, parent);
                const V len = length(dd);
                px = select(hn::Gt(len, S(1e-9f)), add(parent, mul(hn::Div(S(t.segment[i - 1]), len), dd)), px);
                for (std::uint32_t pass = 0; pass < rods::kColliderPasses; ++pass) {
                    for (std::size_t k = 0; k < batch.colliders; ++k) collide(px, posed_colliders[k]);
                }
                const Q4 held = qnormalize(qmul(turn_by, q[i]));
                goal = select(hn::Lt(qdot(held, goal), Z()), Q4{hn::Neg(goal.x), hn::Neg(goal.y), hn::Neg(goal.z), hn::Neg(goal.w)},
                              goal);
                const Q4 gap{hn::Sub(goal.x, held.x), hn::Sub(goal.y, held.y), hn::Sub(goal.z, held.z), hn::Sub(goal.w, held.w)};
                pq = qnormalize(qadd(held, Q4{hn::Mul(gap.x, blend), hn::Mul(gap.y, blend), hn::Mul(gap.z, blend),
                                              hn::Mul(gap.w, blend)}));
            }
            parent = px;
            posed_v[i] = div(sub(px, x[i]), dt);
            const Q4 dq = positive_w(qmul(pq, conj(q[i])));
            posed_omega[i] = mul(two_over_dt, V3{dq.x, dq.y, dq.z});
            posed_x[i] = px;
            posed_q[i] = pq;
        }
    }
    // The frame's end: the state (`x_new` relative to the new root), this frame's rest
    // shape, root, view and weights.
    // Lanes that keep their state this frame (RodStepArgs::resting) keep their rows as they
    // were; the others' idle frames are 0 again.
    const bool keeping = (resting >> off) != 0u;
    M keep = hn::FirstN(D(), 0);
    if (keeping) {
        HWY_ALIGN float bits[kBatchLanes];
        for (std::size_t l = 0; l < hn::Lanes(D()); ++l) bits[l] = static_cast<float>((resting >> (off + l)) & 1u);
        keep = hn::Gt(hn::Load(D(), bits), Z());
    }
    auto put = [&](V value, float* rows, std::size_t r) HWY_ATTR {
        if (keeping) value = hn::IfThenElse(keep, load(rows, r, off), value);
        store(value, rows, r, off);
    };
    auto put3 = [&](const V3& value, float* rows, std::size_t r) HWY_ATTR {
        put(value.x, rows, r);
        put(value.y, rows, r + 1);
        put(value.z, rows, r + 2);
    };
    auto put4 = [&](const Q4& value, float* rows, std::size_t r) HWY_ATTR {
        put(value.x, rows, r);
        put(value.y, rows, r + 1);
        put(value.z, rows, r + 2);
        put(value.w, rows, r + 3);
    };
    auto store_frame = [&](const V3* x_new, const V3* v_new, const Q4* q_new, const V3* omega_new) HWY_ATTR {
        for (std::size_t i = 0; i < n; ++i) {
            put3(x_new[i], block, joint_row(i, kX));
            put3(v_new[i], block, joint_row(i, kV));
            put4(q_new[i], block, joint_row(i, kQ));
            put3(omega_new[i], block, joint_row(i, kOmega));
            put3(rest_p[i], block, joint_row(i, kRestP));
            put4(rest_o[i], block, joint_row(i, kRestO));
        }
        put3(to_p, chain_rows, kRootP);
        put4(to_q, chain_rows, kRootQ);
        put3(d, chain_rows, kView);
        for (std::size_t k = 0; k <= rods::kMaxViewExamples; ++k) put(k <= mk ? w[k] : Z(), chain_rows, kWeights + k);
        if (args.lod) put(Z(), chain_rows, kIdle);
    };
    if (any_posed && !any_handing && hn::AllTrue(D(), posed)) {
        for (std::size_t i = 0; i < n; ++i) posed_x[i] = sub(posed_x[i], travel);
        store_frame(posed_x, posed_v, posed_q, posed_omega);
        return;
    }

    // ---- SPEC A.5: momentum suppression (solver.cpp suppress_momentum) ----
    if (t.suppression > 0.0f) {
        const Q4 root_inv = conj(from_q);
        V3 previous_old = x[0];
        V3 old_next = load3(block, joint_row(0, kRestP), off);
        for (std::size_t i = 0; i + 1 < n; ++i) {
            const V3 old_here = old_next;
            old_next = load3(block, joint_row(i + 1, kRestP), off);
            const V3 old_dir = normalize(sub(old_next, old_here));
            const V3 new_dir = normalize(sub(rest_p[i + 1], rest_p[i]));
            const Q4 turn_by = partial(qmul(qmul(from_q, shortest_arc(old_dir, new_dir)), root_inv), t.suppression);
            const V3 segment = sub(x[i + 1], previous_old);
            previous_old = x[i + 1];
            x[i + 1] = add(x[i], rotate(turn_by, segment));
        }
        for (std::size_t i = 1; i < n; ++i) {
            const Q4 change = positive_w(qmul(rest_o[i], conj(load4(block, joint_row(i, kRestO), off))));
            q[i] = qnormalize(qmul(partial(qmul(qmul(from_q, change), root_inv), t.suppression), q[i]));
        }
    }

    // ---- SPEC A.4: the substeps (solver.cpp step), with step sizes `sc`: the template's,
    // or rods::reduced_params' for reduced lanes ----
    // Solved relative to the previous root position; colliders likewise.
    const bool wind = args.air != nullptr;
    const V3 air = wind ? load3(in.rows, kAir, off) : zero3();
    CollidersK colliders[kMaxK];
    const Q4 to_root = conj(to_q);
    for (std::size_t k = 0; k < batch.colliders; ++k) {
        const float* rows = in.colliders + k * kColliderRows * kBatchLanes;
        CollidersK& c = colliders[k];
        load_kinds(rows, off, c);
        // In the end root's frame (solver.cpp): a plane's normal b is a direction.
        const V3 b = load3(rows, kCapB, off);
        c.la = rotate(to_root, sub(load3(rows, kCapA, off), to_p));
        c.lb = select(c.plane, rotate(to_root, b), rotate(to_root, sub(b, to_p)));
    }
    // solver_collide.cpp collide_all(): every collider, the whole set kColliderPasses times.
    auto collide_all = [&](V3& particle) HWY_ATTR {
        for (std::uint32_t pass = 0; pass < rods::kColliderPasses; ++pass) {
            for (std::size_t k = 0; k < batch.colliders; ++k) collide(particle, colliders[k]);
        }
    };
    const Q4 relative_root = qmul(conj(from_q), to_q);  // interpolate(): a^-1 b
    V3 p[kMaxJ], xbar[kMaxJ], obar_axis[kMaxJ], goal_sum[kMaxJ];
    Q4 qs[kMaxJ], obar[kMaxJ], q_new[kMaxJ];
    M3 ellipsoid[kMaxJ];
    // Values the reference computes again where they are the same: a group's rest centre
    // cbar and rest offsets xbar_j - cbar (constant over a substep's iterations), and
    // q_j obar_j^-1 with its matrix (the ellipsoid term's relative rotation is also the
    // warm start of group j's rotation extraction). Same operations, same bits, once.
    V3 cbar[kMaxJ];
    Q4 relative[kMaxJ];
    auto substeps = [&](const RodStepConsts& sc) HWY_ATTR {
        for (std::uint32_t sub_step = 1; sub_step <= sc.substeps; ++sub_step) {
            const float f = static_cast<float>(sub_step) / static_cast<float>(sc.substeps);
            const V3 r_p = mul(S(f), travel);
            const Q4 r_q = qnormalize(qmul(from_q, partial(relative_root, f)));

            // 1-2. Kinematic root and the rest shape placed by the root.
            for (std::size_t i = 0; i < n; ++i) {
                xbar[i] = add(r_p, rotate(r_q, rest_p[i]));
                obar[i] = qnormalize(qmul(r_q, rest_o[i]));
                obar_axis[i] = rotate(obar[i], splat3(t.bone_axis[i].data()));
            }
            p[0] = xbar[0];
            qs[0] = obar[0];
            // 3. The colliders placed by the root.
            for (std::size_t k = 0; k < batch.colliders; ++k) place(colliders[k], r_p, r_q);
            // The parent bones' swing from their rest (solver.cpp step, angle limits).
            const Q4 identity{Z(), Z(), Z(), S(1.0f)};
            Q4 swing = identity;
            V3 pulled[kMaxJ];  // the distance constraints' corrections (DFTL)
            V3 pushed[kMaxJ];  // and the colliders' (their net push, the contact normal)
            for (std::size_t i = 0; i < n; ++i) pulled[i] = zero3();
            for (std::size_t i = 0; i < n; ++i) pushed[i] = zero3();
            auto collide_counted = [&](std::size_t j) HWY_ATTR {
                const V3 before = p[j];
                collide_all(p[j]);
                pushed[j] = add(pushed[j], sub(p[j], before));
            };
            // solver.cpp limit_child(): child i + 1 turned about particle i to the nearest
            // direction segment i's limit allows (shaders/lib/spring_limit.glsl, its every
            // expression repeated per lane), then the parent bones' swing carried past it.
            // The limit's kind is the template's, so one branch serves every lane.
            auto limit_child = [&](std::size_t i) HWY_ATTR {
                const V3 seg = sub(p[i + 1], p[i]);
                const V len = length(seg);
                const M ok = hn::Gt(len, S(1e-9f));
                V3 dir = div(seg, len);
                const std::uint32_t kind = t.limit_kind[i];
                if (kind != 0u) {
                    const Q4 lframe = qmul(qmul(swing, obar[i]), splat4(t.limit_frame[i].data()));
                    const V3 l = rotate(conj(lframe), dir);
                    const V cx = S(t.limit_trig[i][0]), sx = S(t.limit_trig[i][1]);
                    const V singular = S(1e-12f);
                    V3 allowed = l;
                    if (kind == 1u) {
                        const V h2 = hn::Add(hn::Mul(l.x, l.x), hn::Mul(l.z, l.z));
                        const V s = hn::Div(sx, hn::Sqrt(h2));
                        const V3 tilted = select(hn::Le(h2, singular), V3{Z(), cx, sx}, V3{hn::Mul(l.x, s), cx, hn::Mul(l.z, s)});
                        allowed = select(hn::Lt(l.y, cx), tilted, l);
                    } else if (kind == 2u) {
                        const V p2 = hn::Add(hn::Mul(l.y, l.y), hn::Mul(l.z, l.z));
                        const V inv = hn::Div(S(1.0f), hn::Sqrt(p2));
                        V3 e{Z(), hn::Mul(l.y, inv), hn::Mul(l.z, inv)};
                        const V z_side = hn::IfThenElse(hn::Lt(e.z, Z()), hn::Neg(sx), sx);
                        e = select(hn::Lt(e.y, cx), V3{Z(), cx, z_side}, e);
                        allowed = select(hn::Le(p2, singular), V3{Z(), S(1.0f), Z()}, e);
                    } else {
                        const V cyaw = S(t.limit_trig[i][2]), syaw = S(t.limit_trig[i][3]);
                        const V p2 = hn::Add(hn::Mul(l.y, l.y), hn::Mul(l.z, l.z));
                        const M sing = hn::Le(p2, singular);
                        const V inv = hn::Div(S(1.0f), hn::Sqrt(p2));
                        V cp = hn::IfThenElse(sing, S(1.0f), hn::Mul(l.y, inv));
                        V sp = hn::IfThenElse(sing, Z(), hn::Mul(l.z, inv));
                        const M pitch_out = hn::Lt(cp, cx);
                        sp = hn::IfThenElse(pitch_out, hn::IfThenElse(hn::Lt(sp, Z()), hn::Neg(sx), sx), sp);
                        cp = hn::IfThenElse(pitch_out, cx, cp);
                        const M yaw_out = hn::Gt(hn::Abs(l.x), syaw);
                        const V sy = hn::IfThenElse(yaw_out, hn::IfThenElse(hn::Lt(l.x, Z()), hn::Neg(syaw), syaw), l.x);
                        const V cy = hn::IfThenElse(yaw_out, cyaw, hn::Sqrt(p2));
                        const M limited = hn::Or(sing, hn::Or(pitch_out, yaw_out));
                        allowed = select(limited, V3{sy, hn::Mul(cy, cp), hn::Mul(cy, sp)}, l);
                    }
                    // Only a direction the limit changed is turned back (solver.cpp: `allowed != local`).
                    const M changed = hn::Or(hn::Ne(allowed.x, l.x), hn::Or(hn::Ne(allowed.y, l.y), hn::Ne(allowed.z, l.z)));
                    const M apply = hn::And(ok, changed);
                    const V3 turned = rotate(lframe, allowed);
                    dir = select(apply, turned, dir);
                    p[i + 1] = select(apply, add(p[i], mul(len, turned)), p[i + 1]);
                }
                swing = select(ok, qnormalize(qmul(shortest_arc(rotate(swing, obar_axis[i]), dir), swing)), swing);
            };
            // solver.cpp place_on_parent(): child i + 1 on its parent's segment length.
            auto place_on_parent = [&](std::size_t i) HWY_ATTR {
                const V3 dd = sub(p[i + 1], p[i]);
                const V len = length(dd);
                const M along = hn::Gt(len, S(1e-9f));
                const V3 placed_child = add(p[i], mul(hn::Div(S(t.segment[i]), len), dd));
                pulled[i + 1] = select(along, add(pulled[i + 1], sub(placed_child, p[i + 1])), pulled[i + 1]);
                p[i + 1] = select(along, placed_child, p[i + 1]);
            };
            for (std::size_t i = 0; i < n; ++i) {
                const std::size_t lo = i == 0 ? 0 : i - 1;
                const std::size_t hi = i + 1 < n ? i + 1 : n - 1;
                V3 sum = zero3();
                for (std::size_t j = lo; j <= hi; ++j) sum = add(sum, mul(S(t.weight[j]), xbar[j]));
                cbar[i] = div(sum, S(t.group_mass[i]));
            }

            // 4. Predict.
            const V3 h_acceleration = splat3(sc.h_acceleration.data());
            for (std::size_t i = 1; i < n; ++i) {
                if (wind || t.drag) {
                    // Relative to the air (0 without wind), then drag across and along the
                    // segment (solver.cpp); the else branch is this with air = 0 and no drag.
                    V3 rel_air = mul(S(sc.decay), sub(v[i], air));
                    if (t.drag) {
                        const V3 segment = sub(x[i], x[i - 1]);
                        const V len = length(segment);
                        const M along_segment = hn::Gt(len, S(1e-9f));
                        const V3 axis = div(segment, len);
                        const V3 along = mul(dot(rel_air, axis), axis);
                        const V3 dragged = add(mul(S(sc.normal_decay), sub(rel_air, along)), mul(S(sc.tangent_decay), along));
                        rel_air = select(along_segment, dragged, rel_air);
                    }
                    v[i] = add(add(air, rel_air), h_acceleration);
                } else {
                    v[i] = add(mul(S(sc.decay), v[i]), h_acceleration);
                }
                omega[i] = mul(S(sc.decay), omega[i]);
                p[i] = add(x[i], mul(S(sc.h), v[i]));
                qs[i] = turn(q[i], mul(S(sc.half_h), omega[i]));
            }

            // 5. Project.
            for (std::uint32_t it = 0; it < sc.iterations; ++it) {
                // The ellipsoid terms A_j, once per particle.
                for (std::size_t j = 0; j < n; ++j) {
                    for (int line = 0; line < 8 && prefetch < prefetch_end; ++line, prefetch += 16) hwy::Prefetch(prefetch);
                    relative[j] = qmul(qs[j], conj(obar[j]));
                    const M3 rel = mat3_cast(relative[j]);
                    const V3 u = rotate(qs[j], splat3(t.bone_axis[j].data()));
                    const V3& ob = obar_axis[j];
                    const V uc[3] = {u.x, u.y, u.z};
                    const V oc[3] = {ob.x, ob.y, ob.z};
                    const V b2 = S(t.b2), ab = S(t.ab[j]), w5 = S(t.weight5[j]);
                    for (int col = 0; col < 3; ++col) {
                        const V rc[3] = {rel.c[col].x, rel.c[col].y, rel.c[col].z};
                        V e[3];
                        for (int row = 0; row < 3; ++row) {
                            e[row] = hn::Mul(w5, hn::Add(hn::Mul(b2, rc[row]), hn::Mul(ab, hn::Mul(uc[row], oc[col]))));
                        }
                        ellipsoid[j].c[col] = {e[0], e[1], e[2]};
                    }
                    goal_sum[j] = zero3();
                }
                // Shape matching over G_i = {i-1, i, i+1}, clipped at the ends: the goal centre c
                // and rotation of group i, then its goals added to its members' sums, in group
                // order. Two groups at a time, so that the processor overlaps their long chains
                // of dependent operations (the sums still take the groups in order).
                auto group = [&](std::size_t i, V3& c, Q4& rot) HWY_ATTR {
                    const std::size_t lo = i == 0 ? 0 : i - 1;
                    const std::size_t hi = i + 1 < n ? i + 1 : n - 1;
                    c = zero3();
                    for (std::size_t j = lo; j <= hi; ++j) c = add(c, mul(S(t.weight[j]), p[j]));
                    c = div(c, S(t.group_mass[i]));
                    M3 a{{zero3(), zero3(), zero3()}};
                    for (std::size_t j = lo; j <= hi; ++j) {
                        const V3 u = sub(p[j], c), ub = sub(xbar[j], cbar[i]);
                        const V uc[3] = {u.x, u.y, u.z};
                        const V bc[3] = {ub.x, ub.y, ub.z};
                        const V wj = S(t.weight[j]);
                        for (int col = 0; col < 3; ++col) {
                            V* ac[3] = {&a.c[col].x, &a.c[col].y, &a.c[col].z};
                            const V ec[3] = {ellipsoid[j].c[col].x, ellipsoid[j].c[col].y, ellipsoid[j].c[col].z};
                            for (int row = 0; row < 3; ++row) {
                                *ac[row] = hn::Add(hn::Add(*ac[row], hn::Mul(wj, hn::Mul(uc[row], bc[col]))), ec[row]);
                            }
                        }
                    }
                    rot = extract_rotation(a, relative[i], mat3_cast(relative[i]));
                };
                auto goals = [&](std::size_t i, const V3& c, const Q4& rot) HWY_ATTR {
                    const std::size_t lo = i == 0 ? 0 : i - 1;
                    const std::size_t hi = i + 1 < n ? i + 1 : n - 1;
                    for (std::size_t j = lo; j <= hi; ++j) {
                        goal_sum[j] = add(goal_sum[j], add(c, rotate(rot, sub(xbar[j], cbar[i]))));
                    }
                    q_new[i] = qnormalize(qmul(rot, obar[i]));
                };
                std::size_t g = 0;
                for (; g + 1 < n; g += 2) {
                    V3 c0, c1;
                    Q4 r0, r1;
                    group(g, c0, r0);
                    group(g + 1, c1, r1);
                    goals(g, c0, r0);
                    goals(g + 1, c1, r1);
                }
                if (g < n) {
                    V3 c0;
                    Q4 r0;
                    group(g, c0, r0);
                    goals(g, c0, r0);
                }
                for (std::size_t i = 1; i < n; ++i) {
                    const V count = S(i + 1 == n ? 2.0f : 3.0f);
                    p[i] = add(p[i], mul(S(sc.k_iter), sub(div(goal_sum[i], count), p[i])));
                    qs[i] = q_new[i];
                }
                // Rest-pose attraction.
                for (std::size_t i = 1; i < n; ++i) p[i] = add(p[i], mul(S(sc.k_rest), sub(xbar[i], p[i])));
                // Distance constraints, follow-the-leader, each child pushed out of the
                // colliders right after it is placed.
                swing = identity;
                for (std::size_t i = 0; i + 1 < n; ++i) {
                    place_on_parent(i);
                    if (batch.colliders > 0) collide_counted(i + 1);
                    if (t.limited) limit_child(i);
                }
            }
            // The last sweep: placed and pushed out, twice (solver.cpp).
            swing = identity;
            for (std::size_t i = 0; i + 1 < n; ++i) {
                place_on_parent(i);
                if (batch.colliders > 0) {
                    collide_counted(i + 1);
                    place_on_parent(i);
                    collide_counted(i + 1);
                    place_on_parent(i);
                    collide_counted(i + 1);
                }
                if (t.limited) limit_child(i);
            }

            // What the colliders undid is not the parent's to give back (solver.cpp): the part
            // of a child's distance corrections into its colliders' net push direction.
            if (batch.colliders > 0) {
                for (std::size_t i = 1; i < n; ++i) {
                    const V pl = length(pushed[i]);
                    const V3 nn = div(pushed[i], pl);
                    const V along = dot(pulled[i], nn);
                    const M into = hn::And(hn::Gt(pl, Z()), hn::Lt(along, Z()));
                    pulled[i] = select(into, sub(pulled[i], mul(hn::Max(along, hn::Neg(pl)), nn)), pulled[i]);
                }
            }
            // 6. Update, with the dynamic follow-the-leader correction (solver.cpp).
            for (std::size_t i = 0; i < n; ++i) {
                v[i] = div(sub(p[i], x[i]), S(sc.h));
                if (i > 0 && i + 1 < n) v[i] = sub(v[i], mul(S(sc.ftl_over_h), pulled[i + 1]));
                const Q4 dq = positive_w(qmul(qs[i], conj(q[i])));
                omega[i] = mul(S(sc.two_over_h), V3{dq.x, dq.y, dq.z});
                x[i] = p[i];
                q[i] = qs[i];
            }
        }
    };
    // A vector of lanes at one of the two levels steps once; one with both steps the state
    // at each and takes each lane's own.
    const bool any_reduced = args.lod && !hn::AllFalse(D(), reduced);
    const bool any_full = !any_reduced || !hn::AllTrue(D(), hn::Or(reduced, posed));
    if (any_full && any_reduced) {
        // The start kept aside, the full step, then the start back (the full result kept
        // aside in its place) for the reduced step.
        V3 x_other[kMaxJ], v_other[kMaxJ], omega_other[kMaxJ];
        Q4 q_other[kMaxJ];
        auto each = [&](auto&& f) HWY_ATTR {
            f(x, x_other);
            f(v, v_other);
            f(q, q_other);
            f(omega, omega_other);
        };
        each([&](auto* state, auto* other) HWY_ATTR { std::copy(state, state + n, other); });
        substeps(t.step);
        each([&](auto* state, auto* other) HWY_ATTR { std::swap_ranges(state, state + n, other); });
        substeps(t.reduced);
        each([&](auto* state, const auto* other) HWY_ATTR {
            for (std::size_t i = 0; i < n; ++i) state[i] = select(reduced, state[i], other[i]);
        });
    } else {
        substeps(any_reduced ? t.reduced : t.step);
    }

    // ---- store: the state relative to the new root, this frame's rest shape, view, weights ----
    const V dt = S(frame.dt);
    const V two_over_dt = S(2.0f / frame.dt);
    for (std::size_t i = 0; i < n; ++i) {
        V3 stored = sub(x[i], travel);
        if (any_handing) {  // solver_posed.cpp hand_over(): the step's result mixed with the posed one
            const V3 a = sub(posed_x[i], travel);
            const V3 mixed = add(a, mul(share, sub(stored, a)));
            const Q4 pq = posed_q[i];
            const Q4 full = select(hn::Lt(qdot(pq, q[i]), Z()), Q4{hn::Neg(q[i].x), hn::Neg(q[i].y), hn::Neg(q[i].z), hn::Neg(q[i].w)},
                                   q[i]);
            const Q4 gap{hn::Sub(full.x, pq.x), hn::Sub(full.y, pq.y), hn::Sub(full.z, pq.z), hn::Sub(full.w, pq.w)};
            const Q4 qm = qnormalize(qadd(pq, Q4{hn::Mul(gap.x, share), hn::Mul(gap.y, share), hn::Mul(gap.z, share),
                                                 hn::Mul(gap.w, share)}));
            const V3 vm = div(sub(mixed, sub(x_before[i], travel)), dt);
            const Q4 dq = positive_w(qmul(qm, conj(q_before[i])));
            stored = select(handing, mixed, stored);
            v[i] = select(handing, vm, v[i]);
            q[i] = select(handing, qm, q[i]);
            omega[i] = select(handing, mul(two_over_dt, V3{dq.x, dq.y, dq.z}), omega[i]);
        }
        if (any_posed) {  // the posed lanes' results (above) in place of the step's
            stored = select(posed, sub(posed_x[i], travel), stored);
            v[i] = select(posed, posed_v[i], v[i]);
            q[i] = select(posed, posed_q[i], q[i]);
            omega[i] = select(posed, posed_omega[i], omega[i]);
        }
        x[i] = stored;
    }
    store_frame(x, v, q, omega);
}

void step_batches(const RodStepArgs& args, std::size_t begin, std::size_t end) {
    const std::size_t lanes = hn::Lanes(D());
    Inputs in;
    // Every lane of a batch keeps its state (padding lanes repeat lane 0's chain and decide alike).
    constexpr std::uint32_t kAllLanes = (1u << kBatchLanes) - 1u;
    auto resting = [&](std::size_t b) { return args.resting != nullptr ? args.resting[b] : 0u; };
    for (std::size_t b = begin; b < end; ++b) {
        if (resting(b) == kAllLanes) continue;
        const RodBatch& batch = args.batches[b];
        gather_inputs(args, batch, args.templates[batch.templ], in);
        const float* next = nullptr;
        const float* next_end = nullptr;
        std::size_t a = b + 1;
        while (a < end && resting(a) == kAllLanes) ++a;
        if (a < end) {
            const RodBatch& after = args.batches[a];
            next = args.storage + after.offset;
            next_end = next + rod_block_floats(args.templates[after.templ].joints);
        }
        for (std::size_t off = 0; off < batch.count; off += lanes) {
            // The first sub-vector asks for the next block (the others find it on its way).
            step_lanes(args, batch, resting(b), in, off, off == 0 ? next : nullptr, off == 0 ? next_end : nullptr);
        }
    }
}

}  // namespace

RodKernels rod_kernels() { return {&step_batches}; }

}  // namespace HWY_NAMESPACE
}  // namespace kodawari::simd
HWY_AFTER_NAMESPACE();

#if HWY_ONCE
#include "simd/dispatch.hpp"

namespace kodawari::simd {

RodKernels rod_kernels(std::int64_t target) { KW_SIMD_SELECT(target, rod_kernels) }

}  // namespace kodawari::simd
#endif
