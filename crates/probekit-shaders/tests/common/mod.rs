//! What the numeric tests share: a CPU Vulkan adapter (Mesa lavapipe) and a
//! runner for the check kernel `pk_check` with every buffer it binds.

#![allow(dead_code)]

use probekit_shaders::{full_wgsl, CHECK_IN_FLOATS, CHECK_OUT_FLOATS};
use wgpu::util::DeviceExt;

/// A CPU (software) Vulkan adapter, else any Vulkan adapter, else `None`.
pub fn adapter() -> Option<wgpu::Adapter> {
    let mut desc = wgpu::InstanceDescriptor::new_without_display_handle();
    desc.backends = wgpu::Backends::VULKAN;
    let instance = wgpu::Instance::new(desc);
    let adapters = pollster::block_on(instance.enumerate_adapters(wgpu::Backends::VULKAN));
    let mut best: Option<wgpu::Adapter> = None;
    for a in adapters {
        let cpu = a.get_info().device_type == wgpu::DeviceType::Cpu;
        if cpu || best.is_none() {
            best = Some(a);
            if cpu {
                break;
            }
        }
    }
    best.or_else(|| {
        pollster::block_on(instance.request_adapter(&wgpu::RequestAdapterOptions {
            force_fallback_adapter: true,
            ..Default::default()
        }))
        .ok()
    })
}

/// The adapter, or `None` after printing the skip message to stderr
/// (straight to stderr: the harness captures `print!`, and a skip must show).
pub fn adapter_or_skip() -> Option<wgpu::Adapter> {
    let a = adapter();
    match &a {
        Some(a) => {
            let info = a.get_info();
            println!(
                "adapter: {} ({:?}, {:?})",
                info.name, info.device_type, info.backend
            );
        }
        None => {
            use std::io::Write;
            let _ = writeln!(
                std::io::stderr(),
                "SKIPPED: no wgpu adapter (install Mesa lavapipe: apt-get install mesa-vulkan-drivers)"
            );
        }
    }
    a
}

/// The check modes of `pk_check` (`check_params.mode`).
pub const MODE_LIBRARY: u32 = 0;
pub const MODE_CLOUD: u32 = 1;
pub const MODE_VOLUME: u32 = 2;
pub const MODE_BRICKS: u32 = 3;
pub const MODE_RIG: u32 = 4;
pub const MODE_LIGHT: u32 = 5;

/// The buffers `pk_check` reads; empty ones are bound as 16 zero bytes.
pub struct Buffers {
    /// `pk_probe_words`.
    pub words: Vec<u32>,
    /// `pk_sh_coeffs`.
    pub sh: Vec<f32>,
    /// `pk_sh_gradients`.
    pub gradients: Vec<f32>,
    /// `pk_cloud`.
    pub cloud: Vec<u32>,
    /// `pk_bricks`.
    pub bricks: Vec<u32>,
    /// `pk_rig`.
    pub rig: Vec<u32>,
    /// `pk_sphere_table`.
    pub sphere_table: Vec<u32>,
    /// The `PkVolumeGrid` of the parameters (48 bytes).
    pub grid: [u8; 48],
    /// Codec offsets of mode 0 (l1, zh3, l2, cube).
    pub offsets: [u32; 4],
}

impl Default for Buffers {
    fn default() -> Self {
        Buffers {
            words: Vec::new(),
            sh: Vec::new(),
            gradients: Vec::new(),
            cloud: Vec::new(),
            bricks: Vec::new(),
            rig: Vec::new(),
            sphere_table: Vec::new(),
            grid: [0; 48],
            offsets: [0; 4],
        }
    }
}

/// One compiled `pk_check` pipeline.
pub struct Gpu {
    device: wgpu::Device,
    queue: wgpu::Queue,
    pipeline: wgpu::ComputePipeline,
    bind_layout: wgpu::BindGroupLayout,
}

