// Lit, flat-shaded triangles: block faces and contact arrows (render/solids.rs,
// render/arrows.rs). Needs globals.wgsl.

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
