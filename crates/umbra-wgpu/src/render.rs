//! One run on a wgpu device: the shadow pass into a depth texture (one layer per cube face),
//! the lit pass into colour (RGBA8), visibility (R32Float, exact) and face id (R32Uint)
//! targets, readback. Row padding for texture-to-buffer copies (256 bytes) is handled once,
//! in [`read_texture`]. Every wgpu call of a run sits inside a validation error scope, and the
//! device's uncaptured-error handler records rather than panics, so a wgpu or driver error
//! fails the run with its message.
//!
//! `Gpu::render` runs the stages in order over a `RunPlan` (what every stage reads, decided
//! once): upload, [`shadow_pass`], [`lit_pass`], [`readback`], the frame.

use std::sync::{Arc, Mutex};
use std::time::Instant;

use umbra_case::fault::Fault;
use umbra_case::format::{DepthFormat, MipSource};
use umbra_case::{BackendError, Convention, Frame, LightRun, Prepared, Technique};

use crate::shaders::UNIFORM_SIZE;

mod lit_pass;
mod readback;
mod shadow_pass;

/// Bytes per vertex of `Geometry::interleaved`.
const STRIDE: u64 = 4 * umbra_case::Geometry::VERTEX_FLOATS as u64;

/// A device and what we learned about its adapter.
pub struct Gpu {
    /// The device, reused across runs.
    pub device: wgpu::Device,
    /// Its queue.
    pub queue: wgpu::Queue,
    /// What the adapter says about itself.
    pub info: wgpu::AdapterInfo,
    /// Features enabled on the device.
    pub features: wgpu::Features,
    /// Errors the device reported outside a scope.
    pub uncaptured: Arc<Mutex<Vec<String>>>,
    /// The visibility target: R32Float where renderable (exact), else Rgba8Unorm (8 bits,
    /// wgpu's GL backend).
    pub vis_format: wgpu::TextureFormat,
    /// Whether depth textures can be copied to buffers (not on wgpu's GL backend).
    pub depth_copies: bool,
    /// Whether a depth bias clamp is allowed (DownlevelFlags::DEPTH_BIAS_CLAMP; wgpu's GL
    /// backend has no glPolygonOffsetClamp path).
    pub depth_bias_clamp: bool,
    /// Whether cube-array views can be made (DownlevelFlags::CUBE_ARRAY_TEXTURES: Vulkan's
    /// imageCubeArray feature; GL 4.0 or GLES 3.2 on wgpu's GL backend).
    pub cube_arrays: bool,
}

/// wgpu's cull mode for `cull`: the shadow pass's `shadow.cull`, the lit pass's `camera.cull`.
fn cull_mode(cull: umbra_case::format::Cull) -> Option<wgpu::Face> {
    use umbra_case::format::Cull;
    match cull {
        Cull::None => None,
        Cull::Back => Some(wgpu::Face::Back),
        Cull::Front => Some(wgpu::Face::Front),
    }
}

fn err(stage: &str, message: impl Into<String>) -> BackendError {
    BackendError::Api {
        stage: stage.into(),
        message: message.into(),
    }
}

/// The wgpu format for a case's depth format. `unsized` and `depth24` are Depth24Plus, the
/// format whose precision the adapter picks (at least 24 bits; see `Gpu::depth24plus`).
pub fn texture_format(f: DepthFormat) -> wgpu::TextureFormat {
    match f {
        DepthFormat::Depth16 => wgpu::TextureFormat::Depth16Unorm,
        DepthFormat::Unsized | DepthFormat::Depth24 => wgpu::TextureFormat::Depth24Plus,
        DepthFormat::Depth32f => wgpu::TextureFormat::Depth32Float,
    }
}

impl Gpu {
    /// Runs `f` inside a validation and out-of-memory error scope named `stage`.
    pub fn scoped<T>(
        &self,
        stage: &str,
        f: impl FnOnce() -> Result<T, BackendError>,
    ) -> Result<T, BackendError> {
        let validation = self.device.push_error_scope(wgpu::ErrorFilter::Validation);
        let memory = self.device.push_error_scope(wgpu::ErrorFilter::OutOfMemory);
        let out = f();
        let oom = pollster::block_on(memory.pop());
        let invalid = pollster::block_on(validation.pop());
        if let Some(e) = oom.or(invalid) {
            return Err(err(stage, e.to_string()));
        }
        if let Ok(mut v) = self.uncaptured.lock() {
            if !v.is_empty() {
                return Err(err(stage, v.drain(..).collect::<Vec<_>>().join("; ")));
            }
        }
        out
    }

