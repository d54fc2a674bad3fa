// GPU-shared data of the rods kernel (SPEC part A): every struct, binding index and the
// workgroup size, defined once for shaders/rods_step.comp and the C++ backend
// (engine/vulkan_backends/vulkan_rods.cpp). Layout: std430, only vec4/uvec4 members (see
// glsl_types.h); sizes and offsets are checked in engine/gpu/shared_layout.cpp.
//
// Why this layout. One invocation simulates one whole chain: every substep and
// iteration of SPEC A.4 runs in registers, and the chain's state is loaded once and
// stored once per frame (lavapipe executes each storage access lane by lane, see
// shared/PERF-NOTES.md, so a kernel per solver phase would spend most of its time
// loading and storing). A chain's joints are contiguous (joint_begin + i) in every
// per-joint buffer, so one invocation walks consecutive addresses. The state is split
// by what each phase needs and by size: lavapipe caps one storage buffer at 128 MiB,
// and 100 000 chains x 16 joints x 64 bytes of state would not fit in one. Nothing a
// frame can recompute from per-chain data is stored per joint: the shape-matching warm
// start comes from the orientations, last frame's rest shape from last frame's weights.
// Quaternions are vec4(x, y, z, w).
//
// The template constants (RodTemplateGpu, RodTemplateJointGpu, RodShapeJointGpu) are
// shared by every chain of a template: chains are listed by template and, in worlds of
// few templates, each template's run is its own dispatch whose push constants (RodPush)
// name the template, so every lane reads the same addresses (KW_RODS_SPEC_GROUPED).
//
// On a discrete GPU. The same mapping is sound but not what a GPU is best at: one
// invocation holds a whole chain, so with MAX_J = 16 its live set (positions, velocities,
// orientations, rest shape, the shape-matching terms: some 40 floats per joint) is several
// hundred registers, beyond the 255 VGPRs of AMD or NVIDIA; the compiler spills to
// scratch (or keeps the arrays in local memory) and occupancy is one or two waves per
// SIMD. The per-joint state is contiguous per chain, so neighbouring lanes read addresses
// MAX_J x 32 bytes apart: each vec4 load touches its own 32-byte sector (uncoalesced;
// a joint's two vec4 of a struct share that sector). The template constants of a
// GROUPED dispatch are uniform, so they go through the scalar/constant cache. A
// GPU-first kernel would map a subgroup (or workgroup) to a chain and an invocation to a
// joint, exchanging the group's neighbours by subgroup shuffles or shared memory:
// coalesced, few registers, but lavapipe pays per invocation and per shuffle, which is
// why this one does not. shaders/rods_lanes.comp is that kernel (shared memory: lavapipe's
// subgroups are 8 lanes, fewer than a chain's joints), a variant for a GPU run to time
// (BackendOptions::rod_kernel, RodKernel::PerJoint); it reads the same buffers.
#ifndef KODAWARI_SHADERS_SHARED_RODS_H
#define KODAWARI_SHADERS_SHARED_RODS_H

#include "glsl_types.h"

#define KW_RODS_WORKGROUP_SIZE 64
#define KW_RODS_MAX_JOINTS 32  // rods::kMaxChainJoints
#define KW_RODS_MAX_VIEWS 7    // rods::kMaxViewExamples
#define KW_RODS_MAX_CHAIN_COLLIDERS 16  // rods::kMaxChainColliders
#define KW_RODS_COLLIDER_PASSES 2       // rods::kColliderPasses
#define KW_RODS_UNROLLED_COLLIDERS 4    // rods_step.comp unrolls its collisions up to this many colliders a chain
#define KW_RODS_FTL_DAMPING 1.0         // rods::kFollowTheLeaderDamping (DFTL's s_damping)

#define KW_RODS_BINDING_TEMPLATES 0        // RodTemplateGpu, per chain template
#define KW_RODS_BINDING_TEMPLATE_JOINTS 1  // RodTemplateJointGpu, per template joint
#define KW_RODS_BINDING_SHAPES 2           // RodShapeJointGpu, per template x shape x joint
#define KW_RODS_BINDING_CHAINS 3           // RodChainGpu, per chain
#define KW_RODS_BINDING_REFERENCE 4        // RodTransformGpu, per character: reference joint (this frame)
#define KW_RODS_BINDING_ROOTS 5            // RodTransformGpu, per chain: root frame (this frame)
#define KW_RODS_BINDING_COLLIDERS 6        // RodColliderGpu (this frame)
#define KW_RODS_BINDING_MOTION 7           // RodJointMotionGpu, per joint (state)
#define KW_RODS_BINDING_SPIN 8             // RodJointSpinGpu, per joint (state)
#define KW_RODS_BINDING_CHAIN_STATE 9      // RodChainStateGpu, per chain (state and diagnostics)
#define KW_RODS_BINDING_KEYED 10           // vec4 per chain: raw keyed weights u_1 .. u_4 (this frame, shared/rod_keys.h)
#define KW_RODS_BINDING_CENTERS 11         // RodTransformGpu, per center (RodFrame::centers, this frame)
#define KW_RODS_BINDING_CENTER_STATE 12    // RodTransformGpu, per center: the last frame's (state)
#define KW_RODS_BINDING_WINDS 13           // RodWindGpu, per wind field (RodFrame::winds, this frame)
#define KW_RODS_BINDING_COUNT 14

