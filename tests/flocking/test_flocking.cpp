// The flocking domain (issue 32, docs/flocking.md): the same body on every backend, what
// a flock looks like by the measures of starling flocks, predators, the routes of other
// flocks untouched, shards, and bad input.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <map>
#include <cmath>
#include <cstring>
#include <string>
#include <vector>

#include <glm/glm.hpp>
#include <glm/gtc/quaternion.hpp>

#include "kodawari/domains/birds.hpp"
#include "kodawari/domains/flocking.hpp"
#include "kodawari/simulation/simulation.hpp"
#include "test_support.hpp"

using namespace kodawari;

namespace {

// A loop over a field at 45 m, 1 001 birds (not a multiple of the 64- or 256-wide
// workgroups), and the flocking object `flocking` (JSON); `grow` scales the formation's
// box (more birds at the same density).
std::string scene_text(std::uint32_t birds, double seconds, const std::string& flocking, const std::string& extra_flock = "",
                       float grow = 1.0f) {
    return R"({"format": "kodawari-scene", "version": 1, "name": "flocking-test", "fps": 60, "duration": )" + std::to_string(seconds) +
           R"(, "camera": {"position": [0, 60, -160], "target": [0, 45, 0], "fov_deg": 60}, "flocks": [)" + extra_flock +
           R"({"name": "starlings", "wing_type": "pigeon", "count": )" + std::to_string(birds) +
           R"(, "seed": 2024, "speed": 15, "speed_jitter": 0.04,
               "generated_route": {"seed": 7, "segments": 8, "center": [0, 45, 0], "extent": [45, 8, 45], "loop": true},
               "formation": {"spread": [)" + std::to_string(14.0f * grow) + ", " + std::to_string(6.0f * grow) + ", " +
           std::to_string(14.0f * grow) + R"(]}, "flocking": )" + flocking + "}]}";
}

std::unique_ptr<Simulation> open_text(const std::string& text, const testing_support::BackendCase& backend) {
    auto scene = parse_scene(text, "flocking-test.json");
    EXPECT_TRUE(scene.ok()) << scene.error().message;
    if (!scene.ok()) return nullptr;
    SimulationOptions options{.backend = backend.kind, .options = testing_support::backend_options(backend)};
    auto made = Simulation::create(std::move(scene).value(), options);
    EXPECT_TRUE(made.ok()) << made.error().message;
    return made.ok() ? std::move(made).value() : nullptr;
}

// The poses of `frames` frames of scene_text(birds, seconds, flocking) on the cpu backend.
std::vector<gpu::BirdPose> fly_cpu(std::uint32_t birds, double seconds, std::uint32_t frames, const std::string& flocking) {
    auto sim = open_text(scene_text(birds, seconds, flocking), {BackendKind::Cpu, ""});
    EXPECT_NE(sim, nullptr);
    std::vector<gpu::BirdPose> poses(std::size_t{frames} * birds);
    if (sim) {
        EXPECT_TRUE(step_birds(*sim, frames, poses).ok());
    }
    return poses;
}

// A point as JSON, [x, y, z].
std::string json_point(const glm::vec3& v) {
    return "[" + std::to_string(v.x) + ", " + std::to_string(v.y) + ", " + std::to_string(v.z) + "]";
}

std::string parse_error(const std::string& text) {
    auto scene = parse_scene(text, "flocking-test.json");
    return scene.ok() ? std::string("(parsed)") : scene.error().message;
}

bool same_bits(const gpu::BirdPose& a, const gpu::BirdPose& b) { return std::memcmp(&a, &b, sizeof(a)) == 0; }

glm::vec3 position(const gpu::BirdPose& p) { return {p.position.x, p.position.y, p.position.z}; }
glm::vec3 forward(const gpu::BirdPose& p) {
    const gpu::vec4& q = p.rotation[KW_PART_BODY];
    return glm::quat(q.w, q.x, q.y, q.z) * glm::vec3(0.0f, 0.0f, 1.0f);
}

// Starling flocks' measures (Ballerini et al. 2008) of one frame's poses.
struct FlockMeasures {
    float min_nn = 1e9f, median_nn = 0.0f, polarization = 0.0f, cos2 = 0.0f;
};
FlockMeasures measure(std::span<const gpu::BirdPose> poses) {
    const std::size_t n = poses.size();
    std::vector<float> nn(n, 1e9f);
    std::vector<std::size_t> nearest(n, 0);
    for (std::size_t i = 0; i < n; ++i) {
        for (std::size_t j = 0; j < n; ++j) {
            if (i == j) continue;
            const float d = glm::length(position(poses[j]) - position(poses[i]));
            if (d < nn[i]) nn[i] = d, nearest[i] = j;
        }
    }
    FlockMeasures m;
    glm::vec3 mean_forward(0.0f);
    double cos2 = 0.0;
    for (std::size_t i = 0; i < n; ++i) {
        const glm::vec3 f = forward(poses[i]);
        mean_forward += f;
        const glm::vec3 to = glm::normalize(position(poses[nearest[i]]) - position(poses[i]));
        cos2 += static_cast<double>(glm::dot(to, f) * glm::dot(to, f));
        m.min_nn = std::min(m.min_nn, nn[i]);
    }
    std::vector<float> sorted = nn;
    std::nth_element(sorted.begin(), sorted.begin() + static_cast<std::ptrdiff_t>(n / 2), sorted.end());
    m.median_nn = sorted[n / 2];
    m.polarization = glm::length(mean_forward) / static_cast<float>(n);
    m.cos2 = static_cast<float>(cos2 / static_cast<double>(n));
    return m;
}

// The largest group of one frame's birds at single linkage `link` (m): birds nearer than
// `link` to each other are one group, and so on transitively (cells of `link` and a
// union-find over neighbouring cells).
std::size_t largest_group(std::span<const gpu::BirdPose> poses, float link) {
    const std::size_t n = poses.size();
    std::vector<std::size_t> parent(n);
    for (std::size_t i = 0; i < n; ++i) parent[i] = i;
    const auto root = [&](std::size_t i) {
        while (parent[i] != i) i = parent[i] = parent[parent[i]];
        return i;
    };
    std::map<std::array<int, 3>, std::vector<std::size_t>> cells;
    const auto cell_of = [&](const glm::vec3& p) {
        return std::array<int, 3>{static_cast<int>(std::floor(p.x / link)), static_cast<int>(std::floor(p.y / link)),
                                  static_cast<int>(std::floor(p.z / link))};
    };
    for (std::size_t i = 0; i < n; ++i) cells[cell_of(position(poses[i]))].push_back(i);
    for (std::size_t i = 0; i < n; ++i) {
        const glm::vec3 p = position(poses[i]);
        const auto c = cell_of(p);
        for (int dx = -1; dx <= 1; ++dx) {
            for (int dy = -1; dy <= 1; ++dy) {
                for (int dz = -1; dz <= 1; ++dz) {
                    const auto it = cells.find({c[0] + dx, c[1] + dy, c[2] + dz});
                    if (it == cells.end()) continue;
                    for (std::size_t j : it->second) {
                        if (j > i && glm::length(position(poses[j]) - p) < link) parent[root(i)] = root(j);
                    }
                }
            }
        }
    }
    std::map<std::size_t, std::size_t> sizes;
    std::size_t largest = 0;
    for (std::size_t i = 0; i < n; ++i) largest = std::max(largest, ++sizes[root(i)]);
    return largest;
}

class FlockingBackends : public ::testing::TestWithParam<testing_support::BackendCase> {};

// cpu (every instruction set) is cpu-reference's bits in the flock's motion and the birds'
// positions (their rotations within the bird backends' parity), with every kind of the
// scene's obstacles and an attractor among the birds; vulkan is
// within 1e-3 m of it after 40 frames (the flow is chaotic, so two orders of rounding part
// slowly: measured 3.8e-6 m after 40 frames on lavapipe) and gives the same bits twice.
TEST_P(FlockingBackends, StepLikeTheReference) {
    if (GetParam() == BackendKind::Vulkan) {
        const std::string why = testing_support::no_vulkan_device_reason();
        if (!why.empty()) GTEST_SKIP() << why;
    }
    constexpr std::uint32_t kBirds = 1001, kFrames = 40;
    // Where the flock starts, for the scene's obstacles to be among it: a capsule through
    // it, a plane across it, a sphere and an attractor beside it (every agent kind).
    glm::vec3 c(0.0f);
    {
        auto probe = open_text(scene_text(kBirds, 2.0, "{}"), {BackendKind::CpuReference, ""});
        ASSERT_NE(probe, nullptr);
        std::vector<gpu::BirdPose> first(kBirds);
        ASSERT_TRUE(step_birds(*probe, 1, first).ok());
        for (const gpu::BirdPose& p : first) c += position(p) / float(kBirds);
    }
    const auto at = [&](float x, float y, float z) {
        return "[" + std::to_string(c.x + x) + ", " + std::to_string(c.y + y) + ", " + std::to_string(c.z + z) + "]";
    };
    const std::string text = scene_text(
        kBirds, 2.0,
        R"({"obstacles": [{"type": "capsule", "a": )" + at(-3, -20, 0) + R"(, "b": )" + at(-3, 20, 0) +
            R"(, "radius": 2, "margin": 6}, {"type": "plane", "point": )" + at(0, -2, 0) +
            R"(, "normal": [0, 1, 0.2], "margin": 4}, {"type": "sphere", "center": )" + at(6, 0, 4) +
            R"(, "radius": 1.5, "margin": 5}], "attractors": [{"position": )" + at(0, 10, 30) + R"(, "radius": 60, "weight": 10}]})");
    const auto run = [&](const testing_support::BackendCase& backend, std::vector<gpu::BirdPose>& poses,
                         std::vector<gpu::BirdMotionGpu>& motion) {
        auto sim = open_text(text, backend);
        ASSERT_NE(sim, nullptr);
        poses.resize(std::size_t{kFrames} * kBirds);
        motion.resize(std::size_t{kFrames} * kBirds);
        // In two calls: the second starts from the state the first left.
        const std::size_t half = std::size_t{kFrames / 2} * kBirds;
        for (std::size_t first : {std::size_t{0}, half}) {
            // The second half with two agents of the application's (an obstacle and a
            // predator crossing the flock), so that every backend runs both agent counts.
            if (first == half) {
                FlockAgent obstacle, predator;
                obstacle.kind = FlockAgent::Kind::Obstacle;
                obstacle.position = {10.0f, 45.0f, 0.0f};
                obstacle.radius = 6.0f;
                predator.position = {-20.0f, 45.0f, 5.0f};
                predator.velocity = {20.0f, 0.0f, 0.0f};
                predator.radius = 25.0f;
                const FlockAgent agents[] = {obstacle, predator};
                ASSERT_TRUE(set_flock_agents(*sim, agents).ok());
            }
            const ChannelOutput out[] = {
                {kBirdPosesChannel, std::as_writable_bytes(std::span(poses).subspan(first, half))},
                {kFlockingMotionChannel, std::as_writable_bytes(std::span(motion).subspan(first, half))}};
            ASSERT_TRUE(sim->step(kFrames / 2, out).ok());
        }
    };
    std::vector<gpu::BirdPose> reference, poses, again;
    std::vector<gpu::BirdMotionGpu> reference_motion, motion, again_motion;
    run({BackendKind::CpuReference, ""}, reference, reference_motion);
    run(GetParam(), poses, motion);
    if (GetParam() == BackendKind::Vulkan) {
        float worst = 0.0f;
        for (std::size_t i = 0; i < poses.size(); ++i) worst = std::max(worst, glm::length(position(poses[i]) - position(reference[i])));
        std::printf("vulkan against cpu-reference after %u frames: %.3g m\n", kFrames, static_cast<double>(worst));
        EXPECT_LT(worst, 1e-3f);
        run(GetParam(), again, again_motion);
        EXPECT_EQ(std::memcmp(again.data(), poses.data(), poses.size() * sizeof(gpu::BirdPose)), 0) << "vulkan twice: other bits";
        EXPECT_EQ(std::memcmp(again_motion.data(), motion.data(), motion.size() * sizeof(gpu::BirdMotionGpu)), 0);
    } else {
        EXPECT_EQ(std::memcmp(motion.data(), reference_motion.data(), motion.size() * sizeof(gpu::BirdMotionGpu)), 0);
        // The bird backends' own parity (compare.hpp's BirdTolerances): positions within
        // 1e-5 m (the body's bob follows the wingbeat's sine), part rotations within 1e-4
        // (the cpu backend's own vector sines of the wingbeat and the attitude's).
        for (std::size_t i = 0; i < poses.size(); ++i) {
            ASSERT_LT(glm::length(position(poses[i]) - position(reference[i])), 1e-5f) << "frame " << i / kBirds << ", bird " << i % kBirds;
            for (int p = 0; p < KW_PART_COUNT; ++p) {
                const gpu::vec4 &a = poses[i].rotation[p], &b = reference[i].rotation[p];
                ASSERT_NEAR(a.x, b.x, 1e-4f);
                ASSERT_NEAR(a.y, b.y, 1e-4f);
                ASSERT_NEAR(a.z, b.z, 1e-4f);
                ASSERT_NEAR(a.w, b.w, 1e-4f);
            }
        }
    }
}

INSTANTIATE_TEST_SUITE_P(All, FlockingBackends, testing_support::all_backend_kinds(), testing_support::backend_test_name);

// The default rules give what starling flocks show (Ballerini et al. 2008; Cavagna et al.
// 2010) once it has settled from the random box it starts in (6 s): no two birds closer
// than 0.1 m (half a body length), nearest neighbours 0.5 to 2 m apart (median),
// polarization at least 0.9, and neighbours to the sides more than ahead or behind (mean
// cos^2 of the angle between a bird's flight and the direction to its nearest neighbour
// at most 0.3; 1/3 is no structure). Measured on cpu at 8, 10 and 12 s: nearest 0.39 to
// 0.60 m, medians 1.28 to 1.29 m, polarization 0.999, cos^2 0.25 to 0.26 (before
// collision avoidance, with the separation off: nearest 0.02 m, median 0.3 m).
TEST(Flocking, FliesLikeStarlings) {
    constexpr std::uint32_t kBirds = 1501;
    auto sim = open_text(scene_text(kBirds, 12.0, "{}"), {BackendKind::Cpu, ""});
    ASSERT_NE(sim, nullptr);
    std::vector<gpu::BirdPose> poses(kBirds);
    std::uint32_t done = 0;
    for (const std::uint32_t until : {480u, 600u, 720u}) {
        std::vector<gpu::BirdPose> frames(std::size_t{until - done} * kBirds);
        ASSERT_TRUE(step_birds(*sim, until - done, frames).ok());
        done = until;
        const FlockMeasures m = measure(std::span(frames).last(kBirds));
        // No Body turns more than 6 degrees between frames (the route birds' bound,
        // tests/birds/test_bank_filter.cpp), wingbeat included.
        double worst_turn = 0.0;
        for (std::size_t f = 1; f < frames.size() / kBirds; ++f) {
            for (std::size_t b = 0; b < kBirds; ++b) {
                const gpu::vec4 &p = frames[(f - 1) * kBirds + b].rotation[KW_PART_BODY], &q = frames[f * kBirds + b].rotation[KW_PART_BODY];
                const double dot = std::min(1.0, std::abs(double{p.x * q.x + p.y * q.y + p.z * q.z + p.w * q.w}));
                worst_turn = std::max(worst_turn, 2.0 * std::acos(dot) * 180.0 / 3.141592653589793);
            }
        }
        std::printf("largest Body turn between frames: %.2f deg\n", worst_turn);
        EXPECT_LE(worst_turn, 6.0);
        std::printf("t = %.0f s: nearest %.3f m, median %.2f m, polarization %.3f, cos^2 %.3f\n", until / 60.0,
                    static_cast<double>(m.min_nn), static_cast<double>(m.median_nn), static_cast<double>(m.polarization),
                    static_cast<double>(m.cos2));
        EXPECT_GE(m.min_nn, 0.1f);
        EXPECT_GE(m.median_nn, 0.5f);
        EXPECT_LE(m.median_nn, 2.0f);
        EXPECT_GE(m.polarization, 0.9f);
        EXPECT_LE(m.cos2, 0.3f);
    }
}

// A predator through the middle of the flock at 4 s: birds keep out of its way (measured:
// the nearest bird 1.84 m from it, 2.5 to 5.5 s; 2.05 m before collision avoidance, whose
// spaced start is another flock). Without it (the control) birds are where it passes
// (0.13 m).
TEST(Flocking, BirdsFleeAPredator) {
    constexpr std::uint32_t kBirds = 601, kFrames = 420;
    const auto closest = [&](const std::string& flocking) { return fly_cpu(kBirds, 7.0, kFrames, flocking); };
    // Where the flock is at 4 s without a predator: the predator is sent through there.
    const std::vector<gpu::BirdPose> alone = closest("{}");
    glm::vec3 centre(0.0f);
    for (std::uint32_t b = 0; b < kBirds; ++b) centre += position(alone[std::size_t{240} * kBirds + b]) / float(kBirds);
    const glm::vec3 from = centre + glm::vec3(-40.0f, 0.0f, 0.0f), to = centre + glm::vec3(40.0f, 0.0f, 0.0f);
    const std::string predator = R"({"predators": [{"from": [)" + std::to_string(from.x) + "," + std::to_string(from.y) + "," +
                                 std::to_string(from.z) + "], \"to\": [" + std::to_string(to.x) + "," + std::to_string(to.y) + "," +
                                 std::to_string(to.z) + R"(], "start": 2, "speed": 20, "radius": 20, "weight": 60}]})";
    const std::vector<gpu::BirdPose> chased = closest(predator);
    // The predator is at from + 20 (t - 2) m along x; the nearest bird to it each frame.
    const auto nearest = [&](const std::vector<gpu::BirdPose>& poses) {
        float best = 1e9f;
        for (std::uint32_t f = 150; f < 330; ++f) {
            const float t = static_cast<float>(f) / 60.0f;
            const glm::vec3 at = from + glm::vec3(20.0f * (t - 2.0f), 0.0f, 0.0f);
            for (std::uint32_t b = 0; b < kBirds; ++b) best = std::min(best, glm::length(position(poses[std::size_t{f} * kBirds + b]) - at));
        }
        return best;
    };
    const float without = nearest(alone), with = nearest(chased);
    std::printf("nearest bird to the predator's path, 2.5 to 5.5 s: %.2f m without it, %.2f m with it\n", static_cast<double>(without),
                static_cast<double>(with));
    EXPECT_LT(without, 1.0f);  // the control: the line goes through the flock
    EXPECT_GT(with, 3.0f * without + 1.0f);
}

// A falcon head-on through the middle of the flock splits it in two, and the flock closes
// behind it: the largest group at 3 m single linkage (issue 32's measure; the median
// nearest neighbour is about 1 m) every quarter second. The falcon: 30 m/s (a peregrine's
// level chase), fled within 15 m at up to 40 m/s^2 (the defaults). Measured (2 001
// birds): split at 4.25 s into 1 199 and the rest, 99% together again at 11.25 s (before
// collision avoidance and its spaced start, another flock: 4.75 s and 9.0 s); the old
// rule, fleeing straight away from the path, opened a tube that never split it (at least
// 1 984 together). The control flies whole. How soon halves rejoin depends on where the
// cut falls: the same falcon 1 s later cut the flock into 1 018 and 983 birds that flew
// on 18 m apart for the 7 s measured (only the route's formation slots draw two halves
// together; a bird's 7 neighbours are all in its own half: docs/flocking.md).
TEST(Flocking, AFalconSplitsTheFlockAndItRejoins) {
    constexpr std::uint32_t kBirds = 2001, kFrames = 900;
    const std::vector<gpu::BirdPose> alone = fly_cpu(kBirds, 15.0, kFrames, "{}");
    // Head-on along the flock's heading at 4 s, as a falcon attacks from ahead: from 60 m
    // ahead of the flock's centre then, at 30 m/s from 1 s, so it meets the flock at about
    // 2.5 s on and passes through its length.
    glm::vec3 centre(0.0f), heading(0.0f);
    for (std::uint32_t b = 0; b < kBirds; ++b) {
        centre += position(alone[std::size_t{240} * kBirds + b]) / float(kBirds);
        heading += forward(alone[std::size_t{240} * kBirds + b]);
    }
    heading.y = 0.0f;
    heading = glm::normalize(heading);
    const glm::vec3 from = centre + 60.0f * heading, to = centre - 120.0f * heading;
    const std::vector<gpu::BirdPose> chased =
        fly_cpu(kBirds, 15.0, kFrames,
                R"({"predators": [{"from": )" + json_point(from) + R"(, "to": )" + json_point(to) +
                    R"(, "start": 1, "speed": 30, "radius": 15, "weight": 40}]})");
    const auto largest = [&](const std::vector<gpu::BirdPose>& poses, std::uint32_t f) {
        return largest_group(std::span(poses).subspan(std::size_t{f} * kBirds, kBirds), 3.0f);
    };
    std::size_t smallest_alone = kBirds, smallest = kBirds;
    std::uint32_t split_at = 0, rejoined_at = 0;
    for (std::uint32_t f = 120; f < kFrames; f += 15) {
        smallest_alone = std::min(smallest_alone, largest(alone, f));
        const std::size_t now = largest(chased, f);
        if (now < smallest) smallest = now;
        if (split_at == 0 && now < kBirds * 7 / 10) split_at = f;
        if (split_at != 0 && rejoined_at == 0 && now * 100 >= std::size_t{kBirds} * 99) rejoined_at = f;
    }
    std::printf("[ measured ] largest group at 3 m: %zu of %u without the falcon at the fewest; with it %zu at the fewest, "
                "split at %.2f s, 99%% together again at %.2f s\n",
                smallest_alone, kBirds, smallest, static_cast<double>(split_at) / 60.0, static_cast<double>(rejoined_at) / 60.0);
    EXPECT_EQ(smallest_alone, kBirds);  // the control: one flock all along
    ASSERT_NE(split_at, 0u) << "no split: the largest group never fell below 70% of the flock";
    EXPECT_NE(rejoined_at, 0u) << "not together again by 15 s";
    EXPECT_LE(rejoined_at - split_at, 480u);  // within 8 s (measured 7 s; 4.25 s before)
}

// The application's agents (set_flock_agents, per frame): a predator it moves through the
// flock frame by frame, as the scene's predator of BirdsFleeAPredator is moved (the same
// line and speed), is fled the same way (1.84 m from its path, as the scene's); an
// obstacle sphere it places where the flock flies (4 m, its push from 12 m off its surface,
// as far as a bird at 15 m/s needs to turn 4 m aside at its wings' 17 m/s^2) is flown
// round: no bird inside it (measured 4.28 m from its centre at the nearest; a push
// straight out of it, which only brakes a bird heading for its centre, left one 0.77 m
// inside). Without them the flock flies through both places (0.13 and 0.21 m).
TEST(Flocking, ApplicationAgentsAreFledAndAvoided) {
    constexpr std::uint32_t kBirds = 601, kFrames = 420;
    const std::string text = scene_text(kBirds, 7.0, "{}");
    // Where the flock is at 4 s with nothing placed: the agents go there.
    auto probe = open_text(text, {BackendKind::Cpu, ""});
    ASSERT_NE(probe, nullptr);
    std::vector<gpu::BirdPose> alone(std::size_t{kFrames} * kBirds);
    ASSERT_TRUE(step_birds(*probe, kFrames, alone).ok());
    glm::vec3 centre(0.0f);
    for (std::uint32_t b = 0; b < kBirds; ++b) centre += position(alone[std::size_t{240} * kBirds + b]) / float(kBirds);
    const glm::vec3 from = centre + glm::vec3(-40.0f, 0.0f, 0.0f);
    const auto predator_at = [&](std::uint32_t f) { return from + glm::vec3(20.0f * (static_cast<float>(f) / 60.0f - 2.0f), 0.0f, 0.0f); };
    const auto run = [&](bool predator, bool obstacle) {
        auto sim = open_text(text, {BackendKind::Cpu, ""});
        EXPECT_NE(sim, nullptr);
        std::vector<gpu::BirdPose> poses(std::size_t{kFrames} * kBirds);
        for (std::uint32_t f = 0; f < kFrames; ++f) {
            std::vector<FlockAgent> agents;
            if (predator && f >= 120) {
                FlockAgent a;
                a.position = predator_at(f);
                a.velocity = {20.0f, 0.0f, 0.0f};
                a.radius = 20.0f;
                a.weight = 60.0f;
                agents.push_back(a);
            }
            if (obstacle) {
                FlockAgent a;
                a.kind = FlockAgent::Kind::Obstacle;
                a.position = centre;
                a.radius = 4.0f;
                a.margin = 12.0f;
                a.weight = 80.0f;
                agents.push_back(a);
            }
            EXPECT_TRUE(set_flock_agents(*sim, agents).ok());
            EXPECT_TRUE(step_birds(*sim, 1, std::span(poses).subspan(std::size_t{f} * kBirds, kBirds)).ok());
        }
        return poses;
    };
    const auto nearest = [&](const std::vector<gpu::BirdPose>& poses, bool moving) {
        float best = 1e9f;
        for (std::uint32_t f = 150; f < 330; ++f) {
            const glm::vec3 at = moving ? predator_at(f) : centre;
            for (std::uint32_t b = 0; b < kBirds; ++b) best = std::min(best, glm::length(position(poses[std::size_t{f} * kBirds + b]) - at));
        }
        return best;
    };
    const float predator_without = nearest(alone, true), predator_with = nearest(run(true, false), true);
    const float obstacle_without = nearest(alone, false), obstacle_with = nearest(run(false, true), false);
    std::printf("[ measured ] nearest bird to the application's predator, 2.5 to 5.5 s: %.2f m without it, %.2f m with it; "
                "to the obstacle's centre (radius 4 m): %.2f m without it, %.2f m with it\n",
                static_cast<double>(predator_without), static_cast<double>(predator_with), static_cast<double>(obstacle_without),
                static_cast<double>(obstacle_with));
    EXPECT_LT(predator_without, 1.0f);
    EXPECT_GT(predator_with, 3.0f * predator_without + 1.0f);
    EXPECT_LT(obstacle_without, 1.0f);
    EXPECT_GT(obstacle_with, 4.0f);
    // Bad agents: named, and nothing changes.
    FlockAgent bad;
    bad.radius = 0.0f;
    const FlockAgent two[] = {FlockAgent{}, bad};
    const auto refused = set_flock_agents(*probe, two);
    ASSERT_FALSE(refused.ok());
    EXPECT_NE(refused.error().message.find("agents[1].radius"), std::string::npos) << refused.error().message;
    const std::vector<FlockAgent> many(kMaxFlockAgents + 1);
    EXPECT_FALSE(set_flock_agents(*probe, many).ok());
}

// The scene's own obstacles and attractors (flocking.obstacles, flocking.attractors): a
// capsule standing where the flock flies at 4 s (a tower: radius 4 m, margin 12 m) is flown
// round, a plane across the flock's height (a cliff top: margin 6 m) keeps the birds
// above it, and an attractor 60 m aside draws the flock's centre towards it. Measured
// against the same scene without each, from 2.5 to 5.5 s.
TEST(Flocking, SceneObstaclesAndAttractorsShapeTheFlight) {
    constexpr std::uint32_t kBirds = 601, kFrames = 330;
    auto probe = open_text(scene_text(kBirds, 5.5, "{}"), {BackendKind::Cpu, ""});
    ASSERT_NE(probe, nullptr);
    std::vector<gpu::BirdPose> alone(std::size_t{kFrames} * kBirds);
    ASSERT_TRUE(step_birds(*probe, kFrames, alone).ok());
    glm::vec3 centre(0.0f);
    for (std::uint32_t b = 0; b < kBirds; ++b) centre += position(alone[std::size_t{240} * kBirds + b]) / float(kBirds);
    const auto json = json_point;
    const auto run = [&](const std::string& flocking) { return fly_cpu(kBirds, 5.5, kFrames, flocking); };
    const glm::vec3 foot = centre - glm::vec3(0.0f, 40.0f, 0.0f), top = centre + glm::vec3(0.0f, 40.0f, 0.0f);
    const std::vector<gpu::BirdPose> towered = run(R"({"obstacles": [{"type": "capsule", "a": )" + json(foot) + R"(, "b": )" +
                                                   json(top) + R"(, "radius": 4, "margin": 12, "weight": 80}]})");
    const float cliff = centre.y - 2.0f;
    const std::vector<gpu::BirdPose> walled = run(R"({"obstacles": [{"type": "plane", "point": )" +
                                                  json(glm::vec3(centre.x, cliff, centre.z)) +
                                                  R"(, "normal": [0, 1, 0], "margin": 6, "weight": 80}]})");
    const glm::vec3 lure = centre + glm::vec3(60.0f, 0.0f, 0.0f);
    const std::vector<gpu::BirdPose> lured = run(R"({"attractors": [{"position": )" + json(lure) + R"(, "radius": 120, "weight": 30}]})");
    // Over 2.5 to 5.5 s: the nearest bird to the tower's axis, the lowest bird against the
    // plane, the flock's centre's mean distance to the attractor.
    const auto measure = [&](const std::vector<gpu::BirdPose>& poses, float& axis, float& lowest, float& lure_distance) {
        axis = 1e9f, lowest = 1e9f, lure_distance = 0.0f;
        for (std::uint32_t f = 150; f < kFrames; ++f) {
            glm::vec3 mean(0.0f);
            for (std::uint32_t b = 0; b < kBirds; ++b) {
                const glm::vec3 p = position(poses[std::size_t{f} * kBirds + b]);
                axis = std::min(axis, glm::length(glm::vec2(p.x - centre.x, p.z - centre.z)));
                lowest = std::min(lowest, p.y - cliff);
                mean += p / float(kBirds);
            }
            lure_distance += glm::length(mean - lure) / float(kFrames - 150);
        }
    };
    float axis_alone = 0, low_alone = 0, lure_alone = 0, axis_with = 0, low_with = 0, lure_with = 0, unused = 0;
    measure(alone, axis_alone, low_alone, lure_alone);
    measure(towered, axis_with, unused, unused);
    measure(walled, unused, low_with, unused);
    measure(lured, unused, unused, lure_with);
    std::printf("[ measured ] nearest bird to the tower's axis (radius 4 m): %.2f m without it, %.2f m with it; lowest bird "
                "against the plane: %.2f m without it, %.2f m with it; the flock's centre to the attractor: %.1f m without "
                "it, %.1f m with it\n",
                static_cast<double>(axis_alone), static_cast<double>(axis_with), static_cast<double>(low_alone),
                static_cast<double>(low_with), static_cast<double>(lure_alone), static_cast<double>(lure_with));
    EXPECT_LT(axis_alone, 1.0f);
    EXPECT_GT(axis_with, 4.0f);  // never inside the tower
    EXPECT_LT(low_alone, -3.0f);
    EXPECT_GT(low_with, -0.5f);  // at most half a metre into the cliff's plane
    EXPECT_LT(lure_with, lure_alone - 10.0f);
    // The same capsule and plane placed by the application (set_flock_agents, once: they
    // stay until called again) fly the scene's flight bit for bit: one encoding, one path.
    const auto placed = [&](const FlockAgent& agent) {
        auto sim = open_text(scene_text(kBirds, 5.5, "{}"), {BackendKind::Cpu, ""});
        EXPECT_NE(sim, nullptr);
        std::vector<gpu::BirdPose> poses(std::size_t{kFrames} * kBirds);
        if (sim) {
            EXPECT_TRUE(set_flock_agents(*sim, std::span(&agent, 1)).ok());
            EXPECT_TRUE(step_birds(*sim, kFrames, poses).ok());
        }
        return poses;
    };
    FlockAgent tower;
    tower.kind = FlockAgent::Kind::Capsule;
    tower.position = foot;
    tower.end = top;
    tower.radius = 4.0f;
    tower.margin = 12.0f;
    tower.weight = 80.0f;
    FlockAgent wall;
    wall.kind = FlockAgent::Kind::Plane;
    wall.position = {centre.x, cliff, centre.z};
    wall.normal = {0.0f, 2.5f, 0.0f};  // normalized, as the scene's
    wall.margin = 6.0f;
    wall.weight = 80.0f;
    // The scene's text rounds the points to 6 decimals (std::to_string): the agents get the
    // same rounding.
    const auto rounded = [](glm::vec3 v) {
        for (int c = 0; c < 3; ++c) v[c] = std::stof(std::to_string(v[c]));
        return v;
    };
    tower.position = rounded(tower.position);
    tower.end = rounded(tower.end);
    wall.position = rounded(wall.position);
    const std::vector<gpu::BirdPose> towered_by_app = placed(tower), walled_by_app = placed(wall);
    EXPECT_EQ(std::memcmp(towered_by_app.data(), towered.data(), towered.size() * sizeof(gpu::BirdPose)), 0);
    EXPECT_EQ(std::memcmp(walled_by_app.data(), walled.data(), walled.size() * sizeof(gpu::BirdPose)), 0);
    // Bad ones are named: a capsule's end, a plane's normal.
    FlockAgent far_end = tower;
    far_end.end.y = 2e6f;
    const auto no_end = set_flock_agents(*probe, std::span(&far_end, 1));
    ASSERT_FALSE(no_end.ok());
    EXPECT_NE(no_end.error().message.find("agents[0].end"), std::string::npos) << no_end.error().message;
    FlockAgent flat = wall;
    flat.normal = glm::vec3(0.0f);
    const auto no_normal = set_flock_agents(*probe, std::span(&flat, 1));
    ASSERT_FALSE(no_normal.ok());
    EXPECT_NE(no_normal.error().message.find("agents[0].normal: expected a direction"), std::string::npos)
        << no_normal.error().message;
}

// A flock without "flocking" flies its route exactly as without the flocking flock beside
// it: the same bits.
TEST(Flocking, RouteFlocksBesideItAreUnchanged) {
    const std::string route_flock = R"({"name": "gulls", "wing_type": "gull", "count": 37, "seed": 5,
        "route": {"points": [[0, 20, 0], [10, 22, 5], [20, 24, 5], [30, 20, 0]]}}, )";
    auto both = open_text(scene_text(101, 1.0, "{}", route_flock), {BackendKind::Cpu, ""});
    auto alone_scene = parse_scene(R"({"format": "kodawari-scene", "version": 1, "name": "flocking-test", "fps": 60, "duration": 1,
        "camera": {"position": [0, 60, -160], "target": [0, 45, 0], "fov_deg": 60}, "flocks": [)" +
                                       route_flock.substr(0, route_flock.size() - 2) + "]}",
                                   "alone.json");
    ASSERT_TRUE(alone_scene.ok()) << alone_scene.error().message;
    auto alone = Simulation::create(std::move(alone_scene).value(), {.backend = BackendKind::Cpu});
    ASSERT_TRUE(alone.ok()) << alone.error().message;
    ASSERT_NE(both, nullptr);
    constexpr std::uint32_t kFrames = 60;
    std::vector<gpu::BirdPose> a(kFrames * 138), b(kFrames * 37);
    ASSERT_TRUE(step_birds(*both, kFrames, a).ok());
    ASSERT_TRUE(step_birds(*alone.value(), kFrames, b).ok());
    for (std::uint32_t f = 0; f < kFrames; ++f) {
        for (std::uint32_t i = 0; i < 37; ++i) ASSERT_TRUE(same_bits(a[f * 138 + i], b[f * 37 + i])) << "frame " << f << ", gull " << i;
    }
}

