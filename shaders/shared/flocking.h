// GPU-shared data of the flocking domain (issue 32, docs/flocking.md): every struct,
// binding and constant its kernels (shaders/flock_grid.comp, flock_step.comp) and its CPU
// paths (engine/domains/flocking/) share. Static asserts: engine/gpu/shared_layout.cpp.
#ifndef KODAWARI_SHADERS_SHARED_FLOCKING_H
#define KODAWARI_SHADERS_SHARED_FLOCKING_H

#include "birds.h"
#include "glsl_types.h"

#define KW_FLOCK_WORKGROUP_SIZE 64
// flock_step.comp's one specialization constant: its invocations per workgroup
// (BackendOptions::workgroup_size; the grid's passes keep KW_FLOCK_SCAN_SIZE).
#define KW_FLOCK_SPEC_WORKGROUP_SIZE 0
// The most neighbours a bird weighs (FlockParamsGpu.counts.x is at most this).
#define KW_FLOCK_MAX_NEIGHBOURS 16
// The grid's buckets are a power of two (FlockPush.counts.y = buckets - 1) and the scan
// of their counts runs in one workgroup of this many invocations.
#define KW_FLOCK_SCAN_SIZE 256

#define KW_FLOCK_BINDING_FLOCKS 0   // FlockParamsGpu per flock (per frame: its target moves)
#define KW_FLOCK_BINDING_BIRDS 1    // FlockBirdGpu per bird (constants)
#define KW_FLOCK_BINDING_STATES 2   // FlockStateGpu per bird, two slots: [slot * birds + i]
#define KW_FLOCK_BINDING_CELLS 3    // uint per bird: its bucket this frame
#define KW_FLOCK_BINDING_BUCKETS 4  // uvec2 per bucket as two uints: start, count; then a uint per scan tile
#define KW_FLOCK_BINDING_SORTED 5   // uint per bird: bird indices by bucket
#define KW_FLOCK_BINDING_AGENTS 6   // FlockAgentGpu: repellers, attractors, obstacles (per frame)
#define KW_FLOCK_BINDING_MOTION 7   // BirdMotionGpu (shared/birds.h) per frame per bird: what the bird domain flies
#define KW_FLOCK_BINDING_POINTS 8   // vec4 per bird in SORTED's order: xyz its position, w its flock (a float, exact below 2^24)
#define KW_FLOCK_BINDING_PERCHES 9  // FlockPerchGpu per bird (constants; read only by birds that land)
#define KW_FLOCK_BINDING_COUNT 10
// The most flocking flocks a world holds: a flock index is carried as a float in POINTS.
#define KW_FLOCK_MAX_FLOCKS 16777216u

// flock_grid.comp's passes (FlockPush.counts.w). The scan of the bucket counts runs over
// tiles of KW_FLOCK_SCAN_TILE buckets, a workgroup each, so that a million birds' two
// million buckets spread over the device rather than one workgroup: each tile's total,
// the tiles' exclusive prefix sums (one workgroup), then each tile's starts from its offset.
#define KW_FLOCK_PASS_CLEAR 0u       // every bucket's count to 0
#define KW_FLOCK_PASS_COUNT 1u       // each bird's bucket, its count incremented
#define KW_FLOCK_PASS_SCAN_TILES 2u  // each tile's total of counts, after the buckets
#define KW_FLOCK_PASS_SCAN_TOP 3u    // the tiles' totals to their exclusive prefix sums
#define KW_FLOCK_PASS_SCAN_DOWN 4u   // starts = exclusive prefix sum of the counts; counts to 0
#define KW_FLOCK_PASS_SCATTER 5u     // each bird into its bucket's range (counts back up), its point beside it
// Buckets a lane of the scan sums in order, and so buckets per tile (a workgroup's).
#define KW_FLOCK_SCAN_RUN 16u
#define KW_FLOCK_SCAN_TILE (KW_FLOCK_SCAN_SIZE * KW_FLOCK_SCAN_RUN)

