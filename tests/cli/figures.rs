//! `ntori figures` end to end: the files it writes, the caption file, byte-identical re-runs, and a
//! clear error for a directory it cannot create. The PNG figures need a graphics adapter (a GPU or
//! Mesa's software one); where there is none the run leaves them out, says so, and they are skipped.

use std::path::Path;

use predicates::prelude::*;

use crate::common::ntori;

const SVG: [&str; 6] = [
    "fig1-polygon.svg",
    "fig2a-corners.svg",
    "fig3-hyperbolic-polygon.svg",
    "fig4-charts.svg",
    "fig5-overlaps.svg",
    "fig7-tessellation.svg",
];

/// The PNG figures and their sizes in pixels.
const PNG: [(&str, u32, u32); 16] = [
    ("fig2b-loops.png", 1200, 900),
    ("fig6a-input-mesh.png", 1200, 900),
    ("fig6b-fitted.png", 1200, 900),
    ("fig6c-edit-rim.png", 1200, 900),
    ("fig6d-edit-hole.png", 1200, 900),
    ("gallery-genus0.png", 800, 600),
    ("gallery-genus1.png", 800, 600),
    ("gallery-genus2.png", 800, 600),
    ("gallery-genus3.png", 800, 600),
    ("gallery-genus4.png", 800, 600),
    ("gallery-genus5.png", 800, 600),
    ("gallery-genus6.png", 800, 600),
    ("gallery-genus32.png", 800, 600),
    ("gallery-genus32-mean.png", 800, 600),
    ("gallery-genus2-charts.png", 800, 600),
    ("gallery-genus2-gaussian.png", 800, 600),
];

fn listing(dir: &Path) -> Vec<String> {
    let mut files: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().into_string().unwrap())
        .collect();
    files.sort();
    files
}

#[test]
fn writes_every_figure_with_its_caption_and_the_same_bytes_again() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("new").join("figures");
    let run = ntori()
        .arg("figures")
        .arg("--out")
        .arg(&out)
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&run.stderr);
    assert!(run.status.success(), "{stderr}");
    let captions = std::fs::read_to_string(out.join("CAPTIONS.md")).unwrap();
    let files = listing(&out);
    for f in SVG {
        assert!(files.iter().any(|g| g == f), "{f} missing: {files:?}");
    }
    let rendered = !captions.contains("were not made");
    if rendered {
        for (f, w, h) in PNG {
            let bytes = std::fs::read(out.join(f)).unwrap_or_else(|e| panic!("{f}: {e}"));
            let reader = png::Decoder::new(std::io::Cursor::new(bytes))
                .read_info()
                .unwrap();
            let info = reader.info();
            assert_eq!((info.width, info.height), (w, h), "{f}");
        }
        assert!(files.iter().any(|g| g == "gallery-genus2-mean.png"));
    } else {
        eprintln!("no graphics adapter here: the PNG figures are left out, as the run says");
        assert!(stderr.contains("were not made"), "{stderr}");
        assert!(!files.iter().any(|f| f.ends_with(".png")));
    }
    // The caption file lists every file written (and nothing else), each with its parameters.
    for f in files.iter().filter(|f| *f != "CAPTIONS.md") {
        assert!(
            captions.contains(&format!("## {f}\n")),
            "CAPTIONS.md lacks {f}"
        );
    }
    assert_eq!(
        captions.matches("\n## ").count(),
        files.len() - 1,
        "{captions}"
    );
    assert_eq!(captions.matches("\nParameters: ").count(), files.len() - 1);
    // Not a terminal: no progress bar, and --quiet is not needed for a clean stdout.
    assert_eq!(
        String::from_utf8_lossy(&run.stdout).trim(),
        format!("wrote {} files to {}", files.len(), out.display())
    );
    // A re-run writes the same bytes.
    let before: Vec<Vec<u8>> = files
        .iter()
        .map(|f| std::fs::read(out.join(f)).unwrap())
        .collect();
    ntori()
        .args(["figures", "--quiet", "--out"])
        .arg(&out)
        .assert()
        .success()
        .stdout("");
    assert_eq!(listing(&out), files);
    for (f, b) in files.iter().zip(before) {
        assert!(
            std::fs::read(out.join(f)).unwrap() == b,
            "{f} changed on a re-run"
        );
    }
}

#[test]
fn a_directory_that_cannot_be_made_is_a_clear_error() {
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("plain-file");
    std::fs::write(&file, "not a directory").unwrap();
    for out in [file.join("figures"), file.clone()] {
        ntori()
            .args(["figures", "--quiet", "--out"])
            .arg(&out)
            .assert()
            .code(1)
            .stderr(predicate::str::contains(format!(
                "cannot create the figure directory {}",
                out.display()
            )));
    }
    assert_eq!(std::fs::read_to_string(&file).unwrap(), "not a directory");
}
