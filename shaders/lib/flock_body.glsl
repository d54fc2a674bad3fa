// The flocking step of one bird, written once (issue 31 item 5): GLSL in
// shaders/flock_step.comp, C++ (GLM's vec3 and functions) in the cpu-reference and cpu
// backends (engine/domains/flocking/flock_cpu.cpp). The includer provides, before this
// file:
//   KW_XYZ(v)                  the xyz of a shared vec4 as a vec3
//   FlockParamsGpu kw_flock(uint f)      FlockBirdGpu kw_bird(uint i)
//   FlockStateGpu kw_state(uint i)       (this frame's, the slot read)
//   uint kw_bucket_start(uint b)  uint kw_bucket_count(uint b)  uint kw_sorted(uint s)
//   vec4 kw_point(uint s)      the bird in grid slot s: xyz its position, w its flock
//                              (float(ids.x)); the GPU reads it from the copy the grid's
//                              scatter writes, cpu-reference by index, the same values
//   FlockAgentGpu kw_agent(uint a)
//   KW_INOUT(T)                a parameter read and written: GLSL's inout T, C++'s T&
// and lib/flock_hash.glsl's functions.
// Float literals carry an f (GLSL accepts it; C++ needs it: no double arithmetic here),
// conversions are explicit, and nothing depends on the order candidates are visited in:
// the neighbours are the k nearest by (distance, index), a total order, and the rules
// sum over them in that order, so the GPU's atomically filled buckets give the bits of
// the CPU's ordered ones on the same device (docs/flocking.md, "Determinism").
//
// The model: Reynolds (1987) separation, alignment and cohesion over each bird's k
// nearest neighbours (topological, as Ballerini et al. 2008 measured in starlings) in
// its field of view (a blind angle behind it, as Hildenbrandt, Carere & Hemelrijk 2010),
// with their Gaussian-softened separation, attraction to the flock's route (their roost
// attraction, here a point moving along the scene's route), a cruise-speed control with
// time constant tau (their eq. for the thrust), ground clearance, agents (predators,
// attractors, obstacles: spheres, capsules, planes), and the wing's limits (docs/flocking.md).

struct FlockStep {
    vec3 position;
    vec3 velocity;
    vec3 acceleration;
};

// A bird's neighbours: the k nearest, nearest first, by (distance^2, index).
struct FlockNeighbours {
    uint found;
    float d2[KW_FLOCK_MAX_NEIGHBOURS];
    uint j[KW_FLOCK_MAX_NEIGHBOURS];
};

// Whether candidate (d2, j) comes before (bd, bj): nearer, or as near with a lower index.
bool flock_before(float d2, uint j, float bd, uint bj) { return d2 < bd || (d2 == bd && j < bj); }

// The direction a bird flies (+z when it is still): its field of view's axis.
vec3 flock_forward(vec3 v) {
    const float speed = length(v);
    return speed > 1e-6f ? v / speed : vec3(0.0f, 0.0f, 1.0f);
}

// `forward` within the plane normal to the unit `axis` (a capsule's, a plane's upright):
// the heading a bird turns from, left or right of the axis; `forward` itself where it
// runs along the axis.
vec3 flock_facing(vec3 forward, vec3 axis) {
    const vec3 flat_forward = forward - dot(forward, axis) * axis;
    const float fl = length(flat_forward);
    return fl > 1e-3f ? flat_forward / fl : forward;
}

// The way an obstacle's steering turns a bird: along `across` (the obstacle's part across
// the bird's facing); dead on it, towards the bird's right (facing x up), a fixed choice
// rather than none, and +x where that has no direction either.
vec3 flock_round(vec3 across, vec3 facing, vec3 up) {
    const float cl = length(across);
    const vec3 side = cross(facing, up);
    const float sl = length(side);
    return cl > 1e-3f ? across / cl : sl > 1e-3f ? side / sl : vec3(1.0f, 0.0f, 0.0f);
}