    fn wait(&self) -> Result<(), BackendError> {
        self.device
            .poll(wgpu::PollType::wait_indefinitely())
            .map(|_| ())
            .map_err(|e| err("wait", e.to_string()))
    }

    /// Renders one run.
    pub fn render(&self, run: &Prepared) -> Result<Frame, BackendError> {
        self.scoped("run", || self.render_inner(run))
    }

    /// One run, in stages, as the GL backend renders one (`render_with` there): the triangles
    /// uploaded once; every light's shadow pass into its own map or its layer of one 2D array,
    /// all in one submission; then every light's lit pass over the same targets, the later
    /// ones added into the colour ([`Gpu::encode_added`]), each submitted and its visibility
    /// read back on its own; every map read back. Each light's passes write their own
    /// timestamps (queries 4k to 4k + 3), so a stage's GPU time is the sum over the lights.
    fn render_inner(&self, run: &Prepared) -> Result<Frame, BackendError> {
        let start = Instant::now();
        let plans: Vec<RunPlan> = run.lights.iter().map(|r| RunPlan::new(r, self)).collect();
        let array = run.case().maps_share_array();
        let vbo = self.upload(&run.geometry);
        let maps: Vec<wgpu::Texture> = if array {
            // The first light's plan sizes the array for every light's layer.
            plans
                .first()
                .map(|p| self.create_map(p))
                .into_iter()
                .collect()
        } else {
            plans.iter().map(|p| self.create_map(p)).collect()
        };
        let map_of = |k: usize| if array { &maps[0] } else { &maps[k] };
        let timestamps = self
            .features
            .contains(wgpu::Features::TIMESTAMP_QUERY)
            .then(|| {
                self.device.create_query_set(&wgpu::QuerySetDescriptor {
                    label: Some("passes"),
                    ty: wgpu::QueryType::Timestamp,
                    count: 4 * plans.len() as u32,
                })
            });
        let shadow_wall = self.shadow_passes(&plans, &vbo, &map_of, timestamps.as_ref())?;
        let targets = self.lit_targets(&plans[0]);
        let mut lit_wall = std::time::Duration::ZERO;
        let mut outputs = Vec::new();
        for (k, p) in plans.iter().enumerate() {
            let technique = Technique::new(p.run, p.fault);
            let lit = self.lit_pipeline(p, &technique, k > 0);
            // The map light k reads: its own, unless the self-test mixes the lights up (in
            // an array the layer is the shader's, Technique::layer).
            let read = if array {
                map_of(k)
            } else {
                &maps[Fault::map_of_light(p.fault, k, plans.len(), false, |j| plans[j].cube)]
            };
            let bindings = self.lit_bindings(p, &technique, &lit, read);
            let lit_start = Instant::now();
            let mut enc = self.encoding("lit", &vbo, timestamps.as_ref());
            if k == 0 {
                self.encode_lit(p, &lit, &bindings, &targets, &mut enc);
            } else {
                self.encode_added(p, &lit, &bindings, &targets, &mut enc);
            }
            self.queue.submit([enc.encoder.finish()]);
            self.wait()?;
            lit_wall += lit_start.elapsed();
            outputs.push(self.read_outputs(p, &targets)?);
        }
        let stamps = timestamps.as_ref().map(|q| self.resolve(q));
        let mut stored = Vec::new();
        for (k, p) in plans.iter().enumerate() {
            stored.push(self.read_map(p, map_of(k))?);
        }
        let (shadow_pass, lit_pass, clock) = self.pass_times(stamps, shadow_wall, lit_wall)?;
        let total = start.elapsed();
        let [w, h] = run.camera.size;
        // Every light added: the last pass's colour.
        let color = outputs
            .last_mut()
            .map(|o| std::mem::take(&mut o.color))
            .ok_or_else(|| err("run", "a case without a light".to_string()))?;
        let lights = outputs
            .into_iter()
            .zip(stored)
            .map(|(o, shadow_map)| umbra_case::LightPlane {
                visibility: o.visibility,
                shadow_map,
                surface: Some(o.surface),
            })
            .collect();
        Ok(Frame {
            width: w,
            height: h,
            color,
            lights,
            visibility_storage: self.visibility_storage(),
            timings: umbra_case::Timings {
                shadow_pass,
                lit_pass,
                readback: total.saturating_sub(shadow_wall + lit_wall),
                total,
                clock: Some(clock),
            },
        })
    }

