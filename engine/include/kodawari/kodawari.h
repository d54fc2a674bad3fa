/* Kodawari's C API (issue 11, section 3): the chain worlds (SPEC A) and bird worlds
 * (SPEC B) from plain arrays, for C programs and for every language and engine that binds
 * C (Python's ctypes, a Unity native plug-in, a Godot GDExtension, a Blender add-on).
 * C99; no C++ in this header. Link libkodawari.so (CMake: kodawari::c). */
#ifndef KODAWARI_KODAWARI_H
#define KODAWARI_KODAWARI_H

/// @file
/// The C API of Kodawari.
///
/// **Status codes.** Every call that can fail returns a kodawari_status; KODAWARI_OK is 0.
/// The few calls that cannot fail return their value directly: the version queries,
/// kodawari_status_name(), the message getters and the destroy functions.
///
/// **Messages.** A failed call also leaves a message for a person that names the function,
/// the argument (down to the field and index) and what was expected, e.g.
/// `kodawari_chain_world_create: desc->templates[0].base.positions[3]: 2e-07 m from joint 2;
/// segments must be at least 1e-06 m long`. Two places hold it:
/// - kodawari_last_error(): the message of this thread's most recent call (any call listed
///   with a status); "" when that call succeeded. This is where a failed create, or a call
///   given a NULL handle, reports.
/// - kodawari_chain_world_last_error() / kodawari_bird_world_last_error(): the message of
///   the most recent call on that handle; "" when it succeeded. A handle used from worker
///   threads keeps its own message for whoever looks later.
/// The returned strings are owned by the library and stay valid until the next call on the
/// same thread (kodawari_last_error) or on the same handle (the per-handle getters).
///
/// **Bad input.** Every entry point checks all its arguments before it changes anything:
/// NULL handles and pointers, counts that do not match, NaN or infinite values, values out
/// of the documented ranges, zero-length segments, zero view directions, non-unit
/// quaternions, buffers smaller than the result. A call rejected with
/// KODAWARI_INVALID_ARGUMENT or KODAWARI_BUFFER_TOO_SMALL leaves the handle exactly as it
/// was (the next step gives the same bits as if the call had never been made) and writes
/// nothing to the caller's buffers. No C++ exception and no abort crosses this boundary:
/// an internal failure comes back as KODAWARI_INTERNAL or KODAWARI_OUT_OF_MEMORY. After
/// KODAWARI_DEVICE_ERROR from a step or simulate, the handle's state is unspecified (the
/// device may have run part of the work): destroy it.
///
/// **Threading.**
/// - A handle is not synchronized inside: calls on one handle (its last_error getter and
///   destroy included) must not overlap. It may move between threads between calls.
/// - Different handles may be used concurrently from different threads; each owns its
///   backend (and, for vulkan, its own Vulkan device).
/// - kodawari_version*(), kodawari_status_name(), kodawari_last_error() (which reads the
///   calling thread's message), the *_default() functions and
///   kodawari_camera_from_view_matrix() are thread-safe.
/// - The cpu backend runs a step on several threads of its own; calls return only when the
///   work is done (the vulkan backend waits for its device).
///
/// **Lifetimes.** Descriptions and frames are read during the call only: every array they
/// point to may be freed as soon as the call returns.
///
/// **Conventions.** Metres, seconds, radians, kilograms. Vectors are float[3] (x, y, z);
/// quaternions are float[4] (x, y, z, w), unit length (within 1e-3). World space has +Y
/// up. Booleans are uint32_t 0 or 1 (anything else is rejected, which catches structs
/// left uninitialized). Zero-initialized kodawari_backend_options mean "auto, the best
/// device, no validation, as many cpu threads as the hardware has".

#include <stddef.h>
#include <stdint.h>

#if defined(_WIN32)
#if defined(KODAWARI_C_BUILDING)
#define KODAWARI_C_API __declspec(dllexport)
#else
#define KODAWARI_C_API __declspec(dllimport)
#endif
#elif defined(KODAWARI_C_BUILDING)
/// Marks the library's exported functions: the library is compiled with hidden
/// visibility, so these are the only symbols libkodawari.so exports.
#define KODAWARI_C_API __attribute__((visibility("default")))
#else
#define KODAWARI_C_API
#endif