// (flock_flies() and flock_seen_as(), which the grid's scatter shares: lib/flock_hash.glsl.)
// Whether a flying bird leaves the flock to land at this frame (asked at a frame's first
// substep, so that it leaves on a whole frame): from the first frame it may, once it has
// passed its landing's start (the plane through its route's landing start plus its offset,
// across the route there: it lands where it arrives, a bird behind its slot later), and by
// the last frame wherever it is (docs/flocking.md, "Perches").
bool flock_lands(FlockBirdGpu bird, FlockPerchGpu perch, FlockParamsGpu flock, FlockStateGpu state) {
    if (flock.counts.z < bird.ids.z) return false;
    const vec3 past = KW_XYZ(state.position) - KW_XYZ(perch.land_position);
    return flock.counts.z >= bird.ids.w || dot(past, KW_XYZ(perch.land_velocity)) >= 0.0f;
}

// The state of a bird that leaves the flock to land at this frame: where its last flocking
// frame left it, marked landing, with that frame's time t0 (frame_dt: the bird domain's).
FlockStateGpu flock_landing_state(FlockStateGpu state, uint frame, float frame_dt) {
    state.position.w = float(frame - 1u) * frame_dt;
    state.velocity.w = 1.0f;
    return state;
}

// Whether a bird is stepped by the rules this substep (`substep` of the frame; frame_dt the
// bird domain's): not on its perch or landing, and a flying one leaves the flock to land
// at a frame's first substep, `state` becoming the landing state it then keeps. The one
// decision flock_step.comp and the CPU backends take.
bool flock_stepped(FlockBirdGpu bird, FlockPerchGpu perch, FlockParamsGpu flock, KW_INOUT(FlockStateGpu) state, uint substep,
                   float frame_dt) {
    if (!flock_flies(bird, flock, state)) return false;
    if (substep != 0u || !flock_lands(bird, perch, flock, state)) return true;
    state = flock_landing_state(state, flock.counts.z, frame_dt);
    return false;
}

// What a bird that is not flying hands the bird domain (shared/birds.h, KW_MOTION_ROUTE),
// at its cruise speed: before its take-off is behind it, its route from its take-off's
// time offset, uncorrected (its state is where that route leaves it, flight.cpp's sample
// at the frame before it flocks: docs/flocking.md); once landing, its route from its
// landing's start at t0, eased from where its flight left it (its state, kept since) by
// the difference to that route's place and velocity there.
struct FlockRouteMotion {
    vec4 position;
    vec4 velocity;
    vec4 acceleration;
};
FlockRouteMotion flock_route_motion(FlockBirdGpu bird, FlockPerchGpu perch, FlockStateGpu state) {
    FlockRouteMotion m;
    if (state.velocity.w == 0.0f) {
        m.position = vec4(0.0f, 0.0f, 0.0f, float(KW_MOTION_ROUTE));
        m.velocity = vec4(0.0f, 0.0f, 0.0f, bird.offset.w);
        m.acceleration = vec4(0.0f, 0.0f, bird.speed.x, 0.0f);
    } else {
        const float t0 = state.position.w;
        const vec3 e_p = KW_XYZ(state.position) - KW_XYZ(perch.land_position);
        const vec3 e_v = KW_XYZ(state.velocity) - KW_XYZ(perch.land_velocity);
        m.position = vec4(e_p.x, e_p.y, e_p.z, float(KW_MOTION_ROUTE));
        m.velocity = vec4(e_v.x, e_v.y, e_v.z, perch.land_position.w - t0);
        m.acceleration = vec4(t0, perch.land_velocity.w, bird.speed.x, 0.0f);
    }
    return m;
}

// How many neighbours a bird of `flock` heeds: k, or all it finds (up to the most) with a
// metric radius.
uint flock_k(FlockParamsGpu flock) {
    return flock.counts.y == 1u ? uint(KW_FLOCK_MAX_NEIGHBOURS) : min(flock.counts.x, uint(KW_FLOCK_MAX_NEIGHBOURS));
}

