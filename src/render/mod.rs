//! The renderer: one wgpu pipeline setup ([`gpu`], `shaders/*.wgsl`) and one camera model
//! ([`camera`]) for the editor's viewport and for headless pictures. Offscreen it needs no window
//! and no GPU: Mesa's software Vulkan (lavapipe) is enough, which is what CI uses.
//!
//! Styles: shaded; wireframe (the tessellation's edges over the shading); charts (each vertex
//! coloured by its blend weights, one colour per chart); curvature (Gaussian or mean curvature on a
//! diverging scale, with a legend).

pub mod camera;
pub mod gpu;
mod legend;
pub mod palette;
pub mod reembed;
pub mod scene;

use embedding::Surface;

use camera::Camera;
use gpu::{GpuScene, SurfaceRenderer, Targets};
use scene::SceneGeometry;

/// What can go wrong when rendering.
#[derive(Debug, thiserror::Error)]
pub enum RenderError {
    #[error(
        "no graphics adapter is available ({0}); install a Vulkan driver (on Debian or Ubuntu, Mesa's software one: apt-get install mesa-vulkan-drivers)"
    )]
    NoAdapter(String),
    #[error("the graphics device could not be opened: {0}")]
    Device(String),
    #[error("an image of {width}×{height} pixels is not possible (1 to {max} per side)")]
    Size { width: u32, height: u32, max: u32 },
    #[error("{0}")]
    View(String),
    #[error("the mesh cannot be drawn: {0}")]
    Mesh(String),
    #[error(
        "the {what} would take {bytes} bytes, more than {limit} bytes ({limit_name}); use a smaller tessellation"
    )]
    BufferTooLarge {
        what: &'static str,
        bytes: u64,
        limit: u64,
        /// Which limit: the device's, or ntori's own cap on a scene's memory.
        limit_name: &'static str,
    },
    #[error(
        "genus {genus} at a tessellation of {t} makes {triangles} triangles; a picture may have at most {max}: use a smaller tessellation"
    )]
    TooManyTriangles {
        genus: u32,
        t: u32,
        triangles: u64,
        max: u64,
    },
    #[error("the surface is degenerate: its control points coincide, so it has no area to draw")]
    Degenerate,
    #[error(
        "vertex {index} lies at ({x:e}, {y:e}, {z:e}), beyond the 32-bit floats the GPU draws with (±3.4e38); scale the model down"
    )]
    NotDrawable {
        index: usize,
        x: f64,
        y: f64,
        z: f64,
    },
    #[error(
        "the surface spans {extent:e}, below what the GPU's 32-bit floats can tell apart: it would be drawn as one point; scale the model up"
    )]
    Collapses { extent: f64 },
    #[error("reading the image back from the GPU failed: {0}")]
    Readback(String),
    #[error("the PNG could not be encoded: {0}")]
    Png(String),
    #[error(transparent)]
    Model(#[from] embedding::EmbeddingError),
    #[error(transparent)]
    Charts(#[from] charts::ChartsError),
}

/// Where the camera is: degrees around the vertical axis (z) and above the horizontal plane, and
/// how far from the centre, in radii of the bounding sphere.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct View {
    pub azimuth_deg: f64,
    pub elevation_deg: f64,
    pub distance: f64,
}

impl Default for View {
    fn default() -> Self {
        View::DEFAULT
    }
}

impl View {
    /// The default view of `ntori render` and of the editor.
    pub const DEFAULT: View = View {
        azimuth_deg: 30.0,
        elevation_deg: 35.0,
        distance: 3.6,
    };

