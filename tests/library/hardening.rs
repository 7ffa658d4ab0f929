//! Hardening (issue 16) through the library: limits checked before anything is allocated, so an
//! impossible request is a typed error, never a panic.

use ntori::editor::gpu::ViewportRenderer;
use ntori::editor::mesh::LiveMesh;
use ntori::io::export::Meshing;
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
    let mut mesh = LiveMesh::new(
        small_model(2),
        Meshing::TeTr { te: 64, tr: 64 },
        Style::Shaded,
    )
    .unwrap();
    let mut renderer = ViewportRenderer::new(&device);
    let err = renderer
        .sync(&device, &queue, &mut mesh, None)
        .expect_err("the editor's vertices do not fit 1 MiB");
    assert!(err.to_string().contains("editor's"), "{err}");
    // Asked again (the next frame), the same answer, still without a panic.
    assert!(renderer.sync(&device, &queue, &mut mesh, None).is_err());
    let mut small = LiveMesh::new(
        small_model(2),
        Meshing::TeTr { te: 2, tr: 2 },
        Style::Shaded,
    )
    .unwrap();
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

#[test]
fn a_directory_that_takes_no_files_is_named_without_the_temporary_file() {
    // /proc takes no new files, not even from root: tempfile's error names its temporary file,
    // which the message must not show.
    let target = std::path::Path::new("/proc/ntori-hardening.txt");
    if !std::path::Path::new("/proc/self").exists() {
        return; // not Linux
    }
    let err = ntori::io::atomic::write_atomically(target, b"x").expect_err("/proc takes no files");
    let text = err.to_string();
    assert!(!text.contains(".ntori-"), "{text}");
    assert!(!text.contains(".tmp"), "{text}");
    assert_eq!(text.matches("ntori-hardening.txt").count(), 1, "{text}");
}

#[test]
fn saved_models_hold_only_finite_numbers() {
    let surface = small_model(1);
    let mut points = surface.control_points().to_vec();
    points[3].y = f64::NAN;
    assert!(surface.with_control_points(points.clone()).is_err());
    points[3].y = f64::INFINITY;
    assert!(surface.with_control_points(points).is_err());
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("m.json");
    ntori::io::model_file::save(&path, surface).unwrap();
    let text = std::fs::read_to_string(&path).unwrap();
    assert!(!text.contains("null") && !text.contains("NaN"), "{text}");
    assert_eq!(&ntori::io::model_file::load(&path).unwrap(), surface);
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
    // Genus 64 at resolution 48 makes far more triangles than the cap (at 8 it makes 223 516, at
    // 24 928 100), and is refused before it is meshed, from a lower bound on the count ("more
    // than").
    let started = std::time::Instant::now();
    let Err(err) = initial_model(64, 48, settings, FitSettings::default()) else {
        panic!("genus 64 at resolution 48 is refused");
    };
    let EmbeddingError::FitTooLarge {
        triangles,
        max,
        at_least,
        ..
    } = &err
    else {
        panic!("expected FitTooLarge, got {err:?}");
    };
    assert!(
        *triangles > MAX_FIT_TRIANGLES && *max == MAX_FIT_TRIANGLES && *at_least,
        "{err:?}"
    );
    eprintln!("refused in {:?}", started.elapsed());
    let text = err.to_string();
    assert!(
        text.contains("GB to fit") && text.contains("lower the resolution"),
        "{text}"
    );
    // The largest genus-16 mesh at resolution 32 is within the cap: it is meshed, not refused.
    let mesh = embedding::holed::HoledMesh::new(16, 32).unwrap();
    assert!(mesh.triangles.len() <= MAX_FIT_TRIANGLES);
}

