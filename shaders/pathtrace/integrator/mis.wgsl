// Multiple importance sampling of direct light: the weights of a BSDF-sampled hit on an
// emitter and of a light sample (power heuristic, or one strategy alone: `frame.strategy`).
// requires: var frame (integrator/pathtrace.wgsl)
#import "common/sampling.wgsl"

const STRATEGY_MIS: u32 = 0u;
const STRATEGY_LIGHT: u32 = 1u;
const STRATEGY_BSDF: u32 = 2u;

// Weight of emission that a BSDF-sampled ray (solid-angle pdf `bsdf_pdf`, 0 after a mirror,
// an interface or from the camera) finds where light sampling has pdf `light_pdf`.
fn hit_weight(bsdf_pdf: f32, light_pdf: f32) -> f32 {
    if bsdf_pdf == 0.0 || frame.strategy == STRATEGY_BSDF {
        return 1.0;
    }
    return select(mis_power(bsdf_pdf, light_pdf), 0.0, frame.strategy == STRATEGY_LIGHT);
}

// Weight of a light sample of pdf `light_pdf` where BSDF sampling has pdf `bsdf_pdf`.
fn light_weight(light_pdf: f32, bsdf_pdf: f32) -> f32 {
    return select(mis_power(light_pdf, bsdf_pdf), 1.0, frame.strategy == STRATEGY_LIGHT);
}
