// The Vulkan rod backend: one dispatch of shaders/rods_step.comp per frame advances every
// chain (view weights, blend, suppression, all substeps and iterations in registers; see
// shaders/shared/rods.h for the layout and why), after one of shaders/rod_keys.comp for
// the chains with keyed examples (docs/keyed-examples.md K.6). Per frame the host writes
// only the kinematic input (reference joints, chain roots, colliders, key sources) and,
// when dt changes, the templates' step sizes and smoothing factors; state stays on the
// device until the caller reads it.
#include <algorithm>
#include <bit>
#include <array>
#include <cmath>
#include <cstring>
#include <deque>
#include <optional>

#include <kodawari/shared/rod_keys.h>
#include <kodawari/shared/rods.h>

#include "backends/backends.hpp"
#include "vulkan_backends/device_backends.hpp"
#include "core/parallel.hpp"

namespace kodawari {
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

using compute::Buffer;

gpu::vec4 to_gpu(glm::vec3 v, float w = 0.0f) { return {v.x, v.y, v.z, w}; }
gpu::vec4 to_gpu(glm::quat q) { return {q.x, q.y, q.z, q.w}; }
// The KW_RODS_FEATURE_* a collider kind needs (0: outside colliders are always compiled in).
std::uint32_t feature_of(rods::ColliderKind kind) {
    switch (kind) {
        case rods::ColliderKind::Inside: return KW_RODS_FEATURE_INSIDE;
        case rods::ColliderKind::Plane: return KW_RODS_FEATURE_PLANE;
        case rods::ColliderKind::Outside: break;
    }
    return 0u;
}
glm::vec3 vec3_of(const gpu::vec4& v) { return {v.x, v.y, v.z}; }
glm::quat quat_of(const gpu::vec4& v) { return glm::quat(v.w, v.x, v.y, v.z); }
gpu::RodTransformGpu to_gpu(const rods::Transform& t) { return {to_gpu(t.position), to_gpu(t.rotation)}; }
rods::Transform transform_of(const gpu::RodTransformGpu& t) { return {vec3_of(t.position), quat_of(t.rotation)}; }

template <typename T>
std::span<const std::byte> bytes_of(const std::vector<T>& v) {
    return std::as_bytes(std::span<const T>(v));
}
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

// A wind field as the kernel takes it (shared/rods.h), with rods::air_velocity's own
// reciprocals, so both sides scale the noise by the same bits.
gpu::RodWindGpu to_gpu(const rods::WindField& w) {
    return {to_gpu(w.velocity, w.gust), {1.0f / w.gust_period, 1.0f / w.gust_size, 0.0f, 0.0f}, {w.seed, 0u, 0u, 0u}};
}

// The smoothing factors alpha_j of a template's motion keys for a frame of `dt` (K.2),
// the expression of rods::keyed_weights, so both sides smooth with the same bits.
void set_smoothing(gpu::RodKeyTemplateGpu& g, std::span<const rods::KeyedExample> keyed, float dt) {
    for (std::size_t j = 0; j < keyed.size(); ++j) {
        const rods::KeyedExample& e = keyed[j];
        g.smoothing[j].z = e.smoothing > 0.0f ? 1.0f - std::exp(-dt / e.smoothing) : 1.0f;
    }
}

// A template's keyed examples (shared/rod_keys.h), alpha left for set_smoothing.
gpu::RodKeyTemplateGpu key_template(const rods::ChainTemplate& t) {
    gpu::RodKeyTemplateGpu g{};
    std::uint32_t motion = 0;
    for (std::size_t s = 0; s < t.key_sources.size(); ++s) {
        if (t.key_sources[s] == rods::KeySourceKind::Motion) motion |= 1u << s;
    }
    g.counts = {static_cast<std::uint32_t>(t.key_sources.size()), static_cast<std::uint32_t>(t.keyed.size()), motion,
                std::bit_cast<std::uint32_t>(t.params.teleport_distance)};
    for (std::size_t j = 0; j < t.keyed.size(); ++j) {
        const rods::KeyedExample& e = t.keyed[j];
        const bool pose = e.kind == rods::KeyKind::Pose;
        g.examples[j] = {static_cast<std::uint32_t>(e.kind), pose ? e.source_mask : e.source, static_cast<std::uint32_t>(e.measure),
                         static_cast<std::uint32_t>(e.frame)};
        g.keys[j] = to_gpu(e.value, e.influence);
        g.smoothing[j] = {e.smoothing, e.saturation, 1.0f, 0.0f};
        for (std::size_t s = 0; s < rods::kMaxKeySources; ++s) {
            g.rotations[j * KW_ROD_KEYS_MAX_SOURCES + s] = to_gpu(e.rotations[s]);
        }
    }
    return g;
}

class VulkanRodBackend final : public RodBackend, public DeviceRodBackend, public DeviceData {
public:
    VulkanRodBackend(std::shared_ptr<compute::Device> ctx, std::uint32_t workgroup, RodKernel kernel)
        : ctx_(std::move(ctx)), workgroup_(workgroup), kernel_kind_(kernel), joint_lanes_(kernel == RodKernel::PerJoint) {}

