//! Compiles the C++ shim over OpenSubdiv (Debian's `libosd-dev`) when its headers are there, and
//! links `libosdCPU`. Without them the crate still builds: every constructor then returns
//! `Error::Unavailable`, so a fresh machine needs only Rust; `.ci/run` installs the package.
//! `OSD_INCLUDE_DIR` and `OSD_LIB_DIR` point elsewhere than `/usr/include` and the system libraries.

use std::env;
use std::path::PathBuf;

fn main() {
    println!("cargo::rustc-check-cfg=cfg(osd_missing)");
    println!("cargo::rerun-if-changed=src/osd_shim.cpp");
    println!("cargo::rerun-if-env-changed=OSD_INCLUDE_DIR");
    println!("cargo::rerun-if-env-changed=OSD_LIB_DIR");
    let include = env::var_os("OSD_INCLUDE_DIR")
        .map(PathBuf::from)
        .unwrap_or_else(|| PathBuf::from("/usr/include"));
    let header = include.join("opensubdiv/far/stencilTableFactory.h");
    println!("cargo::rerun-if-changed={}", header.display());
    if !header.is_file() {
        missing(&format!("no {}", header.display()));
        return;
    }
    let built = cc::Build::new()
        .cpp(true)
        .std("c++14")
        .include(&include)
        .opt_level(3)
        .warnings(false)
        .file("src/osd_shim.cpp")
        .try_compile("ntori_osd_shim");
    if let Err(e) = built {
        missing(&format!("the shim did not compile: {e}"));
        return;
    }
    if let Some(dir) = env::var_os("OSD_LIB_DIR") {
        println!(
            "cargo::rustc-link-search=native={}",
            PathBuf::from(dir).display()
        );
    }
    println!("cargo::rustc-link-lib=dylib=osdCPU");
}

fn missing(why: &str) {
    println!("cargo::warning=OpenSubdiv comparisons are off ({why}); apt-get install libosd-dev");
    println!("cargo::rustc-cfg=osd_missing");
}
