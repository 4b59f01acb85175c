//! What comes back from the driver: the shadow map's depths (GL 3.3 only: GLES cannot read
//! depth with glReadPixels), and the visibility target decoded into visibility and surface
//! ids. GL rows are bottom first: images are flipped once, in [`super::flip_rows`].

use umbra_case::{BackendError, DepthMap};

use super::{Renderer, RunPlan, flip_rows};
use crate::record::Readback;

impl Renderer {
    /// Every face of `map`, read as DEPTH_COMPONENT floats from the shadow pass's framebuffer
    /// (still bound), rows top first, faces in order.
    pub(super) fn read_map(
        &self,
        p: &RunPlan,
        map: glow::Texture,
    ) -> Result<DepthMap, BackendError> {
        let gl = &self.g();
        let [mw, mh] = p.s.size;
        let mut values = Vec::with_capacity((mw * mh) as usize * p.faces);
        // SAFETY: reading DEPTH_COMPONENT as FLOAT from the complete shadow framebuffer.
        unsafe {
            for (k, ft) in p.face_targets().into_iter().enumerate() {
                p.attach_depth(gl, ft, k, map, 0);
                let mut bytes = vec![0u8; (mw * mh * 4) as usize];
                gl.tag_readback(Readback::MapLayer(k as u32));
                gl.read_pixels(
                    0,
                    0,
                    mw as i32,
                    mh as i32,
                    glow::DEPTH_COMPONENT,
                    glow::FLOAT,
                    glow::PixelPackData::Slice(Some(&mut bytes)),
                );
                let layer: Vec<f32> = bytes
                    .chunks_exact(4)
                    .map(|b| f32::from_ne_bytes([b[0], b[1], b[2], b[3]]))
                    .collect();
                values.extend(flip_rows(&layer, mw as usize));
            }
        }
        self.check("shadow map readback")?;
        Ok(DepthMap {
            width: mw,
            height: mh,
            layers: p.faces as u32,
            format: p.s.format,
            values,
        })
    }
}

/// The visibility target (R: visibility in 1/255; G + 256 B + 65536 A: face id + 1, 0 where
/// nothing was drawn) as visibility (NaN where uncovered) and surface ids.
pub(super) fn decode_visibility(vis: &[u8]) -> (Vec<f32>, Vec<u32>) {
    let mut visibility = Vec::with_capacity(vis.len() / 4);
    let mut surface = Vec::with_capacity(vis.len() / 4);
    for px in vis.chunks_exact(4) {
        let id = u32::from(px[1]) + 256 * u32::from(px[2]) + 65536 * u32::from(px[3]);
        surface.push(id);
        visibility.push(if id == 0 {
            f32::NAN
        } else {
            f32::from(px[0]) / 255.0
        });
    }
    (visibility, surface)
}
