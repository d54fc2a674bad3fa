#version 450
// Evaluates glTF animation clips for a crowd of instances of one character: one
// invocation per instance computes its clip time, walks the anchors (the animated nodes)
// parents first, samples the clip's channels of each (§3.11 Animations, Appendix C
// Interpolation of the glTF 2.0.1 specification), composes local T * R * S and world =
// parent world * local (§3.5.3 Transformations), then writes every node's world matrix,
// its anchor's times the node's constant rest transform relative to it, with the
// instance's placement applied. Mirrors engine/animation/character.cpp (sample, compute_world)
// and clip_time() in engine/backends/pose_backend.cpp; shared/poses.h has the layout and
// why.
#extension GL_GOOGLE_include_directive : require

#include "shared/poses.h"
#include "lib/matrix.glsl"
#include "lib/quat.glsl"

// The size is a specialization constant (default KW_POSES_WORKGROUP_SIZE, see birds_flap.comp).
layout(local_size_x = KW_POSES_WORKGROUP_SIZE, local_size_x_id = KW_POSES_SPEC_WORKGROUP_SIZE) in;

layout(std140, binding = KW_POSES_BINDING_NODES) uniform Nodes { PoseNodeGpu nodes[KW_POSES_UNIFORM_NODES]; };
layout(std430, binding = KW_POSES_BINDING_MORE_NODES) readonly buffer MoreNodes { PoseNodeGpu more_nodes[]; };
layout(std430, binding = KW_POSES_BINDING_CLIPS) readonly buffer Clips { PoseClipGpu clips[]; };
layout(std430, binding = KW_POSES_BINDING_CHANNELS) readonly buffer Channels { PoseChannelGpu channels[]; };
layout(std430, binding = KW_POSES_BINDING_TIMES) readonly buffer Times { float times[]; };
layout(std430, binding = KW_POSES_BINDING_VALUES) readonly buffer Values { vec4 values[]; };
layout(std430, binding = KW_POSES_BINDING_INSTANCES) readonly buffer Instances { PoseInstanceGpu instances[]; };
layout(std430, binding = KW_POSES_BINDING_WORLD) buffer World { PoseMatrixGpu world[]; };
layout(std430, binding = KW_POSES_BINDING_WORLD) buffer WorldColumns { PoseColumnGpu world_columns[]; };
layout(std430, binding = KW_POSES_BINDING_ANCHORS) readonly buffer Anchors { PoseAnchorGpu anchors[]; };

layout(constant_id = KW_POSES_SPEC_SLOTS) const uint SLOTS = 1u;
layout(constant_id = KW_POSES_SPEC_AFFINE) const bool AFFINE = false;

layout(push_constant) uniform Push { PosePush push; };

// ---- the clip time, bit for bit as clip_time() ----------------------------------------

// a / b rounded to nearest even as IEEE division does, from integer operations only, for
// a normal or zero and b normal and positive. The wrap count floor((t - start) / d) of a
// looping clip is a discrete decision: Vulkan lets x / y be 2.5 ulp off (and a driver may
// compute a * (1 / b)), and a quotient one ulp below a whole number would wrap one period
// less than the CPU does (the clip's end instead of its start). Quotients below 2^-126
// return a value with the same floor (0 or -FLT_MIN) instead of a subnormal; they would
// need d > 2^24 x, far beyond any clip.
float div_rn(float a, float b) {
    if (a == 0.0) return a;
    const uint ua = floatBitsToUint(a);
    const uint ub = floatBitsToUint(b);
    const uint sign = ua & 0x80000000u;
    uint ma = (ua & 0x007FFFFFu) | 0x00800000u;  // the 24-bit significands
    const uint mb = (ub & 0x007FFFFFu) | 0x00800000u;
    int e = int((ua >> 23) & 0xFFu) - int((ub >> 23) & 0xFFu);
    if (ma < mb) {  // ma / mb in [1, 2) from here on
        ma <<= 1;
        e -= 1;
    }
    // Long division: 24 bits of significand, then a guard bit; the remainder is sticky.
    uint q = 0u;
    uint r = ma;
    for (int k = 0; k < 25; ++k) {
        q <<= 1;
        if (r >= mb) {
            r -= mb;
            q |= 1u;
        }
        r <<= 1;
    }
    uint m = q >> 1;
    if ((q & 1u) != 0u && (r != 0u || (m & 1u) != 0u)) m += 1u;  // round half to even
    if (m == 0x01000000u) {
        m >>= 1;
        e += 1;
    }
    const int biased = e + 127;
    if (biased <= 0) return sign != 0u ? -1.17549435e-38 : 0.0;
    if (biased >= 255) return uintBitsToFloat(sign | 0x7F800000u);
    return uintBitsToFloat(sign | (uint(biased) << 23) | (m & 0x007FFFFFu));
}

