// egui's meshes for the window (ui/painter.rs): sRGB-encoded vertex colours and textures,
// premultiplied alpha, positions in egui points. A plain `textureSample`, without egui-wgpu's
// run-time choice of filtering, which Mesa's software rasterizer runs about four times slower.

struct Locals { screen_size: vec2<f32>, _pad: vec2<f32> };
@group(0) @binding(0) var<uniform> locals: Locals;
@group(1) @binding(0) var tex: texture_2d<f32>;
@group(1) @binding(1) var samp: sampler;

struct VOut {
    @builtin(position) pos: vec4<f32>,
    @location(0) uv: vec2<f32>,
    @location(1) color: vec4<f32>,
};

@vertex
fn vs(@location(0) p: vec2<f32>, @location(1) uv: vec2<f32>, @location(2) c: u32) -> VOut {
    var out: VOut;
    out.pos = vec4<f32>(2.0 * p.x / locals.screen_size.x - 1.0,
                        1.0 - 2.0 * p.y / locals.screen_size.y, 0.0, 1.0);
    out.uv = uv;
    out.color = unpack4x8unorm(c);
    return out;
}

@fragment
fn fs(in: VOut) -> @location(0) vec4<f32> {
    return in.color * textureSample(tex, samp, in.uv);
}
