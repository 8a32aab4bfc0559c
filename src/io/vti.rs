//! The input image or volume as VTK XML image data (`.vti`) in its
//! [`Frame`], and the two scene files that open several files together: a
//! VTK multiblock file (`.vtm`, read by VTK's own XML readers and ParaView)
//! and a ParaView data collection (`.pvd`, ParaView's format, which the VTK
//! library alone does not read).
//!
//! Written by hand rather than through `vtkio`, whose image data has no
//! `Direction` (needed for flipped or oblique NIfTI affines) and keeps the
//! origin in single precision. Arrays are inline base64 binary with
//! `UInt64` headers, the header and the data encoded separately, as VTK's
//! own writer does.

use std::fmt::Write as _;
use std::path::Path;

use base64::engine::general_purpose::STANDARD;
use base64::Engine as _;

use super::atomic::write_atomic;
use super::error::{IoError, Result};
use super::frame::Frame;

/// Writes `values` (x fastest, then y, then z; one per voxel of `frame`) as
/// the point data array `name` of a `.vti` file: point `(i, j, k)` is the
/// centre of voxel `(i, j, k)` placed by the frame, as VTK's image readers
/// place it.
pub fn write_vti(path: impl AsRef<Path>, frame: &Frame, name: &str, values: &[f32]) -> Result<()> {
    let path = path.as_ref();
    let [nx, ny, nz] = frame.dims;
    if values.len() != nx * ny * nz || values.is_empty() {
        return Err(IoError::invalid(
            path,
            format!("{} values for {nx}x{ny}x{nz} voxels", values.len()),
        ));
    }
    let (origin, dir, flipped) = axis_flips_undone(frame);
    let values = reversed_along(values, frame.dims, flipped);
    let extent = format!("0 {} 0 {} 0 {}", nx - 1, ny - 1, nz - 1);
    let mut head = String::new();
    let _ = write!(
        head,
        "<?xml version=\"1.0\"?>\n\
         <VTKFile type=\"ImageData\" version=\"1.0\" byte_order=\"LittleEndian\" header_type=\"UInt64\">\n\
         <ImageData WholeExtent=\"{extent}\" Origin=\"{}\" Spacing=\"{}\" Direction=\"{}\">\n\
         <Piece Extent=\"{extent}\">\n<PointData Scalars=\"{name}\">\n\
         <DataArray type=\"Float32\" Name=\"{name}\" NumberOfComponents=\"1\" format=\"binary\">\n",
        join(&origin),
        join(&frame.spacing),
        join(&dir.concat()),
    );
    let tail = "\n</DataArray>\n</PointData>\n<CellData>\n</CellData>\n</Piece>\n</ImageData>\n</VTKFile>\n";
    let mut bytes = Vec::with_capacity(4 * values.len());
    for v in values {
        bytes.extend_from_slice(&v.to_le_bytes());
    }
    write_atomic(path, |w| {
        w.write_all(head.as_bytes())?;
        w.write_all(
            STANDARD
                .encode((bytes.len() as u64).to_le_bytes())
                .as_bytes(),
        )?;
        w.write_all(STANDARD.encode(&bytes).as_bytes())?;
        w.write_all(tail.as_bytes())
    })
}

/// The frame's origin and direction with every axis that points against its
/// world axis (a flipped row order or NIfTI axis) turned around, and which
/// were: the data is then reversed along them, so that viewers ignoring
/// `Direction` still show the image where it belongs when the frame is
/// axis-aligned.
fn axis_flips_undone(frame: &Frame) -> ([f64; 3], [[f64; 3]; 3], [bool; 3]) {
    let (mut origin, mut dir) = frame.origin_and_direction();
    let mut flipped = [false; 3];
    for c in 0..3 {
        let aligned = (0..3).all(|r| r == c || dir[r][c] == 0.0);
        if aligned && dir[c][c] < 0.0 && frame.dims[c] > 1 {
            let steps = (frame.dims[c] - 1) as f64;
            for (r, o) in origin.iter_mut().enumerate() {
                *o += frame.index_to_world[r][c] * steps;
            }
            dir[c][c] = -dir[c][c];
            flipped[c] = true;
        }
    }
    (origin, dir, flipped)
}

