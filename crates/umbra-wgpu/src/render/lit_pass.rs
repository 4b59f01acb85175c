//! The lit pass: its pipeline (the technique's WGSL, three targets: colour, visibility, face
//! id), its bind group (uniforms, the map's view, the compare sampler unless the technique
//! compares by hand), its targets, and the recorded pass with its timestamps.

use umbra_case::fault::Fault;
use umbra_case::format::{ColorFormat, Filter, MipFilter, Outside};
use umbra_case::technique::CompareOp;
use umbra_case::{LightKind, LookupMatrices, Technique};

use super::{Encoding, RunPlan, STRIDE, cull_mode, uniform_buffer, uniform_entry};
use crate::render::Gpu;
use crate::shaders;

/// The lit pipeline and what its bind group is made against.
pub(super) struct LitPipeline {
    pipeline: wgpu::RenderPipeline,
    /// A later light of several ([`Gpu::encode_added`]): the same shaders drawing depth
    /// alone first; `pipeline` then draws where the depth is equal, its colour blended.
    depth_again: Option<wgpu::RenderPipeline>,
    layout: wgpu::BindGroupLayout,
    view_dimension: wgpu::TextureViewDimension,
}

/// The lit pass's bind group and the uniform buffer it references.
pub(super) struct LitBindings {
    group: wgpu::BindGroup,
    _uniforms: wgpu::Buffer,
}

/// The lit pass's targets.
pub(super) struct LitTargets {
    /// Colour (RGBA8), visibility (the adapter's visibility format), face id (R32Uint).
    pub(super) color: wgpu::Texture,
    pub(super) vis: wgpu::Texture,
    pub(super) face: wgpu::Texture,
    views: [wgpu::TextureView; 3],
    depth_view: wgpu::TextureView,
}

