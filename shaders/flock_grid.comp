#version 450
// The flocking domain's neighbour grid (issue 32): a uniform grid of the search radius's
// cells hashed into a power-of-two bucket table, filled by a counting sort in four passes
// (FlockPush.counts.w): clear, count, scan, scatter. The order of birds within a bucket
// is the order atomics happen to give; nothing downstream depends on it (lib/flock_body.glsl).
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

void main() {
    const uint i = gl_GlobalInvocationID.x;
    const uint count = push.counts.x;
    const uint buckets_n = push.counts.y + 1u;
    const uint pass = push.counts.w;
    if (pass == KW_FLOCK_PASS_SCAN) {
        // One workgroup: each invocation sums a contiguous run of buckets, the runs'
        // sums are scanned in shared memory, then each run is written as starts.
        const uint lane = gl_LocalInvocationID.x;
        const uint run = (buckets_n + KW_FLOCK_SCAN_SIZE - 1u) / KW_FLOCK_SCAN_SIZE;
        const uint first = lane * run;
        const uint end = min(first + run, buckets_n);
        uint sum = 0u;
        for (uint b = first; b < end; ++b) sum += buckets[2u * b + 1u];
        partial[lane] = sum;
        barrier();
        // Hillis-Steele inclusive scan of the 256 sums.
        for (uint offset = 1u; offset < KW_FLOCK_SCAN_SIZE; offset *= 2u) {
            const uint add = lane >= offset ? partial[lane - offset] : 0u;
            barrier();
            partial[lane] += add;
            barrier();
        }
        uint start = partial[lane] - sum;
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
        points[slot] = vec4(states[push.slots.x * count + i].position.xyz, float(birds[i].ids.x));
    }
}