// Every shard simulates the whole flocking flock and keeps its birds: the shards' birds
// are the whole run's, bit for bit.
TEST(Flocking, ShardsAreTheWholeRunsBirds) {
    constexpr std::uint32_t kBirds = 301, kFrames = 30, kShards = 3;
    auto scene = parse_scene(scene_text(kBirds, 0.5, "{}"), "flocking-test.json");
    ASSERT_TRUE(scene.ok());
    auto whole = Simulation::create(scene.value(), {.backend = BackendKind::Cpu});
    ASSERT_TRUE(whole.ok());
    std::vector<gpu::BirdPose> all(std::size_t{kFrames} * kBirds);
    ASSERT_TRUE(step_birds(*whole.value(), kFrames, all).ok());
    for (std::uint32_t s = 0; s < kShards; ++s) {
        auto part = Simulation::create(scene.value(), {.backend = BackendKind::Cpu, .shard = {s, kShards}});
        ASSERT_TRUE(part.ok()) << part.error().message;
        const InstanceRange range = part.value()->shard().part("birds").range;
        std::vector<gpu::BirdPose> poses(std::size_t{kFrames} * range.size());
        ASSERT_TRUE(step_birds(*part.value(), kFrames, poses).ok());
        for (std::uint32_t f = 0; f < kFrames; ++f) {
            for (std::uint32_t b = 0; b < range.size(); ++b) {
                ASSERT_TRUE(same_bits(poses[f * range.size() + b], all[f * kBirds + range.begin + b])) << "shard " << s << ", frame " << f;
            }
        }
    }
}