    /// Checks the numbers: finite, elevation within ±90°, distance beyond the bounding sphere.
    pub fn validate(&self) -> Result<(), RenderError> {
        let finite = [self.azimuth_deg, self.elevation_deg, self.distance]
            .iter()
            .all(|v| v.is_finite());
        if !finite || self.elevation_deg.abs() > 90.0 || !(1.05..=1000.0).contains(&self.distance) {
            return Err(RenderError::View(format!(
                "the view azimuth {}, elevation {}, distance {} is not possible: elevation must lie in −90 to 90 degrees and the distance in 1.05 to 1000 bounding radii",
                self.azimuth_deg, self.elevation_deg, self.distance
            )));
        }
        Ok(())
    }
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum CurvatureKind {
    Gaussian,
    Mean,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Style {
    Shaded,
    Wireframe,
    Charts,
    Curvature(CurvatureKind),
}

/// A picture's size, view, style and tessellation (t_e = t_r).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RenderOptions {
    pub width: u32,
    pub height: u32,
    pub view: View,
    pub style: Style,
    pub tessellation: u32,
}

impl Default for RenderOptions {
    fn default() -> Self {
        RenderOptions {
            width: 1024,
            height: 768,
            view: View::default(),
            style: Style::Shaded,
            tessellation: 32,
        }
    }
}

/// The tessellation `ntori render` draws a model of `genus` at where none is chosen: 32, or 64
/// from genus 8 on where that stays within [`DEFAULT_MAX_TRIANGLES`] (genus 8 to 13). At high genus the
/// t = 32 tessellation's triangles grow large on the plates' outer rim, and their chords showed as
/// notches in its silhouette (genus 10 and 16) where the surface is within 0.02% of the diagonal
/// of the intended rim (the `rim_report` example); at 64 they all but go.
pub fn default_tessellation(genus: u32) -> u32 {
    const FINE: u32 = 64;
    let fits = charts::Tessellation::expected_triangles(genus, FINE, FINE) <= DEFAULT_MAX_TRIANGLES;
    if genus >= 8 && fits { FINE } else { 32 }
}

/// The most triangles [`default_tessellation`] chooses at t = 64: genus 13 there has 1.1 million
/// (genus 8 to 13 get 64; from genus 14 the wheels take twice t_r's rings, see
/// `charts::Tessellation::wheel_rings`, and t = 32 is as fine across them), which lavapipe draws
/// at 1024 × 768 in a few seconds and whose vertex buffer stays well inside wgpu's default
/// 256 MiB limit.
pub const DEFAULT_MAX_TRIANGLES: u64 = 1_500_000;

/// A polyline on the surface, drawn on top of it.
#[derive(Clone, Debug, PartialEq)]
pub struct Curve {
    pub points: Vec<[f64; 3]>,
    pub colour: [f32; 3],
}

/// An RGBA image, rows top to bottom.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Image {
    pub width: u32,
    pub height: u32,
    pub rgba: Vec<u8>,
}

impl Image {
    /// PNG bytes (deterministic: same pixels, same bytes).
    pub fn to_png(&self) -> Result<Vec<u8>, RenderError> {
        let mut out = Vec::new();
        let mut encoder = png::Encoder::new(&mut out, self.width, self.height);
        encoder.set_color(png::ColorType::Rgba);
        encoder.set_depth(png::BitDepth::Eight);
        let mut writer = encoder
            .write_header()
            .map_err(|e| RenderError::Png(e.to_string()))?;
        writer
            .write_image_data(&self.rgba)
            .map_err(|e| RenderError::Png(e.to_string()))?;
        writer
            .finish()
            .map_err(|e| RenderError::Png(e.to_string()))?;
        Ok(out)
    }
}

/// The colour format of offscreen pictures: plain 8-bit, so the shader's colours are the pixels.
const OFFSCREEN_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba8Unorm;
/// Multisampling for smooth silhouettes.
const SAMPLES: u32 = 4;
/// The largest picture side accepted.
pub const MAX_SIDE: u32 = 8192;
/// The most triangles a picture may have. Building the scene holds about 740 bytes a triangle on
/// the CPU (measured: genus 1 at t = 256, 1 308 672 triangles, peaks at 967 MB: the tessellation,
/// the evaluated corners, the vertex buffer's copy), so this bounds the renderer near 3 GB. The
/// command line's cases that failed on wgpu's default limits (genus 2 at t = 255, genus 8 at 128,
/// genus 64 at 40) are all below it.
pub const MAX_TRIANGLES: u64 = 4_000_000;
/// The most bytes one buffer of a scene may take, whatever the device allows: the CPU holds a copy
/// of it (and more) while the scene is built, so this also bounds the renderer's memory.
pub const MAX_SCENE_BUFFER: u64 = 2 << 30;

