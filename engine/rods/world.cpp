// Chain templates, the rod world's bookkeeping and the per-chain rest shape (SPEC A.2, A.3).
#include "kodawari/rods/world.hpp"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <limits>

namespace kodawari::rods {
namespace {

Error bad(const std::string& what) { return make_error(Error::Kind::InvalidInput, what); }

bool finite(glm::vec3 v) { return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z); }
bool finite(glm::quat q) { return std::isfinite(q.x) && std::isfinite(q.y) && std::isfinite(q.z) && std::isfinite(q.w); }

}  // namespace

Result<ChainTemplate> make_chain_template(std::string name, const ChainShape& base,
                                          std::span<const ChainShape> example_shapes,
                                          std::span<const ViewExample> views, float thickness, float mass,
                                          const SolverParams& params) {
    const std::string where = "chain '" + name + "': ";
    auto with_name = [&](const Error& e) { return make_error(e.kind, where + e.message); };
    if (example_shapes.size() != views.size()) {
        return bad(where + "expected one shape per view example");
    }
    if (views.size() > kMaxViewExamples) {
        return bad(where + "at most " + std::to_string(kMaxViewExamples) + " view examples, got " +
                   std::to_string(views.size()));
    }
    if (auto ok = validate(params); !ok) return with_name(ok.error());
    ChainTemplate t;
    t.name = std::move(name);
    t.params = params;
    auto chain = make_chain(base, thickness, mass);
    if (!chain) return with_name(chain.error());
    t.chain = chain.value();
    auto basis = make_basis(base);
    if (!basis) return with_name(basis.error());
    t.basis = std::move(basis.value());
    auto base_rot = to_rotations(t.basis, base);
    if (!base_rot) return with_name(base_rot.error());
    t.shapes.push_back(std::move(base_rot.value()));
    for (std::size_t k = 0; k < views.size(); ++k) {
        const std::string example = "view example " + std::to_string(k) + ": ";
        ViewExample v = views[k];
        if (!(v.influence > 0.0f && std::isfinite(v.influence))) {
            return bad(where + example + "influence must be > 0");
        }
        const float len = glm::length(v.direction);
        if (!(len > 1e-6f && std::isfinite(len))) {
            return bad(where + example + "direction must be a finite, non-zero vector");
        }
        v.direction /= len;
        for (const glm::quat& o : example_shapes[k].orientations) {
            if (!finite(o) || !(std::abs(glm::length(o) - 1.0f) < 1e-3f)) {
                return bad(where + example + "orientations must be unit quaternions");
            }
        }
        auto rot = to_rotations(t.basis, example_shapes[k]);
        if (!rot) return bad(where + example + rot.error().message);
        t.shapes.push_back(std::move(rot.value()));
        t.views.push_back(v);
    }
    return t;
}