// FlockAgentGpu.kind_weight.x
#define KW_FLOCK_AGENT_REPELLER 0.0f  // a predator: birds within radius flee it
#define KW_FLOCK_AGENT_ATTRACTOR 1.0f // birds within radius are drawn to it
#define KW_FLOCK_AGENT_SPHERE 2.0f    // an obstacle: birds keep out of it, margin = kind_weight.z
#define KW_FLOCK_AGENT_CAPSULE 3.0f   // a sphere swept from position.xyz to velocity.xyz (radius position.w), as SPHERE
#define KW_FLOCK_AGENT_PLANE 4.0f     // birds keep to the side of velocity.xyz (unit normal) of the plane through position.xyz

KW_NAMESPACE_BEGIN

// Per flock: the rules' parameters (FlockingSpec) and where its route's leader is this
// frame, which the flock is drawn to.
struct FlockParamsGpu {
    uvec4 counts;   // x: neighbours k, y: 1 = metric (every neighbour within radii.x, nearest k first), z: the frame stepped to, w: unused
    vec4 radii;     // x: search radius (m), y: separation distance (m), z: cos of half the field of view (blind angle behind), w: route radius (m)
    vec4 weights;   // x: separation, y: alignment, z: cohesion, w: route attraction (m/s^2)
    vec4 ground;    // x: clearance (m), y: weight (m/s^2), z: speed time constant tau (s), w: separation's front factor
    vec4 target;    // xyz: the route's leader this frame (m), w: unused
    vec4 collision; // x: collision distance (m; 0: off), y: its look-ahead (s), z, w: unused
};

// Per bird, constant: its flock, its place in the formation about the leader, what its
// wing allows (birds::derive_flight, docs/wing-types.md) and its perches (docs/flocking.md,
// "Perches": a bird flocks from frame ids.y, after its take-off, until it lands: from
// frame ids.z on, at the first frame it has passed its landing's start, and at ids.w
// wherever it is; outside them it flies its route, KW_MOTION_ROUTE in shared/birds.h).
// 64 bytes, a cache line: the rules read it by index for every bird.
struct FlockBirdGpu {
    uvec4 ids;      // x: flock, y: its first flocking frame, z: the first frame it may land (0xFFFFFFFF: no landing), w: the frame it lands by
    vec4 offset;    // xyz: formation offset from the leader (m), w: the take-off's route time offset (s)
    vec4 speed;     // x: cruise speed v0, y: minimum speed, z: maximum speed (m/s), w: max speed change (m/s^2)
    vec4 turn;      // x: max lateral acceleration g tan(max bank) (m/s^2), y: sin(max climb), z: sin(max dive), w: unused
};

// Per bird, constant: its landing (docs/flocking.md, "Perches"), apart from FlockBirdGpu
// so that flocks without one do not carry it through the caches (in it, 9% of the cpu
// backend's time at a million birds).
struct FlockPerchGpu {
    vec4 land_position;  // xyz: its route's landing start plus its offset (m), w: the route's time there at its speed v0 (s)
    vec4 land_velocity;  // xyz: the route's velocity there (m/s), w: 1 / T, T the landing's time to its touchdown (1/s)
};

// Per bird, carried from frame to frame. A landing bird's is where it left the flock (kept).
struct FlockStateGpu {
    vec4 position;  // xyz (m), w: 0, or landing: t0, the time of its last flocking frame (s)
    vec4 velocity;  // xyz (m/s), w: 0 flying (or on its perch before its take-off), 1 landing
};

// A repeller, attractor or obstacle, given per frame by the scene or the application.
struct FlockAgentGpu {
    vec4 position;     // xyz (m), w: radius of influence (m)
    vec4 kind_weight;  // x: KW_FLOCK_AGENT_*, y: weight (m/s^2), z: obstacle margin (m), w: unused
    vec4 velocity;     // xyz: the agent's velocity (m/s): a predator is fled across its path, w: unused
};

struct FlockPush {
    uvec4 counts;  // x: birds, y: bucket mask (buckets - 1), z: agents, w: the grid pass (KW_FLOCK_PASS_*)
    uvec4 slots;   // x: state slot read (the other is written), y: motion frame slot, z: substeps, w: substep index
    uvec4 bases;   // x: this frame's first FlockParamsGpu, y: its first FlockAgentGpu, zw: unused
    vec4 step;     // x: dt of a substep (s), y: 1 / search radius, z: gravity (m/s^2), w: dt of a frame (s; the bird domain's)
};

KW_NAMESPACE_END

#endif
