// GPU-shared data of the bird flapping kernel (SPEC part B): every struct, binding
// index and the workgroup size, defined once for shaders/birds_flap.comp and the C++
// backends. Layout: std430; only vec4/uvec4 members (see glsl_types.h). Sizes and
// offsets are checked by static_asserts in engine/gpu/shared_layout.cpp.
#ifndef KODAWARI_SHADERS_SHARED_BIRDS_H
#define KODAWARI_SHADERS_SHARED_BIRDS_H

#include "glsl_types.h"

#define KW_BIRDS_WORKGROUP_SIZE 64

#define KW_BIRDS_BINDING_UNIFORMS 0
#define KW_BIRDS_BINDING_ROUTES 1
#define KW_BIRDS_BINDING_CONTROL_POINTS 2
#define KW_BIRDS_BINDING_ARC_SAMPLES 3
#define KW_BIRDS_BINDING_PARAMS 4
#define KW_BIRDS_BINDING_STATES 5
#define KW_BIRDS_BINDING_POSES 6  // BirdPoseGpu
#define KW_BIRDS_BINDING_DIAGNOSTICS 7
#define KW_BIRDS_BINDING_MOTION 8  // BirdMotionGpu per frame per driven bird (KW_BIRD_DRIVEN), frame-major
#define KW_BIRDS_BINDING_COUNT 9

// Specialization constant ids of birds_flap.comp.
#define KW_BIRDS_SPEC_BANK_RULE 0
#define KW_BIRDS_SPEC_MODE_RULE 1
#define KW_BIRDS_SPEC_DIAGNOSTICS 2
#define KW_BIRDS_SPEC_DRIVEN 3  // the world has driven birds (reads the motion binding)
#define KW_BIRDS_SPEC_WORKGROUP_SIZE 4  // invocations per workgroup (BackendOptions::workgroup_size)
#define KW_BIRDS_SPEC_POSE_FIELDS 5  // poses as six arrays of vec4, one per field (BackendOptions::bird_pose_fields)
#define KW_BIRDS_SPEC_COUNT 6

// Flight modes (SPEC B.5). KW_MODE_UNSET marks a state that has not seen frame 0.
#define KW_MODE_LEVEL 0u
#define KW_MODE_ASCEND 1u
#define KW_MODE_DESCEND 2u
#define KW_MODE_GLIDE 3u     // wings held out, no flapping (docs/flight-modes.md)
#define KW_MODE_TAKEOFF 4u   // crouch, leap, strong low-speed beats, climb-out
#define KW_MODE_LANDING 5u   // flare and touchdown at zero speed
#define KW_MODE_HOVER 6u     // figure-eight strokes, hovering types only
#define KW_MODE_COUNT 7u
#define KW_MODE_UNSET 0xFFFFFFFFu

#define KW_BANK_COORDINATED 0u
#define KW_BANK_SEED 1u
#define KW_MODE_RULE_CLIMB 0u
#define KW_MODE_RULE_SEED 1u

// BirdParams.ids.w: the bird flies the motion another domain gives it each frame
// (BirdMotionGpu below) instead of its route; its offset is not added.
#define KW_BIRD_DRIVEN 1u

#define KW_ROUTE_LOOP 1u
#define KW_ROUTE_PARAMETRIC 2u
#define KW_ROUTE_TAKEOFF 4u  // the first segment is a take-off from a perch (docs/flight-modes.md)
#define KW_ROUTE_LANDING 8u  // the last segment is a landing on a perch

// A segment's mode, in the w of its first control point: a KW_MODE_* or this for the
// climb rule (and the flap-glide rhythm).
#define KW_SEGMENT_AUTO -1.0

// Parts of the rig (SPEC B.1), the order of BirdPose.rotation.
#define KW_PART_BODY 0
#define KW_PART_HEAD 1
#define KW_PART_TAIL 2
#define KW_PART_LEFT_ARM1 3
#define KW_PART_LEFT_ARM2 4
#define KW_PART_RIGHT_ARM1 5
#define KW_PART_RIGHT_ARM2 6
#define KW_PART_COUNT 7