// clip_time(): t = time + offset; looping, start + (t - start) - d * floor((t - start) / d)
// with d = end - start, evaluated left to right; `precise` keeps every +, -, * separate and
// correctly rounded (Vulkan requires that of them), as -ffp-contract=off does in C++.
float clip_time(PoseClipGpu clip, float offset, bool loop, float time) {
    precise float t = time + offset;
    if (!loop) return t;
    const float start = clip.range.x;
    precise float d = clip.range.y - start;
    if (d == 0.0) return start;
    precise float x = t - start;
    const float wraps = floor(div_rn(x, d));
    precise float wrapped = start + x - d * wraps;
    return wrapped;
}

// ---- sampling (§3.11, Appendix C), as animation::sample() ------------------------------------

// sin(x) / x by its Taylor series to x^12: the truncation is below 5e-10 on [0, pi/2].
float sinc(float x) {
    const float x2 = x * x;
    return 1.0 + x2 * (-1.0 / 6.0 + x2 * (1.0 / 120.0 + x2 * (-1.0 / 5040.0 + x2 * (1.0 / 362880.0 +
           x2 * (-1.0 / 39916800.0 + x2 * (1.0 / 6227020800.0))))));
}

// Appendix C, spherical linear interpolation along the shorter arc (b's sign flipped when
// the dot product is negative), as animation.cpp's slerp(), which works in double. Here
// in float: the angle theta between the quaternions comes from atan(|a - b|, |a + b|)
// (= theta / 2 for unit a, b), not acos(dot), which loses half its digits for nearby
// keys; and sin(u theta) / sin(theta) is u sinc(u theta) / sinc(theta), with theta in
// [0, pi/2] after the flip. That is accurate to float rounding at every angle (GPU sin
// only bounds the absolute error, useless for small angles), so nearly equal keys need no
// special case (the CPU's normalized lerp there differs from slerp by O(theta^3) < 1e-13).
vec4 slerp(vec4 a, vec4 b, float u) {
    if (dot(a, b) < 0.0) b = -b;
    const float theta = 2.0 * atan(length(a - b), length(a + b));
    const float s = sinc(theta);
    return a * ((1.0 - u) * sinc((1.0 - u) * theta) / s) + b * (u * sinc(u * theta) / s);
}

