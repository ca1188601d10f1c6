// The scene's per-frame uniform block and output encoding, shared by every primitive's shader
// (solid.wgsl, line.wgsl): the renderer prepends this file to each. Colours arrive in linear
// light; an sRGB target encodes them in hardware, any other target through `encode`.

struct Globals {
    view_proj: mat4x4<f32>,
    // xyz: eye position (relative to the scene origin).
    eye: vec4<f32>,
    // xyz: unit vector toward the key light.
    key_light: vec4<f32>,
    // xyz: unit vector toward the fill light.
    fill_light: vec4<f32>,
    // x, y: target size in pixels; z: line-width scale; w: fraction of the eye distance by
    // which line endpoints are pulled toward the eye so outlines win the depth test against
    // the faces they lie on.
    viewport: vec4<f32>,
    // x: opacity of the "hidden arrow" pass; y: 1 when the target is not sRGB and the shader
    // must encode the output itself.
    params: vec4<f32>,
};

@group(0) @binding(0) var<uniform> g: Globals;

// Linear light → the target's encoding (identity for sRGB targets, which encode in hardware).
fn encode(c: vec3<f32>) -> vec3<f32> {
    if (g.params.y < 0.5) {
        return c;
    }
    let x = clamp(c, vec3<f32>(0.0), vec3<f32>(1.0));
    let lo = x * 12.92;
    let hi = 1.055 * pow(x, vec3<f32>(1.0 / 2.4)) - 0.055;
    return select(hi, lo, x <= vec3<f32>(0.0031308));
}
