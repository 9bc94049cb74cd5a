//! Points each bare-metal binary at its own memory layout.
//!
//! cortex-m-rt's `link.x` does `INCLUDE memory.x` (and `device.x`); the two binaries of this package
//! run on different parts, so each gets its own search directory: `board` the STM32F407's,
//! `qemu` the MPS2 AN386's. Host builds (tests, the harness) need none of this.

use std::env;

fn main() {
    let dir = env::var("CARGO_MANIFEST_DIR").unwrap_or_default();
    if env::var("CARGO_CFG_TARGET_OS").as_deref() == Ok("none") {
        println!("cargo:rustc-link-arg-bin=board=-L{dir}/link/stm32f407");
        println!("cargo:rustc-link-arg-bin=qemu=-L{dir}/link/mps2-an386");
    }
    println!("cargo:rerun-if-changed=link");
    println!("cargo:rerun-if-changed=build.rs");
}