// RodChainGpu.joints.z of a chain without a center frame (rods::kNoCenter).
#define KW_RODS_NO_CENTER 0xFFFFFFFFu

// RodColliderGpu.b.w: the collider's kind (rods::ColliderKind), stored as a float.
#define KW_RODS_COLLIDER_OUTSIDE 0
#define KW_RODS_COLLIDER_INSIDE 1
#define KW_RODS_COLLIDER_PLANE 2

// Specialization constant ids of rods_step.comp (and of rods_lanes.comp, which reads
// MAX_VIEWS, SUPPRESSION, FEATURES, MAX_COLLIDERS, WORKGROUP_SIZE and LANES).
#define KW_RODS_SPEC_MAX_JOINTS 0  // the longest chain of the dispatch: sizes the register arrays
#define KW_RODS_SPEC_MAX_VIEWS 1   // the most view examples of a chain of the dispatch
#define KW_RODS_SPEC_SUPPRESSION 2 // KW_RODS_SUPPRESSION_*: what the world's chains need of SPEC A.5
#define KW_RODS_SPEC_GROUPED 3     // 1: one dispatch per template, its constants named by RodPush (see there)
#define KW_RODS_SPEC_EXACT 4       // 1: every chain of the dispatch has MAX_J joints, MAX_VIEWS views and MAX_KEYED keyed examples
#define KW_RODS_SPEC_MAX_KEYED 5   // the most keyed examples of a chain of the dispatch (0: keyed examples compiled out)
#define KW_RODS_SPEC_FEATURES 6    // KW_RODS_FEATURE_* the world uses; the others are compiled out
#define KW_RODS_SPEC_MAX_COLLIDERS 7  // the most colliders of a chain of the world (0: collisions compiled out)
#define KW_RODS_SPEC_WORKGROUP_SIZE 8  // invocations per workgroup (BackendOptions::workgroup_size)
#define KW_RODS_SPEC_LANES 9  // rods_lanes.comp: invocations per chain (a power of two >= its joints)
#define KW_RODS_SPEC_COUNT 10

// What a world may use beyond outside colliders (KW_RODS_SPEC_FEATURES): lavapipe runs
// both sides of a branch under a mask, so code a world never takes still costs it (the
// center's rotation of every joint, each collider kind's projection) unless compiled out.
#define KW_RODS_FEATURE_CENTERS 1u  // chains with a center frame
#define KW_RODS_FEATURE_INSIDE 2u   // inside colliders
#define KW_RODS_FEATURE_PLANE 4u    // plane colliders
#define KW_RODS_FEATURE_AIR 8u      // wind fields or drag: velocities relative to the air (rods::WindField)
#define KW_RODS_FEATURE_LIMITS 16u  // angle limits (rods::AngleLimit, shaders/lib/spring_limit.glsl)
#define KW_RODS_FEATURE_LOD 32u     // level of detail (rods::LodSettings, shaders/lib/rod_lod.glsl)
#define KW_RODS_FEATURE_ALL 63u

// A chain's level of detail (rods::Level, docs/level-of-detail.md), kept in
// RodChainStateGpu.view.w as a float (with its idle frames, below).
#define KW_RODS_LEVEL_FULL 0u    // every substep
#define KW_RODS_LEVEL_POSED 1u   // no dynamics: carried by its root and eased onto its rest shape
#define KW_RODS_LEVEL_HIDDEN 2u  // off the camera's frustum: updated as posed
#define KW_RODS_LEVEL_REDUCED 3u // dynamics at half the substeps and iterations (rods::reduced_params)
// RodChainStateGpu.view.w holds level + KW_RODS_IDLE_UNIT x idle, idle the frames the chain
// has kept its state since its last step (rods::ChainState::idle, at most 3).
#define KW_RODS_IDLE_UNIT 4u

