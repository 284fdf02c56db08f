//! Shared helpers of the integration tests: GPU setup on lavapipe and image comparison.
#![allow(dead_code)]

use std::path::{Path, PathBuf};

use skytune::render::{AdapterChoice, GpuContext, Headless};

/// Options that draw physical sky models on the HDR target (the reference picture of a model:
/// what HDR exports read), whatever the default strategy draws on screen.
#[allow(dead_code)]
pub fn hdr_options() -> skytune::render::RenderOptions {
    skytune::render::RenderOptions { strategy: skytune::render::FillStrategy::software().with_hdr(), ..Default::default() }
}

/// A headless renderer on the software adapter (lavapipe): the same pixels on every machine.
pub fn headless(width: u32, height: u32) -> Headless {
    let ctx = GpuContext::headless(AdapterChoice::Cpu).expect("lavapipe (mesa-vulkan-drivers) is required: run scripts/setup.sh");
    Headless::new(ctx, width, height).expect("creating the renderer")
}

/// Folder of committed reference images.
pub fn reference_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/reference")
}

/// Git-ignored folder receiving actual and diff images of failed comparisons.
pub fn output_dir() -> PathBuf {
    let d = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/output");
    std::fs::create_dir_all(&d).expect("creating tests/output");
    d
}

/// Per-pixel tolerance: a pixel differs when a channel differs by more than this (of 255).
pub const CHANNEL_TOLERANCE: u8 = 10;
/// Budget: the comparison fails when more than this fraction of pixels differ.
pub const PIXEL_BUDGET: f64 = 0.01;

/// Result of comparing two images (the library's measure, also behind `skytune compare`).
pub type Diff = skytune::measure::image_diff::PixelDiff;

/// Compares two equally sized images: pixels whose largest channel difference exceeds
/// `tolerance`, and an image marking them.
pub fn diff(a: &image::RgbaImage, b: &image::RgbaImage, tolerance: u8) -> (Diff, image::RgbaImage) {
    skytune::measure::image_diff::pixel_diff(a, b, tolerance)
}

/// Compares with `tests/reference/NAME.png`. `SKYTUNE_ACCEPT=1` writes the reference instead.
/// On failure, writes NAME.actual.png and NAME.diff.png into tests/output and panics.
pub fn check_reference(name: &str, actual: &image::RgbaImage) {
    let reference = reference_dir().join(format!("{name}.png"));
    if std::env::var("SKYTUNE_ACCEPT").is_ok_and(|v| v == "1") {
        actual.save(&reference).expect("writing the reference");
        eprintln!("accepted new reference {}", reference.display());
        return;
    }
    let expected = match image::open(&reference) {
        Ok(img) => img.to_rgba8(),
        Err(e) => {
            let out = output_dir().join(format!("{name}.actual.png"));
            actual.save(&out).expect("writing the actual image");
            panic!("no reference {} ({e}); actual written to {}; run with SKYTUNE_ACCEPT=1 to accept it", reference.display(), out.display());
        }
    };
    let (d, diff_img) = diff(actual, &expected, CHANNEL_TOLERANCE);
    if d.differing > PIXEL_BUDGET {
        let out = output_dir();
        actual.save(out.join(format!("{name}.actual.png"))).expect("writing actual");
        diff_img.save(out.join(format!("{name}.diff.png"))).expect("writing diff");
        panic!(
            "{name}: {:.2}% of pixels differ by more than {CHANNEL_TOLERANCE}/255 (budget {:.2}%), max {}, mean {:.2}; see tests/output/{name}.actual.png and .diff.png",
            d.differing * 100.0,
            PIXEL_BUDGET * 100.0,
            d.max,
            d.mean
        );
    }
}

