//! What `Depth24Plus` really is on an adapter (WebGPU lets it be any format with at least 24
//! bits). The probe renders a depth ramp with steps of about 1e-7 (between the D24 step,
//! 6e-8, and f32's spacing near 0.5) into a Depth24Plus texture, samples it back into an
//! R32Float target, and checks whether every value is a 24-bit code k/(2^24 − 1).
//! Adapters that cannot render R32Float (wgpu's GL backend) cannot show it: "not observable".

use crate::render::Gpu;

const RAMP: u32 = 256;

const SHADER: &str = "
struct V { @builtin(position) p: vec4<f32>, }
@vertex fn ramp(@builtin(vertex_index) i: u32) -> V {
  // One triangle over the viewport; depth 0.5 at x = -1 rising by 4e-7 per pixel of 256.
  let xy = array<vec2<f32>, 3>(vec2<f32>(-1.0, -1.0), vec2<f32>(3.0, -1.0), vec2<f32>(-1.0, 3.0));
  let z = select(0.5, 0.5 + 2.0 * 128.0 * 4.0e-7, xy[i].x > 0.0);
  var v: V; v.p = vec4<f32>(xy[i], z, 1.0); return v;
}
@group(0) @binding(0) var depth: texture_depth_2d;
@group(0) @binding(1) var nearest: sampler;
@fragment fn read(v: V) -> @location(0) vec4<f32> {
  return vec4<f32>(textureSampleLevel(depth, nearest, v.p.xy / vec2<f32>(256.0, 1.0), 0), 0.0, 0.0, 1.0);
}
";

/// Runs the probe and says what it found.
pub fn depth24plus(gpu: &Gpu) -> String {
    if gpu.vis_format != wgpu::TextureFormat::R32Float {
        return "Depth24Plus precision not observable (no renderable R32Float)".into();
    }
    match run(gpu) {
        Ok(values) => {
            let max = f64::from((1u32 << 24) - 1);
            let unorm24 = values.iter().all(|v| {
                let k = f64::from(*v) * max;
                (k - k.round()).abs() < 0.02
            });
            let distinct = values.windows(2).filter(|w| w[0] != w[1]).count();
            if unorm24 {
                format!("Depth24Plus = 24-bit unorm ({distinct} distinct codes over the ramp)")
            } else {
                format!("Depth24Plus = 32-bit float ({distinct} distinct values over the ramp)")
            }
        }
        Err(e) => format!("Depth24Plus probe failed: {e}"),
    }
}

fn run(gpu: &Gpu) -> Result<Vec<f32>, String> {
    let d = &gpu.device;
    let tex = |format, usage| {
        d.create_texture(&wgpu::TextureDescriptor {
            label: Some("probe"),
            size: wgpu::Extent3d {
                width: RAMP,
                height: 1,
                depth_or_array_layers: 1,
            },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format,
            usage,
            view_formats: &[],
        })
    };
    let depth = tex(
        wgpu::TextureFormat::Depth24Plus,
        wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::TEXTURE_BINDING,
    );
    let out = tex(
        wgpu::TextureFormat::R32Float,
        wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_SRC,
    );
    let module = d.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some("probe"),
        source: wgpu::ShaderSource::Wgsl(SHADER.into()),
    });
    let depth_state = wgpu::DepthStencilState {
        format: wgpu::TextureFormat::Depth24Plus,
        depth_write_enabled: Some(true),
        depth_compare: Some(wgpu::CompareFunction::Always),
        stencil: Default::default(),
        bias: Default::default(),
    };
    let ramp = d.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
        label: Some("probe ramp"),
        layout: None,
        vertex: wgpu::VertexState {
            module: &module,
            entry_point: Some("ramp"),
            compilation_options: Default::default(),
            buffers: &[],
        },
        primitive: Default::default(),
        depth_stencil: Some(depth_state),
        multisample: Default::default(),
        fragment: None,
        multiview_mask: None,
        cache: None,
    });
    let targets = [Some(wgpu::ColorTargetState::from(
        wgpu::TextureFormat::R32Float,
    ))];
    let read = d.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
        label: Some("probe read"),
        layout: None,
        vertex: wgpu::VertexState {
            module: &module,
            entry_point: Some("ramp"),
            compilation_options: Default::default(),
            buffers: &[],
        },
        primitive: Default::default(),
        depth_stencil: None,
        multisample: Default::default(),
        fragment: Some(wgpu::FragmentState {
            module: &module,
            entry_point: Some("read"),
            compilation_options: Default::default(),
            targets: &targets,
        }),
        multiview_mask: None,
        cache: None,
    });
    let sampler = d.create_sampler(&wgpu::SamplerDescriptor::default());
    let depth_view = depth.create_view(&Default::default());
    let out_view = out.create_view(&Default::default());
    let bg = d.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some("probe"),
        layout: &read.get_bind_group_layout(0),
        entries: &[
            wgpu::BindGroupEntry {
                binding: 0,
                resource: wgpu::BindingResource::TextureView(&depth_view),
            },
            wgpu::BindGroupEntry {
                binding: 1,
                resource: wgpu::BindingResource::Sampler(&sampler),
            },
        ],
    });
    let mut encoder = d.create_command_encoder(&Default::default());
    {
        let mut pass = crate::render::depth_only_pass(&mut encoder, "probe ramp", &depth_view);
        pass.set_pipeline(&ramp);
        pass.draw(0..3, 0..1);
    }
    {
        let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("probe read"),
            color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                view: &out_view,
                depth_slice: None,
                resolve_target: None,
                ops: wgpu::Operations {
                    load: wgpu::LoadOp::Clear(wgpu::Color::BLACK),
                    store: wgpu::StoreOp::Store,
                },
            })],
            depth_stencil_attachment: None,
            timestamp_writes: None,
            occlusion_query_set: None,
            multiview_mask: None,
        });
        pass.set_pipeline(&read);
        pass.set_bind_group(0, &bg, &[]);
        pass.draw(0..3, 0..1);
    }
    gpu.queue.submit([encoder.finish()]);
    let bytes = gpu
        .scoped("Depth24Plus probe", || {
            crate::render::read_texture(gpu, &out, 4, RAMP, 1, wgpu::TextureAspect::All)
        })
        .map_err(|e| e.to_string())?;
    Ok(bytes
        .chunks_exact(4)
        .map(|b| f32::from_ne_bytes([b[0], b[1], b[2], b[3]]))
        .collect())
}
