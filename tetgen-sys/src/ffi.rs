//! Raw declarations of the C shim (`shim/shim.cpp`) and one safe entry point.

use std::ffi::{c_char, c_int, CString};

/// Invalid argument passed to the shim.
pub(crate) const TG_ERR_ARGS: i32 = -1;
/// `std::bad_alloc` caught in the shim.
pub(crate) const TG_ERR_ALLOC: i32 = -2;
/// Other `std::exception` caught in the shim.
pub(crate) const TG_ERR_STD: i32 = -3;

/// Opaque handle owning a heap-allocated output `tetgenio`.
#[repr(C)]
struct TgOutput {
    _private: [u8; 0],
}

extern "C" {
    fn tg_tetrahedralize(
        switches: *const c_char,
        npoints: c_int,
        points: *const f64,
        ntris: c_int,
        tris: *const c_int,
        nregions: c_int,
        regions: *const f64,
        out: *mut *mut TgOutput,
    ) -> c_int;
    fn tg_output_free(out: *mut TgOutput);
    fn tg_output_firstnumber(out: *const TgOutput) -> c_int;
    fn tg_output_num_points(out: *const TgOutput) -> c_int;
    fn tg_output_num_tets(out: *const TgOutput) -> c_int;
    fn tg_output_num_corners(out: *const TgOutput) -> c_int;
    fn tg_output_num_tet_attributes(out: *const TgOutput) -> c_int;
    fn tg_output_copy_points(out: *const TgOutput, buf: *mut f64);
    fn tg_output_copy_tets(out: *const TgOutput, buf: *mut c_int);
    fn tg_output_copy_tet_attributes(out: *const TgOutput, buf: *mut f64);
}

/// TetGen's output, copied out of the `tetgenio`.
pub(crate) struct RawOutput {
    pub first_number: i32,
    pub num_corners: i32,
    pub num_tet_attributes: i32,
    /// `3 * numberofpoints` coordinates.
    pub points: Vec<f64>,
    /// `numberofcorners * numberoftetrahedra` indices.
    pub tets: Vec<i32>,
    /// `numberoftetrahedronattributes * numberoftetrahedra` attributes.
    pub tet_attributes: Vec<f64>,
}

/// Frees the output handle on drop, so it is released on every path.
struct OutputGuard(*mut TgOutput);

impl Drop for OutputGuard {
    fn drop(&mut self) {
        // SAFETY: the pointer came from a successful `tg_tetrahedralize` and is
        // freed exactly once, here.
        unsafe { tg_output_free(self.0) }
    }
}

/// Converts a C count to `usize`, treating negative values as an error.
fn count(n: c_int) -> Result<usize, i32> {
    usize::try_from(n).map_err(|_| TG_ERR_ARGS)
}

/// Runs TetGen on flat arrays: `points` (3 per point), `tris` (3 zero-based
/// indices per triangle, all in range), `regions` (5 per region). Returns the
/// shim's error code on failure.
///
/// The caller must have validated the indices; the shim and TetGen do not
/// bounds-check them.
pub(crate) fn run(
    switches: &str,
    points: &[f64],
    tris: &[i32],
    regions: &[f64],
) -> Result<RawOutput, i32> {
    debug_assert!(points.len() % 3 == 0 && tris.len() % 3 == 0 && regions.len() % 5 == 0);
    let npoints = points.len() / 3;
    debug_assert!(tris.iter().all(|&i| i >= 0 && (i as usize) < npoints));
    let switches = CString::new(switches).map_err(|_| TG_ERR_ARGS)?;
    let npoints = c_int::try_from(npoints).map_err(|_| TG_ERR_ARGS)?;
    let ntris = c_int::try_from(tris.len() / 3).map_err(|_| TG_ERR_ARGS)?;
    let nregions = c_int::try_from(regions.len() / 5).map_err(|_| TG_ERR_ARGS)?;

    let mut out: *mut TgOutput = std::ptr::null_mut();
    // SAFETY: all pointers are valid for the lengths passed (3 * npoints,
    // 3 * ntris, 5 * nregions); the shim only reads them and copies them into
    // its own `new[]` allocations. `out` is a valid place for the handle.
    let code = unsafe {
        tg_tetrahedralize(
            switches.as_ptr(),
            npoints,
            points.as_ptr(),
            ntris,
            tris.as_ptr(),
            nregions,
            regions.as_ptr(),
            &mut out,
        )
    };
    if code != 0 {
        return Err(code);
    }
    if out.is_null() {
        return Err(TG_ERR_ARGS);
    }
    let guard = OutputGuard(out);
    let h = guard.0 as *const TgOutput;

    // SAFETY: `h` is a live output handle (owned by `guard`); each buffer is
    // sized exactly as the shim's copy functions require.
    unsafe {
        let first_number = tg_output_firstnumber(h);
        let num_points = count(tg_output_num_points(h))?;
        let num_tets = count(tg_output_num_tets(h))?;
        let num_corners = tg_output_num_corners(h);
        let num_tet_attributes = tg_output_num_tet_attributes(h);
        let corners = count(num_corners)?;
        let attributes = count(num_tet_attributes)?;

        let mut points = vec![0.0f64; 3 * num_points];
        tg_output_copy_points(h, points.as_mut_ptr());
        let mut tets = vec![0 as c_int; corners * num_tets];
        tg_output_copy_tets(h, tets.as_mut_ptr());
        let mut tet_attributes = vec![0.0f64; attributes * num_tets];
        tg_output_copy_tet_attributes(h, tet_attributes.as_mut_ptr());

        Ok(RawOutput {
            first_number,
            num_corners,
            num_tet_attributes,
            points,
            tets,
            tet_attributes,
        })
    }
}
