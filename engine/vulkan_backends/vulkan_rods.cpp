// The Vulkan rod backend: one dispatch of shaders/rods_step.comp per frame advances every
// chain (view weights, blend, suppression, all substeps and iterations in registers; see
// shaders/shared/rods.h for the layout and why), after one of shaders/rod_keys.comp for
// the chains with keyed examples (docs/keyed-examples.md K.6). Per frame the host writes
// only the kinematic input (reference joints, chain roots, colliders, key sources) and,
// when dt changes, the templates' step sizes and smoothing factors; state stays on the
// device until the caller reads it.
#include "vulkan_backends/vulkan_rods.hpp"

#include <algorithm>
#include <bit>
#include <array>
#include <cmath>
#include <cstring>
#include <deque>
#include <optional>

#include "core/parallel.hpp"

namespace kodawari::vulkan_rods_detail {
namespace {

// RodChainGpu.joints.z of a chain without a center is rods::kNoCenter (checked here, with
// the domain, so that gpu/shared_layout.cpp includes no domain header).
static_assert(rods::kNoCenter == KW_RODS_NO_CENTER);
// RodColliderGpu.b.w is a rods::ColliderKind as a float.
static_assert(static_cast<std::uint32_t>(rods::ColliderKind::Outside) == KW_RODS_COLLIDER_OUTSIDE &&
              static_cast<std::uint32_t>(rods::ColliderKind::Inside) == KW_RODS_COLLIDER_INSIDE &&
              static_cast<std::uint32_t>(rods::ColliderKind::Plane) == KW_RODS_COLLIDER_PLANE);
// The kernel's fixed-size arrays hold what the rod world allows.
static_assert(KW_RODS_MAX_JOINTS == rods::kMaxChainJoints && KW_RODS_MAX_VIEWS == rods::kMaxViewExamples);
static_assert(KW_RODS_MAX_CHAIN_COLLIDERS == rods::kMaxChainColliders && KW_RODS_COLLIDER_PASSES == rods::kColliderPasses);
static_assert(static_cast<float>(KW_RODS_FTL_DAMPING) == rods::kFollowTheLeaderDamping);
static_assert(KW_ROD_KEYS_MAX_SOURCES == rods::kMaxKeySources && KW_ROD_KEYS_MAX_EXAMPLES == rods::kMaxKeyedExamples);
// rods_step.comp keeps u_1 .. u_4 in one vec4 and the combined weights in 8 floats.
static_assert(rods::kMaxKeyedExamples == 4 && rods::kMaxViewExamples + 1 == 8);
static_assert(KW_ROD_KEYS_KIND_MOTION == std::uint32_t(rods::KeyKind::Motion) &&
              KW_ROD_KEYS_KIND_POSE == std::uint32_t(rods::KeyKind::Pose));
static_assert(KW_ROD_KEYS_MEASURE_SPEED == std::uint32_t(rods::MotionMeasure::Speed) &&
              KW_ROD_KEYS_MEASURE_ACCELERATION == std::uint32_t(rods::MotionMeasure::Acceleration) &&
              KW_ROD_KEYS_MEASURE_ANGULAR_SPEED == std::uint32_t(rods::MotionMeasure::AngularSpeed));
static_assert(KW_ROD_KEYS_FRAME_MAGNITUDE == std::uint32_t(rods::MotionFrame::Magnitude) &&
              KW_ROD_KEYS_FRAME_JOINT == std::uint32_t(rods::MotionFrame::Joint));

glm::vec3 vec3_of(const gpu::vec4& v) { return {v.x, v.y, v.z}; }
glm::quat quat_of(const gpu::vec4& v) { return glm::quat(v.w, v.x, v.y, v.z); }
rods::Transform transform_of(const gpu::RodTransformGpu& t) { return {vec3_of(t.position), quat_of(t.rotation)}; }

template <typename T>
std::span<std::byte> writable_bytes_of(std::vector<T>& v) {
    return std::as_writable_bytes(std::span<T>(v));
}

// One set of solver settings' step sizes for a frame of `dt`, computed exactly as
// rods::step computes them (same expressions, same library calls), so both sides use the
// same bits.
struct StepSizes {
    std::uint32_t substeps;
    float h, decay, k_iter, k_rest, normal_decay, tangent_decay;
};
StepSizes step_sizes(const rods::SolverParams& p, float dt) {
    const std::uint32_t substeps = std::max(1u, static_cast<std::uint32_t>(std::ceil(dt / p.max_substep)));
    const float h = dt / static_cast<float>(substeps);
    return {substeps,
            h,
            std::exp(-p.damping * h),
            rods::iteration_stiffness(rods::substep_stiffness(p.stiffness, h), p.iterations),
            rods::iteration_stiffness(rods::substep_stiffness(p.rest_stiffness, h), p.iterations),
            std::exp(-p.normal_drag * h),
            std::exp(-p.tangent_drag * h)};
}

// The step fields of a template for a frame of `dt`: its settings' and the reduced
// level's (rods::reduced_params).
void set_step(gpu::RodTemplateGpu& g, const rods::SolverParams& p, float dt) {
    const StepSizes s = step_sizes(p, dt);
    g.solver = {p.iterations, s.substeps, g.solver.z, g.solver.w};  // z: the keyed examples, w: limited, set at load
    g.step = {s.h, s.decay, s.k_iter, p.momentum_suppression};
    g.physics.y = s.k_rest;
    const bool drag = p.normal_drag > 0.0f || p.tangent_drag > 0.0f;
    g.drag = {s.normal_decay, s.tangent_decay, drag ? 1.0f : 0.0f, 0.0f};
    const rods::SolverParams reduced = rods::reduced_params(p);
    const StepSizes r = step_sizes(reduced, dt);
    g.reduced_step = {r.h, r.decay, r.k_iter, r.k_rest};
    g.reduced_solver = {r.normal_decay, r.tangent_decay, static_cast<float>(reduced.iterations), static_cast<float>(r.substeps)};
}

// The smoothing factors alpha_j of a template's motion keys for a frame of `dt` (K.2),
// the expression of rods::keyed_weights, so both sides smooth with the same bits.
void set_smoothing(gpu::RodKeyTemplateGpu& g, std::span<const rods::KeyedExample> keyed, float dt) {
    for (std::size_t j = 0; j < keyed.size(); ++j) {
        const rods::KeyedExample& e = keyed[j];
        g.smoothing[j].z = e.smoothing > 0.0f ? 1.0f - std::exp(-dt / e.smoothing) : 1.0f;
    }
}

}  // namespace

DeviceSpan VulkanRodBackend::buffer(std::string_view name) const {
    if (world_ == nullptr) return {};
    auto span = [](const compute::Buffer& buffer, std::size_t items, std::size_t element_bytes) {
        return DeviceSpan{.buffer = &buffer,
                          .items = static_cast<std::uint32_t>(items),
                          .element_bytes = static_cast<std::uint32_t>(element_bytes)};
    };
    const auto& b = buffers_;
    const rods::RodWorld& w = *world_;
    if (name == rod_buffers::chain_states) return span(b[KW_RODS_BINDING_CHAIN_STATE], w.chains.size(), sizeof(gpu::RodChainStateGpu));
    if (name == rod_buffers::motion) return span(b[KW_RODS_BINDING_MOTION], w.joint_count, sizeof(gpu::RodJointMotionGpu));
    if (name == rod_buffers::spin) return span(b[KW_RODS_BINDING_SPIN], w.joint_count, sizeof(gpu::RodJointSpinGpu));
    if (name == rod_buffers::reference) return span(b[KW_RODS_BINDING_REFERENCE], w.character_count, sizeof(gpu::RodTransformGpu));
    if (name == rod_buffers::roots) return span(b[KW_RODS_BINDING_ROOTS], w.chains.size(), sizeof(gpu::RodTransformGpu));
    if (name == rod_buffers::colliders) return span(b[KW_RODS_BINDING_COLLIDERS], w.collider_count, sizeof(gpu::RodColliderGpu));
    if (name == rod_buffers::centers) return span(b[KW_RODS_BINDING_CENTERS], w.center_count, sizeof(gpu::RodTransformGpu));
    if (name == rod_buffers::keys) return span(key_buffers_[KW_ROD_KEYS_BINDING_KEYS], w.key_count, sizeof(gpu::RodTransformGpu));
    return {};
}

Result<void> VulkanRodBackend::step(const rods::RodFrame& frame) {
    const compute::Queue queue(*ctx_);
    auto recording = queue.begin();
    if (!recording) return recording.error();
    KW_TRY(record(recording.value(), frame, true));
    auto submission = queue.submit(std::move(recording).value());
    if (!submission) return submission.error();
    double ms = -1.0;
    KW_TRY(submission.value().wait(&ms));
    gpu_ms_ = ms;
    return {};
}

Result<void> VulkanRodBackend::record_step(compute::Recording& recording, const rods::RodFrame& frame) {
    assert(&recording.device() == ctx_.get() && "a recording of the backend's device");
    // Untimed: the timestamps are the caller's submission's.
    return record(recording, frame, false);
}

Result<void> VulkanRodBackend::record_external(compute::Recording& borrowed, const rods::RodFrame& frame) {
    if (world_ == nullptr) return make_error(Error::Kind::InvalidInput, "record_step: the backend has no world; load() one first");
    KW_TRY(rods::check_frame(*world_, frame));
    if (!ring_) {
        // The most one frame uploads: the templates (when dt changes) and the input.
        auto rounded = [](std::uint64_t bytes) { return (bytes + 15) / 16 * 16; };
        const std::uint64_t bytes = rounded(templates_.size() * sizeof(gpu::RodTemplateGpu)) +
                                    rounded(key_templates_.size() * sizeof(gpu::RodKeyTemplateGpu)) +
                                    rounded(std::uint64_t{world_->key_count} * sizeof(gpu::RodTransformGpu)) +
                                    rounded(std::uint64_t{world_->character_count} * sizeof(gpu::RodTransformGpu)) +
                                    rounded(world_->chains.size() * sizeof(gpu::RodTransformGpu)) +
                                    rounded(std::uint64_t{world_->collider_count} * sizeof(gpu::RodColliderGpu)) +
                                    rounded(std::uint64_t{world_->center_count} * sizeof(gpu::RodTransformGpu)) +
                                    rounded(std::uint64_t{world_->wind_count} * sizeof(gpu::RodWindGpu));
        auto ring = compute::StagingRing::create(*ctx_, bytes, ctx_->frames_in_flight());
        if (!ring) return ring.error();
        ring_.emplace(std::move(ring).value());
    }
    ring_->next_frame();
    auto recording = borrowed.share(&*ring_);
    // The application's reads of the previous frame's state and input (draws, its
    // kernels, copies) before this frame's copies and dispatch overwrite them.
    compute::barrier(recording, embedding_consumers(*ctx_), compute::Stage::Transfer | compute::Stage::Compute);
    KW_TRY(record(recording, frame, false));
    compute::barrier(recording, compute::Stage::Compute, embedding_consumers(*ctx_));
    return {};
}

Result<void> VulkanRodBackend::read(ChainSnapshot& out) {
    assert(world_ != nullptr && "load() first");
    KW_TRY(fetch());
    const std::size_t count = world_->chains.size();
    constexpr std::size_t kWeights = rods::kMaxViewExamples + 1;
    out.positions.resize(world_->joint_count);
    out.orientations.resize(world_->joint_count);
    out.rest.resize(world_->joint_count);
    out.view_directions.resize(count);
    out.weights.assign(count * kWeights, 0.0f);
    for (std::size_t c = 0; c < count; ++c) {
        const rods::ChainInstance& ch = world_->chains[c];
        const gpu::RodChainStateGpu& cs = chain_states_[c];
        const rods::Transform root = transform_of(cs.root);
        out.view_directions[c] = vec3_of(cs.view);
        const float w[8] = {cs.weights[0].x, cs.weights[0].y, cs.weights[0].z, cs.weights[0].w,
                            cs.weights[1].x, cs.weights[1].y, cs.weights[1].z, cs.weights[1].w};
        // W_0 .. W_{m+J} (K.4): the base, the views, the keyed examples.
        const std::size_t shapes = world_->templ(ch).shapes.size();
        for (std::size_t k = 0; k < shapes; ++k) out.weights[c * kWeights + k] = w[k];
        const rods::ChainShape rest = rest_of(static_cast<std::uint32_t>(c));
        for (std::uint32_t i = 0; i < world_->templ(ch).chain.joint_count; ++i) {
            const std::uint32_t j = ch.joint_begin + i;
            out.positions[j] = root.position + vec3_of(motion_[j].x);
            out.orientations[j] = quat_of(spin_[j].q);
            out.rest[j] = root.position + root.rotation * rest.positions[i];
        }
    }
    return {};
}

Result<void> VulkanRodBackend::read_states(std::vector<rods::ChainState>& out) {
    assert(world_ != nullptr && "load() first");
    KW_TRY(fetch());
    out.assign(world_->chains.size(), rods::ChainState{});
    for (std::size_t c = 0; c < out.size(); ++c) {
        const rods::ChainInstance& ch = world_->chains[c];
        rods::ChainState& s = out[c];
        s.root = transform_of(chain_states_[c].root);
        s.started = started_;
        const auto packed = static_cast<std::uint32_t>(chain_states_[c].view.w);  // level + KW_RODS_IDLE_UNIT x idle
        s.level = packed % KW_RODS_IDLE_UNIT;
        s.idle = packed / KW_RODS_IDLE_UNIT;
        s.blend_in = chain_states_[c].root.position.w;
        if (ch.center != rods::kNoCenter) s.center = transform_of(center_states_[ch.center]);
        const rods::ChainShape rest = rest_of(static_cast<std::uint32_t>(c));
        for (std::uint32_t i = 0; i < world_->templ(ch).chain.joint_count; ++i) {
            const std::uint32_t j = ch.joint_begin + i;
            s.x[i] = vec3_of(motion_[j].x);
            s.v[i] = vec3_of(motion_[j].v);
            s.q[i] = quat_of(spin_[j].q);
            s.omega[i] = vec3_of(spin_[j].omega);
            s.sag[i] = {motion_[j].x.w, motion_[j].v.w, spin_[j].omega.w};
            s.rest_position[i] = rest.positions[i];
            s.rest_orientation[i] = rest.orientations[i];
        }
    }
    return {};
}

// The step of `frame`: its input (and, when dt changed, the templates' step sizes)
// written, the input writer's kernels, then the step's dispatch between the
// timestamps when `timed`, its writes made visible to the host and to copies.
Result<void> VulkanRodBackend::record(compute::Recording& recording, const rods::RodFrame& frame, bool timed) {
    assert(world_ != nullptr && "load() first");
    KW_TRY(rods::check_frame(*world_, frame));
    if (frame.dt != dt_) {
        const float blend = rods::posed_blend(world_->lod, frame.dt);
        for (std::size_t t = 0; t < templates_.size(); ++t) {
            set_step(templates_[t], world_->templates[t].params, frame.dt);
            templates_[t].accel.w = blend;  // the world's, in every template (rods::step_posed)
            templates_[t].drag.w = frame.dt / world_->lod.blend_time;  // rods::blend_in's step
        }
        KW_TRY(compute::upload(recording, buffers_[KW_RODS_BINDING_TEMPLATES], bytes_of(templates_)));
        for (std::size_t t = 0; t < key_templates_.size(); ++t) set_smoothing(key_templates_[t], world_->templates[t].keyed, frame.dt);
        KW_TRY(compute::upload(recording, key_buffers_[KW_ROD_KEYS_BINDING_TEMPLATES], bytes_of(key_templates_)));
        dt_ = frame.dt;
    }
    for (const rods::Collider& c : frame.colliders) {
        if ((feature_of(c.kind) & ~features_) != 0u) {
            return make_error(Error::Kind::InvalidInput,
                              "rod frame: a collider of a kind (inside or plane) the world's first frame did not have; "
                              "the kernel is specialized to the kinds it loaded with: load() the world again");
        }
    }
    if ((features_ & KW_RODS_FEATURE_AIR) == 0u && moving_air(frame)) {
        features_ |= KW_RODS_FEATURE_AIR;
        KW_TRY(select_kernels());
    }
    KW_TRY(upload_input(recording, frame));
    if (input_writer_) input_writer_->record(recording, *this);

    const bool ortho = frame.camera.projection == rods::Camera::Projection::Orthographic;
    // The world's first step starts its chains moving with their roots (rods::start_moving).
    // Levels of detail: the camera's part of the decision (rods::lod_view), for
    // shaders/lib/rod_lod.glsl.
    const rods::LodView lod = rods::lod_view(world_->lod, frame.camera, frame.full_distance_cap);
    // The posed and hidden levels' rate (rods::rate_turn): the frame's turn mod 4 and the
    // first character's place in its group, which with each chain's character give its turn.
    const std::uint32_t rate = lod.enabled && lod.lower_rate && frame.number != rods::kNoFrameNumber
                                   ? KW_RODS_RATE_ON | ((frame.number + frame.first_character / KW_RODS_RATE_GROUP) & 3u) |
                                         ((frame.first_character % KW_RODS_RATE_GROUP) << 2u)
                                   : 0u;
    gpu::RodPush push{{},
                      {},
                      to_gpu(frame.camera.position, ortho ? 1.0f : 0.0f),
                      to_gpu(frame.camera.forward, frame.dt),
                      {(started_ ? 0u : KW_RODS_STEP_FIRST) | (moving_air(frame) ? KW_RODS_STEP_WIND : 0u) |
                           (lod.enabled ? KW_RODS_STEP_LOD : 0u),
                       std::bit_cast<std::uint32_t>(lod.reduced_distance), std::bit_cast<std::uint32_t>(lod.reduced_stay),
                       rate},
                      {frame.time, lod.margin, lod.full_distance, lod.stay_distance},
                      to_gpu(lod.right, lod.tan_x),
                      to_gpu(lod.up, lod.tan_y)};
    started_ = true;
    auto dispatch = [&](const compute::Kernel* kernel, std::uint32_t first, std::uint32_t chains) {
        push.counts.x = chains;
        push.counts.y = first;
        kernel->dispatch(recording, std::as_bytes(std::span(&push, 1)), compute::groups_for(chains, chains_per_group()));
    };
    // What earlier dispatches and copies wrote (the state this dispatch reads and
    // overwrites, the input) before the step.
    compute::barrier(recording, compute::Stage::Compute | compute::Stage::Transfer, compute::Stage::Compute);
    if (timed) recording.timestamp(compute::Timestamp::Begin);
    if (keyed_chains_ > 0) {
        // K.2, K.3: the raw keyed weights, which the step reads (K.4).
        const gpu::RodKeyPush key_push{{keyed_chains_, lod.enabled ? 1u : 0u, push.flags.w, 0u},
                                       {frame.dt, lod.margin, lod.full_distance, lod.stay_distance},
                                       to_gpu(frame.camera.position, lod.reduced_distance),
                                       to_gpu(frame.camera.forward, lod.reduced_stay),
                                       push.camera_right,
                                       push.camera_up};
        const std::uint32_t key_groups = (keyed_chains_ + KW_ROD_KEYS_WORKGROUP_SIZE - 1) / KW_ROD_KEYS_WORKGROUP_SIZE;
        key_kernel_->dispatch(recording, std::as_bytes(std::span(&key_push, 1)), key_groups);
        compute::barrier(recording, compute::Stage::Compute, compute::Stage::Compute);
    }
    if (grouped_) {
        // Disjoint chains: the dispatches need no barrier between them.
        for (const Group& g : groups_) {
            const gpu::RodTemplateGpu& t = templates_[g.template_index];
            push.counts.z = t.counts.z;
            push.counts.w = t.counts.w;
            push.group = {g.template_index, t.counts.x, t.counts.y, t.solver.z};
            dispatch(g.kernel, g.first, g.count);
        }
    } else {
        dispatch(kernel_, 0u, static_cast<std::uint32_t>(world_->chains.size()));
    }
    if (timed) recording.timestamp(compute::Timestamp::End);
    // The host reads mapped state after the fence; staged reads copy it.
    compute::barrier(recording, compute::Stage::Compute, compute::Stage::Host | compute::Stage::Transfer);
    return {};
}

// The rest shape of chain c's last frame from its weights (SPEC A.2), as the kernel
// blends it; the GPU keeps only the weights.
rods::ChainShape VulkanRodBackend::rest_of(std::uint32_t c) const {
    const rods::ChainTemplate& t = world_->templ(world_->chains[c]);
    const gpu::RodChainStateGpu& cs = chain_states_[c];
    const float w[8] = {cs.weights[0].x, cs.weights[0].y, cs.weights[0].z, cs.weights[0].w,
                        cs.weights[1].x, cs.weights[1].y, cs.weights[1].z, cs.weights[1].w};
    return rods::to_positions(t.basis, rods::blend(t.shapes, std::span<const float>(w, t.shapes.size())));
}

Result<void> VulkanRodBackend::fetch() {
    motion_.resize(world_->joint_count);
    spin_.resize(world_->joint_count);
    chain_states_.resize(world_->chains.size());
    KW_TRY(compute::download(*ctx_, buffers_[KW_RODS_BINDING_MOTION], writable_bytes_of(motion_)));
    KW_TRY(compute::download(*ctx_, buffers_[KW_RODS_BINDING_SPIN], writable_bytes_of(spin_)));
    KW_TRY(compute::download(*ctx_, buffers_[KW_RODS_BINDING_CHAIN_STATE], writable_bytes_of(chain_states_)));
    center_states_.resize(world_->center_count);
    KW_TRY(compute::download(*ctx_, buffers_[KW_RODS_BINDING_CENTER_STATE], writable_bytes_of(center_states_)));
    return {};
}

}  // namespace kodawari::vulkan_rods_detail

namespace kodawari {

using vulkan_rods_detail::VulkanRodBackend;

Result<std::unique_ptr<RodBackend>> make_vulkan_rod_backend(const BackendOptions& options) {
    auto ctx = backend_context(options);
    if (!ctx) return ctx.error();
    auto workgroup = compute::workgroup_size(*ctx.value(), options.workgroup_size, KW_RODS_WORKGROUP_SIZE);
    if (!workgroup) return workgroup.error();
    return std::unique_ptr<RodBackend>(
        std::make_unique<VulkanRodBackend>(std::move(ctx).value(), workgroup.value(), options.rod_kernel));
}

}  // namespace kodawari
