//! Sets the cfg `jetid_realdata` when the shared real-data folder is beside the repository
//! (`../shared/realdata`), so that the tests that need it run there and are marked ignored, with
//! the reason, where it is absent. Real data are never copied into the repository.
fn main() {
    println!("cargo::rustc-check-cfg=cfg(jetid_realdata)");
    let data = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../shared/realdata");
    println!("cargo::rerun-if-changed={}", data.display());
    if data.is_dir() {
        println!("cargo::rustc-cfg=jetid_realdata");
    }
}