/// Refuses a buffer of `bytes` that the device (`limits`) could not hold, or that is larger than
/// [`MAX_SCENE_BUFFER`]; `storage` for buffers bound as storage (their binding has its own limit).
/// Called before anything of that size is allocated, so an impossible request is an error rather
/// than wgpu's panic.
pub fn check_buffer(
    limits: &wgpu::Limits,
    what: &'static str,
    bytes: u64,
    storage: bool,
) -> Result<(), RenderError> {
    let mut checks = vec![
        (
            limits.max_buffer_size,
            "the graphics device's max_buffer_size",
        ),
        (MAX_SCENE_BUFFER, "ntori's cap on one scene buffer"),
    ];
    if storage {
        checks.push((
            limits.max_storage_buffer_binding_size,
            "the graphics device's max_storage_buffer_binding_size",
        ));
    }
    match checks.into_iter().filter(|&(limit, _)| bytes > limit).min() {
        Some((limit, limit_name)) => Err(RenderError::BufferTooLarge {
            what,
            bytes,
            limit,
            limit_name,
        }),
        None => Ok(()),
    }
}

/// Opens a device on the first adapter wgpu finds, with the adapter's own buffer limits (wgpu's
/// defaults are far below what most adapters allow), capped at `max_buffer_size` where given.
/// Returns the device, its queue and the adapter's name.
pub fn open_device(
    max_buffer_size: Option<u64>,
) -> Result<(wgpu::Device, wgpu::Queue, String), RenderError> {
    // Vulkan (or Metal, DX12) first: probing OpenGL through EGL without a display only prints
    // errors. OpenGL is the fallback where nothing else exists.
    let adapter = request_adapter(wgpu::Backends::PRIMARY)
        .or_else(|_| request_adapter(wgpu::Backends::all()))?;
    let adapter_name = adapter.get_info().name;
    let available = adapter.limits();
    let mut limits = wgpu::Limits::downlevel_defaults().using_resolution(available.clone());
    limits.max_buffer_size = available.max_buffer_size;
    limits.max_storage_buffer_binding_size = available.max_storage_buffer_binding_size;
    if let Some(cap) = max_buffer_size {
        limits.max_buffer_size = limits.max_buffer_size.min(cap);
        limits.max_storage_buffer_binding_size = limits.max_storage_buffer_binding_size.min(cap);
    }
    let (device, queue) = pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
        label: Some("ntori offscreen"),
        required_features: wgpu::Features::empty(),
        required_limits: limits,
        experimental_features: Default::default(),
        memory_hints: wgpu::MemoryHints::MemoryUsage,
        trace: Default::default(),
    }))
    .map_err(|e| RenderError::Device(e.to_string()))?;
    Ok((device, queue, adapter_name))
}

fn request_adapter(backends: wgpu::Backends) -> Result<wgpu::Adapter, RenderError> {
    let instance = wgpu::Instance::new(wgpu::InstanceDescriptor {
        backends,
        ..wgpu::InstanceDescriptor::new_without_display_handle()
    });
    pollster::block_on(instance.request_adapter(&wgpu::RequestAdapterOptions {
        power_preference: wgpu::PowerPreference::HighPerformance,
        force_fallback_adapter: false,
        compatible_surface: None,
        ..Default::default()
    }))
    .map_err(|e| RenderError::NoAdapter(e.to_string()))
}

/// A GPU device for pictures without a window, reused from one picture to the next.
pub struct Offscreen {
    device: wgpu::Device,
    queue: wgpu::Queue,
    renderer: SurfaceRenderer,
    adapter_name: String,
}

impl Offscreen {
    /// Opens the first adapter wgpu finds (a GPU, or Mesa's lavapipe on a machine without one).
    pub fn new() -> Result<Offscreen, RenderError> {
        Offscreen::with_max_buffer_size(None)
    }

    /// Like [`Offscreen::new`], with no buffer larger than `max_buffer_size` bytes where given (to
    /// leave GPU memory to others, or to test what happens at the limit).
    pub fn with_max_buffer_size(max_buffer_size: Option<u64>) -> Result<Offscreen, RenderError> {
        let (device, queue, adapter_name) = open_device(max_buffer_size)?;
        let renderer = SurfaceRenderer::new(&device, OFFSCREEN_FORMAT, SAMPLES);
        tracing::info!(adapter = %adapter_name, "offscreen renderer ready");
        Ok(Offscreen {
            device,
            queue,
            renderer,
            adapter_name,
        })
    }