impl Gpu {
    /// Compiles the check kernel `entry` (`pk_check_library`,
    /// `pk_check_cloud`, …) with a layout holding every binding of
    /// `pk_check`, so one bind group fits every kernel.
    pub fn new(adapter: &wgpu::Adapter, entry: &str) -> Self {
        let (device, queue) = pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
            label: Some("probekit-shaders test"),
            required_limits: adapter.limits(),
            ..Default::default()
        }))
        .expect("request_device");
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("probekit"),
            source: wgpu::ShaderSource::Wgsl(full_wgsl().into()),
        });
        let entry_of = |binding: u32, ty: wgpu::BufferBindingType| wgpu::BindGroupLayoutEntry {
            binding,
            visibility: wgpu::ShaderStages::COMPUTE,
            ty: wgpu::BindingType::Buffer {
                ty,
                has_dynamic_offset: false,
                min_binding_size: None,
            },
            count: None,
        };
        let read = wgpu::BufferBindingType::Storage { read_only: true };
        let mut entries: Vec<_> = [0, 1, 2, 3, 4, 5, 6, 8]
            .into_iter()
            .map(|b| entry_of(b, read))
            .collect();
        entries.push(entry_of(
            9,
            wgpu::BufferBindingType::Storage { read_only: false },
        ));
        entries.push(entry_of(10, wgpu::BufferBindingType::Uniform));
        let bind_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("pk_check bindings"),
            entries: &entries,
        });
        let layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("pk_check layout"),
            bind_group_layouts: &[Some(&bind_layout)],
            immediate_size: 0,
        });
        let pipeline = device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
            label: Some(entry),
            layout: Some(&layout),
            module: &module,
            entry_point: Some(entry),
            compilation_options: Default::default(),
            cache: None,
        });
        Gpu {
            device,
            queue,
            pipeline,
            bind_layout,
        }
    }

    /// Runs `pk_check` in `mode` over `input.len() / CHECK_IN_FLOATS` cases
    /// and returns `CHECK_OUT_FLOATS` floats per case.
    pub fn run(&self, mode: u32, input: &[f32], b: &Buffers) -> Vec<f32> {
        assert_eq!(input.len() % CHECK_IN_FLOATS, 0);
        let cases = input.len() / CHECK_IN_FLOATS;
        let device = &self.device;
        let storage = |label: &str, data: &[u8]| {
            let mut data = data.to_vec();
            data.resize(data.len().max(16).next_multiple_of(4), 0);
            device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some(label),
                contents: &data,
                usage: wgpu::BufferUsages::STORAGE,
            })
        };
        let f2b = |v: &[f32]| v.iter().flat_map(|x| x.to_le_bytes()).collect::<Vec<u8>>();
        let u2b = |v: &[u32]| v.iter().flat_map(|x| x.to_le_bytes()).collect::<Vec<u8>>();
        let buffers = [
            (0, storage("pk_probe_words", &u2b(&b.words))),
            (1, storage("pk_sh_coeffs", &f2b(&b.sh))),
            (2, storage("pk_sh_gradients", &f2b(&b.gradients))),
            (3, storage("pk_cloud", &u2b(&b.cloud))),
            (4, storage("pk_bricks", &u2b(&b.bricks))),
            (5, storage("pk_rig", &u2b(&b.rig))),
            (6, storage("pk_sphere_table", &u2b(&b.sphere_table))),
            (8, storage("check_in", &f2b(input))),
        ];
        let out_size = (cases.max(1) * CHECK_OUT_FLOATS * 4) as u64;
        let b_out = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("check_out"),
            size: out_size,
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
            mapped_at_creation: false,
        });
        // PkCheckParams: PkVolumeGrid (48 B), count @48, l1/zh3/l2/cube
        // offsets @52..68, mode @68, size rounded to 80.
        let mut params = vec![0u8; 80];
        params[..48].copy_from_slice(&b.grid);
        params[48..52].copy_from_slice(&(cases as u32).to_le_bytes());
        for (k, o) in b.offsets.iter().enumerate() {
            params[52 + 4 * k..56 + 4 * k].copy_from_slice(&o.to_le_bytes());
        }
        params[68..72].copy_from_slice(&mode.to_le_bytes());
        let b_params = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("check_params"),
            contents: &params,
            usage: wgpu::BufferUsages::UNIFORM,
        });
        let b_read = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("readback"),
            size: out_size,
            usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let mut entries: Vec<wgpu::BindGroupEntry> = buffers
            .iter()
            .map(|(binding, buf)| wgpu::BindGroupEntry {
                binding: *binding,
                resource: buf.as_entire_binding(),
            })
            .collect();
        entries.push(wgpu::BindGroupEntry {
            binding: 9,
            resource: b_out.as_entire_binding(),
        });
        entries.push(wgpu::BindGroupEntry {
            binding: 10,
            resource: b_params.as_entire_binding(),
        });
        let bind = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: None,
            layout: &self.bind_layout,
            entries: &entries,
        });
        let mut enc = device.create_command_encoder(&Default::default());
        {
            let mut pass = enc.begin_compute_pass(&Default::default());
            pass.set_pipeline(&self.pipeline);
            pass.set_bind_group(0, &bind, &[]);
            pass.dispatch_workgroups(cases.div_ceil(64) as u32, 1, 1);
        }
        enc.copy_buffer_to_buffer(&b_out, 0, &b_read, 0, out_size);
        self.queue.submit([enc.finish()]);
        let slice = b_read.slice(..);
        slice.map_async(wgpu::MapMode::Read, |r| r.expect("map_async"));
        device
            .poll(wgpu::PollType::wait_indefinitely())
            .expect("device poll");
        let data = slice.get_mapped_range().expect("mapped range");
        let mut out: Vec<f32> = data
            .chunks_exact(4)
            .map(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]]))
            .collect();
        out.truncate(cases * CHECK_OUT_FLOATS);
        out
    }
}

