#version 450
#include "constants.glsl"
// Exposure pass: the log-average luminance of the HDR image over a
// regular grid of its pixels (every STEP-th in x and y, at most ~65k
// samples, so the pass costs about as much as an empty full-screen pass),
// and from it the exposure that maps it to middle grey: 0.18 / Lavg.
// One workgroup: each invocation sums a strided share of the grid, then a
// shared-memory tree adds the partial sums.

layout(local_size_x = EXPOSURE_GROUP_SIZE) in;
layout(set = 0, binding = EXPOSURE_HDR_BINDING) uniform sampler2D hdr;
layout(set = 0, binding = EXPOSURE_BUFFER_BINDING, std430) writeonly buffer Exposure {
    float exposure;
};
layout(constant_id = SPEC_EXPOSURE_STEP) const int STEP = 1;

// Sum and count per invocation; float sums of up to ~256 samples each
// keep the rounding well below what the 8-bit output shows.
shared float sums[EXPOSURE_GROUP_SIZE];
// Below this a sample counts as black.
const float MIN_LUMINANCE = 1e-4;
shared uint counts[EXPOSURE_GROUP_SIZE];

void main() {
    ivec2 size = textureSize(hdr, 0);
    ivec2 grid = (size + STEP - 1) / STEP;
    int samples = grid.x * grid.y;
    uint id = gl_LocalInvocationID.x;
    float sum = 0.0;
    uint count = 0u;
    for (int i = int(id); i < samples; i += EXPOSURE_GROUP_SIZE) {
        ivec2 p = ivec2(i % grid.x, i / grid.x) * STEP;
        vec3 c = texelFetch(hdr, p, 0).rgb;
        float l = dot(c, vec3(0.2126, 0.7152, 0.0722));
        // Black samples (space, an empty background) and NaN and Inf ones
        // say nothing about the brightness of what is in view: counted,
        // half a frame of space would push the exposure of a planet seen
        // from orbit up until the planet is white. A NaN fails both
        // comparisons.
        if (l >= MIN_LUMINANCE && l <= 3.0e38) {
            sum += log(l);
            count += 1u;
        }
    }
    sums[id] = sum;
    counts[id] = count;
    barrier();
    for (uint half_size = EXPOSURE_GROUP_SIZE / 2; half_size > 0u; half_size /= 2u) {
        if (id < half_size) {
            sums[id] += sums[id + half_size];
            counts[id] += counts[id + half_size];
        }
        barrier();
    }
    if (id == 0u) {
        // Nothing but black or non-finite samples: a neutral exposure.
        float mean = counts[0] > 0u ? sums[0] / float(counts[0]) : log(0.18);
        exposure = clamp(0.18 / exp(mean), 1e-6, 1e6);
    }
}
