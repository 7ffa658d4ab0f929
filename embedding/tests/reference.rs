//! ntori's Floater map against CGAL's (issue 14): `floater::parameterize` and CGAL's
//! `Mean_value_coordinates_parameterizer_3` on the same disks with the same fixed convex boundary,
//! every vertex compared. The reference is a small C++ driver (`tests/cgal/floater_reference.cpp`),
//! compiled here once per target directory (about 25 s) with g++ against Debian's `libcgal-dev` and
//! `libeigen3-dev`, both header-only.
//!
//! The disks: the real cut disks of `HoledMesh` (genus 1, 2, 3) pinned to the regular 4n-gon as
//! the Klein model draws it (straight sides, boundary vertices spaced by 3D arc length along each
//! side), and seeded bumpy height-field disks with an irregular triangulation pinned to a circle.
//!
//! Where g++ or the headers are missing the test prints "skipped" and passes, unless
//! NTORI_REQUIRE_TOOLS is set (`.ci/run` sets it after installing them): there it fails.

use std::f64::consts::TAU;
use std::fs::File;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::sync::OnceLock;

use embedding::Point3;
use embedding::fit::cut;
use embedding::floater;
use embedding::holed::HoledMesh;

/// The largest allowed difference between the two maps, relative to the boundary's size (every
/// disk here is pinned inside the unit disk, so the size is 1). Both sides solve the same linear
/// system with a direct LU (faer's, Eigen's); the measured differences grow with the mesh, from
/// 3e-15 (169 vertices) to 7e-14 (2401 vertices), so this leaves a margin of ten or more.
const TOLERANCE: f64 = 1e-12;

/// The driver's source.
fn source() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/cgal/floater_reference.cpp")
}

/// Where the test keeps the driver and its inputs.
fn work_dir() -> PathBuf {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join("cgal");
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// The compiled driver, or why there is none (a missing tool, not a broken driver: that panics).
fn driver() -> Result<PathBuf, String> {
    static DRIVER: OnceLock<Result<PathBuf, String>> = OnceLock::new();
    DRIVER.get_or_init(compile).clone()
}

fn compile() -> Result<PathBuf, String> {
    let binary = work_dir().join("floater_reference");
    let modified = |p: &Path| std::fs::metadata(p).and_then(|m| m.modified()).ok();
    if let (Some(built), Some(written)) = (modified(&binary), modified(&source()))
        && built > written
    {
        return Ok(binary);
    }
    let out = Command::new("g++")
        .args([
            "-O2",
            "-std=c++17",
            "-DCGAL_EIGEN3_ENABLED",
            "-I/usr/include/eigen3",
        ])
        .arg(source())
        .arg("-o")
        .arg(&binary)
        .output()
        .map_err(|e| format!("g++ cannot run ({e}); install g++"))?;
    if out.status.success() {
        return Ok(binary);
    }
    let stderr = String::from_utf8_lossy(&out.stderr);
    // A missing header is a missing tool; any other error is the driver's own fault.
    if let Some(line) = stderr
        .lines()
        .find(|l| l.contains("fatal error") && l.contains("No such file"))
    {
        return Err(format!(
            "CGAL or Eigen headers are missing ({}); install libcgal-dev libeigen3-dev",
            line.trim()
        ));
    }
    panic!("g++ could not build the CGAL driver:\n{stderr}");
}

/// The driver, or `None` after saying why it is skipped (a failure under NTORI_REQUIRE_TOOLS).
fn require_driver() -> Option<PathBuf> {
    match driver() {
        Ok(path) => Some(path),
        Err(why) => {
            assert!(
                std::env::var_os("NTORI_REQUIRE_TOOLS").is_none(),
                "NTORI_REQUIRE_TOOLS is set, but {why}"
            );
            eprintln!("skipped: {why}");
            None
        }
    }
}

/// A disk to flatten: positions, counter-clockwise triangles, the boundary's fixed positions.
struct Disk {
    name: String,
    positions: Vec<Point3>,
    triangles: Vec<[u32; 3]>,
    pins: Vec<(u32, [f64; 2])>,
}

/// CGAL's map of the disk (`solver`: "lu" or "bicgstab", see the driver), every vertex in order.
fn cgal(driver: &Path, disk: &Disk, solver: &str) -> Vec<[f64; 2]> {
    use std::fmt::Write;
    // Rust's `{}` for f64 is the shortest text that reads back as the same number.
    let mut text = format!(
        "{} {} {}\n",
        disk.positions.len(),
        disk.triangles.len(),
        disk.pins.len()
    );
    for p in &disk.positions {
        writeln!(text, "{} {} {}", p.x, p.y, p.z).unwrap();
    }
    for t in &disk.triangles {
        writeln!(text, "{} {} {}", t[0], t[1], t[2]).unwrap();
    }
    for (v, uv) in &disk.pins {
        writeln!(text, "{v} {} {}", uv[0], uv[1]).unwrap();
    }
    let input = work_dir().join(format!("{}.txt", disk.name.replace(' ', "_")));
    std::fs::write(&input, text).unwrap();
    let out = Command::new(driver)
        .arg(solver)
        .stdin(Stdio::from(File::open(&input).unwrap()))
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "the CGAL driver failed on {}: {}",
        input.display(),
        String::from_utf8_lossy(&out.stderr)
    );
    let uv: Vec<[f64; 2]> = String::from_utf8(out.stdout)
        .unwrap()
        .lines()
        .map(|l| {
            let mut it = l.split(' ').map(|x| x.parse::<f64>().unwrap());
            [it.next().unwrap(), it.next().unwrap()]
        })
        .collect();
    assert_eq!(uv.len(), disk.positions.len(), "{}", disk.name);
    uv
}

