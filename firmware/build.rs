//! Points each bare-metal binary at its own memory layout.
//!
//! cortex-m-rt's `link.x` does `INCLUDE memory.x` (and `device.x`); the two binaries of this package
//! run on different parts, so each gets its own search directory: `board` the STM32F407's,
//! `qemu` the MPS2 AN386's. Host builds (tests, the harness) need none of this.

use std::env;

fn main() {
    let dir = env::var("CARGO_MANIFEST_DIR").unwrap_or_default();
    if env::var("CARGO_CFG_TARGET_OS").as_deref() == Ok("none") {
        // "-L" and the path as two arguments: flip-link (the linker wrapper) only finds memory.x
        // through search paths given that way.
        for (bin, part) in [("board", "stm32f407"), ("qemu", "mps2-an386")] {
            println!("cargo:rustc-link-arg-bin={bin}=-L");
            println!("cargo:rustc-link-arg-bin={bin}={dir}/link/{part}");
        }
    }
    println!("cargo:rerun-if-changed=link");
    println!("cargo:rerun-if-changed=build.rs");
}
