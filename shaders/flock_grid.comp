#version 450
// The flocking domain's neighbour grid (issue 32): a uniform grid of the search radius's
// cells hashed into a power-of-two bucket table, filled by a counting sort in six passes
// (FlockPush.counts.w): clear, count, the scan in three (shared/flocking.h), scatter. The
// order of birds within a bucket is the order atomics happen to give; nothing downstream
// depends on it (lib/flock_body.glsl).
#extension GL_GOOGLE_include_directive : require

#include "shared/flocking.h"

layout(local_size_x = KW_FLOCK_SCAN_SIZE) in;

layout(std430, binding = KW_FLOCK_BINDING_FLOCKS) readonly buffer Flocks { FlockParamsGpu flocks[]; };
layout(std430, binding = KW_FLOCK_BINDING_BIRDS) readonly buffer Birds { FlockBirdGpu birds[]; };
layout(std430, binding = KW_FLOCK_BINDING_STATES) readonly buffer States { FlockStateGpu states[]; };
layout(std430, binding = KW_FLOCK_BINDING_CELLS) buffer Cells { uint cells[]; };
layout(std430, binding = KW_FLOCK_BINDING_BUCKETS) buffer Buckets { uint buckets[]; };
layout(std430, binding = KW_FLOCK_BINDING_SORTED) writeonly buffer Sorted { uint sorted_birds[]; };
layout(std430, binding = KW_FLOCK_BINDING_AGENTS) readonly buffer Agents { FlockAgentGpu agents_in[]; };
layout(std430, binding = KW_FLOCK_BINDING_MOTION) readonly buffer Motion { BirdMotionGpu motion[]; };
layout(std430, binding = KW_FLOCK_BINDING_POINTS) writeonly buffer Points { vec4 points[]; };

layout(push_constant) uniform Push { FlockPush push; };

shared uint partial[KW_FLOCK_SCAN_SIZE];

#include "lib/flock_hash.glsl"

// The inclusive prefix sums of the workgroup's `partial` (Hillis-Steele), in place.
void scan_partial(uint lane) {
    for (uint offset = 1u; offset < KW_FLOCK_SCAN_SIZE; offset *= 2u) {
        const uint add = lane >= offset ? partial[lane - offset] : 0u;
        barrier();
        partial[lane] += add;
        barrier();
    }
}

void main() {
    const uint i = gl_GlobalInvocationID.x;
    const uint count = push.counts.x;
    const uint buckets_n = push.counts.y + 1u;
    const uint tiles = (buckets_n + KW_FLOCK_SCAN_TILE - 1u) / KW_FLOCK_SCAN_TILE;
    const uint pass = push.counts.w;
    const uint lane = gl_LocalInvocationID.x;
    // The scan's passes: every invocation of a workgroup takes part (barriers), so no
    // early return before them. A lane's run of buckets in its workgroup's tile.
    const uint first = gl_WorkGroupID.x * KW_FLOCK_SCAN_TILE + lane * KW_FLOCK_SCAN_RUN;
    const uint end = min(first + KW_FLOCK_SCAN_RUN, buckets_n);
    if (pass == KW_FLOCK_PASS_SCAN_TILES) {
        uint sum = 0u;
        for (uint b = first; b < end; ++b) sum += buckets[2u * b + 1u];
        partial[lane] = sum;
        barrier();
        scan_partial(lane);
        if (lane == KW_FLOCK_SCAN_SIZE - 1u) buckets[2u * buckets_n + gl_WorkGroupID.x] = partial[lane];
        return;
    }
    if (pass == KW_FLOCK_PASS_SCAN_TOP) {
        // One workgroup: each lane a contiguous run of tiles, whose totals become their
        // exclusive prefix sums.
        const uint run = (tiles + KW_FLOCK_SCAN_SIZE - 1u) / KW_FLOCK_SCAN_SIZE;
        const uint t0 = lane * run;
        const uint t1 = min(t0 + run, tiles);
        uint sum = 0u;
        for (uint t = t0; t < t1; ++t) sum += buckets[2u * buckets_n + t];
        partial[lane] = sum;
        barrier();
        scan_partial(lane);
        uint start = partial[lane] - sum;
        for (uint t = t0; t < t1; ++t) {
            const uint n = buckets[2u * buckets_n + t];
            buckets[2u * buckets_n + t] = start;
            start += n;
        }
        return;
    }
    if (pass == KW_FLOCK_PASS_SCAN_DOWN) {
        uint sum = 0u;
        for (uint b = first; b < end; ++b) sum += buckets[2u * b + 1u];
        partial[lane] = sum;
        barrier();
        scan_partial(lane);
        uint start = buckets[2u * buckets_n + gl_WorkGroupID.x] + partial[lane] - sum;
        for (uint b = first; b < end; ++b) {
            const uint n = buckets[2u * b + 1u];
            buckets[2u * b] = start;
            buckets[2u * b + 1u] = 0u;
            start += n;
        }
        return;
    }
    if (pass == KW_FLOCK_PASS_CLEAR) {
        if (i >= buckets_n) return;
        buckets[2u * i + 1u] = 0u;
        return;
    }
    if (i >= count) return;
    if (pass == KW_FLOCK_PASS_COUNT) {
        const uint b = flock_bucket(states[push.slots.x * count + i].position.xyz, push.step.y, push.counts.y);
        cells[i] = b;
        atomicAdd(buckets[2u * b + 1u], 1u);
    } else {
        const uint b = cells[i];
        const uint slot = buckets[2u * b] + atomicAdd(buckets[2u * b + 1u], 1u);
        sorted_birds[slot] = i;
        // What the neighbour search reads of a candidate, beside its index: one 16-byte
        // load in the grid's order instead of its state and flock by index.
        // A bird on its perch or landing is in no flock's search (lib/flock_body.glsl).
        const FlockBirdGpu bird = birds[i];
        const FlockStateGpu state = states[push.slots.x * count + i];
        points[slot] = vec4(state.position.xyz, flock_seen_as(bird, flocks[push.bases.x + bird.ids.x], state));
    }
}
