#version 450
// The flocking step (issue 32): one invocation per bird, in the grid's order, finds its
// neighbours in the grid flock_grid.comp built and applies the rules (lib/flock_body.glsl,
// the same source the CPU backends compile), writing the other state slot and, after a
// frame's last substep, the frame's motion for the bird domain.
// Built a second time with KW_FLOCK_SEARCH_ONLY as `flock_search_only`: the neighbour
// search alone, each bird's state kept (profile_flocking() times the step's parts apart).
#extension GL_GOOGLE_include_directive : require

#include "shared/flocking.h"

// The size is a specialization constant (default KW_FLOCK_WORKGROUP_SIZE, see birds_flap.comp).
layout(local_size_x = KW_FLOCK_WORKGROUP_SIZE, local_size_x_id = KW_FLOCK_SPEC_WORKGROUP_SIZE) in;

layout(std430, binding = KW_FLOCK_BINDING_FLOCKS) readonly buffer Flocks { FlockParamsGpu flocks[]; };
layout(std430, binding = KW_FLOCK_BINDING_BIRDS) readonly buffer Birds { FlockBirdGpu birds[]; };
layout(std430, binding = KW_FLOCK_BINDING_STATES) buffer States { FlockStateGpu states[]; };
layout(std430, binding = KW_FLOCK_BINDING_CELLS) readonly buffer Cells { uint cells[]; };
layout(std430, binding = KW_FLOCK_BINDING_BUCKETS) readonly buffer Buckets { uint buckets[]; };
layout(std430, binding = KW_FLOCK_BINDING_SORTED) readonly buffer Sorted { uint sorted_birds[]; };
layout(std430, binding = KW_FLOCK_BINDING_AGENTS) readonly buffer Agents { FlockAgentGpu agents_in[]; };
layout(std430, binding = KW_FLOCK_BINDING_MOTION) writeonly buffer Motion { BirdMotionGpu motion[]; };
layout(std430, binding = KW_FLOCK_BINDING_POINTS) readonly buffer Points { vec4 points[]; };
layout(std430, binding = KW_FLOCK_BINDING_PERCHES) readonly buffer Perches { FlockPerchGpu perches[]; };

layout(push_constant) uniform Push { FlockPush push; };

#define KW_XYZ(v) ((v).xyz)
#define KW_INOUT(T) inout T
FlockParamsGpu kw_flock(uint f) { return flocks[push.bases.x + f]; }
FlockBirdGpu kw_bird(uint i) { return birds[i]; }
FlockStateGpu kw_state(uint i) { return states[push.slots.x * push.counts.x + i]; }
uint kw_bucket_start(uint b) { return buckets[2u * b]; }
uint kw_bucket_count(uint b) { return buckets[2u * b + 1u]; }
uint kw_sorted(uint s) { return sorted_birds[s]; }
vec4 kw_point(uint s) { return points[s]; }
FlockAgentGpu kw_agent(uint a) { return agents_in[push.bases.y + a]; }

#include "lib/flock_hash.glsl"
#include "lib/flock_body.glsl"

void main() {
    const uint slot = gl_GlobalInvocationID.x;
    const uint count = push.counts.x;
    if (slot >= count) return;
    // Birds in the grid's order: the invocations of a subgroup are birds of one cell or of
    // few, which scan the same buckets (the same loads, loops of about the same length)
    // where birds by index would each scan their own (docs/performance.md, "Flocking").
    const uint i = sorted_birds[slot];
    const uint out_slot = 1u - push.slots.x;
#ifdef KW_FLOCK_SEARCH_ONLY
    // The state kept, its unused w given what the search found, so that no compiler
    // drops the search.
    const FlockNeighbours nb = flock_neighbours(i, push.counts.y, push.step.y);
    FlockStateGpu kept = states[push.slots.x * count + i];
    kept.position.w = float(nb.found) + (nb.found > 0u ? nb.d2[0] : 0.0);
    states[out_slot * count + i] = kept;
#else
    const FlockBirdGpu bird = birds[i];
    const FlockParamsGpu flock = kw_flock(bird.ids.x);
    FlockStateGpu kept = states[push.slots.x * count + i];
    // Perches (lib/flock_body.glsl): on its perch or landing it is not stepped.
    if (!flock_stepped(bird, perches[i], flock, kept, push.slots.w, push.step.w)) {
        // On its perch or landing: its state kept, its route's motion.
        states[out_slot * count + i] = kept;
        if (push.slots.w + 1u == push.slots.z) {
            const FlockRouteMotion m = flock_route_motion(bird, perches[i], kept);
            motion[push.slots.y * count + i] = BirdMotionGpu(m.position, m.velocity, m.acceleration);
        }
        return;
    }
    const FlockStep s = flock_step_bird(i, push.counts.y, push.counts.z, push.step.x, push.step.y);
    states[out_slot * count + i] = FlockStateGpu(vec4(s.position, 0.0), vec4(s.velocity, 0.0));
    if (push.slots.w + 1u == push.slots.z) {
        motion[push.slots.y * count + i] = BirdMotionGpu(vec4(s.position, 0.0), vec4(s.velocity, 0.0), vec4(s.acceleration, 0.0));
    }
#endif
}
