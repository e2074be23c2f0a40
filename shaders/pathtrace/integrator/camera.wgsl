// The camera: pinhole rays, and rays through a thin lens (depth of field).
// requires: var frame (integrator/pathtrace.wgsl)
#import "pathtrace/scene_types.wgsl"
#import "pathtrace/integrator/sampler.wgsl"
#import "common/sampling.wgsl"

// The pinhole ray through image position `u` within `pixel`.
fn pinhole_ray(pixel: vec2u, u: vec2f) -> Ray {
    let cam = frame.camera;
    let size = vec2f(f32(frame.settings.width), f32(frame.settings.height));
    let xy = (vec2f(pixel) + u) / size;
    let dir = cam.forward + (2.0 * xy.x - 1.0) * cam.tan_half_fov * cam.aspect * cam.right
        - (2.0 * xy.y - 1.0) * cam.tan_half_fov * cam.up;
    return Ray(cam.position, normalize(dir));
}

fn camera_ray(pixel: vec2u, u: vec2f) -> Ray {
    let cam = frame.camera;
    var ray = pinhole_ray(pixel, u);
    if cam.aperture_radius > 0.0 {
        let lens = cam.aperture_radius * sample_disk(sample_2d(PAIR_LENS));
        let focus = cam.position + ray.dir * (cam.focus_distance / dot(ray.dir, cam.forward));
        ray.origin = cam.position + lens.x * cam.right + lens.y * cam.up;
        ray.dir = normalize(focus - ray.origin);
    }
    return ray;
}

// The spread angle of a pixel's ray cone (Akenine-Moller et al. 2021, eq. 30): the angle a
// pixel subtends at the image's center, atan(2 tan(fov / 2) / height).
fn pixel_spread() -> f32 {
    return atan(2.0 * frame.camera.tan_half_fov / f32(frame.settings.height));
}
