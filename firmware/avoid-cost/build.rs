//! Reuse the firmware's MPS2-AN386 memory layout (`../link/mps2-an386/memory.x`, `device.x`); the
//! linker scripts themselves are named in `../.cargo/config.toml`, which cargo also reads here.
fn main() {
    let dir = std::env::var("CARGO_MANIFEST_DIR").unwrap_or_default();
    // "-L" and the path as two arguments: flip-link, the linker ../.cargo/config.toml names, only
    // finds memory.x through search paths given that way.
    println!("cargo:rustc-link-arg=-L");
    println!("cargo:rustc-link-arg={dir}/../link/mps2-an386");
    println!("cargo:rerun-if-changed=build.rs");
}
