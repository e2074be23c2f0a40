// AutoExposure, pass 1: the luminance histogram of `input` (bins in
// post/luminance_bins.wgsl), counted per 16×16 tile in workgroup memory, then added to
// `bins` (cleared before the pass).
#import "post/luminance_bins.wgsl"

@group(0) @binding(0) var input: texture_2d<f32>;
@group(0) @binding(1) var<storage, read_write> bins: array<atomic<u32>, 256>;

var<workgroup> tile: array<atomic<u32>, 256>;

@compute @workgroup_size(16, 16)
fn main(
    @builtin(global_invocation_id) id: vec3u,
    @builtin(local_invocation_index) local: u32,
) {
    atomicStore(&tile[local], 0u);
    workgroupBarrier();
    let size = textureDimensions(input);
    if id.x < size.x && id.y < size.y {
        let bin = luminance_bin(textureLoad(input, id.xy, 0).rgb);
        if bin < HISTOGRAM_BINS {
            atomicAdd(&tile[bin], 1u);
        }
    }
    workgroupBarrier();
    let n = atomicLoad(&tile[local]);
    if n > 0u {
        atomicAdd(&bins[local], n);
    }
}