    /// Every light's shadow pass (its map `map_of(k)`), all in one submission, waited for:
    /// the wall time from the submission's recording to its end. Pipelines are made before
    /// the clock starts.
    fn shadow_passes<'m>(
        &self,
        plans: &[RunPlan],
        vbo: &wgpu::Buffer,
        map_of: &dyn Fn(usize) -> &'m wgpu::Texture,
        timestamps: Option<&wgpu::QuerySet>,
    ) -> Result<std::time::Duration, BackendError> {
        let shadow: Vec<_> = plans
            .iter()
            .map(|p| (self.shadow_pipelines(p), self.dummy_views(p)))
            .collect();
        let shadow_start = Instant::now();
        let mut enc = self.encoding("shadow", vbo, timestamps);
        // What the recorded passes reference, kept until they are submitted.
        let mut recorded = Vec::new();
        for (k, (p, (pipelines, dummy_views))) in plans.iter().zip(&shadow).enumerate() {
            recorded.push(self.encode_shadow(p, map_of(k), pipelines, dummy_views, &mut enc));
        }
        self.queue.submit([enc.encoder.finish()]);
        self.wait()?;
        let shadow_wall = shadow_start.elapsed();
        drop(recorded);
        Ok(shadow_wall)
    }

    /// Every light's timestamps (`q`) resolved into a buffer, in a submission of its own.
    fn resolve(&self, q: &wgpu::QuerySet) -> wgpu::Buffer {
        let count = q.count();
        let resolve = self.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("timestamps"),
            size: 8 * u64::from(count),
            usage: wgpu::BufferUsages::QUERY_RESOLVE | wgpu::BufferUsages::COPY_SRC,
            mapped_at_creation: false,
        });
        let mut encoder = self
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("timestamps"),
            });
        encoder.resolve_query_set(q, 0..count, &resolve, 0);
        self.queue.submit([encoder.finish()]);
        resolve
    }

    /// How the visibility target stores values: R32Float where the adapter renders to it,
    /// else RGBA8.
    fn visibility_storage(&self) -> umbra_case::VisibilityStorage {
        if self.vis_format == wgpu::TextureFormat::R32Float {
            umbra_case::VisibilityStorage::Float32
        } else {
            umbra_case::VisibilityStorage::Unorm8
        }
    }

    /// A command encoder for one stage, with what its passes draw with.
    fn encoding<'e>(
        &self,
        label: &str,
        vbo: &'e wgpu::Buffer,
        timestamps: Option<&'e wgpu::QuerySet>,
    ) -> Encoding<'e> {
        Encoding {
            vbo,
            timestamps,
            encoder: self
                .device
                .create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some(label) }),
        }
    }

    /// The run's vertices, interleaved as `Geometry::interleaved` lays them out.
    fn upload(&self, geometry: &umbra_case::Geometry) -> wgpu::Buffer {
        let verts = geometry.interleaved();
        let vbo = self.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("vertices"),
            size: (verts.len() * 4) as u64,
            usage: wgpu::BufferUsages::VERTEX | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        self.queue.write_buffer(&vbo, 0, &f32_bytes(&verts));
        vbo
    }
}

/// A stage's command encoder and what its passes draw with: the run's vertices and the
/// timestamp queries (light k's 4k, 4k + 1: its shadow pass; 4k + 2, 4k + 3: its lit pass).
struct Encoding<'e> {
    vbo: &'e wgpu::Buffer,
    timestamps: Option<&'e wgpu::QuerySet>,
    encoder: wgpu::CommandEncoder,
}

