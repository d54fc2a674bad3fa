// The effects the seed asks for, on the CPU reference: the ahoge's sideways curl, the bangs parting, the bunny ears splaying per view.

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <memory>
#include <numbers>
#include <string>
#include <vector>

#include <glm/glm.hpp>
#include <glm/gtc/matrix_transform.hpp>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <kodawari/vulkan/gpu_info.hpp>
#include <kodawari/backends/rod_backend.hpp>
#include <kodawari/scene/scene.hpp>
#include <kodawari/rods/kinematics.hpp>
#include <kodawari/rods/solver.hpp>
#include <kodawari/rods/world.hpp>

#include "character_support.hpp"

using namespace kodawari::testing_support::characters;  // the character suites' shared helpers

// ---------------------------------------------------------------------------------------
// The ahoge (SPEC A; the seed's figure 7): "seen from any direction, the ahoge reads as a
// sideways curl".

namespace {

struct AhogeRun {
    float min_ratio = 1e9f;                  // worst sideways offset, in strand lengths
    int failing_frames = 0;                  // frames below the margin
    int frames = 0;
    std::array<float, 24> bin_min{};         // worst ratio per 15-degree bin of the view azimuth
    std::array<int, 24> bin_frames{};
};

// The criterion: on screen, the tip lies to the camera's right of the root by at least
// `margin` of the strand's length (as projected at the root's depth). That is what "reads
// as a sideways curl" means for a strand that stands up from the top of the head: the
// curl shows in profile, always opening the same way.
AhogeRun run_ahoge(const RodScene& scene, float margin, float warmup_s) {
    AhogeRun out;
    out.bin_min.fill(1e9f);
    Simulation sim(scene);
    const rods::ChainTemplate& t = scene.world.templates[0];
    float length = 0.0f;
    for (std::uint32_t i = 0; i + 1 < t.chain.joint_count; ++i) length += t.chain.segment_length[i];
    const std::uint32_t last = t.chain.joint_count - 1;
    const auto first_checked = static_cast<std::uint32_t>(std::lround(warmup_s * scene.fps));
    for (std::uint32_t f = 1; f < scene.frames; ++f) {
        sim.step(f);
        if (f < first_checked) continue;
        const Projector cam(scene.camera_pose(f), scene.fov_deg);
        const glm::vec3 root = sim.x(0, 0);
        const float sideways = (cam.pixel(sim.x(0, last)).x - cam.pixel(root).x) / (length * cam.scale(root));
        const glm::vec3 d = rods::rest_shape(scene.world, 0, sim.frame()).view_direction;
        float azimuth = std::atan2(d.x, d.z) * 180.0f / kPi;  // 0 = the head's front, 90 = its left
        if (azimuth < 0.0f) azimuth += 360.0f;
        const auto bin = static_cast<std::size_t>(std::min(23.0f, azimuth / 15.0f));
        out.bin_min[bin] = std::min(out.bin_min[bin], sideways);
        ++out.bin_frames[bin];
        out.min_ratio = std::min(out.min_ratio, sideways);
        if (sideways < margin) ++out.failing_frames;
        ++out.frames;
    }
    return out;
}

}  // namespace

// SPEC A.3 with the seed's figure 7. scenes/ahoge.json is simulated with the CPU reference
// while its camera orbits the head once (12 s, after 2 s to settle from the initial pose),
// at 60 fps: 720 frames, 30 per 15 degrees of view azimuth, so every one of 24 azimuth bins
// round the head is checked about 30 times. At every frame the chain is projected with a
// look-at + perspective camera and the tip must lie to the camera's right of the root by
// at least 0.25 of the strand's length. Why 0.25: the view examples are 150-degree curls
// whose tip sits ~0.7 of the length sideways; the blend between two neighbouring examples
// (45 degrees off both) still curls ~0.69 sideways, and the simulated strand lags the
// orbit, the head turn and the sway by a few per cent of its length, so 0.25 leaves a wide
// margin while a curl that opens the wrong way (negative) or faces the camera (near 0)
// fails. The same
// scene without its view examples (the base shape, curled to the character's left) must
// fail the check somewhere, so the test can fail: seen from behind, the base curl opens
// to the camera's left.
TEST(Characters, AhogeReadsSidewaysFromEveryAngle) {
    Scene scene = load("scenes/ahoge.json");
    ASSERT_EQ(scene.characters.size(), 1u);
    const RodScene with_views = build(scene);
    ASSERT_EQ(with_views.world.chains.size(), 1u);
    constexpr float kMargin = 0.25f;
    const AhogeRun run = run_ahoge(with_views, kMargin, 2.0f);
    for (std::size_t b = 0; b < 24; ++b) {
        std::printf("[ measured ] view azimuth %3zu-%3zu deg: %2d frames, tip at least %.3f of the length to the camera's right\n",
                    15 * b, 15 * b + 15, run.bin_frames[b], static_cast<double>(run.bin_min[b]));
        EXPECT_GE(run.bin_frames[b], 10) << "azimuth bin " << b << " barely visited";
    }
    std::printf("[ measured ] ahoge with view examples: worst sideways offset %.3f of the strand length over %d frames "
                "(bound %.2f)\n",
                static_cast<double>(run.min_ratio), run.frames, static_cast<double>(kMargin));
    scene.characters[0].chains[0].views.clear();
    const RodScene base_only = build(scene);
    const AhogeRun control = run_ahoge(base_only, kMargin, 2.0f);
    std::printf("[ measured ] ahoge, base shape only: worst sideways offset %.3f; %d of %d frames below %.2f\n",
                static_cast<double>(control.min_ratio), control.failing_frames, control.frames, static_cast<double>(kMargin));
    EXPECT_EQ(run.failing_frames, 0);
    EXPECT_GE(run.min_ratio, kMargin);
    EXPECT_GT(control.failing_frames, 0) << "without view examples the check should fail somewhere";
}