#ifdef __cplusplus
extern "C" {
#endif

/* ------------------------------------------------------------------------------------ */
/* Version                                                                              */
/* ------------------------------------------------------------------------------------ */

/// The library's version, "MAJOR.MINOR.PATCH" (CMake's project version, the one place it
/// is set). A static string.
KODAWARI_C_API const char* kodawari_version(void);
/// The library's major version; a change of it breaks this API. While it is 0, a change
/// of the minor version may break the API and the ABI too, and the SONAME is
/// libkodawari.so.MAJOR.MINOR (libkodawari.so.0.3): a program runs only against the
/// minor version it was built for.
KODAWARI_C_API int kodawari_version_major(void);
/// The library's minor version.
KODAWARI_C_API int kodawari_version_minor(void);
/// The library's patch version.
KODAWARI_C_API int kodawari_version_patch(void);

/* ------------------------------------------------------------------------------------ */
/* Status codes and messages                                                            */
/* ------------------------------------------------------------------------------------ */

/// What a call returns.
typedef enum kodawari_status {
    /// It worked.
    KODAWARI_OK = 0,
    /// An argument is wrong: a NULL handle or pointer, a count that does not match, a value
    /// that is NaN, infinite or out of its range. Nothing changed.
    KODAWARI_INVALID_ARGUMENT = 1,
    /// A caller's buffer is smaller than the result (the message says how many floats it
    /// needs). Nothing changed and nothing was written.
    KODAWARI_BUFFER_TOO_SMALL = 2,
    /// What was asked for does not exist on this machine: the vulkan backend without a
    /// Vulkan loader, driver or device (the message says why each device was passed over),
    /// or a world larger than the device can hold.
    KODAWARI_UNAVAILABLE = 3,
    /// A Vulkan call failed (device lost, ...).
    KODAWARI_DEVICE_ERROR = 4,
    /// Host or device memory ran out.
    KODAWARI_OUT_OF_MEMORY = 5,
    /// A bug in Kodawari: the message says what; please report it.
    KODAWARI_INTERNAL = 6,
    /// Keeps the enum 32-bit wide on every compiler; never returned.
    KODAWARI_STATUS_MAX_ENUM = 0x7FFFFFFF
} kodawari_status;

/// The status' name ("KODAWARI_INVALID_ARGUMENT"); "unknown kodawari_status" for a value
/// not listed above. A static string.
KODAWARI_C_API const char* kodawari_status_name(kodawari_status status);

/// The message of this thread's most recent call that returns a status: "" when it
/// succeeded. Valid until this thread's next call into the library. Never NULL.
KODAWARI_C_API const char* kodawari_last_error(void);

/* ------------------------------------------------------------------------------------ */
/* Backends                                                                             */
/* ------------------------------------------------------------------------------------ */

/// Which implementation simulates a world. All agree within the tolerances the project's
/// tests state; cpu-reference and cpu give the same bits.
typedef enum kodawari_backend {
    /// vulkan when a GPU opens and can hold the world (a buffer within its
    /// maxStorageBufferRange), else cpu (the world's info says why). A CPU-type Vulkan
    /// device (Mesa's lavapipe) gives cpu too, which is several times faster there,
    /// unless `device` names it.
    KODAWARI_BACKEND_AUTO = 0,
    /// Scalar, one thread: the validation oracle.
    KODAWARI_BACKEND_CPU_REFERENCE = 1,
    /// The reference's code on several threads.
    KODAWARI_BACKEND_CPU = 2,
    /// Compute shaders on a Vulkan device (Mesa's lavapipe where there is no GPU).
    KODAWARI_BACKEND_VULKAN = 3,
    KODAWARI_BACKEND_MAX_ENUM = 0x7FFFFFFF
} kodawari_backend;

/// How a world's backend is made. All zeros: auto, the best device, no validation, one
/// cpu thread per hardware thread.
typedef struct kodawari_backend_options {
    kodawari_backend backend;
    /// vulkan: a device index ("0") or a substring of its name ("llvmpipe"); NULL or "" =
    /// the best (discrete > integrated > virtual > cpu). One that matches no device is
    /// KODAWARI_INVALID_ARGUMENT, with AUTO too (AUTO never falls back from a device asked for).
    const char* device;
    /// vulkan: 1 = Khronos validation with synchronization validation (the count of
    /// messages is in the world's info); 0 = off.
    uint32_t validation;
    /// cpu: worker threads, 0 = one per hardware thread; at most 1024.
    uint32_t threads;
    /// vulkan: the application's own device (kodawari_vulkan_device_adopt); NULL = a device
    /// of the world's own. When set, `backend` must be AUTO or VULKAN (and means VULKAN),
    /// and `device` and `validation` are the application's business (0 / NULL).
    struct kodawari_vulkan_device* vulkan_device;
    /// cpu: the SIMD instruction set, "avx512", "avx2", "sse4" or "scalar"; NULL or "" =
    /// the widest this machine runs. One this machine cannot run is INVALID_ARGUMENT.
    const char* isa;
    /// vulkan: invocations per workgroup of the kernels that run one chain, bird or
    /// character each, a power of two from 32 to 1024 that the device allows; 0 = 64. The
    /// results are the same at every size (it is a speed variant to time on a GPU). Another
    /// value, or one with a CPU backend, is INVALID_ARGUMENT.
    uint32_t workgroup_size;
} kodawari_backend_options;

/* ------------------------------------------------------------------------------------ */
/* Common types                                                                         */
/* ------------------------------------------------------------------------------------ */

/// A rigid transform: world = position + rotation * local.
typedef struct kodawari_transform {
    float position[3];  ///< m, |each| <= 1e6
    float rotation[4];  ///< unit quaternion (x, y, z, w)
} kodawari_transform;

/// A capsule (a segment swept by a sphere); a sphere is a capsule with a == b.
typedef struct kodawari_capsule {
    float a[3];    ///< m
    float b[3];    ///< m
    float radius;  ///< m, 0 .. 1e6
} kodawari_capsule;

/// The camera that decides the view direction of every chain (SPEC A.3).
typedef struct kodawari_camera {
    /// 0: perspective, the view direction points from the reference joint to `position`.
    /// 1: orthographic, the view direction is -forward.
    uint32_t orthographic;
    float position[3];  ///< m, |each| <= 1e6
    /// Where the camera looks; non-zero (length >= 1e-6), normalized by the library. Needed
    /// by a perspective camera too: sitting on a reference joint (closer than 1e-6 m) it
    /// has no direction from it, and the orthographic rule is used there.
    float forward[3];
} kodawari_camera;

/// A camera from a view matrix (world to camera; column-major, OpenGL and glm's layout:
/// element (row r, column c) at view[c * 4 + r]; the camera looks down its -Z). The
/// rotation part must be orthonormal within 1e-3 and the last row (0, 0, 0, 1).
KODAWARI_C_API kodawari_status kodawari_camera_from_view_matrix(const float view[16], uint32_t orthographic,
                                                                kodawari_camera* out);

/* ------------------------------------------------------------------------------------ */
/* Chain worlds (SPEC A: view-dependent rods)                                           */
/* ------------------------------------------------------------------------------------ */

/// The most joints one chain may have.
#define KODAWARI_MAX_CHAIN_JOINTS 32
/// The most view examples one chain template may have.
#define KODAWARI_MAX_VIEW_EXAMPLES 7
/// The most colliders one chain may touch.
#define KODAWARI_MAX_CHAIN_COLLIDERS 16
/// Weights read per chain: w_0 (the base shape's), w_1 .. w_m, then zeros.
#define KODAWARI_WEIGHTS_PER_CHAIN (KODAWARI_MAX_VIEW_EXAMPLES + 1)

/// A chain shape C = (X, O) in the chain root's frame (SPEC A.1), joint 0 first. The joint
/// count is the template's.
typedef struct kodawari_chain_shape {
    /// joint_count x 3 floats: joint positions, m, |each| <= 100. Joint 0 is (0, 0, 0) (it
    /// sits on the chain root: move the chain with its root transform); consecutive joints
    /// at least 1e-6 m apart.
    const float* positions;
    /// joint_count x 4 floats: joint orientations, unit quaternions; or NULL: each joint's
    /// local +Y along its segment (the last joint's along the last segment), by the
    /// shortest arc from +Y, as the scene files' default.
    const float* orientations;
} kodawari_chain_shape;

/// A view example (SPEC A.1, A.3): from near `direction`, the rest shape leans to `shape`.
typedef struct kodawari_view_example {
    /// d_k, in the reference joint's frame; non-zero (length >= 1e-6), normalized by the
    /// library.
    float direction[3];
    /// p_k in (0, 1000]: small reaches far from `direction`, large stays local.
    float influence;
    /// Its shape; segment lengths are the base's whatever these positions say (only the
    /// directions of the segments count, SPEC A.2).
    kodawari_chain_shape shape;
} kodawari_view_example;

/// The solver's settings (SPEC A.4, A.5). kodawari_solver_params_default() gives the
/// engine's defaults.
typedef struct kodawari_solver_params {
    /// Longest substep, s, in [1e-4, 0.05]: a frame of dt runs ceil(dt / max_substep)
    /// substeps. Default 1/120.
    float max_substep;
    /// Projection iterations per substep, 1 .. 64. Default 4.
    uint32_t iterations;
    /// Shape-matching stiffness in [0, 1] per 1/120 s (other substeps take the same
    /// compliance: rods::substep_stiffness). Default 0.5.
    float stiffness;
    /// Attraction to the rest shape in [0, 1] per 1/120 s, converted like stiffness; holds
    /// the shape against gravity.
    /// Default 0.1.
    float rest_stiffness;
    /// Velocity damping rate, 1/s, in [0, 1000]. Default 1.
    float damping;
    /// m/s^2, |each| <= 1000. Default (0, -9.81, 0).
    float gravity[3];
    /// An extra acceleration, m/s^2, |each| <= 1000. Default 0.
    float wind[3];
    /// Momentum suppression (SPEC A.5) in [0, 1]: 0 = plain shape matching, 1 = a change of
    /// rest shape injects no velocity. Default 1.
    float momentum_suppression;
    /// 1: a chain starts at rest in equilibrium under gravity, wind and its colliders and
    /// moving with its root; 0: on its rest shape and still (as UniVRM and three-vrm
    /// start). Default 1.
    uint32_t settle_start;
    /// A root that moves farther than this in one frame, m (> 0, finite), has teleported:
    /// its chain is carried with it instead of dragged across the gap. Default 1.
    float teleport_distance;
    /// Drag across each segment, 1/s, in [0, 1000]: on top of `damping`, the part of a
    /// particle's velocity relative to the air (kodawari_wind) across its segment decays
    /// at this rate. Default 0.
    float normal_drag;
    /// Drag along each segment, 1/s, in [0, 1000]. Default 0.
    float tangent_drag;
} kodawari_solver_params;

/// A wind field (docs/models.md "Wind"): the air moves at `velocity` with gusts, smooth
/// noise in horizontal position and time carried along with the wind. Chains feel the
/// air at their root through their damping and drag (kodawari_solver_params).
/// kodawari_wind_default() gives calm air.
typedef struct kodawari_wind {
    /// The mean air velocity, m/s, |each| <= 100. Default 0 (calm).
    float velocity[3];
    /// Gust strength in [0, 4], a fraction of the mean speed. Default 0.
    float gust;
    /// Gust period, s, in [0.05, 1000]. Default 3.
    float gust_period;
    /// Gust size, m, in [0.05, 10000]. Default 6.
    float gust_size;
    /// Noise seed. Default 0.
    uint32_t seed;
} kodawari_wind;

/// Fills `out` with calm air and the default gust scales.
KODAWARI_C_API kodawari_status kodawari_wind_default(kodawari_wind* out);

/// Fills `out` with the engine's default solver settings.
KODAWARI_C_API kodawari_status kodawari_solver_params_default(kodawari_solver_params* out);

/// Which angle limit a joint has (docs/models.md "Angle limits"; VRMC_springBone_limit).
typedef enum kodawari_limit_kind {
    KODAWARI_LIMIT_NONE = 0,
    /// At most `angle` from the limit's axis.
    KODAWARI_LIMIT_CONE = 1,
    /// Turning about the limit frame's X only, at most `angle` from its axis.
    KODAWARI_LIMIT_HINGE = 2,
    /// Pitch (about X) within +-`angle` and yaw (towards X) within +-`yaw`.
    KODAWARI_LIMIT_SPHERICAL = 3
} kodawari_limit_kind;

/// One joint's angle limit: the direction from the joint to its child is kept within it,
/// in the limit's frame (+Y along the joint's rest direction to its child, carried by its
/// parent bone's current turn, then turned by `rotation`).
typedef struct kodawari_angle_limit {
    /// A kodawari_limit_kind.
    uint32_t kind;
    /// Cone and hinge: the angle; spherical: the pitch. rad, in [0, pi].
    float angle;
    /// Spherical: the yaw, rad, in [0, pi/2]; 0 otherwise.
    float yaw;
    /// The limit frame's turn, a unit quaternion [x, y, z, w].
    float rotation[4];
} kodawari_angle_limit;

/// A chain template: what the chains made from it share (their shapes, views, physics).
typedef struct kodawari_chain_template_desc {
    /// Joints of every shape, 2 .. KODAWARI_MAX_CHAIN_JOINTS.
    uint32_t joint_count;
    /// The base shape C_0 (the bind pose); its segment lengths are the chain's.
    kodawari_chain_shape base;
    /// view_count view examples, or NULL with view_count 0 (the base shape from every side).
    const kodawari_view_example* views;
    /// 0 .. KODAWARI_MAX_VIEW_EXAMPLES.
    uint32_t view_count;
    /// Particle thickness, m, in [1e-5, 1]: ellipsoid radii across the segment and the
    /// collision radius.
    float thickness;
    /// Mass of every particle, kg, in [1e-9, 1000].
    float mass;
    kodawari_solver_params solver;
    /// limit_count angle limits, one per segment (joint i to i+1: limit_count =
    /// joint_count - 1), or NULL with limit_count 0 (no limits).
    const kodawari_angle_limit* limits;
    uint32_t limit_count;
} kodawari_chain_template_desc;

/// One simulated chain: a template on one character.
typedef struct kodawari_chain_desc {
    /// Index into kodawari_chain_world_desc::templates.
    uint32_t template_index;
    /// The character whose reference joint gives this chain's view direction: index into
    /// every frame's `references`.
    uint32_t character;
    /// The colliders it touches: [collider_begin, collider_begin + collider_count) of the
    /// world's colliders; at most KODAWARI_MAX_CHAIN_COLLIDERS.
    uint32_t collider_begin;
    uint32_t collider_count;
} kodawari_chain_desc;

/// A collider attached to a character's reference joint, so that a frame need not give
/// it: its world capsule is reference.position + reference.rotation * (a, b).
typedef struct kodawari_collider_desc {
    /// The character whose reference joint carries it.
    uint32_t character;
    /// In the reference joint's frame; |each coordinate| <= 1000 m, radius in [0, 1000].
    kodawari_capsule local;
} kodawari_collider_desc;

/// Everything a chain world is made of.
typedef struct kodawari_chain_world_desc {
    const kodawari_chain_template_desc* templates;
    uint32_t template_count;  ///< >= 1
    const kodawari_chain_desc* chains;
    uint32_t chain_count;  ///< >= 1
    /// Characters: entries of every frame's `references`; >= 1.
    uint32_t character_count;
    /// Colliders: entries of a frame's `colliders` when it gives them.
    uint32_t collider_count;
    /// collider_count attachments, so that frames may leave the colliders out (NULL
    /// colliders); or NULL: every frame must give the colliders in world space.
    const kodawari_collider_desc* colliders;
    kodawari_backend_options backend;
} kodawari_chain_world_desc;

/// One frame's kinematic input, world space, at the end of the frame.
typedef struct kodawari_chain_frame {
    /// Frame length, s, in [1e-5, 1]; ignored by create and reset.
    float dt;
    kodawari_camera camera;
    /// Per character: its reference joint's pose (SPEC A.3), reference_count ==
    /// character_count.
    const kodawari_transform* references;
    uint32_t reference_count;
    /// Per chain: its root's frame (joint 0 follows it exactly), root_count == chain_count.
    const kodawari_transform* roots;
    uint32_t root_count;
    /// The world's colliders in world space (collider_count of them); or NULL with
    /// collider_count 0: placed from the references by the world's collider attachments.
    const kodawari_capsule* colliders;
    uint32_t collider_count;
} kodawari_chain_frame;

/// A chain world and the backend that simulates it (opaque).
typedef struct kodawari_chain_world kodawari_chain_world;

/// Creates a chain world from `desc` and puts every chain at rest on the rest shape that
/// `initial` gives it (its camera and poses; dt is not used). `*out` is set only on
/// success (to NULL otherwise). The message names the first problem found.
KODAWARI_C_API kodawari_status kodawari_chain_world_create(const kodawari_chain_world_desc* desc,
                                                           const kodawari_chain_frame* initial,
                                                           kodawari_chain_world** out);

/// Destroys a world (NULL: nothing happens).
KODAWARI_C_API void kodawari_chain_world_destroy(kodawari_chain_world* world);

/// The message of the most recent call on `world` ("" when it succeeded; "" for NULL).
/// Valid until the next call on `world`.
KODAWARI_C_API const char* kodawari_chain_world_last_error(const kodawari_chain_world* world);

/// Puts every chain at rest again on the rest shape that `frame` gives it (a character
/// teleported, a cut in the film); dt is not used.
KODAWARI_C_API kodawari_status kodawari_chain_world_reset(kodawari_chain_world* world,
                                                          const kodawari_chain_frame* frame);

/// The wind every chain of `world` feels from the next step (or reset) on; NULL: calm
/// air (the default). A field out of range is KODAWARI_INVALID_ARGUMENT naming the member.
KODAWARI_C_API kodawari_status kodawari_chain_world_set_wind(kodawari_chain_world* world, const kodawari_wind* wind);

/// Advances every chain by one frame (SPEC A.3-A.5): the rest shape from the view, then
/// the oriented-particles solver.
KODAWARI_C_API kodawari_status kodawari_chain_world_step(kodawari_chain_world* world,
                                                         const kodawari_chain_frame* frame);

/// Where kodawari_chain_world_read() writes. Per-joint arrays hold every chain's joints in
/// chain order (kodawari_chain_world_chain_joints() says where each chain starts). Every
/// array is optional (NULL: not read); a capacity counts floats.
typedef struct kodawari_chain_output {
    float* positions;  ///< joint_count x 3: world positions
    size_t positions_capacity;
    float* orientations;  ///< joint_count x 4: world orientations of the particles (x, y, z, w)
    size_t orientations_capacity;
    float* rest_positions;  ///< joint_count x 3: the frame's blended rest shape placed by the root
    size_t rest_positions_capacity;
    float* view_directions;  ///< chain_count x 3: d, in the chain's reference joint's frame
    size_t view_directions_capacity;
    float* weights;  ///< chain_count x KODAWARI_WEIGHTS_PER_CHAIN: w_0 .. w_m, then zeros
    size_t weights_capacity;
} kodawari_chain_output;

/// Reads the state after the last step (or create/reset) into the caller's arrays, with one
/// read-back from the device. KODAWARI_BUFFER_TOO_SMALL names the first array that is too
/// small and writes nothing.
KODAWARI_C_API kodawari_status kodawari_chain_world_read(kodawari_chain_world* world,
                                                         const kodawari_chain_output* out);

/// Chain `chain`'s joints in the per-joint arrays: [*joint_begin, *joint_begin +
/// *joint_count). Either pointer may be NULL.
KODAWARI_C_API kodawari_status kodawari_chain_world_chain_joints(kodawari_chain_world* world, uint32_t chain,
                                                                 uint32_t* joint_begin, uint32_t* joint_count);

/// What a chain world is and where it runs.
typedef struct kodawari_chain_world_info {
    uint32_t template_count;
    uint32_t chain_count;
    uint32_t joint_count;  ///< every chain's joints: the per-joint arrays' length
    uint32_t character_count;
    uint32_t collider_count;
    /// The backend running (never AUTO).
    kodawari_backend backend;
    /// Validation messages so far (vulkan with validation on; else 0).
    uint32_t validation_messages;
    /// What it runs on ("llvmpipe (LLVM 15.0.6, 256 bits)", "4 threads"), cut to fit.
    char device[256];
    /// AUTO that fell back to cpu: why vulkan was not used, cut to fit; else "".
    char fallback_reason[1024];
} kodawari_chain_world_info;

/// Fills `out` with what `world` is.
KODAWARI_C_API kodawari_status kodawari_chain_world_get_info(kodawari_chain_world* world,
                                                             kodawari_chain_world_info* out);

/* ------------------------------------------------------------------------------------ */
/* Bird worlds (SPEC B: procedural flapping along routes)                               */
/* ------------------------------------------------------------------------------------ */

/// The wing types (SPEC B.1; figures and sources in docs/wing-types.md).
typedef enum kodawari_wing_type {
    KODAWARI_WING_PIGEON = 0,  ///< short elliptical wings (woodpecker, pigeon)
    KODAWARI_WING_GULL = 1,    ///< long narrow wings (gull, albatross)
    KODAWARI_WING_HAWK = 2,    ///< broad soaring wings (hawk, eagle)
    KODAWARI_WING_HUMMINGBIRD = 3,  ///< hovering wings (hummingbird)
    KODAWARI_WING_STARLING = 4,     ///< short pointed wings of a flocking passerine (common starling)
    KODAWARI_WING_MAX_ENUM = 0x7FFFFFFF
} kodawari_wing_type;

/// The parts of a bird's rig, in output order. Head, Tail and the Arm1s are children of
/// Body; each Arm2 (the outer wing) is the child of its Arm1.
typedef enum kodawari_bird_part {
    KODAWARI_PART_BODY = 0,
    KODAWARI_PART_HEAD = 1,
    KODAWARI_PART_TAIL = 2,
    KODAWARI_PART_LEFT_ARM1 = 3,
    KODAWARI_PART_LEFT_ARM2 = 4,
    KODAWARI_PART_RIGHT_ARM1 = 5,
    KODAWARI_PART_RIGHT_ARM2 = 6,
    KODAWARI_PART_MAX_ENUM = 0x7FFFFFFF
} kodawari_bird_part;

/// Parts per bird.
#define KODAWARI_BIRD_PARTS 7
/// Floats per part transform: position x, y, z, then rotation x, y, z, w.
#define KODAWARI_TRANSFORM_FLOATS 7

/// A route: n >= 1 cubic Bezier segments that share their end points (SPEC B.3). A smooth
/// route through waypoints P_k takes, for segment k, the handles P_k + (P_{k+1} - P_{k-1}) / 6
/// and P_{k+1} - (P_{k+2} - P_k) / 6 (Catmull-Rom; what the scene files' generated routes do).
typedef struct kodawari_route_desc {
    /// point_count x 3 floats: control points B0 B1 B2 B3 of segment 0, then B1 B2 B3 of each
    /// next segment; m, |each| <= 1e6; no two consecutive points alike, no cusp.
    const float* points;
    /// 3n + 1.
    uint32_t point_count;
    /// 1: the route closes (the last point equals the first) and birds go round; 0: past
    /// its end a bird flies on straight.
    uint32_t loop;
    /// 0: flown at each bird's speed by arc length (default); 1: the seed's parametric
    /// timing, u driven by time, `segment_duration` seconds per segment.
    uint32_t parametric;
    /// s per segment, in [0.001, 3600], for parametric timing; ignored otherwise.
    float segment_duration;
    /// NULL (every segment KODAWARI_SEGMENT_AUTO) or one kodawari_segment_mode per segment,
    /// (point_count - 1) / 3 of them: a take-off only first and a landing only last, on an
    /// open route with arc-length timing; hover only on routes of hovering flocks
    /// (docs/flight-modes.md F.1).
    const int32_t* modes;
} kodawari_route_desc;

/// A route segment's flight mode (docs/flight-modes.md).
typedef enum kodawari_segment_mode {
    KODAWARI_SEGMENT_AUTO = -1,    ///< the climb rule and the flap-glide rhythm
    KODAWARI_SEGMENT_GLIDE = 3,    ///< wings held out
    KODAWARI_SEGMENT_TAKEOFF = 4,  ///< from rest on a perch at the route's start
    KODAWARI_SEGMENT_LANDING = 5,  ///< to rest on a perch at the route's end
    KODAWARI_SEGMENT_HOVER = 6,    ///< figure-eight strokes (hovering wing types only)
} kodawari_segment_mode;

/// A flock: `count` birds of one wing type on one route. kodawari_flock_desc_default()
/// fills the wing type's own speed, frequency and amplitude.
typedef struct kodawari_flock_desc {
    /// Index into kodawari_bird_world_desc::routes.
    uint32_t route;
    kodawari_wing_type wing_type;
    /// Birds, >= 1; at most 10,000,000 in a world.
    uint32_t count;
    /// m/s along the route, in (0, 1000].
    float speed;
    /// Wingbeats per second in level flight, in (0, 1000].
    float frequency;
    /// Scale of the wingbeat angles (1 = the seed's), in (0, 3].
    float amplitude;
    /// count x 4 floats per bird: x, y, z added to the route (m, |each| <= 1e4) and w, a
    /// time offset (s, 0 .. 3600: the bird is that far ahead on the route); or NULL: all 0.
    const float* offsets;
    /// count initial wingbeat phases in cycles, [0, 1); or NULL: bird k starts at k / count.
    const float* phases;
} kodawari_flock_desc;

/// Fills `out` for `count` birds of `wing_type` on route 0 with the wing type's cruise
/// speed, flap frequency and amplitude, and NULL offsets and phases.
KODAWARI_C_API kodawari_status kodawari_flock_desc_default(kodawari_wing_type wing_type, uint32_t count,
                                                           kodawari_flock_desc* out);

/// How birds bank and choose their flight mode (SPEC B.4-B.6).
/// kodawari_flight_settings_default() gives the engine's defaults.
typedef struct kodawari_flight_settings {
    /// m/s^2 for the coordinated-turn bank, in (0, 1000]. Default 9.81.
    float gravity;
    /// Largest bank, rad, in [0, 89 degrees]. Default 60 degrees.
    float max_bank;
    /// 0: coordinated turn (default); 1: the seed's rule (SPEC B.4).
    uint32_t seed_bank_rule;
    /// 0: climb angle with hysteresis (default); 1: the seed's vertical acceleration rule
    /// (SPEC B.5).
    uint32_t seed_mode_rule;
    /// Climb angles, rad, within (-90, 90) degrees, nested so that the hysteresis works:
    /// descend_enter < descend_exit <= ascend_exit < ascend_enter. Defaults -10, -5, 5, 10
    /// degrees.
    float ascend_enter;
    float ascend_exit;
    float descend_enter;
    float descend_exit;
    /// The seed rule's |a_y| threshold, m/s^2, in (0, 1000]. Default 0.05.
    float seed_accel_threshold;
    /// Blend progress per 1/60 s into level, ascend and descend, each in (0, 1]. Default
    /// 0.016, 0.036, 0.032 (the seed's).
    float blend_rates[3];
    /// Time constant of the first-order filter the bank (and the head's and tail's turn
    /// responses) follows, s, in [0, 10]; 0 rolls instantly. Default 0.3 (a scene's
    /// `flight.bank_time_constant`, docs/flight-modes.md).
    float bank_time_constant;
} kodawari_flight_settings;

/// Fills `out` with the engine's default flight settings.
KODAWARI_C_API kodawari_status kodawari_flight_settings_default(kodawari_flight_settings* out);

/// Everything a bird world is made of.
typedef struct kodawari_bird_world_desc {
    const kodawari_route_desc* routes;
    uint32_t route_count;  ///< >= 1
    const kodawari_flock_desc* flocks;
    uint32_t flock_count;  ///< >= 1
    /// Frames per second, in [0.01, 1000]: frame f is at time f / fps.
    float fps;
    kodawari_flight_settings flight;
    kodawari_backend_options backend;
} kodawari_bird_world_desc;

/// A bird world and the backend that simulates it (opaque). Birds are numbered flock by
/// flock, in each flock's order.
typedef struct kodawari_bird_world kodawari_bird_world;

/// Creates a bird world at frame 0. `*out` is set only on success (to NULL otherwise).
KODAWARI_C_API kodawari_status kodawari_bird_world_create(const kodawari_bird_world_desc* desc,
                                                          kodawari_bird_world** out);

/// Destroys a world (NULL: nothing happens).
KODAWARI_C_API void kodawari_bird_world_destroy(kodawari_bird_world* world);

/// The message of the most recent call on `world` ("" when it succeeded; "" for NULL).
/// Valid until the next call on `world`.
KODAWARI_C_API const char* kodawari_bird_world_last_error(const kodawari_bird_world* world);

/// Goes back to frame 0.
KODAWARI_C_API kodawari_status kodawari_bird_world_rewind(kodawari_bird_world* world);

/// Where kodawari_bird_world_simulate() writes: per frame, per bird, per part (in
/// kodawari_bird_part order) KODAWARI_TRANSFORM_FLOATS floats, frame-major. Every array is
/// optional (NULL: not read; with both NULL the frames are simulated and nothing is read
/// back); a capacity counts floats and must be at least frames x birds x 49.
typedef struct kodawari_bird_output {
    /// Each part relative to its parent (its rig offset and its rotation), Body's in world
    /// space: what drives a skeleton.
    float* local_transforms;
    size_t local_transforms_capacity;
    /// Each part in world space: what places one mesh per part.
    float* world_transforms;
    size_t world_transforms_capacity;
} kodawari_bird_output;

/// Simulates the next `frames` frames (1 .. 100000) of every bird.
KODAWARI_C_API kodawari_status kodawari_bird_world_simulate(kodawari_bird_world* world, uint32_t frames,
                                                            const kodawari_bird_output* out);

/// What a bird world is and where it runs.
typedef struct kodawari_bird_world_info {
    uint32_t route_count;
    uint32_t bird_count;
    /// The next frame simulate() computes (the frames simulated since create or rewind).
    uint32_t next_frame;
    float fps;
    kodawari_backend backend;  ///< never AUTO
    uint32_t validation_messages;
    char device[256];
    char fallback_reason[1024];
} kodawari_bird_world_info;

/// Fills `out` with what `world` is.
KODAWARI_C_API kodawari_status kodawari_bird_world_get_info(kodawari_bird_world* world,
                                                            kodawari_bird_world_info* out);

/* ------------------------------------------------------------------------------------ */
/* Device embedding: the application's Vulkan device and command buffers                */
/* ------------------------------------------------------------------------------------ */
/* The C form of kodawari/vulkan/vulkan_embed.hpp (docs/embedding.md has the frame loop, the
 * synchronization the module records and the lifetimes). Vulkan handles travel as void*
 * (dispatchable: VkInstance, VkPhysicalDevice, VkDevice, VkCommandBuffer) and uint64_t
 * (non-dispatchable: VkBuffer), so that this header needs no Vulkan header. */

/// The application's Vulkan objects (what VulkanDeviceHandles holds in C++). The module
/// creates only its own objects on the device, with `allocator`, calls Vulkan through
/// `get_instance_proc_addr`, and destroys neither the instance nor the device.
typedef struct kodawari_vulkan_device_desc {
    void* instance;                /* VkInstance */
    void* physical_device;         /* VkPhysicalDevice */
    void* device;                  /* VkDevice */
    uint32_t queue_family;         /* of the command buffers passed to *_record_*; must do compute */
    uint32_t queue_index;          /* the queue creation and read-back submit to (and wait on) */
    void* get_instance_proc_addr;  /* PFN_vkGetInstanceProcAddr */
    const void* allocator;         /* const VkAllocationCallbacks*, or NULL */
    uint32_t api_version;          /* the instance's VkApplicationInfo::apiVersion, >= 1.1 */
    uint32_t frames_in_flight;     /* 1 to 16: the depth of the per-frame input rings */
} kodawari_vulkan_device_desc;

typedef struct kodawari_vulkan_device kodawari_vulkan_device;

/// Wraps the application's device for kodawari_backend_options::vulkan_device. Every
/// field is checked before the first call through a handle (KODAWARI_INVALID_ARGUMENT
/// naming it; KODAWARI_UNAVAILABLE when the device lacks what the kernels need).
KODAWARI_C_API kodawari_status kodawari_vulkan_device_adopt(const kodawari_vulkan_device_desc* desc,
                                                            kodawari_vulkan_device** out);
/// Releases the wrapper (NULL is fine). Worlds made on it keep what they need until they
/// are destroyed; destroy them all, once the GPU finished their work, before destroying
/// the VkDevice.
KODAWARI_C_API void kodawari_vulkan_device_release(kodawari_vulkan_device* device);

/// Records one step of a world on the application's device (backend options with
/// vulkan_device) into `command_buffer` (a VkCommandBuffer of the device's queue family,
/// recording): the frame's input through the world's staging ring, the step, and the
/// barriers docs/embedding.md lists; nothing submitted or waited for. The frame is checked
/// as kodawari_chain_world_step checks it, before anything is recorded.
KODAWARI_C_API kodawari_status kodawari_chain_world_record_step(kodawari_chain_world* world, void* command_buffer,
                                                                const kodawari_chain_frame* frame);
/// Records the next `frames` frames of a flock on the application's device.
KODAWARI_C_API kodawari_status kodawari_bird_world_record_simulate(kodawari_bird_world* world, void* command_buffer,
                                                                   uint32_t frames);

/// The module's buffers, for the application's shaders. Element layouts: the std430
/// structs of <kodawari/shared/rods.h> and <kodawari/shared/birds.h> (GLSL and C++).
typedef enum kodawari_device_buffer {
    KODAWARI_BUFFER_CHAIN_STATES = 0,  /* RodChainStateGpu per chain: root.position, root.rotation */
    KODAWARI_BUFFER_JOINT_MOTION = 1,  /* RodJointMotionGpu per joint: x relative to the chain's root */
    KODAWARI_BUFFER_JOINT_SPIN = 2,    /* RodJointSpinGpu per joint: q (x, y, z, w) */
    KODAWARI_BUFFER_BIRD_POSES = 3,    /* BirdPoseGpu per bird: the last simulated frame */
    KODAWARI_BUFFER_FLOCK_AGENTS = 4,  /* FlockAgentGpu: a simulation's agents on the device (kodawari_simulation_set_flock_device_agents) */
    KODAWARI_BUFFER_MAX_ENUM = 0x7FFFFFFF
} kodawari_device_buffer;

typedef struct kodawari_buffer_range {
    uint64_t buffer;  /* VkBuffer */
    uint64_t offset;  /* bytes to the first element */
    uint64_t range;   /* bytes: count x stride */
    uint32_t count;   /* elements */
    uint32_t stride;  /* bytes per element */
} kodawari_buffer_range;

/// Where a chain world's buffer is (a vulkan world; CHAIN_STATES, JOINT_MOTION, JOINT_SPIN).
KODAWARI_C_API kodawari_status kodawari_chain_world_buffer(kodawari_chain_world* world, kodawari_device_buffer which,
                                                           kodawari_buffer_range* out);
/// Where a bird world's buffer is (a vulkan world, after a frame; BIRD_POSES).
KODAWARI_C_API kodawari_status kodawari_bird_world_buffer(kodawari_bird_world* world, kodawari_device_buffer which,
                                                          kodawari_buffer_range* out);

/* ------------------------------------------------------------------------------------ */
/* Simulations of scene files (issue 33): a whole scene, birds and characters           */
/* ------------------------------------------------------------------------------------ */
/* A scene file (docs/scene-format.md) opened, stepped and baked as `kodawari run` does,
 * on one backend kind: what the Python package (python/kodawari) and the Blender add-on
 * use. The chain and bird worlds above build a world from arrays instead. */

/// A scene simulated frame after frame (opaque).
typedef struct kodawari_simulation kodawari_simulation;

/// Loads the scene file at `path` (UTF-8) and opens its backends. `backend`: as for the
/// worlds (NULL = all zeros: auto); `frames`: how many frames to simulate (at most
/// 10 000 000), or 0 for the scene's own count (its duration x fps). A file that cannot
/// be read or is not a valid scene is KODAWARI_INVALID_ARGUMENT with a message naming the
/// file (and the JSON path of the first problem). `*out` is set only on success (to NULL otherwise).
KODAWARI_C_API kodawari_status kodawari_simulation_open(const char* path, const kodawari_backend_options* backend,
                                                        uint32_t frames, kodawari_simulation** out);
/// Destroys a simulation (NULL: nothing happens).
KODAWARI_C_API void kodawari_simulation_destroy(kodawari_simulation* sim);
/// The message of the most recent call on `sim` ("" when it succeeded; "" for NULL).
/// Valid until the next call on `sim`.
KODAWARI_C_API const char* kodawari_simulation_last_error(const kodawari_simulation* sim);
/// Simulates the next `frames` frames (the first call simulates frame 0), at least 1 and
/// at most the frames left (info.frame_count - info.next_frame).
KODAWARI_C_API kodawari_status kodawari_simulation_step(kodawari_simulation* sim, uint32_t frames);

/// The wind the scene's characters feel from the next frame on, in place of the scene's
/// `wind` (characters with a `wind` of their own keep theirs); NULL: the scene's again. A
/// field out of range is KODAWARI_INVALID_ARGUMENT naming the member.
KODAWARI_C_API kodawari_status kodawari_simulation_set_wind(kodawari_simulation* sim, const kodawari_wind* wind);

/// The budget mode of the levels of detail (docs/level-of-detail.md "The budget"): from
/// the next frame, fewer characters are fully simulated, nearest first, so that a frame's
/// clips and chains stay within `budget_ms` milliseconds (a positive finite number).
/// `measured` 0 prices frames by the scene's cost model alone (`lod.costs`: the same bits
/// on every run, as a bake must be); non-zero scales the model by what the frames took
/// (an interactive application's). KODAWARI_INVALID_ARGUMENT naming `budget_ms` for a bad
/// budget, or when the scene has no characters or its `lod` is off; KODAWARI_UNAVAILABLE
/// once the rigged characters' rod input is written on the device, which the vulkan
/// backend does from the first step (set the budget before it).
KODAWARI_C_API kodawari_status kodawari_simulation_set_lod_budget(kodawari_simulation* sim, float budget_ms, int measured);

/// What the levels' budget did (kodawari_simulation_lod_budget).
typedef struct kodawari_lod_budget {
    uint32_t active;      ///< 1 while a budget is in force (the scene's `lod.budget_ms` or the call above), else 0
    uint32_t measured;    ///< 1: scaled by what the frames took; 0: the cost model alone
    float budget_ms;      ///< the budget, ms
    float scale;          ///< what measured frames put on the model (1 for a model-only budget)
    float full_distance;  ///< at the last step, the depth along the camera's axis within which characters could be full (m): +INFINITY when the budget took every character the projected-size rule makes full (and before the first step), -INFINITY when it took none
    float modelled_ms;    ///< the last step's frame as the model priced it, ms (before the scale)
} kodawari_lod_budget;
/// Fills `out` with the levels' budget and what it did at the last step; `out->active` 0
/// (and the rest zero) without a budget.
KODAWARI_C_API kodawari_status kodawari_simulation_lod_budget(kodawari_simulation* sim, kodawari_lod_budget* out);

/// What an application places among a scene's flocking birds (docs/flocking.md): a
/// predator they flee, an attractor they are drawn to, or an obstacle they keep out of
/// (a sphere, a capsule, or a plane they keep to one side of).
typedef enum kodawari_flock_agent_kind {
    /// Fled within `radius` (across its path, by `velocity`), `weight` m/s^2 at it, 0 at `radius`.
    KODAWARI_FLOCK_PREDATOR = 0,
    /// Drawn to within `radius`, the same falloff.
    KODAWARI_FLOCK_ATTRACTOR = 1,
    /// A sphere of `radius`: pushed out within `margin` of its surface, `weight` m/s^2 at it.
    KODAWARI_FLOCK_OBSTACLE = 2,
    /// A capsule of `radius` from `position` to `end`: kept out of as the sphere, steered round its axis.
    KODAWARI_FLOCK_CAPSULE = 3,
    /// The plane through `position` with `normal`: birds keep to the normal's side, pushed within `margin`.
    KODAWARI_FLOCK_PLANE = 4
} kodawari_flock_agent_kind;

/// One agent; kodawari_flock_agent_default() gives a predator at the origin.
typedef struct kodawari_flock_agent {
    /// A kodawari_flock_agent_kind.
    uint32_t kind;
    /// World position, m, |each| <= 1e6.
    float position[3];
    /// Its velocity, m/s, |each| <= 1000 (a predator's; unused by the others). Default 0.
    float velocity[3];
    /// m, in (0, 10000] (a plane's is not read). Default 15.
    float radius;
    /// m/s^2, in [0, 1000]. Default 40.
    float weight;
    /// An obstacle's margin (sphere, capsule, plane), m, in (0, 1000]. Default 2.
    float margin;
    /// A capsule's other end, m, |each| <= 1e6. Default 0.
    float end[3];
    /// A plane's normal, any length above 1e-6 (normalized). Default (0, 1, 0).
    float normal[3];
} kodawari_flock_agent;

/// Fills `out` with the defaults above.
KODAWARI_C_API kodawari_status kodawari_flock_agent_default(kodawari_flock_agent* out);

/// Places `count` agents (at most 64; NULL with 0 removes them) among the scene's flocking
/// birds from the next frame on, beside the scene's predators, until called again. An
/// agent out of range is KODAWARI_INVALID_ARGUMENT naming agents[i] and the member, and
/// changes nothing. A scene without flocking flocks takes them and does nothing with them.
KODAWARI_C_API kodawari_status kodawari_simulation_set_flock_agents(kodawari_simulation* sim, const kodawari_flock_agent* agents,
                                                                    uint32_t count);

/// Agents the application writes on its device for kodawari_simulation_record to read
/// (docs/flocking.md, "Agents on the device"): from the next recorded frame on, the first
/// `count` elements (at most 64) of the buffer KODAWARI_BUFFER_FLOCK_AGENTS
/// (kodawari_simulation_buffer; FlockAgentGpu each, kodawari/shared/flocking.h; encode
/// them as kodawari_encode_flock_agent does) are the application's agents, in
/// place of kodawari_simulation_set_flock_agents' (each call replaces the other's; 0
/// removes them). Write them after the previous frame's recording has read them and
/// before this frame's, which begins with a barrier from transfer and compute-shader
/// writes. Their values are not checked. KODAWARI_INVALID_ARGUMENT naming `count` above
/// 64, or on a CPU backend, or on a simulation opened without the backend options'
/// vulkan_device (it cannot record); while `count` > 0, kodawari_simulation_step is
/// refused.
KODAWARI_C_API kodawari_status kodawari_simulation_set_flock_device_agents(kodawari_simulation* sim, uint32_t count);
/// `agent` as the kernels read it: 12 floats (FlockAgentGpu: position xyz and radius;
/// kind, weight, margin, 0; velocity, a capsule's end or a plane's unit normal, and 0)
/// into `out`, what an application writes into KODAWARI_BUFFER_FLOCK_AGENTS. An agent out
/// of range is KODAWARI_INVALID_ARGUMENT naming the member.
KODAWARI_C_API kodawari_status kodawari_encode_flock_agent(const kodawari_flock_agent* agent, float out[12]);

/// Records the next frame of the whole scene (its flocks, flocking birds and characters'
/// chains) into `command_buffer`, a VkCommandBuffer of the application's in the
/// recording state, on the device the simulation was opened on (backend options with
/// vulkan_device): Simulation::record, with the synchronization of the record calls
/// above. Nothing is read back: the frame's state is in the simulation's buffers
/// (kodawari_simulation_buffer) once the application's submission completed, so
/// kodawari_simulation_bird_poses refuses after it until the next step, while
/// kodawari_simulation_read_chains reads the chains back (after that submission).
/// Another backend, a null command buffer or no frame left: KODAWARI_INVALID_ARGUMENT.
KODAWARI_C_API kodawari_status kodawari_simulation_record(kodawari_simulation* sim, void* command_buffer);
/// Where a simulation's buffer is on its Vulkan device, for the application's shaders:
/// BIRD_POSES (the last frame's, after a step or record: ask again after each), or the
/// chains' CHAIN_STATES, JOINT_MOTION and JOINT_SPIN. Another backend, a buffer the scene
/// does not have or no frame yet: KODAWARI_INVALID_ARGUMENT.
KODAWARI_C_API kodawari_status kodawari_simulation_buffer(kodawari_simulation* sim, kodawari_device_buffer which,
                                                          kodawari_buffer_range* out);

/// What a simulation is, where it runs and how far it got.
typedef struct kodawari_simulation_info {
    uint32_t bird_count;
    uint32_t character_count;  ///< character instances (their chains are the chains below)
    uint32_t chain_count;
    uint32_t joint_count;      ///< every chain's joints: the per-joint arrays' length
    uint32_t frame_count;      ///< frames in all: `frames` of open, else the scene's
    uint32_t next_frame;       ///< the frames simulated so far (0 before the first step)
    float fps;
    kodawari_backend backend;  ///< never AUTO
    uint32_t validation_messages;
    char name[256];             ///< the scene's name, cut to fit
    char device[256];           ///< what it runs on, cut to fit
    char fallback_reason[1024];  ///< AUTO that fell back to cpu: why; else ""
} kodawari_simulation_info;
/// Fills `out` with what `sim` is.
KODAWARI_C_API kodawari_status kodawari_simulation_get_info(kodawari_simulation* sim, kodawari_simulation_info* out);

/// The last simulated frame's bird poses, as kodawari_bird_world_simulate writes one frame:
/// per bird (in the scene's order, flock by flock), per part, KODAWARI_TRANSFORM_FLOATS
/// floats; capacities at least bird_count x 49. Before the first step:
/// KODAWARI_INVALID_ARGUMENT.
KODAWARI_C_API kodawari_status kodawari_simulation_bird_poses(kodawari_simulation* sim, const kodawari_bird_output* out);
/// The last simulated frame's tail spread of every bird (`out`: at least bird_count floats):
/// s, the Tail's scale along its width (its local X) being 1 + s (docs/flight-modes.md F.5;
/// the glTF export's Tail scale). Before the first step: KODAWARI_INVALID_ARGUMENT.
KODAWARI_C_API kodawari_status kodawari_simulation_bird_tail_spreads(kodawari_simulation* sim, float* out,
                                                                     size_t capacity);
/// The chains' state after the last step, as kodawari_chain_world_read writes it (one
/// read-back from a device); a scene without characters has 0 joints and writes nothing.
/// Before the first step: KODAWARI_INVALID_ARGUMENT.
KODAWARI_C_API kodawari_status kodawari_simulation_read_chains(kodawari_simulation* sim, const kodawari_chain_output* out);
/// Chain `chain`'s joints in the per-joint arrays: [*joint_begin, *joint_begin +
/// *joint_count). Either pointer may be NULL.
KODAWARI_C_API kodawari_status kodawari_simulation_chain_joints(kodawari_simulation* sim, uint32_t chain,
                                                                uint32_t* joint_begin, uint32_t* joint_count);
/// A chain's level of detail (docs/level-of-detail.md): simulated fully, posed (no
/// dynamics: carried by its root onto its rest shape), hidden (off the camera's view), or
/// reduced (simulated at half the substeps and iterations, where the scene's
/// `lod.reduced_pixels` turns that level on).
typedef enum kodawari_level {
    KODAWARI_LEVEL_FULL = 0,
    KODAWARI_LEVEL_POSED = 1,
    KODAWARI_LEVEL_HIDDEN = 2,
    KODAWARI_LEVEL_REDUCED = 3
} kodawari_level;
/// Every chain's level of detail at the last step, in the order of the per-chain arrays
/// (one read-back from a device): `levels[c]` a kodawari_level, and where `kept` is not
/// NULL, `kept[c]` 1 if chain c kept its state at that step instead of stepping (a far
/// posed or hidden chain between its turns, docs/level-of-detail.md "The rate"), else 0.
/// Both arrays hold `capacity` bytes, at least chain_count (else
/// KODAWARI_BUFFER_TOO_SMALL); every chain is FULL while the scene's `lod` is off, and a
/// scene without characters writes nothing. Before the first step, or `levels` NULL:
/// KODAWARI_INVALID_ARGUMENT.
KODAWARI_C_API kodawari_status kodawari_simulation_chain_levels(kodawari_simulation* sim, uint8_t* levels, uint8_t* kept,
                                                                size_t capacity);
/// Bakes the scene to glTF binary files as `kodawari run --out PATH` does: every frame from
/// frame 0, on a simulation of its own with the same scene, backend and frame count, so
/// that `sim`'s own state and frame are untouched; being the scene file's, the bake has
/// nothing of what was set on `sim` (kodawari_simulation_set_flock_agents, _set_wind,
/// _set_lod_budget). The flock goes to `path`; the
/// characters to `path` too when the scene has no birds, else to `<path without
/// .glb>-characters.glb` (one file per rigged character template, as the command line
/// writes them). `compact`: 1 drops the keys linear interpolation reproduces within 1 mm
/// and 0.001 rad (docs/compact.md), 0 keeps every key. Each file is written whole or not
/// at all. `written` (NULL, or `written_size` bytes): the paths written, one per line,
/// cut to fit. A `path` not named .glb (any case) is KODAWARI_INVALID_ARGUMENT unless it is
/// a device or a named pipe, as is one that is the scene file or a file the scene reads.
KODAWARI_C_API kodawari_status kodawari_simulation_bake(kodawari_simulation* sim, const char* path, uint32_t compact,
                                                        char* written, size_t written_size);

/// Sets up the chains of a rigged character as `kodawari rig CHARACTER --out SCENE` does
/// (docs/rigged-characters.md): VRM spring bones, else bones named like hair, tails and
/// ears, with their colliders; writes a scene file that simulates it (one instance at the
/// origin, `clip` playing, "" or NULL: the file's first; `duration` s, (0, 3600]) at
/// `scene_path`, whole or not at all. A file without chains is KODAWARI_INVALID_ARGUMENT
/// naming it. `chains` (NULL, or `chains_size` bytes): one line per chain, its name, root
/// node and joint count separated by tabs, cut to fit.
KODAWARI_C_API kodawari_status kodawari_rig_scene(const char* character_path, const char* scene_path, const char* clip,
                                                  float duration, char* chains, size_t chains_size);

#ifdef __cplusplus
}
#endif

#endif /* KODAWARI_KODAWARI_H */
