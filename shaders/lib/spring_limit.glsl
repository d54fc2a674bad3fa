// Angle limits of a spring joint (VRMC_springBone_limit 1.0-draft: cone, hinge, spherical;
// rods::AngleLimit, docs/models.md "Angle limits"), written once for GLSL
// (shaders/rods_step.comp) and C++ (engine/rods/limits.cpp, which cpu-reference calls;
// the Highway kernel repeats it lane-wise in engine/simd/rods_simd.cpp).
//
// `d` is the unit direction from a joint to its child in the limit's own frame, whose +Y
// is the direction the limit is centred on; the result is the nearest direction the limit
// allows, by the draft's reference implementation, with its angles given as their cosines
// and sines (`trig`: cone and hinge x = cos(angle), y = sin(angle); spherical x =
// cos(pitch), y = sin(pitch), z = cos(yaw), w = sin(yaw)), so that only square roots are
// taken here: correctly rounded on every instruction set, so the CPU backends agree to
// the bit. The draft's atan2 and asin of the spherical limit are replaced by the same
// comparisons on cosines and sines (|pitch| > P exactly when cos(pitch) < cos(P), for P
// in [0, pi]; |yaw| > Y exactly when |sin(yaw)| > sin(Y), for Y in [0, pi/2]), and a
// direction within its limits comes back unchanged, bit for bit.
//
// The draft's singular directions (its table "Singular Directions"), tested within
// kSingular (a direction within 1e-6 rad of the singular one, about float's resolution of
// a unit vector): a cone's -Y goes to the boundary on the +Z side; a hinge's +-X to +Y;
// a hinge's -Y to the boundary on the +Z side; a spherical limit's +-X to the boundary on
// the +Y side, its -Y to the boundary on the +Z side.
//
// KW_LIMIT_FN: nothing in GLSL, `inline` in C++. Float literals carry an f.
#ifndef KW_LIMIT_FN
#define KW_LIMIT_FN
#endif

#define KW_LIMIT_SINGULAR 1e-12f  // squared length of a projection taken as zero (1e-6 rad)

KW_LIMIT_FN vec3 limit_direction(uint kind, vec4 trig, vec3 d) {
    if (kind == 1u) {
        // Cone: at most `angle` from +Y. Outside it, the direction keeps its azimuth and
        // is tilted back onto the cone.
        if (d.y < trig.x) {
            const float h2 = d.x * d.x + d.z * d.z;
            if (h2 <= KW_LIMIT_SINGULAR) return vec3(0.0f, trig.x, trig.y);
            const float s = trig.y / sqrt(h2);
            return vec3(d.x * s, trig.x, d.z * s);
        }
        return d;
    }
    if (kind == 2u) {
        // Hinge: in the YZ plane (a turn about X only), at most `angle` from +Y.
        const float p2 = d.y * d.y + d.z * d.z;
        if (p2 <= KW_LIMIT_SINGULAR) return vec3(0.0f, 1.0f, 0.0f);
        const float inv = 1.0f / sqrt(p2);
        vec3 e = vec3(0.0f, d.y * inv, d.z * inv);
        if (e.y < trig.x) e = vec3(0.0f, trig.x, e.z < 0.0f ? -trig.y : trig.y);
        return e;
    }
    if (kind == 3u) {
        // Spherical: pitch (a turn about X, from +Y towards +Z) within +-P and yaw (towards
        // +X) within +-Y, the direction being (sin yaw, cos yaw cos pitch, cos yaw sin pitch).
        const float p2 = d.y * d.y + d.z * d.z;
        float cp = 1.0f;
        float sp = 0.0f;
        if (p2 > KW_LIMIT_SINGULAR) {
            const float inv = 1.0f / sqrt(p2);
            cp = d.y * inv;
            sp = d.z * inv;
        }
        bool limited = p2 <= KW_LIMIT_SINGULAR;
        if (cp < trig.x) {
            cp = trig.x;
            sp = sp < 0.0f ? -trig.y : trig.y;
            limited = true;
        }
        float sy = d.x;
        float cy = sqrt(p2);
        if (abs(sy) > trig.w) {
            sy = sy < 0.0f ? -trig.w : trig.w;
            cy = trig.z;
            limited = true;
        }
        if (!limited) return d;
        return vec3(sy, cy * cp, cy * sp);
    }
    return d;
}