#[test]
fn absurd_control_points_are_refused_at_load_with_their_index() {
    use embedding::EmbeddingError;
    use embedding::model::MAX_COORDINATE;
    use ntori::io::model_file::{self, ModelFileError};
    let good = small_model(1).to_model();
    let path = std::path::Path::new("absurd.json");
    let with = |index: usize, value: f64| {
        let mut model = good.clone();
        model.control_points[index][1] = value;
        model
    };
    for (index, value) in [(5, 1e300), (17, -1e10), (0, MAX_COORDINATE * (1.0 + 1e-15))] {
        let model = with(index, value);
        assert_eq!(
            model.check_control_points(),
            Err(EmbeddingError::OutOfRange {
                index,
                value,
                max: MAX_COORDINATE
            })
        );
        let layout = small_model(1).layout();
        assert!(model.validate(&layout).is_err());
        let text = serde_json::to_string(&model).unwrap();
        let err = model_file::from_bytes(path, text.as_bytes()).unwrap_err();
        assert!(matches!(err, ModelFileError::Inconsistent { .. }), "{err}");
        let message = err.to_string();
        assert!(
            message.contains(&format!(
                "control point {index} has a coordinate of {value:e}"
            )) && message.contains("absurd.json"),
            "{message}"
        );
    }
    // The bound itself loads.
    let edge = with(3, -MAX_COORDINATE);
    assert_eq!(edge.check_control_points(), Ok(()));
    let text = serde_json::to_string(&edge).unwrap();
    model_file::from_bytes(path, text.as_bytes()).unwrap();
    // Non-finite coordinates keep their own error.
    assert_eq!(
        with(2, f64::NAN).check_control_points(),
        Err(EmbeddingError::NotFinite(2))
    );
    // A surface beyond the bound (an edit can make one) is not saved: it would not load back.
    let mut points = small_model(1).control_points().to_vec();
    points[9].x = 1e12;
    let far = small_model(1).with_control_points(points).unwrap();
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("far.json");
    let err = model_file::save(&out, &far).unwrap_err();
    assert!(matches!(err, ModelFileError::Unloadable { .. }), "{err}");
    assert!(err.to_string().contains("control point 9"), "{err}");
    assert!(!out.exists());
}

// ----------------------------------------------------------------------------------- fuzzing

/// Interesting replacements for a number in a model file.
const TOKENS: &[&str] = &[
    "1e309",
    "-1e309",
    "NaN",
    "null",
    "1e-400",
    "4294967296",
    "-1",
    "0",
    "-0",
    "3.5e38",
    "1e155",
    "1e-46",
    "\"x\"",
    "[]",
    "{}",
    "true",
    "99999999999999999999999",
    "4096",
    "7",
    "64",
    "65",
    "1.5",
];

/// One edit of a model file's bytes.
#[derive(Clone, Debug)]
enum Mutation {
    FlipBit(proptest::sample::Index, u8),
    SetByte(proptest::sample::Index, u8),
    Insert(proptest::sample::Index, Vec<u8>),
    Delete(proptest::sample::Index, usize),
    Truncate(proptest::sample::Index),
    /// The nth number replaced by a token of [`TOKENS`].
    Number(proptest::sample::Index, proptest::sample::Index),
    /// A span copied elsewhere (duplicate keys, repeated points, nested arrays).
    Splice(proptest::sample::Index, usize, proptest::sample::Index),
}

fn mutation() -> impl proptest::strategy::Strategy<Value = Mutation> {
    use proptest::prelude::*;
    prop_oneof![
        1 => (any::<proptest::sample::Index>(), 0u8..8).prop_map(|(i, b)| Mutation::FlipBit(i, b)),
        1 => (any::<proptest::sample::Index>(), any::<u8>()).prop_map(|(i, b)| Mutation::SetByte(i, b)),
        1 => (
            any::<proptest::sample::Index>(),
            proptest::collection::vec(
                prop_oneof![
                    Just(b'['),
                    Just(b']'),
                    Just(b'{'),
                    Just(b'}'),
                    Just(b','),
                    Just(b':'),
                    Just(b'"'),
                    Just(b'\\'),
                    any::<u8>()
                ],
                1..8
            )
        )
            .prop_map(|(i, b)| Mutation::Insert(i, b)),
        1 => (any::<proptest::sample::Index>(), 1usize..64).prop_map(|(i, n)| Mutation::Delete(i, n)),
        1 => any::<proptest::sample::Index>().prop_map(Mutation::Truncate),
        // Weighted up: replacing numbers keeps the JSON valid and reaches the model's checks.
        4 => (
            any::<proptest::sample::Index>(),
            any::<proptest::sample::Index>()
        )
            .prop_map(|(i, t)| Mutation::Number(i, t)),
        2 => (
            any::<proptest::sample::Index>(),
            1usize..200,
            any::<proptest::sample::Index>()
        )
            .prop_map(|(f, n, t)| Mutation::Splice(f, n, t)),
    ]
}

