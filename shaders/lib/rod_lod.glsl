// The level of detail of a character's chains (rods::Level, docs/level-of-detail.md):
// the one decision every rod backend takes, per chain, from where its character's
// reference joint sits in the camera's view, written once for GLSL
// (shaders/rods_step.comp) and C++ (engine/rods/lod.cpp, which the CPU backends call),
// so that no backend has its own rule. Every chain of a character reads the same joint
// and the same camera, so they take the same level: the level is the character's.
//
// `depth`, `right`, `up`: the reference joint from the camera, along its forward, right
// and up axes (m). `tan_x`, `tan_y`: the tangents of half the horizontal and vertical
// fields of view. `margin`: the character's size (m), by which it may stick out of the
// frustum while its joint is outside. `full_distance`: the depth within which a posed or
// hidden character turns full (its projected size reaches LodSettings::full_pixels);
// `stay_distance` (>= full_distance): the depth within which a full one stays full (the
// hysteresis band). `reduced_distance` (>= full_distance) and `reduced_stay` (>=
// reduced_distance, >= stay_distance): the same for the reduced level (its projected size
// reaches LodSettings::reduced_pixels), which a full or reduced character keeps within
// reduced_stay; both equal full_distance and stay_distance when the reduced level is off,
// and the decision is then the two-level one bit for bit. `previous`: the chain's level at
// its last step (KW_RODS_LEVEL_*).
//
// A character off the frustum by more than its size is hidden; else one nearer than
// its full distance is full, one nearer than its reduced distance reduced, and a farther
// one posed. The comparisons are of products and
// sums of a few floats: a GPU that fuses a multiply-add can differ from the CPU only for
// a character on a boundary to the last bit.
//
// KW_LOD_FN: nothing in GLSL, `inline` in C++. Float literals carry an f.
#ifndef KW_LOD_FN
#define KW_LOD_FN
#endif

KW_LOD_FN uint rod_level(float depth, float right, float up, float tan_x, float tan_y, float margin, float full_distance,
                         float stay_distance, float reduced_distance, float reduced_stay, uint previous) {
    const float across = right < 0.0f ? -right : right;
    const float above = up < 0.0f ? -up : up;
    if (depth < -margin || across > depth * tan_x + margin || above > depth * tan_y + margin) return KW_RODS_LEVEL_HIDDEN;
    if (depth <= (previous == KW_RODS_LEVEL_FULL ? stay_distance : full_distance)) return KW_RODS_LEVEL_FULL;
    const bool dynamic = previous == KW_RODS_LEVEL_FULL || previous == KW_RODS_LEVEL_REDUCED;
    return depth <= (dynamic ? reduced_stay : reduced_distance) ? KW_RODS_LEVEL_REDUCED : KW_RODS_LEVEL_POSED;
}

// Whether a hidden character is far off the view: off the frustum widened by
// KW_RODS_FAR_OFF_DEG on every side by more than its size (the arguments as rod_level's).
// The camera must turn by that angle, or move as far across, before it sees the
// character, which takes more frames than KW_RODS_HIDDEN_PERIOD at any pace short of a
// cut (20 degrees in 3 frames: 400 degrees a second). tan(a + w) = (tan a + tan w) / (1 -
// tan a tan w); a field of view that the widening takes to 90 degrees or more has no far
// side (false).
KW_LOD_FN bool rod_far_off_view(float depth, float right, float up, float tan_x, float tan_y, float margin) {
    const float w = KW_RODS_FAR_OFF_TAN;
    const float below_x = 1.0f - tan_x * w;
    const float below_y = 1.0f - tan_y * w;
    if (below_x <= 0.0f || below_y <= 0.0f) return false;
    return rod_level(depth, right, up, (tan_x + w) / below_x, (tan_y + w) / below_y, margin, 0.0f, 0.0f, 0.0f, 0.0f,
                     KW_RODS_LEVEL_HIDDEN) == KW_RODS_LEVEL_HIDDEN;
}

// Whether a chain keeps its state this frame instead of stepping (docs/level-of-detail.md,
// "The rate"): posed chains step every KW_RODS_POSED_PERIOD-th frame, hidden ones every
// KW_RODS_HIDDEN_PERIOD-th, when `turn` (the frame's number plus the character's index in
// the scene / KW_RODS_RATE_GROUP) comes round, and then over the frames they kept. Never a
// full or reduced chain, one whose level changed (`level` this frame's, `previous` its last
// step's), or one within twice its dynamic distance of the camera (|depth| <= 2
// dynamic_distance, the reduced distance, or the full one when the reduced level is off: as
// if twice as near it would be simulated), which steps every frame so that it turns full
// or reduced from a state of the frame before; but a hidden one far off the view (`far_off`,
// rod_far_off_view()) rests at any distance. Hidden chains at the view's side step every
// frame: one turns full when the camera turns to it, and a full step over 4 frames of its
// root's motion jumps (tests/backends/test_level_of_detail.cpp measured 5.0 cm at a change
// of level against 2.3 cm of full simulation when hidden chains rested at any distance).
KW_LOD_FN bool rod_rests(uint level, uint previous, float depth, float dynamic_distance, bool far_off, uint turn) {
    if (level == KW_RODS_LEVEL_FULL || level == KW_RODS_LEVEL_REDUCED || level != previous) return false;
    const bool anywhere = level == KW_RODS_LEVEL_HIDDEN && far_off;
    if (!anywhere && (depth < 0.0f ? -depth : depth) <= 2.0f * dynamic_distance) return false;
    const uint period = level == KW_RODS_LEVEL_POSED ? KW_RODS_POSED_PERIOD : KW_RODS_HIDDEN_PERIOD;
    return (turn & (period - 1u)) != 0u;
}

// The turn of a chain of the world's character `character` (its index in the world) from
// RodPush.flags.w with KW_RODS_RATE_ON set (rods_step.comp and rod_keys.comp decode it
// here, once): the frame's number plus its character's index in the whole scene /
// KW_RODS_RATE_GROUP, mod 4 (rods::rate_turn; every period divides 4).
KW_LOD_FN uint rod_rate_turn(uint rate, uint character) {
    return (rate & 3u) + (((rate >> 2u) & 15u) + character) / KW_RODS_RATE_GROUP;
}
