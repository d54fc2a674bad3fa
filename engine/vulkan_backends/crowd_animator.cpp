// CrowdAnimator: RodScene frames with the rigged characters posed by pose backends, and
// optionally the rigged part of the rod input written on the device (rod_inputs.comp).

#include "kodawari/vulkan/crowd_animator.hpp"

#include <chrono>
#include <optional>

#include <kodawari/shared/rod_inputs.h>

#include "vulkan_backends/device_backends.hpp"
#include "core/parallel.hpp"
#include "kodawari/vulkan/backend_factory.hpp"

namespace kodawari {

// rod_inputs.comp tells a motion key source by kind 0.
static_assert(static_cast<std::uint32_t>(rods::KeySourceKind::Motion) == 0u);

/// Records shaders/rod_inputs.comp for every rigged character template: its instances'
/// reference joints, chain roots, colliders and key sources from the pose backend's world matrices into
/// the rod backend's input buffers (what RodScene::rigged_frame computes on the host).
class DeviceInputWriter final : public RodInputWriter {
public:
    struct Rig {
        std::shared_ptr<PoseBackend> backend;  // keeps its world buffer alive
        compute::Kernel kernel;
        compute::Buffer instances, attachments;
        gpu::RodInputPush push;
    };

    DeviceInputWriter(std::shared_ptr<compute::Device> ctx, std::vector<Rig> rigs) : ctx_(std::move(ctx)), rigs_(std::move(rigs)) {}

