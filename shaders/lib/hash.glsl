// Wellons' "lowbias32" (hash-prospector): a 32-bit integer hash with good avalanche and
// hash(0) = 0, written once for GLSL and C++: the wind's noise lattice (lib/wind.glsl) and
// the flocking grid's spreading of far cells (lib/flock_hash.glsl). Unsigned arithmetic
// wraps the same way in both languages. KW_HASH_FN: what the including file's functions
// are (nothing in GLSL, `inline` in C++), undefined again at the end. No include guard:
// the C++ side includes it in each kernel's own namespace.
#ifndef KW_HASH_FN
#define KW_HASH_FN
#endif

// Its two multipliers, named for the cpu flocking grid's vector copy (flock_grid_simd.cpp).
#ifndef KW_LOWBIAS32_M1
#define KW_LOWBIAS32_M1 0x7feb352du
#define KW_LOWBIAS32_M2 0x846ca68bu
#endif

KW_HASH_FN uint kw_lowbias32(uint x) {
    x ^= x >> 16u;
    x *= KW_LOWBIAS32_M1;
    x ^= x >> 15u;
    x *= KW_LOWBIAS32_M2;
    x ^= x >> 16u;
    return x;
}

#undef KW_HASH_FN