/// `values` (x fastest) with the index order reversed along the flipped axes.
fn reversed_along(values: &[f32], dims: [usize; 3], flipped: [bool; 3]) -> Vec<f32> {
    let [nx, ny, nz] = dims;
    let at = |i: usize, n: usize, f: bool| if f { n - 1 - i } else { i };
    let mut out = Vec::with_capacity(values.len());
    for k in 0..nz {
        for j in 0..ny {
            let row = nx * (at(j, ny, flipped[1]) + ny * at(k, nz, flipped[2]));
            out.extend((0..nx).map(|i| values[row + at(i, nx, flipped[0])]));
        }
    }
    out
}

/// Writes a VTK multiblock file (`.vtm`) listing `files` (paths relative to
/// its directory), so that opening it in ParaView shows them all together.
pub fn write_vtm(path: impl AsRef<Path>, files: &[&str]) -> Result<()> {
    let mut text = String::from(
        "<?xml version=\"1.0\"?>\n<VTKFile type=\"vtkMultiBlockDataSet\" version=\"1.0\">\n\
         <vtkMultiBlockDataSet>\n",
    );
    for (index, f) in files.iter().enumerate() {
        let _ = writeln!(
            text,
            "<DataSet index=\"{index}\" name=\"{}\" file=\"{f}\"/>",
            f.rsplit_once('.').map_or(*f, |(stem, _)| stem)
        );
    }
    text.push_str("</vtkMultiBlockDataSet>\n</VTKFile>\n");
    super::atomic::write_bytes_atomic(path, text.as_bytes())
}

/// Writes a ParaView data collection (`.pvd`) listing `files` (paths
/// relative to its directory) as parts of one time step, so that opening it
/// in ParaView shows them all together.
pub fn write_pvd(path: impl AsRef<Path>, files: &[&str]) -> Result<()> {
    let mut text = String::from(
        "<?xml version=\"1.0\"?>\n\
         <VTKFile type=\"Collection\" version=\"0.1\" byte_order=\"LittleEndian\">\n\
         <Collection>\n",
    );
    for (part, f) in files.iter().enumerate() {
        let _ = writeln!(
            text,
            "<DataSet timestep=\"0\" group=\"\" part=\"{part}\" file=\"{f}\"/>"
        );
    }
    text.push_str("</Collection>\n</VTKFile>\n");
    super::atomic::write_bytes_atomic(path, text.as_bytes())
}

/// Numbers separated by spaces, at full precision.
fn join(v: &[f64]) -> String {
    v.iter()
        .map(|x| format!("{x:?}"))
        .collect::<Vec<_>>()
        .join(" ")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn vti_holds_its_frame_and_values() {
        let dir = tempfile::tempdir().unwrap();
        let a = [
            [-0.5, 0.0, 0.0, 10.0],
            [0.0, 0.5, 0.0, -3.0],
            [0.0, 0.0, 2.0, 7.0],
        ];
        let f = Frame::volume_affine([3, 2, 2], [0.5, 0.5, 2.0], "mm", a);
        let values: Vec<f32> = (0..12).map(|v| v as f32).collect();
        let p = dir.path().join("image.vti");
        write_vti(&p, &f, "intensity", &values).unwrap();
        let text = std::fs::read_to_string(&p).unwrap();
        // The flipped x axis is turned around: voxel 2 of x is the origin.
        assert!(text.contains("Origin=\"9.0 -3.0 7.0\""), "{text}");
        assert!(text.contains("Direction=\"1.0 0.0 0.0 0.0 1.0 0.0 0.0 0.0 1.0\""));
        assert!(text.contains("WholeExtent=\"0 2 0 1 0 1\""));
        let data = text.split("format=\"binary\">\n").nth(1).unwrap();
        let header = STANDARD.decode(&data[..12]).unwrap();
        assert_eq!(u64::from_le_bytes(header.try_into().unwrap()), 48);
        let body = STANDARD
            .decode(data[12..].split('\n').next().unwrap())
            .unwrap();
        assert_eq!(&body[..4], &2f32.to_le_bytes());
        assert!(write_vti(&p, &f, "intensity", &values[1..]).is_err());
        write_vtm(dir.path().join("scene.vtm"), &["image.vti", "mesh.vtu"]).unwrap();
        let vtm = std::fs::read_to_string(dir.path().join("scene.vtm")).unwrap();
        assert!(vtm.contains("file=\"mesh.vtu\"") && vtm.contains("name=\"image\""));
        write_pvd(dir.path().join("scene.pvd"), &["image.vti", "mesh.vtu"]).unwrap();
        let pvd = std::fs::read_to_string(dir.path().join("scene.pvd")).unwrap();
        assert!(pvd.contains("type=\"Collection\""));
        assert!(pvd.contains("part=\"1\" file=\"mesh.vtu\""), "{pvd}");
    }
}
