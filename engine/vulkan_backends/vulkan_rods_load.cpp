// The Vulkan rod backend's world (vulkan_rods.cpp steps it): at load, its templates,
// shapes, chains, keyed examples and initial state packed into the kernels' layout
// (shaders/shared/rods.h, shared/rod_keys.h) and uploaded, and the kernels specialized
// to what it uses chosen and built.

#include <algorithm>
#include <bit>
#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "core/parallel.hpp"
#include "vulkan_backends/vulkan_rods.hpp"

namespace kodawari::vulkan_rods_detail {
namespace {

// A template's keyed examples (shared/rod_keys.h), alpha left for set_smoothing (vulkan_rods.cpp).
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

}  // namespace

/// The kernel specialized for a world (shared/rods.h, KW_RODS_SPEC_*); built on first
/// use and kept. The backend's one RodKernel picks the shader.
Result<const compute::Kernel*> VulkanRodBackend::pipeline(const Variant& spec) {
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

Result<void> VulkanRodBackend::load(const rods::RodWorld& world, const rods::RodFrame& initial) {
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

// BackendOptions::rod_kernel other than PerChain: whether its kernel can step `world`,
// and for PerJoint the lanes per chain of rods_lanes.comp (a power of two, at least its
// longest chain; 0 for PerChainSharedConstants).
Result<std::uint32_t> VulkanRodBackend::kernel_variant_for(const rods::RodWorld& world) const {
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
Result<void> VulkanRodBackend::select_kernels() {
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

}  // namespace kodawari::vulkan_rods_detail
