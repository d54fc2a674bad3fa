// The rods solver's setup (SPEC A.4): its parameters checked, a chain built from its base
// shape, its angle limits, and its initial state.
#include <algorithm>
#include <cassert>
#include <cmath>
#include <string>

#include "kodawari/rods/solver.hpp"

namespace kodawari::rods {

Result<void> validate(const SolverParams& p) {
    auto bad = [](const std::string& what) { return make_error(Error::Kind::InvalidInput, "rods solver: " + what); };
    if (!(p.max_substep > 0.0f && p.max_substep <= 0.05f)) return bad("max_substep must be in (0, 0.05] s");
    if (p.iterations < 1 || p.iterations > 64) return bad("iterations must be 1 to 64");
    if (!(p.stiffness >= 0.0f && p.stiffness <= 1.0f)) return bad("stiffness must be in [0, 1]");
    if (!(p.rest_stiffness >= 0.0f && p.rest_stiffness <= 1.0f)) return bad("rest_stiffness must be in [0, 1]");
    if (!(p.damping >= 0.0f && std::isfinite(p.damping))) return bad("damping must be >= 0");
    if (!(p.momentum_suppression >= 0.0f && p.momentum_suppression <= 1.0f)) {
        return bad("momentum_suppression must be in [0, 1]");
    }
    if (!(p.normal_drag >= 0.0f && p.normal_drag <= 1000.0f)) return bad("normal_drag must be in [0, 1000] 1/s");
    if (!(p.tangent_drag >= 0.0f && p.tangent_drag <= 1000.0f)) return bad("tangent_drag must be in [0, 1000] 1/s");
    if (!std::isfinite(glm::dot(p.gravity, p.gravity)) || !std::isfinite(glm::dot(p.wind, p.wind))) {
        return bad("gravity and wind must be finite");
    }
    if (!(p.teleport_distance > 0.0f && std::isfinite(p.teleport_distance))) {
        return bad("teleport_distance must be > 0 m and finite");
    }
    return {};
}

Result<void> set_limits(Chain& chain, std::span<const AngleLimit> limits, const std::string& what) {
    if (!limits.empty() && limits.size() + 1 != chain.joint_count) {
        return make_error(Error::Kind::InvalidInput, what + ": expected " + std::to_string(chain.joint_count - 1) +
                                                         " limits (one per segment), got " +
                                                         std::to_string(limits.size()));
    }
    Chain limited = chain;
    limited.limited = false;
    for (std::uint32_t i = 0; i < kMaxChainJoints; ++i) {
        const AngleLimit limit = i < limits.size() ? limits[i] : AngleLimit{};
        KW_TRY(validate(limit, what + "[" + std::to_string(i) + "]"));
        limited.limit[i] = limit;
        limited.limit_trig[i] = limit_trig(limit);
        limited.limit_frame[i] = limit_frame(chain.bone_axis[i], limit.rotation);
        limited.limited = limited.limited || limit.kind != LimitKind::None;
    }
    chain = limited;
    return {};
}

Result<Chain> make_chain(const ChainShape& base, float thickness, float mass) {
    auto basis = make_basis(base);
    if (!basis) return basis.error();
    // Lower bounds, not just > 0: the inertia m r^2 of a denormal mass or radius is 0 in
    // float and its inverse infinite (found by fuzzing the C API). 10 um and 1 ug are
    // below a single hair's width and a segment's mass.
    if (!(thickness >= kMinThickness && std::isfinite(thickness))) {
        return make_error(Error::Kind::InvalidInput, "rods chain: thickness must be >= 1e-5 m");
    }
    if (!(mass >= kMinMass && std::isfinite(mass))) {
        return make_error(Error::Kind::InvalidInput, "rods chain: mass must be >= 1e-9 kg");
    }
    Chain chain;
    chain.joint_count = basis.value().joint_count();
    chain.thickness = thickness;
    const std::uint32_t n = chain.joint_count;
    for (std::uint32_t i = 0; i < n; ++i) {
        const std::uint32_t seg = std::min(i, n - 2);
        chain.mass[i] = mass;
        if (i + 1 < n) chain.segment_length[i] = basis.value().lengths[i];
        // SPEC A.4: a = half the segment length along the segment.
        chain.half_length[i] = 0.5f * basis.value().lengths[seg];
        const glm::vec3 dir = glm::normalize(base.positions[seg + 1] - base.positions[seg]);
        chain.bone_axis[i] = glm::normalize(glm::conjugate(glm::normalize(base.orientations[i])) * dir);
    }
    return chain;
}

ChainState initial_state(const Chain& chain, const Transform& root, const ChainShape& rest) {
    assert(rest.positions.size() == chain.joint_count && rest.orientations.size() == chain.joint_count);
    ChainState s;
    s.root = root;
    for (std::uint32_t i = 0; i < chain.joint_count; ++i) {
        s.x[i] = root.rotation * rest.positions[i];
        s.q[i] = glm::normalize(root.rotation * rest.orientations[i]);
        s.rest_position[i] = rest.positions[i];
        s.rest_orientation[i] = rest.orientations[i];
    }
    return s;
}

}  // namespace kodawari::rods