// Candidate j at offset d (d2 = dot(d, d)) offered to a bird's sorted list of k.
void flock_offer(KW_INOUT(FlockNeighbours) nb, uint k, float d2, uint j) {
    if (nb.found == k && !flock_before(d2, j, nb.d2[k - 1u], nb.j[k - 1u])) return;
    // Insertion into the sorted list, dropping the farthest when full.
    uint at = nb.found < k ? nb.found : k - 1u;
    while (at > 0u && flock_before(d2, j, nb.d2[at - 1u], nb.j[at - 1u])) {
        nb.d2[at] = nb.d2[at - 1u];
        nb.j[at] = nb.j[at - 1u];
        at -= 1u;
    }
    nb.d2[at] = d2;
    nb.j[at] = j;
    if (nb.found < k) nb.found += 1u;
}

// The neighbour search (the grid's part of the step): the k nearest birds of the flock
// within the search radius and the field of view. The 27 cells round the bird's hold
// every bird within the radius.
FlockNeighbours flock_neighbours(uint i, uint mask, float inv_radius) {
    const FlockBirdGpu bird = kw_bird(i);
    const FlockParamsGpu flock = kw_flock(bird.ids.x);
    const FlockStateGpu state = kw_state(i);
    const vec3 p = KW_XYZ(state.position);
    const vec3 forward = flock_forward(KW_XYZ(state.velocity));
    const float radius = flock.radii.x;
    const float radius2 = radius * radius;
    const uint k = flock_k(flock);
    const float own_flock = float(bird.ids.x);
    FlockNeighbours nb;
    nb.found = 0u;
    // On its perch or landing, it is not stepped: it searches for nobody.
    if (!flock_flies(bird, flock, state)) return nb;
    uint visited[27];
    uint visited_count = 0u;
    const ivec3 home = flock_cell(p, inv_radius);
    for (int dz = -1; dz <= 1; ++dz) {
        for (int dy = -1; dy <= 1; ++dy) {
            for (int dx = -1; dx <= 1; ++dx) {
                const uint b = flock_cell_bucket(flock_cell_near(home, ivec3(dx, dy, dz)), mask);
                // Two of the 27 cells may hash to one bucket: visit it once.
                bool seen = false;
                for (uint s = 0u; s < visited_count; ++s) seen = seen || visited[s] == b;
                if (seen) continue;
                visited[visited_count] = b;
                visited_count += 1u;
                const uint first = kw_bucket_start(b);
                const uint end = first + kw_bucket_count(b);
                for (uint s = first; s < end; ++s) {
                    const vec4 point = kw_point(s);
                    if (point.w != own_flock) continue;
                    const vec3 d = vec3(point.x, point.y, point.z) - p;
                    const float d2 = dot(d, d);
                    if (d2 > radius2) continue;
                    // Behind the bird, in its blind angle: not seen.
                    if (dot(d, forward) < flock.radii.z * sqrt(d2)) continue;
                    // The bird itself passes the tests above (d = 0): left out by index.
                    const uint j = kw_sorted(s);
                    if (j == i) continue;
                    flock_offer(nb, k, d2, j);
                }
            }
        }
    }
    return nb;
}