impl Gpu {
    /// The lit pipeline for `technique`: its map binding is a cube or a cube array, a 2D
    /// array (cascades, several lights, a cube or cube array read by hand) or 2D, and a compare sampler only when the hardware compares.
    ///
    /// `added`: a later light of several, added into the first's colour (the pipeline that
    /// draws depth again, and the one that blends where it is equal).
    pub(super) fn lit_pipeline(
        &self,
        p: &RunPlan,
        technique: &Technique,
        added: bool,
    ) -> LitPipeline {
        let d = &self.device;
        let manual = technique.manual();
        let module = d.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("lit"),
            source: wgpu::ShaderSource::Wgsl(shaders::lit(technique).into()),
        });
        let view_dimension = match (p.cube, manual) {
            (true, false) if p.layered => wgpu::TextureViewDimension::CubeArray,
            _ if p.layered => wgpu::TextureViewDimension::D2Array,
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
        let layout = d.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("lit"),
            entries: &entries,
        });
        let pipeline_layout = d.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("lit"),
            bind_group_layouts: &[Some(&layout)],
            immediate_size: 0,
        });
        let attributes = [
            (wgpu::VertexFormat::Float32x3, 0),
            (wgpu::VertexFormat::Float32x3, 12),
            (wgpu::VertexFormat::Float32x3, 24),
            (wgpu::VertexFormat::Float32, 36),
        ]
        .into_iter()
        .enumerate()
        .map(|(i, (format, offset))| wgpu::VertexAttribute {
            format,
            offset,
            shader_location: i as u32,
        })
        .collect::<Vec<_>>();
        // An added light blends (ONE, ONE) into the colour; its visibility and face ids are
        // written as the first light's are.
        let add = wgpu::BlendComponent {
            src_factor: wgpu::BlendFactor::One,
            dst_factor: wgpu::BlendFactor::One,
            operation: wgpu::BlendOperation::Add,
        };
        let target = |format, blend, writes| {
            Some(wgpu::ColorTargetState {
                format,
                blend,
                write_mask: writes,
            })
        };
        let targets = |blend, writes| {
            [
                target(colour_format(p), blend, writes),
                target(self.vis_format, None, writes),
                target(wgpu::TextureFormat::R32Uint, None, writes),
            ]
        };
        let drawn = targets(
            added.then_some(wgpu::BlendState {
                color: add,
                alpha: add,
            }),
            wgpu::ColorWrites::ALL,
        );
        let depth_only = targets(None, wgpu::ColorWrites::empty());
        let make = |targets: &[Option<wgpu::ColorTargetState>], compare, writes| {
            d.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
                label: Some("lit"),
                layout: Some(&pipeline_layout),
                vertex: wgpu::VertexState {
                    module: &module,
                    entry_point: Some("vs"),
                    compilation_options: Default::default(),
                    buffers: &[Some(wgpu::VertexBufferLayout {
                        array_stride: STRIDE,
                        step_mode: wgpu::VertexStepMode::Vertex,
                        attributes: &attributes,
                    })],
                },
                // `camera.cull`, counter-clockwise front as in the shadow pass.
                primitive: wgpu::PrimitiveState {
                    front_face: wgpu::FrontFace::Ccw,
                    cull_mode: cull_mode(Fault::lit_cull(p.fault, &p.run.case().camera)),
                    ..Default::default()
                },
                depth_stencil: Some(wgpu::DepthStencilState {
                    format: wgpu::TextureFormat::Depth32Float,
                    depth_write_enabled: Some(writes),
                    depth_compare: Some(compare),
                    stencil: Default::default(),
                    bias: Default::default(),
                }),
                multisample: Default::default(),
                fragment: Some(wgpu::FragmentState {
                    module: &module,
                    entry_point: Some("fs"),
                    compilation_options: Default::default(),
                    targets,
                }),
                multiview_mask: None,
                cache: None,
            })
        };
        let (pipeline, depth_again) = if added {
            (
                make(&drawn, wgpu::CompareFunction::Equal, false),
                Some(make(&depth_only, wgpu::CompareFunction::Less, true)),
            )
        } else {
            (make(&drawn, wgpu::CompareFunction::Less, true), None)
        };
        LitPipeline {
            pipeline,
            depth_again,
            layout,
            view_dimension,
        }
    }

    /// The lit pass's uniforms (camera, each face's light and texture matrices, the light,
    /// the bias terms, the map's size), the map's view (the mip faults narrow its levels) and
    /// the compare sampler.
    pub(super) fn lit_bindings(
        &self,
        p: &RunPlan,
        technique: &Technique,
        lit: &LitPipeline,
        map: &wgpu::Texture,
    ) -> LitBindings {
        let (run, conv, b) = (p.run, p.conv, &p.bias);
        let [mw, mh] = p.s.size;
        let mut light = Vec::new();
        let mut tex = Vec::new();
        for v in &run.light.views {
            let m = LookupMatrices::new(conv, v.view_proj(conv));
            light.push(m.light);
            tex.push(m.texture);
        }
        let k = run.of_lights.light;
        umbra_case::fault::Fault::stale_texture(p.fault, &run.case().name, k, &mut tex);
        let (pos, towards) = match run.light.kind {
            // A directional light's eye is read only by an N·L bias towards its position.
            LightKind::Directional { towards, position } => (position, towards),
            LightKind::Spot { position } | LightKind::Point { position } => {
                (position, glam::Vec3::ZERO)
            }
        };
        let eye = run.camera.eye;
        let (slope_scale, slope_max) = b.slope.map_or((0.0, 0.0), |sl| (sl.scale, sl.max));
        let (ndl_scale, ndl_min) = b.n_dot_l.map_or((0.0, 0.0), |nl| (nl.scale, nl.min));
        let cascade = run
            .light
            .cascading
            .as_ref()
            .map_or([[0.0; 4]; 3], |c| c.uniforms());
        let mut offsets = [0.0f32; 8];
        for (o, f) in offsets
            .iter_mut()
            .zip(run.light.face_offsets(b.normal_offset_texels, p.s.size))
        {
            *o = f;
        }
        let uniforms = uniform_buffer(
            &self.device,
            &self.queue,
            run.camera.view_proj(conv),
            &light,
            &tex,
            &[
                [pos.x, pos.y, pos.z, 0.0],
                [towards.x, towards.y, towards.z, b.light_offset],
                [eye.x, eye.y, eye.z, 0.0],
                [mw as f32, mh as f32, ndl_scale, ndl_min],
                [b.constant, slope_scale, slope_max, b.normal_offset],
                cascade[0],
                cascade[1],
                cascade[2],
                [offsets[0], offsets[1], offsets[2], offsets[3]],
                [offsets[4], offsets[5], offsets[6], offsets[7]],
            ],
        );
        // The mip faults: level 0 alone, or the levels from 1 on.
        let (base_mip_level, mip_level_count) = match p.fault {
            Some(umbra_case::fault::Fault::MipBaseOnly) => (0, Some(1)),
            Some(umbra_case::fault::Fault::MipLevelCoarse) if p.levels > 1 => (1, None),
            _ => (0, None),
        };
        let map_view = map.create_view(&wgpu::TextureViewDescriptor {
            dimension: Some(lit.view_dimension),
            base_mip_level,
            mip_level_count,
            ..Default::default()
        });
        let sampler = (!technique.manual()).then(|| {
            self.sampler(
                p.s.filter,
                p.s.mipmaps.map(|m| m.filter),
                technique.texel_wrap(),
                technique.compare_op(),
                p.cube,
            )
        });
        let mut entries = vec![
            wgpu::BindGroupEntry {
                binding: 0,
                resource: uniforms.as_entire_binding(),
            },
            wgpu::BindGroupEntry {
                binding: 1,
                resource: wgpu::BindingResource::TextureView(&map_view),
            },
        ];
        if let Some(samp) = &sampler {
            entries.push(wgpu::BindGroupEntry {
                binding: 2,
                resource: wgpu::BindingResource::Sampler(samp),
            });
        }
        let group = self.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("lit"),
            layout: &lit.layout,
            entries: &entries,
        });
        LitBindings {
            group,
            _uniforms: uniforms,
        }
    }

    /// The camera-sized targets: colour (Rgba8Unorm, or Rgba8UnormSrgb for an sRGB target),
    /// visibility, face id, and a Depth32Float depth.
    pub(super) fn lit_targets(&self, p: &RunPlan) -> LitTargets {
        let [w, h] = p.run.camera.size;
        let target = |format, label| {
            self.device.create_texture(&wgpu::TextureDescriptor {
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
        let color = target(colour_format(p), "colour");
        let vis = target(self.vis_format, "visibility");
        let face = target(wgpu::TextureFormat::R32Uint, "face");
        let depth = target(wgpu::TextureFormat::Depth32Float, "camera depth");
        let views = [&color, &vis, &face].map(|t| t.create_view(&Default::default()));
        LitTargets {
            color,
            vis,
            face,
            views,
            depth_view: depth.create_view(&Default::default()),
        }
    }

    /// Records the first light's lit pass (its timestamps, [`Encoding`]) into `encoder`.
    pub(super) fn encode_lit(
        &self,
        p: &RunPlan,
        lit: &LitPipeline,
        bindings: &LitBindings,
        targets: &LitTargets,
        enc: &mut Encoding,
    ) {
        let (vbo, timestamps) = (enc.vbo, enc.timestamps);
        let attach = |i: usize, c: wgpu::Color| {
            Some(wgpu::RenderPassColorAttachment {
                view: &targets.views[i],
                depth_slice: None,
                resolve_target: None,
                ops: wgpu::Operations {
                    load: wgpu::LoadOp::Clear(c),
                    store: wgpu::StoreOp::Store,
                },
            })
        };
        let mut pass = enc.encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("lit pass"),
            color_attachments: &[
                attach(0, {
                    // The case's clear colour (`camera.clear`): what the background shows.
                    let [r, g, b] = Fault::clear_colour(p.fault, &p.run.case().camera);
                    wgpu::Color {
                        r: f64::from(r),
                        g: f64::from(g),
                        b: f64::from(b),
                        a: 1.0,
                    }
                }),
                attach(1, wgpu::Color::TRANSPARENT),
                attach(2, wgpu::Color::TRANSPARENT),
            ],
            depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                view: &targets.depth_view,
                depth_ops: Some(wgpu::Operations {
                    load: wgpu::LoadOp::Clear(1.0),
                    store: wgpu::StoreOp::Store,
                }),
                stencil_ops: None,
            }),
            timestamp_writes: timestamps.map(|q| lit_stamps(q, p)),
            occlusion_query_set: None,
            multiview_mask: None,
        });
        pass.set_pipeline(&lit.pipeline);
        pass.set_bind_group(0, &bindings.group, &[]);
        pass.set_vertex_buffer(0, vbo.slice(..));
        pass.draw(0..p.count, 0..1);
    }

    /// Records a later light's lit pass over the first light's `targets`: the depth cleared
    /// and drawn again by this light's shaders with colour writes off, then the colour drawn
    /// where the depth is equal, blended into the stored colour, the visibility target
    /// cleared to 0 and written (the GL backend's `add_light` says why the depth is drawn
    /// again).
    pub(super) fn encode_added(
        &self,
        p: &RunPlan,
        lit: &LitPipeline,
        bindings: &LitBindings,
        targets: &LitTargets,
        enc: &mut Encoding,
    ) {
        let (vbo, timestamps) = (enc.vbo, enc.timestamps);
        let attach = |i: usize, load| {
            Some(wgpu::RenderPassColorAttachment {
                view: &targets.views[i],
                depth_slice: None,
                resolve_target: None,
                ops: wgpu::Operations {
                    load,
                    store: wgpu::StoreOp::Store,
                },
            })
        };
        let mut pass = enc.encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("lit pass (added light)"),
            color_attachments: &[
                attach(0, wgpu::LoadOp::Load),
                attach(1, wgpu::LoadOp::Clear(wgpu::Color::TRANSPARENT)),
                attach(2, wgpu::LoadOp::Load),
            ],
            depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                view: &targets.depth_view,
                depth_ops: Some(wgpu::Operations {
                    load: wgpu::LoadOp::Clear(1.0),
                    store: wgpu::StoreOp::Store,
                }),
                stencil_ops: None,
            }),
            timestamp_writes: timestamps.map(|q| lit_stamps(q, p)),
            occlusion_query_set: None,
            multiview_mask: None,
        });
        pass.set_bind_group(0, &bindings.group, &[]);
        pass.set_vertex_buffer(0, vbo.slice(..));
        if let Some(depth) = &lit.depth_again {
            pass.set_pipeline(depth);
            pass.draw(0..p.count, 0..1);
        }
        pass.set_pipeline(&lit.pipeline);
        pass.draw(0..p.count, 0..1);
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
        let f = if filter.sampler_linear() {
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

/// The lit pass's colour target (`camera.color_format`): Rgba8Unorm, or Rgba8UnormSrgb, whose
/// writes and clear value Vulkan (and wgpu's GL backend) encode; its copy to a buffer is the
/// stored bytes.
fn colour_format(p: &RunPlan) -> wgpu::TextureFormat {
    match Fault::colour_format(p.fault, &p.run.case().camera) {
        ColorFormat::Rgba8 => wgpu::TextureFormat::Rgba8Unorm,
        ColorFormat::Srgb8Alpha8 => wgpu::TextureFormat::Rgba8UnormSrgb,
    }
}

/// Light k's lit pass writes queries 4k + 2 (its start) and 4k + 3 (its end).
fn lit_stamps<'q>(q: &'q wgpu::QuerySet, p: &RunPlan) -> wgpu::RenderPassTimestampWrites<'q> {
    let base = 4 * p.run.of_lights.light as u32;
    wgpu::RenderPassTimestampWrites {
        query_set: q,
        beginning_of_pass_write_index: Some(base + 2),
        end_of_pass_write_index: Some(base + 3),
    }
}