// lavapipe runs every load instruction (a loop over the lanes) whichever branch a lane
// takes, so the four values any interpolation needs are loaded once, at indices that
// depend on the case, instead of in each case's own branch (nine loads before).
vec4 sample_channel(PoseChannelGpu ch, float time) {
    const uint n = ch.target.w;
    const uint first = ch.keys.x;
    const bool cubic = ch.target.z == KW_POSES_INTERP_CUBICSPLINE;
    float t_lo = times[first];
    float t_hi = times[first + n - 1u];
    // `hold`: key k's value unchanged. Outside the keys the first / last value holds
    // (§3.11: clamped, no extrapolation); `!(time > first)` also sends NaN to the first key.
    uint k;
    bool hold = true;
    if (!(time > t_lo)) {
        k = 0u;
    } else if (time >= t_hi) {
        k = n - 1u;
    } else {
        // k with times[k] <= time < times[k + 1] (std::upper_bound - 1 in sample(); the
        // times increase strictly), keeping both ends' times. First a guess from the keys'
        // mean spacing, right for evenly spaced keys (which baked clips have) and checked
        // against the two keys around it; the binary search runs only where it missed. Two
        // loads instead of log2(n), each a loop over the lanes on lavapipe.
        const float per_second = uintBitsToFloat(ch.keys.z);
        const uint guess = uint(min((time - t_lo) * per_second, float(n - 2u)));
        const float t_guess = times[first + guess];
        const float t_next = times[first + guess + 1u];
        uint lo = 0u;
        uint hi = n - 1u;
        if (t_guess <= time && time < t_next) {
            lo = guess;
            hi = guess + 1u;
            t_lo = t_guess;
            t_hi = t_next;
        }
        while (hi - lo > 1u) {
            const uint mid = (lo + hi) / 2u;
            const float t_mid = times[first + mid];
            if (t_mid <= time) {
                lo = mid;
                t_lo = t_mid;
            } else {
                hi = mid;
                t_hi = t_mid;
            }
        }
        k = lo;
        hold = time == t_lo || ch.target.z == KW_POSES_INTERP_STEP;
    }
    // Key k's value, then key k + 1's and, for CUBICSPLINE (in-tangent, value, out-tangent
    // per key), the out-tangent b_k and in-tangent a_k+1 between them; a held key reads
    // its own value again, never past the channel's keys.
    const uint stride = cubic ? 3u : 1u;
    const uint v = ch.keys.y + stride * k + (cubic ? 1u : 0u);
    const bool between = !hold;
    const vec4 a = values[v];
    const vec4 b = values[between ? v + stride : v];
    const vec4 out_tangent = values[between && cubic ? v + 1u : v];
    const vec4 in_tangent = values[between && cubic ? v + 2u : v];
    if (hold) return a;
    const float td = t_hi - t_lo;
    const float u = (time - t_lo) / td;
    if (!cubic) {
        if (ch.target.y == KW_POSES_PATH_ROTATION) return slerp(a, b, u);
        return a + (b - a) * u;
    }
    // Appendix C, cubic spline: Hermite on [t_k, t_k+1] with the key values v_k, v_k+1, the
    // out-tangent b_k of key k and the in-tangent a_k+1 of key k+1, tangents scaled by the
    // keyframe delta t_d.
    const vec4 p0 = a;
    const vec4 m0 = out_tangent * td;
    const vec4 m1 = in_tangent * td;
    const vec4 p1 = b;
    const float u2 = u * u;
    const float u3 = u2 * u;
    vec4 r = (2.0 * u3 - 3.0 * u2 + 1.0) * p0 + (u3 - 2.0 * u2 + u) * m0 + (-2.0 * u3 + 3.0 * u2) * p1 + (u3 - u2) * m1;
    // The spline of unit quaternions leaves the unit sphere; Appendix C normalizes.
    if (ch.target.y == KW_POSES_PATH_ROTATION) {
        const float len = length(r);
        if (len > 0.0) r /= len;
    }
    return r;
}

// ---- composition (§3.5.3) ----------------------------------------------------------------

// T * R * S, with R as glm::mat4_cast computes it (its upper 3x3 is glm::mat3_cast's).
mat4 compose(vec3 t, vec4 q, vec3 s) {
    const mat3 r = mat3_cast(q);
    return mat4(vec4(r[0] * s.x, 0.0), vec4(r[1] * s.y, 0.0), vec4(r[2] * s.z, 0.0), vec4(t, 1.0));
}