fn apply(bytes: &mut Vec<u8>, m: &Mutation) {
    if bytes.is_empty() {
        return;
    }
    let len = bytes.len();
    match m {
        Mutation::FlipBit(i, b) => bytes[i.index(len)] ^= 1 << b,
        Mutation::SetByte(i, b) => bytes[i.index(len)] = *b,
        Mutation::Insert(i, b) => {
            let at = i.index(len + 1);
            bytes.splice(at..at, b.iter().copied());
        }
        Mutation::Delete(i, n) => {
            let at = i.index(len);
            bytes.drain(at..(at + n).min(len));
        }
        Mutation::Truncate(i) => bytes.truncate(i.index(len)),
        Mutation::Number(i, t) => {
            // Runs of number characters after a ':' ',' or '['.
            let mut numbers = Vec::new();
            let mut k = 0;
            while k < len {
                let starts = matches!(bytes[k], b'-' | b'0'..=b'9')
                    && (k == 0 || matches!(bytes[k - 1], b':' | b',' | b'['));
                if starts {
                    let end = (k..len)
                        .find(|&e| {
                            !matches!(bytes[e], b'-' | b'+' | b'.' | b'e' | b'E' | b'0'..=b'9')
                        })
                        .unwrap_or(len);
                    numbers.push(k..end);
                    k = end;
                } else {
                    k += 1;
                }
            }
            if !numbers.is_empty() {
                let range = numbers[i.index(numbers.len())].clone();
                let token = TOKENS[t.index(TOKENS.len())].as_bytes();
                bytes.splice(range, token.iter().copied());
            }
        }
        Mutation::Splice(f, n, t) => {
            let from = f.index(len);
            let span: Vec<u8> = bytes[from..(from + n).min(len)].to_vec();
            let to = t.index(len + 1);
            bytes.splice(to..to, span);
        }
    }
}

/// The seeds: every file of `tests/fuzz-corpus/` (valid models of genus 0, 1 and 2).
fn corpus() -> Vec<Vec<u8>> {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fuzz-corpus");
    let mut files: Vec<_> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .collect();
    files.sort();
    files.iter().map(|p| std::fs::read(p).unwrap()).collect()
}

/// Mutated model files (1 to 4 edits of a corpus file) never make the loader panic; what it
/// accepts is a valid surface that saves and loads back the same; what it refuses gets one short
/// message naming the file once. NTORI_FUZZ_CASES sets the number of cases (default 10 000; the
/// long run used 10⁶).
#[test]
fn fuzz_model_loader() {
    use proptest::strategy::Strategy as _;
    use std::collections::BTreeMap;
    let cases: u32 = std::env::var("NTORI_FUZZ_CASES")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(10_000);
    let seeds = corpus();
    assert!(!seeds.is_empty());
    // Every seed loads as is.
    let name = std::path::Path::new("fuzzed.json");
    for seed in &seeds {
        ntori::io::model_file::from_bytes(name, seed).expect("a corpus file loads");
    }
    let strategy = (
        proptest::sample::select((0..seeds.len()).collect::<Vec<_>>()),
        proptest::collection::vec(mutation(), 1..5),
    );
    let outcomes = std::cell::RefCell::new(BTreeMap::<String, u64>::new());
    let mut runner = proptest::test_runner::TestRunner::new(proptest::test_runner::Config {
        cases,
        failure_persistence: None,
        ..Default::default()
    });
    let start = std::time::Instant::now();
    let result = runner.run(&strategy.boxed(), |(seed, mutations)| {
        let mut bytes = seeds[seed].clone();
        for m in &mutations {
            apply(&mut bytes, m);
        }
        let loaded = std::panic::catch_unwind(|| ntori::io::model_file::from_bytes(name, &bytes))
            .map_err(|_| {
            proptest::test_runner::TestCaseError::fail(format!(
                "the loader panicked on {:?}",
                String::from_utf8_lossy(&bytes)
            ))
        })?;
        let outcome = match &loaded {
            Ok(surface) => {
                let text = serde_json::to_string(&surface.to_model()).unwrap();
                let back = ntori::io::model_file::from_bytes(name, text.as_bytes())
                    .map_err(|e| proptest::test_runner::TestCaseError::fail(e.to_string()))?;
                proptest::prop_assert_eq!(&back, surface);
                "accepted".to_owned()
            }
            Err(e) => {
                let text = e.to_string();
                proptest::prop_assert!(text.len() <= 1_000, "a long message: {}", text);
                proptest::prop_assert_eq!(text.matches("fuzzed.json").count(), 1, "{}", text);
                format!("{e:?}")
                    .split([' ', '(', '{'])
                    .next()
                    .unwrap()
                    .to_owned()
            }
        };
        *outcomes.borrow_mut().entry(outcome).or_default() += 1;
        Ok(())
    });
    let seconds = start.elapsed().as_secs_f64();
    let outcomes = outcomes.into_inner();
    let executions: u64 = outcomes.values().sum();
    eprintln!(
        "fuzz_model_loader: {executions} executions in {seconds:.1} s ({:.0}/s), findings: {}; outcomes {outcomes:?}",
        executions as f64 / seconds,
        if result.is_ok() { 0 } else { 1 }
    );
    result.unwrap();
}