// The rules' part of the step, given the bird's neighbours (flock_neighbours(), or the cpu
// backend's own search, which finds the same list).
FlockStep flock_rules(uint i, FlockNeighbours nb, uint agents, float dt) {
    const FlockBirdGpu bird = kw_bird(i);
    const FlockParamsGpu flock = kw_flock(bird.ids.x);
    const FlockStateGpu state = kw_state(i);
    const vec3 p = KW_XYZ(state.position);
    const vec3 v = KW_XYZ(state.velocity);
    const float speed = length(v);
    const vec3 forward = flock_forward(v);
    const float radius = flock.radii.x;
    const uint found = nb.found;

    // Reynolds' rules over the neighbours, nearest first.
    vec3 separation = vec3(0.0f);
    vec3 heading = vec3(0.0f);
    vec3 centre = vec3(0.0f);
    vec3 collide = vec3(0.0f);
    const float r_sep = flock.radii.y;
    const float r_col = flock.collision.x;
    const float lookahead = flock.collision.y;
    for (uint n = 0u; n < found; ++n) {
        const FlockStateGpu other = kw_state(nb.j[n]);
        const vec3 d = KW_XYZ(other.position) - p;
        const float dist = sqrt(nb.d2[n]);
        // Hildenbrandt et al.'s separation: full within r_sep, a Gaussian beyond it; r_sep
        // grows along the flight direction by (1 + front cos^2), keeping a longer gap to
        // the bird ahead or behind than to the side (ours, docs/flocking.md).
        const float along_axis = dist > 1e-6f ? dot(d, forward) / dist : 0.0f;
        const float r_here = r_sep * (1.0f + flock.ground.w * along_axis * along_axis);
        const float over = max(dist - r_here, 0.0f) / r_here;
        const float g = exp(-(over * over));
        if (dist > 1e-6f) separation += (g / dist) * d;
        const vec3 w = KW_XYZ(other.velocity);
        const float ws = length(w);
        if (ws > 1e-6f) heading += w / ws;
        centre += d;
        // Collision avoidance, the first of Reynolds (1987)'s rules by priority, predicted
        // as his "unaligned collision avoidance" (Reynolds 1999, "Steering behaviors for
        // autonomous characters"): where the two will be nearest within the look-ahead at
        // their present velocities, t* = clamp(-d.rel / rel.rel, 0, lookahead), d* = d +
        // t* rel; nearer than r_col, the bird steers from the neighbour's place then at the
        // wing's lateral limit at contact, falling linearly to 0 at r_col, allocated before
        // the other rules with the obstacles (below). The separation alone, whose weight a
        // close neighbour shares with the bird's others, let two of scenes/starlings.json's
        // birds drift to 4 mm apart, and without the look-ahead birds closing at 2 to 5 m/s
        // after the falcon's pass met within 2 cm (docs/flocking.md).
        const vec3 rel = w - v;
        const float rel2 = dot(rel, rel);
        const float t_near = rel2 > 0.0f ? clamp(-dot(d, rel) / rel2, 0.0f, lookahead) : 0.0f;
        const vec3 near_d = d + t_near * rel;
        const float near_dist = length(near_d);
        if (near_dist < r_col) {
            const vec3 from = near_dist > 1e-6f ? near_d / near_dist : dist > 1e-6f ? d / dist : vec3(0.0f);
            collide += (bird.turn.x * (near_dist / r_col - 1.0f)) * from;
        }
    }
    // Agents, in one pass: their pushes, and panic: within a predator's reach a bird heeds
    // the flock's centre and its route the less the nearer the predator is
    // (1 - distance / reach), so that the flock can part round it and close again behind
    // it (ours, docs/flocking.md).
    vec3 fled = vec3(0.0f);
    vec3 avoid = vec3(0.0f);  // the obstacles' (spheres, capsules, planes): allocated first, below
    float panic = 0.0f;
    for (uint g = 0u; g < agents; ++g) {
        const FlockAgentGpu agent = kw_agent(g);
        const float kind = agent.kind_weight.x;
        if (kind == KW_FLOCK_AGENT_PLANE) {
            // Kept to the normal's side: within `margin` of the plane (and behind it), in
            // proportion to the depth into that layer. A bird flying into it is steered
            // across its flight at the full strength, as round a capsule below: across
            // the plane's upright (world up within the plane; a wall's is up, a floor has
            // none), so that a bird flying at a wall turns left or right in a level, banked
            // turn, and one diving at a floor pulls up (Reynolds 1999's steering). A push
            // along the normal only braked a bird flying straight at a wall, which then
            // turned as little as its angle to the wall gave; steering in the plane of its
            // flight and the normal had a diving bird dive further, into its dive limit,
            // and not turn (scenes/tower.json's cliff: birds 2.9 m into it at a 15 m
            // margin, 6.7 m at 25 m, 19 m so). One flying along it or away is pushed along
            // the normal. Dead at it: to its right (facing x up), or, flying straight down
            // at a floor, to +x.
            const vec3 n = KW_XYZ(agent.velocity);
            const float margin = max(agent.kind_weight.z, 1e-3f);
            const float depth = margin - dot(p - KW_XYZ(agent.position), n);
            if (depth > 0.0f) {
                const float s = agent.kind_weight.y * min(depth / margin, 1.0f);
                const float toward = dot(forward, n);
                vec3 away = n;
                float brake = 0.0f;
                if (toward < 0.0f) {
                    const vec3 upright = vec3(0.0f, 1.0f, 0.0f) - n.y * n;
                    const float ul = length(upright);
                    const vec3 facing = ul > 1e-3f ? flock_facing(forward, upright / ul) : forward;
                    away = flock_round(n - dot(n, facing) * facing, facing, vec3(0.0f, 1.0f, 0.0f));
                    brake = s * toward;
                }
                avoid += s * away + brake * forward;
            }
            continue;
        }
        // A capsule is avoided as the sphere round its segment's point nearest the bird,
        // steering across its axis: the bird's heading and its sides are taken in the
        // plane normal to the axis (a bird flying at a tower turns left or right, where
        // the sphere's rule would have it pitch up or down along the tower).
        vec3 at = KW_XYZ(agent.position);
        vec3 facing = forward;
        vec3 up = vec3(0.0f, 1.0f, 0.0f);
        if (kind == KW_FLOCK_AGENT_CAPSULE) {
            const vec3 ab = KW_XYZ(agent.velocity) - at;
            const float ab2 = dot(ab, ab);
            const float t = ab2 > 0.0f ? clamp(dot(p - at, ab) / ab2, 0.0f, 1.0f) : 0.0f;
            at += t * ab;
            if (ab2 > 0.0f) {
                up = ab / sqrt(ab2);
                facing = flock_facing(forward, up);
            }
        }
        const vec3 d = p - at;
        const float dist = length(d);
        const float reach = agent.position.w;
        if (dist < 1e-6f) continue;
        if (kind == KW_FLOCK_AGENT_SPHERE || kind == KW_FLOCK_AGENT_CAPSULE) {
            // Steered round, not only pushed back (Reynolds 1999's "obstacle avoidance"
            // steers laterally): a bird flying at the sphere turns across its own flight,
            // away from the sphere's centre line, since a push straight back would only
            // brake a bird heading for its centre; one moving away from it, or inside it,
            // is pushed straight out. Within `margin` of its surface, in proportion to the
            // depth into that shell.
            const float margin = max(agent.kind_weight.z, 1e-3f);
            const float depth = reach + margin - dist;
            if (depth > 0.0f) {
                const float s = agent.kind_weight.y * min(depth / margin, 1.0f);
                const float along = dot(d, facing);
                vec3 away = d / dist;
                if (along < 0.0f && dist > reach) away = flock_round(d - along * facing, facing, up);
                avoid += s * away;
            }
        } else if (dist < reach) {
            const float s = agent.kind_weight.y * (1.0f - dist / reach);
            if (kind == KW_FLOCK_AGENT_REPELLER) {
                if (agent.kind_weight.y > 0.0f) panic = max(panic, 1.0f - dist / reach);
                // Escaped by a banked turn to the side of the predator's path the bird is
                // on (starlings and pigeons turn away from an attacking falcon: Storms et
                // al. 2019, Behav Ecol Sociobiol 73:10; Papadopoulou et al. 2022, Proc R
                // Soc B 289:20212337): level, across the path, so that birds above and
                // below it turn the same way and the flock parts along the vertical plane
                // through the path and closes again behind it. Fleeing radially from the
                // path, as before, opened a tube through the flock that never split it
                // (docs/flocking.md). A predator at rest, or one diving straight down: away
                // from it, level.
                const vec3 u = KW_XYZ(agent.velocity);
                vec3 side = cross(u, vec3(0.0f, 1.0f, 0.0f));
                const float sl = length(side);
                vec3 away;
                if (sl > 1e-3f) {
                    away = (dot(d, side) >= 0.0f ? 1.0f / sl : -1.0f / sl) * side;
                } else {
                    const vec3 flat_d = vec3(d.x, 0.0f, d.z);
                    const float fl = length(flat_d);
                    away = fl > 1e-3f ? flat_d / fl : vec3(1.0f, 0.0f, 0.0f);
                }
                fled += s * away;
            } else {
                fled -= (s / dist) * d;
            }
        }
    }
    avoid += collide;
    const float calm = 1.0f - panic;
    vec3 a = vec3(0.0f);
    if (found > 0u) {
        const float inv_n = 1.0f / float(found);
        a += (-flock.weights.x * inv_n) * separation;
        const float hl = length(heading);
        if (hl > 1e-6f) a += flock.weights.y * (heading / hl - forward);
        a += (calm * flock.weights.z * inv_n / radius) * centre;
    }
    // The route: drawn to the leader's place plus the bird's formation offset, in
    // proportion within the route radius, at full weight beyond it.
    const vec3 to_target = KW_XYZ(flock.target) + KW_XYZ(bird.offset) - p;
    a += (calm * flock.weights.w / max(length(to_target), flock.radii.w)) * to_target;
    // Cruise speed: thrust towards v0 with time constant tau.
    a += ((bird.speed.x - speed) / flock.ground.z) * forward;
    // The ground: pushed up within the clearance, in proportion to the depth into it.
    if (p.y < flock.ground.x) a.y += flock.ground.y * (flock.ground.x - p.y) / flock.ground.x;
    a += fled;

    // What the wing allows: the tangential part within the largest speed change, the
    // lateral part within a coordinated turn at the largest bank (g tan(bank)).
    float along;
    vec3 lateral;
    if (dot(avoid, avoid) == 0.0f) {
        along = clamp(dot(a, forward), -bird.speed.w, bird.speed.w);
        lateral = a - dot(a, forward) * forward;
        const float ll = length(lateral);
        if (ll > bird.turn.x) lateral *= bird.turn.x / ll;
    } else {
        // Reynolds (1987)'s prioritized acceleration allocation: avoiding an obstacle takes
        // the lateral budget first and the other rules get what is left, so that the
        // flock pressing on (separation, cohesion, the route) cannot turn a bird into a
        // tower it is steering round.
        const vec3 total = a + avoid;
        along = clamp(dot(total, forward), -bird.speed.w, bird.speed.w);
        vec3 first = avoid - dot(avoid, forward) * forward;
        const float fl = length(first);
        if (fl > bird.turn.x) first *= bird.turn.x / fl;
        vec3 rest = a - dot(a, forward) * forward;
        const float budget = bird.turn.x - min(fl, bird.turn.x);
        const float rl = length(rest);
        if (rl > budget) rest *= budget / rl;
        lateral = first + rest;
    }
    a = along * forward + lateral;
    // Semi-implicit Euler; speed within [min, max], climb and dive within the wing's.
    vec3 v1 = v + dt * a;
    const float s1 = length(v1);
    const float s = clamp(s1, bird.speed.y, bird.speed.z);
    v1 = s1 > 1e-6f ? (s / s1) * v1 : s * forward;
    const float sin_pitch = v1.y / s;
    const float limited = clamp(sin_pitch, -bird.turn.z, bird.turn.y);
    if (limited != sin_pitch) {
        vec3 h = vec3(v1.x, 0.0f, v1.z);
        const float hl = length(h);
        h = hl > 1e-6f ? h / hl : vec3(1.0f, 0.0f, 0.0f);
        const float cos_pitch = sqrt(max(1.0f - limited * limited, 0.0f));
        v1 = vec3(s * cos_pitch * h.x, s * limited, s * cos_pitch * h.z);
    }
    FlockStep result;
    result.velocity = v1;
    result.position = p + dt * v1;
    result.acceleration = (v1 - v) / dt;
    return result;
}

// The whole step of bird i.
FlockStep flock_step_bird(uint i, uint mask, uint agents, float dt, float inv_radius) {
    return flock_rules(i, flock_neighbours(i, mask, inv_radius), agents, dt);
}
