//! Compiles the C++ shim around TetGen and links the system `libtet`.
//!
//! TetGen is expected to be installed as Debian's `libtet1.5-dev`
//! (`/usr/include/tetgen.h`, `/usr/lib/<triple>/libtet.so`). Set
//! `TETGEN_INCLUDE_DIR` / `TETGEN_LIB_DIR` to point elsewhere.

use std::env;
use std::path::PathBuf;

fn main() {
    println!("cargo:rerun-if-changed=shim/shim.cpp");
    println!("cargo:rerun-if-env-changed=TETGEN_INCLUDE_DIR");
    println!("cargo:rerun-if-env-changed=TETGEN_LIB_DIR");

    let include_dir = env::var_os("TETGEN_INCLUDE_DIR").map(PathBuf::from);
    let header_found = match &include_dir {
        Some(dir) => dir.join("tetgen.h").exists(),
        None => PathBuf::from("/usr/include/tetgen.h").exists(),
    };
    if !header_found {
        println!(
            "cargo:warning=tetgen.h not found; install Debian's libtet1.5-dev \
             (apt-get install libtet1.5-dev) or set TETGEN_INCLUDE_DIR"
        );
    }

    let mut build = cc::Build::new();
    build.cpp(true).file("shim/shim.cpp").warnings(true);
    if let Some(dir) = &include_dir {
        build.include(dir);
    }
    build.compile("tetgen_shim");

    if let Some(dir) = env::var_os("TETGEN_LIB_DIR") {
        println!(
            "cargo:rustc-link-search=native={}",
            PathBuf::from(dir).display()
        );
    }
    println!("cargo:rustc-link-lib=dylib=tet");
}
