#pragma once
/// @file
/// Scenes: the JSON format of docs/scene-format.md (birds, and from version 2 hair-rigged
/// characters), its loader with errors that name the file and the JSON path, and the
/// step from a scene to the data the bird backends run (rod_scene.hpp does the same for
/// the characters).

#include <array>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "kodawari/core/api.hpp"
#include "kodawari/birds/bird_model.hpp"
#include "kodawari/birds/world.hpp"
#include "kodawari/rods/lod.hpp"
#include "kodawari/animation/character.hpp"
#include "kodawari/core/result.hpp"
#include "kodawari/rods/keyed.hpp"
#include "kodawari/rods/limits.hpp"
#include "kodawari/rods/kinematics.hpp"
#include "kodawari/rods/rod_scene.hpp"
#include "kodawari/rods/shape.hpp"
#include "kodawari/rods/solver.hpp"
#include "kodawari/rods/view.hpp"

namespace kodawari {

/// The camera: fixed at `position` looking at `target`, or moving (`motion`, from
/// version 2: orbit, path or keyframes). The birds ignore it; for characters it decides
/// the view direction of every chain (SPEC A.3).
struct CameraSpec {
    std::array<float, 3> position = {0.0f, 30.0f, -120.0f};
    std::array<float, 3> target = {0.0f, 30.0f, 0.0f};
    float fov_deg = 50.0f;
    /// How the camera moves; this is what build_rod_scene uses. For a fixed camera the
    /// loader copies `position` and `target` above into motion.position and
    /// motion.target (set both when building a Scene by hand). A path is stored as
    /// keyframes that all look at the path's target.
    rods::CameraMotion motion;
};

/// A leader route made from a seed: `segments` Bezier segments through random
/// waypoints inside a box around `center`, C1-continuous.
struct GeneratedRouteSpec {
    std::uint64_t seed = 1;
    std::uint32_t segments = 6;
    std::array<float, 3> center = {0.0f, 40.0f, 0.0f};
    std::array<float, 3> extent = {150.0f, 30.0f, 150.0f};  ///< half sizes of the box (m)
    bool loop = true;
};

/// How the birds of a flock spread around the leader route.
struct FormationSpec {
    /// The region the offsets are uniform in: the box of half sizes `spread`, or the
    /// ellipsoid of those semi-axes (a flocking flock's outline follows its offsets).
    enum class Shape : std::uint8_t { Box, Ellipsoid };
    std::array<float, 3> spread = {4.0f, 2.0f, 4.0f};  ///< half sizes of the offset box (m)
    Shape shape = Shape::Box;
    std::uint32_t route_variants = 1;  ///< distinct jittered copies of the leader route
    float jitter = 0.0f;               ///< max displacement of the variants' junction points (m)
    float trail = 0.0f;                ///< time offsets spread over [0, trail] seconds
};

/// A predator passing through a flocking flock: from `from` to `to` at `speed`, starting
/// at `start` s and again every `every` s (0: once); or, with `flock`, the first bird of
/// that (route) flock from `start` on, drawn and baked as the bird it is. Birds within
/// `radius` flee it.
struct PredatorSpec {
    std::string flock;  ///< a flock without flocking, or empty: from and to
    glm::vec3 from{0.0f}, to{0.0f};
    float start = 0.0f;    ///< s
    float every = 0.0f;    ///< s, 0: one pass
    float speed = 20.0f;   ///< m/s
    float radius = 15.0f;  ///< m
    float weight = 40.0f;  ///< m/s^2 at its position, falling linearly to 0 at radius
};

/// An obstacle flocking birds keep clear of (docs/scene-format.md, `flocking.obstacles`):
/// a sphere, a capsule or a plane in world space, as the chains' colliders, with a
/// margin within which birds are steered away.
struct FlockObstacleSpec {
    enum class Type : std::uint8_t { Sphere, Capsule, Plane };
    Type type = Type::Sphere;
    glm::vec3 a{0.0f};  ///< a sphere's centre, a capsule's first end, a point of a plane (m)
    glm::vec3 b{0.0f};  ///< a capsule's second end (a sphere's: a); a plane's unit normal
    float radius = 1.0f;   ///< m, spheres and capsules
    float margin = 2.0f;   ///< m: birds within it of the surface are pushed out
    float weight = 40.0f;  ///< m/s^2 at the surface, falling to 0 at the margin
};

/// A place flocking birds are drawn to within `radius` (`flocking.attractors`).
struct FlockAttractorSpec {
    glm::vec3 position{0.0f};
    float radius = 15.0f;  ///< m
    float weight = 40.0f;  ///< m/s^2 at the attractor's place, falling linearly to 0 at radius
};

/// The flocking rules of a flock (docs/flocking.md): its birds fly by their neighbours
/// and are drawn to the flock's route rather than following it. Accelerations in m/s^2.
struct FlockingSpec {
    std::uint32_t neighbours = 7;   ///< k nearest (topological), in [1, 16]
    bool metric = false;            ///< true: every neighbour within search_radius (16 nearest at most)
    float search_radius = 3.0f;     ///< m: neighbours are looked for this far
    float blind_angle_deg = 90.0f;  ///< behind the bird, unseen
    float separation_distance = 0.6f;  ///< m: full separation within, Gaussian beyond
    float separation = 6.0f;
    /// The separation distance along the flight direction is (1 + this) x as long as to
    /// the side: a bird keeps a longer gap to the bird ahead or behind.
    float separation_front = 1.0f;
    /// m: a neighbour that will be nearer than this within collision_lookahead (at the two
    /// birds' present velocities) is steered from before anything else, at up to the
    /// wing's lateral limit at contact (Reynolds 1987's collision avoidance, predicted as
    /// Reynolds 1999's unaligned collision avoidance); 0: off.
    float collision_distance = 0.3f;
    float collision_lookahead = 0.25f;  ///< s, in [0, 10]
    float alignment = 2.0f;
    float cohesion = 2.0f;
    float route = 10.0f;          ///< drawn to the route's leader plus the bird's formation offset
    float route_radius = 20.0f;   ///< m: within it the draw falls in proportion to the distance
    float ground_clearance = 3.0f;  ///< m
    float ground = 10.0f;
    float speed_time = 1.0f;      ///< s: the time constant of the cruise-speed control
    std::vector<PredatorSpec> predators;
    /// Every flocking bird of the scene keeps clear of them and is drawn to them, as it
    /// flees every predator (the flocks share one sky).
    std::vector<FlockObstacleSpec> obstacles;
    std::vector<FlockAttractorSpec> attractors;
};

/// One flock: `count` birds of a wing type following a route.
struct FlockSpec {
    std::string name;
    birds::WingType wing_type = birds::WingType::Pigeon;
    /// A user's bird instead of a wing type (`"model"`, docs/bird-models.md): loaded with
    /// the scene, its bones mapped (by `"map"` when given); null for a built-in type.
    std::shared_ptr<const birds::BirdModel> model;
    std::string model_file;  ///< `"model"` as written in the scene
    std::string map_file;    ///< `"map"` as written (may be empty)
    std::uint32_t count = 1;
    std::uint64_t seed = 1;
    std::optional<float> speed;      ///< m/s; default: the wing type's cruise speed
    float speed_jitter = 0.0f;       ///< relative, uniform in [-j, j]
    std::optional<float> frequency;  ///< Hz; default: the wing type's
    float frequency_jitter = 0.0f;   ///< relative
    std::optional<float> amplitude;  ///< default: the wing type's
    float amplitude_jitter = 0.0f;   ///< relative
    float phase_jitter = 1.0f;       ///< initial phase uniform in [0, phase_jitter) cycles
    std::optional<birds::RouteSpec> route;            ///< explicit control points, or
    std::optional<GeneratedRouteSpec> generated_route;  ///< one made from a seed
    birds::RouteTiming timing = birds::RouteTiming::ArcLength;
    FormationSpec formation;
    /// Flies by the flocking rules (a flocking domain) instead of its route; none: the
    /// route, exactly as without the key.
    std::optional<FlockingSpec> flocking;
};

/// One kinematic collider of a character, in its joint's frame (a sphere is a capsule
/// with a == b; a plane has a on it and b its unit normal; rods::Collider).
struct ColliderSpec {
    std::string name;         ///< for chains' `colliders` lists; may be empty
    std::uint32_t joint = 0;  ///< index into CharacterSpec::skeleton.joints
    glm::vec3 a{0.0f}, b{0.0f};
    float radius = 0.0f;  ///< m, > 0 (0 for a plane)
    rods::ColliderKind kind = rods::ColliderKind::Outside;
};

/// One view example of a chain (SPEC A.1): direction and influence, and its shape.
struct ViewSpec {
    std::string name;        ///< for people ("front"); may be empty
    rods::ViewExample view;  ///< direction unit, in the reference joint's frame
    rods::ChainShape shape;  ///< chain root frame, the base shape's joint count
};

/// One keyed example of a chain (docs/keyed-examples.md K.1): its key, influence and
/// smoothing (its sources index ChainSpec::key_sources), and its shape.
struct KeyedSpec {
    std::string name;              ///< for people ("sprint"); may be empty
    rods::KeyedExample example;
    rods::ChainShape shape;        ///< chain root frame, the base shape's joint count
};

/// One joint chain of a character (SPEC A.1), after mirroring: a mirrored pair is two
/// ChainSpecs.
struct ChainSpec {
    std::string name;
    std::uint32_t joint = 0;  ///< the skeleton joint the chain root is attached to
    rods::Transform offset;   ///< the chain root's frame in that joint's frame
    rods::ChainShape base;    ///< the base shape C_0 in the chain root's frame
    std::vector<ViewSpec> views;
    std::vector<rods::KeyJoint> key_sources;  ///< the joints its keyed examples read
    std::vector<KeyedSpec> keyed;             ///< keyed examples (docs/keyed-examples.md)
    /// Angle limits, one per segment (joint i to i+1), or none (rods::set_limits).
    std::vector<rods::AngleLimit> limits;
    float thickness = 0.005f;  ///< m
    float mass = 0.002f;       ///< kg per joint
    rods::SolverParams params;
    bool collide = true;  ///< false: against none of its character's colliders
    /// The colliders it collides with, indices into CharacterSpec::colliders in the
    /// scene's order (VRM's per-spring collider groups); empty with `all_colliders`.
    std::vector<std::uint32_t> colliders;
    bool all_colliders = true;  ///< no `colliders` list: all of its character's
    /// The joint (a rigged character's node) whose space its inertia is measured in
    /// (`center`, rods::follow_center), -1 for the world.
    std::int32_t center = -1;
    std::string path;     ///< its JSON path (for messages from the builder)
    /// A rigged (glTF) character's chain: its joints' node indices, root first. Then
    /// `joint` is nodes[0], `offset` the identity, and the chain root's frame is the
    /// root node's animated world transform with its scale removed (animation::rigid_part).
    std::vector<int> nodes;
};

/// Where a rigged character comes from (issue 4, SPEC A.7): a glTF 2.0 / VRM file whose
/// node hierarchy and animation clips pose the character.
struct RigSpec {
    std::string file;      ///< as written in the scene
    std::string resolved;  ///< the path it was loaded from (relative to the scene file's folder)
    std::shared_ptr<const animation::Character> character;
    /// The clip instances play unless their crowd says otherwise: an index into
    /// character->animations, or -1 for the rest pose.
    std::int32_t clip = -1;
    /// What the character's `motions` could not use (gltf/motion.hpp), each naming the
    /// scene, the motion's JSON path, and the file and JSON path of the problem.
    std::vector<std::string> warnings;
    /// The files its motions read (their clips and maps), as resolved.
    std::vector<std::string> motion_files;
};

/// A character template: skeleton, motions, colliders and chains (SPEC A.1). A rigged
/// character (`rig` set) has no skeleton joints or motions: its joints are the glTF
/// file's nodes (joint index = node index, in colliders, chains and
/// skeleton.reference) and its animation clips move them.
struct CharacterSpec {
    std::string name;
    rods::Skeleton skeleton;  ///< parents first; skeleton.reference is the reference joint
    rods::CharacterMotion motion;
    std::optional<RigSpec> rig;
    std::vector<ColliderSpec> colliders;
    std::vector<ChainSpec> chains;
    /// Its own wind field (the scene's values where its `wind` is silent); none: the
    /// scene's.
    std::optional<rods::WindField> wind;
    std::string path;
};

/// How a crowd lays out its generated instances.
enum class CrowdLayout { Grid, Ring };

/// One explicitly placed character instance.
struct InstanceSpec {
    glm::vec3 position{0.0f};
    float yaw = 0.0f;          ///< rad about +Y; 0 faces +Z
    float time_offset = 0.0f;  ///< s, added to the scene time for this instance's motions
    /// Rigged characters: the clip it plays (index, -1 = rest pose); none: the crowd's
    /// or the character's.
    std::optional<std::int32_t> clip;
};

/// `count` instances of a character on a grid or a ring, plus explicit instances
/// (SPEC C: each with its own transform and time offset).
struct CrowdSpec {
    std::string name;
    std::uint32_t character = 0;  ///< index into Scene::characters
    std::uint32_t count = 0;      ///< generated instances
    CrowdLayout layout = CrowdLayout::Grid;
    float spacing = 1.5f;              ///< m between neighbours
    std::uint32_t columns = 0;         ///< grid; 0 = ceil(sqrt(count))
    std::optional<float> radius;       ///< ring, m; default: spacing * count / (2 pi), at least spacing
    glm::vec3 center{0.0f};
    float yaw = 0.0f;                  ///< rad; on a ring, added to facing outwards
    float yaw_jitter = 0.0f;           ///< rad, uniform in [-j, j)
    float position_jitter = 0.0f;      ///< m, x and z uniform in [-j, j)
    float time_offset = 0.0f;          ///< s, per instance uniform in [0, time_offset)
    std::uint64_t seed = 1;
    /// Rigged characters: clips (indices) the generated instances pick from, uniformly
    /// at random (a stream of its own); empty: the character's clip.
    std::vector<std::int32_t> clips;
    std::vector<InstanceSpec> instances;  ///< after the generated ones
};

/// A whole scene file.
/// A file a scene read besides itself.
struct SceneInput {
    std::string path;  ///< as resolved (relative to the scene file's folder unless absolute)
    std::string what;  ///< for messages: "the model of character \"chibi\"", "a motion of ...", "the map of flock 0"
};

struct KODAWARI_API Scene {
    std::string path;  ///< where it was loaded from (for messages)
    /// Every other file the scene read (characters' and birds' models, motions, maps):
    /// what a bake must not write over (`kodawari run` refuses to). A .gltf model's
    /// external buffers and images are not listed.
    std::vector<SceneInput> inputs;
    std::string name;
    std::uint32_t version = 1;  ///< 1: birds only; 2: characters, crowds and camera motion too
    float fps = 60.0f;
    float duration = 10.0f;  ///< seconds
    CameraSpec camera;
    birds::FlightSettings flight;
    std::vector<FlockSpec> flocks;
    std::vector<CharacterSpec> characters;
    /// Instances of the characters. When the file has no `crowds`, the loader puts one
    /// instance of every character at the origin here.
    std::vector<CrowdSpec> crowds;
    /// The wind the characters' chains feel (rods::WindField); none: calm air, until an
    /// application sets one (set_wind, kodawari/domains/chains.hpp).
    std::optional<rods::WindField> wind;
    /// Levels of detail of the characters' chains (rods::LodSettings,
    /// docs/level-of-detail.md): off unless the file's `lod` object turns them on (or an
    /// application does, here, before Simulation::create). The vertical field of view is
    /// the camera's (build_rod_scene sets it).
    rods::LodSettings lod;

