//! One run on a wgpu device: the shadow pass into a depth texture (one layer per cube face),
//! the lit pass into colour (RGBA8), visibility (R32Float, exact) and face id (R32Uint)
//! targets, readback. Row padding for texture-to-buffer copies (256 bytes) is handled once,
//! in [`read_texture`]. Every wgpu call of a run sits inside a validation error scope, and the
//! device's uncaptured-error handler records rather than panics, so a wgpu or driver error
//! fails the run with its message.

use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use umbra_case::format::{
    Attachments, Cull, DepthFormat, DepthOrder, Filter, MipFilter, MipSource, Mipmaps, Outside,
};
use umbra_case::technique::CompareOp;
use umbra_case::{
    BackendError, Clock, Convention, DepthMap, Frame, LightKind, LookupMatrices, Prepared,
    Technique,
};

use crate::shaders::{self, UNIFORM_SIZE};

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

    fn render_inner(&self, run: &Prepared) -> Result<Frame, BackendError> {
        let start = Instant::now();
        let case = run.case();
        let s = &case.shadow;
        // A deliberate mistake, only under `cargo xtask selftest`.
        let fault = umbra_case::fault::Fault::active();
        let is = |f: umbra_case::fault::Fault| fault == Some(f);
        // The GL-depth-range fault builds every matrix with the [-1,1] convention.
        let conv = if is(umbra_case::fault::Fault::GlDepthRange) {
            Convention::GL
        } else {
            Convention::ZERO_TO_ONE
        }
        .with_order(s.depth_order);
        let cube = matches!(run.light.kind, LightKind::Point { .. });
        let d = &self.device;
        let verts = run.geometry.interleaved();
        let count = (verts.len() / umbra_case::Geometry::VERTEX_FLOATS) as u32;
        let vbo = d.create_buffer(&wgpu::BufferDescriptor {
            label: Some("vertices"),
            size: (verts.len() * 4) as u64,
            usage: wgpu::BufferUsages::VERTEX | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        self.queue.write_buffer(&vbo, 0, &f32_bytes(&verts));

        // Shadow pass.
        let [mw, mh] = s.size;
        let faces = run.light.views.len() as u32;
        let format = texture_format(s.format);
        let copyable = self.depth_copies && format != wgpu::TextureFormat::Depth24Plus;
        // A mipmapped map's levels, and how many of them shadow passes draw (the rest are
        // averaged from the level above: MipSource::Averaged).
        let levels = s.mipmaps.map_or(1, |m| m.levels);
        let drawn_levels = match s.mipmaps {
            Some(m) if m.source == MipSource::Averaged => 1,
            _ => levels,
        };
        let map = d.create_texture(&wgpu::TextureDescriptor {
            label: Some("shadow map"),
            size: wgpu::Extent3d {
                width: mw,
                height: mh,
                depth_or_array_layers: faces,
            },
            mip_level_count: levels,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format,
            usage: wgpu::TextureUsages::RENDER_ATTACHMENT
                | wgpu::TextureUsages::TEXTURE_BINDING
                | if copyable {
                    wgpu::TextureUsages::COPY_SRC
                } else {
                    wgpu::TextureUsages::empty()
                },
            view_formats: &[],
        });
        let with_color = s.attachments == Attachments::WithColor;
        let shadow_module = d.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("shadow"),
            source: wgpu::ShaderSource::Wgsl(shaders::shadow(with_color).into()),
        });
        let uniform_layout = d.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("shadow uniforms"),
            entries: &[uniform_entry(wgpu::ShaderStages::VERTEX)],
        });
        let shadow_layout = d.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("shadow"),
            bind_group_layouts: &[Some(&uniform_layout)],
            immediate_size: 0,
        });
        // The case's bias as the (faulted) backend applies it.
        let faulted_bias = fault.map_or_else(|| s.bias.clone(), |f| f.bias(&s.bias));
        let [factor, units] = faulted_bias.polygon_offset;
        let sign = conv.toward_far();
        let bias = wgpu::DepthBiasState {
            // Whole numbers only (supports() refuses others); a threshold fault's units are
            // rounded, and its sweep skips points that rounding would change.
            constant: (sign * units).round() as i32,
            slope_scale: sign * factor,
            clamp: sign * faulted_bias.polygon_offset_clamp,
        };
        let position_only = [wgpu::VertexAttribute {
            format: wgpu::VertexFormat::Float32x3,
            offset: 0,
            shader_location: 0,
        }];
        let color_target = [Some(wgpu::ColorTargetState::from(
            wgpu::TextureFormat::Rgba8Unorm,
        ))];
        // Cube faces are rendered with y flipped, which reverses their winding; a face the
        // self-test draws mirrored gets the other front face too.
        let normal_front = if cube {
            wgpu::FrontFace::Cw
        } else {
            wgpu::FrontFace::Ccw
        };
        let shadow_pipeline_for = |front_face| {
            d.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
                label: Some("shadow"),
                layout: Some(&shadow_layout),
                vertex: wgpu::VertexState {
                    module: &shadow_module,
                    entry_point: Some("vs"),
                    compilation_options: Default::default(),
                    buffers: &[Some(wgpu::VertexBufferLayout {
                        array_stride: STRIDE,
                        step_mode: wgpu::VertexStepMode::Vertex,
                        attributes: &position_only,
                    })],
                },
                primitive: wgpu::PrimitiveState {
                    front_face,
                    cull_mode: match s.cull {
                        Cull::None => None,
                        Cull::Back => Some(wgpu::Face::Back),
                        Cull::Front => Some(wgpu::Face::Front),
                    },
                    ..Default::default()
                },
                depth_stencil: Some(wgpu::DepthStencilState {
                    format,
                    depth_write_enabled: Some(true),
                    depth_compare: Some(if s.depth_order == DepthOrder::Forward {
                        wgpu::CompareFunction::Less
                    } else {
                        wgpu::CompareFunction::Greater
                    }),
                    stencil: Default::default(),
                    bias,
                }),
                multisample: Default::default(),
                fragment: with_color.then(|| wgpu::FragmentState {
                    module: &shadow_module,
                    entry_point: Some("fs"),
                    compilation_options: Default::default(),
                    targets: &color_target,
                }),
                multiview_mask: None,
                cache: None,
            })
        };
        let shadow_pipeline = shadow_pipeline_for(normal_front);
        let mirrored_pipeline = fault
            .is_some_and(|f| (0..6).any(|k| f.face_mistake(k, cube).is_some_and(|(_, m)| m)))
            .then(|| {
                shadow_pipeline_for(match normal_front {
                    wgpu::FrontFace::Cw => wgpu::FrontFace::Ccw,
                    wgpu::FrontFace::Ccw => wgpu::FrontFace::Cw,
                })
            });
        // As many levels as the map: a pass's attachments must have one size.
        let dummy = with_color.then(|| {
            d.create_texture(&wgpu::TextureDescriptor {
                label: Some("dummy colour"),
                size: wgpu::Extent3d {
                    width: mw,
                    height: mh,
                    depth_or_array_layers: 1,
                },
                mip_level_count: levels,
                sample_count: 1,
                dimension: wgpu::TextureDimension::D2,
                format: wgpu::TextureFormat::Rgba8Unorm,
                usage: wgpu::TextureUsages::RENDER_ATTACHMENT,
                view_formats: &[],
            })
        });
        let dummy_views: Vec<wgpu::TextureView> = dummy
            .as_ref()
            .map(|t| {
                (0..levels)
                    .map(|level| {
                        t.create_view(&wgpu::TextureViewDescriptor {
                            base_mip_level: level,
                            mip_level_count: Some(1),
                            ..Default::default()
                        })
                    })
                    .collect()
            })
            .unwrap_or_default();
        let timestamps = self
            .features
            .contains(wgpu::Features::TIMESTAMP_QUERY)
            .then(|| {
                d.create_query_set(&wgpu::QuerySetDescriptor {
                    label: Some("passes"),
                    ty: wgpu::QueryType::Timestamp,
                    count: 4,
                })
            });
        let shadow_start = Instant::now();
        let mut encoder = d.create_command_encoder(&wgpu::CommandEncoderDescriptor {
            label: Some("shadow"),
        });
        let mut face_buffers = Vec::new();
        // Every face, and on a mipmapped map every level its source draws.
        let passes: Vec<(u32, u32)> = (0..faces)
            .flat_map(|k| (0..drawn_levels).map(move |level| (k, level)))
            .collect();
        let last_pass = passes.len() - 1;
        for (pass_index, &(k, level)) in passes.iter().enumerate() {
            let [lw, lh] = Mipmaps::level_size(s.size, level);
            let mut m = run.light.views[k as usize].view_proj(conv);
            // A face drawn with a wrong orientation (the self-test's Oriented fault), before
            // the convention's flip so that it moves the content as on GL.
            let mistake = fault.and_then(|f| f.face_mistake(k as usize, cube));
            if let Some((wrong, _)) = mistake {
                m = wrong * m;
            }
            // A shift of the image (ShadowHalfTexel, the shadow-shift sweep) in texels along
            // the map's u and v as GL lays them out: 2 · t / size in NDC, before the cube
            // face's flip; a 2D map's rows run down here, so +v is −y.
            let [sx, sy] = fault.map_or([0.0; 2], |f| f.shadow_shift_texels());
            if sx != 0.0 || sy != 0.0 {
                let sy = if cube { sy } else { -sy };
                m = glam::Mat4::from_translation(glam::Vec3::new(
                    2.0 * sx / lw as f32,
                    2.0 * sy / lh as f32,
                    0.0,
                )) * m;
            }
            if cube {
                m = conv.cube_face_render_flip() * m;
            }
            let ub = uniform_buffer(
                d,
                &self.queue,
                m,
                &[],
                &[],
                [0.0; 4],
                [0.0; 4],
                [0.0; 4],
                [0.0; 4],
                [0.0; 4],
            );
            let bg = d.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("shadow face"),
                layout: &uniform_layout,
                entries: &[wgpu::BindGroupEntry {
                    binding: 0,
                    resource: ub.as_entire_binding(),
                }],
            });
            let view = map.create_view(&wgpu::TextureViewDescriptor {
                dimension: Some(wgpu::TextureViewDimension::D2),
                base_array_layer: k,
                array_layer_count: Some(1),
                base_mip_level: level,
                mip_level_count: Some(1),
                ..Default::default()
            });
            let color = dummy_views
                .get(level as usize)
                .map(|v| wgpu::RenderPassColorAttachment {
                    view: v,
                    depth_slice: None,
                    resolve_target: None,
                    ops: wgpu::Operations {
                        load: wgpu::LoadOp::Clear(wgpu::Color::BLACK),
                        store: wgpu::StoreOp::Store,
                    },
                });
            let colors = [color];
            let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("shadow pass"),
                color_attachments: if with_color { &colors } else { &[] },
                depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                    view: &view,
                    depth_ops: Some(wgpu::Operations {
                        load: wgpu::LoadOp::Clear(conv.clear_depth()),
                        store: wgpu::StoreOp::Store,
                    }),
                    stencil_ops: None,
                }),
                // The shadow pass spans all faces: stamp the start of the first, the end of the last.
                timestamp_writes: timestamps
                    .as_ref()
                    .filter(|_| pass_index == 0 || pass_index == last_pass)
                    .map(|q| wgpu::RenderPassTimestampWrites {
                        query_set: q,
                        beginning_of_pass_write_index: (pass_index == 0).then_some(0),
                        end_of_pass_write_index: (pass_index == last_pass).then_some(1),
                    }),
                occlusion_query_set: None,
                multiview_mask: None,
            });
            match (&mirrored_pipeline, mistake) {
                (Some(p), Some((_, true))) => pass.set_pipeline(p),
                _ => pass.set_pipeline(&shadow_pipeline),
            }
            if is(umbra_case::fault::Fault::ShadowViewport) {
                // The camera's viewport left in place (clipped to the map).
                let [cw, ch] = run.camera.size;
                pass.set_viewport(0.0, 0.0, cw.min(lw) as f32, ch.min(lh) as f32, 0.0, 1.0);
            }
            pass.set_bind_group(0, &bg, &[]);
            pass.set_vertex_buffer(0, vbo.slice(..));
            pass.draw(0..count, 0..1);
            drop(pass);
            face_buffers.push((ub, bg));
        }
        if drawn_levels < levels {
            self.average_levels(&mut encoder, &map, format, levels);
        }
        self.queue.submit([encoder.finish()]);
        self.wait()?;
        let shadow_wall = shadow_start.elapsed();

        // Lit pass.
        let technique = Technique::new(run, fault);
        let manual = technique.manual();
        let lit_module = d.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("lit"),
            source: wgpu::ShaderSource::Wgsl(shaders::lit(&technique).into()),
        });
        let view_dimension = match (cube, manual) {
            (false, _) => wgpu::TextureViewDimension::D2,
            (true, false) => wgpu::TextureViewDimension::Cube,
            (true, true) => wgpu::TextureViewDimension::D2Array,
        };
        let mut entries = vec![
            uniform_entry(wgpu::ShaderStages::VERTEX | wgpu::ShaderStages::FRAGMENT),
            wgpu::BindGroupLayoutEntry {
                binding: 1,
                visibility: wgpu::ShaderStages::FRAGMENT,
                ty: wgpu::BindingType::Texture {
                    sample_type: wgpu::TextureSampleType::Depth,
                    view_dimension,
                    multisampled: false,
                },
                count: None,
            },
        ];
        if !manual {
            entries.push(wgpu::BindGroupLayoutEntry {
                binding: 2,
                visibility: wgpu::ShaderStages::FRAGMENT,
                ty: wgpu::BindingType::Sampler(wgpu::SamplerBindingType::Comparison),
                count: None,
            });
        }
        let lit_bgl = d.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("lit"),
            entries: &entries,
        });
        let lit_layout = d.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("lit"),
            bind_group_layouts: &[Some(&lit_bgl)],
            immediate_size: 0,
        });
        let attributes = [
            wgpu::VertexAttribute {
                format: wgpu::VertexFormat::Float32x3,
                offset: 0,
                shader_location: 0,
            },
            wgpu::VertexAttribute {
                format: wgpu::VertexFormat::Float32x3,
                offset: 12,
                shader_location: 1,
            },
            wgpu::VertexAttribute {
                format: wgpu::VertexFormat::Float32x3,
                offset: 24,
                shader_location: 2,
            },
            wgpu::VertexAttribute {
                format: wgpu::VertexFormat::Float32,
                offset: 36,
                shader_location: 3,
            },
        ];
        let targets = [
            Some(wgpu::ColorTargetState::from(
                wgpu::TextureFormat::Rgba8Unorm,
            )),
            Some(wgpu::ColorTargetState::from(self.vis_format)),
            Some(wgpu::ColorTargetState::from(wgpu::TextureFormat::R32Uint)),
        ];
        let lit_pipeline = d.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
            label: Some("lit"),
            layout: Some(&lit_layout),
            vertex: wgpu::VertexState {
                module: &lit_module,
                entry_point: Some("vs"),
                compilation_options: Default::default(),
                buffers: &[Some(wgpu::VertexBufferLayout {
                    array_stride: STRIDE,
                    step_mode: wgpu::VertexStepMode::Vertex,
                    attributes: &attributes,
                })],
            },
            primitive: wgpu::PrimitiveState {
                cull_mode: None,
                ..Default::default()
            },
            depth_stencil: Some(wgpu::DepthStencilState {
                format: wgpu::TextureFormat::Depth32Float,
                depth_write_enabled: Some(true),
                depth_compare: Some(wgpu::CompareFunction::Less),
                stencil: Default::default(),
                bias: Default::default(),
            }),
            multisample: Default::default(),
            fragment: Some(wgpu::FragmentState {
                module: &lit_module,
                entry_point: Some("fs"),
                compilation_options: Default::default(),
                targets: &targets,
            }),
            multiview_mask: None,
            cache: None,
        });
        let mut light = Vec::new();
        let mut tex = Vec::new();
        for v in &run.light.views {
            let m = LookupMatrices::new(conv, v.view_proj(conv));
            light.push(m.light);
            tex.push(m.texture);
        }
        let (pos, towards) = match run.light.kind {
            // A directional light's eye is read only by an N·L bias towards its position.
            LightKind::Directional { towards, position } => (position, towards),
            LightKind::Spot { position } | LightKind::Point { position } => {
                (position, glam::Vec3::ZERO)
            }
        };
        let eye = run.camera.eye;
        let b = &faulted_bias;
        let (slope_scale, slope_max) = b.slope.map_or((0.0, 0.0), |sl| (sl.scale, sl.max));
        let (ndl_scale, ndl_min) = b.n_dot_l.map_or((0.0, 0.0), |nl| (nl.scale, nl.min));
        let ub = uniform_buffer(
            d,
            &self.queue,
            run.camera.view_proj(conv),
            &light,
            &tex,
            [pos.x, pos.y, pos.z, 0.0],
            [towards.x, towards.y, towards.z, 0.0],
            [eye.x, eye.y, eye.z, 0.0],
            [mw as f32, mh as f32, ndl_scale, ndl_min],
            [b.constant, slope_scale, slope_max, b.normal_offset],
        );
        // The mip faults: level 0 alone, or the levels from 1 on.
        let (base_mip_level, mip_level_count) = match fault {
            Some(umbra_case::fault::Fault::MipBaseOnly) => (0, Some(1)),
            Some(umbra_case::fault::Fault::MipLevelCoarse) if levels > 1 => (1, None),
            _ => (0, None),
        };
        let map_view = map.create_view(&wgpu::TextureViewDescriptor {
            dimension: Some(view_dimension),
            base_mip_level,
            mip_level_count,
            ..Default::default()
        });
        let sampler = (!manual).then(|| {
            self.sampler(
                s.filter,
                s.mipmaps.map(|m| m.filter),
                technique.texel_wrap(),
                technique.compare_op(),
                cube,
            )
        });
        let mut group_entries = vec![
            wgpu::BindGroupEntry {
                binding: 0,
                resource: ub.as_entire_binding(),
            },
            wgpu::BindGroupEntry {
                binding: 1,
                resource: wgpu::BindingResource::TextureView(&map_view),
            },
        ];
        if let Some(samp) = &sampler {
            group_entries.push(wgpu::BindGroupEntry {
                binding: 2,
                resource: wgpu::BindingResource::Sampler(samp),
            });
        }
        let lit_bg = d.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("lit"),
            layout: &lit_bgl,
            entries: &group_entries,
        });
        let [w, h] = run.camera.size;
        let target = |format, label| {
            d.create_texture(&wgpu::TextureDescriptor {
                label: Some(label),
                size: wgpu::Extent3d {
                    width: w,
                    height: h,
                    depth_or_array_layers: 1,
                },
                mip_level_count: 1,
                sample_count: 1,
                dimension: wgpu::TextureDimension::D2,
                format,
                usage: wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_SRC,
                view_formats: &[],
            })
        };
        let color_tex = target(wgpu::TextureFormat::Rgba8Unorm, "colour");
        let vis_tex = target(self.vis_format, "visibility");
        let face_tex = target(wgpu::TextureFormat::R32Uint, "face");
        let depth_tex = target(wgpu::TextureFormat::Depth32Float, "camera depth");
        let views = [&color_tex, &vis_tex, &face_tex].map(|t| t.create_view(&Default::default()));
        let depth_view = depth_tex.create_view(&Default::default());
        let clear = |c: wgpu::Color| wgpu::Operations {
            load: wgpu::LoadOp::Clear(c),
            store: wgpu::StoreOp::Store,
        };
        let lit_start = Instant::now();
        let mut encoder =
            d.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some("lit") });
        {
            let attach = |i: usize, c: wgpu::Color| {
                Some(wgpu::RenderPassColorAttachment {
                    view: &views[i],
                    depth_slice: None,
                    resolve_target: None,
                    ops: clear(c),
                })
            };
            let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("lit pass"),
                color_attachments: &[
                    attach(0, wgpu::Color::BLACK),
                    attach(1, wgpu::Color::TRANSPARENT),
                    attach(2, wgpu::Color::TRANSPARENT),
                ],
                depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                    view: &depth_view,
                    depth_ops: Some(wgpu::Operations {
                        load: wgpu::LoadOp::Clear(1.0),
                        store: wgpu::StoreOp::Store,
                    }),
                    stencil_ops: None,
                }),
                timestamp_writes: timestamps
                    .as_ref()
                    .map(|q| wgpu::RenderPassTimestampWrites {
                        query_set: q,
                        beginning_of_pass_write_index: Some(2),
                        end_of_pass_write_index: Some(3),
                    }),
                occlusion_query_set: None,
                multiview_mask: None,
            });
            pass.set_pipeline(&lit_pipeline);
            pass.set_bind_group(0, &lit_bg, &[]);
            pass.set_vertex_buffer(0, vbo.slice(..));
            pass.draw(0..count, 0..1);
        }
        let stamps = timestamps.as_ref().map(|q| {
            let resolve = d.create_buffer(&wgpu::BufferDescriptor {
                label: Some("timestamps"),
                size: 32,
                usage: wgpu::BufferUsages::QUERY_RESOLVE | wgpu::BufferUsages::COPY_SRC,
                mapped_at_creation: false,
            });
            encoder.resolve_query_set(q, 0..4, &resolve, 0);
            resolve
        });
        self.queue.submit([encoder.finish()]);
        self.wait()?;
        let lit_wall = lit_start.elapsed();
        let read = |t: &wgpu::Texture| -> Result<Vec<u8>, BackendError> {
            let rows = read_texture(self, t, 4, w, h, wgpu::TextureAspect::All)?;
            // The flip a GL-minded port adds by mistake.
            Ok(if is(umbra_case::fault::Fault::NoYFlip) {
                rows.chunks((w * 4) as usize)
                    .rev()
                    .flatten()
                    .copied()
                    .collect()
            } else {
                rows
            })
        };
        let color = read(&color_tex)?;
        let vis = read(&vis_tex)?;
        let face = read(&face_tex)?;
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
        let shadow_map = if copyable {
            let mut values = Vec::with_capacity((mw * mh * faces) as usize);
            for layer in 0..faces {
                let bpp = if format == wgpu::TextureFormat::Depth16Unorm {
                    2
                } else {
                    4
                };
                let bytes = read_layer(
                    self,
                    &map,
                    bpp,
                    mw,
                    mh,
                    layer,
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
                values.extend(if cube {
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
            Some(DepthMap {
                width: mw,
                height: mh,
                layers: faces,
                format: s.format,
                values,
            })
        } else {
            None
        };
        let gpu_times = match stamps {
            Some(buf) => Some(read_buffer(self, &buf, 32)?),
            None => None,
        };
        let (shadow_pass, lit_pass, clock) = match gpu_times {
            Some(bytes) => {
                let t: Vec<u64> = bytes
                    .chunks_exact(8)
                    .map(|b| u64::from_ne_bytes([b[0], b[1], b[2], b[3], b[4], b[5], b[6], b[7]]))
                    .collect();
                let period = f64::from(self.queue.get_timestamp_period());
                let ns = |a: u64, b: u64| {
                    Duration::from_nanos((b.saturating_sub(a) as f64 * period) as u64)
                };
                let (sp, lp) = (ns(t[0], t[1]), ns(t[2], t[3]));
                if sp <= shadow_wall && lp <= lit_wall {
                    (sp, lp, Clock::Gpu)
                } else {
                    (shadow_wall, lit_wall, Clock::CpuWall)
                }
            }
            None => (shadow_wall, lit_wall, Clock::CpuWall),
        };
        let total = start.elapsed();
        drop(face_buffers);
        Ok(Frame {
            width: w,
            height: h,
            color,
            visibility,
            surface: Some(surface),
            shadow_map,
            visibility_storage: if self.vis_format == wgpu::TextureFormat::R32Float {
                umbra_case::VisibilityStorage::Float32
            } else {
                umbra_case::VisibilityStorage::Unorm8
            },
            timings: umbra_case::Timings {
                shadow_pass,
                lit_pass,
                readback: total.saturating_sub(shadow_wall + lit_wall),
                total,
                clock: Some(clock),
            },
        })
    }

    /// Records the passes that fill levels 1.. of the 2D `map` (`levels` in all, level 0
    /// drawn) with the mean of the level above ([`shaders::AVERAGE`]), as a program
    /// generating depth mips does: each pass reads one level through a view of that level
    /// alone and writes the next as its depth attachment.
    fn average_levels(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        map: &wgpu::Texture,
        format: wgpu::TextureFormat,
        levels: u32,
    ) {
        let d = &self.device;
        let module = d.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("mip average"),
            source: wgpu::ShaderSource::Wgsl(shaders::AVERAGE.into()),
        });
        let layout = d.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("mip average"),
            entries: &[wgpu::BindGroupLayoutEntry {
                binding: 0,
                visibility: wgpu::ShaderStages::FRAGMENT,
                ty: wgpu::BindingType::Texture {
                    sample_type: wgpu::TextureSampleType::Depth,
                    view_dimension: wgpu::TextureViewDimension::D2,
                    multisampled: false,
                },
                count: None,
            }],
        });
        let pipeline_layout = d.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("mip average"),
            bind_group_layouts: &[Some(&layout)],
            immediate_size: 0,
        });
        let pipeline = d.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
            label: Some("mip average"),
            layout: Some(&pipeline_layout),
            vertex: wgpu::VertexState {
                module: &module,
                entry_point: Some("vs"),
                compilation_options: Default::default(),
                buffers: &[],
            },
            primitive: Default::default(),
            depth_stencil: Some(wgpu::DepthStencilState {
                format,
                depth_write_enabled: Some(true),
                depth_compare: Some(wgpu::CompareFunction::Always),
                stencil: Default::default(),
                bias: Default::default(),
            }),
            multisample: Default::default(),
            fragment: Some(wgpu::FragmentState {
                module: &module,
                entry_point: Some("fs"),
                compilation_options: Default::default(),
                targets: &[],
            }),
            multiview_mask: None,
            cache: None,
        });
        let level_view = |level: u32| {
            map.create_view(&wgpu::TextureViewDescriptor {
                dimension: Some(wgpu::TextureViewDimension::D2),
                base_array_layer: 0,
                array_layer_count: Some(1),
                base_mip_level: level,
                mip_level_count: Some(1),
                ..Default::default()
            })
        };
        for level in 1..levels {
            let src = level_view(level - 1);
            let dst = level_view(level);
            let bg = d.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("mip average"),
                layout: &layout,
                entries: &[wgpu::BindGroupEntry {
                    binding: 0,
                    resource: wgpu::BindingResource::TextureView(&src),
                }],
            });
            let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("mip average"),
                color_attachments: &[],
                depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                    view: &dst,
                    depth_ops: Some(wgpu::Operations {
                        load: wgpu::LoadOp::Clear(1.0),
                        store: wgpu::StoreOp::Store,
                    }),
                    stencil_ops: None,
                }),
                timestamp_writes: None,
                occlusion_query_set: None,
                multiview_mask: None,
            });
            pass.set_pipeline(&pipeline);
            pass.set_bind_group(0, &bg, &[]);
            pass.draw(0..3, 0..1);
        }
    }

    /// The compare sampler. A border reads as far for the compare in use (1 for `<=`, 0 for
    /// `>=`); a cube map clamps to the edge whatever the wrap.
    fn sampler(
        &self,
        filter: Filter,
        mip: Option<MipFilter>,
        wrap: Outside,
        op: CompareOp,
        cube: bool,
    ) -> wgpu::Sampler {
        let far_is_one = matches!(op, CompareOp::LessEqual | CompareOp::Less);
        let (address, border) = match (cube, wrap) {
            (true, _) | (false, Outside::Lit | Outside::ClampToEdge) => {
                (wgpu::AddressMode::ClampToEdge, None)
            }
            (false, Outside::Repeat) => (wgpu::AddressMode::Repeat, None),
            (false, Outside::Border) => (
                wgpu::AddressMode::ClampToBorder,
                Some(if far_is_one {
                    wgpu::SamplerBorderColor::OpaqueWhite
                } else {
                    wgpu::SamplerBorderColor::TransparentBlack
                }),
            ),
        };
        let f = if filter == Filter::Linear {
            wgpu::FilterMode::Linear
        } else {
            wgpu::FilterMode::Nearest
        };
        self.device.create_sampler(&wgpu::SamplerDescriptor {
            label: Some("shadow compare"),
            address_mode_u: address,
            address_mode_v: address,
            address_mode_w: address,
            mag_filter: f,
            min_filter: f,
            mipmap_filter: match mip {
                Some(MipFilter::Linear) => wgpu::MipmapFilterMode::Linear,
                _ => wgpu::MipmapFilterMode::Nearest,
            },
            compare: Some(match op {
                CompareOp::LessEqual => wgpu::CompareFunction::LessEqual,
                CompareOp::GreaterEqual => wgpu::CompareFunction::GreaterEqual,
                CompareOp::Less => wgpu::CompareFunction::Less,
                CompareOp::Greater => wgpu::CompareFunction::Greater,
            }),
            border_color: border,
            ..Default::default()
        })
    }
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

#[allow(clippy::too_many_arguments)]
fn uniform_buffer(
    d: &wgpu::Device,
    q: &wgpu::Queue,
    view_proj: glam::Mat4,
    light: &[glam::Mat4],
    tex: &[glam::Mat4],
    light_pos: [f32; 4],
    towards: [f32; 4],
    eye: [f32; 4],
    size: [f32; 4],
    bias: [f32; 4],
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
    for v in [light_pos, towards, eye, size, bias] {
        data.extend_from_slice(&v);
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
