// Chain templates, the rod world's bookkeeping and the per-chain rest shape (SPEC A.2, A.3).
#include "kodawari/rods/world.hpp"

#include <cmath>

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

Result<void> RodWorld::finalize() {
    joint_count = 0;
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
        chain.joint_begin = joint_count;
        joint_count += templates[chain.template_index].chain.joint_count;
    }
    return {};
}

Result<void> check_frame(const RodWorld& world, const RodFrame& frame) {
    // >= 10 us: velocities are displacements / dt, infinite for a denormal dt (fuzzing).
    if (!(frame.dt >= kMinFrameDt && std::isfinite(frame.dt))) return bad("rod frame: dt must be >= 1e-5 s");
    if (frame.reference.size() != world.character_count || frame.roots.size() != world.chains.size() ||
        frame.colliders.size() != world.collider_count) {
        return bad("rod frame: expected " + std::to_string(world.character_count) + " reference poses, " +
                   std::to_string(world.chains.size()) + " roots and " + std::to_string(world.collider_count) +
                   " colliders");
    }
    for (const Transform& t : frame.reference) {
        if (!finite(t.position) || !finite(t.rotation)) return bad("rod frame: non-finite reference pose");
    }
    for (const Transform& t : frame.roots) {
        if (!finite(t.position) || !finite(t.rotation)) return bad("rod frame: non-finite chain root");
    }
    for (const Capsule& c : frame.colliders) {
        if (!finite(c.a) || !finite(c.b) || !(c.radius >= 0.0f)) return bad("rod frame: bad collider");
    }
    if (!finite(frame.camera.position) || !finite(frame.camera.forward)) return bad("rod frame: non-finite camera");
    return {};
}

RestShape rest_shape(const RodWorld& world, std::uint32_t chain, const RodFrame& frame) {
    const ChainInstance& c = world.chains[chain];
    const ChainTemplate& t = world.templ(c);
    const Transform& ref = frame.reference[c.character];
    RestShape out;
    out.view_direction = view_direction(frame.camera, ref.position, ref.rotation);  // SPEC A.3
    out.weights = view_weights(out.view_direction, t.views);                         // SPEC A.3
    out.shape = to_positions(t.basis, blend(t.shapes, out.weights));                 // SPEC A.2
    return out;
}

}  // namespace kodawari::rods
