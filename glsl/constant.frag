#version 450
// The empty pass: writes one constant colour, so what is measured is the
// driver's cost of a full-screen pass and nothing the shader does.
layout(location = 0) out vec4 out_color;

void main() {
    out_color = vec4(0.25, 0.5, 0.75, 1.0);
}