// The posed and hidden levels' rate (shaders/lib/rod_lod.glsl rod_rests,
// docs/level-of-detail.md "The rate"): a posed chain steps every KW_RODS_POSED_PERIOD-th
// frame, a hidden one every KW_RODS_HIDDEN_PERIOD-th (powers of two), characters taking
// turns in groups of KW_RODS_RATE_GROUP consecutive ones of the scene.
#define KW_RODS_POSED_PERIOD 2u
#define KW_RODS_HIDDEN_PERIOD 4u
#define KW_RODS_RATE_GROUP 16u
// A hidden chain off the frustum widened by 20 degrees on every side rests at any distance
// (shaders/lib/rod_lod.glsl rod_far_off_view): tan(20 degrees).
#define KW_RODS_FAR_OFF_DEG 20
#define KW_RODS_FAR_OFF_TAN 0.36397023f
// RodPush.flags.w with the rate on: this bit, the frame's number plus the world's first
// character / KW_RODS_RATE_GROUP in bits 0-1 (mod 4: every period divides 4), and the first
// character mod KW_RODS_RATE_GROUP in bits 2-5.
#define KW_RODS_RATE_ON 0x80000000u

// RodPush.flags.x's bits.
#define KW_RODS_STEP_FIRST 1u  // the world's first step (chains of templates with physics.w != 0 start moving with their roots)
#define KW_RODS_STEP_WIND 2u   // a wind field moves the air (KW_RODS_BINDING_WINDS)
#define KW_RODS_STEP_LOD 4u    // levels of detail (rods::LodView::enabled)

// RodTemplateJointGpu.lengths.z: the joint's limit (rods::LimitKind), stored as a float.
#define KW_RODS_LIMIT_NONE 0u
#define KW_RODS_LIMIT_CONE 1u
#define KW_RODS_LIMIT_HINGE 2u
#define KW_RODS_LIMIT_SPHERICAL 3u

// Worlds of at most this many templates are stepped one dispatch per template (GROUPED);
// each dispatch costs tens of microseconds on lavapipe, so more templates take one.
#define KW_RODS_MAX_GROUPS 32
// GROUPED worlds get a kernel per distinct (joints, views) of their templates when they
// have at most this many (each variant is a compilation: 0.1-2 s on lavapipe, then cached).
#define KW_RODS_MAX_VARIANTS 4

#define KW_RODS_SUPPRESSION_NONE 0u     // every chain has momentum_suppression 0
#define KW_RODS_SUPPRESSION_FULL 1u     // every chain has momentum_suppression 1
#define KW_RODS_SUPPRESSION_PARTIAL 2u  // anything else

KW_NAMESPACE_BEGIN

// A chain template's constants (rods::ChainTemplate) and this frame's step sizes.
struct RodTemplateGpu {
    uvec4 counts;     // x: joint count n, y: view examples m, z: first RodTemplateJointGpu, w: first RodShapeJointGpu
    uvec4 solver;     // x: projection iterations, y: substeps this frame, z: keyed examples J (shapes m+1 .. m+J),
                      // w: 1 = a joint has an angle limit
    vec4 step;        // x: substep h (s), y: velocity decay exp(-damping h), z: k' per iteration, w: suppression
    vec4 physics;     // x: thickness (m), y: k_rest' per iteration (this frame), z: teleport distance (m), w: 1 = settle_start
    vec4 accel;       // xyz: gravity + wind (m/s^2), w: this frame's posed blend (rods::posed_blend, the world's)
    vec4 first_dir;   // xyz: e, the base shape's first segment direction (SPEC A.2)
    vec4 drag;        // this frame's: x: exp(-normal_drag h), y: exp(-tangent_drag h), z: 1 = drag on,
                      // w: dt / LodSettings::blend_time (rods::blend_in's step, the world's)
    vec4 reduced_step;  // this frame's at the reduced level (rods::reduced_params): x: substep h (s), y: velocity
                        // decay, z: k' per iteration, w: k_rest' per iteration
    vec4 reduced_solver;  // x: exp(-normal_drag h), y: exp(-tangent_drag h) (its h), z: projection iterations,
                          // w: substeps this frame (whole numbers as floats)
    vec4 views[KW_RODS_MAX_VIEWS];  // xyz: d_k (unit, reference joint's frame), w: influence p_k
};

