#pragma once
// A hand-built rod world with keyed examples (docs/keyed-examples.md) and its frames, for
// the tests that compare the backends' keyed examples (test_rod_backends.cpp) and the
// Vulkan backend's record mode (test_record_mode.cpp). Until the scene format says which
// joints are key sources, worlds with keyed examples are built with the rods API.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include <glm/gtc/quaternion.hpp>

#include "kodawari/rods/shape.hpp"
#include "kodawari/rods/world.hpp"

namespace kodawari::testing_support {

// A strand of `joints` joints leaving its root along -Y, curling by `turn` rad per segment
// about `axis`; each joint's +Y along its segment (as the synthetic scenes' strands).
inline rods::ChainShape keyed_strand(std::uint32_t joints, float length, glm::vec3 axis, float turn) {
    rods::ChainShape s;
    glm::vec3 d(0.0f, -1.0f, 0.0f);
    const float l = length / static_cast<float>(joints - 1);
    s.positions.push_back(glm::vec3(0.0f));
    for (std::uint32_t i = 0; i + 1 < joints; ++i) {
        s.positions.push_back(s.positions.back() + l * d);
        s.orientations.push_back(rods::shortest_arc(glm::vec3(0, 1, 0), d));
        d = glm::normalize(glm::angleAxis(turn, axis) * d);
    }
    s.orientations.push_back(s.orientations.back());
    return s;
}

// Characters that sprint along +Z, stop, turn on the spot and nod, over 90 frames (1.5 s),
// each a little later than the last; at the end every one stands still, head up. Their
// chains use three kinds of template, in turn: a "runner" (2 views, a motion speed example
// by magnitude smoothed over 0.2 s and an angular-speed example in the head's frame, one
// motion key source: the head), a "nodder" (1 view, a pose example on 2 pose key sources:
// the head's pitch relative to the neck and the neck's relative to the chest) and a plain
// one without keyed examples. With `templates` = 5, two more (a runner and a plain one of
// other joint counts): more distinct (joints, views, keyed) than KW_RODS_MAX_VARIANTS, so
// the Vulkan backend runs its general, not exact, kernel with keyed examples compiled in.
// Past 5 the five repeat; over KW_RODS_MAX_GROUPS (32) templates the Vulkan backend runs
// one dispatch for all chains, each finding its template itself.
inline constexpr float kKeyedDt = 1.0f / 60.0f;

class KeyedScene {
public:
    static constexpr float kLength = 0.3f;
    static constexpr std::uint32_t kFrames = 90;
    enum Kind { Runner = 0, Nodder = 1, Plain = 2 };

    static KeyedScene make(std::uint32_t chains, std::uint32_t templates) {
        KeyedScene out;
        const std::uint32_t joints[5] = {9, 7, 6, 8, 5};
        const Kind kinds[5] = {Runner, Nodder, Plain, Runner, Plain};
        for (std::uint32_t t = 0; t < templates; ++t) {
            const std::uint32_t n = joints[t % 5];
            const Kind kind = kinds[t % 5];
            const rods::ChainShape base = keyed_strand(n, kLength, glm::vec3(1, 0, 0), 0.05f);
            std::vector<rods::ChainShape> shapes;
            std::vector<rods::ViewExample> views;
            shapes.push_back(keyed_strand(n, kLength, glm::vec3(0, 0, 1), 0.25f));
            views.push_back({glm::vec3(1, 0, 0), 2.0f});
            if (kind != Nodder) {
                shapes.push_back(keyed_strand(n, kLength, glm::vec3(0, 0, 1), -0.25f));
                views.push_back({glm::vec3(-1, 0, 0), 3.0f});
            }
            rods::SolverParams params;
            params.momentum_suppression = kind == Runner ? 1.0f : 0.5f;  // both of SPEC A.5's cases (K.5)
            auto made = rods::make_chain_template("keyed" + std::to_string(t), base, shapes, views, 0.003f, 0.002f, params);
            EXPECT_TRUE(made.ok()) << made.error().message;
            rods::ChainTemplate tpl = std::move(made).value();
            if (kind == Runner) {
                const rods::KeySourceKind sources[] = {rods::KeySourceKind::Motion};
                // Streaming back (+Z is forward) when sprinting; swung sideways when turning.
                const rods::ChainShape keyed_shapes[] = {keyed_strand(n, kLength, glm::vec3(1, 0, 0), -0.3f),
                                                         keyed_strand(n, kLength, glm::vec3(0, 0, 1), 0.4f)};
                rods::KeyedExample sprint;
                sprint.kind = rods::KeyKind::Motion;
                sprint.source = 0;
                sprint.measure = rods::MotionMeasure::Speed;
                sprint.frame = rods::MotionFrame::Magnitude;
                sprint.value = glm::vec3(4.0f, 0.0f, 0.0f);  // m/s
                sprint.influence = 1.2f;
                sprint.smoothing = 0.2f;
                rods::KeyedExample turn;
                turn.kind = rods::KeyKind::Motion;
                turn.source = 0;
                turn.measure = rods::MotionMeasure::AngularSpeed;
                turn.frame = rods::MotionFrame::Joint;
                turn.value = glm::vec3(0.0f, 4.0f, 0.0f);  // rad/s about the head's up axis
                turn.influence = 1.0f;
                turn.smoothing = 0.05f;
                const rods::KeyedExample keyed[] = {sprint, turn};
                EXPECT_TRUE(rods::add_keyed_examples(tpl, sources, keyed_shapes, keyed).ok());
            } else if (kind == Nodder) {
                const rods::KeySourceKind sources[] = {rods::KeySourceKind::Pose, rods::KeySourceKind::Pose};
                const rods::ChainShape keyed_shapes[] = {keyed_strand(n, kLength, glm::vec3(1, 0, 0), 0.35f)};
                rods::KeyedExample nod;
                nod.kind = rods::KeyKind::Pose;
                nod.source_mask = 0b11;
                nod.rotations[0] = glm::angleAxis(0.5f, glm::vec3(1, 0, 0));
                nod.rotations[1] = glm::angleAxis(0.25f, glm::vec3(1, 0, 0));
                nod.influence = 0.2f;  // rad
                const rods::KeyedExample keyed[] = {nod};
                EXPECT_TRUE(rods::add_keyed_examples(tpl, sources, keyed_shapes, keyed).ok());
            }
            out.world_.templates.push_back(std::move(tpl));
            out.kinds_.push_back(kind);
        }
        constexpr std::uint32_t kPerCharacter = 3;
        out.world_.character_count = (chains + kPerCharacter - 1) / kPerCharacter;
        for (std::uint32_t c = 0; c < chains; ++c) {
            rods::ChainInstance ch;
            ch.template_index = c % templates;
            ch.character = c / kPerCharacter;
            out.world_.chains.push_back(ch);
        }
        EXPECT_TRUE(out.world_.finalize().ok());
        return out;
    }