    using Variant = std::array<std::uint32_t, KW_RODS_SPEC_COUNT>;

    /// The kernel specialized for a world (shared/rods.h, KW_RODS_SPEC_*); built on first
    /// use and kept. The backend's one RodKernel picks the shader.
    Result<const compute::Kernel*> pipeline(const Variant& spec) {
        for (const auto& [key, p] : pipelines_) {
            if (key == spec) return &p;
        }
        const std::vector<compute::Binding> types(KW_RODS_BINDING_COUNT, compute::Binding::Storage);
        const char* kernel = kernel_kind_ == RodKernel::PerJoint                  ? "rods_lanes"
                             : kernel_kind_ == RodKernel::PerChainSharedConstants ? "rods_step_shared"
                                                                                  : "rods_step";
        auto created = compute::Kernel::create(*ctx_, kernel, types, sizeof(gpu::RodPush), spec);
        if (!created) return created.error();
        pipelines_.emplace_back(spec, std::move(created).value());
        return &pipelines_.back().second;
    }

    std::string_view name() const override { return "vulkan"; }
    std::string device() const override { return ctx_->info().name; }
    double last_gpu_ms() const override { return gpu_ms_; }
    std::uint32_t validation_messages() const override { return ctx_->validation_messages(); }
    const DeviceData* device_data() const override { return world_ != nullptr ? this : nullptr; }
    const compute::Device& context() const override { return *ctx_; }
    DeviceSpan buffer(std::string_view name) const override {
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
    void set_input_writer(std::shared_ptr<const RodInputWriter> writer) override { input_writer_ = std::move(writer); }
    const rods::RodWorld* world() const override { return world_; }
    compute::Device& compute_device() const override { return *ctx_; }

    Result<void> load(const rods::RodWorld& world, const rods::RodFrame& initial) override {
        KW_TRY(rods::check_frame(world, initial));
        const std::size_t count = world.chains.size();
        if (count == 0) return make_error(Error::Kind::InvalidInput, "the world has no chains");
        if (kernel_kind_ != RodKernel::PerChain) {
            auto lanes = kernel_variant_for(world);
            if (!lanes) return lanes.error();
            lanes_ = lanes.value();
        }
        if (compute::groups_for(count, chains_per_group()) > ctx_->info().max_workgroup_count[0]) {
            return make_error(Error::Kind::Unsupported,
                              std::to_string(count) + " chains exceed what one dispatch on " + ctx_->info().name + " can cover");
        }
        world_ = &world;
        dt_ = -1.0f;
        started_ = false;
        ring_.reset();  // sized for the world

        // Constants: templates, their joints and shapes.
        std::uint32_t max_joints = 2, max_views = 0, max_keyed = 0, max_colliders = 0;
        bool all_none = true, all_full = true;
        bool limits = false;  // a template with angle limits (KW_RODS_FEATURE_LIMITS)
        templates_.clear();
        key_templates_.clear();
        std::vector<gpu::RodTemplateJointGpu> tjoints;
        std::vector<gpu::RodShapeJointGpu> shapes;
        for (const rods::ChainTemplate& t : world.templates) {
            const std::uint32_t n = t.chain.joint_count;
            max_joints = std::max(max_joints, n);
            max_views = std::max(max_views, static_cast<std::uint32_t>(t.views.size()));
            max_keyed = std::max(max_keyed, static_cast<std::uint32_t>(t.keyed.size()));
            all_none = all_none && t.params.momentum_suppression == 0.0f;
            all_full = all_full && t.params.momentum_suppression == 1.0f;
            gpu::RodTemplateGpu g{};
            g.counts = {n, static_cast<std::uint32_t>(t.views.size()), static_cast<std::uint32_t>(tjoints.size()),
                        static_cast<std::uint32_t>(shapes.size())};
            g.solver.z = static_cast<std::uint32_t>(t.keyed.size());
            g.solver.w = t.chain.limited ? 1u : 0u;
            limits = limits || t.chain.limited;
            g.physics = {t.chain.thickness, 0.0f, t.params.teleport_distance, t.params.settle_start ? 1.0f : 0.0f};
            g.accel = to_gpu(t.params.gravity + t.params.wind);
            g.first_dir = to_gpu(t.basis.first_direction);
            for (std::size_t k = 0; k < t.views.size(); ++k) g.views[k] = to_gpu(t.views[k].direction, t.views[k].influence);
            templates_.push_back(g);
            key_templates_.push_back(key_template(t));
            for (std::uint32_t i = 0; i < n; ++i) {
                tjoints.push_back({to_gpu(t.chain.bone_axis[i], t.chain.mass[i]),
                                   {t.chain.segment_length[i], t.chain.half_length[i],
                                    static_cast<float>(static_cast<std::uint32_t>(t.chain.limit[i].kind)), 0.0f},
                                   {t.chain.limit_trig[i].x, t.chain.limit_trig[i].y, t.chain.limit_trig[i].z,
                                    t.chain.limit_trig[i].w},
                                   to_gpu(t.chain.limit_frame[i])});
            }
            const rods::RotationShape& base = t.shapes[0];
            for (const rods::RotationShape& s : t.shapes) {
                for (std::uint32_t i = 0; i < n; ++i) {
                    const glm::quat identity(1.0f, 0.0f, 0.0f, 0.0f);
                    glm::quat r = i + 1 < n ? s.rotations[i] : identity;
                    glm::quat o = s.orientations[i];
                    // The blend's hemisphere flip (rods::blend), once here (see RodShapeJointGpu).
                    if (glm::dot(r, i + 1 < n ? base.rotations[i] : identity) < 0.0f) r = -r;
                    if (glm::dot(o, base.orientations[i]) < 0.0f) o = -o;
                    shapes.push_back({to_gpu(r), to_gpu(o)});
                }
            }
        }
        // The chains listed by template: each template's run is one GROUPED dispatch.
        std::vector<std::uint32_t> order(count);
        for (std::uint32_t c = 0; c < count; ++c) order[c] = c;
        std::stable_sort(order.begin(), order.end(), [&](std::uint32_t a, std::uint32_t b) {
            return world.chains[a].template_index < world.chains[b].template_index;
        });
        std::vector<gpu::RodChainGpu> chains(count);
        groups_.clear();
        for (std::uint32_t e = 0; e < count; ++e) {
            const std::uint32_t c = order[e];
            const rods::ChainInstance& ch = world.chains[c];
            max_colliders = std::max(max_colliders, ch.collider_count);
            chains[e] = {{ch.template_index, ch.character, ch.collider_begin, ch.collider_count},
                         {ch.joint_begin, c, ch.center, world.wind_count > 0 ? ch.wind : 0u}};
            if (groups_.empty() || groups_.back().template_index != ch.template_index) {
                groups_.push_back({ch.template_index, e, 0u, nullptr});
            }
            ++groups_.back().count;
        }
        grouped_ = groups_.size() <= KW_RODS_MAX_GROUPS;

        // The chains with keyed examples, listed densely for rod_keys.comp, and their key
        // state as rods::initial_key_state makes it: every source's last pose the initial
        // frame's, no velocity yet, every smoothed key 0.
        std::vector<gpu::RodKeyChainGpu> key_chains;
        std::vector<gpu::RodKeyStateGpu> key_states;
        for (std::uint32_t c = 0; c < count; ++c) {
            const rods::ChainInstance& ch = world.chains[c];
            if (world.templ(ch).keyed.empty()) continue;
            key_chains.push_back({{ch.template_index, c, ch.key_begin,
                                   ch.center != rods::kNoCenter ? KW_ROD_KEYS_EVERY_FRAME : ch.character}});
            const rods::KeyState initial_keys = rods::initial_key_state(world, c, initial);
            gpu::RodKeyStateGpu ks{};
            for (std::size_t k = 0; k < rods::kMaxKeySources; ++k) {
                const rods::KeyState::Source& src = initial_keys.sources[k];
                ks.position[k] = to_gpu(src.last.position, src.has_velocity ? 1.0f : 0.0f);
                ks.rotation[k] = to_gpu(src.last.rotation);
                ks.velocity[k] = to_gpu(src.velocity);
            }
            for (std::size_t j = 0; j < rods::kMaxKeyedExamples; ++j) ks.smoothed[j] = to_gpu(initial_keys.smoothed[j]);
            key_states.push_back(ks);
        }
        keyed_chains_ = static_cast<std::uint32_t>(key_chains.size());

        // The initial state, from the CPU reference's initial_state (so all backends start
        // from the same bits).
        std::vector<gpu::RodJointMotionGpu> motion(world.joint_count);
        std::vector<gpu::RodJointSpinGpu> spin(world.joint_count);
        std::vector<gpu::RodChainStateGpu> chain_states(count);
        parallel_for(count, 0, [&](std::size_t begin, std::size_t end) {
            for (std::size_t c = begin; c < end; ++c) {
                const rods::ChainInstance& ch = world.chains[c];
                const rods::RestShape r = rods::rest_shape(world, static_cast<std::uint32_t>(c), initial);
                const rods::ChainState s = rods::initial_chain_state(world, static_cast<std::uint32_t>(c), initial);
                for (std::uint32_t i = 0; i < world.templ(ch).chain.joint_count; ++i) {
                    const std::uint32_t j = ch.joint_begin + i;
                    // The w components hold the chain's sag (rods::ChainState::sag), which no
                    // step changes.
                    motion[j] = {to_gpu(s.x[i], s.sag[i].x), to_gpu(s.v[i], s.sag[i].y)};
                    spin[j] = {to_gpu(s.q[i]), to_gpu(s.omega[i], s.sag[i].z)};
                }
                gpu::RodChainStateGpu& cs = chain_states[c];
                cs.root = to_gpu(s.root);
                cs.root.position.w = s.blend_in;
                cs.view = to_gpu(r.view_direction, static_cast<float>(s.level + KW_RODS_IDLE_UNIT * s.idle));
                float w[8] = {};
                std::copy(r.weights.begin(), r.weights.end(), w);
                cs.weights[0] = {w[0], w[1], w[2], w[3]};
                cs.weights[1] = {w[4], w[5], w[6], w[7]};
            }
        });

        buffers_.clear();
        const std::uint64_t sizes[KW_RODS_BINDING_COUNT] = {
            templates_.size() * sizeof(gpu::RodTemplateGpu),
            tjoints.size() * sizeof(gpu::RodTemplateJointGpu),
            shapes.size() * sizeof(gpu::RodShapeJointGpu),
            chains.size() * sizeof(gpu::RodChainGpu),
            std::uint64_t{world.character_count} * sizeof(gpu::RodTransformGpu),
            count * sizeof(gpu::RodTransformGpu),
            std::uint64_t{world.collider_count} * sizeof(gpu::RodColliderGpu),
            motion.size() * sizeof(gpu::RodJointMotionGpu),
            spin.size() * sizeof(gpu::RodJointSpinGpu),
            chain_states.size() * sizeof(gpu::RodChainStateGpu),
            count * sizeof(gpu::vec4),
            std::uint64_t{world.center_count} * sizeof(gpu::RodTransformGpu),
            std::uint64_t{world.center_count} * sizeof(gpu::RodTransformGpu),
            std::uint64_t{world.wind_count} * sizeof(gpu::RodWindGpu)};
        auto storage = compute::create_storage_buffers(*ctx_, sizes, "the rod world");
        if (!storage) return storage.error();
        buffers_ = std::move(storage).value();
        KW_TRY(compute::upload(*ctx_, buffers_[KW_RODS_BINDING_TEMPLATE_JOINTS], bytes_of(tjoints)));
        KW_TRY(compute::upload(*ctx_, buffers_[KW_RODS_BINDING_SHAPES], bytes_of(shapes)));
        KW_TRY(compute::upload(*ctx_, buffers_[KW_RODS_BINDING_CHAINS], bytes_of(chains)));
        KW_TRY(compute::upload(*ctx_, buffers_[KW_RODS_BINDING_MOTION], bytes_of(motion)));
        KW_TRY(compute::upload(*ctx_, buffers_[KW_RODS_BINDING_SPIN], bytes_of(spin)));
        KW_TRY(compute::upload(*ctx_, buffers_[KW_RODS_BINDING_CHAIN_STATE], bytes_of(chain_states)));
        // The centers' last frame: the initial one (rods::initial_chain_state).
        std::vector<gpu::RodTransformGpu> centers(initial.centers.size());
        std::transform(initial.centers.begin(), initial.centers.end(), centers.begin(), [](const rods::Transform& t) { return to_gpu(t); });
        KW_TRY(compute::upload(*ctx_, buffers_[KW_RODS_BINDING_CENTER_STATE], bytes_of(centers)));
        // u = 0 for every chain: rod_keys.comp writes those of the chains with keyed
        // examples before each step; the others' stay 0, which K.4 leaves the view blend.
        KW_TRY(compute::upload(*ctx_, buffers_[KW_RODS_BINDING_KEYED], bytes_of(std::vector<gpu::vec4>(count, gpu::vec4{}))));

        key_buffers_.clear();
        const std::uint64_t key_sizes[KW_ROD_KEYS_BINDING_WEIGHTS] = {  // the bindings the key kernel owns
            key_templates_.size() * sizeof(gpu::RodKeyTemplateGpu), key_chains.size() * sizeof(gpu::RodKeyChainGpu),
            std::uint64_t{world.key_count} * sizeof(gpu::RodTransformGpu), key_states.size() * sizeof(gpu::RodKeyStateGpu)};
        auto key_storage = compute::create_storage_buffers(*ctx_, key_sizes, "the rod world's keyed examples");
        if (!key_storage) return key_storage.error();
        key_buffers_ = std::move(key_storage).value();
        KW_TRY(compute::upload(*ctx_, key_buffers_[KW_ROD_KEYS_BINDING_CHAINS], bytes_of(key_chains)));
        KW_TRY(compute::upload(*ctx_, key_buffers_[KW_ROD_KEYS_BINDING_STATE], bytes_of(key_states)));
        if (keyed_chains_ > 0) {
            if (!key_kernel_) {
                const std::vector<compute::Binding> types(KW_ROD_KEYS_BINDING_COUNT, compute::Binding::Storage);
                auto created = compute::Kernel::create(*ctx_, "rod_keys", types, sizeof(gpu::RodKeyPush));
                if (!created) return created.error();
                key_kernel_.emplace(std::move(created).value());
            }
            const Buffer* key_bound[KW_ROD_KEYS_BINDING_COUNT] = {
                &key_buffers_[KW_ROD_KEYS_BINDING_TEMPLATES], &key_buffers_[KW_ROD_KEYS_BINDING_CHAINS],
                &key_buffers_[KW_ROD_KEYS_BINDING_KEYS], &key_buffers_[KW_ROD_KEYS_BINDING_STATE], &buffers_[KW_RODS_BINDING_KEYED],
                &buffers_[KW_RODS_BINDING_REFERENCE], &buffers_[KW_RODS_BINDING_CHAIN_STATE]};
            key_kernel_->bind(key_bound);
        }
        // The input buffers hold the initial frame's input until the first step (what a
        // renderer drawing the colliders from them sees at frame 0).
        KW_TRY(upload_input(*ctx_, initial));

        // The kinds of collider and the centers the world uses, the rest compiled out.
        features_ = world.center_count > 0 ? KW_RODS_FEATURE_CENTERS : 0u;
        // Velocities relative to the air where the air moves or a template has drag; a
        // world loaded in calm air runs the plain kernel (calm air gives the same bits)
        // until a frame's wind moves (record()).
        bool air = moving_air(initial);
        for (const rods::ChainTemplate& t : world.templates) air = air || t.params.normal_drag > 0.0f || t.params.tangent_drag > 0.0f;
        if (air) features_ |= KW_RODS_FEATURE_AIR;
        if (limits) features_ |= KW_RODS_FEATURE_LIMITS;
        if (world.lod.enabled) features_ |= KW_RODS_FEATURE_LOD;
        for (const rods::Collider& c : initial.colliders) features_ |= feature_of(c.kind);
        suppression_ = all_none   ? KW_RODS_SUPPRESSION_NONE
                       : all_full ? KW_RODS_SUPPRESSION_FULL
                                  : KW_RODS_SUPPRESSION_PARTIAL;
        max_joints_ = max_joints;
        max_views_ = max_views;
        max_keyed_ = max_keyed;
        // rods::kMaxChainColliders bounds a chain's set (rods::check_world).
        max_colliders_ = std::min<std::uint32_t>(max_colliders, KW_RODS_MAX_CHAIN_COLLIDERS);
        return select_kernels();
    }

    Result<void> step(const rods::RodFrame& frame) override {
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

    Result<void> record_step(compute::Recording& recording, const rods::RodFrame& frame) override {
        assert(&recording.device() == ctx_.get() && "a recording of the backend's device");
        // Untimed: the timestamps are the caller's submission's.
        return record(recording, frame, false);
    }

    Result<void> record_external(compute::Recording& borrowed, const rods::RodFrame& frame) override {
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

    Result<void> read(ChainSnapshot& out) override {
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

    Result<void> read_states(std::vector<rods::ChainState>& out) override {
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

private:
    // Chains a workgroup steps: one per invocation, or one per `lanes_` invocations.
    std::uint32_t chains_per_group() const { return joint_lanes_ ? workgroup_ / lanes_ : workgroup_; }

    // BackendOptions::rod_kernel other than PerChain: whether its kernel can step `world`,
    // and for PerJoint the lanes per chain of rods_lanes.comp (a power of two, at least its
    // longest chain; 0 for PerChainSharedConstants).
    Result<std::uint32_t> kernel_variant_for(const rods::RodWorld& world) const {
        const bool per_joint = kernel_kind_ == RodKernel::PerJoint;
        auto refuse = [&](const std::string& what) {
            return make_error(Error::Kind::Unsupported,
                              per_joint ? "BackendOptions::rod_kernel RodKernel::PerJoint: the joint-lanes kernel (shaders/rods_lanes.comp) "
                                          "steps worlds of at most " +
                                              std::to_string(KW_RODS_MAX_GROUPS) +
                                              " templates without levels of detail, keyed examples, center frames or angle limits; "
                                              "this world has " +
                                              what + " (step it with RodKernel::PerChain)"
                                        : "BackendOptions::rod_kernel RodKernel::PerChainSharedConstants: the kernel steps worlds of at "
                                          "most " +
                                              std::to_string(KW_RODS_MAX_GROUPS) + " templates (one dispatch each); this world has " +
                                              what + " (step it with RodKernel::PerChain)");
        };
        std::vector<bool> used(world.templates.size(), false);
        for (const rods::ChainInstance& ch : world.chains) used[ch.template_index] = true;
        const auto templates = static_cast<std::size_t>(std::count(used.begin(), used.end(), true));
        if (templates > KW_RODS_MAX_GROUPS) return refuse(std::to_string(templates) + " templates");
        if (!per_joint) return 0u;
        if (world.lod.enabled) return refuse("levels of detail");
        if (world.center_count > 0) return refuse("center frames");
        std::uint32_t max_joints = 2;
        for (const rods::ChainTemplate& t : world.templates) {
            if (!t.keyed.empty()) return refuse("keyed examples");
            if (t.chain.limited) return refuse("angle limits");
            max_joints = std::max(max_joints, t.chain.joint_count);
        }
        const std::uint32_t lanes = std::bit_ceil(max_joints);
        if (lanes > workgroup_) {
            return make_error(Error::Kind::Unsupported, "BackendOptions::rod_kernel RodKernel::PerJoint: chains of " + std::to_string(max_joints) +
                                                            " joints take " + std::to_string(lanes) +
                                                            " lanes, more than the workgroup's " + std::to_string(workgroup_) +
                                                            " (BackendOptions::workgroup_size)");
        }
        // rods_lanes.comp's shared arrays, per invocation: 8 vec3 and 2 vec4 (16 bytes each,
        // as vec3 arrays are laid out), a mat3 (3 x 16) and 2 floats.
        const std::uint64_t shared = std::uint64_t{workgroup_} * (10 * 16 + 48 + 2 * 4);
        if (shared > ctx_->info().max_shared_memory) {
            return make_error(Error::Kind::Unsupported,
                              "BackendOptions::rod_kernel RodKernel::PerJoint: a workgroup of " + std::to_string(workgroup_) + " invocations needs " +
                                  std::to_string(shared) + " bytes of shared memory; " + ctx_->info().name + " has " +
                                  std::to_string(ctx_->info().max_shared_memory) + " (a smaller BackendOptions::workgroup_size)");
        }
        return lanes;
    }

    // The kernels of the loaded world's dispatches for its features_ (pipeline(), cached):
    // at load, and again when a world loaded in calm air gets a wind (record()).
    Result<void> select_kernels() {
        // Each kernel is specialized to chains of exactly MAX_J joints and MAX_VIEWS views
        // where it can be (KW_RODS_SPEC_EXACT: no per-joint masks, no code for absent
        // joints). GROUPED: one variant per distinct (n, m) of the templates, when there are
        // few (each is a compilation); otherwise the world's longest for the runs that have
        // it and the general kernel for the rest.
        auto shape_of = [&](std::uint32_t t) {
            return std::array<std::uint32_t, 3>{templates_[t].counts.x, templates_[t].counts.y, templates_[t].solver.z};
        };
        std::vector<std::array<std::uint32_t, 3>> shapes_of_runs;
        for (const Group& g : groups_) {
            const auto nmj = shape_of(g.template_index);
            if (std::find(shapes_of_runs.begin(), shapes_of_runs.end(), nmj) == shapes_of_runs.end()) shapes_of_runs.push_back(nmj);
        }
        const bool per_shape = grouped_ && shapes_of_runs.size() <= KW_RODS_MAX_VARIANTS;
        std::vector<const Buffer*> bound;
        for (const auto& b : buffers_) bound.push_back(&b);
        auto kernel_for = [&](std::uint32_t n, std::uint32_t m, std::uint32_t keyed, bool exact) -> Result<const compute::Kernel*> {
            auto kernel = pipeline({n, m, suppression_, grouped_ ? 1u : 0u, exact ? 1u : 0u, keyed, features_, max_colliders_, workgroup_,
                                    joint_lanes_ ? lanes_ : 0u});
            if (!kernel) return kernel.error();
            kernel.value()->bind(bound);  // (again for a shared one: the same bindings)
            return kernel.value();
        };
        bool all_exact = true;
        for (Group& g : groups_) {
            const auto [n, m, keyed] = shape_of(g.template_index);
            const bool exact = n == max_joints_ && m == max_views_ && keyed == max_keyed_;
            all_exact = all_exact && exact;
            if (!grouped_) continue;
            auto kernel = per_shape ? kernel_for(n, m, keyed, true) : kernel_for(max_joints_, max_views_, max_keyed_, exact);
            if (!kernel) return kernel.error();
            g.kernel = kernel.value();
        }
        if (!grouped_) {
            auto kernel = kernel_for(max_joints_, max_views_, max_keyed_, all_exact);
            if (!kernel) return kernel.error();
            kernel_ = kernel.value();
        }
        return {};
    }

    // The step of `frame`: its input (and, when dt changed, the templates' step sizes)
    // written, the input writer's kernels, then the step's dispatch between the
    // timestamps when `timed`, its writes made visible to the host and to copies.
    Result<void> record(compute::Recording& recording, const rods::RodFrame& frame, bool timed) {
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

    // The frame's kinematic input into the input buffers.
    // `target`: the device (a submission of its own) or a recording (compute::upload).
    template <typename Target>
    Result<void> upload_input(Target& target, const rods::RodFrame& frame) {
        reference_.resize(frame.reference.size());
        std::transform(frame.reference.begin(), frame.reference.end(), reference_.begin(),
                       [](const rods::Transform& t) { return to_gpu(t); });
        roots_.resize(frame.roots.size());
        std::transform(frame.roots.begin(), frame.roots.end(), roots_.begin(), [](const rods::Transform& t) { return to_gpu(t); });
        colliders_.resize(frame.colliders.size());
        std::transform(frame.colliders.begin(), frame.colliders.end(), colliders_.begin(), [](const rods::Collider& c) {
            return gpu::RodColliderGpu{to_gpu(c.a, c.radius), to_gpu(c.b, static_cast<float>(c.kind))};  // KW_RODS_COLLIDER_* (shared_layout.cpp)
        });
        centers_.resize(frame.centers.size());
        std::transform(frame.centers.begin(), frame.centers.end(), centers_.begin(), [](const rods::Transform& t) { return to_gpu(t); });
        KW_TRY(compute::upload(target, buffers_[KW_RODS_BINDING_CENTERS], bytes_of(centers_)));
        KW_TRY(compute::upload(target, buffers_[KW_RODS_BINDING_REFERENCE], bytes_of(reference_)));
        KW_TRY(compute::upload(target, buffers_[KW_RODS_BINDING_ROOTS], bytes_of(roots_)));
        keys_.resize(frame.keys.size());
        std::transform(frame.keys.begin(), frame.keys.end(), keys_.begin(), [](const rods::Transform& t) { return to_gpu(t); });
        KW_TRY(compute::upload(target, key_buffers_[KW_ROD_KEYS_BINDING_KEYS], bytes_of(keys_)));
        winds_.resize(frame.winds.size());
        std::transform(frame.winds.begin(), frame.winds.end(), winds_.begin(), [](const rods::WindField& w) { return to_gpu(w); });
        KW_TRY(compute::upload(target, buffers_[KW_RODS_BINDING_WINDS], bytes_of(winds_)));
        return compute::upload(target, buffers_[KW_RODS_BINDING_COLLIDERS], bytes_of(colliders_));
    }

    // The rest shape of chain c's last frame from its weights (SPEC A.2), as the kernel
    // blends it; the GPU keeps only the weights.
    rods::ChainShape rest_of(std::uint32_t c) const {
        const rods::ChainTemplate& t = world_->templ(world_->chains[c]);
        const gpu::RodChainStateGpu& cs = chain_states_[c];
        const float w[8] = {cs.weights[0].x, cs.weights[0].y, cs.weights[0].z, cs.weights[0].w,
                            cs.weights[1].x, cs.weights[1].y, cs.weights[1].z, cs.weights[1].w};
        return rods::to_positions(t.basis, rods::blend(t.shapes, std::span<const float>(w, t.shapes.size())));
    }

    Result<void> fetch() {
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

    std::shared_ptr<compute::Device> ctx_;
    // A few variants at most (one per kind of world): a vector is the simplest map.
    // (A deque: kernel_ and the groups' kernels point into it.)
    std::deque<std::pair<Variant, compute::Kernel>> pipelines_;
    std::uint32_t workgroup_ = KW_RODS_WORKGROUP_SIZE;  // invocations per workgroup (KW_RODS_SPEC_WORKGROUP_SIZE)
    RodKernel kernel_kind_ = RodKernel::PerChain;  // BackendOptions::rod_kernel
    bool joint_lanes_ = false;  // RodKernel::PerJoint: rods_lanes.comp
    std::uint32_t lanes_ = 0;   // its invocations per chain (KW_RODS_SPEC_LANES) for the loaded world
    const compute::Kernel* kernel_ = nullptr;  // the one dispatch's when not grouped_
    const rods::RodWorld* world_ = nullptr;
    std::vector<Buffer> buffers_;
    std::shared_ptr<const RodInputWriter> input_writer_;
    std::optional<compute::StagingRing> ring_;  // record_external's input uploads
    std::vector<gpu::RodTemplateGpu> templates_;
    // Keyed examples (shared/rod_keys.h): per template its constants; the kernel and its
    // buffers (binding KW_ROD_KEYS_BINDING_WEIGHTS is buffers_[KW_RODS_BINDING_KEYED]).
    std::vector<gpu::RodKeyTemplateGpu> key_templates_;
    std::optional<compute::Kernel> key_kernel_;
    std::vector<Buffer> key_buffers_;
    std::uint32_t keyed_chains_ = 0;  // chains with keyed examples: rod_keys.comp's invocations
    // The runs of RodChainGpu that share a template, and whether each is a dispatch of its own.
    struct Group {
        std::uint32_t template_index, first, count;
        const compute::Kernel* kernel;  // its variant (grouped_)
    };
    std::vector<Group> groups_;
    bool grouped_ = false;
    std::uint32_t features_ = KW_RODS_FEATURE_ALL;  // KW_RODS_SPEC_FEATURES of the loaded world
    // What the world's kernels are specialized to besides features_ (select_kernels()).
    std::uint32_t suppression_ = KW_RODS_SUPPRESSION_PARTIAL, max_joints_ = 2, max_views_ = 0, max_keyed_ = 0;
    std::uint32_t max_colliders_ = 0;  // KW_RODS_SPEC_MAX_COLLIDERS: the most colliders of one chain
    float dt_ = -1.0f;
    bool started_ = false;  // whether a step has been recorded since load()
    double gpu_ms_ = -1.0;
    // Per-frame staging on the host, kept to avoid reallocating every frame.
    std::vector<gpu::RodTransformGpu> reference_, roots_, keys_, centers_;
    std::vector<gpu::RodColliderGpu> colliders_;
    std::vector<gpu::RodWindGpu> winds_;
    std::vector<gpu::RodJointMotionGpu> motion_;
    std::vector<gpu::RodJointSpinGpu> spin_;
    std::vector<gpu::RodChainStateGpu> chain_states_;
    std::vector<gpu::RodTransformGpu> center_states_;
};

}  // namespace

Result<std::unique_ptr<RodBackend>> make_vulkan_rod_backend(const BackendOptions& options) {
    auto ctx = backend_context(options);
    if (!ctx) return ctx.error();
    auto workgroup = compute::workgroup_size(*ctx.value(), options.workgroup_size, KW_RODS_WORKGROUP_SIZE);
    if (!workgroup) return workgroup.error();
    return std::unique_ptr<RodBackend>(
        std::make_unique<VulkanRodBackend>(std::move(ctx).value(), workgroup.value(), options.rod_kernel));
}

}  // namespace kodawari
