//! The shadow pass: the map (one array layer per cube face, the case's mip chain), its
//! pipeline (depth test in the case's order, culling, the depth bias; a mirrored twin for the
//! self-test's orientation faults), the dummy colour chain of `with_color`, one render pass
//! per face and drawn level, and averaged mip levels after them.

use umbra_case::fault::Fault;
use umbra_case::format::{Attachments, DepthFunc, Mipmaps};

use super::{Encoding, RunPlan, STRIDE, cull_mode, uniform_buffer, uniform_entry};
use crate::render::Gpu;
use crate::shaders;

/// The shadow pass's pipelines and their uniform layout.
pub(super) struct ShadowPipelines {
    layout: wgpu::BindGroupLayout,
    normal: wgpu::RenderPipeline,
    /// With the other front face, for a face the self-test draws mirrored.
    mirrored: Option<wgpu::RenderPipeline>,
}

/// What the recorded passes reference until they are submitted.
pub(super) type FaceResources = Vec<(wgpu::Buffer, wgpu::BindGroup)>;

impl Gpu {
    /// The map: every face a layer, every level allocated; copyable where the adapter can
    /// copy depth (not Depth24Plus, whose bytes are the adapter's own).
    ///
    /// A one-cascade array gets a second, unused layer on wgpu's GL backend: wgpu-hal's GLES
    /// backend guesses a texture's GL target from its layer count and makes a one-layer
    /// texture a GL_TEXTURE_2D, which the shader's `sampler2DArrayShadow` cannot read
    /// (gfx-rs/wgpu#2161, #4665: "GLES backend guesses the type of the texture … it checks
    /// for n == 1"; the soak's 1,000 cases found it: 2 of them read garbage). Vulkan keeps
    /// the one-layer array, a path of its own.
    pub(super) fn create_map(&self, p: &RunPlan) -> wgpu::Texture {
        let [mw, mh] = p.s.size;
        let gl_guesses_2d =
            p.layered && p.array_layers == 1 && self.info.backend == wgpu::Backend::Gl;
        self.device.create_texture(&wgpu::TextureDescriptor {
            label: Some("shadow map"),
            size: wgpu::Extent3d {
                width: mw,
                height: mh,
                depth_or_array_layers: if gl_guesses_2d { 2 } else { p.array_layers },
            },
            mip_level_count: p.levels,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format: p.format,
            usage: wgpu::TextureUsages::RENDER_ATTACHMENT
                | wgpu::TextureUsages::TEXTURE_BINDING
                | if p.copyable {
                    wgpu::TextureUsages::COPY_SRC
                } else {
                    wgpu::TextureUsages::empty()
                },
            view_formats: &[],
        })
    }

