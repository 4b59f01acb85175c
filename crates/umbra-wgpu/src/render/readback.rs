//! What comes back from the device: the lit pass's targets decoded into colour, visibility
//! (exact R32Float, or 8 bits on wgpu's GL backend) and surface ids; the shadow map's depths
//! where the adapter copies depth (cube faces back to light-view rows); the passes' GPU
//! times, trusted only when they fit in the wall time waited for them.

use std::time::Duration;

use umbra_case::{BackendError, Clock, DepthMap};

use super::lit_pass::LitTargets;
use super::{RunPlan, read_buffer, read_layer, read_texture};
use crate::render::Gpu;

/// The lit pass's outputs: colour (RGBA8), visibility (NaN where nothing was drawn), surface
/// ids (face id + 1, 0 where nothing was drawn).
pub(super) struct Outputs {
    pub(super) color: Vec<u8>,
    pub(super) visibility: Vec<f32>,
    pub(super) surface: Vec<u32>,
}

impl Gpu {
    /// Reads and decodes the lit pass's targets.
    pub(super) fn read_outputs(
        &self,
        p: &RunPlan,
        targets: &LitTargets,
    ) -> Result<Outputs, BackendError> {
        let [w, h] = p.run.camera.size;
        let read = |t: &wgpu::Texture| -> Result<Vec<u8>, BackendError> {
            let rows = read_texture(self, t, 4, w, h, wgpu::TextureAspect::All)?;
            // The flip a GL-minded port adds by mistake.
            Ok(if p.is(umbra_case::fault::Fault::NoYFlip) {
                rows.chunks((w * 4) as usize)
                    .rev()
                    .flatten()
                    .copied()
                    .collect()
            } else {
                rows
            })
        };
        let color = read(&targets.color)?;
        let vis = read(&targets.vis)?;
        let face = read(&targets.face)?;
        let mut visibility = Vec::with_capacity((w * h) as usize);
        let mut surface = Vec::with_capacity((w * h) as usize);
        for (v, f) in vis.chunks_exact(4).zip(face.chunks_exact(4)) {
            let id = u32::from_ne_bytes([f[0], f[1], f[2], f[3]]);
            surface.push(id);
            let value = if self.vis_format == wgpu::TextureFormat::R32Float {
                f32::from_ne_bytes([v[0], v[1], v[2], v[3]])
            } else {
                f32::from(v[0]) / 255.0
            };
            visibility.push(if id == 0 { f32::NAN } else { value });
        }
        Ok(Outputs {
            color,
            visibility,
            surface,
        })
    }

    /// The map's level 0, every face, as depths in [0, 1] (D16 codes / 65535), rows top
    /// first in the light's view; None where the adapter cannot copy this format.
    pub(super) fn read_map(
        &self,
        p: &RunPlan,
        map: &wgpu::Texture,
    ) -> Result<Option<DepthMap>, BackendError> {
        if !p.copyable {
            return Ok(None);
        }
        let [mw, mh] = p.s.size;
        let bpp = if p.format == wgpu::TextureFormat::Depth16Unorm {
            2
        } else {
            4
        };
        let mut values = Vec::with_capacity((mw * mh * p.faces) as usize);
        for layer in 0..p.faces {
            let bytes = read_layer(
                self,
                map,
                bpp,
                mw,
                mh,
                p.layer_base + layer,
                wgpu::TextureAspect::DepthOnly,
            )?;
            let layer_values: Vec<f32> = if bpp == 2 {
                bytes
                    .chunks_exact(2)
                    .map(|b| (f64::from(u16::from_ne_bytes([b[0], b[1]])) / 65535.0) as f32)
                    .collect()
            } else {
                bytes
                    .chunks_exact(4)
                    .map(|b| f32::from_ne_bytes([b[0], b[1], b[2], b[3]]))
                    .collect()
            };
            // Cube faces were rendered with rows flipped: store them light-view top first.
            values.extend(if p.cube {
                layer_values
                    .chunks(mw as usize)
                    .rev()
                    .flatten()
                    .copied()
                    .collect()
            } else {
                layer_values
            });
        }
        Ok(Some(DepthMap {
            width: mw,
            height: mh,
            layers: p.faces,
            format: p.s.format,
            values,
        }))
    }

    /// The shadow and lit passes' times, each summed over the lights: the GPU's timestamps
    /// where they were written and fit in the wall times, else the wall times.
    pub(super) fn pass_times(
        &self,
        stamps: Option<wgpu::Buffer>,
        shadow_wall: Duration,
        lit_wall: Duration,
    ) -> Result<(Duration, Duration, Clock), BackendError> {
        let Some(buf) = stamps else {
            return Ok((shadow_wall, lit_wall, Clock::CpuWall));
        };
        let bytes = read_buffer(self, &buf, buf.size())?;
        let t: Vec<u64> = bytes
            .chunks_exact(8)
            .map(|b| u64::from_ne_bytes([b[0], b[1], b[2], b[3], b[4], b[5], b[6], b[7]]))
            .collect();
        let period = f64::from(self.queue.get_timestamp_period());
        let ns =
            |a: u64, b: u64| Duration::from_nanos((b.saturating_sub(a) as f64 * period) as u64);
        // Each light's four queries: its shadow pass's start and end, its lit pass's.
        let (sp, lp) = t
            .chunks_exact(4)
            .fold((Duration::ZERO, Duration::ZERO), |(sp, lp), q| {
                (sp + ns(q[0], q[1]), lp + ns(q[2], q[3]))
            });
        Ok(if sp <= shadow_wall && lp <= lit_wall {
            (sp, lp, Clock::Gpu)
        } else {
            (shadow_wall, lit_wall, Clock::CpuWall)
        })
    }
}
