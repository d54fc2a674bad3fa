#include "kodawari/backends/compare.hpp"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <limits>
#include <numbers>

#include "kodawari/birds/rig.hpp"

namespace kodawari {

double quaternion_angle(const gpu::vec4& qa, const gpu::vec4& qb) {
    const double a[4] = {qa.x, qa.y, qa.z, qa.w};
    const double b[4] = {qb.x, qb.y, qb.z, qb.w};
    // 2 atan2(|a - b|, |a + b|) is accurate for tiny angles, unlike 2 acos(a.b).
    const double sign = (a[0] * b[0] + a[1] * b[1] + a[2] * b[2] + a[3] * b[3]) < 0.0 ? -1.0 : 1.0;
    double d[4], s[4];
    for (int i = 0; i < 4; ++i) {
        d[i] = a[i] - sign * b[i];
        s[i] = a[i] + sign * b[i];
    }
    const double dn = std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2] + d[3] * d[3]);
    const double sn = std::sqrt(s[0] * s[0] + s[1] * s[1] + s[2] * s[2] + s[3] * s[3]);
    return 2.0 * std::atan2(dn, sn);
}

void BirdComparison::Acc::add(double value, std::uint32_t b, std::uint32_t f) {
    if (!(value <= max)) {  // NaN counts as the worst
        max = std::isnan(value) ? std::numeric_limits<double>::infinity() : value;
        bird = b;
        frame = f;
    }
    sum += value;
    ++n;
}

BirdComparison::BirdComparison(const birds::BirdWorld& world, BirdTolerances tolerances)
    : birds_(static_cast<std::uint32_t>(world.birds.size())), route_length_(std::max(1.0, double{world.max_route_length()})), tol_(tolerances) {}

void BirdComparison::add(std::uint32_t first_frame, std::uint32_t frames, std::span<const gpu::BirdPose> reference,
                         std::span<const gpu::BirdPose> tested, std::span<const gpu::BirdDiag> reference_diag,
                         std::span<const gpu::BirdDiag> tested_diag) {
    assert(reference.size() == std::size_t{frames} * birds_ && tested.size() == reference.size());
    const bool diag = !reference_diag.empty() && !tested_diag.empty();
    constexpr double kTwoPi = 2.0 * std::numbers::pi;
    for (std::uint32_t k = 0; k < frames; ++k) {
        const std::uint32_t frame = first_frame + k;
        for (std::uint32_t b = 0; b < birds_; ++b) {
            const std::size_t i = std::size_t{k} * birds_ + b;
            const gpu::vec4 &p = reference[i].position, &q = tested[i].position;
            const double dx = double{p.x} - double{q.x}, dy = double{p.y} - double{q.y}, dz = double{p.z} - double{q.z};
            position_.add(std::sqrt(dx * dx + dy * dy + dz * dz), b, frame);
            spread_.add(std::fabs(double{p.w} - double{q.w}), b, frame);
            for (int part = 0; part < KW_PART_COUNT; ++part) {
                rotation_[part].add(quaternion_angle(reference[i].rotation[part], tested[i].rotation[part]), b, frame);
            }
            if (diag) {
                const double dp = std::fabs(double{reference_diag[i].attitude.w} - double{tested_diag[i].attitude.w});
                phase_.add(std::min(dp, kTwoPi - dp), b, frame);
                blend_.add(std::fabs(double{reference_diag[i].velocity.w} - double{tested_diag[i].velocity.w}), b, frame);
                mode_.add(reference_diag[i].acceleration.w != tested_diag[i].acceleration.w ? 1.0 : 0.0, b, frame);
            }
        }
    }
}

std::vector<Deviation> BirdComparison::results() const {
    auto make = [](std::string name, std::string unit, const Acc& acc, double tolerance) {
        return Deviation{std::move(name), std::move(unit), acc.max, acc.n ? acc.sum / static_cast<double>(acc.n) : 0.0,
                         tolerance, acc.n, acc.bird, acc.frame};
    };
    std::vector<Deviation> out;
    out.push_back(make("position", "m", position_, tol_.position_fraction_of_route * route_length_));
    out.push_back(make("tail spread", "", spread_, tol_.tail_spread));
    for (std::size_t part = 0; part < KW_PART_COUNT; ++part) {
        out.push_back(make("rotation " + std::string(birds::kPartNames[part]), "rad", rotation_[part], tol_.rotation_rad));
    }
    if (phase_.n > 0) {
        out.push_back(make("phase", "rad", phase_, tol_.phase_rad));
        out.push_back(make("blend", "", blend_, tol_.blend));
        out.push_back(make("mode mismatch", "", mode_, 0.0));
    }
    return out;
}

bool BirdComparison::within() const {
    const auto all = results();
    return std::all_of(all.begin(), all.end(), [](const Deviation& d) { return d.within(); });
}

}  // namespace kodawari