    /// The adapter's name (e.g. "llvmpipe (LLVM 15.0.6, 256 bits)").
    pub fn adapter_name(&self) -> &str {
        &self.adapter_name
    }

    /// The model's surface, tessellated at `options.tessellation`, as PNG bytes.
    pub fn render_model_png(
        &mut self,
        model: &Surface,
        options: &RenderOptions,
        curves: &[Curve],
    ) -> Result<Vec<u8>, RenderError> {
        self.render_model(model, options, curves)?.to_png()
    }

    /// The model's surface as an image.
    pub fn render_model(
        &mut self,
        model: &Surface,
        options: &RenderOptions,
        curves: &[Curve],
    ) -> Result<Image, RenderError> {
        self.check(options)?;
        // The scene's size is known in closed form: refuse it before tessellating anything.
        let t = options.tessellation;
        let corners = 3 * charts::Tessellation::expected_triangles(model.genus(), t, t);
        let bytes = corners.saturating_mul(std::mem::size_of::<gpu::SurfaceVertex>() as u64);
        check_buffer(
            &self.device.limits(),
            "surface's vertex buffer",
            bytes,
            false,
        )?;
        let triangles = corners / 3;
        if triangles > MAX_TRIANGLES {
            return Err(RenderError::TooManyTriangles {
                genus: model.genus(),
                t,
                triangles,
                max: MAX_TRIANGLES,
            });
        }
        let geometry = scene::model_geometry(model, options.tessellation, options.style, curves)?;
        self.draw(&geometry, options)
    }

    /// A triangle mesh (flat shaded) as PNG bytes.
    pub fn render_mesh_png(
        &mut self,
        positions: &[[f64; 3]],
        triangles: &[[u32; 3]],
        options: &RenderOptions,
    ) -> Result<Vec<u8>, RenderError> {
        self.check(options)?;
        let geometry = scene::mesh_geometry(positions, triangles)?;
        self.draw(&geometry, options)?.to_png()
    }

    fn check(&self, options: &RenderOptions) -> Result<(), RenderError> {
        let max = MAX_SIDE.min(self.device.limits().max_texture_dimension_2d);
        if !(1..=max).contains(&options.width) || !(1..=max).contains(&options.height) {
            return Err(RenderError::Size {
                width: options.width,
                height: options.height,
                max,
            });
        }
        options.view.validate()
    }

    fn draw(
        &self,
        geometry: &SceneGeometry,
        options: &RenderOptions,
    ) -> Result<Image, RenderError> {
        let (width, height) = (options.width, options.height);
        let camera = Camera {
            centre: geometry.centre,
            radius: geometry.radius,
            view: options.view,
            aspect: width as f32 / height as f32,
        };
        let scene = GpuScene::new(&self.device, &geometry.vertices, &geometry.segments)?;
        let mut frame = camera.uniforms(options.style, (width, height));
        if geometry.legend.is_some() {
            // Leave room at the right for the legend.
            let shift = glam::Mat4::from_translation(glam::Vec3::new(-0.14, 0.0, 0.0));
            frame.view_proj =
                (shift * glam::Mat4::from_cols_array_2d(&frame.view_proj)).to_cols_array_2d();
        }
        self.renderer.set_frame(&self.queue, &frame);
        let targets = Targets::new(
            &self.device,
            "ntori",
            [width, height],
            OFFSCREEN_FORMAT,
            SAMPLES,
            wgpu::TextureUsages::empty(),
        );
        let mut encoder = self
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor { label: None });
        {
            let mut pass = targets.begin_pass(&mut encoder, "ntori picture", wgpu::Color::WHITE);
            self.renderer.paint(&mut pass, &scene);
        }
        let mut image = targets.read_back(&self.device, &self.queue, encoder)?;
        if let Some((kind, range)) = geometry.legend {
            legend::draw(&mut image, kind, range);
        }
        Ok(image)
    }
}
