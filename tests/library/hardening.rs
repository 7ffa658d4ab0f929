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

#[test]
fn exclusive_write_keeps_a_file_created_meanwhile() {
    use ntori::io::atomic::{FileError, write_new_with};
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("m.json");
    // Another process creates the file while ntori is still writing its own.
    let err = write_new_with(&path, |w| {
        std::fs::write(&path, "theirs")?;
        w.write_all(b"ours")
    })
    .expect_err("the file appeared meanwhile");
    assert!(matches!(err, FileError::Exists { .. }), "{err:?}");
    assert!(err.to_string().contains("m.json"), "{err}");
    assert_eq!(std::fs::read_to_string(&path).unwrap(), "theirs");
    // And nothing is left behind.
    let names: Vec<_> = std::fs::read_dir(dir.path())
        .unwrap()
        .map(|e| e.unwrap().file_name())
        .collect();
    assert_eq!(names, ["m.json"]);
    // Where no file exists, it is written.
    let fresh = dir.path().join("fresh.json");
    write_new_with(&fresh, |w| w.write_all(b"ours")).unwrap();
    assert_eq!(std::fs::read_to_string(&fresh).unwrap(), "ours");
}

/// A process id that no running process has.
fn dead_pid() -> u32 {
    (1..4_000_000u32)
        .rev()
        .find(|pid| !std::path::Path::new("/proc").join(pid.to_string()).exists())
        .unwrap()
}

#[test]
fn stale_temporaries_of_dead_writers_are_removed() {
    use ntori::io::atomic::{STALE_AFTER, write_atomically};
    let dir = tempfile::tempdir().unwrap();
    let old = std::time::SystemTime::now() - STALE_AFTER - std::time::Duration::from_secs(60);
    let make = |name: String, modified: std::time::SystemTime| {
        let path = dir.path().join(name);
        let file = std::fs::File::create(&path).unwrap();
        file.set_modified(modified).unwrap();
        path
    };
    let dead = dead_pid();
    let stale = make(format!(".ntori-{dead}-AbC123.tmp"), old);
    let recent = make(
        format!(".ntori-{dead}-DeF456.tmp"),
        std::time::SystemTime::now(),
    );
    let live = make(format!(".ntori-{}-GhI789.tmp", std::process::id()), old);
    let foreign = make(".other-1-x.tmp".into(), old);
    write_atomically(&dir.path().join("out.txt"), b"x").unwrap();
    assert!(!stale.exists(), "a dead writer's old file is litter");
    assert!(recent.exists(), "a recent file may belong to a reused pid");
    assert!(live.exists(), "a live writer's file is never touched");
    assert!(foreign.exists(), "only ntori's own names");
}

#[test]
fn file_errors_name_the_target_not_a_temporary_file() {
    use ntori::io::atomic::write_atomically;
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("out.txt");
    let err = write_atomically_failing(&path);
    let text = err.to_string();
    assert!(text.contains("out.txt"), "{text}");
    assert!(!text.contains(".ntori-"), "{text}");
    assert_eq!(text.matches("out.txt").count(), 1, "{text}");
    // A directory that takes no files: the message names the target and the directory once each.
    let locked = dir.path().join("locked");
    std::fs::create_dir(&locked).unwrap();
    std::fs::set_permissions(&locked, std::os::unix::fs::PermissionsExt::from_mode(0o500)).unwrap();
    let target = locked.join("m.json");
    if let Err(e) = write_atomically(&target, b"x") {
        let text = e.to_string();
        assert!(!text.contains(".ntori-"), "{text}");
        assert_eq!(text.matches("m.json").count(), 1, "{text}");
    } // else: running as root, which may write anywhere.
}

fn write_atomically_failing(path: &std::path::Path) -> ntori::io::atomic::FileError {
    ntori::io::atomic::write_atomically_with(path, |_| {
        Err(std::io::Error::other("the writer failed"))
    })
    .expect_err("the writer fails")
}

#[test]
fn fits_beyond_the_memory_cap_are_refused_before_fitting() {
    use embedding::EmbeddingError;
    use embedding::fit::{FitSettings, MAX_FIT_TRIANGLES, initial_model};
    let settings = embedding::SplineSettings::default();
    // Genus 64 makes 1.8 million triangles even at resolution 8: meshing stops at the cap.
    let Err(err) = initial_model(64, 8, settings, FitSettings::default()) else {
        panic!("genus 64 is refused");
    };
    let EmbeddingError::FitTooLarge {
        triangles,
        at_least,
        max,
        ..
    } = &err
    else {
        panic!("expected FitTooLarge, got {err:?}");
    };
    assert!(*at_least && *triangles > MAX_FIT_TRIANGLES && *max == MAX_FIT_TRIANGLES);
    let text = err.to_string();
    assert!(
        text.contains("GB to fit") && text.contains("lower the resolution"),
        "{text}"
    );
    // The largest genus-16 mesh at resolution 32 is within the cap: it is meshed, not refused.
    let mesh = embedding::holed::HoledMesh::new(16, 32).unwrap();
    assert!(mesh.triangles.len() <= MAX_FIT_TRIANGLES);
}