// Constants of the new modes' looks, docs/flight-modes.md (F.2: take-off and landing
// timing; F.5: body bob, head and tail), shared by every backend.
#define KW_CROUCH_SECONDS 0.3      // on the perch before the leap
#define KW_LEAP_SECONDS 0.2        // the leap opens the folded wings
#define KW_FOLD_SECONDS 0.5        // folding the wings after touchdown
#define KW_BOB_HEIGHT 0.05         // body bob, in body lengths per unit amplitude
#define KW_BOB_PITCH 0.04          // body pitch oscillation (rad per unit amplitude)
#define KW_LOOK_AHEAD 0.35         // the head turns by the turn rate times this (s)
#define KW_MAX_LOOK 0.5            // rad
#define KW_HEAD_PITCH_HOLD 0.8     // share of the extra pitch the head undoes
#define KW_HEAD_BOB_HOLD 0.9       // share of the pitch oscillation the head undoes
#define KW_HEAD_BANK_HOLD 0.7      // share of the bank the head undoes
#define KW_HEAD_CLIMB_HOLD 0.5     // share of the climb the head undoes
#define KW_TAIL_CLIMB 0.3          // share of the climb the tail adds (lowered)
#define KW_TAIL_PITCH 0.5          // share of the extra pitch the tail adds
#define KW_TAIL_BANK 0.5           // share of the bank the tail twists with
#define KW_TAIL_BANK_SPREAD 0.4    // tail spread per unit sin(bank)

KW_NAMESPACE_BEGIN

// World-wide flight settings, one per dispatch.
struct FlightUniforms {
    vec4 physics;      // x: gravity (m/s^2), y: max bank (rad), z: dt (s), w: dt * 60 (blend steps per frame)
    vec4 climb;        // sin(g)|sin(g)| of the climb thresholds g: x ascend enter, y ascend exit, z descend enter, w descend exit
    vec4 blend_rates;  // x: into level, y: into ascend, z: into descend (per 1/60 s), w: seed rule's |a_y| threshold
    uvec4 rules;       // x: bank rule, y: mode rule (the kernel takes both as specialization constants), z: bird count, w: unused
    vec4 bank_limit;   // x: cos(max bank), y: sin(max bank), z: the roll filter's gain per frame 1 - exp(-dt / tau) (1: no filter; docs/flight-modes.md F.6), w: unused
    vec4 blend_rates2; // into glide, take-off, landing, hover (per 1/60 s)
};

// One route: a chain of cubic Bezier segments sharing end points (SPEC B.3).
struct RouteHeader {
    uvec4 extent;  // x: first control point, y: segment count, z: first arc sample, w: arc samples (intervals + 1)
    uvec4 flags;   // x: KW_ROUTE_* bits
    vec4 info;     // x: arc length L (m), y: seconds per segment D (parametric timing), z: 1/L, w: 1/D
    vec4 perch;    // take-off and landing segments (docs/flight-modes.md F.2): x: take-off length L0 (m), y: 1/L0, z: landing length Ln, w: 1/Ln (0 without)
};

// Arc-length table sample: x: s (m from route start), y: u (global parameter: segment +
// local), z: du/ds just before the sample, w: du/ds just after it. The two derivatives
// differ at segment junctions whose handles have different lengths; the cubic Hermite
// interpolation of u(s) over [s_j, s_j+1] uses w of sample j and z of sample j+1.
// next.x: 1 / (s_j+1 - s_j), so no division is needed (see "exact decisions" below).
struct ArcSample {
    vec4 s_u_duds;
    vec4 next;
};

// Exact decisions: flight modes, transitions and the phase are discrete or carried from
// frame to frame, so a rounding difference between backends could change a decision and
// with it every later frame. Everything they depend on is computed with +, -, * only
// (correctly rounded, no contraction: `precise` in GLSL, -ffp-contract=off in C++), in
// the same order on every backend, so they agree bit for bit.

// Per-bird constants.
struct BirdParams {
    vec4 offset;  // xyz: translation added to the route (m), w: time offset (s)
    vec4 motion;  // x: speed (m/s), y: flap frequency (Hz), z: flap amplitude scale, w: initial phase (cycles)
    uvec4 ids;    // x: route index, y: bird type (WingType, or a user's model after them), z: motion slot (driven birds), w: KW_BIRD_DRIVEN or 0
    vec4 flight;  // x: glide ratio, y: flap-glide beats (0: none), z: flap-glide glide seconds, w: 1 if it can hover
    vec4 shape;   // x: body length (m), y: wingspan (m), z, w: unused
};

// Per-bird state carried from frame to frame (mode hysteresis, transitions, phase, roll).
struct BirdState {
    vec4 blend;   // weights of the level, ascend, descend and glide poses in the blend source
    vec4 blend2;  // xyz: weights of the take-off, landing and hover poses, w: alpha (1 = no transition)
    vec4 phase;   // x: wingbeat phase in cycles [0, 1), y: seconds glided (flap-glide rhythm), z: wingbeats since the last glide, w: unused
    uvec4 mode;   // x: current target mode (KW_MODE_*), yzw: unused
    vec4 roll;    // the roll filter (docs/flight-modes.md F.6): xy: the filtered bank quaternion's w, z (not normalised), z: the filtered lateral acceleration (m/s^2), w: unused
};

