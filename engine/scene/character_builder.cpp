// From a Scene's characters and crowds to a RodScene (SPEC A.1, C): one chain template
// per chain of each character (shared by all its instances), then the instances crowd
// by crowd, each with its chains and colliders in contiguous ranges. The random numbers
// (jitter, time offsets) come from std::mt19937_64, mapped to [0, 1) here, as in
// flock_builder.cpp, so that no standard library's distribution changes the result.

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <numbers>
#include <numeric>
#include <random>
#include <string>
#include <utility>

#include <kodawari/scene/scene.hpp>

#include "scene/character_loader.hpp"
#include "scene/seeded_random.hpp"

namespace kodawari {
namespace {

// Purposes of a crowd's random streams: each has its own generator so that, say,
// adding yaw jitter does not move every instance's time offset.
enum class Stream : std::uint64_t { Position = 1, Yaw = 2, TimeOffset = 3, Clip = 4 };

using Random = scene_detail::SeededRandom;

rods::Transform placement(glm::vec3 position, double yaw) {
    return rods::Transform{position, glm::angleAxis(static_cast<float>(yaw), glm::vec3(0.0f, 1.0f, 0.0f))};
}

// The generated instances of a crowd: a grid (rows along +Z, centred on `center`) or a
// ring (instance k at angle 2 pi k / count, facing outwards, plus `yaw`), then jitter.
std::vector<InstanceSpec> generate(const CrowdSpec& crowd) {
    std::vector<InstanceSpec> out(crowd.count);
    if (crowd.count == 0) return out;
    Random position_rng(crowd.seed, Stream::Position);
    Random yaw_rng(crowd.seed, Stream::Yaw);
    Random time_rng(crowd.seed, Stream::TimeOffset);
    Random clip_rng(crowd.seed, Stream::Clip);
    const double spacing = crowd.spacing;
    const std::uint32_t columns =
        crowd.columns != 0 ? crowd.columns : static_cast<std::uint32_t>(std::ceil(std::sqrt(static_cast<double>(crowd.count))));
    const std::uint32_t rows = (crowd.count + columns - 1) / columns;
    const double ring_radius =
        crowd.radius ? static_cast<double>(*crowd.radius)
                     : std::max(spacing, spacing * static_cast<double>(crowd.count) / (2.0 * std::numbers::pi));
    for (std::uint32_t k = 0; k < crowd.count; ++k) {
        double x = 0.0;
        double z = 0.0;
        double yaw = crowd.yaw;
        if (crowd.layout == CrowdLayout::Grid) {
            x = (static_cast<double>(k % columns) - 0.5 * static_cast<double>(columns - 1)) * spacing;
            z = (static_cast<double>(k / columns) - 0.5 * static_cast<double>(rows - 1)) * spacing;
        } else {
            const double angle = 2.0 * std::numbers::pi * static_cast<double>(k) / static_cast<double>(crowd.count);
            x = ring_radius * std::sin(angle);
            z = ring_radius * std::cos(angle);
            yaw += angle;
        }
        // Always draw, so that a jitter of 0 keeps the other streams' numbers the same.
        x += static_cast<double>(crowd.position_jitter) * position_rng.symmetric();
        z += static_cast<double>(crowd.position_jitter) * position_rng.symmetric();
        yaw += static_cast<double>(crowd.yaw_jitter) * yaw_rng.symmetric();
        InstanceSpec& s = out[k];
        s.position = crowd.center + glm::vec3(static_cast<float>(x), 0.0f, static_cast<float>(z));
        s.yaw = static_cast<float>(yaw);
        s.time_offset = static_cast<float>(static_cast<double>(crowd.time_offset) * time_rng.unit());
        if (!crowd.clips.empty()) {
            const auto pick = static_cast<std::size_t>(clip_rng.unit() * static_cast<double>(crowd.clips.size()));
            s.clip = crowd.clips[std::min(pick, crowd.clips.size() - 1)];
        }
    }
    return out;
}

// Where the chain colliding with the colliders `set` (indices into `specs`) finds them in
// its template's collider list `out`: the run of an earlier chain with the same set, or a
// new run appended. Each chain's colliders are one contiguous run (RodFrame::colliders
// [begin, begin + count)), so overlapping sets (VRM's per-spring collider groups) repeat
// the colliders they share. Returns (begin, count).
std::pair<std::uint32_t, std::uint32_t> collider_run(std::vector<std::vector<std::uint32_t>>& runs,
                                                     const std::vector<std::uint32_t>& set,
                                                     const std::vector<ColliderSpec>& specs,
                                                     std::vector<ColliderAttachment>& out) {
    if (set.empty()) return {0u, 0u};
    std::uint32_t begin = 0;
    for (const std::vector<std::uint32_t>& run : runs) {
        if (run == set) return {begin, static_cast<std::uint32_t>(set.size())};
        begin += static_cast<std::uint32_t>(run.size());
    }
    runs.push_back(set);
    for (const std::uint32_t i : set) {
        const ColliderSpec& c = specs[i];
        out.push_back(ColliderAttachment{c.joint, c.a, c.b, c.radius, c.kind});
    }
    return {begin, static_cast<std::uint32_t>(set.size())};
}

}  // namespace

Result<RodScene> build_rod_scene(const Scene& scene) {
    RodScene out;
    out.fps = scene.fps;
    out.frames = scene.frame_count();
    out.fov_deg = scene.camera.fov_deg;
    out.camera = scene.camera.motion;
    rods::RodWorld& world = out.world;
    world.lod = scene.lod;
    world.lod.vertical_fov_deg = scene.camera.fov_deg;
    // Wind fields: the scene's first (calm without one, so that an application can set a
    // wind later: set_wind), then each character's own.
    out.winds.push_back(scene.wind.value_or(rods::WindField{}));
    std::vector<std::uint32_t> wind_of(scene.characters.size(), 0u);
    for (std::size_t c = 0; c < scene.characters.size(); ++c) {
        if (!scene.characters[c].wind) continue;
        wind_of[c] = static_cast<std::uint32_t>(out.winds.size());
        out.winds.push_back(*scene.characters[c].wind);
    }
    world.wind_count = static_cast<std::uint32_t>(out.winds.size());

    // Templates, shared by every instance of a character.
    for (const CharacterSpec& ch : scene.characters) {
        CharacterKinematics k;
        k.name = ch.name;
        k.skeleton = ch.skeleton;
        k.motion = ch.motion;
        k.first_template = static_cast<std::uint32_t>(world.templates.size());
        // The collider sets laid out so far, in k.colliders order: first all of them as
        // written when a colliding chain has no `colliders` list (so that such characters
        // keep the layout they always had), then each list not laid out yet. A set no chain
        // uses is not laid out: every frame would place it for nothing.
        std::vector<std::vector<std::uint32_t>> runs;
        const bool takes_all = std::any_of(ch.chains.begin(), ch.chains.end(),
                                           [](const ChainSpec& c) { return c.collide && c.all_colliders; });
        if (!ch.colliders.empty() && takes_all) {
            std::vector<std::uint32_t> all(ch.colliders.size());
            std::iota(all.begin(), all.end(), 0u);
            collider_run(runs, all, ch.colliders, k.colliders);
        }
        for (const rods::SkeletonJoint& j : ch.skeleton.joints) {
            k.joint_names.push_back(j.name);
            k.joint_parents.push_back(j.parent);
        }
        if (ch.rig) {
            k.rig = ch.rig->character;
            for (std::size_t n = 0; n < k.rig->nodes.size(); ++n) {
                const std::string& name = k.rig->nodes[n].name;
                k.joint_names.push_back(name.empty() ? "node" + std::to_string(n) : name);
                k.joint_parents.push_back(k.rig->nodes[n].parent);
            }
        }
        for (const ChainSpec& chain : ch.chains) {
            auto t = scene_detail::make_template(ch.name + "/" + chain.name, chain);
            if (!t) return make_error(Error::Kind::InvalidInput, scene.path + ": " + chain.path + ": " + t.error().message);
            world.templates.push_back(std::move(t.value()));
            // Key sources only with keyed examples to read them (make_template adds both or neither).
            ChainAttachment attachment;
            attachment.joint = chain.joint;
            attachment.offset = chain.offset;
            attachment.collide = chain.collide;
            attachment.center = chain.center;
            attachment.keys = chain.keyed.empty() ? std::vector<rods::KeyJoint>{} : chain.key_sources;
            if (chain.collide) {
                std::vector<std::uint32_t> set = chain.colliders;
                if (chain.all_colliders) {
                    set.resize(ch.colliders.size());
                    std::iota(set.begin(), set.end(), 0u);
                }
                const auto [begin, count] = collider_run(runs, set, ch.colliders, k.colliders);
                attachment.collider_begin = begin;
                attachment.collider_count = count;
            }
            k.chains.push_back(std::move(attachment));
            k.chain_nodes.push_back(chain.nodes);
            if (ch.rig) {
                k.simulated_joint.resize(ch.rig->character->nodes.size(), {-1, -1});
                for (std::size_t i = 1; i < chain.nodes.size(); ++i) {
                    k.simulated_joint[static_cast<std::size_t>(chain.nodes[i])] = {static_cast<int>(k.chains.size() - 1),
                                                                                   static_cast<int>(i)};
                }
            }
        }
        out.characters.push_back(std::move(k));
    }

    // Instances, crowd by crowd: generated ones first, then the explicit ones.
    std::vector<std::uint32_t> per_character(scene.characters.size(), 0);
    for (const CrowdSpec& crowd : scene.crowds) {
        std::vector<InstanceSpec> instances = generate(crowd);
        instances.insert(instances.end(), crowd.instances.begin(), crowd.instances.end());
        const CharacterKinematics& k = out.characters[crowd.character];
        for (const InstanceSpec& s : instances) {
            CharacterInstance inst;
            inst.character = crowd.character;
            inst.placement = placement(s.position, static_cast<double>(s.yaw));
            inst.time_offset = s.time_offset;
            if (const CharacterSpec& spec = scene.characters[crowd.character]; spec.rig) {
                inst.clip = s.clip.value_or(spec.rig->clip);
            }
            inst.chain_begin = static_cast<std::uint32_t>(world.chains.size());
            inst.collider_begin = world.collider_count;
            inst.center_begin = world.center_count;
            const auto index = static_cast<std::uint32_t>(out.instances.size());
            const std::string name = k.name + "#" + std::to_string(per_character[crowd.character]++);
            for (std::size_t c = 0; c < k.chains.size(); ++c) {
                rods::ChainInstance chain;
                chain.template_index = k.first_template + static_cast<std::uint32_t>(c);
                chain.character = index;
                chain.collider_begin = inst.collider_begin + k.chains[c].collider_begin;
                chain.collider_count = k.chains[c].collider_count;
                chain.wind = wind_of[crowd.character];
                if (k.chains[c].center >= 0) chain.center = world.center_count++;
                world.chains.push_back(chain);
                out.chain_names.push_back(name + "/" + scene.characters[crowd.character].chains[c].name);
            }
            world.collider_count += static_cast<std::uint32_t>(k.colliders.size());
            out.character_names.push_back(name);
            out.instances.push_back(inst);
        }
    }
    world.character_count = static_cast<std::uint32_t>(out.instances.size());
    KW_TRY(world.finalize());
    return out;
}

}  // namespace kodawari