/// A fresh folder holding a copy of the default sky (sky.toml + bitmaps).
pub fn default_sky_folder() -> (tempfile::TempDir, PathBuf) {
    let dir = tempfile::tempdir().expect("temp dir");
    let palette = skytune::sky::procedural::preset("default").unwrap();
    let sky = skytune::sky::builtin::write_sky_folder(dir.path(), palette, 7).expect("writing the default sky");
    (dir, sky)
}

/// Copies the checkout's shaders/ (with its folders) into `dst`.
pub fn copy_shaders(dst: &Path) {
    fn copy(src: &Path, dst: &Path) {
        std::fs::create_dir_all(dst).expect("creating the shader folder");
        for e in std::fs::read_dir(src).expect("reading shaders/") {
            let p = e.expect("a folder entry").path();
            let to = dst.join(p.file_name().expect("a file name"));
            if p.is_dir() {
                copy(&p, &to);
            } else {
                std::fs::copy(&p, &to).expect("copying a shader");
            }
        }
    }
    copy(&Path::new(env!("CARGO_MANIFEST_DIR")).join("shaders"), dst);
}

/// Starts Xvfb with one screen of `size` on a display it picks itself (`-displayfd`), so parallel
/// tests never collide. Returns the server and its `DISPLAY`.
pub fn xvfb(size: (u32, u32)) -> Option<(std::process::Child, String)> {
    use std::io::BufRead;
    let mut child = std::process::Command::new("Xvfb")
        .args(["-displayfd", "1", "-screen", "0", &format!("{}x{}x24", size.0, size.1), "-nolisten", "tcp"])
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::null())
        .spawn()
        .ok()?;
    let mut line = String::new();
    std::io::BufReader::new(child.stdout.take()?).read_line(&mut line).ok()?;
    let n: u32 = line.trim().parse().ok()?;
    Some((child, format!(":{n}")))
}

/// What the X server shows on `display`: the root window's pixels, through `xwd` (x11-apps).
pub fn x_screenshot(display: &str) -> Result<image::RgbaImage, String> {
    let out = std::process::Command::new("xwd").args(["-root", "-silent", "-display", display]).output().map_err(|e| format!("running xwd (x11-apps): {e}"))?;
    if !out.status.success() {
        return Err(format!("xwd failed: {}", String::from_utf8_lossy(&out.stderr)));
    }
    read_xwd(&out.stdout)
}

/// Decodes an XWD image (X Window Dump, version 7) of 24 or 32 bits per pixel in ZPixmap format,
/// as `xwd` writes the screens of Xvfb.
pub fn read_xwd(bytes: &[u8]) -> Result<image::RgbaImage, String> {
    let field =
        |i: usize| -> Result<u32, String> { bytes.get(i * 4..i * 4 + 4).map(|b| u32::from_be_bytes([b[0], b[1], b[2], b[3]])).ok_or_else(|| "xwd: short header".to_string()) };
    let (header_size, version, format) = (field(0)? as usize, field(1)?, field(2)?);
    if version != 7 || format != 2 {
        return Err(format!("xwd: version {version}, format {format}: expected 7 and ZPixmap (2)"));
    }
    let (width, height, byte_order, bits_per_pixel, bytes_per_line) = (field(4)?, field(5)?, field(7)?, field(11)?, field(12)? as usize);
    let masks = [field(14)?, field(15)?, field(16)?];
    let colours = field(19)? as usize;
    if bits_per_pixel != 32 && bits_per_pixel != 24 {
        return Err(format!("xwd: {bits_per_pixel} bits per pixel"));
    }
    let data = header_size + colours * 12;
    let step = bits_per_pixel as usize / 8;
    if bytes.len() < data + bytes_per_line * height as usize {
        return Err("xwd: short image data".into());
    }
    let mut img = image::RgbaImage::new(width, height);
    for y in 0..height as usize {
        for x in 0..width as usize {
            let at = data + y * bytes_per_line + x * step;
            let mut b = [0u8; 4];
            b[..step].copy_from_slice(&bytes[at..at + step]);
            // byte_order 0: least significant byte first.
            let v = if byte_order == 0 { u32::from_le_bytes(b) } else { u32::from_be_bytes(b) >> (32 - bits_per_pixel) };
            let channel = |m: u32| ((v & m) >> m.trailing_zeros()) as u8;
            img.put_pixel(x as u32, y as u32, image::Rgba([channel(masks[0]), channel(masks[1]), channel(masks[2]), 255]));
        }
    }
    Ok(img)
}