// Per joint of a template.
struct RodTemplateJointGpu {
    vec4 axis_mass;  // xyz: bone axis u_i (joint frame), w: mass (kg)
    vec4 lengths;    // x: segment length l_i (0 for the last joint), y: ellipsoid half length a_i,
                     // z: segment i's angle limit (KW_RODS_LIMIT_*), w: unused
    vec4 limit_trig;   // rods::limit_trig: (cos angle, sin angle, cos yaw, sin yaw)
    vec4 limit_frame;  // rods::limit_frame: the limit's frame in the joint's (quaternion)
};

// Per joint of one shape of a template (shape 0 = base, k = view example k, m + j = keyed
// example j; docs/keyed-examples.md K.4), SPEC A.2. An example's quaternions are uploaded
// negated where their dot with the base's is negative (the blend's hemisphere flip done
// once; negation is exact, so the blend's bits are the CPU's).
struct RodShapeJointGpu {
    vec4 rotation;     // r_i (identity for the last joint, which has no segment)
    vec4 orientation;  // o_i
};

// Listed by template (the groups of GROUPED dispatches), so joints.y names the chain.
struct RodChainGpu {
    uvec4 ids;     // x: template, y: character, z: first collider, w: collider count
    uvec4 joints;  // x: first joint in the per-joint buffers, y: the chain's index in the per-chain buffers,
                   // z: its center (KW_RODS_BINDING_CENTERS index, KW_RODS_NO_CENTER: none),
                   // w: its wind field (KW_RODS_BINDING_WINDS index; read where the world has winds)
};

// A wind field (rods::WindField) as shaders/lib/wind.glsl takes it.
struct RodWindGpu {
    vec4 velocity;  // xyz: the mean air velocity (m/s), w: gust strength
    vec4 scales;    // x: 1 / gust_period (1/s), y: 1 / gust_size (1/m), z, w: unused
    uvec4 seed;     // x: the noise seed, yzw: 0
};

struct RodTransformGpu {
    vec4 position;  // xyz, w: unused
    vec4 rotation;  // quaternion
};

// A capsule (a sphere has a == b) or a plane (through a, unit normal b): rods::Collider.
struct RodColliderGpu {
    vec4 a;  // xyz, w: radius (m)
    vec4 b;  // xyz, w: kind (KW_RODS_COLLIDER_*)
};

struct RodJointMotionGpu {
    vec4 x;  // position relative to the chain's root position (RodChainStateGpu.root), w: sag.x (rods::ChainState::sag)
    vec4 v;  // velocity, w: sag.y
};

struct RodJointSpinGpu {
    vec4 q;      // orientation
    vec4 omega;  // angular velocity (world), w: sag.z (the w components are written at load only)
};

struct RodChainStateGpu {
    RodTransformGpu root;  // last frame's root frame; position.w: the share of full simulation in its result (rods::blend_in)
    vec4 view;             // xyz: this frame's view direction d (reference joint's frame), w: its level (KW_RODS_LEVEL_*)
                           // + KW_RODS_IDLE_UNIT x the frames it has kept its state since (rods::ChainState::idle)
    vec4 weights[2];       // W_0 .. W_7 (W_0 = the base's; views, then keyed examples, K.4); the next frame blends last
                           // frame's rest shape from them again for SPEC A.5 instead of
                           // storing it per joint (loads and stores are the costly part)
};

// One dispatch's: its chains are RodChainGpu counts.y .. counts.y + counts.x - 1. In a
// GROUPED dispatch they share template group.x, whose constants are found from these
// push constants alone (so lavapipe loads them once for all lanes).
struct RodPush {
    uvec4 counts;           // x: chains, y: first RodChainGpu, z: first RodTemplateJointGpu, w: first RodShapeJointGpu (GROUPED)
    uvec4 group;            // GROUPED: x: template, y: joint count n, z: view examples m, w: keyed examples J
    vec4 camera_position;   // xyz, w: 1 = orthographic
    vec4 camera_forward;    // xyz, w: the frame's length dt (s)
    uvec4 flags;            // x: KW_RODS_STEP_* bits; y, z: the bits of the LOD reduced distance and
                            // reduced stay distance (m, rods::LodView; floats); w: the posed and
                            // hidden levels' rate (KW_RODS_RATE_ON), or 0
    vec4 time;              // x: the frame's time (s, RodFrame::time: the wind's), y: LOD margin (m),
                            // z: LOD full distance (m), w: LOD stay distance (m) (rods::LodView)
    vec4 camera_right;      // xyz: the camera's right axis (unit), w: tan of half the horizontal field of view
    vec4 camera_up;         // xyz: the camera's up axis (unit), w: tan of half the vertical field of view
};

KW_NAMESPACE_END

#endif
