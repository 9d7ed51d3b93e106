//! Fuzzes the Gmsh reader (mshio underneath, then abut's conversion and surfaces): any bytes
//! must give a mesh or an error, never a panic.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    for dim in [2, 3] {
        if let Ok(mesh) = abut::io::gmsh::parse(data, "fuzz.msh", dim) {
            for name in mesh.element_sets.keys() {
                let _ = mesh.surface(name);
            }
            let _ = mesh.boundary(None);
        }
    }
});
