//! The command line as a new user meets it: on a headless machine without `XDG_RUNTIME_DIR`,
//! the first lines are abut's own (Mesa's display probe stays quiet).

#[test]
fn no_display_probe_noise_without_a_runtime_dir() {
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_abut"))
        .args(["search", "--slaves", "200", "--side", "10", "--repeat", "1"])
        .env_remove("XDG_RUNTIME_DIR")
        .output()
        .expect("abut runs");
    let stderr = String::from_utf8_lossy(&out.stderr);
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success(), "{stderr}");
    assert!(!stderr.contains("XDG_RUNTIME_DIR"), "{stderr}");
    assert!(stdout.starts_with("device: "), "{stdout}");
}
