// Octahedral normal encoding (Meyer et al. 2010; Cigolle et al. 2014): a
// unit vector is projected onto the octahedron |x|+|y|+|z| = 1 and the
// lower half folded over the upper, giving two values in [-1, 1] that fit
// a two-channel signed 16-bit target. The Rust mirror and its round-trip
// test are in src/render/octahedral.rs.

vec2 sign_not_zero(vec2 v) {
    return vec2(v.x >= 0.0 ? 1.0 : -1.0, v.y >= 0.0 ? 1.0 : -1.0);
}

vec2 octahedral_encode(vec3 n) {
    vec2 p = n.xy / (abs(n.x) + abs(n.y) + abs(n.z));
    return n.z >= 0.0 ? p : (1.0 - abs(p.yx)) * sign_not_zero(p);
}

vec3 octahedral_decode(vec2 e) {
    vec3 n = vec3(e, 1.0 - abs(e.x) - abs(e.y));
    if (n.z < 0.0) {
        n.xy = (1.0 - abs(n.yx)) * sign_not_zero(n.xy);
    }
    return normalize(n);
}