    const rods::RodWorld& world() const { return world_; }
    Kind kind(std::uint32_t chain) const { return kinds_[world_.chains[chain].template_index]; }

    void frame(std::uint32_t f, rods::RodFrame& out) const {
        const float t = static_cast<float>(f) * kKeyedDt;
        out.time = t;
        out.dt = kKeyedDt;
        out.camera = rods::Camera{};
        out.camera.position = glm::vec3(2.5f, 1.7f, 3.0f);
        out.reference.resize(world_.character_count);
        out.roots.resize(world_.chains.size());
        out.colliders.clear();
        out.keys.resize(world_.key_count);
        auto smooth = [](float u) {
            u = std::clamp(u, 0.0f, 1.0f);
            return u * u * (3.0f - 2.0f * u);
        };
        std::vector<float> pitch(world_.character_count);
        std::vector<glm::quat> heading(world_.character_count);
        for (std::uint32_t i = 0; i < world_.character_count; ++i) {
            const float late = 0.02f * static_cast<float>(i % 7);
            const float run = smooth((t - 0.1f - late) / 0.6f);            // 3-3.6 m in 0.6 s: up to ~9 m/s
            const float yaw = 1.2f * smooth((t - 0.7f - late) / 0.35f);    // up to ~5 rad/s
            const float nod = std::clamp((t - 0.8f - late) / 0.5f, 0.0f, 1.0f);
            pitch[i] = 0.55f * std::sin(3.14159265f * nod);
            heading[i] = glm::angleAxis(yaw, glm::vec3(0, 1, 0));
            const glm::vec3 at(1.5f * static_cast<float>(i % 6), 1.6f, -1.5f * static_cast<float>(i / 6) +
                                                                          (3.0f + 0.3f * static_cast<float>(i % 3)) * run);
            out.reference[i] = rods::Transform{at, glm::normalize(heading[i] * glm::angleAxis(pitch[i], glm::vec3(1, 0, 0)))};
        }
        for (std::uint32_t c = 0; c < world_.chains.size(); ++c) {
            const rods::ChainInstance& ch = world_.chains[c];
            const rods::Transform& head = out.reference[ch.character];
            const glm::vec3 offset(0.04f * static_cast<float>(c % 3) - 0.04f, 0.08f, -0.05f);
            out.roots[c] = rods::Transform{head.position + head.rotation * offset, head.rotation};
            switch (kind(c)) {
                case Runner: out.keys[ch.key_begin] = head; break;
                case Nodder:
                    out.keys[ch.key_begin] = rods::Transform{glm::vec3(0.0f), glm::angleAxis(pitch[ch.character], glm::vec3(1, 0, 0))};
                    out.keys[ch.key_begin + 1] =
                        rods::Transform{glm::vec3(0.0f), glm::angleAxis(0.5f * pitch[ch.character], glm::vec3(1, 0, 0))};
                    break;
                case Plain: break;
            }
        }
    }

private:
    rods::RodWorld world_;
    std::vector<Kind> kinds_;
};


}  // namespace kodawari::testing_support
