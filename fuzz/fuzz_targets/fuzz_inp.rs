//! Fuzzes the Abaqus deck parser and the model built from what it accepts: any input must give
//! a deck or an error naming the file and line, never a panic.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    // *INCLUDE reads other files (a fuzzer would find /dev/zero): parsing itself is the target
    if text.to_ascii_uppercase().contains("INCLUDE") {
        return;
    }
    if let Ok(deck) = abut::io::inp::parse(text, std::path::Path::new("fuzz.inp")) {
        // what parsed must also build a model or fail with an error
        let _ = deck.to_model(1.0);
    }
});