/// Runs compute entry point `entry` of WGSL `source` (a shader module with a probe appended)
/// over `count` invocations in workgroups of 64, with the pipeline-overridable `constants` and,
/// where given, `input` bound read-only at `@group(0) @binding(16)`; returns what it wrote to
/// `@group(0) @binding(15)`: `count` items of `item_bytes` bytes.
pub fn run_compute_probe(ctx: &GpuContext, source: String, entry: &str, constants: &[(&str, f64)], input: Option<&[u8]>, count: u32, item_bytes: u64) -> Vec<u8> {
    let device = &ctx.device;
    let module = device.create_shader_module(wgpu::ShaderModuleDescriptor { label: Some("compute_probe::module"), source: wgpu::ShaderSource::Wgsl(source.into()) });
    let pipeline = device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
        label: Some("compute_probe::pipeline"),
        layout: None,
        module: &module,
        entry_point: Some(entry),
        compilation_options: wgpu::PipelineCompilationOptions { constants, ..Default::default() },
        cache: None,
    });
    let bytes = u64::from(count) * item_bytes;
    let out = device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("compute_probe::out"),
        size: bytes,
        usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
        mapped_at_creation: false,
    });
    let read = device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("compute_probe::read"),
        size: bytes,
        usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    });
    let input = input.map(|bytes| {
        use wgpu::util::DeviceExt;
        device.create_buffer_init(&wgpu::util::BufferInitDescriptor { label: Some("compute_probe::input"), contents: bytes, usage: wgpu::BufferUsages::STORAGE })
    });
    let mut entries = vec![wgpu::BindGroupEntry { binding: 15, resource: out.as_entire_binding() }];
    entries.extend(input.iter().map(|b| wgpu::BindGroupEntry { binding: 16, resource: b.as_entire_binding() }));
    let bind_group =
        device.create_bind_group(&wgpu::BindGroupDescriptor { label: Some("compute_probe::bind_group"), layout: &pipeline.get_bind_group_layout(0), entries: &entries });
    let mut encoder = device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some("compute_probe::encoder") });
    {
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor { label: Some("compute_probe::pass"), timestamp_writes: None });
        pass.set_pipeline(&pipeline);
        pass.set_bind_group(0, &bind_group, &[]);
        pass.dispatch_workgroups(count.div_ceil(64), 1, 1);
    }
    encoder.copy_buffer_to_buffer(&out, 0, &read, 0, bytes);
    ctx.queue.submit([encoder.finish()]);
    read.slice(..).map_async(wgpu::MapMode::Read, |r| r.expect("mapping the probe's output"));
    ctx.wait_idle().expect("waiting for the probe");
    let view = read.slice(..).get_mapped_range().expect("the probe's buffer");
    view.to_vec()
}

/// The checkout's shaders plus the test passes' files (tests/passes/), in one folder: the
/// library of a renderer with passes added by a test (`SkyRenderer::with_passes`).
pub fn library_with_test_passes() -> (tempfile::TempDir, skytune::render::ShaderLibrary) {
    let dir = tempfile::tempdir().expect("temp dir");
    copy_shaders(dir.path());
    for e in std::fs::read_dir(Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/passes")).expect("reading tests/passes") {
        let p = e.expect("a folder entry").path();
        std::fs::copy(&p, dir.path().join(p.file_name().expect("a file name"))).expect("copying a test pass's shader");
    }
    let library = skytune::render::ShaderLibrary { dir: Some(dir.path().to_path_buf()) };
    (dir, library)
}