    /// The shadow pipelines: position only, the case's cull mode, depth clamp and depth
    /// order, the (faulted) polygon offset as wgpu's depth bias.
    pub(super) fn shadow_pipelines(&self, p: &RunPlan) -> ShadowPipelines {
        let d = &self.device;
        let s = p.s;
        let with_color = s.attachments == Attachments::WithColor;
        let module = d.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("shadow"),
            source: wgpu::ShaderSource::Wgsl(shaders::shadow(with_color).into()),
        });
        let layout = d.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("shadow uniforms"),
            entries: &[uniform_entry(wgpu::ShaderStages::VERTEX)],
        });
        let pipeline_layout = d.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("shadow"),
            bind_group_layouts: &[Some(&layout)],
            immediate_size: 0,
        });
        let [factor, units] = p.bias.polygon_offset;
        let sign = p.conv.toward_far();
        let bias = wgpu::DepthBiasState {
            // Whole numbers only (supports() refuses others); a threshold fault's units are
            // rounded, and its sweep skips points that rounding would change.
            constant: (sign * units).round() as i32,
            slope_scale: sign * factor,
            clamp: sign * p.bias.polygon_offset_clamp,
        };
        let clamp = umbra_case::fault::Fault::depth_clamp(p.fault, s.depth_clamp)
            && self.features.contains(wgpu::Features::DEPTH_CLIP_CONTROL);
        let position_only = [wgpu::VertexAttribute {
            format: wgpu::VertexFormat::Float32x3,
            offset: 0,
            shader_location: 0,
        }];
        let color_target = [Some(wgpu::ColorTargetState::from(
            wgpu::TextureFormat::Rgba8Unorm,
        ))];
        let pipeline_for = |front_face| {
            d.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
                label: Some("shadow"),
                layout: Some(&pipeline_layout),
                vertex: wgpu::VertexState {
                    module: &module,
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
                    cull_mode: cull_mode(s.cull),
                    // No near/far clipping, depth clamped to the viewport's [0, 1] (Vulkan's
                    // depthClampEnable, GL_DEPTH_CLAMP on wgpu's GL backend). Only with the
                    // feature: a forced clamp (the self-test's) without it stays off.
                    unclipped_depth: clamp,
                    ..Default::default()
                },
                depth_stencil: Some(wgpu::DepthStencilState {
                    format: p.format,
                    depth_write_enabled: Some(true),
                    depth_compare: Some(compare_function(umbra_case::fault::Fault::depth_func(
                        p.fault, s,
                    ))),
                    stencil: Default::default(),
                    bias,
                }),
                multisample: Default::default(),
                fragment: with_color.then(|| wgpu::FragmentState {
                    module: &module,
                    entry_point: Some("fs"),
                    compilation_options: Default::default(),
                    targets: &color_target,
                }),
                multiview_mask: None,
                cache: None,
            })
        };
        // Cube faces are rendered with y flipped, which reverses their winding; a face the
        // self-test draws mirrored gets the other front face too.
        let (front, other) = if p.cube {
            (wgpu::FrontFace::Cw, wgpu::FrontFace::Ccw)
        } else {
            (wgpu::FrontFace::Ccw, wgpu::FrontFace::Cw)
        };
        let normal = pipeline_for(front);
        let mirrored = p
            .fault
            .is_some_and(|f| (0..6).any(|k| f.face_mistake(k, p.cube).is_some_and(|(_, m)| m)))
            .then(|| pipeline_for(other));
        ShadowPipelines {
            layout,
            normal,
            mirrored,
        }
    }

    /// The dummy colour attachment of `with_color`, one view per level: a pass's attachments
    /// must have one size, so it has as many levels as the map.
    pub(super) fn dummy_views(&self, p: &RunPlan) -> Vec<wgpu::TextureView> {
        if p.s.attachments != Attachments::WithColor {
            return Vec::new();
        }
        let [mw, mh] = p.s.size;
        let t = self.device.create_texture(&wgpu::TextureDescriptor {
            label: Some("dummy colour"),
            size: wgpu::Extent3d {
                width: mw,
                height: mh,
                depth_or_array_layers: 1,
            },
            mip_level_count: p.levels,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format: wgpu::TextureFormat::Rgba8Unorm,
            usage: wgpu::TextureUsages::RENDER_ATTACHMENT,
            view_formats: &[],
        });
        (0..p.levels)
            .map(|level| {
                t.create_view(&wgpu::TextureViewDescriptor {
                    base_mip_level: level,
                    mip_level_count: Some(1),
                    ..Default::default()
                })
            })
            .collect()
    }

    /// Records one render pass per face and drawn level into `encoder` (the shadow pass's
    /// timestamps on the first and the last), and the averaged levels after them.
    pub(super) fn encode_shadow(
        &self,
        p: &RunPlan,
        map: &wgpu::Texture,
        pipelines: &ShadowPipelines,
        dummy_views: &[wgpu::TextureView],
        enc: &mut Encoding,
    ) -> FaceResources {
        let (vbo, timestamps, encoder) = (enc.vbo, enc.timestamps, &mut enc.encoder);
        let base = 4 * p.run.of_lights.light as u32;
        let mut face_buffers = Vec::new();
        // Every face, and on a mipmapped map every level its source draws.
        let passes: Vec<(u32, u32)> = (0..p.faces)
            .flat_map(|k| (0..p.drawn_levels).map(move |level| (k, level)))
            .collect();
        let last_pass = passes.len() - 1;
        for (pass_index, &(k, level)) in passes.iter().enumerate() {
            let [lw, lh] = Mipmaps::level_size(p.s.size, level);
            let ub = uniform_buffer(
                &self.device,
                &self.queue,
                face_matrix(p, k, lw, lh),
                &[],
                &[],
                &[],
            );
            let bg = self.device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("shadow face"),
                layout: &pipelines.layout,
                entries: &[wgpu::BindGroupEntry {
                    binding: 0,
                    resource: ub.as_entire_binding(),
                }],
            });
            let view = map.create_view(&wgpu::TextureViewDescriptor {
                dimension: Some(wgpu::TextureViewDimension::D2),
                base_array_layer: p.layer_base + k,
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
                color_attachments: if dummy_views.is_empty() { &[] } else { &colors },
                depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                    view: &view,
                    depth_ops: Some(wgpu::Operations {
                        load: wgpu::LoadOp::Clear(p.conv.clear_depth()),
                        store: wgpu::StoreOp::Store,
                    }),
                    stencil_ops: None,
                }),
                // The shadow pass spans all faces: stamp the start of the first, the end of
                // the last.
                // Light k's queries 4k and 4k + 1.
                timestamp_writes: timestamps
                    .filter(|_| pass_index == 0 || pass_index == last_pass)
                    .map(|q| wgpu::RenderPassTimestampWrites {
                        query_set: q,
                        beginning_of_pass_write_index: (pass_index == 0).then_some(base),
                        end_of_pass_write_index: (pass_index == last_pass).then_some(base + 1),
                    }),
                occlusion_query_set: None,
                multiview_mask: None,
            });
            let mistake = p.fault.and_then(|f| f.face_mistake(k as usize, p.cube));
            match (&pipelines.mirrored, mistake) {
                (Some(m), Some((_, true))) => pass.set_pipeline(m),
                _ => pass.set_pipeline(&pipelines.normal),
            }
            if p.is(umbra_case::fault::Fault::ShadowViewport) {
                // The camera's viewport left in place (clipped to the map).
                let [cw, ch] = p.run.camera.size;
                pass.set_viewport(0.0, 0.0, cw.min(lw) as f32, ch.min(lh) as f32, 0.0, 1.0);
            }
            pass.set_bind_group(0, &bg, &[]);
            pass.set_vertex_buffer(0, vbo.slice(..));
            pass.draw(0..p.count, 0..1);
            drop(pass);
            face_buffers.push((ub, bg));
        }
        if p.drawn_levels < p.levels {
            self.average_levels(encoder, map, p.format, p.levels);
        }
        face_buffers
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
            let mut pass = crate::render::depth_only_pass(encoder, "mip average", &dst);
            pass.set_pipeline(&pipeline);
            pass.set_bind_group(0, &bg, &[]);
            pass.draw(0..3, 0..1);
        }
    }
}