/// The largest distance between the two maps' positions of one vertex.
fn max_difference(a: &[[f64; 2]], b: &[[f64; 2]]) -> f64 {
    a.iter()
        .zip(b)
        .map(|(p, q)| (p[0] - q[0]).hypot(p[1] - q[1]))
        .fold(0.0, f64::max)
}

/// Compares ntori's map of `disk` with CGAL's; returns the largest difference.
fn agrees(driver: &Path, disk: &Disk) -> f64 {
    let ntori = floater::parameterize(&disk.positions, &disk.triangles, &disk.pins).unwrap();
    let reference = cgal(driver, disk, "lu");
    assert!(
        reference.iter().flatten().all(|c| c.is_finite()),
        "{}: CGAL left a vertex unsolved",
        disk.name
    );
    let difference = max_difference(&ntori, &reference);

    // Not vacuous: there are interior vertices, they spread over the disk (not one point, not the
    // boundary), and the comparison sees a 1% change of the mesh's shape (the weights follow the
    // 3D geometry), which moves the map by far more than the tolerance.
    let mut pinned = vec![false; disk.positions.len()];
    for &(v, _) in &disk.pins {
        pinned[v as usize] = true;
    }
    let interior: Vec<[f64; 2]> = (0..disk.positions.len())
        .filter(|&v| !pinned[v])
        .map(|v| reference[v])
        .collect();
    assert!(
        interior.len() > 10,
        "{}: too few interior vertices",
        disk.name
    );
    let spread = |axis: usize| {
        let (lo, hi) = interior.iter().fold((f64::MAX, f64::MIN), |(lo, hi), p| {
            (lo.min(p[axis]), hi.max(p[axis]))
        });
        hi - lo
    };
    assert!(
        spread(0) > 0.5 && spread(1) > 0.5,
        "{}: interior collapsed",
        disk.name
    );
    let stretched: Vec<Point3> = disk
        .positions
        .iter()
        .map(|p| Point3::new(p.x, p.y, 1.01 * p.z))
        .collect();
    let other = floater::parameterize(&stretched, &disk.triangles, &disk.pins).unwrap();
    let sensitivity = max_difference(&other, &reference);

    eprintln!(
        "{}: {} vertices ({} interior), max |ntori − CGAL| = {difference:.2e}, \
         after a 1% stretch {sensitivity:.2e}",
        disk.name,
        disk.positions.len(),
        interior.len()
    );
    assert!(
        sensitivity > 1e3 * TOLERANCE,
        "{}: a 1% stretch moves the map by only {sensitivity:e}",
        disk.name
    );
    assert!(
        difference <= TOLERANCE,
        "{}: ntori and CGAL differ by {difference:e} (tolerance {TOLERANCE:e})",
        disk.name
    );
    difference
}