/// What every stage of a run reads, decided once from the case and the device.
struct RunPlan<'a> {
    run: &'a LightRun,
    s: &'a umbra_case::format::Shadow,
    /// A deliberate mistake, only under `cargo xtask selftest`.
    fault: Option<Fault>,
    /// wgpu's [0, 1] clip range in the case's depth order (the GL-depth-range fault builds
    /// every matrix with GL's [-1, 1] instead).
    conv: Convention,
    /// A cube map (point light): six layers.
    cube: bool,
    /// An array: one layer per cascade, or the lights' maps in one array's layers (with
    /// `cube`, a cube-map array: six layers per point light).
    layered: bool,
    /// Faces (layers) of the map.
    faces: u32,
    /// The array's layer of face 0: the light's among several (`shadow.placement` `array`;
    /// 6 · its cube in a `cube_array`), else 0.
    layer_base: u32,
    /// The array's layers: the faces, or the lights sharing it (six each in a cube array).
    array_layers: u32,
    /// The map's format, and whether its depths can be copied back.
    format: wgpu::TextureFormat,
    copyable: bool,
    /// The map's mip levels, and how many of them shadow passes draw (the rest are averaged
    /// from the level above: MipSource::Averaged).
    levels: u32,
    drawn_levels: u32,
    /// Vertices drawn.
    count: u32,
    /// The case's bias as the (faulted) backend applies it.
    bias: umbra_case::format::Bias,
}

impl<'a> RunPlan<'a> {
    fn new(run: &'a LightRun, gpu: &Gpu) -> RunPlan<'a> {
        let s = &run.case().shadow;
        let fault = Fault::active();
        let conv = if fault == Some(Fault::GlDepthRange) {
            Convention::GL
        } else {
            Convention::ZERO_TO_ONE
        }
        .with_order(s.depth_order);
        let format = texture_format(s.format);
        let levels = s.mipmaps.map_or(1, |m| m.levels);
        let array = Some(run.of_lights).filter(|o| o.array);
        let cube = run.light.is_cube();
        // Light k's faces (six for a cube) start at layer k · faces of the lights' array.
        let faces = run.light.views.len();
        RunPlan {
            run,
            s,
            fault,
            conv,
            cube,
            layered: run.light.cascading.is_some() || array.is_some(),
            faces: faces as u32,
            layer_base: array.map_or(0, |o| o.light * faces) as u32,
            array_layers: (array.map_or(1, |o| o.lights) * faces) as u32,
            format,
            copyable: gpu.depth_copies && format != wgpu::TextureFormat::Depth24Plus,
            levels,
            drawn_levels: match s.mipmaps {
                Some(m) if m.source == MipSource::Averaged => 1,
                _ => levels,
            },
            count: (run.geometry.triangles.len() * 3) as u32,
            bias: fault.map_or_else(|| s.bias.clone(), |f| f.bias(&s.bias)),
        }
    }

    /// Whether `f` is the active self-test fault.
    fn is(&self, f: Fault) -> bool {
        self.fault == Some(f)
    }
}

/// A render pass that writes depth only, into `view` cleared to 1 (the mip averaging and
/// the Depth24Plus probe's ramp).
pub fn depth_only_pass<'e>(
    encoder: &'e mut wgpu::CommandEncoder,
    label: &str,
    view: &wgpu::TextureView,
) -> wgpu::RenderPass<'e> {
    encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
        label: Some(label),
        color_attachments: &[],
        depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
            view,
            depth_ops: Some(wgpu::Operations {
                load: wgpu::LoadOp::Clear(1.0),
                store: wgpu::StoreOp::Store,
            }),
            stencil_ops: None,
        }),
        timestamp_writes: None,
        occlusion_query_set: None,
        multiview_mask: None,
    })
}

fn uniform_entry(visibility: wgpu::ShaderStages) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding: 0,
        visibility,
        ty: wgpu::BindingType::Buffer {
            ty: wgpu::BufferBindingType::Uniform,
            has_dynamic_offset: false,
            min_binding_size: None,
        },
        count: None,
    }
}

