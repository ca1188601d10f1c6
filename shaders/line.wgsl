// Screen-space thick lines: block outlines and the ground grid (render/lines.rs), one instance
// per segment drawn as a six-vertex quad. Needs globals.wgsl.

struct LineIn {
    @location(0) a: vec3<f32>,
    @location(1) width: f32,
    @location(2) b: vec3<f32>,
    @location(3) color: vec4<f32>,
};

struct LineOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) color: vec4<f32>,
};

@vertex
fn vs_line(@builtin(vertex_index) vi: u32, l: LineIn) -> LineOut {
    // Quad corner: x = 0 at end a, 1 at end b; y = -1 / +1 across the line.
    var corners = array<vec2<f32>, 6>(
        vec2<f32>(0.0, -1.0), vec2<f32>(1.0, -1.0), vec2<f32>(1.0, 1.0),
        vec2<f32>(0.0, -1.0), vec2<f32>(1.0, 1.0), vec2<f32>(0.0, 1.0),
    );
    let c = corners[vi % 6u];
    var o: LineOut;
    o.color = l.color;

    let pull = g.viewport.w;
    let a = l.a + (g.eye.xyz - l.a) * pull;
    let b = l.b + (g.eye.xyz - l.b) * pull;
    var ca = g.view_proj * vec4<f32>(a, 1.0);
    var cb = g.view_proj * vec4<f32>(b, 1.0);
    // Clip to the near plane (z >= 0) first, so the on-screen direction stays meaningful for
    // segments that pass beside the eye.
    if (ca.z < 0.0 && cb.z < 0.0) {
        o.clip = vec4<f32>(2.0, 2.0, 2.0, 1.0);
        return o;
    }
    if (ca.z < 0.0) {
        ca = mix(ca, cb, ca.z / (ca.z - cb.z));
    } else if (cb.z < 0.0) {
        cb = mix(cb, ca, cb.z / (cb.z - ca.z));
    }
    let half_px = g.viewport.xy * 0.5;
    let sa = ca.xy / ca.w * half_px;
    let sb = cb.xy / cb.w * half_px;
    var dir = sb - sa;
    let len = length(dir);
    if (len < 1e-6) {
        dir = vec2<f32>(1.0, 0.0);
    } else {
        dir = dir / len;
    }
    let across = vec2<f32>(-dir.y, dir.x);
    let w = 0.5 * l.width * g.viewport.z;
    // Extend past the ends by half the width so joints between segments are filled.
    let off_px = across * (c.y * w) + dir * ((c.x * 2.0 - 1.0) * w);
    var p = ca;
    if (c.x > 0.5) {
        p = cb;
    }
    o.clip = vec4<f32>(p.xy + off_px / half_px * p.w, p.z, p.w);
    return o;
}

@fragment
fn fs_line(o: LineOut) -> @location(0) vec4<f32> {
    return vec4<f32>(encode(o.color.rgb), o.color.a);
}