// The vulkan grid's scan over tiles (shared/flocking.h: KW_FLOCK_SCAN_TILE buckets a
// workgroup): the first flocking frame (frame 1) of `birds` birds from the same state is
// `reference`'s to rounding. One step, so that rounding (a GPU's contractions, its exp)
// has no frames to change a bird's neighbours by. A bucket's wrong start puts birds in
// the wrong cells, so that they see the wrong neighbours (each tile's start taken as the
// first's: 75 m and 16 m/s within that step at 6 001 birds).
void grid_against(BackendKind reference_kind, std::uint32_t birds, float grow) {
    const std::string why = testing_support::no_vulkan_device_reason();
    if (!why.empty()) GTEST_SKIP() << why;
    constexpr std::uint32_t kFrames = 2;
    const std::string text = scene_text(birds, 1.0, "{}", "", grow);
    const auto fly = [&](BackendKind kind, std::vector<gpu::BirdMotionGpu>& motion) {
        auto sim = open_text(text, {kind, ""});
        ASSERT_NE(sim, nullptr);
        motion.resize(std::size_t{kFrames} * birds);
        const ChannelOutput out[] = {{kFlockingMotionChannel, std::as_writable_bytes(std::span(motion))}};
        ASSERT_TRUE(sim->step(kFrames, out).ok());
    };
    std::vector<gpu::BirdMotionGpu> reference, vulkan;
    fly(reference_kind, reference);
    fly(BackendKind::Vulkan, vulkan);
    ASSERT_EQ(reference.size(), vulkan.size());
    float position = 0.0f, velocity = 0.0f;
    for (std::size_t i = std::size_t{kFrames - 1} * birds; i < reference.size(); ++i) {
        const auto& a = reference[i];
        const auto& b = vulkan[i];
        position = std::max(position, glm::length(glm::vec3(a.position.x - b.position.x, a.position.y - b.position.y,
                                                            a.position.z - b.position.z)));
        velocity = std::max(velocity, glm::length(glm::vec3(a.velocity.x - b.velocity.x, a.velocity.y - b.velocity.y,
                                                            a.velocity.z - b.velocity.z)));
    }
    std::printf("%u birds, frame %u: vulkan within %.3g m and %.3g m/s of %s\n", birds, kFrames - 1, static_cast<double>(position),
                static_cast<double>(velocity), std::string(backend_name(reference_kind)).c_str());
    EXPECT_LT(position, 1e-4f);
    EXPECT_LT(velocity, 1e-3f);
}