Result<void> add_keyed_examples(ChainTemplate& t, std::span<const KeySourceKind> sources,
                                std::span<const ChainShape> shapes, std::span<const KeyedExample> keyed) {
    const std::string where = "chain '" + t.name + "': ";
    assert(t.keyed.empty() && t.key_sources.empty() && "add_keyed_examples once per template");
    if (shapes.size() != keyed.size()) return bad(where + "expected one shape per keyed example");
    if (sources.size() > kMaxKeySources) {
        return bad(where + "at most " + std::to_string(kMaxKeySources) + " key sources, got " +
                   std::to_string(sources.size()));
    }
    if (keyed.size() > kMaxKeyedExamples) {
        return bad(where + "at most " + std::to_string(kMaxKeyedExamples) + " keyed examples, got " +
                   std::to_string(keyed.size()));
    }
    if (t.views.size() + keyed.size() > kMaxViewExamples) {
        return bad(where + "at most " + std::to_string(kMaxViewExamples) + " examples in all (views and keyed), got " +
                   std::to_string(t.views.size() + keyed.size()));
    }
    for (std::size_t j = 0; j < keyed.size(); ++j) {
        const KeyedExample& e = keyed[j];
        const std::string example = "keyed example " + std::to_string(j) + ": ";
        if (!(e.influence > 0.0f && std::isfinite(e.influence))) return bad(where + example + "influence must be > 0");
        if (e.kind == KeyKind::Motion) {
            if (!(e.smoothing >= 0.0f && e.smoothing <= kMaxSmoothing)) {
                return bad(where + example + "smoothing must be in [0, " + std::to_string(int(kMaxSmoothing)) + "] s");
            }
            if (e.source >= sources.size() || sources[e.source] != KeySourceKind::Motion) {
                return bad(where + example + "source must be a motion key source");
            }
            if (!finite(e.value)) return bad(where + example + "the key must be finite");
            if (e.frame == MotionFrame::Magnitude && !(e.value.x >= 0.0f)) {
                return bad(where + example + "a magnitude key must be >= 0");
            }
        } else {
            if (e.source_mask == 0 || e.source_mask >= (1u << sources.size())) {
                return bad(where + example + "a pose key needs at least one pose key source");
            }
            for (std::uint32_t s = 0; s < sources.size(); ++s) {
                if ((e.source_mask & (1u << s)) == 0) continue;
                if (sources[s] != KeySourceKind::Pose) return bad(where + example + "its sources must be pose key sources");
                if (!finite(e.rotations[s]) || !(std::abs(glm::length(e.rotations[s]) - 1.0f) < 1e-3f)) {
                    return bad(where + example + "key rotations must be unit quaternions");
                }
            }
        }
        for (const glm::quat& o : shapes[j].orientations) {
            if (!finite(o) || !(std::abs(glm::length(o) - 1.0f) < 1e-3f)) {
                return bad(where + example + "orientations must be unit quaternions");
            }
        }
    }
    std::vector<RotationShape> rotations;
    for (std::size_t j = 0; j < keyed.size(); ++j) {
        auto rot = to_rotations(t.basis, shapes[j]);
        if (!rot) return bad(where + "keyed example " + std::to_string(j) + ": " + rot.error().message);
        rotations.push_back(std::move(rot.value()));
    }
    t.key_sources.assign(sources.begin(), sources.end());
    t.keyed.assign(keyed.begin(), keyed.end());
    for (KeyedExample& e : t.keyed) {
        e.saturation = std::numeric_limits<float>::infinity();
        if (e.kind != KeyKind::Motion || e.frame != MotionFrame::Magnitude) continue;
        float top = 0.0f;  // K.2: the largest key of the same source and measure
        for (const KeyedExample& o : t.keyed) {
            if (o.kind == KeyKind::Motion && o.frame == MotionFrame::Magnitude && o.source == e.source &&
                o.measure == e.measure) {
                top = std::max(top, o.value.x);
            }
        }
        e.saturation = top;
    }
    for (RotationShape& r : rotations) t.shapes.push_back(std::move(r));
    return {};
}

Result<void> RodWorld::finalize() {
    KW_TRY(validate(lod, "rod world: lod"));
    joint_count = 0;
    key_count = 0;
    std::vector<bool> center_taken(center_count, false);
    for (std::size_t c = 0; c < chains.size(); ++c) {
        ChainInstance& chain = chains[c];
        const std::string where = "rod world: chain " + std::to_string(c) + ": ";
        if (chain.template_index >= templates.size()) return bad(where + "template index out of range");
        if (chain.character >= character_count) return bad(where + "character index out of range");
        if (chain.collider_begin > collider_count || chain.collider_count > collider_count - chain.collider_begin) {
            return bad(where + "collider range out of range");
        }
        if (chain.collider_count > kMaxChainColliders) {
            return bad(where + "at most " + std::to_string(kMaxChainColliders) + " colliders per chain");
        }
        if (wind_count > 0 && chain.wind >= wind_count) return bad(where + "wind index out of range");
        if (chain.center != kNoCenter) {
            if (chain.center >= center_count) return bad(where + "center index out of range");
            if (center_taken[chain.center]) return bad(where + "center " + std::to_string(chain.center) + " belongs to another chain");
            center_taken[chain.center] = true;
        }
        chain.joint_begin = joint_count;
        joint_count += templates[chain.template_index].chain.joint_count;
        chain.key_begin = key_count;
        key_count += static_cast<std::uint32_t>(templates[chain.template_index].key_sources.size());
    }
    return {};
}