    void record(compute::Recording& recording, const DeviceData& rods) const override {
        // The pose kernel wrote the world matrices in an earlier submission.
        compute::barrier(recording, compute::Stage::Compute | compute::Stage::Transfer, compute::Stage::Compute);
        for (const Rig& rig : rigs_) {
            // Never null: write_inputs_on() evaluated every pose backend once.
            const DeviceData* poses = rig.backend->device_data();
            if (poses == nullptr) continue;
            // The rod backend's buffers change with each load(); the set is not in use here
            // (the previous submission that used it has been waited for).
            const compute::BufferView views[KW_ROD_INPUTS_BINDING_COUNT] = {
                {poses->buffer(pose_buffers::world).buffer}, {&rig.instances}, {&rig.attachments},
                {rods.buffer(rod_buffers::reference).buffer}, {rods.buffer(rod_buffers::roots).buffer},
                {rods.buffer(rod_buffers::colliders).buffer}, {rods.buffer(rod_buffers::keys).buffer},
                {rods.buffer(rod_buffers::centers).buffer}};
            rig.kernel.bind(views);
            const std::uint32_t groups = (rig.push.counts.x + KW_ROD_INPUTS_WORKGROUP_SIZE - 1) / KW_ROD_INPUTS_WORKGROUP_SIZE;
            rig.kernel.dispatch(recording, std::as_bytes(std::span(&rig.push, 1)), groups);
        }
    }

private:
    std::shared_ptr<compute::Device> ctx_;  // outlives the kernels and buffers
    std::vector<Rig> rigs_;
};

Result<CrowdAnimator> CrowdAnimator::create(const RodScene& scene, BackendKind kind, const BackendOptions& options) {
    CrowdAnimator out(scene);
    out.options_ = options;
    out.host_threads_ = kind == BackendKind::Cpu ? cpu_backend_threads(options) : 1u;
    for (std::uint32_t k = 0; k < scene.characters.size(); ++k) {
        const CharacterKinematics& character = scene.characters[k];
        if (!character.rig) continue;
        Rig rig;
        rig.character = k;
        std::vector<PoseInstance> instances;
        for (std::uint32_t c = 0; c < scene.instances.size(); ++c) {
            const CharacterInstance& inst = scene.instances[c];
            if (inst.character != k) continue;
            rig.instances.push_back(c);
            instances.push_back(PoseInstance{inst.placement, inst.clip, inst.time_offset, true});
        }
        if (instances.empty()) continue;
        auto backend = make_pose_backend(kind, options);
        if (!backend) return backend.error();
        KW_TRY(backend.value()->load(*character.rig, instances));
        rig.backend = std::move(backend).value();
        rig.nodes = character.rig->nodes.size();
        out.rigs_.push_back(std::move(rig));
    }
    return out;
}

Result<void> CrowdAnimator::frame(std::uint32_t index, rods::RodFrame& out) {
    if (!writer_) return host_frame(index, out, /*clip_rate=*/true);
    const RodScene& scene = *scene_;
    // The rigged entries are written on the device at the rod backend's step.
    scene.kinematic_frame(index, out, /*rigged=*/false);
    const auto start = std::chrono::steady_clock::now();
    for (Rig& rig : rigs_) KW_TRY(rig.backend->evaluate(scene.time(index)));
    last_pose_ms_ = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
    return {};
}

Result<void> CrowdAnimator::host_frame(std::uint32_t index, rods::RodFrame& out) { return host_frame(index, out, false); }

bool CrowdAnimator::choose_clip_updates(std::uint32_t index, const rods::RodFrame& previous) {
    const RodScene& scene = *scene_;
    const rods::LodSettings& lod = scene.world.lod;
    const bool follows = last_rate_frame_ && *last_rate_frame_ + 1 == index && previous.reference.size() == scene.instances.size();
    last_rate_frame_ = index;
    if (!lod.enabled || !follows) {
        // The first frame, a seek or a rewind: every clip, and the levels afresh.
        clip_level_.assign(scene.instances.size(), rods::Level::Full);
        return false;
    }
    // The rod backends' decision (rods::chain_level, then rods::chain_rests at this frame's
    // turn), taken from the last frame's reference joints and camera: a character keeps its
    // clip's pose where its chains will keep their state, so that they step at the frames its
    // pose renews. Within twice its full distance (about to turn full) it has every clip.
    // With lower_rate off, the levels of characters twice as near decide (one about to turn
    // full has its clip at every frame first) and the clips alone keep the levels' rate.
    rods::LodSettings decide = lod;
    float cap = previous.full_distance_cap;  // the budget's, at the last frame
    if (!lod.lower_rate) {
        decide.bias = std::min(lod.bias + 1.0f, 8.0f);
        cap *= 2.0f;
    }
    const rods::LodView view = rods::lod_view(decide, previous.camera, cap);
    for (Rig& rig : rigs_) {
        rig.may_keep.resize(rig.instances.size());
        for (std::size_t j = 0; j < rig.instances.size(); ++j) {
            const std::uint32_t c = rig.instances[j];
            const glm::vec3 reference = previous.reference[c].position;
            const rods::Level level = rods::chain_level(view, reference, clip_level_[c]);
            // Groups of consecutive instances of the whole scene take turns (the cpu pose
            // backend's batches of one clip, when they line up), so that every frame costs
            // about the same.
            const std::uint32_t turn = rods::rate_turn(index, scene.first_instance + c);
            bool keep = false;
            if (lod.lower_rate) {
                keep = rods::chain_rests(view, reference, level, clip_level_[c], turn);
            } else {
                const std::uint32_t period = rods::dynamic(level)          ? 1u
                                             : level == rods::Level::Posed ? kPosedClipPeriod
                                                                           : kHiddenClipPeriod;
                keep = turn % period != 0;
            }
            clip_level_[c] = level;
            rig.may_keep[j] = keep ? 1 : 0;
        }
    }
    return true;
}

Result<void> CrowdAnimator::host_frame(std::uint32_t index, rods::RodFrame& out, bool clip_rate) {
    const RodScene& scene = *scene_;
    // The last frame's camera (as the caller set it) and reference joints, before
    // kinematic_frame() writes this frame's camera.
    const bool rate = clip_rate && choose_clip_updates(index, out);
    scene.kinematic_frame(index, out, /*rigged=*/rigs_.empty());
    const auto start = std::chrono::steady_clock::now();
    for (Rig& rig : rigs_) {
        const std::span<const std::uint8_t> may_keep = rate ? std::span<const std::uint8_t>(rig.may_keep)
                                                            : std::span<const std::uint8_t>();
        KW_TRY(rig.backend->evaluate_some(scene.time(index), may_keep));
        // The cpu kinds' matrices where they are; a device's read back.
        std::span<const glm::mat4> world = rig.backend->host_world();
        if (world.empty()) {
            KW_TRY(rig.backend->read(world_));
            world = world_;
        }
        // Each instance writes its own entries of `out` (sized by kinematic_frame); one
        // that keeps its clip's pose keeps them too.
        parallel_for(rig.instances.size(), host_threads_, [&](std::size_t begin, std::size_t end) {
            for (std::size_t j = begin; j < end; ++j) {
                if (!may_keep.empty() && may_keep[j] != 0) continue;
                scene.rigged_frame(rig.instances[j], world.subspan(j * rig.nodes, rig.nodes), out);
            }
        });
    }
    last_pose_ms_ = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
    return {};
}

Result<bool> CrowdAnimator::write_inputs_on(RodBackend& rods) {
    if (rigs_.empty() || !options_.context) return false;
    auto* device_rods = dynamic_cast<DeviceRodBackend*>(&rods);
    const DeviceData* state = rods.device_data();
    if (device_rods == nullptr || state == nullptr || &state->context() != options_.context.get()) return false;
    for (Rig& rig : rigs_) {
        // The world buffer exists once evaluated; its device must be the rod backend's.
        KW_TRY(rig.backend->evaluate(scene_->time(0)));
        const DeviceData* world = rig.backend->device_data();
        if (world == nullptr || &world->context() != &state->context()) return false;
    }
    compute::Device& ctx = *options_.context;
    std::vector<DeviceInputWriter::Rig> rigs;
    for (const Rig& rig : rigs_) {
        const CharacterKinematics& k = scene_->characters[rig.character];
        std::vector<gpu::RodInputInstanceGpu> instances;
        for (const std::uint32_t c : rig.instances) {
            const CharacterInstance& inst = scene_->instances[c];
            // Its chains' key sources follow each other (RodWorld::finalize, chain by chain).
            const std::uint32_t first_key = k.chains.empty() ? 0u : scene_->world.chains[inst.chain_begin].key_begin;
            instances.push_back({{c, inst.chain_begin, inst.collider_begin, first_key}, {inst.center_begin, 0u, 0u, 0u}});
        }
        std::vector<gpu::RodInputAttachmentGpu> attachments;
        for (const ChainAttachment& a : k.chains) attachments.push_back({{a.joint, 0u, 0u, 0u}, {}, {}});
        for (const ColliderAttachment& a : k.colliders) {
            attachments.push_back({{a.joint, 0u, 0u, 0u}, {a.a.x, a.a.y, a.a.z, a.radius}, {a.b.x, a.b.y, a.b.z, static_cast<float>(a.kind)}});
        }
        std::uint32_t keys = 0;
        for (const ChainAttachment& a : k.chains) {
            for (const KeyJoint& key : a.keys) {
                const std::uint32_t parent = key.parent >= 0 ? static_cast<std::uint32_t>(key.parent) : KW_ROD_INPUTS_NO_PARENT;
                attachments.push_back({{key.joint, parent, static_cast<std::uint32_t>(key.kind), 0u}, {}, {}});
                ++keys;
            }
        }
        std::uint32_t centers = 0;
        for (const ChainAttachment& a : k.chains) {
            if (a.center < 0) continue;
            attachments.push_back({{static_cast<std::uint32_t>(a.center), 0u, 0u, 0u}, {}, {}});
            ++centers;
        }
        const std::uint64_t sizes[] = {instances.size() * sizeof(gpu::RodInputInstanceGpu),
                                       attachments.size() * sizeof(gpu::RodInputAttachmentGpu)};
        auto buffers = compute::create_storage_buffers(ctx, sizes, "the rigged characters' rod input");
        if (!buffers) return buffers.error();
        KW_TRY(compute::upload(ctx, buffers.value()[0], std::as_bytes(std::span(instances))));
        KW_TRY(compute::upload(ctx, buffers.value()[1], std::as_bytes(std::span(attachments))));
        const std::vector<compute::Binding> types(KW_ROD_INPUTS_BINDING_COUNT, compute::Binding::Storage);
        auto kernel = compute::Kernel::create(ctx, "rod_inputs", types, sizeof(gpu::RodInputPush));
        if (!kernel) return kernel.error();
        const gpu::RodInputPush push{{static_cast<std::uint32_t>(instances.size()), static_cast<std::uint32_t>(rig.nodes),
                                      k.skeleton.reference, static_cast<std::uint32_t>(k.chains.size())},
                                     {static_cast<std::uint32_t>(k.colliders.size()), keys, centers, 0u}};
        rigs.push_back({rig.backend, std::move(kernel).value(), std::move(buffers.value()[0]), std::move(buffers.value()[1]), push});
    }
    auto writer = std::make_shared<const DeviceInputWriter>(options_.context, std::move(rigs));
    device_rods->set_input_writer(writer);
    writer_ = std::move(writer);
    return true;
}

std::vector<CrowdAnimator::PosedCharacter> CrowdAnimator::posed_characters() const {
    std::vector<PosedCharacter> out;
    for (const Rig& rig : rigs_) out.push_back({rig.character, rig.instances, rig.backend.get()});
    return out;
}

std::uint32_t CrowdAnimator::validation_messages() const {
    std::uint32_t n = 0;
    for (const Rig& rig : rigs_) n += rig.backend->validation_messages();
    return n;
}

}  // namespace kodawari
