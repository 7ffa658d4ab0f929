//! The shim's C functions (`osd_shim.cpp`), or, in a build without OpenSubdiv, stand-ins that
//! return null or zero, which the safe layer reports as `Error::Unavailable`.

#[cfg(not(osd_missing))]
pub use linked::*;
#[cfg(osd_missing)]
pub use missing::*;

#[cfg(not(osd_missing))]
mod linked {
    use std::ffi::{c_long, c_void};

    unsafe extern "C" {
        pub fn ntori_osd_refiner_new(
            vertices: i32,
            faces: i32,
            counts: *const i32,
            indices: *const i32,
        ) -> *mut c_void;
        pub fn ntori_osd_refiner_free(refiner: *mut c_void);
        pub fn ntori_osd_refine_uniform(refiner: *mut c_void, level: i32) -> i32;
        pub fn ntori_osd_refine_adaptive(refiner: *mut c_void, level: i32) -> i32;
        pub fn ntori_osd_refine_uniform_full(refiner: *mut c_void, level: i32) -> i32;
        pub fn ntori_osd_finest_sizes(refiner: *const c_void, faces: *mut i32, corners: *mut i32);
        pub fn ntori_osd_finest_faces(
            refiner: *const c_void,
            counts: *mut i32,
            faces: i32,
            indices: *mut i32,
            corners: i32,
        ) -> i32;
        pub fn ntori_osd_limit_positions(
            refiner: *const c_void,
            base: *const f64,
            base_count: i32,
            out: *mut f64,
            du: *mut f64,
            dv: *mut f64,
            out_count: i32,
        ) -> i32;
        pub fn ntori_osd_uniform_stencils(refiner: *const c_void) -> *mut c_void;
        pub fn ntori_osd_limit_stencils(
            refiner: *const c_void,
            count: i32,
            faces: *const i32,
            s: *const f32,
            t: *const f32,
            derivatives: i32,
        ) -> *mut c_void;
        pub fn ntori_osd_stencils_free(table: *mut c_void);
        pub fn ntori_osd_stencil_count(table: *const c_void) -> i32;
        pub fn ntori_osd_weight_count(table: *const c_void) -> c_long;
        pub fn ntori_osd_apply(
            table: *const c_void,
            src: *const f32,
            dst: *mut f32,
            start: i32,
            end: i32,
        ) -> i32;
        pub fn ntori_osd_apply4(
            table: *const c_void,
            src: *const f32,
            dst: *mut f32,
            start: i32,
            end: i32,
        ) -> i32;
        pub fn ntori_osd_update_values(table: *const c_void, src: *const f32, dst: *mut f32);
        pub fn ntori_osd_apply_with_derivatives(
            table: *const c_void,
            src: *const f32,
            dst: *mut f32,
            du: *mut f32,
            dv: *mut f32,
            start: i32,
            end: i32,
        ) -> i32;
    }
}

#[cfg(osd_missing)]
#[allow(clippy::missing_safety_doc)]
mod missing {
    use std::ffi::{c_long, c_void};
    use std::ptr::null_mut;

    pub unsafe extern "C" fn ntori_osd_refiner_new(
        _: i32,
        _: i32,
        _: *const i32,
        _: *const i32,
    ) -> *mut c_void {
        null_mut()
    }
    pub unsafe extern "C" fn ntori_osd_refiner_free(_: *mut c_void) {}
    pub unsafe extern "C" fn ntori_osd_refine_uniform(_: *mut c_void, _: i32) -> i32 {
        0
    }
    pub unsafe extern "C" fn ntori_osd_refine_adaptive(_: *mut c_void, _: i32) -> i32 {
        0
    }
    pub unsafe extern "C" fn ntori_osd_refine_uniform_full(_: *mut c_void, _: i32) -> i32 {
        0
    }
    pub unsafe extern "C" fn ntori_osd_finest_sizes(_: *const c_void, _: *mut i32, _: *mut i32) {}
    pub unsafe extern "C" fn ntori_osd_finest_faces(
        _: *const c_void,
        _: *mut i32,
        _: i32,
        _: *mut i32,
        _: i32,
    ) -> i32 {
        0
    }
    pub unsafe extern "C" fn ntori_osd_limit_positions(
        _: *const c_void,
        _: *const f64,
        _: i32,
        _: *mut f64,
        _: *mut f64,
        _: *mut f64,
        _: i32,
    ) -> i32 {
        0
    }
    pub unsafe extern "C" fn ntori_osd_uniform_stencils(_: *const c_void) -> *mut c_void {
        null_mut()
    }
    pub unsafe extern "C" fn ntori_osd_limit_stencils(
        _: *const c_void,
        _: i32,
        _: *const i32,
        _: *const f32,
        _: *const f32,
        _: i32,
    ) -> *mut c_void {
        null_mut()
    }
    pub unsafe extern "C" fn ntori_osd_stencils_free(_: *mut c_void) {}
    pub unsafe extern "C" fn ntori_osd_stencil_count(_: *const c_void) -> i32 {
        0
    }
    pub unsafe extern "C" fn ntori_osd_weight_count(_: *const c_void) -> c_long {
        0
    }
    pub unsafe extern "C" fn ntori_osd_apply(
        _: *const c_void,
        _: *const f32,
        _: *mut f32,
        _: i32,
        _: i32,
    ) -> i32 {
        0
    }
    pub unsafe extern "C" fn ntori_osd_apply4(
        _: *const c_void,
        _: *const f32,
        _: *mut f32,
        _: i32,
        _: i32,
    ) -> i32 {
        0
    }
    pub unsafe extern "C" fn ntori_osd_update_values(_: *const c_void, _: *const f32, _: *mut f32) {
    }
    pub unsafe extern "C" fn ntori_osd_apply_with_derivatives(
        _: *const c_void,
        _: *const f32,
        _: *mut f32,
        _: *mut f32,
        _: *mut f32,
        _: i32,
        _: i32,
    ) -> i32 {
        0
    }
}