namespace {

// Seen from a fixed camera in front of the face, the smallest on-screen distance from
// either eye to any bang over the last second of a 3 s run, in head radii.
float eye_clearance(Scene scene) {
    scene.camera.motion.kind = rods::CameraMotion::Kind::Fixed;
    scene.camera.motion.position = glm::vec3(0.0f, 1.57f, 1.0f);
    scene.camera.motion.target = glm::vec3(0.0f, 1.57f, 0.0f);
    scene.duration = 3.0f;
    const RodScene rs = build(scene);
    Simulation sim(rs);
    float clearance = 1e9f;
    for (std::uint32_t f = 1; f < rs.frames; ++f) {
        sim.step(f);
        if (rs.time(f) < 2.0f) continue;
        clearance = std::min(clearance, eye_to_strands(rs, sim, Projector(rs.camera_pose(f), rs.fov_deg)));
    }
    return clearance;
}

}  // namespace

// The seed's first example: front hair that keeps off the eyes when seen from the front.
// Bounds: with the front example every strand stays at least 0.2 head radii (22 mm at
// this head) from both eye centres on screen; the base shape alone (hanging straight
// down the forehead) brings a strand within 0.1 head radii of an eye. Measured 0.38 and
// 0.05; the rest shapes alone give 0.41 and 0.06, so gravity and the sway take little.
TEST(Characters, BangsPartFromTheFront) {
    Scene scene = load("scenes/bangs.json");
    const float with_views = eye_clearance(scene);
    for (kodawari::ChainSpec& chain : scene.characters[0].chains) chain.views.clear();
    const float base_only = eye_clearance(scene);
    std::printf("[ measured ] eye clearance seen from the front: %.3f head radii with the view example, %.3f with the base shape only\n",
                static_cast<double>(with_views), static_cast<double>(base_only));
    EXPECT_GE(with_views, 0.2f);
    EXPECT_LE(base_only, 0.1f);
}

namespace {

// Seen from a fixed camera at `azimuth_deg` round the head (0 = in front, 90 = the
// character's left), the smallest on-screen horizontal distance between the two ear tips
// over the last second of a 3 s run, in ear lengths. The head turn is left out so that
// the camera alone sets the view.
float ear_tip_separation(Scene scene, float azimuth_deg) {
    auto& oscillations = scene.characters[0].motion.oscillations;
    oscillations.erase(std::remove_if(oscillations.begin(), oscillations.end(),
                                      [](const rods::Oscillation& o) { return o.axis == glm::vec3(0.0f, 1.0f, 0.0f); }),
                       oscillations.end());
    const float a = azimuth_deg * kPi / 180.0f;
    scene.camera.motion.kind = rods::CameraMotion::Kind::Fixed;
    scene.camera.motion.target = glm::vec3(0.0f, 1.65f, 0.0f);
    scene.camera.motion.position = scene.camera.motion.target + 1.6f * glm::vec3(std::sin(a), 0.0f, std::cos(a));
    scene.duration = 3.0f;
    const RodScene rs = build(scene);
    Simulation sim(rs);
    const rods::Chain& ear = rs.world.templates[0].chain;
    float length = 0.0f;
    for (std::uint32_t i = 0; i + 1 < ear.joint_count; ++i) length += ear.segment_length[i];
    float separation = 1e9f;
    for (std::uint32_t f = 1; f < rs.frames; ++f) {
        sim.step(f);
        if (rs.time(f) < 2.0f) continue;
        const Projector cam(rs.camera_pose(f), rs.fov_deg);
        const glm::vec3 left = sim.x(0, ear.joint_count - 1);
        const glm::vec3 right = sim.x(1, ear.joint_count - 1);
        separation = std::min(separation, std::abs(cam.pixel(left).x - cam.pixel(right).x) / (length * cam.scale(0.5f * (left + right))));
    }
    return separation;
}

}  // namespace

// The seed's figure 8: bunny ears with three view examples. From the front they splay
// into a V; from either side the near ear sweeps back and the far one forward, so both
// ears show instead of one hiding the other. Bounds: from each side the tips stay at least
// 0.5 ear lengths apart on screen while the base shape alone keeps them within 0.2 (they
// line up); from the front the V adds at least 0.5 ear lengths to the base's spread.
TEST(Characters, BunnyEarsSplayPerView) {
    Scene scene = load("scenes/bunny.json");
    ASSERT_EQ(scene.characters[0].chains.size(), 2u);
    const float front = ear_tip_separation(scene, 0.0f);
    const float side = ear_tip_separation(scene, 90.0f);
    const float other_side = ear_tip_separation(scene, -90.0f);
    for (kodawari::ChainSpec& chain : scene.characters[0].chains) chain.views.clear();
    const float front_base = ear_tip_separation(scene, 0.0f);
    const float side_base = ear_tip_separation(scene, 90.0f);
    std::printf("[ measured ] ear tips apart on screen: front %.3f, left side %.3f, right side %.3f ear lengths; base shape only: front %.3f, side %.3f\n",
                static_cast<double>(front), static_cast<double>(side), static_cast<double>(other_side), static_cast<double>(front_base), static_cast<double>(side_base));
    EXPECT_GE(side, 0.5f);
    EXPECT_GE(other_side, 0.5f);
    EXPECT_LE(side_base, 0.2f);
    EXPECT_GE(front, front_base + 0.5f);
}
