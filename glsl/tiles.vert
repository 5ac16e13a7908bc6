#version 450
// Screen tiles of the deferred lighting pass, given in normalized device
// coordinates. Depth 0 is the far plane (reversed Z), so with a LESS test
// against the stored depth only pixels that hold a surface are shaded.
layout(location = 0) in vec2 in_ndc;

void main() {
    gl_Position = vec4(in_ndc, 0.0, 1.0);
}
