// Contact arrows, instanced (render/arrows.rs): one unit arrow template (render/arrow_mesh.rs)
// placed per arrow. Needs globals.wgsl and solid.wgsl (SolidOut, fs_solid, fs_ghost).
// `ArrowInstance::vertex` in render/arrow_mesh.rs is this shader's formula in Rust, tested there.

struct ArrowIn {
    // Template: direction around the axis (cos, sin) and part (station, radius, normal).
    @location(0) ring: vec2<f32>,
    @location(1) part: vec3<f32>,
    // Instance.
    @location(2) base: vec3<f32>,
    @location(3) length: f32,
    @location(4) dir: vec3<f32>,
    @location(5) shaft_radius: f32,
    @location(6) head: vec2<f32>,
    @location(7) color: vec4<f32>,
};

@vertex
fn vs_arrow(v: ArrowIn) -> SolidOut {
    let d = v.dir;
    // An orthonormal pair perpendicular to d (Duff et al. 2017).
    let sign = select(-1.0, 1.0, d.z >= 0.0);
    let a = -1.0 / (sign + d.z);
    let b = d.x * d.y * a;
    let u = vec3<f32>(1.0 + sign * d.x * d.x * a, sign * b, -sign * d.x);
    let w = vec3<f32>(b, sign + d.y * d.y * a, -d.y);
    let r = u * v.ring.x + w * v.ring.y;
    let head_radius = v.head.x;
    let head_len = v.head.y;
    // Station: 0 base, 1 neck, 2 tip. Radius: 0 axis, 1 shaft, 2 head.
    var along = v.length;
    if (v.part.x < 0.5) {
        along = 0.0;
    } else if (v.part.x < 1.5) {
        along = v.length - head_len;
    }
    var radius = head_radius;
    if (v.part.y < 0.5) {
        radius = 0.0;
    } else if (v.part.y < 1.5) {
        radius = v.shaft_radius;
    }
    // Normal: 0 backwards, 1 radial, 2 the cone's side (radial tilted toward the tip).
    var n = -d;
    if (v.part.z > 1.5) {
        n = normalize(r * head_len + d * head_radius);
    } else if (v.part.z > 0.5) {
        n = r;
    }
    let p = v.base + d * along + r * radius;
    var o: SolidOut;
    o.clip = g.view_proj * vec4<f32>(p, 1.0);
    o.world = p;
    o.normal = n;
    o.color = v.color;
    return o;
}
