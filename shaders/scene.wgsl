// dda3d scene shader: lit flat-shaded solids (blocks, arrows) and screen-space thick lines
// (outlines, grid). Colours arrive in linear light; the sRGB target encodes them.

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

struct SolidIn {
    @location(0) position: vec3<f32>,
    @location(1) normal: vec3<f32>,
    @location(2) color: vec4<f32>,
};

struct SolidOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) world: vec3<f32>,
    @location(1) normal: vec3<f32>,
    @location(2) color: vec4<f32>,
};

@vertex
fn vs_solid(v: SolidIn) -> SolidOut {
    var o: SolidOut;
    o.clip = g.view_proj * vec4<f32>(v.position, 1.0);
    o.world = v.position;
    o.normal = v.normal;
    o.color = v.color;
    return o;
}

fn shade(o: SolidOut) -> vec3<f32> {
    var n = normalize(o.normal);
    // Two-sided: a face seen from behind (wrong winding, or an arrow's inside) is lit as if it
    // faced the viewer instead of going black.
    let to_eye = normalize(g.eye.xyz - o.world);
    if (dot(n, to_eye) < 0.0) {
        n = -n;
    }
    let key = max(dot(n, g.key_light.xyz), 0.0);
    let fill = max(dot(n, g.fill_light.xyz), 0.0);
    // Hemisphere ambient: upward faces a little brighter, as under an overcast sky.
    let ambient = mix(0.24, 0.36, 0.5 + 0.5 * n.z);
    // A faint highlight gives the round arrows their shape.
    let h = normalize(g.key_light.xyz + to_eye);
    let spec = pow(max(dot(n, h), 0.0), 40.0) * 0.12;
    return o.color.rgb * (ambient + 0.6 * key + 0.22 * fill) + vec3<f32>(spec);
}

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

@fragment
fn fs_solid(o: SolidOut) -> @location(0) vec4<f32> {
    return vec4<f32>(encode(shade(o)), 1.0);
}

// Hidden parts of arrows, premultiplied alpha.
@fragment
fn fs_ghost(o: SolidOut) -> @location(0) vec4<f32> {
    let a = g.params.x;
    return vec4<f32>(encode(shade(o)) * a, a);
}

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