// Affine: the bottom row is (0, 0, 0, 1) exactly (every factor has it, so every product
// does for finite entries), load() wrote it, and only the upper three rows are stored, as
// whole vec3 members: lavapipe stores each float lane by lane, and a swizzled .xyz store
// of a vec4 member would be three stores.
// A relative transform or link; affine, its bottom row is known and only xyz is loaded
// (each loaded float is a gather or a loop over the lanes on lavapipe).
mat4 constant_columns(vec4 c[4]) {
    if (AFFINE) return mat4(vec4(c[0].xyz, 0.0), vec4(c[1].xyz, 0.0), vec4(c[2].xyz, 0.0), vec4(c[3].xyz, 1.0));
    return mat4_columns(c);
}

void store(uint at, mat4 w) {
    if (AFFINE) {
        world_columns[4u * at].xyz = w[0].xyz;
        world_columns[4u * at + 1u].xyz = w[1].xyz;
        world_columns[4u * at + 2u].xyz = w[2].xyz;
        world_columns[4u * at + 3u].xyz = w[3].xyz;
    } else {
        world[at].columns[0] = w[0];
        world[at].columns[1] = w[1];
        world[at].columns[2] = w[2];
        world[at].columns[3] = w[3];
    }
}

void main() {
    const uint i = gl_GlobalInvocationID.x;
    if (i >= push.counts.x) return;
    const uint node_count = push.counts.y;
    const uint anchor_count = push.counts.z;
    const PoseInstanceGpu instance = instances[i];

    // The clip's channels, sorted by anchor: [c, c_end), `next` the anchor of channel c.
    // A rest-pose instance has none.
    uint c = 0u;
    uint c_end = 0u;
    float t = 0.0;
    if (instance.clip.x != KW_POSES_NONE) {
        const PoseClipGpu clip = clips[instance.clip.x];
        c = clip.channels.x;
        c_end = c + clip.channels.y;
        t = clip_time(clip, instance.timing.x, instance.clip.y != 0u, push.time.x);
    }
    // The next channel, loaded once (its target says which anchor it belongs to).
    PoseChannelGpu ch;
    if (c < c_end) ch = channels[c];
    uint next = c < c_end ? ch.target.x : KW_POSES_NONE;

    // The placed world matrices of the anchors, parents first, in registers: nothing is
    // read back from the output.
    mat4 slots[SLOTS];
    slots[0] = mat4_columns(instance.placement);
    for (uint a = 0u; a < anchor_count; ++a) {
        // The rest TRS with the clip's channels of this anchor applied in the file's order
        // (a later channel of the same property wins, as in animation::evaluate).
        vec3 translation = anchors[a].rest[0].xyz;
        vec4 rotation = anchors[a].rest[1];
        vec3 scale = anchors[a].rest[2].xyz;
        while (next == a) {
            const vec4 value = sample_channel(ch, t);
            if (ch.target.y == KW_POSES_PATH_TRANSLATION) {
                translation = value.xyz;
            } else if (ch.target.y == KW_POSES_PATH_ROTATION) {
                rotation = value;
            } else {
                scale = value.xyz;
            }
            ++c;
            if (c < c_end) ch = channels[c];
            next = c < c_end ? ch.target.x : KW_POSES_NONE;
        }
        const mat4 parent = slots[anchors[a].ids.x] * constant_columns(anchors[a].link);
        slots[a + 1u] = parent * compose(translation, rotation, scale);
    }

    const uint base = i * node_count;
    const uint uniform_nodes = min(node_count, KW_POSES_UNIFORM_NODES);
    for (uint n = 0u; n < uniform_nodes; ++n) {
        store(base + n, slots[nodes[n].ids.x] * constant_columns(nodes[n].relative));
    }
    for (uint n = uniform_nodes; n < node_count; ++n) {
        const uint m = n - KW_POSES_UNIFORM_NODES;
        store(base + n, slots[more_nodes[m].ids.x] * constant_columns(more_nodes[m].relative));
    }
}