// 6 001 birds have 16 384 buckets, 4 tiles, where the other tests' 1 001 fit one.
// Measured on lavapipe: 0 m (positions move by the old velocity) and 9.5e-7 m/s.
TEST(Flocking, VulkanGridOfSeveralScanTilesIsTheReferences) { grid_against(BackendKind::CpuReference, 6001, 1.0f); }

// 524 289 birds (at the same density) have 2 097 152 buckets, 512 tiles: two for each
// lane of the scan's top pass, where 4 tiles leave most lanes none. Against the cpu
// backend (cpu-reference's bits, FlockingBackends.StepLikeTheReference; cpu-reference
// would take seconds more). About 10 s on lavapipe, so not in the ASan lane.
TEST(Flocking, VulkanGridOfMoreScanTilesThanLanesIsTheCpus) { grid_against(BackendKind::Cpu, 524289, 4.45f); }

// profile_flocking() times the vulkan step's parts apart (the grid, the search, what the
// rules add) and leaves the flock as it was: after it, the next frames are the bits of a
// run without it. Refused, naming the argument, for the CPU kinds, another domain and 0
// frames. Measured on lavapipe (301 birds, 5 frames), alone: the search 74% to 89% of the
// step (timings are printed, not asserted).
TEST(Flocking, ProfileTimesTheVulkanStepsPartsAndLeavesTheFlock) {
    const std::string why = testing_support::no_vulkan_device_reason();
    if (!why.empty()) GTEST_SKIP() << why;
    constexpr std::uint32_t kBirds = 301, kBefore = 8, kAfter = 6, kFrames = 5;
    const std::string text = scene_text(kBirds, 1.0, "{}");
    const auto fly = [&](bool profile, std::vector<gpu::BirdMotionGpu>& motion) {
        auto sim = open_text(text, {BackendKind::Vulkan, ""});
        ASSERT_NE(sim, nullptr);
        ASSERT_TRUE(sim->step(kBefore, {}).ok());
        Domain* flock = sim->domain(kFlockingDomain);
        ASSERT_NE(flock, nullptr);
        if (profile) {
            auto t = profile_flocking(*flock, kFrames);
            ASSERT_TRUE(t.ok()) << t.error().message;
            const FlockingTiming& p = t.value();
            const double step = p.grid_seconds + p.search_seconds + p.rules_seconds;
            std::printf("profile_flocking on vulkan, %u birds, %u frames: grid %.3g s, search %.3g s, rules %.3g s "
                        "(search %.0f%%), device %.3g s\n",
                        kBirds, kFrames, p.grid_seconds, p.search_seconds, p.rules_seconds, 100.0 * p.search_seconds / step,
                        p.device_seconds);
            // Times, so no bounds on them: the parts are differences of three runs (the
            // grid; the grid and the search; the whole step), which a busy machine can
            // order either way (a negative difference is given as 0). So the parts add up
            // to the whole step's time (device_seconds, the third run), or to more where
            // a difference was raised to 0; less would mean a part left out.
            EXPECT_GT(p.grid_seconds, 0.0);
            EXPECT_TRUE(std::isfinite(p.search_seconds) && std::isfinite(p.rules_seconds));
            if (p.device_seconds >= 0.0) {
                EXPECT_GE(step, p.device_seconds * (1.0 - 1e-12)) << "the parts add up to less than the whole step";
            } else {
                std::printf("no timestamps on this device: the parts' sum is not checked against the whole step\n");
            }
            EXPECT_EQ(p.bird_steps, std::uint64_t{kBirds} * kFrames);  // 60 fps: a substep a frame
            // The domain's own count is of its steps only (frame 0 is the routes').
            EXPECT_EQ(flocking_timing(*flock).bird_steps, std::uint64_t{kBirds} * (kBefore - 1u));
        }
        motion.resize(std::size_t{kAfter} * kBirds);
        const ChannelOutput out[] = {{kFlockingMotionChannel, std::as_writable_bytes(std::span(motion))}};
        ASSERT_TRUE(sim->step(kAfter, out).ok());
        EXPECT_EQ(sim->validation_messages(), 0u);  // with KODAWARI_VALIDATION=1 (ctest's)
    };
    std::vector<gpu::BirdMotionGpu> plain, profiled;
    fly(false, plain);
    fly(true, profiled);
    ASSERT_EQ(plain.size(), profiled.size());
    EXPECT_EQ(std::memcmp(plain.data(), profiled.data(), plain.size() * sizeof(gpu::BirdMotionGpu)), 0)
        << "the frames after profile_flocking differ from a run without it";

    auto cpu = open_text(text, {BackendKind::Cpu, ""});
    ASSERT_NE(cpu, nullptr);
    ASSERT_TRUE(cpu->step(2, {}).ok());
    const auto on_cpu = profile_flocking(*cpu->domain(kFlockingDomain), kFrames);
    ASSERT_FALSE(on_cpu.ok());
    EXPECT_EQ(on_cpu.error().kind, Error::Kind::Unsupported);
    const auto no_frames = profile_flocking(*cpu->domain(kFlockingDomain), 0);
    ASSERT_FALSE(no_frames.ok());
    EXPECT_NE(no_frames.error().message.find("frames"), std::string::npos) << no_frames.error().message;
    const auto birds = profile_flocking(*cpu->domain(kBirdDomain), kFrames);
    ASSERT_FALSE(birds.ok());
    EXPECT_NE(birds.error().message.find("domain: expected the flocking domain"), std::string::npos) << birds.error().message;
}