/// The uniform block ([`crate::shaders::UNIFORMS`]): the camera, six light and six texture
/// matrices (identity past those given), then its vectors in order (light_pos, towards, eye,
/// size, bias, view_row, split[0], split[1]; zero past those given).
fn uniform_buffer(
    d: &wgpu::Device,
    q: &wgpu::Queue,
    view_proj: glam::Mat4,
    light: &[glam::Mat4],
    tex: &[glam::Mat4],
    vectors: &[[f32; 4]],
) -> wgpu::Buffer {
    let mut data: Vec<f32> = Vec::with_capacity((UNIFORM_SIZE / 4) as usize);
    data.extend_from_slice(&view_proj.to_cols_array());
    for set in [light, tex] {
        for k in 0..6 {
            data.extend_from_slice(
                &set.get(k)
                    .copied()
                    .unwrap_or(glam::Mat4::IDENTITY)
                    .to_cols_array(),
            );
        }
    }
    for k in 0..10 {
        data.extend_from_slice(&vectors.get(k).copied().unwrap_or([0.0; 4]));
    }
    let buf = d.create_buffer(&wgpu::BufferDescriptor {
        label: Some("uniforms"),
        size: UNIFORM_SIZE,
        usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    });
    q.write_buffer(&buf, 0, &f32_bytes(&data));
    buf
}

/// Native-endian bytes of floats (the crate forbids `unsafe`, so no reinterpreting cast).
fn f32_bytes(v: &[f32]) -> Vec<u8> {
    v.iter().flat_map(|f| f.to_ne_bytes()).collect()
}

/// Reads a whole single-layer texture, removing the 256-byte row padding.
pub fn read_texture(
    gpu: &Gpu,
    t: &wgpu::Texture,
    bpp: u32,
    w: u32,
    h: u32,
    aspect: wgpu::TextureAspect,
) -> Result<Vec<u8>, BackendError> {
    read_layer(gpu, t, bpp, w, h, 0, aspect)
}

/// Reads one array layer of a texture into tightly packed rows (the one place that knows about
/// wgpu's 256-byte `bytes_per_row` alignment).
fn read_layer(
    gpu: &Gpu,
    t: &wgpu::Texture,
    bpp: u32,
    w: u32,
    h: u32,
    layer: u32,
    aspect: wgpu::TextureAspect,
) -> Result<Vec<u8>, BackendError> {
    let row = w * bpp;
    let padded =
        row.div_ceil(wgpu::COPY_BYTES_PER_ROW_ALIGNMENT) * wgpu::COPY_BYTES_PER_ROW_ALIGNMENT;
    let buf = gpu.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("readback"),
        size: u64::from(padded * h),
        usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ,
        mapped_at_creation: false,
    });
    let mut encoder = gpu
        .device
        .create_command_encoder(&wgpu::CommandEncoderDescriptor {
            label: Some("readback"),
        });
    encoder.copy_texture_to_buffer(
        wgpu::TexelCopyTextureInfo {
            texture: t,
            mip_level: 0,
            origin: wgpu::Origin3d {
                x: 0,
                y: 0,
                z: layer,
            },
            aspect,
        },
        wgpu::TexelCopyBufferInfo {
            buffer: &buf,
            layout: wgpu::TexelCopyBufferLayout {
                offset: 0,
                bytes_per_row: Some(padded),
                rows_per_image: Some(h),
            },
        },
        wgpu::Extent3d {
            width: w,
            height: h,
            depth_or_array_layers: 1,
        },
    );
    gpu.queue.submit([encoder.finish()]);
    let bytes = read_buffer(gpu, &buf, u64::from(padded * h))?;
    Ok(bytes
        .chunks(padded as usize)
        .flat_map(|r| r[..row as usize].to_vec())
        .collect())
}

fn read_buffer(gpu: &Gpu, buf: &wgpu::Buffer, size: u64) -> Result<Vec<u8>, BackendError> {
    let staging;
    let source = if buf.usage().contains(wgpu::BufferUsages::MAP_READ) {
        buf
    } else {
        staging = gpu.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("staging"),
            size,
            usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ,
            mapped_at_creation: false,
        });
        let mut encoder = gpu
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("staging"),
            });
        encoder.copy_buffer_to_buffer(buf, 0, &staging, 0, size);
        gpu.queue.submit([encoder.finish()]);
        &staging
    };
    let (tx, rx) = std::sync::mpsc::channel();
    source.slice(..).map_async(wgpu::MapMode::Read, move |r| {
        let _ = tx.send(r);
    });
    gpu.wait()?;
    rx.recv()
        .map_err(|e| err("readback", e.to_string()))?
        .map_err(|e| err("readback", e.to_string()))?;
    let view = source
        .slice(..)
        .get_mapped_range()
        .map_err(|e| err("readback", format!("{e:?}")))?;
    let bytes = view.to_vec();
    drop(view);
    source.unmap();
    Ok(bytes)
}
