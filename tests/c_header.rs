//! include/abut.h is what cbindgen makes of src/capi/ now: a stale header fails here.
//! `ABUT_BLESS=1 cargo test --test c_header` writes it.
#![cfg(feature = "capi")]

#[test]
fn the_committed_c_header_is_cbindgens() {
    let root = env!("CARGO_MANIFEST_DIR");
    let config = cbindgen::Config::from_file(format!("{root}/capi/cbindgen.toml"))
        .expect("capi/cbindgen.toml reads");
    let mut made = Vec::new();
    cbindgen::Builder::new()
        .with_crate(root)
        .with_config(config)
        .generate()
        .expect("cbindgen parses src/capi")
        .write(&mut made);
    let path = format!("{root}/include/abut.h");
    if std::env::var_os("ABUT_BLESS").is_some() {
        std::fs::write(&path, &made).expect("include/abut.h writes");
    }
    let committed = std::fs::read(&path).unwrap_or_default();
    // the one constant written by hand in capi/cbindgen.toml is the Rust one
    assert_eq!(abut::capi::ABUT_NO_NODE, u32::MAX);
    let text = String::from_utf8_lossy(&made);
    assert!(
        text.contains("#define ABUT_NO_NODE UINT32_MAX"),
        "ABUT_NO_NODE in the header"
    );
    assert!(
        committed == made,
        "include/abut.h is stale: src/capi/ changed; run `ABUT_BLESS=1 cargo test --release \
         --test c_header` and commit the header"
    );
}
