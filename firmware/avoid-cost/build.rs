//! Reuse the firmware's MPS2-AN386 memory layout (`../link/mps2-an386/memory.x`, `device.x`); the
//! linker scripts themselves are named in `../.cargo/config.toml`, which cargo also reads here.
fn main() {
    let dir = std::env::var("CARGO_MANIFEST_DIR").unwrap_or_default();
    println!("cargo:rustc-link-arg=-L{dir}/../link/mps2-an386");
    println!("cargo:rerun-if-changed=build.rs");
}