// Per-bird, per-frame output: the 7 part transforms. Translations other than the
// body's are constants of the wing type's rig and are not repeated here.
struct BirdPose {
    vec4 position;     // xyz: Body world position, w: tail spread s (the Tail's scale along its width, X, is 1 + s)
    vec4 rotation[7];  // local rotations, quaternion (x, y, z, w), KW_PART_* order; Body in world space
};

// What the kernel stores per bird and frame: the parts that move. The right wing mirrors
// the left (SPEC B.2), so storing it would only add stores, the largest cost of the
// kernel on lavapipe; the Vulkan backend expands this to BirdPose when it reads poses back.
struct BirdPoseGpu {
    vec4 position;   // xyz: Body world position, w: tail spread (BirdPose.position.w)
    vec4 body;       // Body world rotation
    vec4 head;       // Head local rotation
    vec4 tail;       // Tail local rotation
    vec4 left_arm1;  // LeftArm1 local rotation
    vec4 left_arm2;  // LeftArm2 local rotation
};

// Optional per-bird, per-frame diagnostics (trace, validation).
struct BirdDiag {
    vec4 velocity;      // xyz (m/s), w: blend alpha
    vec4 acceleration;  // xyz (m/s^2), w: mode (as float)
    vec4 angles;        // target pose of the left wing: arm1 pitch, arm2 pitch, arm1 heading, arm2 heading (rad)
    vec4 attitude;      // yaw, pitch (climb), bank, phase (rad)
    vec4 flight;        // x: speed as a fraction of the cruise speed, y: extra body pitch (rad, nose up), z: tail spread, w: seconds glided
};

// BirdMotionGpu.position.w: what a driven bird flies this frame.
#define KW_MOTION_FLOWN 0.0  // the motion itself: position, velocity, acceleration
#define KW_MOTION_ROUTE 1.0  // its own route, as a route bird, eased from where the motion left it (perches)

// What another domain (flocking) flies a driven bird along: per bird per frame, the
// bird domain's input; its route sample (engine/birds/flight.cpp) is made from it.
//
// KW_MOTION_FLOWN (w 0): position, velocity and acceleration are the bird's frame.
// KW_MOTION_ROUTE (w 1): the bird flies its route (BirdParams.ids.x) as a route bird
// does, take-off and landing segments included, with the time offset velocity.w and the
// speed acceleration.z in place of its BirdParams' offset.w and motion.x, and its offset
// (BirdParams.offset.xyz) added; plus a correction c(t) that eases the bird from where
// its flocking flight left it onto the route (docs/flocking.md, "Perches"): with the
// frame's time t = frame * dt, t0 = acceleration.x, 1/T = acceleration.y (0: no
// correction), e_p = position.xyz, e_v = velocity.xyz and s = clamp((t - t0) / T, 0, 1),
//   c(t)   = e_p h00(s) + T e_v h10(s)           (added to the position)
//   c'(t)  = e_p h00'(s) / T + e_v h10'(s)        (to the velocity and the attitude's velocity)
//   c''(t) = e_p h00''(s) / T^2 + e_v h10''(s) / T, 0 once s = 1 (to the acceleration)
// with the cubic Hermite bases h00 = 2s^3 - 3s^2 + 1, h10 = s^3 - 2s^2 + s: c(t0) = e_p,
// c'(t0) = e_v, and c and c' are 0 from t0 + T on. The mode, the phase and every other
// exact decision come from the route sample alone (the correction moves the bird only).
struct BirdMotionGpu {
    vec4 position;      // xyz (m) or e_p, w: KW_MOTION_FLOWN or KW_MOTION_ROUTE
    vec4 velocity;      // xyz (m/s) or e_v, w: unused or the route's time offset (s)
    vec4 acceleration;  // xyz (m/s^2): the velocity's change over the frame / dt; or x: t0 (s), y: 1/T (1/s), z: the route's speed (m/s); w: unused
};

// Push constants of birds_flap.comp.
struct BirdPush {
    uvec4 frames;  // x: first frame, y: frame count, z: output slots (frames the pose buffer holds), w: driven birds (the motion's frame stride)
};

KW_NAMESPACE_END

#endif