TEST(Flocking, BadValuesAreRefusedNamingThem) {
    EXPECT_EQ(parse_error(scene_text(10, 1.0, R"({"neighbours": 0})")),
              "flocking-test.json: $.flocks[0].flocking.neighbours: expected an integer in [1, 16], got 0");
    EXPECT_EQ(parse_error(scene_text(10, 1.0, R"({"blind_angle_deg": 180})")),
              "flocking-test.json: $.flocks[0].flocking.blind_angle_deg: expected a finite number in [0, 180), got 180");
    EXPECT_EQ(parse_error(scene_text(10, 1.0, R"({"search_radius": 2, "separation_distance": 3})")),
              "flocking-test.json: $.flocks[0].flocking.separation_distance: expected at most search_radius (2 m), got 3");
    EXPECT_EQ(parse_error(scene_text(10, 1.0, R"({"predators": [{"from": [0, 1, 2], "to": [0, 1, 2]}]})")),
              "flocking-test.json: $.flocks[0].flocking.predators[0]: expected \"from\" and \"to\" apart, got the same point");
    EXPECT_EQ(parse_error(scene_text(10, 1.0, R"({"speed_time": -1})")),
              "flocking-test.json: $.flocks[0].flocking.speed_time: expected a finite number in (0, 60], got -1");
    EXPECT_EQ(parse_error(scene_text(10, 1.0, R"({"cohesion": "strong"})")),
              "flocking-test.json: $.flocks[0].flocking.cohesion: expected a finite number in [0, 1000], got \"strong\"");
    EXPECT_EQ(parse_error(scene_text(10, 1.0, R"({"collision_distance": -0.1})")),
              "flocking-test.json: $.flocks[0].flocking.collision_distance: expected a finite number in [0, 100], got -0.1");
    EXPECT_EQ(parse_error(scene_text(10, 1.0, R"({"collision_lookahead": 11})")),
              "flocking-test.json: $.flocks[0].flocking.collision_lookahead: expected a finite number in [0, 10], got 11");
    EXPECT_EQ(parse_error(scene_text(10, 1.0, R"({"alignement": 1})")).substr(0, 64),
              "flocking-test.json: $.flocks[0].flocking.alignement: unknown key");
    // The scene's obstacles and attractors.
    const auto obstacle = [](const std::string& o) { return parse_error(scene_text(10, 1.0, R"({"obstacles": [)" + o + "]}")); };
    EXPECT_EQ(obstacle(R"({"type": "cube", "center": [0, 0, 0], "radius": 1})"),
              "flocking-test.json: $.flocks[0].flocking.obstacles[0].type: expected one of \"sphere\", \"capsule\", \"plane\", got \"cube\"");
    EXPECT_EQ(obstacle(R"({"type": "sphere", "center": [0, 0, 0], "radius": 0})"),
              "flocking-test.json: $.flocks[0].flocking.obstacles[0].radius: expected a finite number in (0, 10000], got 0");
    EXPECT_EQ(obstacle(R"({"type": "capsule", "a": [0, 0, 0], "radius": 1})"),
              "flocking-test.json: $.flocks[0].flocking.obstacles[0].b: expected an array of 3 numbers [x, y, z], each a finite "
              "number in [-1000000, 1000000], got nothing (required key missing)");
    EXPECT_EQ(obstacle(R"({"type": "plane", "normal": [0, 0, 0]})").substr(0, 71),
              "flocking-test.json: $.flocks[0].flocking.obstacles[0].normal: expected ");
    EXPECT_EQ(obstacle(R"({"type": "sphere", "radius": 1, "margin": 0})"),
              "flocking-test.json: $.flocks[0].flocking.obstacles[0].margin: expected a finite number in (0, 1000], got 0");
    EXPECT_EQ(obstacle(R"({"type": "plane", "normal": [0, 1, 0], "radius": 2})").substr(0, 73),
              "flocking-test.json: $.flocks[0].flocking.obstacles[0].radius: unknown key");
    EXPECT_EQ(parse_error(scene_text(10, 1.0, R"({"attractors": [{"position": [0, 1e9, 0]}]})")),
              "flocking-test.json: $.flocks[0].flocking.attractors[0].position[1]: expected a finite number in [-1000000, 1000000], "
              "got 1000000000");
    EXPECT_EQ(parse_error(scene_text(10, 1.0, R"({"attractors": [{"position": [0, 1, 0], "weight": -1}]})")),
              "flocking-test.json: $.flocks[0].flocking.attractors[0].weight: expected a finite number in [0, 1000], got -1");
    // A segment's mode on a flocking flock: its birds' modes are their own flight's, so a
    // forced glide or hover would be silently ignored; a take-off and a landing are its
    // perches (first and last segment only, as on any route).
    const auto with_modes = [](const std::string& modes) {
        return parse_error(R"({"format": "kodawari-scene", "version": 1, "name": "t", "fps": 30, "duration": 1,
            "flocks": [{"name": "f", "wing_type": "pigeon", "count": 10, "flocking": {},
                        "route": {"points": [[0,10,0],[0,10,10],[0,12,20],[0,12,30],[0,12,40],[0,12,50],[0,12,60]],
                                  "modes": )" + modes + "}}]}");
    };
    EXPECT_EQ(with_modes(R"(["glide", "auto"])"),
              "flocking-test.json: $.flocks[0].route.modes[0]: \"glide\" is not flown by a flocking flock (its birds choose "
              "their modes from their own flight): expected \"auto\", or \"takeoff\" and \"landing\" for its perches");
    EXPECT_NE(with_modes(R"(["auto", "hover"])").find("$.flocks[0].route.modes[1]: \"hover\" is not flown"), std::string::npos);
    EXPECT_EQ(with_modes(R"(["auto", "auto"])"), "(parsed)");
    EXPECT_EQ(with_modes(R"(["takeoff", "landing"])"), "(parsed)");
}

// A bird backend given a world with driven birds and no motion says so.
TEST(Flocking, DrivenBirdsWithoutMotionAreAnError) {
    auto scene = parse_scene(scene_text(10, 1.0, "{}"), "flocking-test.json");
    ASSERT_TRUE(scene.ok());
    auto world = build_bird_world(scene.value());
    ASSERT_TRUE(world.ok());
    world.value().frames = 60;
    for (const BackendKind kind : {BackendKind::CpuReference, BackendKind::Cpu}) {
        auto backend = make_cpu_bird_backend(kind, {});
        ASSERT_TRUE(backend.ok());
        ASSERT_TRUE(backend.value()->load(world.value()).ok());
        const auto result = backend.value()->simulate(2, {});
        ASSERT_FALSE(result.ok());
        EXPECT_EQ(result.error().message, "10 birds are flown by another domain: drive() must give 20 motions for 2 frames, got 0");
    }
}

}  // namespace