    /// Number of frames: round(duration * fps), at least 1.
    [[nodiscard]] std::uint32_t frame_count() const;
    /// What `file` is to the scene when it is the scene file ("the scene file") or one of
    /// `inputs` (same_file(); the input's `what`); empty when the scene does not read it.
    /// What a bake must not write over.
    [[nodiscard]] std::string reads(const std::string& file) const;
};

/// Why `name` cannot be a scene's `name`, or "" when it can: it names the scene's output
/// files (out/<name>.glb, <name>_00000.png), so it must be one file name: not empty, "."
/// or "..", without '/', '\\' or control characters.
[[nodiscard]] KODAWARI_API std::string scene_name_problem(const std::string& name);

/// `name` made a scene name by scene_name_problem()'s rule: '/', '\\' and control
/// characters become '_'; "", "." and ".." become `fallback`.
[[nodiscard]] KODAWARI_API std::string as_scene_name(std::string name, const std::string& fallback);

/// Reads and checks a scene file. Errors name the file, the JSON path and what was
/// expected (Error::Kind::InvalidInput), or the I/O failure.
[[nodiscard]] KODAWARI_API Result<Scene> load_scene(const std::string& path);

/// Parses scene text; `path` is only used in messages.
[[nodiscard]] KODAWARI_API Result<Scene> parse_scene(const std::string& text, const std::string& path);

/// Builds the backends' data: routes, arc-length tables and every bird's constants.
/// Deterministic: the same scene gives the same bits.
[[nodiscard]] KODAWARI_API Result<birds::BirdWorld> build_bird_world(const Scene& scene);

/// Builds the rod data of `scene`'s characters and crowds (SPEC A, C): the RodScene of
/// kodawari/rods/rod_scene.hpp. Deterministic: the same scene gives the same bits (on the
/// same build and platform: the motions use the C library's sin and cos). A scene without
/// characters gives an empty RodScene (no chains). Errors (InvalidInput) name the file and
/// the JSON path.
[[nodiscard]] KODAWARI_API Result<RodScene> build_rod_scene(const Scene& scene);

}  // namespace kodawari
