// The procedural rod world of benchmarks and backend tests.
#include "kodawari/rods/synthetic.hpp"

#include <cmath>
#include <numbers>

namespace kodawari::rods {
namespace {

constexpr float kPi = std::numbers::pi_v<float>;
constexpr float kHeadRadius = 0.1f;
constexpr float kSpacing = 1.5f;  // m between characters

// A strand of `joints` joints and length `length` leaving the root along -Y... then
// curling by `turn` rad per segment about `axis`; each joint's +Y along its segment.
ChainShape strand(std::uint32_t joints, float length, glm::vec3 axis, float turn) {
    ChainShape s;
    glm::vec3 d(0.0f, -1.0f, 0.0f);
    const float l = length / static_cast<float>(joints - 1);
    s.positions.push_back(glm::vec3(0.0f));
    for (std::uint32_t i = 0; i + 1 < joints; ++i) {
        s.positions.push_back(s.positions.back() + l * d);
        s.orientations.push_back(shortest_arc(glm::vec3(0, 1, 0), d));
        d = glm::normalize(glm::angleAxis(turn, axis) * d);
    }
    s.orientations.push_back(s.orientations.back());
    return s;
}

std::uint32_t character_count(const SyntheticOptions& o) {
    return (o.chains + o.chains_per_character - 1) / o.chains_per_character;
}

// The head of character c at time t: a grid position, a sway and a turn with per-character phases.
Transform head(const SyntheticOptions& o, std::uint32_t c, float t) {
    const std::uint32_t side = static_cast<std::uint32_t>(std::ceil(std::sqrt(static_cast<float>(character_count(o)))));
    const float phase = 0.37f * static_cast<float>(c);
    Transform h;
    h.position = glm::vec3(kSpacing * static_cast<float>(c % side), 1.6f, kSpacing * static_cast<float>(c / side));
    h.position.x += o.motion * 0.08f * std::sin(2.0f * kPi * 0.7f * t + phase);
    h.position.y += o.motion * 0.03f * std::sin(2.0f * kPi * 1.9f * t + phase);
    h.rotation = glm::angleAxis(o.motion * 0.9f * std::sin(2.0f * kPi * 0.4f * t + phase), glm::vec3(0, 1, 0)) *
                 glm::angleAxis(o.motion * 0.2f * std::sin(2.0f * kPi * 1.1f * t + phase), glm::vec3(1, 0, 0));
    return h;
}

}  // namespace

Result<SyntheticScene> SyntheticScene::make(const SyntheticOptions& o) {
    if (o.chains < 1 || o.joints < 2 || o.joints > kMaxChainJoints || o.chains_per_character < 1 ||
        o.views > kMaxViewExamples || o.iterations < 1 || o.iterations > 64) {
        return make_error(Error::Kind::InvalidInput,
                          "synthetic rods: need chains >= 1, joints 2.." + std::to_string(kMaxChainJoints) +
                              ", views <= " + std::to_string(kMaxViewExamples) + ", iterations 1..64");
    }
    SyntheticScene s;
    s.options_ = o;
    s.length_ = 0.02f * static_cast<float>(o.joints);  // 2 cm segments
    const std::uint32_t per = std::min(o.chains, o.chains_per_character);
    SolverParams params;
    params.iterations = o.iterations;
    params.stiffness = 0.5f;
    params.damping = 2.0f;
    params.settle_start = o.settle;
    const glm::vec3 directions[kMaxViewExamples] = {{0, 0, 1},  {1, 0, 0},  {-1, 0, 0}, {0, 0, -1},
                                                    {0, 1, 0},  {0.7f, 0, 0.7f}, {-0.7f, 0, 0.7f}};
    for (std::uint32_t k = 0; k < per; ++k) {
        // Strands around the crown of the head, each leaving outwards.
        const float angle = 2.0f * kPi * static_cast<float>(k) / static_cast<float>(per);
        const glm::vec3 out(std::sin(angle), 0.0f, std::cos(angle));
        Transform offset;
        offset.position = kHeadRadius * glm::normalize(out + glm::vec3(0, 0.6f, 0));
        offset.rotation = glm::angleAxis(-0.5f, glm::normalize(glm::cross(out, glm::vec3(0, -1, 0))));  // tilts -Y outwards
        s.chain_offsets_.push_back(offset);
        const ChainShape base = strand(o.joints, s.length_, glm::vec3(1, 0, 0), 0.05f);
        std::vector<ChainShape> examples;
        std::vector<ViewExample> views;
        for (std::uint32_t v = 0; v < o.views; ++v) {
            const glm::vec3 axis = v % 2 == 0 ? glm::vec3(0, 0, 1) : glm::vec3(1, 0, 0);
            examples.push_back(strand(o.joints, s.length_, axis, (v % 3 == 0 ? 0.15f : -0.12f)));
            views.push_back({glm::normalize(directions[v]), 2.0f + static_cast<float>(v)});
        }
        auto t = make_chain_template("strand" + std::to_string(k), base, examples, views, 0.003f, 0.002f, params);
        if (!t) return t.error();
        s.world_.templates.push_back(std::move(t).value());
    }
    const std::uint32_t characters = character_count(o);
    s.world_.character_count = characters;
    s.world_.collider_count = o.colliders ? characters : 0;
    for (std::uint32_t c = 0; c < o.chains; ++c) {
        const std::uint32_t character = c / o.chains_per_character;
        s.world_.chains.push_back({c % o.chains_per_character % per, character, o.colliders ? character : 0u,
                                   o.colliders ? 1u : 0u, 0u});
    }
    KW_TRY(s.world_.finalize());
    return s;
}

void SyntheticScene::frame(std::uint32_t index, float dt, RodFrame& out) const {
    const float t = static_cast<float>(index) * dt;
    out.time = t;
    out.dt = dt;
    // The camera orbits the whole grid once every 8 s at 3 m above the heads.
    const float orbit = 2.0f * kPi * t / 8.0f;
    out.camera = Camera{};
    out.camera.position = glm::vec3(20.0f * std::sin(orbit), 4.6f, 20.0f * std::cos(orbit));
    out.reference.resize(world_.character_count);
    out.roots.resize(world_.chains.size());
    out.colliders.resize(world_.collider_count);
    for (std::uint32_t c = 0; c < world_.character_count; ++c) {
        out.reference[c] = head(options_, c, t);
        if (options_.colliders) {
            // Inside the roots, as a scalp collider must be: a root inside its collider
            // would fight the collision pass for the first segment.
            out.colliders[c] = Collider{out.reference[c].position, out.reference[c].position, 0.8f * kHeadRadius};
        }
    }
    for (std::size_t k = 0; k < world_.chains.size(); ++k) {
        const ChainInstance& chain = world_.chains[k];
        const Transform& h = out.reference[chain.character];
        const Transform& off = chain_offsets_[chain.template_index];
        out.roots[k] = Transform{h.position + h.rotation * off.position, glm::normalize(h.rotation * off.rotation)};
    }
}

}  // namespace kodawari::rods