Result<void> check_frame(const RodWorld& world, const RodFrame& frame) {
    // >= 10 us: velocities are displacements / dt, infinite for a denormal dt (fuzzing).
    if (!(frame.dt >= kMinFrameDt && std::isfinite(frame.dt))) return bad("rod frame: dt must be >= 1e-5 s");
    if (frame.reference.size() != world.character_count || frame.roots.size() != world.chains.size() ||
        frame.colliders.size() != world.collider_count || frame.keys.size() != world.key_count ||
        frame.centers.size() != world.center_count || frame.winds.size() != world.wind_count) {
        return bad("rod frame: expected " + std::to_string(world.character_count) + " reference poses, " +
                   std::to_string(world.chains.size()) + " roots, " + std::to_string(world.collider_count) +
                   " colliders, " + std::to_string(world.key_count) + " key sources, " +
                   std::to_string(world.center_count) + " centers and " + std::to_string(world.wind_count) + " winds");
    }
    if (!std::isfinite(frame.time)) return bad("rod frame: time must be finite");
    for (std::size_t k = 0; k < frame.winds.size(); ++k) {
        const std::string what = "rod frame: winds[" + std::to_string(k) + "]";
        KW_TRY(validate(frame.winds[k], what.c_str()));
    }
    for (const Transform& t : frame.centers) {
        if (!finite(t.position) || !finite(t.rotation)) return bad("rod frame: non-finite center");
    }
    for (const Transform& t : frame.keys) {
        if (!finite(t.position) || !finite(t.rotation)) return bad("rod frame: non-finite key source");
    }
    for (const Transform& t : frame.reference) {
        if (!finite(t.position) || !finite(t.rotation)) return bad("rod frame: non-finite reference pose");
    }
    for (const Transform& t : frame.roots) {
        if (!finite(t.position) || !finite(t.rotation)) return bad("rod frame: non-finite chain root");
    }
    for (const Collider& c : frame.colliders) {
        if (!finite(c.a) || !finite(c.b) || !(c.radius >= 0.0f)) return bad("rod frame: bad collider");
        switch (c.kind) {
            case ColliderKind::Outside:
            case ColliderKind::Inside: break;
            case ColliderKind::Plane:
                // The normal b is a unit vector (to rounding: a rotation keeps it one).
                if (std::abs(glm::length(c.b) - 1.0f) > 1e-3f) return bad("rod frame: a plane collider's normal b is not a unit vector");
                break;
            default: return bad("rod frame: unknown collider kind");
        }
    }
    if (!finite(frame.camera.position) || !finite(frame.camera.forward)) return bad("rod frame: non-finite camera");
    return {};
}

RestShape rest_shape(const RodWorld& world, std::uint32_t chain, const RodFrame& frame, const KeyedWeights& keyed) {
    const ChainInstance& c = world.chains[chain];
    const ChainTemplate& t = world.templ(c);
    const Transform& ref = frame.reference[c.character];
    RestShape out;
    out.view_direction = view_direction(frame.camera, ref.position, ref.rotation);  // SPEC A.3
    out.weights = view_weights(out.view_direction, t.views);                         // SPEC A.3
    if (!t.keyed.empty()) {  // keyed-examples.md K.4
        const std::vector<float> view = std::move(out.weights);
        out.weights.assign(view.size() + t.keyed.size(), 0.0f);
        combine_weights(view, std::span<const float>(keyed.data(), t.keyed.size()), out.weights);
    }
    out.shape = to_positions(t.basis, blend(t.shapes, out.weights));  // SPEC A.2
    return out;
}

glm::vec3 chain_air(const RodWorld& world, std::uint32_t chain, const RodFrame& frame) {
    if (world.wind_count == 0) return glm::vec3(0.0f);
    return air_velocity(frame.winds[world.chains[chain].wind], frame.roots[chain].position, frame.time);
}

ChainState initial_chain_state(const RodWorld& world, std::uint32_t chain, const RodFrame& frame) {
    const ChainInstance& c = world.chains[chain];
    const ChainTemplate& t = world.templ(c);
    const ChainShape rest = rest_shape(world, chain, frame).shape;
    ChainState s = initial_state(t.chain, frame.roots[chain], rest);
    if (t.params.settle_start) {
        settle(t.chain, t.params, frame.roots[chain], rest,
               std::span<const Collider>(frame.colliders).subspan(c.collider_begin, c.collider_count), s,
               chain_air(world, chain, frame));
        const glm::quat to_root = glm::conjugate(frame.roots[chain].rotation);
        for (std::uint32_t i = 0; i < t.chain.joint_count; ++i) {
            s.sag[i] = to_root * (s.x[i] - frame.roots[chain].rotation * rest.positions[i]);
        }
    }
    if (c.center != kNoCenter) s.center = frame.centers[c.center];
    return s;
}

std::span<const Transform> chain_keys(const RodWorld& world, std::uint32_t chain, const RodFrame& frame) {
    const ChainInstance& c = world.chains[chain];
    return std::span<const Transform>(frame.keys).subspan(c.key_begin, world.templ(c).key_sources.size());
}

KeyState initial_key_state(const RodWorld& world, std::uint32_t chain, const RodFrame& frame) {
    return initial_key_state(chain_keys(world, chain, frame));
}

KeyedWeights measure_keys(const RodWorld& world, std::uint32_t chain, const RodFrame& frame, KeyState& keys,
                          std::uint32_t frames) {
    assert(frames >= 1);
    const ChainTemplate& t = world.templ(world.chains[chain]);
    if (t.keyed.empty()) return {};
    const float dt = frame.dt * static_cast<float>(frames);  // over the frames since the last measure
    return keyed_weights(t.keyed, t.key_sources, chain_keys(world, chain, frame), dt, keys, t.params.teleport_distance);
}

}  // namespace kodawari::rods