/// Face `k`'s view-projection at a `lw` × `lh` level, with the self-test's geometric faults
/// and, on a cube, the convention's face flip.
fn face_matrix(p: &RunPlan, k: u32, lw: u32, lh: u32) -> glam::Mat4 {
    // A layer shift moves a cascade's map; a cube's faces are the face faults' to move.
    let drawn = Fault::drawn_view(p.fault, k as usize, p.faces as usize, p.layered && !p.cube);
    let mut m = p.run.light.views[drawn].view_proj(p.conv);
    // A face drawn with a wrong orientation (the self-test's Oriented fault), before the
    // convention's flip so that it moves the content as on GL.
    if let Some((wrong, _)) = p.fault.and_then(|f| f.face_mistake(k as usize, p.cube)) {
        m = wrong * m;
    }
    // A shift of the image (ShadowHalfTexel, the shadow-shift sweep) in texels along the
    // map's u and v as GL lays them out: 2 · t / size in NDC, before the cube face's flip; a
    // 2D map's rows run down here, so +v is −y.
    let [sx, sy] = p.fault.map_or([0.0; 2], |f| f.shadow_shift_texels());
    if sx != 0.0 || sy != 0.0 {
        let sy = if p.cube { sy } else { -sy };
        m = glam::Mat4::from_translation(glam::Vec3::new(
            2.0 * sx / lw as f32,
            2.0 * sy / lh as f32,
            0.0,
        )) * m;
    }
    if p.cube {
        m = p.conv.cube_face_render_flip() * m;
    }
    m
}

/// wgpu's compare function for the shadow pass's depth test.
fn compare_function(f: DepthFunc) -> wgpu::CompareFunction {
    match f {
        DepthFunc::Less => wgpu::CompareFunction::Less,
        DepthFunc::LessEqual => wgpu::CompareFunction::LessEqual,
        DepthFunc::Greater => wgpu::CompareFunction::Greater,
        DepthFunc::GreaterEqual => wgpu::CompareFunction::GreaterEqual,
    }
}