/// Largest error of each quantity, with the first failures.
#[derive(Default)]
pub struct Report {
    /// Magnitude of the inputs the next checks derive from.
    pub unit: f32,
    /// (name, largest relative error, largest absolute error, tolerance).
    pub rows: Vec<(String, f32, f32, f32)>,
    pub failures: Vec<String>,
}

impl Report {
    /// Compares `gpu` with `cpu` component-wise:
    /// |gpu − cpu| ≤ tol·(unit + |cpu|∞).
    pub fn check(&mut self, name: &str, case: usize, gpu: &[f32], cpu: &[f32], tol: f32) {
        assert_eq!(gpu.len(), cpu.len());
        let scale = self.unit + cpu.iter().fold(0.0f32, |m, x| m.max(x.abs()));
        let abs = gpu
            .iter()
            .zip(cpu)
            .fold(0.0f32, |m, (g, c)| m.max((g - c).abs()));
        let (abs, err) = if gpu.iter().all(|x| x.is_finite()) {
            (abs, abs / scale)
        } else {
            (f32::INFINITY, f32::INFINITY)
        };
        match self.rows.iter_mut().find(|r| r.0 == name) {
            Some(r) => {
                r.1 = r.1.max(err);
                r.2 = r.2.max(abs);
            }
            None => self.rows.push((name.to_string(), err, abs, tol)),
        }
        if (err.is_nan() || err > tol) && self.failures.len() < 20 {
            self.failures.push(format!(
                "{name}, case {case}: gpu {gpu:?} vs rust {cpu:?} (rel. error {err:e})"
            ));
        }
    }

    /// Prints the table and fails on any failure.
    pub fn finish(&self, what: &str) {
        for (name, err, abs, tol) in &self.rows {
            println!(
                "{name:>36}: max relative error {err:.2e} (abs {abs:.2e}, tolerance {tol:.0e})"
            );
        }
        assert!(
            self.failures.is_empty(),
            "{what}: WGSL differs from Rust:\n{}",
            self.failures.join("\n")
        );
    }
}

/// xorshift64*: deterministic test inputs without a dependency.
pub struct Rng(pub u64);

impl Rng {
    pub fn next_f32(&mut self) -> f32 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        ((self.0.wrapping_mul(0x2545_f491_4f6c_dd1d) >> 40) as f32) / (1u64 << 24) as f32
    }
    pub fn range(&mut self, lo: f32, hi: f32) -> f32 {
        lo + (hi - lo) * self.next_f32()
    }
    pub fn unit(&mut self) -> glam::Vec3 {
        loop {
            let v = glam::Vec3::new(
                self.range(-1.0, 1.0),
                self.range(-1.0, 1.0),
                self.range(-1.0, 1.0),
            );
            let l = v.length();
            if l > 0.1 && l <= 1.0 {
                return v / l;
            }
        }
    }
    pub fn below(&mut self, n: usize) -> usize {
        ((self.next_f32() * n as f32) as usize).min(n - 1)
    }
}

pub fn flat(v: &[glam::Vec3]) -> Vec<f32> {
    v.iter().flat_map(|x| x.to_array()).collect()
}
