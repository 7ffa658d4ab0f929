//! Hardening (issue 16) through the library: limits checked before anything is allocated, so an
//! impossible request is a typed error, never a panic.

use ntori::editor::gpu::ViewportRenderer;
use ntori::editor::mesh::LiveMesh;
use ntori::render::gpu::{GpuScene, SurfaceVertex};
use ntori::render::{Offscreen, RenderError, RenderOptions, Style, open_device};

use crate::common::small_model;

/// A buffer cap far below what a tessellation of 32 needs (genus 2: 121 344 corners of 48 bytes).
const SMALL_CAP: u64 = 1 << 20;

#[test]
fn render_refuses_a_scene_beyond_the_devices_buffer_limit() {
    let mut offscreen = Offscreen::with_max_buffer_size(Some(SMALL_CAP))
        .expect("a graphics adapter (CI installs mesa-vulkan-drivers)");
    let options = RenderOptions {
        width: 64,
        height: 48,
        tessellation: 32,
        ..RenderOptions::default()
    };
    let err = offscreen
        .render_model(small_model(2), &options, &[])
        .expect_err("5.8 MB of vertices do not fit a 1 MiB buffer");
    let RenderError::BufferTooLarge { bytes, limit, .. } = &err else {
        panic!("expected BufferTooLarge, got {err:?}");
    };
    assert_eq!((*bytes, *limit), (121_344 * 48, SMALL_CAP));
    let text = err.to_string();
    assert!(text.contains("max_buffer_size"), "{text}");
    assert!(text.contains("1048576 bytes"), "{text}");
    // Within the limit the same device draws.
    let small = RenderOptions {
        tessellation: 4,
        ..options
    };
    offscreen
        .render_model(small_model(2), &small, &[])
        .expect("a tessellation of 4 fits in 1 MiB");
}

#[test]
fn gpu_scene_checks_its_buffers_before_uploading() {
    let (device, _queue, _) = open_device(Some(SMALL_CAP)).expect("a graphics adapter");
    let zero = SurfaceVertex {
        position: [0.0; 3],
        normal: [0.0; 3],
        colour: [0.0; 3],
        bary: [0.0; 3],
    };
    let vertices = vec![zero; (SMALL_CAP / 48 + 1) as usize];
    let err = GpuScene::new(&device, &vertices, &[])
        .err()
        .expect("one vertex too many");
    assert!(
        matches!(err, RenderError::BufferTooLarge { limit, .. } if limit == SMALL_CAP),
        "{err:?}"
    );
    assert!(GpuScene::new(&device, &vertices[1..], &[]).is_ok());
}

#[test]
fn editor_upload_checks_its_buffers() {
    let (device, queue, _) = open_device(Some(SMALL_CAP)).expect("a graphics adapter");
    let mut mesh = LiveMesh::new(small_model(2), 64, 64, Style::Shaded).unwrap();
    let mut renderer = ViewportRenderer::new(&device);
    let err = renderer
        .sync(&device, &queue, &mut mesh, None)
        .expect_err("the editor's vertices do not fit 1 MiB");
    assert!(err.to_string().contains("editor's"), "{err}");
    // Asked again (the next frame), the same answer, still without a panic.
    assert!(renderer.sync(&device, &queue, &mut mesh, None).is_err());
    let mut small = LiveMesh::new(small_model(2), 2, 2, Style::Shaded).unwrap();
    assert!(renderer.sync(&device, &queue, &mut small, None).is_ok());
}