/// The cut disk of `HoledMesh::new(genus, resolution)` pinned to the regular 4n-gon of the Klein
/// model (corners on the unit circle), boundary vertices spaced along each side by 3D arc length.
fn cut_disk(genus: u32, resolution: usize) -> Disk {
    let mesh = HoledMesh::new(genus, resolution).unwrap();
    let disk = cut(&mesh).unwrap();
    let positions: Vec<Point3> = disk
        .original
        .iter()
        .map(|&o| mesh.positions[o as usize])
        .collect();
    let sides = disk.arcs.len();
    assert_eq!(sides, 4 * genus as usize);
    let corner = |k: usize| {
        let a = TAU * k as f64 / sides as f64;
        [a.cos(), a.sin()]
    };
    let len = disk.boundary.len();
    let mut pins = Vec::with_capacity(len);
    for (a, &(start, _)) in disk.arcs.iter().enumerate() {
        let end = disk.arcs.get(a + 1).map_or(len, |next| next.0);
        // Arc lengths from the arc's first vertex to each of its vertices and on to the next corner.
        let at = |i: usize| positions[disk.boundary[i % len] as usize];
        let mut lengths = vec![0.0];
        for i in start..end {
            lengths.push(lengths.last().unwrap() + (at(i + 1) - at(i)).norm());
        }
        let total = *lengths.last().unwrap();
        let (p, q) = (corner(a), corner(a + 1));
        for i in start..end {
            let t = lengths[i - start] / total;
            pins.push((
                disk.boundary[i],
                [p[0] + t * (q[0] - p[0]), p[1] + t * (q[1] - p[1])],
            ));
        }
    }
    Disk {
        name: format!("cut disk genus {genus} resolution {resolution}"),
        positions,
        triangles: disk.triangles,
        pins,
    }
}

/// SplitMix64: a seeded stream of uniform numbers in [0, 1).
struct Random(u64);

impl Random {
    fn next(&mut self) -> f64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        ((z ^ (z >> 31)) >> 11) as f64 / (1u64 << 53) as f64
    }
}

/// An n × n grid on [−1, 1]², interior vertices jittered by up to 0.35 of a cell, each square
/// split along a random diagonal, lifted by a sum of random Gaussian bumps plus per-vertex noise;
/// the square's boundary is pinned to the unit circle by 3D arc length.
fn bumpy_disk(seed: u64, n: usize) -> Disk {
    let mut random = Random(seed);
    let bumps: Vec<[f64; 4]> = (0..6)
        .map(|_| {
            let mut r = || 2.0 * random.next() - 1.0;
            [r(), r(), 0.8 * r(), 0.2 + 0.3 * r().abs()]
        })
        .collect();
    let cell = 2.0 / n as f64;
    let index = |i: usize, j: usize| (j * (n + 1) + i) as u32;
    let mut positions = Vec::with_capacity((n + 1) * (n + 1));
    for j in 0..=n {
        for i in 0..=n {
            let (mut x, mut y) = (-1.0 + i as f64 * cell, -1.0 + j as f64 * cell);
            let mut jitter = || 0.35 * cell * (2.0 * random.next() - 1.0);
            if i > 0 && i < n {
                x += jitter();
            }
            if j > 0 && j < n {
                y += jitter();
            }
            let z: f64 = bumps
                .iter()
                .map(|b| b[2] * (-((x - b[0]).powi(2) + (y - b[1]).powi(2)) / b[3].powi(2)).exp())
                .sum::<f64>()
                + 0.05 * cell * (2.0 * random.next() - 1.0);
            positions.push(Point3::new(x, y, z));
        }
    }
    let mut triangles = Vec::with_capacity(2 * n * n);
    for j in 0..n {
        for i in 0..n {
            let (a, b, c, d) = (
                index(i, j),
                index(i + 1, j),
                index(i + 1, j + 1),
                index(i, j + 1),
            );
            if random.next() < 0.5 {
                triangles.extend([[a, b, c], [a, c, d]]);
            } else {
                triangles.extend([[a, b, d], [b, c, d]]);
            }
        }
    }
    // The boundary counter-clockwise from (−1, −1).
    let boundary: Vec<u32> = (0..n)
        .map(|i| index(i, 0))
        .chain((0..n).map(|j| index(n, j)))
        .chain((0..n).map(|i| index(n - i, n)))
        .chain((0..n).map(|j| index(0, n - j)))
        .collect();
    let at = |k: usize| positions[boundary[k % boundary.len()] as usize];
    let mut lengths = vec![0.0];
    for k in 0..boundary.len() {
        lengths.push(lengths.last().unwrap() + (at(k + 1) - at(k)).norm());
    }
    let total = *lengths.last().unwrap();
    let pins = boundary
        .iter()
        .enumerate()
        .map(|(k, &v)| {
            let a = TAU * lengths[k] / total;
            (v, [a.cos(), a.sin()])
        })
        .collect();
    Disk {
        name: format!("bumpy disk seed {seed} grid {n}"),
        positions,
        triangles,
        pins,
    }
}

#[test]
fn floater_matches_cgal_on_cut_disks() {
    let Some(driver) = require_driver() else {
        return;
    };
    for genus in 1..=3 {
        agrees(&driver, &cut_disk(genus, 24));
    }
}

#[test]
fn floater_matches_cgal_on_bumpy_disks() {
    let Some(driver) = require_driver() else {
        return;
    };
    for (seed, n) in [(1, 12), (2, 20), (3, 31), (4, 48)] {
        agrees(&driver, &bumpy_disk(seed, n));
    }
}
