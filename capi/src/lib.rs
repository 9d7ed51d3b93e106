//! libabut.so and libabut.a: the `abut` crate's C ABI (`abut::capi`, feature `capi`) linked as
//! a C library. The functions are defined there; this crate only makes the library files.
//! Their declarations: include/abut.h.

pub use abut_rs::capi::*;
